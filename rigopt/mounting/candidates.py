"""Mount candidates: the directions a camera at a mount point can face without the body in its near view.

Mount points are lens positions sampled on the zones (:mod:`rigopt.mounting.sampling`). For a grid of yaw
and pitch angles (ISO: yaw > 0 left of forward, pitch > 0 up, radians) a direction is *clear* when every
probe ray of the checked frustum (centre, edge midpoints and corners of the image with each half-angle shrunk by
``MountRules.frustum_margin``) travels from the lens to ``frustum_range`` without meeting the body (nor a
keep-out that blocks views, such as a coupled trailer, nor the space its front swings through): the
ray-cast counterpart of the fcl frustum rule, vectorised over all candidates at once. The body is a solid
(:meth:`rigopt.raycast.RayCaster.blocked_distance`), and so are the keep-outs and the swing: a lens facing into
any of them, however close, is blocked, even where its whole frustum lies inside it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigopt.camera import CameraModel, Lens
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.mounting.features import segments_hit_swings, trailer_swings
from rigopt.mounting.practice import keep_out_boxes, segments_hit_boxes
from rigopt.mounting.records import MountRules
from rigopt.mounting.sampling import DEFAULT_SPACING, sample_zone_points
from rigopt.rig.model import Rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.placement import known_vehicle

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
    """(n, k, m) bool: the probe rays of the checked frustum of a camera with ``lens`` at ``points`` (n, 3) m facing
    (pitches[k], yaws[m]) rad are not blocked within ``rules.frustum_range`` m of the lens (:func:`rays_blocked`)."""
    points = np.atleast_2d(points)
    yaw_grid, pitch_grid = np.meshgrid(yaws, pitches)  # (k, m)
    rotations = rotation_from_yaw_pitch_roll(yaw_grid, pitch_grid, np.zeros_like(yaw_grid))  # (k, m, 3, 3)
    rays = np.einsum("kmij,rj->kmri", rotations, probe_directions(lens, rules))  # (k, m, r, 3)
    n, shape = len(points), rays.shape[:3]
    origins = np.broadcast_to(points[:, None, None, None, :], (n, *rays.shape))  # (n, k, m, r, 3)
    directions = np.broadcast_to(rays[None], origins.shape)
    hit = rays_blocked(vehicle, origins.reshape(-1, 3), directions.reshape(-1, 3), rules)
    return ~hit.reshape(n, *shape).any(axis=-1)


def rays_blocked(vehicle: Vehicle, origins, directions, rules: MountRules = MountRules()) -> np.ndarray:
    """(n,) bool: rays from lenses ``origins`` (n, 3) m along unit ``directions`` (n, 3) that meet, within
    ``rules.frustum_range`` m, the body (a solid: a lens inside it or facing into it from its skin is blocked at
    once), a keep-out that blocks views (a coupled trailer) or the space its front swings through."""
    hit = vehicle.ray_caster.blocked_distance(origins, directions) <= rules.frustum_range
    blockers = keep_out_boxes(vehicle, rules.practice.lifted, occluding_only=True) if rules.practice.enabled else []
    if blockers:
        hit |= segments_hit_boxes(origins, directions, rules.frustum_range, blockers)
    swings = trailer_swings(vehicle, rules.practice.lifted) if rules.practice.feature_rules else []
    if swings:
        hit |= segments_hit_swings(origins, directions, rules.frustum_range, swings)
    return hit


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
    cells (rays through their centres from the lens, the body a solid within BODY_RANGE_M).

    positions : (n, 3) m; rotations : (n, 3, 3) R_vehicle_cam; model : CameraModel of batch shape (n,).
    """
    rays = model.grid_rays(grid)  # (n, g, 3) camera body frame
    directions = np.einsum("nij,ngj->ngi", np.asarray(rotations, dtype=float), rays)
    origins = np.broadcast_to(np.asarray(positions, dtype=float)[:, None, :], directions.shape)
    distance = vehicle.ray_caster.blocked_distance(origins.reshape(-1, 3), directions.reshape(-1, 3))
    return (distance.reshape(directions.shape[:2]) <= BODY_RANGE_M).mean(axis=1)


def rig_body_share(rig: Rig, grid=BODY_GRID) -> np.ndarray:
    """(N,) float: :func:`body_fraction` of each of ``rig``'s cameras on its vehicle (the rig measured from the
    vehicle's centre on the ground); zeros on a vehicle rigopt has no mesh of, which the renderer draws no body of.
    A :data:`rigopt.metrics.drop_model.BodyShare`."""
    vehicle = known_vehicle(rig)
    if vehicle is None:
        return np.zeros(len(rig))
    return body_fraction(vehicle, rig.positions, rig.rotations, CameraModel.of_cameras(rig.cameras), grid)
