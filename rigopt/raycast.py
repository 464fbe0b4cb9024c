"""Casting rays at a triangle mesh: the one ray-casting layer of rigopt, below vehicle, mounting, coverage and bench.

Rays are cast with trimesh: embree (the ``embreex`` package) when installed, or trimesh's pure triangle
intersector; both give the same answers (tested against a brute-force oracle). Every ray cast in rigopt goes
through this module, so the backend choice and its caching live in one place.

Conventions: origins and points in metres in the mesh's frame; directions unit vectors unless a function
says otherwise; a ray that misses has distance inf and face -1.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import trimesh

from rigopt.errors import RigoptError

BACKENDS = ("auto", "embree", "triangle")
#: A hit closer than this (m) to the end of a segment does not block it (the end may lie on the surface).
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


@dataclass(frozen=True, eq=False)
class RayHits:
    """The first mesh triangle along each of n rays.

    distance : (n,) float m from the ray's origin, inf where it misses; face : (n,) int triangle index, -1 where
    it misses; location : (n, 3) float m, the hit point, NaN where it misses.
    """

    distance: np.ndarray
    face: np.ndarray
    location: np.ndarray


def first_hits(mesh: trimesh.Trimesh, origins, directions, backend: str = "auto") -> RayHits:
    """The first triangle of ``mesh`` met by each unit ray (origins, directions (n, 3)); see :class:`RayHits`."""
    origins, directions = np.atleast_2d(origins), np.atleast_2d(directions)
    n = len(origins)
    distance, face, location = np.full(n, np.inf), np.full(n, -1), np.full((n, 3), np.nan)
    if n == 0:
        return RayHits(distance, face, location)
    faces, rays, locations = ray_caster(mesh, backend).intersects_id(origins, directions, multiple_hits=False,
                                                                     return_locations=True)
    if len(rays):
        hit = np.linalg.norm(locations - origins[rays], axis=1)
        np.minimum.at(distance, rays, hit)  # the nearest, should a backend return several hits of a ray
        first = hit == distance[rays]
        face[rays[first]], location[rays[first]] = faces[first], locations[first]
    return RayHits(distance, face, location)


def first_hit_distance(mesh: trimesh.Trimesh, origins, directions, backend: str = "auto") -> np.ndarray:
    """(n,) float: distance along each unit ray (origins, directions (n, 3)) to the first body triangle;
    inf where the ray misses."""
    return first_hits(mesh, origins, directions, backend).distance


def segments_clear(mesh: trimesh.Trimesh, starts, ends, backend: str = "auto") -> np.ndarray:
    """(n,) bool: no body triangle lies on the segment from starts[k] to ends[k] ((n, 3) m each)."""
    starts, ends = np.atleast_2d(starts), np.atleast_2d(ends)
    vector = ends - starts
    length = np.linalg.norm(vector, axis=1)
    direction = vector / np.maximum(length, 1e-12)[:, None]
    return first_hit_distance(mesh, starts, direction, backend) >= length - SEGMENT_END_TOLERANCE


def inside(mesh: trimesh.Trimesh, points, backend: str = "auto") -> np.ndarray:
    """(n,) bool: ``points`` (n, 3) m inside the closed ``mesh`` (trimesh's ray-parity containment test)."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    if len(points) == 0:
        return np.zeros(0, dtype=bool)
    return np.asarray(ray_caster(mesh, backend).contains_points(points), dtype=bool)
