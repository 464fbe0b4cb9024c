"""Mount candidates for the designer: points on the zones' surfaces and the directions each can face.

A candidate point is a lens position: a surface sample pushed out along the outward normal by half the
housing depth (as :mod:`rigopt.collision` mounts a camera). For a grid of yaw and pitch angles (ISO:
yaw > 0 left of forward, pitch > 0 up, radians) a direction is *clear* when every probe ray of the
checked frustum (centre, edge midpoints and corners of the image with each half-angle shrunk by
``MountRules.frustum_margin``) travels from ``near`` to ``frustum_range`` without meeting the body: the
ray-cast counterpart of the fcl frustum rule, vectorised over all candidates at once.
"""

from __future__ import annotations

import logging
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
import trimesh

from rigopt.camera import CameraModel
from rigopt.collision import MountRules, housing_fits
from rigopt.errors import RigoptError
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.raycast import first_hit_distance
from rigopt.rig.model import DEFAULT_IMAGE_SIZE
from rigopt.vehicle.model import Vehicle

DEFAULT_SPACING = 0.10
DEFAULT_YAWS_DEG = tuple(range(-180, 180, 10))
DEFAULT_PITCHES_DEG = (-20, -10, 0, 10, 20)


@dataclass(frozen=True)
class MountCandidates:
    """Candidate lens positions and the directions they can face.

    points : (n, 3) float, metres, vehicle frame (lens positions); normals : (n, 3) outward unit normals;
    zones : (n,) str; yaws : (m,) float rad; pitches : (k,) float rad; clear : (n, k, m) bool;
    fov : the horizontal FOV (deg) the directions were checked with.
    """

    points: np.ndarray
    normals: np.ndarray
    zones: np.ndarray
    yaws: np.ndarray
    pitches: np.ndarray
    clear: np.ndarray
    fov: float


def sample_zone_points(vehicle: Vehicle, spacing: float = DEFAULT_SPACING, zones=None, seed: int = 0,
                       rules: MountRules = MountRules()):
    """Evenly spread surface samples of the zones (about ``spacing`` m apart).

    Returns points (n, 3) lens positions, normals (n, 3), zone names (n,) str; samples whose lens would
    sit nearest to another zone's surface (at edges), or whose housing would sink into the body (in
    hollows), are dropped.
    """
    if not spacing > 0:
        raise RigoptError(f"the candidate spacing must be positive (metres), got {spacing}")
    mesh = vehicle.fine_mesh
    wanted = set(zones) if zones else None
    known = {z.name for z in vehicle.zones}
    if wanted and not wanted <= known:
        raise RigoptError(f"unknown zones {sorted(wanted - known)} on {vehicle.name}; its zones: {', '.join(sorted(known))}")
    points, normals, names = [], [], []
    for zone_name in dict.fromkeys(z.name for z in vehicle.zones):
        if wanted and zone_name not in wanted:
            continue
        faces = np.flatnonzero(vehicle.fine_face_zones == zone_name)
        if len(faces) == 0:
            continue
        part = mesh.submesh([faces], append=True)
        count = max(1, int(np.ceil(part.area / spacing**2 * 2)))
        with _quiet_trimesh():  # it logs a warning when rejection leaves fewer samples than asked for
            samples, index = trimesh.sample.sample_surface_even(part, count, radius=spacing, seed=seed)
        normal = part.face_normals[index]
        points.append(samples + normal * rules.housing[2] / 2.0)
        normals.append(normal)
        names += [zone_name] * len(samples)
    if not names:
        raise RigoptError(f"the zones {sorted(wanted) if wanted else sorted(known)} of {vehicle.name} hold no surface")
    points, normals, names = np.concatenate(points), np.concatenate(normals), np.array(names)
    # Keep the samples that the mount checks will place in the same zone (near edges the nearest surface of
    # the lens can be a neighbouring face with another normal) and at the intended distance.
    surface = vehicle.surface(points)
    agrees = np.array(vehicle.zone_names(surface.foot, surface.normal)) == names
    agrees &= np.abs(surface.distance - rules.housing[2] / 2.0) < 1e-3
    agrees &= housing_fits(vehicle, surface.foot, surface.normal, rules)
    if not agrees.any():
        raise RigoptError(f"the zones {sorted(wanted) if wanted else sorted(known)} of {vehicle.name} hold no surface "
                          "a camera can be mounted on")
    return points[agrees], normals[agrees], names[agrees]


@contextmanager
def _quiet_trimesh():
    logger = logging.getLogger("trimesh")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        yield
    finally:
        logger.setLevel(level)


def probe_directions(fov: float, rules: MountRules = MountRules(), image_size=DEFAULT_IMAGE_SIZE) -> np.ndarray:
    """(9, 3) unit rays in the camera body frame: centre, edge midpoints and corners of the checked frustum."""
    return CameraModel.from_fov(fov, image_size).probe_rays(1.0 - rules.frustum_margin)


def clear_directions(vehicle: Vehicle, points, yaws, pitches, fov: float, rules: MountRules = MountRules()):
    """(n, k, m) bool: the checked frustum of a camera at ``points`` (n, 3) facing (pitches[k], yaws[m])
    meets no body surface between ``rules.near`` and ``rules.frustum_range``."""
    points = np.atleast_2d(points)
    yaw_grid, pitch_grid = np.meshgrid(yaws, pitches)  # (k, m)
    rotations = rotation_from_yaw_pitch_roll(yaw_grid, pitch_grid, np.zeros_like(yaw_grid))  # (k, m, 3, 3)
    rays = np.einsum("kmij,rj->kmri", rotations, probe_directions(fov, rules))  # (k, m, r, 3)
    n, shape = len(points), rays.shape[:3]
    origins = points[:, None, None, None, :] + rules.near * rays[None]  # (n, k, m, r, 3)
    directions = np.broadcast_to(rays[None], origins.shape)
    distance = first_hit_distance(vehicle.mesh, origins.reshape(-1, 3), directions.reshape(-1, 3))
    hit = distance <= rules.frustum_range - rules.near
    return ~hit.reshape(n, *shape).any(axis=-1)


def mount_candidates(vehicle: Vehicle, spacing: float = DEFAULT_SPACING, fov: float = 65.0, zones=None,
                     yaws_deg=DEFAULT_YAWS_DEG, pitches_deg=DEFAULT_PITCHES_DEG,
                     rules: MountRules = MountRules()) -> MountCandidates:
    """Sample the zones and check every (point, pitch, yaw) for a clear view with a ``fov`` lens."""
    points, normals, names = sample_zone_points(vehicle, spacing, zones, rules=rules)
    yaws, pitches = np.deg2rad(np.asarray(yaws_deg, dtype=float)), np.deg2rad(np.asarray(pitches_deg, dtype=float))
    clear = clear_directions(vehicle, points, yaws, pitches, fov, rules)
    return MountCandidates(points, normals, names, yaws, pitches, clear, float(fov))
