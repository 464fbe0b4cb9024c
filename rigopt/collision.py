"""Where a camera may go: python-fcl checks of housings and near view frustums against the body.

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
from functools import lru_cache

import numpy as np

from rigopt.camera import CameraModel
from rigopt.rig.model import Camera, Rig
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


def _fcl():
    import fcl

    return fcl


@lru_cache(maxsize=16)
def _body(vehicle: Vehicle):
    """The body as an fcl BVH collision object; one per vehicle."""
    fcl = _fcl()
    model = fcl.BVHModel()
    mesh = vehicle.mesh
    model.beginModel(len(mesh.vertices), len(mesh.faces))
    model.addSubModel(np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int32))
    model.endModel()
    return fcl.CollisionObject(model, fcl.Transform())


def surface_frame(normal: np.ndarray, forward: np.ndarray) -> np.ndarray:
    """(3, 3) columns (width axis, height axis, outward normal) of a housing on a surface of ``normal`` (3,).

    The width axis is horizontal; on a horizontal surface it is perpendicular to ``forward`` (3,).
    """
    width = np.cross([0.0, 0.0, 1.0], normal)
    if np.linalg.norm(width) < 1e-6:
        width = np.cross(normal, forward)
        if np.linalg.norm(width) < 1e-6:
            width = np.cross(normal, [1.0, 0.0, 0.0])
    width /= np.linalg.norm(width)
    return np.stack([width, np.cross(normal, width), normal], axis=1)


def housing_object(foot: np.ndarray, normal: np.ndarray, forward: np.ndarray, size, sink: float = 0.0):
    """fcl box of ``size`` (w, h, d) m with its back face on the surface at ``foot`` (3,), raised by
    ``sink`` m and shortened by it (so that only penetration deeper than ``sink`` collides)."""
    fcl = _fcl()
    w, h, d = size
    frame = surface_frame(normal, forward)
    centre = foot + normal * (sink + (d - sink) / 2.0)
    return fcl.CollisionObject(fcl.Box(w, h, d - sink), fcl.Transform(frame, centre))


def frustum_vertices(camera: Camera, rules: MountRules) -> np.ndarray:
    """(8, 3) float: near-plane then far-plane corners of the checked frustum, vehicle frame, metres."""
    local = CameraModel.of_camera(camera).frustum_corners(rules.near, rules.frustum_range, 1.0 - rules.frustum_margin)
    return camera.position + local @ camera.rotation.T


# Faces of the frustum hexahedron over frustum_vertices' order, outward-facing.
_FRUSTUM_FACES = np.array([[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]])


def frustum_object(camera: Camera, rules: MountRules):
    fcl = _fcl()
    faces = np.concatenate([[4, *f] for f in _FRUSTUM_FACES]).astype(np.int64)
    return fcl.CollisionObject(fcl.Convex(frustum_vertices(camera, rules), len(_FRUSTUM_FACES), faces),
                               fcl.Transform())


def _collides(a, b) -> bool:
    fcl = _fcl()
    return fcl.collide(a, b, fcl.CollisionRequest(), fcl.CollisionResult()) > 0


def housing_fits(vehicle: Vehicle, feet, normals, rules: MountRules = MountRules()) -> np.ndarray:
    """(n,) bool: a housing with its back face at each foot point (n, 3) on a surface of normal (n, 3) sinks
    no deeper than ``rules.penetration_tolerance`` into the body (the housing rule, for mount points)."""
    body = _body(vehicle)
    feet, normals = np.atleast_2d(feet), np.atleast_2d(normals)
    forward = np.array([1.0, 0.0, 0.0])
    return np.array([not _collides(housing_object(foot, normal, forward, rules.housing, rules.penetration_tolerance),
                                   body) for foot, normal in zip(feet, normals)], dtype=bool)


def check_rig(rig: Rig, vehicle: Vehicle, rules: MountRules = MountRules()) -> RigCheck:
    """Apply every mount rule to every camera of ``rig`` on ``vehicle``."""
    body = _body(vehicle)
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
        if distance >= 0 and _collides(sunk, body):
            problems.append(f"housing penetrates the body by more than {rules.penetration_tolerance * 100:.0f} cm")
        if _collides(frustum_object(camera, rules), body):
            problems.append(f"the body is in its view within {rules.frustum_range:g} m")
        if zones[k] is None:
            problems.append("outside every mounting zone")
        clashes = [other.id for j, other in enumerate(rig.cameras) if j != k and _collides(housings[k], housings[j])]
        if clashes:
            problems.append(f"housing collides with {', '.join(clashes)}")
        checks.append(CameraCheck(camera.id, not problems, distance, zones[k], tuple(problems)))
    return RigCheck(rig.name, vehicle.name, tuple(checks))
