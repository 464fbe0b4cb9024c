"""The solids the mount rules collide, as python-fcl objects: the body, a camera housing on the surface, a raised
camera's post, the near view frustum (its shape from the camera model, :class:`rigopt.camera.CameraModel`), the
keep-out boxes and a trailer's swing.

Frames and units: vehicle frame (ISO 8855), metres. python-fcl is imported on first use.
"""

from __future__ import annotations

import numpy as np

from rigopt.camera import CameraModel
from rigopt.mounting.records import MountRules, RaisedMount
from rigopt.rig.model import Camera


def _fcl():
    import fcl

    return fcl


def surface_frame(normal: np.ndarray, forward: np.ndarray) -> np.ndarray:
    """(3, 3) columns (width axis, height axis, outward normal) of a housing on a surface of ``normal`` (3,).

    The width axis is horizontal; on a horizontal surface it is perpendicular to ``forward`` (3,).
    """
    width = cross3((0.0, 0.0, 1.0), normal)
    if np.linalg.norm(width) < 1e-6:
        width = cross3(normal, forward)
        if np.linalg.norm(width) < 1e-6:
            width = cross3(normal, (1.0, 0.0, 0.0))
    width /= np.linalg.norm(width)
    return np.column_stack([width, cross3(normal, width), normal])


def cross3(a, b) -> np.ndarray:
    """(3,) float: the cross product of two 3-vectors, each component computed as ``np.cross`` computes it (to
    the bit) without its array machinery (the mount checks take tens of thousands of surface frames)."""
    a0, a1, a2 = (float(v) for v in a)
    b0, b1, b2 = (float(v) for v in b)
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def housing_object(foot: np.ndarray, normal: np.ndarray, forward: np.ndarray, size, sink: float = 0.0):
    """fcl box of ``size`` (w, h, d) m with its back face on the surface at ``foot`` (3,), raised by
    ``sink`` m and shortened by it (so that only penetration deeper than ``sink`` collides)."""
    fcl = _fcl()
    w, h, d = size
    frame = surface_frame(normal, forward)
    centre = foot + normal * (sink + (d - sink) / 2.0)
    return fcl.CollisionObject(fcl.Box(w, h, d - sink), fcl.Transform(frame, centre))


#: The checked view of a near_field camera: the central cone of a pinhole of this horizontal FOV (deg). A
#: surround-view fisheye sees its own body at its image's edges by design; its centre must be clear.
NEAR_FIELD_CLEAR_CONE_DEG = 60.0


def checked_model(camera: Camera) -> CameraModel:
    """The camera model whose view the frustum rule checks: the camera's own, or for a near_field camera the
    central NEAR_FIELD_CLEAR_CONE_DEG cone of its image's aspect."""
    if camera.role == "near_field":
        return CameraModel.from_fov(NEAR_FIELD_CLEAR_CONE_DEG, camera.image_size)
    return CameraModel.of_camera(camera)


def frustum_vertices(camera: Camera, rules: MountRules) -> np.ndarray:
    """(8, 3) float: near-plane then far-plane corners of the checked frustum, vehicle frame, metres."""
    local = checked_model(camera).frustum_corners(rules.near, rules.frustum_range, 1.0 - rules.frustum_margin)
    return camera.position + local @ camera.rotation.T


def probe_rays(camera: Camera, rules: MountRules) -> np.ndarray:
    """(9, 3) float unit rays, vehicle frame, from the lens along the axis and to the edge midpoints and corners
    of the checked frustum (:meth:`rigopt.camera.CameraModel.probe_rays`)."""
    return checked_model(camera).probe_rays(1.0 - rules.frustum_margin) @ camera.rotation.T


# Faces of the frustum hexahedron over frustum_vertices' order, outward-facing.
_FRUSTUM_FACES = np.array([[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]])


def frustum_object(camera: Camera, rules: MountRules):
    """fcl convex hexahedron of :func:`frustum_vertices`."""
    fcl = _fcl()
    faces = np.concatenate([[4, *f] for f in _FRUSTUM_FACES]).astype(np.int64)
    return fcl.CollisionObject(fcl.Convex(frustum_vertices(camera, rules), len(_FRUSTUM_FACES), faces),
                               fcl.Transform())


def collides(a, b) -> bool:
    """True when the fcl objects ``a`` and ``b`` intersect."""
    fcl = _fcl()
    return fcl.collide(a, b, fcl.CollisionRequest(), fcl.CollisionResult()) > 0


def box_object(low, high):
    """An fcl box filling [low, high] (3,) m."""
    fcl = _fcl()
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    return fcl.CollisionObject(fcl.Box(*(high - low)), fcl.Transform(np.eye(3), (low + high) / 2.0))


def swing_object(swing):
    """An fcl cylinder filling a trailer's swing (:class:`rigopt.mounting.features.TrailerSwing`)."""
    fcl = _fcl()
    length = swing.top - swing.kingpin[2]
    centre = np.array([swing.kingpin[0], swing.kingpin[1], swing.kingpin[2] + length / 2.0])
    return fcl.CollisionObject(fcl.Cylinder(swing.radius, length), fcl.Transform(np.eye(3), centre))


def post_object(mount: RaisedMount, forward, rules: MountRules):
    """fcl box of a raised camera's post: the housing's footprint from the foot to the housing's back face;
    None when the housing sits on the surface."""
    fcl = _fcl()
    w, h, d = rules.housing
    length = mount.height - d / 2.0
    if length <= 1e-3:
        return None
    frame = surface_frame(mount.axis, np.asarray(forward, float))
    return fcl.CollisionObject(fcl.Box(w, h, length), fcl.Transform(frame, mount.foot + mount.axis * length / 2.0))
