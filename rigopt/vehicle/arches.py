"""Wheel arches: the opening the body leaves around each wheel, measured on the mesh.

A wheel's arch is its outline in the side view: from the axle, in the vertical plane through the outer edge
of the tyre's tread, rays every ``ARCH_STEP_DEG`` from straight back, over the top, to straight ahead, each
starting just outside the tyre; where a ray meets the body within ``ARCH_REACH_M`` of the tyre, the arch edge
lies at that distance from the axle in that direction, and where it meets nothing the wheel is open there (a
truck's rear tyres under a mudguard, the ground behind a tyre). The arch's *lip* is the band of body just
outside that edge (:mod:`rigopt.mounting.practice` refuses lenses on it).

Frames and units: ISO 8855 vehicle frame, metres; arch angles in radians from straight up (+z), positive
towards the front (+x).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigopt.raycast import RayCaster

#: Angular step (degrees) of the rays that trace an arch.
ARCH_STEP_DEG = 5.0
#: How far beyond the tyre (m) a ray still counts the body it meets as the arch (a wheel well is deeper than
#: this only where it is open).
ARCH_REACH_M = 0.6
#: The section plane lies this far (m) inside the tyre's outer face: through the tread, not beside it.
SECTION_INSET_M = 0.02


@dataclass(frozen=True)
class WheelArch:
    """One wheel's arch: ``name`` ('front-left wheel'), ``centre`` (3,) m the axle centre, ``radius`` m the
    tyre's, ``width`` m its tread's, ``side`` +1 left / -1 right, ``plane_y`` m the section plane's y,
    ``angles`` (k,) rad from straight up (positive forward), ``edge`` (k,) m from the axle to the body along
    each angle in that plane (inf where open)."""

    name: str
    centre: np.ndarray
    radius: float
    width: float
    side: float
    plane_y: float
    angles: np.ndarray
    edge: np.ndarray

    @property
    def inner_y(self) -> float:
        """|y| (m) of the tyre's inner face: lenses further in are under the body, not beside the wheel."""
        return abs(float(self.centre[1])) - self.width / 2.0

    def side_view(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Polar coordinates of ``points`` (n, 3) m about the axle in the side view: distance (n,) m in the
        x-z plane and angle (n,) rad from straight up, positive forward."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        dx, dz = points[:, 0] - self.centre[0], points[:, 2] - self.centre[2]
        return np.hypot(dx, dz), np.arctan2(dx, dz)

    def edge_at(self, angles) -> np.ndarray:
        """(n,) m: the arch edge's distance from the axle at ``angles`` (n,) rad (linear between the traced
        rays; inf where either neighbour is open or outside the traced half-circle)."""
        angles = np.asarray(angles, dtype=float)
        inside = (angles >= self.angles[0]) & (angles <= self.angles[-1])
        k = np.clip(np.searchsorted(self.angles, angles) - 1, 0, len(self.angles) - 2)
        a0, a1 = self.angles[k], self.angles[k + 1]
        e0, e1 = self.edge[k], self.edge[k + 1]
        t = np.clip((angles - a0) / (a1 - a0), 0.0, 1.0)
        with np.errstate(invalid="ignore"):
            edge = np.where(np.isfinite(e0) & np.isfinite(e1), e0 + (e1 - e0) * t, np.inf)
        return np.where(inside, edge, np.inf)


def wheel_name(axles, centre) -> str:
    """'front-left wheel', 'rear-right wheel', or 'x -1.85 m-left wheel' for a middle axle of ``axles``."""
    side = "left" if centre[1] >= 0 else "right"
    if len(axles) > 1 and centre[0] == axles[0]:
        return f"front-{side} wheel"
    if len(axles) > 1 and centre[0] == axles[-1]:
        return f"rear-{side} wheel"
    return f"x {centre[0]:.2f} m-{side} wheel"


def trace_arches(caster: RayCaster, wheels, axles) -> tuple[WheelArch, ...]:
    """Each wheel's arch on the mesh of ``caster`` (the body's ray caster): ``wheels`` as (centre (3,), radius, width) m, ``axles`` x m front first."""
    angles = np.deg2rad(np.arange(-90.0, 90.0 + 1e-9, ARCH_STEP_DEG))
    directions = np.stack([np.sin(angles), np.zeros_like(angles), np.cos(angles)], axis=1)
    arches = []
    for centre, radius, width in wheels:
        side = 1.0 if centre[1] >= 0 else -1.0
        plane_y = float(centre[1] + side * (width / 2.0 - SECTION_INSET_M))
        axle = np.array([centre[0], plane_y, centre[2]])
        starts = axle + directions * (radius + 0.01)
        hits = caster.first_hits(starts, directions)
        found = (hits.face >= 0) & (hits.distance <= ARCH_REACH_M)
        edge = np.where(found, radius + 0.01 + hits.distance, np.inf)
        arches.append(WheelArch(wheel_name(axles, centre), np.asarray(centre, dtype=float), float(radius),
                                float(width), side, plane_y, angles, edge))
    return tuple(arches)
