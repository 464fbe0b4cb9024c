"""Mount candidates: the directions a camera at a mount point can face without the body in its near view.

Mount points are lens positions sampled on the zones (:mod:`rigopt.mounting.sampling`). For a grid of yaw
and pitch angles (ISO: yaw > 0 left of forward, pitch > 0 up, radians) a direction is *clear* when every
probe ray of the checked frustum (centre, edge midpoints and corners of the image with each half-angle shrunk by
``MountRules.frustum_margin``) travels from ``near`` to ``frustum_range`` without meeting the body (nor a
keep-out that blocks views, such as a coupled trailer, nor the space its front swings through): the
ray-cast counterpart of the fcl frustum rule, vectorised over all candidates at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigopt.camera import CameraModel, Lens
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.mounting.features import segments_hit_swings, trailer_swings
from rigopt.mounting.practice import keep_out_boxes, segments_hit_boxes
from rigopt.mounting.rules import MountRules
from rigopt.mounting.sampling import DEFAULT_SPACING, sample_zone_points
from rigopt.vehicle.model import Vehicle

DEFAULT_YAWS_DEG = tuple(range(-180, 180, 10))
DEFAULT_PITCHES_DEG = (-20, -10, 0, 10, 20)


@dataclass(frozen=True)
class MountCandidates:
    """Candidate lens positions and the directions they can face.

    points : (n, 3) float, metres, vehicle frame (lens positions); normals : (n, 3) outward unit normals;
    zones : (n,) str; yaws : (m,) float rad; pitches : (k,) float rad; clear : (n, k, m) bool;
    fov : the horizontal FOV (deg) of the lens the directions were checked with.
    """

    points: np.ndarray
    normals: np.ndarray
    zones: np.ndarray
    yaws: np.ndarray
    pitches: np.ndarray
    clear: np.ndarray
    fov: float


def probe_directions(lens: Lens, rules: MountRules = MountRules()) -> np.ndarray:
    """(9, 3) unit rays in the camera body frame: centre, edge midpoints and corners of the checked frustum of
    ``lens`` (the benchmark's pinhole of a FOV is ``Lens.pinhole(fov)``)."""
    if not isinstance(lens, Lens):
        raise TypeError(f"a checked frustum needs a rigopt.camera.Lens (Lens.pinhole(fov) for a pinhole), got {lens!r}")
    return CameraModel.of_lens(lens).probe_rays(1.0 - rules.frustum_margin)


def clear_directions(vehicle: Vehicle, points, yaws, pitches, lens: Lens, rules: MountRules = MountRules()):
    """(n, k, m) bool: the checked frustum of a camera with ``lens`` at ``points`` (n, 3) facing
    (pitches[k], yaws[m]) meets no body surface between ``rules.near`` and ``rules.frustum_range``."""
    points = np.atleast_2d(points)
    yaw_grid, pitch_grid = np.meshgrid(yaws, pitches)  # (k, m)
    rotations = rotation_from_yaw_pitch_roll(yaw_grid, pitch_grid, np.zeros_like(yaw_grid))  # (k, m, 3, 3)
    rays = np.einsum("kmij,rj->kmri", rotations, probe_directions(lens, rules))  # (k, m, r, 3)
    n, shape = len(points), rays.shape[:3]
    origins = points[:, None, None, None, :] + rules.near * rays[None]  # (n, k, m, r, 3)
    directions = np.broadcast_to(rays[None], origins.shape)
    distance = vehicle.ray_caster.first_hit_distance(origins.reshape(-1, 3), directions.reshape(-1, 3))
    hit = distance <= rules.frustum_range - rules.near
    # keep-outs that block views, e.g. a coupled trailer
    blockers = keep_out_boxes(vehicle, rules.practice.lifted, occluding_only=True) if rules.practice.enabled else []
    if blockers:
        hit |= segments_hit_boxes(origins.reshape(-1, 3), directions.reshape(-1, 3), rules.frustum_range - rules.near,
                                  blockers)
    swings = trailer_swings(vehicle, rules.practice.lifted) if rules.practice.feature_rules else []
    if swings:  # and the space a coupled trailer's front swings through
        hit |= segments_hit_swings(origins.reshape(-1, 3), directions.reshape(-1, 3), rules.frustum_range - rules.near,
                                   swings)
    return ~hit.reshape(n, *shape).any(axis=-1)


def mount_candidates(vehicle: Vehicle, spacing: float = DEFAULT_SPACING, lens: Lens | None = None, zones=None,
                     yaws_deg=DEFAULT_YAWS_DEG, pitches_deg=DEFAULT_PITCHES_DEG,
                     rules: MountRules = MountRules()) -> MountCandidates:
    """Sample the zones and check every (point, pitch, yaw) for a clear view with ``lens`` (default the
    benchmark's 65-degree pinhole, ``Lens.pinhole(65.0)``)."""
    lens = Lens.pinhole(65.0) if lens is None else lens
    points, normals, names = sample_zone_points(vehicle, spacing, zones, rules=rules)
    yaws, pitches = np.deg2rad(np.asarray(yaws_deg, dtype=float)), np.deg2rad(np.asarray(pitches_deg, dtype=float))
    clear = clear_directions(vehicle, points, yaws, pitches, lens, rules)
    return MountCandidates(points, normals, names, yaws, pitches, clear, float(lens.hfov))


#: Image grid (columns, rows) the ego-body share of a candidate's image is estimated on.
BODY_GRID = (8, 5)
#: Rays that meet the body within this distance (m) count as seeing it.
BODY_RANGE_M = 30.0


def body_fraction(vehicle: Vehicle, positions, rotations, model: CameraModel, grid=BODY_GRID) -> np.ndarray:
    """(n,) float: the share of each camera's image that shows the ego body, estimated on a ``grid`` of image
    cells (rays through their centres from the lens, body within BODY_RANGE_M).

    positions : (n, 3) m; rotations : (n, 3, 3) R_vehicle_cam; model : CameraModel of batch shape (n,).
    """
    rays = model.grid_rays(grid)  # (n, g, 3) camera body frame
    directions = np.einsum("nij,ngj->ngi", np.asarray(rotations, dtype=float), rays)
    origins = np.asarray(positions, dtype=float)[:, None, :] + 0.02 * directions
    distance = vehicle.ray_caster.first_hit_distance(origins.reshape(-1, 3), directions.reshape(-1, 3))
    return (distance.reshape(directions.shape[:2]) <= BODY_RANGE_M).mean(axis=1)
