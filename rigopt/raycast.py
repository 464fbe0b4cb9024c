"""Casting rays at a triangle mesh: the one ray-casting layer of rigopt, below vehicle, mounting, coverage and bench.

A :class:`RayCaster` holds one mesh's intersector: embree (the ``embreex`` package) when installed, or trimesh's
pure triangle intersector; both give the same answers (tested against a brute-force oracle). Every ray cast in
rigopt goes through a caster; a vehicle owns its own (``Vehicle.ray_caster``), built once, so nothing here is
cached by mesh.

Conventions: origins and points in metres in the mesh's frame; directions unit vectors unless a method says
otherwise; a ray that misses has distance inf and face -1.

Two readings of a mesh: :meth:`RayCaster.first_hits` reports the first triangle a ray meets, whichever side it
meets it from; :meth:`RayCaster.blocked_distance` and :meth:`RayCaster.segments_clear` take the mesh as the
closed solid a vehicle body is, so that it blocks a ray wherever the ray starts: inside it, on its skin
heading in (where a backend may miss the triangle at distance 0 and report only the far side), or just
outside it. A ray on the skin heading out is not blocked by the triangle it leaves through.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from rigopt.errors import RigoptError

BACKENDS = ("auto", "embree", "triangle")
#: A hit closer than this (m) to the end of a segment does not block it (the end may lie on the surface).
SEGMENT_END_TOLERANCE = 1e-6
#: How near (m) the surface a ray's origin lies on the body's skin: a ray that leaves the body within this of its
#: origin started on the skin heading out and is cast on from there.
SKIN = 1e-4


def has_embree() -> bool:
    """True when trimesh can cast rays with embree."""
    return bool(trimesh.ray.has_embree)


def resolve_backend(backend: str = "auto") -> str:
    """The backend ``backend`` names: "embree" or "triangle" (auto: embree when installed)."""
    if backend not in BACKENDS:
        raise RigoptError(f"unknown ray backend {backend!r}; use one of {', '.join(BACKENDS)}")
    if backend == "auto":
        return "embree" if has_embree() else "triangle"
    if backend == "embree" and not has_embree():
        raise RigoptError("the embree ray backend needs the embreex package: pip install embreex")
    return backend


@dataclass(frozen=True, eq=False)
class RayHits:
    """The first mesh triangle along each of n rays.

    distance : (n,) float m from the ray's origin, inf where it misses; face : (n,) int triangle index, -1 where
    it misses; location : (n, 3) float m, the hit point, NaN where it misses.
    """

    distance: np.ndarray
    face: np.ndarray
    location: np.ndarray


class RayCaster:
    """Rays against one triangle ``mesh`` with one ``backend`` ("auto", "embree" or "triangle"; resolved when
    built). Build it once per mesh and keep it (a vehicle's is ``Vehicle.ray_caster``): the intersector (embree's
    scene) is built on the first cast."""

    def __init__(self, mesh: trimesh.Trimesh, backend: str = "auto"):
        self.mesh = mesh
        self.backend = resolve_backend(backend)
        self._intersector = None

    @property
    def intersector(self):
        """trimesh's RayMeshIntersector of the mesh for the backend, built on first use."""
        if self._intersector is None:
            if self.backend == "embree":
                from trimesh.ray.ray_pyembree import RayMeshIntersector
            else:
                from trimesh.ray.ray_triangle import RayMeshIntersector
            self._intersector = RayMeshIntersector(self.mesh)
        return self._intersector

    def first_hits(self, origins, directions) -> RayHits:
        """The first triangle met by each unit ray (origins, directions (n, 3)); see :class:`RayHits`."""
        origins, directions = np.atleast_2d(origins), np.atleast_2d(directions)
        n = len(origins)
        distance, face, location = np.full(n, np.inf), np.full(n, -1), np.full((n, 3), np.nan)
        if n == 0:
            return RayHits(distance, face, location)
        faces, rays, locations = self.intersector.intersects_id(origins, directions, multiple_hits=False,
                                                                return_locations=True)
        if len(rays):
            hit = np.linalg.norm(locations - origins[rays], axis=1)
            np.minimum.at(distance, rays, hit)  # the nearest, should a backend return several hits of a ray
            first = hit == distance[rays]
            face[rays[first]], location[rays[first]] = faces[first], locations[first]
        return RayHits(distance, face, location)

    def first_hit_distance(self, origins, directions) -> np.ndarray:
        """(n,) float: distance along each unit ray (origins, directions (n, 3)) to the first triangle; inf where
        the ray misses."""
        return self.first_hits(origins, directions).distance

    def blocked_distance(self, origins, directions, cast_on: bool = True) -> np.ndarray:
        """(n,) float m: how far along each unit ray (origins, directions (n, 3)) the mesh, a closed solid,
        blocks it; inf where nothing does.

        A ray whose first triangle is one it enters the solid through is blocked there, as in
        :meth:`first_hit_distance`. One whose first triangle is one it leaves through was inside the solid: at
        its origin (blocked at 0; a lens on the skin heading in, whose entry a backend may miss, counts so too,
        as does an origin within SKIN of the surface), unless that triangle lies within SKIN of the origin (a
        ray on the skin heading out: cast on from just past it, once) or the origin is outside the solid (a
        ray that slipped in through an edge: blocked where it leaves, as before).
        """
        origins, directions = np.atleast_2d(np.asarray(origins, float)), np.atleast_2d(np.asarray(directions, float))
        hits = self.first_hits(origins, directions)
        distance = hits.distance.copy()
        hit = np.flatnonzero(hits.face >= 0)
        leaving = np.zeros(len(distance), dtype=bool)
        leaving[hit] = np.einsum("ij,ij->i", directions[hit], self.mesh.face_normals[hits.face[hit]]) > 0
        out = leaving & (distance <= SKIN)
        if cast_on and out.any():  # on the skin heading out: from just past the triangle it leaves through
            step = distance[out] + SKIN
            distance[out] = step + self.blocked_distance(origins[out] + step[:, None] * directions[out],
                                                         directions[out], cast_on=False)
        inward = np.flatnonzero(leaving & ~out) if cast_on else np.flatnonzero(leaving)
        if len(inward):
            distance[inward[self._in_or_on(origins[inward])]] = 0.0
        return distance

    def _in_or_on(self, points) -> np.ndarray:
        """(n,) bool: ``points`` (n, 3) m inside the closed mesh or within SKIN of its surface (each distinct
        point tested once)."""
        unique, index = np.unique(points, axis=0, return_inverse=True)
        _, gap, _ = trimesh.proximity.closest_point(self.mesh, unique)
        return (self.inside(unique) | (gap <= SKIN))[index.reshape(-1)]

    def segments_clear(self, starts, ends) -> np.ndarray:
        """(n,) bool: the closed mesh, a solid, does not block the segment from starts[k] to ends[k] ((n, 3) m
        each; :meth:`blocked_distance`): no triangle on it, and it does not start inside the solid nor on its
        skin heading in."""
        starts, ends = np.atleast_2d(starts), np.atleast_2d(ends)
        vector = ends - starts
        length = np.linalg.norm(vector, axis=1)
        direction = vector / np.maximum(length, 1e-12)[:, None]
        return self.blocked_distance(starts, direction) >= length - SEGMENT_END_TOLERANCE

    def inside(self, points) -> np.ndarray:
        """(n,) bool: ``points`` (n, 3) m inside the closed mesh (trimesh's ray-parity containment test)."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        if len(points) == 0:
            return np.zeros(0, dtype=bool)
        return np.asarray(self.intersector.contains_points(points), dtype=bool)
