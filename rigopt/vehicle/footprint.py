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

#: Precision (m) of ring radii.
RADIUS_TOLERANCE = 1e-7


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
        """(a,) float: distance from the centre to the outline offset by ``distance`` m at ``azimuths`` (a,) rad.

        Found by bisection on the (monotonic, since the footprint is convex and holds its centre) distance
        from the footprint along each azimuth's ray, to ``RADIUS_TOLERANCE``.
        """
        azimuths = np.asarray(azimuths, dtype=float)
        direction = np.stack([np.cos(azimuths), np.sin(azimuths)], axis=1)
        low = np.zeros(len(azimuths))
        high = np.full(len(azimuths), self._reach + distance + 1.0)
        while np.max(high - low, initial=0.0) > RADIUS_TOLERANCE:
            middle = (low + high) / 2
            outside = self.distance_to(self.centre + middle[:, None] * direction) > distance
            high = np.where(outside, middle, high)
            low = np.where(outside, low, middle)
        return (low + high) / 2

    @cached_property
    def _reach(self) -> float:
        """Largest distance (m) from the centre to the footprint's outline."""
        return float(np.max(np.linalg.norm(self.outline - self.centre, axis=1)))

    def ring_points(self, azimuths, distance: float, height: float) -> np.ndarray:
        """(a, 3) float: ring points at ``azimuths`` (a,) rad, ``distance`` m from the outline, at ``height`` m."""
        azimuths = np.asarray(azimuths, dtype=float)
        r = self.radius(azimuths, distance)
        xy = self.centre + r[:, None] * np.stack([np.cos(azimuths), np.sin(azimuths)], axis=1)
        return np.column_stack([xy, np.full(len(azimuths), float(height))])

    def distance_to(self, points_xy) -> np.ndarray:
        """(n,) float: distance (m) of ground points (n, 2) from the footprint (0 inside)."""
        return shapely.distance(self.polygon, shapely.points(np.asarray(points_xy, dtype=float)))
