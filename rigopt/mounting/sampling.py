"""Mount points: lens positions spread evenly over a vehicle's mounting zones, where a housing fits.

A mount point is a lens position: a surface sample pushed out along the outward normal by half the housing
depth (as the mount rules, :mod:`rigopt.mounting.rules`, mount a camera). Metres, vehicle frame.
"""

from __future__ import annotations


import numpy as np
import trimesh

from rigopt.errors import RigoptError
from rigopt.mounting.practice import practical
from rigopt.mounting.records import MountRules
from rigopt.mounting.rules import housing_fits, raised_mounts
from rigopt.mounting.shapes import collides, housing_object
from rigopt.quiet import quiet_trimesh
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.symmetry import mirror_points

DEFAULT_SPACING = 0.10


def sample_zone_points(vehicle: Vehicle, spacing: float = DEFAULT_SPACING, zones=None, seed: int = 0,
                       rules: MountRules = MountRules(), near: tuple[np.ndarray, float] | None = None):
    """Evenly spread surface samples of the zones (about ``spacing`` m apart).

    Returns points (n, 3) lens positions, normals (n, 3), zone names (n,) str; samples whose lens would
    sit nearest to another zone's surface (at edges), or whose housing would sink into the body (in
    hollows), are dropped. Raised zones (``raised_max`` > 0) are sampled only when named in ``zones``: their
    points are lifted above the surface (see :func:`_raised_points`) and their normals are the posts' axes.

    ``near`` (positions (k, 3) m, radius m): only the samples within the radius of one of the positions are
    checked and returned, in the same order: the checks are per point, so these are the whole set's points
    near them, found for a fraction of the work; none is then an answer, not an error.
    """
    points, normals, names, raised = _zone_samples(vehicle, spacing, zones, seed, rules)
    if near is not None:
        positions, radius = near
        close = np.zeros(len(points), dtype=bool)
        for position in np.atleast_2d(positions):
            close |= np.linalg.norm(points - position, axis=1) <= radius
        points, normals, names = points[close], normals[close], names[close]
        if not close.any():
            return points, normals, names
    keep = _mountable(vehicle, points, normals, names, raised, rules, zones, required=near is None)
    return points[keep], normals[keep], names[keep]


def sample_symmetric_zone_points(vehicle: Vehicle, spacing: float = DEFAULT_SPACING, zones=None, seed: int = 0,
                                 rules: MountRules = MountRules()):
    """Mount points in mirrored pairs across y = 0 and on the centreline, for symmetric designs.

    The samples of the left half (y > spacing / 2) are reflected to the right and each reflection moved onto
    the right side's own surface (a body asymmetric by a few centimetres keeps its pairs mountable); the
    centreline is sampled every ``spacing`` along each zone's section by the plane y = 0 (normals made
    lateral-free). A point is kept only when its mirror is mountable too. Returns points (n, 3), normals (n, 3), zone names (n,) str and
    ``mirror`` (n,) int, the index of each point's mirror (itself on the centreline).
    """
    points, normals, names, raised = _zone_samples(vehicle, spacing, zones, seed, rules)
    half = rules.housing[2] / 2.0
    lifted = np.isin(names, sorted(raised))
    left = points[:, 1] > spacing / 2.0
    # the centreline: the zones' sections by y = 0 sampled every ``spacing``; raised zones' samples near it snapped
    near = lifted & (np.abs(points[:, 1]) <= spacing / 4.0)
    c_points, c_normals, c_names = _centreline_samples(vehicle, spacing, {str(n) for n in names[~lifted]}, half)
    c_points = np.concatenate([c_points, points[near] * [1.0, 0.0, 1.0]])
    c_normals = np.concatenate([c_normals, normals[near] * [1.0, 0.0, 1.0]])
    c_normals /= np.maximum(np.linalg.norm(c_normals, axis=1, keepdims=True), 1e-12)
    c_names = np.concatenate([c_names, names[near]])
    # the right side: the left half reflected, moved onto the right side's surface
    l_points, l_normals = points[left], normals[left]
    r_points, r_normals = mirror_points(l_points), mirror_points(l_normals)
    on_surface = ~lifted[left]
    if on_surface.any():
        surface = vehicle.surface(mirror_points(l_points[on_surface] - l_normals[on_surface] * half))
        r_points[on_surface] = surface.foot + surface.normal * half
        r_normals[on_surface] = surface.normal
    n_left, n_centre = len(l_points), len(c_points)
    points = np.concatenate([l_points, r_points, c_points])
    normals = np.concatenate([l_normals, r_normals, c_normals])
    names = np.concatenate([names[left], names[left], c_names])
    mirror = np.concatenate([np.arange(n_left) + n_left, np.arange(n_left), np.arange(n_centre) + 2 * n_left])
    keep = _mountable(vehicle, points, normals, names, raised, rules, zones)
    keep &= keep[mirror]
    if not keep.any():
        raise RigoptError(f"no mirrored pair of mount points on {vehicle.name} is mountable; design without "
                          "symmetry (--asymmetric) or allow more zones")
    new_index = np.cumsum(keep) - 1
    return points[keep], normals[keep], names[keep], new_index[mirror[keep]]


def _centreline_samples(vehicle: Vehicle, spacing: float, zone_names, half: float):
    """Lens positions every ``spacing`` m along the section of each zone in ``zone_names`` by y = 0, half a
    housing depth off the surface along the lateral-free normal: points (n, 3), normals (n, 3), names (n,)."""
    mesh = vehicle.fine_mesh
    points, normals, names = [np.zeros((0, 3))], [np.zeros((0, 3))], []
    for zone_name in sorted(zone_names):
        faces = np.flatnonzero(vehicle.fine_face_zones == zone_name)
        if len(faces) == 0:
            continue
        part = mesh.submesh([faces], append=True)
        segments, crossed = trimesh.intersections.mesh_plane(part, [0.0, 1.0, 0.0], [0.0, 0.0, 0.0], return_faces=True)
        if len(segments) == 0:
            continue
        length = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1)
        ends = np.cumsum(length)
        stations = np.arange(spacing / 2.0, ends[-1], spacing)
        which = np.minimum(np.searchsorted(ends, stations), len(segments) - 1)
        along = (stations - (ends[which] - length[which])) / np.maximum(length[which], 1e-12)
        foot = segments[which, 0] + (segments[which, 1] - segments[which, 0]) * along[:, None]
        normal = part.face_normals[crossed[which]] * [1.0, 0.0, 1.0]
        normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
        foot[:, 1] = 0.0
        points.append(foot + normal * half)
        normals.append(normal)
        names += [zone_name] * len(foot)
    return np.concatenate(points), np.concatenate(normals), np.array(names, dtype=str)


def _zone_samples(vehicle: Vehicle, spacing: float, zones, seed: int, rules: MountRules):
    """Every zone's surface samples as lens positions (see :func:`sample_zone_points`), unchecked: points (n, 3),
    normals (n, 3), zone names (n,) str and the set of raised zone names."""
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
        with quiet_trimesh():  # it logs a warning when rejection leaves fewer samples than asked for
            samples, index = trimesh.sample.sample_surface_even(part, count, radius=spacing, seed=seed)
        normal = part.face_normals[index]
        points.append(samples + normal * rules.housing[2] / 2.0)
        normals.append(normal)
        names += [zone_name] * len(samples)
    if not names:
        raise RigoptError(f"the zones {sorted(wanted) if wanted else sorted(known)} of {vehicle.name} hold no surface")
    return np.concatenate(points), np.concatenate(normals), np.array(names), raised


def _mountable(vehicle: Vehicle, points, normals, names, raised, rules: MountRules, zones,
               required: bool = True) -> np.ndarray:
    """(n,) bool: the samples the mount checks will place in the same zone (near edges the nearest surface of
    the lens can be a neighbouring face with another normal), at the intended distance, with the housing
    fitting, where mounting practice allows a lens (:func:`rigopt.mounting.practice.practice_problems`: off the
    wheels, high enough, out of the keep-outs, off steps, door frames, fixtures, arch lips and tyre spray,
    within the legal width, out of the tilt-cab arc and the trailer's swing, inside the wiped area). Raises
    when none is, if ``required``."""
    if len(points) == 0:
        raise RigoptError(f"no mount point was sampled on {vehicle.name}'s zones: the spacing is wider than the "
                          "zones themselves; lower --spacing (the default is sized to the vehicle)")
    surface = vehicle.surface(points)
    on_surface = ~np.isin(names, sorted(raised))
    agrees = np.array(vehicle.zone_names(surface.foot, surface.normal)) == names
    agrees &= np.abs(surface.distance - rules.housing[2] / 2.0) < 1e-3
    agrees &= housing_fits(vehicle, surface.foot, surface.normal, rules)
    agrees = np.where(on_surface, agrees, _raised_ok(vehicle, points, names, normals, surface, rules))
    fitting = agrees.copy()
    # off wheels, high enough, out of the keep-outs and off the features practice refuses (steps, door frames...)
    agrees &= practical(vehicle, points, rules.practice, rules.housing, surface)
    if not required:
        return agrees
    floor = rules.practice.height_floor(vehicle)
    if fitting.any() and not agrees.any() and rules.practice.enabled and points[fitting, 2].max() < floor:
        raise RigoptError(f"no mount point of {vehicle.name} is as high as the minimum lens height {floor:.2f} m "
                          f"(--min-height); the highest lies {points[fitting, 2].max():.2f} m up: lower --min-height")
    if not agrees.any():
        known = sorted({z.name for z in vehicle.zones})
        raise RigoptError(f"the zones {sorted(zones) if zones else known} of {vehicle.name} hold no surface "
                          "a camera can be mounted on")
    return agrees


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
    with quiet_trimesh():
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
    ok = np.zeros(len(points), dtype=bool)
    body = vehicle.collision_object
    far = surface.distance > rules.max_distance
    for k, mount in zip(np.flatnonzero(far), raised_mounts(vehicle, points[far])):
        if mount is None or mount.zone.name != names[k]:
            continue
        housing = housing_object(points[k] - mount.axis * rules.housing[2] / 2.0, mount.axis, [1.0, 0.0, 0.0],
                                 rules.housing, rules.penetration_tolerance)
        ok[k] = not collides(housing, body)
    return ok
