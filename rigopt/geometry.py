"""Frames and SO(3): the one frame convention of rigopt and the named conversions at its edges.

Conventions
-----------
Vehicle frame (everywhere inside rigopt): ISO 8855, right-handed, origin at the vehicle's reference
point on the ground, x forward, y left, z up. Positions are in metres.

Camera body frame: x along the optical axis (forward), y left, z up, so that a camera with the identity
rotation looks straight ahead. ``R_vehicle_cam`` (3, 3) maps camera-body directions into the vehicle
frame: ``d_vehicle = R_vehicle_cam @ d_cam``.

Camera optical frame (pinhole, OpenCV, nuScenes): z forward, x right, y down.
``R_cam_optical`` maps optical directions into the camera body frame.

CARLA frame (the PCCR benchmark's files, CARLA spawn lists): x forward, y right, z up (left-handed);
rotations as ``[pitch, yaw, roll]`` degrees. CARLA's own ``Rotation::RotateVector`` (LibCarla
``geom/Rotation.h``) applies ``R_carla = Rz(yaw) @ Ry(-pitch) @ Rx(-roll)`` (right-handed elementary
rotations written in CARLA's axes; its third row is ``(sp, -cp sr, cp cr)``): yaw > 0 turns right, pitch > 0
tilts up, roll > 0 turns the camera's top to the right. Going to ISO 8855 is a reflection
``S = diag(1, -1, 1)``: ``t_iso = S t_carla`` and ``R_iso = S R_carla S = Rz(-yaw) @ Ry(-pitch) @ Rx(roll)``.
Distances and geodesic angles are invariant under that conjugation, so metrics are the same in either frame.
(rigopt before this convention was checked against CARLA's formula wrote and read roll with the opposite
sign; docs/formats.md lists the files that affects.)

URDF (ROS REP 103): ``rpy`` are fixed-axis roll, pitch, yaw, ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)`` in the
ISO axes (:func:`rotation_from_rpy`, :func:`rpy_from_rotation`).

This module is the one owner of these conventions: readers, writers, the renderer and the reports convert
through the functions below and nowhere else.

Angles are radians inside rigopt; degrees appear only at the file and CLI edges (and in FOVs).
"""

from __future__ import annotations

import numpy as np

#: Reflection between the CARLA frame (y right) and ISO 8855 (y left); its own inverse.
S_CARLA_ISO = np.diag([1.0, -1.0, 1.0])
S_CARLA_ISO.flags.writeable = False

#: Optical frame (z forward, x right, y down) -> camera body frame (x forward, y left, z up).
R_CAM_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
R_CAM_OPTICAL.flags.writeable = False


def rot_x(angle):
    """Right-handed rotation about x. angle : (...,) float, radians -> (..., 3, 3) float."""
    c, s = np.cos(angle), np.sin(angle)
    o, z = np.ones_like(c), np.zeros_like(c)
    return np.stack([np.stack([o, z, z], -1), np.stack([z, c, -s], -1), np.stack([z, s, c], -1)], -2)


def rot_y(angle):
    """Right-handed rotation about y. angle : (...,) float, radians -> (..., 3, 3) float."""
    c, s = np.cos(angle), np.sin(angle)
    o, z = np.ones_like(c), np.zeros_like(c)
    return np.stack([np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], -2)


def rot_z(angle):
    """Right-handed rotation about z. angle : (...,) float, radians -> (..., 3, 3) float."""
    c, s = np.cos(angle), np.sin(angle)
    o, z = np.ones_like(c), np.zeros_like(c)
    return np.stack([np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2)


def rotation_from_yaw_pitch_roll(yaw, pitch, roll):
    """ISO 8855 rotation ``Rz(yaw) @ Ry(-pitch) @ Rx(roll)`` of a camera body.

    yaw, pitch, roll : (...,) float, radians; yaw > 0 turns left, pitch > 0 tilts the lens up.
    Returns R_vehicle_cam : (..., 3, 3) float.
    """
    return rot_z(yaw) @ rot_y(-np.asarray(pitch, dtype=float)) @ rot_x(roll)


def yaw_pitch_roll_from_rotation(rotation):
    """Inverse of :func:`rotation_from_yaw_pitch_roll`.

    rotation : (..., 3, 3) float. Returns yaw, pitch, roll : (...,) float radians, yaw and roll in
    (-pi, pi], pitch in [-pi/2, pi/2]. At pitch = +-pi/2 roll is set to 0 (gimbal lock).
    """
    r = np.asarray(rotation, dtype=float)
    cos_p = np.hypot(r[..., 0, 0], r[..., 1, 0])
    pitch = np.arctan2(r[..., 2, 0], cos_p)  # well conditioned near +-pi/2, where arcsin is not
    locked = cos_p < 1e-12
    yaw = np.where(locked, np.arctan2(-r[..., 0, 1], r[..., 1, 1]), np.arctan2(r[..., 1, 0], r[..., 0, 0]))
    roll = np.where(locked, 0.0, np.arctan2(r[..., 2, 1], r[..., 2, 2]))
    return _half_open(yaw, np.pi), pitch, _half_open(roll, np.pi)


def _half_open(angle, half_turn):
    """Map an angle in [-half_turn, half_turn] into (-half_turn, half_turn] (arctan2 can return -pi)."""
    return np.where(angle <= -half_turn, angle + 2 * half_turn, angle) + 0.0


def carla_to_iso(location, rotation_deg):
    """CARLA pose -> ISO 8855 pose.

    location : (..., 3) float, metres, CARLA frame (y right).
    rotation_deg : (..., 3) float, CARLA ``[pitch, yaw, roll]`` in degrees (any multiple of 360 apart).
    Returns (position (..., 3) float metres ISO, R_vehicle_cam (..., 3, 3) float ISO).
    """
    location = np.asarray(location, dtype=float)
    pitch, yaw, roll = np.moveaxis(np.deg2rad(np.asarray(rotation_deg, dtype=float)), -1, 0)
    # S Rz(a) S = Rz(-a), S Ry(a) S = Ry(a), S Rx(a) S = Rx(-a): the reflection flips yaw and CARLA's -roll.
    return location * np.array([1.0, -1.0, 1.0]), rotation_from_yaw_pitch_roll(-yaw, pitch, roll)


def iso_to_carla(position, rotation):
    """ISO 8855 pose -> CARLA pose; inverse of :func:`carla_to_iso`.

    position : (..., 3) float metres ISO; rotation : (..., 3, 3) float ISO R_vehicle_cam.
    Returns (location (..., 3) metres CARLA, rotation_deg (..., 3) CARLA ``[pitch, yaw, roll]`` in
    degrees, yaw and roll in (-180, 180]).
    """
    yaw, pitch, roll = yaw_pitch_roll_from_rotation(rotation)
    angles = np.stack([np.rad2deg(pitch), -np.rad2deg(yaw), np.rad2deg(roll)], axis=-1)
    location = np.asarray(position, dtype=float) * np.array([1.0, -1.0, 1.0])
    return location, wrap_degrees(angles)


def rotation_from_rpy(roll, pitch, yaw):
    """URDF's fixed-axis ``rpy`` -> rotation ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``.

    roll, pitch, yaw : (...,) float, radians (ROS: pitch > 0 tilts the x axis down). Returns (..., 3, 3) float.
    """
    return rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)


def rpy_from_rotation(rotation):
    """Inverse of :func:`rotation_from_rpy`: (3, 3) float -> (roll, pitch, yaw) floats in radians.

    The same decomposition as :func:`yaw_pitch_roll_from_rotation` (ROS's pitch is rigopt's -pitch); at
    gimbal lock (pitch = +-pi/2) all of the turn goes into yaw.
    """
    yaw, pitch, roll = yaw_pitch_roll_from_rotation(rotation)
    return float(roll), float(-pitch) + 0.0, float(yaw)


def wrap_degrees(angle_deg):
    """Wrap angles to (-180, 180] degrees. angle_deg : (...,) float -> (...,) float."""
    wrapped = -np.mod(-np.asarray(angle_deg, dtype=float) + 180.0, 360.0) + 180.0
    return _half_open(wrapped, 180.0)  # also normalises -0.0 to 0.0


def geodesic_distance(rotation_a, rotation_b):
    """Angle of ``M = Ra^T Rb`` in radians, in [0, pi]: the metric's ``arccos((trace(M) - 1) / 2)``.

    rotation_a, rotation_b : (..., 3, 3) float, broadcastable. Returns (...,) float radians.
    """
    a, b = np.asarray(rotation_a, dtype=float), np.asarray(rotation_b, dtype=float)
    return rotation_angle(np.swapaxes(a, -1, -2) @ b)


def rotation_angle(relative):
    """Angle in radians, in [0, pi], of relative rotations ``M`` (..., 3, 3) (e.g. ``Ra^T Rb``).

    Computed as ``atan2(||M - M^T||_F / (2 sqrt 2), (trace(M) - 1) / 2)``: the sine and cosine of the same
    angle for a rotation, but well conditioned everywhere, where the arccos of a rounded trace is off by up
    to sqrt(machine epsilon) ~ 1e-8 rad near 0 and pi. ``M`` of a rotation with itself is exactly
    symmetric, so the distance of a rotation to itself is exactly 0. Used where the matrices are at hand
    (:func:`geodesic_distance`); the batched metric cores compare cameras through their quaternions
    (:func:`quaternion_angle`), which costs a third of the arithmetic.
    """
    m = np.asarray(relative, dtype=float)
    skew = m - np.swapaxes(m, -1, -2)
    sine = np.sqrt(np.einsum("...ij,...ij->...", skew, skew) / 8.0)
    cosine = (np.trace(m, axis1=-2, axis2=-1) - 1.0) / 2.0
    return np.arctan2(sine, cosine)


def quaternion_to_matrix(quaternion):
    """Unit quaternion ``(w, x, y, z)`` (scalar first) -> rotation matrix.

    quaternion : (..., 4) float, normalised here. Returns (..., 3, 3) float.
    """
    q = np.asarray(quaternion, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )


def matrix_to_quaternion(rotation):
    """Rotation matrix -> unit quaternion ``(w, x, y, z)`` with w >= 0.

    rotation : (..., 3, 3) float. Returns (..., 4) float (a (3, 3) input gives (4,)). Shepperd's method:
    each matrix uses the formula of its largest diagonal term (trace, r00, r11, r22; the first on ties),
    which keeps the divisor away from 0.
    """
    r = np.asarray(rotation, dtype=float)
    flat = r.reshape(-1, 3, 3)
    diagonal = np.stack([np.trace(flat, axis1=-2, axis2=-1), flat[:, 0, 0], flat[:, 1, 1], flat[:, 2, 2]], axis=1)
    branch = np.argmax(diagonal, axis=1)
    q = np.empty((len(flat), 4))
    for k in range(4):
        rows = np.flatnonzero(branch == k)
        if len(rows):
            q[rows] = _shepperd(k, flat[rows])
    q = np.where(q[:, :1] >= 0, q, -q)
    return q.reshape(*r.shape[:-2], 4)


def _shepperd(branch: int, r: np.ndarray) -> np.ndarray:
    """Shepperd's formula ``branch`` (0: trace, 1-3: r00, r11, r22 largest) of rotations r (n, 3, 3) ->
    (n, 4) quaternions (w, x, y, z), w of either sign."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = (r[:, i, j] for i in range(3) for j in range(3))
    if branch == 0:
        s = 2.0 * np.sqrt(1.0 + (r00 + r11 + r22))
        return np.stack([0.25 * s, (r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s], axis=1)
    if branch == 1:
        s = 2.0 * np.sqrt(1.0 + r00 - r11 - r22)
        return np.stack([(r21 - r12) / s, 0.25 * s, (r01 + r10) / s, (r02 + r20) / s], axis=1)
    if branch == 2:
        s = 2.0 * np.sqrt(1.0 + r11 - r00 - r22)
        return np.stack([(r02 - r20) / s, (r01 + r10) / s, 0.25 * s, (r12 + r21) / s], axis=1)
    s = 2.0 * np.sqrt(1.0 + r22 - r00 - r11)
    return np.stack([(r10 - r01) / s, (r02 + r20) / s, (r12 + r21) / s, 0.25 * s], axis=1)


def quaternion_angle(quaternion_a, quaternion_b, axis: int = -1):
    """Angle in radians, in [0, pi], of the rotation between two unit quaternions (either sign).

    quaternion_a, quaternion_b : (..., 4) float, unit, broadcastable, components ``(w, x, y, z)`` along
    ``axis`` (default last; ``axis=0`` takes (4, ...) arrays). Returns the broadcast shape without that
    axis, float radians.

    With ``phi`` the angle between the two 4-vectors, ``atan2(|qa - qb|, |qa + qb|) = phi / 2``, and the
    rotation angle is ``2 min(phi, pi - phi)`` (q and -q are the same rotation), so

        angle = 4 atan2(min(|qa - qb|, |qa + qb|), max(|qa - qb|, |qa + qb|))

    Both norms come from differences and sums, never from ``1 - qa . qb``: accurate to a few ulps over
    the whole range (the arccos of a dot product or trace loses ~1e-8 rad near 0 and pi). A quaternion with
    itself (or its negative) gives exactly 0; the result is exactly symmetric in its arguments and the
    same, bit for bit, whichever axis holds the components.
    """
    a = np.moveaxis(np.asarray(quaternion_a, dtype=float), axis, 0)
    b = np.moveaxis(np.asarray(quaternion_b, dtype=float), axis, 0)
    difference = np.subtract(a, b)
    d2 = sum_of_squares(difference)
    s2 = sum_of_squares(np.add(a, b, out=difference))
    return 4.0 * np.arctan2(np.sqrt(np.minimum(d2, s2)), np.sqrt(np.maximum(d2, s2)))


def sum_of_squares(components) -> np.ndarray:
    """``sum_k components[k] ** 2`` over the first axis, added in index order (so the same bits whatever
    the layout). components : (k, ...) float -> (...) float."""
    c = np.asarray(components, dtype=float)
    total = np.asarray(c[0] * c[0])
    square = np.empty_like(total)
    for k in range(1, len(c)):
        total += np.multiply(c[k], c[k], out=square)
    return total


def is_rotation(rotation, atol=1e-6):
    """True where ``rotation`` (..., 3, 3) is orthonormal with determinant +1 within ``atol``."""
    r = np.asarray(rotation, dtype=float)
    eye = np.broadcast_to(np.eye(3), r.shape)
    orthonormal = np.all(np.abs(np.swapaxes(r, -1, -2) @ r - eye) < atol, axis=(-1, -2))
    return orthonormal & (np.abs(np.linalg.det(r) - 1.0) < atol)


def clip_polygon(polygon, axis: int, bound: float, side: float) -> np.ndarray:
    """The part of a convex planar ``polygon`` (k, 3) where ``side * (p[axis] - bound) >= 0``, as (j, 3): one
    Sutherland-Hodgman step against an axis-aligned plane (j < 3 when nothing of it is on that side)."""
    polygon = np.asarray(polygon, dtype=float)
    inside = side * (polygon[:, axis] - bound)
    kept = []
    for k in range(len(polygon)):
        a, b = polygon[k], polygon[(k + 1) % len(polygon)]
        da, db = inside[k], inside[(k + 1) % len(polygon)]
        if da >= 0:
            kept.append(a)
        if (da >= 0) != (db >= 0):
            kept.append(a + (b - a) * (da / (da - db)))
    return np.array(kept).reshape(-1, 3)
