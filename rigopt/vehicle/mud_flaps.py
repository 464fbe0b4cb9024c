"""Mud flaps found on a user mesh: thin plates hanging behind a tyre (``[[fixtures]]`` of kind ``mud_flap``).

A mud flap is a sheet across the wheel's track band that faces along x (its faces' normals within ``FACING_DEG``
of +-x), hangs behind a tyre (its faces between ``GAP`` m and ``REACH`` m behind the tyre's rearmost point, from
``LOW`` m above the ground up to the tyre's top and ``ABOVE`` m more, outboard of the track's inner band) and is
thin: a ray from a face into the sheet leaves it again within ``THICKNESS`` m. The faces behind each tyre that
pass make one fixture box, grown by ``MARGIN`` m. A bumper, a body panel or a step behind the wheel is thicker
than a flap and is not one.

ISO vehicle frame, metres.
"""

from __future__ import annotations

import numpy as np
import trimesh

from rigopt.vehicle.supports import box_around

FACING_DEG = 20.0
GAP, REACH = 0.02, 1.0
LOW, ABOVE = 0.05, 0.3
THICKNESS = 0.04
MIN_AREA = 0.02
MARGIN = 0.01


def mud_flaps(mesh: trimesh.Trimesh, wheels) -> list[dict]:
    """``[[fixtures]]`` entries (name, kind mud_flap, min, max) over the flaps behind the ``wheels`` (FoundWheels:
    x, radius, width, track, m) of ``mesh`` (module doc), front axle first, left before right."""
    centres, normals = mesh.triangles_center, mesh.face_normals
    facing = np.abs(normals[:, 0]) >= np.cos(np.radians(FACING_DEG))
    flaps = []
    for k, axle in enumerate(wheels):
        label = "front" if k == 0 else "rear" if k == len(wheels) - 1 else f"axle {k + 1}"
        for side in (1.0, -1.0):
            outer = axle.track / 2 + axle.width / 2
            behind = axle.x - axle.radius - centres[:, 0]
            near = (facing & (behind >= GAP) & (behind <= REACH) & (centres[:, 2] >= LOW)
                    & (centres[:, 2] <= 2 * axle.radius + ABOVE)
                    & (side * centres[:, 1] >= outer - 2 * axle.width) & (side * centres[:, 1] <= outer + 0.1))
            faces = np.flatnonzero(near)
            if not len(faces):
                continue
            thin = faces[_thin(mesh, faces)]
            if mesh.area_faces[thin].sum() / 2 < MIN_AREA:  # a sheet's two faces
                continue
            where = "left" if side > 0 else "right"
            flaps.append({"name": f"mud flap behind the {label}-{where} wheel (found)", "kind": "mud_flap",
                          **box_around(mesh.triangles[thin], MARGIN)})
    return flaps


def _thin(mesh: trimesh.Trimesh, faces: np.ndarray) -> np.ndarray:
    """(len(faces),) bool: faces from which a ray into the solid (against the normal) meets the mesh again within
    THICKNESS m."""
    normals = mesh.face_normals[faces]
    origins = mesh.triangles_center[faces] - 1e-4 * normals
    locations, rays, _ = mesh.ray.intersects_location(origins, -normals, multiple_hits=False)
    thin = np.zeros(len(faces), dtype=bool)
    if len(rays):
        depth = np.linalg.norm(locations - origins[rays], axis=1)
        thin[rays[depth <= THICKNESS]] = True
    return thin
