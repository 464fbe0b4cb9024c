"""Where a camera housing has no surface to stand on: rails, ladders, light bars, racks, narrow strips.

A zone needs a surface flat and large enough for a housing (8 x 6 cm, ``rigopt.mounting.rules``). The closed
body's surface in the zones is sampled (3 cm apart); at each sample four rays are cast back onto the body
from the housing footprint's edges (``HALF_FOOTPRINT`` m out along both tangent directions, from 2 cm above the
tangent plane): an edge is supported when the body lies within ``SUPPORT_GAP`` below the plane. A sample
unsupported on two opposite edges stands on something narrower than the housing (a rail, a ladder rung, a
bar); such samples are grouped (``GROUP_REACH`` m) and each group of at least 3 becomes a keep-out box
(``[[keep_out]]``, grown by ``MARGIN`` m), so no lens is placed there. An edge of the body (one side
unsupported) is not narrow: cameras at roof edges stay allowed.

ISO vehicle frame, metres.
"""

from __future__ import annotations

import numpy as np
import trimesh

from rigopt import raycast

#: The housing footprint's half-size tested along each tangent direction (m): its larger half-side.
HALF_FOOTPRINT = 0.04
#: Rays start this far above the tangent plane (m); the body must lie within SUPPORT_GAP below it.
RAY_START, SUPPORT_GAP = 0.02, 0.015
#: Sample spacing on the zones' surface (m), and the most samples drawn.
SPACING, MAX_SAMPLES = 0.03, 200_000
#: Narrow samples closer than this join one group (m); a group's box grows by MARGIN (m).
GROUP_REACH, MARGIN = 0.12, 0.06
KEEP_OUT_REASON = "no surface for a housing: rail, ladder or bar"


def narrow_samples(mesh: trimesh.Trimesh, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(n,) bool: surface ``points`` (n, 3) m with outward ``normals`` (n, 3) where a housing footprint is
    unsupported on two opposite edges (module doc)."""
    up = np.array([0.0, 0.0, 1.0])
    u = np.cross(up, normals)
    flat = np.linalg.norm(u, axis=1) < 1e-6  # horizontal surfaces: x as the first tangent
    u[flat] = [1.0, 0.0, 0.0]
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(normals, u)
    supported = []
    for tangent in (u, -u, v, -v):
        origins = points + HALF_FOOTPRINT * tangent + RAY_START * normals
        distance = raycast.first_hit_distance(mesh, origins, -normals)
        supported.append(distance <= RAY_START + SUPPORT_GAP)
    return (~supported[0] & ~supported[1]) | (~supported[2] & ~supported[3])


def narrow_keep_outs(mesh: trimesh.Trimesh, zones) -> list[dict]:
    """``[[keep_out]]`` tables (name, reason, min, max) over the narrow parts of ``mesh``'s surface inside
    ``zones`` (rigopt.vehicle.model.Zone; raised zones left out), largest first."""
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    count = int(min(MAX_SAMPLES, max(1000, mesh.area / SPACING**2)))
    points, face = trimesh.sample.sample_surface(mesh, count, seed=2)
    normals = mesh.face_normals[face]
    in_zone = np.zeros(len(points), dtype=bool)
    for zone in zones:
        if not zone.raised:
            in_zone |= zone.contains(points, normals)
    points, normals = points[in_zone], normals[in_zone]
    narrow = points[narrow_samples(mesh, points, normals)] if len(points) else np.zeros((0, 3))
    if len(narrow) < 3:
        return []
    graph = cKDTree(narrow).sparse_distance_matrix(cKDTree(narrow), GROUP_REACH, output_type="coo_matrix")
    _, label = connected_components(graph, directed=False)
    groups = sorted((narrow[label == k] for k in np.unique(label)), key=len, reverse=True)
    return [{"name": f"narrow_{k + 1}", "reason": KEEP_OUT_REASON,
             "min": np.round(group.min(axis=0) - MARGIN, 4).tolist(),
             "max": np.round(group.max(axis=0) + MARGIN, 4).tolist()}
            for k, group in enumerate(g for g in groups if len(g) >= 3)]
