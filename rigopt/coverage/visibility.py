"""Occlusion-aware visibility: is a point inside a camera's pinhole frustum, with no body in between?

A point p is *seen* by a camera (t, R, fov, image size) when, in the camera body frame
``d = R^T (p - t)`` (x along the optical axis): ``d_x > 0``, ``|d_y| <= d_x tan(hfov / 2)``,
``|d_z| <= d_x tan(vfov / 2)``, ``|d| <= max_range``, and the segment from the lens to p meets no body
triangle. Segments are tested by casting rays with trimesh: embree (``embreex``) when installed, or
trimesh's pure triangle intersector, which give the same answer (tested).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import trimesh

from rigopt.camera import CameraModel, in_frustum
from rigopt.errors import RigoptError

DEFAULT_MAX_RANGE = 80.0
BACKENDS = ("auto", "embree", "triangle")
#: A hit closer than this to the end of a segment does not block it (the point may lie on the surface).
SEGMENT_END_TOLERANCE = 1e-6


def has_embree() -> bool:
    """True when trimesh can cast rays with embree."""
    return bool(trimesh.ray.has_embree)


@lru_cache(maxsize=32)
def _intersector(mesh: trimesh.Trimesh, backend: str):
    if backend == "embree":
        if not has_embree():
            raise RigoptError("the embree ray backend needs the embreex package: pip install embreex")
        from trimesh.ray.ray_pyembree import RayMeshIntersector
    else:
        from trimesh.ray.ray_triangle import RayMeshIntersector
    return RayMeshIntersector(mesh)


def ray_caster(mesh: trimesh.Trimesh, backend: str = "auto"):
    """A cached trimesh ray intersector of ``mesh`` for ``backend`` (auto: embree when installed)."""
    if backend not in BACKENDS:
        raise RigoptError(f"unknown ray backend {backend!r}; use one of {', '.join(BACKENDS)}")
    if backend == "auto":
        backend = "embree" if has_embree() else "triangle"
    return _intersector(mesh, backend)


def first_hit_distance(mesh: trimesh.Trimesh, origins, directions, backend: str = "auto") -> np.ndarray:
    """(n,) float: distance along each unit ray (origins, directions (n, 3)) to the first body triangle;
    inf where the ray misses."""
    origins, directions = np.atleast_2d(origins), np.atleast_2d(directions)
    distance = np.full(len(origins), np.inf)
    if len(origins) == 0:
        return distance
    locations, index, _ = ray_caster(mesh, backend).intersects_location(origins, directions, multiple_hits=False)
    if len(index):
        hit = np.linalg.norm(locations - origins[index], axis=1)
        np.minimum.at(distance, index, hit)
    return distance


def segments_clear(mesh: trimesh.Trimesh, starts, ends, backend: str = "auto") -> np.ndarray:
    """(n,) bool: no body triangle lies on the segment from starts[k] to ends[k] ((n, 3) m each)."""
    starts, ends = np.atleast_2d(starts), np.atleast_2d(ends)
    vector = ends - starts
    length = np.linalg.norm(vector, axis=1)
    direction = vector / np.maximum(length, 1e-12)[:, None]
    return first_hit_distance(mesh, starts, direction, backend) >= length - SEGMENT_END_TOLERANCE


def visible(mesh: trimesh.Trimesh, positions, rotations, fovs, image_sizes, points,
            max_range: float = DEFAULT_MAX_RANGE, backend: str = "auto") -> np.ndarray:
    """(c, p) bool: point p seen by camera c: in its frustum and not hidden by the body ``mesh``.

    positions : (c, 3) m; rotations : (c, 3, 3) R_vehicle_cam; fovs : (c,) deg; image_sizes : (c, 2) px;
    points : (p, 3) m, vehicle frame; max_range : m.
    """
    seen = in_frustum(CameraModel.from_fov(fovs, image_sizes), positions, rotations, points, max_range)
    cam, point = np.nonzero(seen)
    if len(cam):
        clear = segments_clear(mesh, np.asarray(positions, dtype=float)[cam], np.asarray(points, dtype=float)[point],
                               backend)
        seen[cam[~clear], point[~clear]] = False
    return seen
