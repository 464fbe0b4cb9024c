"""Mount points: lens positions spread evenly over a vehicle's mounting zones, where a housing fits.

A mount point is a lens position: a surface sample pushed out along the outward normal by half the housing
depth (as the mount rules, :mod:`rigopt.mounting.rules`, mount a camera). Metres, vehicle frame.
"""

from __future__ import annotations

import logging
from contextlib import contextmanager

import numpy as np
import trimesh

from rigopt.errors import RigoptError
from rigopt.mounting.practice import practical
from rigopt.mounting.rules import MountRules, housing_fits
from rigopt.vehicle.model import Vehicle

DEFAULT_SPACING = 0.10


def sample_zone_points(vehicle: Vehicle, spacing: float = DEFAULT_SPACING, zones=None, seed: int = 0,
                       rules: MountRules = MountRules()):
    """Evenly spread surface samples of the zones (about ``spacing`` m apart).

    Returns points (n, 3) lens positions, normals (n, 3), zone names (n,) str; samples whose lens would
    sit nearest to another zone's surface (at edges), or whose housing would sink into the body (in
    hollows), are dropped. Raised zones (``raised_max`` > 0) are sampled only when named in ``zones``: their
    points are lifted above the surface (see :func:`_raised_points`) and their normals are the posts' axes.
    """
    if not spacing > 0:
        raise RigoptError(f"the candidate spacing must be positive (metres), got {spacing}")
    mesh = vehicle.fine_mesh
    wanted = set(zones) if zones else None
    known = {z.name for z in vehicle.zones}
    if wanted and not wanted <= known:
        raise RigoptError(f"unknown zones {sorted(wanted - known)} on {vehicle.name}; its zones: {', '.join(sorted(known))}")
    points, normals, names = [], [], []
    raised = {z.name for z in vehicle.zones if z.raised}
    for zone_name in dict.fromkeys(z.name for z in vehicle.zones):
        if (wanted and zone_name not in wanted) or (zone_name in raised and not wanted):
            continue
        if zone_name in raised:
            lifted, axes = _raised_points(vehicle, zone_name, spacing, seed, rules)
            points.append(lifted)
            normals.append(axes)
            names += [zone_name] * len(lifted)
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
    on_surface = ~np.isin(names, sorted(raised))
    agrees = np.array(vehicle.zone_names(surface.foot, surface.normal)) == names
    agrees &= np.abs(surface.distance - rules.housing[2] / 2.0) < 1e-3
    agrees &= housing_fits(vehicle, surface.foot, surface.normal, rules)
    agrees = np.where(on_surface, agrees, _raised_ok(vehicle, points, names, normals, surface, rules))
    agrees &= practical(vehicle, points, rules.practice)  # off wheels, high enough, out of the keep-outs
    if not agrees.any():
        raise RigoptError(f"the zones {sorted(wanted) if wanted else sorted(known)} of {vehicle.name} hold no surface "
                          "a camera can be mounted on")
    return points[agrees], normals[agrees], names[agrees]


def _raised_points(vehicle: Vehicle, zone_name: str, spacing: float, seed: int, rules: MountRules):
    """Lens positions over a raised zone: its surface sampled ``spacing`` apart (faces in the zone, whatever
    zone they belong to first), lifted along the zone's normal to heights every 0.25 m up to ``raised_max``
    (at least housing depth / 2 + 5 cm, so that a post stands under the camera). Returns points (n, 3),
    post axes (n, 3)."""
    zone = next(z for z in vehicle.zones if z.name == zone_name)
    mesh = vehicle.fine_mesh
    faces = np.zeros(len(mesh.faces), dtype=bool)
    for same in (z for z in vehicle.zones if z.name == zone_name):
        faces |= same.contains(mesh.triangles_center, mesh.face_normals)
    if not faces.any():
        return np.zeros((0, 3)), np.zeros((0, 3))
    part = mesh.submesh([np.flatnonzero(faces)], append=True)
    count = max(1, int(np.ceil(part.area / spacing**2 * 2)))
    with _quiet_trimesh():
        samples, index = trimesh.sample.sample_surface_even(part, count, radius=spacing, seed=seed)
    lowest = rules.max_distance + rules.housing[2] / 2.0
    heights = np.unique(np.clip(np.append(np.arange(0.25, zone.raised_max, 0.25), zone.raised_max), lowest, None))
    axes = np.array([z.normal for z in vehicle.zones if z.name == zone_name])
    # each sample lifted along the normal of the (mirrored) copy of the zone that holds it
    which = np.array([next(k for k, z in enumerate(z for z in vehicle.zones if z.name == zone_name)
                           if z.contains(p, n)[0]) for p, n in zip(samples, part.face_normals[index])])
    axis = axes[which]
    points = (samples[:, None, :] + axis[:, None, :] * heights[None, :, None]).reshape(-1, 3)
    return points, np.repeat(axis, len(heights), axis=0)


def _raised_ok(vehicle: Vehicle, points, names, axes, surface, rules: MountRules) -> np.ndarray:
    """(n,) bool: raised lens positions that the mount checks will put on a post of their own zone, with the
    housing clear of the body."""
    from rigopt.mounting.rules import raised_mounts
    from rigopt.mounting.shapes import body_object, collides, housing_object

    ok = np.zeros(len(points), dtype=bool)
    body = body_object(vehicle)
    far = surface.distance > rules.max_distance
    for k, mount in zip(np.flatnonzero(far), raised_mounts(vehicle, points[far])):
        if mount is None or mount.zone.name != names[k]:
            continue
        housing = housing_object(points[k] - mount.axis * rules.housing[2] / 2.0, mount.axis, [1.0, 0.0, 0.0],
                                 rules.housing, rules.penetration_tolerance)
        ok[k] = not collides(housing, body)
    return ok


@contextmanager
def _quiet_trimesh():
    logger = logging.getLogger("trimesh")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        yield
    finally:
        logger.setLevel(level)
