"""The body's footprint on the ground and the rings around it where coverage is measured.

The footprint is the convex hull of the body projected on the ground (x, y), metres, vehicle frame.
A ring at distance d is the footprint's outline offset outwards by d; its point at azimuth a (radians,
counter-clockwise from +x, around the footprint's centroid) is where the ray from the centroid at angle a
crosses that offset outline, so every ring point is exactly d from the body's outline.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import shapely
import trimesh

#: Points sampled along an offset outline before interpolating its radius per azimuth.
_OUTLINE_SAMPLES = 4096


@dataclass(frozen=True, eq=False)
class Footprint:
    """Convex footprint of a body: ``polygon`` (shapely), ``centre`` (2,) m."""

    polygon: shapely.Polygon

    @classmethod
    def of_mesh(cls, mesh: trimesh.Trimesh) -> "Footprint":
        return cls(shapely.MultiPoint(np.asarray(mesh.vertices)[:, :2]).convex_hull)

    @cached_property
    def centre(self) -> np.ndarray:
        return np.array(self.polygon.centroid.coords[0])

    @property
    def outline(self) -> np.ndarray:
        """(k, 2) float: the footprint's closed outline, metres."""
        return np.asarray(self.polygon.exterior.coords)

    def radius(self, azimuths, distance: float) -> np.ndarray:
        """(a,) float: distance from the centre to the outline offset by ``distance`` m at ``azimuths`` (a,) rad."""
        shape = self.polygon.buffer(distance, quad_segs=32) if distance > 0 else self.polygon
        positions = np.linspace(0.0, 1.0, _OUTLINE_SAMPLES, endpoint=False)
        samples = shapely.get_coordinates(shapely.line_interpolate_point(shape.exterior, positions, normalized=True))
        samples = samples - self.centre
        angle = np.arctan2(samples[:, 1], samples[:, 0])
        order = np.argsort(angle)
        angle, length = angle[order], np.hypot(samples[order, 0], samples[order, 1])
        return np.interp(np.mod(np.asarray(azimuths, dtype=float) + np.pi, 2 * np.pi) - np.pi, angle, length,
                         period=2 * np.pi)

    def ring_points(self, azimuths, distance: float, height: float) -> np.ndarray:
        """(a, 3) float: ring points at ``azimuths`` (a,) rad, ``distance`` m from the outline, at ``height`` m."""
        azimuths = np.asarray(azimuths, dtype=float)
        r = self.radius(azimuths, distance)
        xy = self.centre + r[:, None] * np.stack([np.cos(azimuths), np.sin(azimuths)], axis=1)
        return np.column_stack([xy, np.full(len(azimuths), float(height))])

    def distance_to(self, points_xy) -> np.ndarray:
        """(n,) float: distance (m) of ground points (n, 2) from the footprint (0 inside)."""
        return shapely.distance(self.polygon, shapely.points(np.asarray(points_xy, dtype=float)))
