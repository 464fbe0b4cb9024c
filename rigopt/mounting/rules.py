"""The mount rules: where a camera may go on a vehicle, checked with python-fcl (the solids are in
:mod:`rigopt.mounting.shapes`).

A camera is valid on a vehicle when
  1. its lens is outside the body and at most ``max_distance`` from the surface;
  2. its housing, a box ``housing`` (width along the horizontal tangent, height, depth along the outward
     normal) whose back face lies on the surface at the lens's foot point, penetrates the body by no more
     than ``penetration_tolerance``;
  3. its near view frustum (from ``near`` to ``frustum_range`` metres, the image shrunk by
     ``frustum_margin`` of each half-angle) does not intersect the body;
  4. its foot point and surface normal lie in one of the vehicle's zones;
  5. its housing does not collide with another camera's housing.
The lens sits at the housing's centre, so a well-mounted camera is ``housing[2] / 2`` off the surface.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rigopt.mounting.shapes import body_object, collides, frustum_object, housing_object
from rigopt.rig.model import Rig
from rigopt.vehicle.model import Vehicle


@dataclass(frozen=True)
class MountRules:
    """Tolerances of the mount checks; lengths in metres, ``frustum_margin`` a fraction of each half-angle."""

    housing: tuple[float, float, float] = (0.08, 0.06, 0.06)
    max_distance: float = 0.05
    penetration_tolerance: float = 0.01
    near: float = 0.02
    frustum_range: float = 1.0
    frustum_margin: float = 0.5


@dataclass(frozen=True)
class CameraCheck:
    """Outcome for one camera: ``distance_to_surface`` m (> 0 outside), ``zone`` (None outside every
    zone), ``problems`` (empty when valid)."""

    id: str
    valid: bool
    distance_to_surface: float
    zone: str | None
    problems: tuple[str, ...] = field(default_factory=tuple)


@dataclass(frozen=True)
class RigCheck:
    """Outcome for a rig on a vehicle; ``valid`` when every camera is."""

    rig: str
    vehicle: str
    cameras: tuple[CameraCheck, ...]

    @property
    def valid(self) -> bool:
        return all(c.valid for c in self.cameras)


def housing_fits(vehicle: Vehicle, feet, normals, rules: MountRules = MountRules()) -> np.ndarray:
    """(n,) bool: a housing with its back face at each foot point (n, 3) on a surface of normal (n, 3) sinks
    no deeper than ``rules.penetration_tolerance`` into the body (the housing rule, for mount points)."""
    body = body_object(vehicle)
    feet, normals = np.atleast_2d(feet), np.atleast_2d(normals)
    forward = np.array([1.0, 0.0, 0.0])
    return np.array([not collides(housing_object(foot, normal, forward, rules.housing, rules.penetration_tolerance),
                                   body) for foot, normal in zip(feet, normals)], dtype=bool)


def check_rig(rig: Rig, vehicle: Vehicle, rules: MountRules = MountRules()) -> RigCheck:
    """Apply every mount rule to every camera of ``rig`` on ``vehicle``."""
    body = body_object(vehicle)
    surface = vehicle.surface(rig.positions)
    zones = vehicle.zone_names(surface.foot, surface.normal)
    housings = [housing_object(surface.foot[k], surface.normal[k], c.forward, rules.housing)
                for k, c in enumerate(rig.cameras)]
    checks = []
    for k, camera in enumerate(rig.cameras):
        problems = []
        distance = float(surface.distance[k])
        if distance < 0:
            problems.append(f"inside the body ({-distance * 100:.1f} cm deep)")
        elif distance > rules.max_distance:
            problems.append(f"{distance * 100:.1f} cm off the surface (at most {rules.max_distance * 100:.0f} cm)")
        sunk = housing_object(surface.foot[k], surface.normal[k], camera.forward, rules.housing,
                              rules.penetration_tolerance)
        if distance >= 0 and collides(sunk, body):
            problems.append(f"housing penetrates the body by more than {rules.penetration_tolerance * 100:.0f} cm")
        if collides(frustum_object(camera, rules), body):
            problems.append(f"the body is in its view within {rules.frustum_range:g} m")
        if zones[k] is None:
            problems.append("outside every mounting zone")
        clashes = [other.id for j, other in enumerate(rig.cameras) if j != k and collides(housings[k], housings[j])]
        if clashes:
            problems.append(f"housing collides with {', '.join(clashes)}")
        checks.append(CameraCheck(camera.id, not problems, distance, zones[k], tuple(problems)))
    return RigCheck(rig.name, vehicle.name, tuple(checks))
