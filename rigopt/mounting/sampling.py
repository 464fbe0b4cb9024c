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
from rigopt.mounting.rules import MountRules, housing_fits
from rigopt.vehicle.model import Vehicle

DEFAULT_SPACING = 0.10


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
