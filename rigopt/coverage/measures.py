"""Coverage of a rig around its vehicle: rings, bird's-eye counts, near-field blind zone, per-camera facts.

Definitions (all distances in metres from the body's footprint outline, heights above the ground,
azimuths in radians counter-clockwise from +x around the footprint's centre; see ``footprint.py``):

- ring (d, h): ``ring_samples`` points evenly spaced in azimuth; ``covered_frac`` is the fraction seen by
  at least one camera (= the fraction of 360 deg), ``overlap2_frac`` by at least two;
- bird's-eye map: per cell of a square grid (half-size ``bev_extent``, cell ``bev_cell``) at height
  ``bev_height``, how many cameras see the cell centre (-1 inside the footprint);
- blind zone: per azimuth, the smallest distance at which the ground (h = 0) is seen by some camera
  (inf if not within ``blind_search``); and the unseen ground area within ``blind_radius`` of the body;
- per camera: ``self_occluded_frac``, the fraction of its image (a grid of pixel rays from the lens) that sees
  the vehicle within ``max_range``: its body or a keep-out that blocks views (a coupled trailer); all of it for a
  lens inside the body or facing into it from its skin; ``overlap_deg``, for every other camera, the degrees of
  the ``overlap_ring`` both see.

What blocks a view (``visibility.py``): the body, a solid, wherever the lens stands, and the keep-outs in force
that occlude (a coupled trailer; ``CoverageSettings.lifted`` names optional ones switched off). A point inside
one of those is not seen.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rigopt.vehicle.footprint import Footprint
from rigopt.errors import RigoptError
from rigopt.camera import CameraModel, Lens
from rigopt.coverage.visibility import DEFAULT_MAX_RANGE, occluders, visible_by
from rigopt.mounting.practice import segments_hit_boxes
from rigopt.rig.model import Rig
from rigopt.vehicle.model import Vehicle


@dataclass(frozen=True)
class CoverageSettings:
    """Every parameter of the coverage measures; lengths in metres. ``lifted``: names of optional keep-outs
    switched off (``("trailer",)``: a tractor without its trailer), as ``MountPractice.lifted``; the others that
    occlude block views."""

    ring_distances: tuple[float, ...] = (2.0, 5.0, 10.0, 20.0, 50.0)
    ring_heights: tuple[float, ...] = (0.0, 0.8)
    ring_samples: int = 720
    sectors: int = 72
    max_range: float = DEFAULT_MAX_RANGE
    bev_extent: float = 80.0
    bev_cell: float = 1.0
    bev_height: float = 0.8
    blind_radius: float = 5.0
    blind_search: float = 20.0
    blind_azimuths: int = 360
    blind_cell: float = 0.1
    image_grid: tuple[int, int] = (64, 36)
    overlap_ring: tuple[float, float] = (10.0, 0.8)
    backend: str = "auto"
    lifted: tuple[str, ...] = ()

    def azimuths(self, count: int | None = None) -> np.ndarray:
        """(count,) float rad: centres of ``count`` (default ``ring_samples``) equal azimuth bins from -pi."""
        count = self.ring_samples if count is None else int(count)
        if count < 1:
            raise RigoptError(f"azimuth sample counts must be positive, got {count}")
        return -np.pi + (np.arange(count) + 0.5) * (2 * np.pi / count)


@dataclass(frozen=True)
class RingCoverage:
    """One ring: ``counts`` (a,) int cameras seeing each azimuth sample ``azimuths`` (a,) rad."""

    distance_m: float
    height_m: float
    covered_frac: float
    overlap2_frac: float
    azimuths: np.ndarray
    counts: np.ndarray

    def sector_covered(self, sectors: int) -> np.ndarray:
        """(sectors,) float: fraction of each equal azimuth sector (from -pi) seen by >= 1 camera."""
        index = np.floor((self.azimuths + np.pi) / (2 * np.pi) * sectors).astype(int) % sectors
        seen = np.bincount(index, weights=(self.counts >= 1).astype(float), minlength=sectors)
        return seen / np.maximum(np.bincount(index, minlength=sectors), 1)


@dataclass(frozen=True)
class BevMap:
    """Bird's-eye counts (ny, nx) int over cell centres ``x`` (nx,) and ``y`` (ny,) m; -1 inside the body."""

    x: np.ndarray
    y: np.ndarray
    counts: np.ndarray
    height_m: float


@dataclass(frozen=True)
class BlindZone:
    """Per azimuth (a,) rad the distance (a,) m at which the ground becomes visible; the unseen ground area
    (m^2) within ``radius_m`` of the body."""

    azimuths: np.ndarray
    distance_m: np.ndarray
    area_m2: float
    radius_m: float


@dataclass(frozen=True)
class CameraCoverage:
    """Per camera: image fraction showing the body; degrees of the overlap ring shared with each other camera;
    the camera's lens (size, intrinsics, distortion), for the reports."""

    id: str
    self_occluded_frac: float
    lens: Lens
    overlap_deg: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class CoverageReport:
    """Everything measured for ``rig`` on ``vehicle``; ``cameras_inside`` lists cameras inside the body."""

    rig: str
    vehicle: str
    settings: CoverageSettings
    footprint: Footprint
    rings: tuple[RingCoverage, ...]
    bev: BevMap
    blind: BlindZone
    cameras: tuple[CameraCoverage, ...]
    cameras_inside: tuple[str, ...]


@dataclass(frozen=True)
class RingReport:
    """The rings alone of ``rig`` on ``vehicle`` (what a ring plot and the regulation fields' picture need,
    without the bird's-eye map, the blind zone and the per-camera facts of a full ``CoverageReport``); the
    ``footprint`` and the ``cameras_inside`` the body as in a ``CoverageReport``."""

    rig: str
    vehicle: str
    settings: CoverageSettings
    rings: tuple[RingCoverage, ...]
    footprint: Footprint
    cameras_inside: tuple[str, ...]


def _seen(vehicle: Vehicle, rig: Rig, points: np.ndarray, settings: CoverageSettings) -> np.ndarray:
    """(c, p) bool: ``points`` (p, 3) m seen by each camera of ``rig`` (body and occluders in force block)."""
    return visible_by(vehicle.caster(settings.backend), CameraModel.of_cameras(rig.cameras), rig.positions,
                      rig.rotations, points, settings.max_range, occluders(vehicle, settings.lifted))


def ring_coverage(vehicle: Vehicle, rig: Rig, settings: CoverageSettings, footprint: Footprint):
    """Every (distance, height) ring of ``settings``, distances varying fastest within each height."""
    azimuths = settings.azimuths()
    rings = []
    for height in settings.ring_heights:
        for distance in settings.ring_distances:
            counts = _seen(vehicle, rig, footprint.ring_points(azimuths, distance, height), settings).sum(axis=0)
            rings.append(RingCoverage(float(distance), float(height), float(np.mean(counts >= 1)),
                                      float(np.mean(counts >= 2)), azimuths, counts))
    return tuple(rings)


def bev_map(vehicle: Vehicle, rig: Rig, settings: CoverageSettings, footprint: Footprint) -> BevMap:
    half, cell = settings.bev_extent, settings.bev_cell
    x = footprint.centre[0] + np.arange(-half + cell / 2, half, cell)
    y = footprint.centre[1] + np.arange(-half + cell / 2, half, cell)
    xx, yy = np.meshgrid(x, y)
    points = np.column_stack([xx.ravel(), yy.ravel(), np.full(xx.size, settings.bev_height)])
    counts = _seen(vehicle, rig, points, settings).sum(axis=0)
    counts[footprint.distance_to(points[:, :2]) == 0] = -1
    return BevMap(x, y, counts.reshape(xx.shape), settings.bev_height)


def blind_zone(vehicle: Vehicle, rig: Rig, settings: CoverageSettings, footprint: Footprint) -> BlindZone:
    azimuths = settings.azimuths(settings.blind_azimuths)
    fine = np.arange(0.0, settings.blind_radius, settings.blind_cell / 2)
    distances = np.concatenate([fine, np.arange(settings.blind_radius, settings.blind_search + 1e-9, 0.25)])
    points = np.concatenate([footprint.ring_points(azimuths, d, 0.0) for d in distances])  # (d * a, 3)
    seen = _seen(vehicle, rig, points, settings).any(axis=0).reshape(len(distances), len(azimuths))
    first = np.where(seen.any(axis=0), distances[np.argmax(seen, axis=0)], np.inf)

    cell, radius = settings.blind_cell, settings.blind_radius
    low, high = np.array(footprint.polygon.bounds[:2]) - radius, np.array(footprint.polygon.bounds[2:]) + radius
    xx, yy = np.meshgrid(np.arange(low[0] + cell / 2, high[0], cell), np.arange(low[1] + cell / 2, high[1], cell))
    ground = np.column_stack([xx.ravel(), yy.ravel()])
    distance = footprint.distance_to(ground)
    band = ground[(distance > 0) & (distance <= radius)]
    unseen = ~_seen(vehicle, rig, np.column_stack([band, np.zeros(len(band))]), settings).any(axis=0)
    return BlindZone(azimuths, first, float(unseen.sum() * cell**2), float(radius))


def camera_coverage(vehicle: Vehicle, rig: Rig, settings: CoverageSettings, footprint: Footprint):
    distance, height = settings.overlap_ring
    ring = _seen(vehicle, rig, footprint.ring_points(settings.azimuths(), distance, height), settings)
    degrees = 360.0 / ring.shape[1]
    boxes = occluders(vehicle, settings.lifted)
    out = []
    for k, camera in enumerate(rig.cameras):
        rays = CameraModel.of_camera(camera).grid_rays(settings.image_grid) @ camera.rotation.T
        lens = np.broadcast_to(camera.position, rays.shape)
        blocked = vehicle.caster(settings.backend).blocked_distance(lens, rays) <= settings.max_range
        if boxes:
            blocked |= segments_hit_boxes(lens, rays, settings.max_range, boxes)
        overlap = {other.id: float((ring[k] & ring[j]).sum() * degrees)
                   for j, other in enumerate(rig.cameras) if j != k and (ring[k] & ring[j]).any()}
        out.append(CameraCoverage(camera.id, float(np.mean(blocked)), camera.lens, overlap))
    return tuple(out)


def cameras_inside(rig: Rig, vehicle: Vehicle) -> tuple[str, ...]:
    """The ids of ``rig``'s cameras inside ``vehicle``'s body."""
    inside = vehicle.surface(rig.positions).distance < 0
    return tuple(c.id for c, flag in zip(rig.cameras, inside) if flag)


def coverage_report(rig: Rig, vehicle: Vehicle, settings: CoverageSettings = CoverageSettings()) -> CoverageReport:
    """All coverage measures of ``rig`` on ``vehicle``; cameras inside the body are listed and still used."""
    footprint = vehicle.footprint
    return CoverageReport(
        rig.name, vehicle.name, settings, footprint,
        ring_coverage(vehicle, rig, settings, footprint),
        bev_map(vehicle, rig, settings, footprint),
        blind_zone(vehicle, rig, settings, footprint),
        camera_coverage(vehicle, rig, settings, footprint),
        cameras_inside(rig, vehicle),
    )


def ring_report(rig: Rig, vehicle: Vehicle, settings: CoverageSettings = CoverageSettings()) -> RingReport:
    """The rings of ``rig`` on ``vehicle``, as in ``coverage_report`` and at a fraction of its cost."""
    return RingReport(rig.name, vehicle.name, settings, ring_coverage(vehicle, rig, settings, vehicle.footprint),
                      vehicle.footprint, cameras_inside(rig, vehicle))


@dataclass(frozen=True)
class RingDifference:
    """``b`` minus ``a`` on one ring: covered and overlap fractions, and per sector (s,) covered fraction."""

    distance_m: float
    height_m: float
    covered_diff: float
    overlap2_diff: float
    sector_diff: np.ndarray


@dataclass(frozen=True)
class CoverageComparison:
    """Rig ``b`` (e.g. a design) against rig ``a`` (e.g. its reference), ring by ring."""

    a: str
    b: str
    rings: tuple[RingDifference, ...]
    blind_area_diff_m2: float


def compare_coverage(a: CoverageReport, b: CoverageReport) -> CoverageComparison:
    """Differences b - a of two reports, which must have been computed with the same settings."""
    if a.settings != b.settings:
        raise RigoptError(f"cannot compare coverage of {a.rig} and {b.rig} computed with different settings")
    sectors = a.settings.sectors
    pairs = {(r.distance_m, r.height_m): r for r in a.rings}
    rings = tuple(
        RingDifference(rb.distance_m, rb.height_m, rb.covered_frac - ra.covered_frac,
                       rb.overlap2_frac - ra.overlap2_frac, rb.sector_covered(sectors) - ra.sector_covered(sectors))
        for rb in b.rings if (ra := pairs.get((rb.distance_m, rb.height_m))) is not None
    )
    return CoverageComparison(a.rig, b.rig, rings, b.blind.area_m2 - a.blind.area_m2)
