"""The coverage matrix of the designer: which ring sectors each of many candidate cameras sees.

A sector point is the ring point (see ``footprint.py``) at the centre azimuth of one of ``sectors`` equal
azimuth sectors, for every ring distance and height of the settings; a candidate *covers* a sector when it
sees that point (frustum, and occlusion by the body and the keep-outs in force that block views, such as a coupled
trailer: ``visibility.py``). One vectorised call handles thousands of candidates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigopt.vehicle.footprint import Footprint
from rigopt.coverage.measures import CoverageSettings
from rigopt.benchmark import BENCHMARK_IMAGE_SIZE
from rigopt.camera import CameraModel
from rigopt.coverage.visibility import occluders, visible_by
from rigopt.rig.model import Rig
from rigopt.vehicle.model import Vehicle


@dataclass(frozen=True)
class CoverageMatrix:
    """``sees`` (n, q) bool: candidate n sees sector point q; per sector point (q,): ``distance_m``,
    ``height_m``, ``sector`` (int, 0 .. sectors - 1 from azimuth -pi), ``azimuth`` (rad), ``points`` (q, 3) m."""

    sees: np.ndarray
    distance_m: np.ndarray
    height_m: np.ndarray
    sector: np.ndarray
    azimuth: np.ndarray
    points: np.ndarray


def sector_points(footprint: Footprint, settings: CoverageSettings):
    """Sector points of every ring, heights outermost: (points (q, 3), distance (q,), height (q,),
    sector (q,), azimuth (q,))."""
    azimuths = settings.azimuths(settings.sectors)
    rows = [(footprint.ring_points(azimuths, d, h), d, h) for h in settings.ring_heights for d in settings.ring_distances]
    points = np.concatenate([r[0] for r in rows])
    count = len(azimuths)
    distance = np.repeat([r[1] for r in rows], count).astype(float)
    height = np.repeat([r[2] for r in rows], count).astype(float)
    sector = np.tile(np.arange(count), len(rows))
    return points, distance, height, sector, np.tile(azimuths, len(rows))


def coverage_matrix(vehicle: Vehicle, positions, rotations, fovs=None, image_sizes=None,
                    settings: CoverageSettings = CoverageSettings(), model: CameraModel | None = None
                    ) -> CoverageMatrix:
    """Coverage of candidate cameras: positions (n, 3) m, rotations (n, 3, 3) R_vehicle_cam, and either their
    lenses as a CameraModel ``model`` of batch shape (n,), or the benchmark's pinholes of fovs (n,) deg at
    image_sizes (n, 2) px (default the benchmark's 1280 x 720)."""
    positions = np.atleast_2d(np.asarray(positions, dtype=float))
    if model is None:
        if image_sizes is None:
            image_sizes = np.tile(BENCHMARK_IMAGE_SIZE, (len(positions), 1))
        model = CameraModel.from_fov(fovs, image_sizes)
    points, distance, height, sector, azimuth = sector_points(vehicle.footprint, settings)
    sees = visible_by(vehicle.caster(settings.backend), model, positions, rotations, points, settings.max_range,
                      occluders(vehicle, settings.lifted))
    return CoverageMatrix(sees, distance, height, sector, azimuth, points)


def rig_coverage_matrix(rig: Rig, vehicle: Vehicle, settings: CoverageSettings = CoverageSettings()) -> CoverageMatrix:
    """The coverage matrix of a rig's cameras (one row per camera, in order), through their lenses."""
    return coverage_matrix(vehicle, rig.positions, rig.rotations, settings=settings,
                           model=CameraModel.of_cameras(rig.cameras))
