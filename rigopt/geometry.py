"""Frames and SO(3): the one module that owns rigopt's frame conventions and every rotation it computes.

The conventions are data: each is stated below as scipy's :class:`scipy.spatial.transform.Rotation` states it
(``from_euler`` / ``as_euler`` sequence letters, ``from_quat`` / ``as_quat`` with ``scalar_first``), and
``tests/test_frame_conventions.py`` holds every function here to scipy's result and to the tool's own published
formula. Angles and geodesic distances are computed by scipy (``magnitude``). The builders and decompositions
(Euler angles, quaternion <-> matrix) are closed forms here, not scipy calls: every rig file and export passes
through them, and scipy's quaternion route (``from_euler`` -> ``as_matrix``, ``from_matrix`` -> ``as_euler``)
agrees with them to 2-4 ulps but not bit for bit, and is the less exact of the two on a round trip (CARLA yaw 90
read and written back gives 89.99999999999999 through scipy, 90.0 here; over a half-degree grid of yaws and
pitches, 80 % of yaws come back exactly through scipy, 97.5 % here). Three more pieces are written here by hand,
each with its reason: :func:`quaternion_angle`, the RigCD kernel on component-first quaternion columns (a few
ulps over the whole range, exactly symmetric; 9 ms for 100,000 pairs where scipy's ``(a.inv() * b).magnitude()``
takes 150 ms); the casadi twins :func:`symbolic_rotation_from_yaw_pitch` and :func:`symbolic_rotation_angle`
(scipy cannot take symbols), tested against the numeric functions; and the frame constants (signed
permutations). No other module of rigopt, ``benchmarks/`` or ``studies/`` builds, decomposes or compares
rotations, or imports scipy's Rotation: ``tests/test_rotation_owner.py`` fails when one does.

Conventions
-----------
Vehicle frame (everywhere inside rigopt): ISO 8855, right-handed, origin at the vehicle's reference
point on the ground, x forward, y left, z up. Positions are in metres.

Camera body frame: x along the optical axis (forward), y left, z up, so that a camera with the identity
rotation looks straight ahead. ``R_vehicle_cam`` (3, 3) maps camera-body directions into the vehicle
frame: ``d_vehicle = R_vehicle_cam @ d_cam``. Its angles (:func:`rotation_from_yaw_pitch_roll`):
``R = Rz(yaw) @ Ry(-pitch) @ Rx(roll)``, scipy's intrinsic ``"ZYX"`` of ``(yaw, -pitch, roll)``; yaw > 0
turns left, pitch > 0 tilts the lens up, roll > 0 turns the camera's top to the right.

Camera optical frame (pinhole, OpenCV, ROS ``*_optical_frame``, nuScenes, Argoverse, DGP): z forward, x right,
y down. ``R_CAM_OPTICAL`` maps optical directions into the camera body frame, so a file's ``R_ego_optical``
is rigopt's ``R_vehicle_cam = R_ego_optical @ R_CAM_OPTICAL.T`` (:func:`body_from_optical`).

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
ISO axes: scipy's extrinsic ``"xyz"`` of ``(roll, pitch, yaw)`` (:func:`rotation_from_rpy`,
:func:`rpy_from_rotation`); ROS's pitch is rigopt's -pitch.

Quaternions: rigopt and the datasets (nuScenes, Argoverse 1 and 2, DGP, the benchmark's tables) write them
scalar first, ``(w, x, y, z)``; scipy's default is scalar last. Every quaternion function here takes
``scalar_first`` (default True, rigopt's order) and passes it to scipy; written quaternions are canonical
(w >= 0; scipy's rule for w = 0).

Angles are radians inside rigopt; degrees appear only at the file and CLI edges (and in FOVs).

The module also holds two small pieces of plain geometry that are not rotations: :func:`sum_of_squares`
(the metric cores' fixed-order sums) and :func:`clip_polygon`.
"""

from __future__ import annotations

import numpy as np

#: Reflection between the CARLA frame (y right) and ISO 8855 (y left); its own inverse.
S_CARLA_ISO = np.diag([1.0, -1.0, 1.0])
S_CARLA_ISO.flags.writeable = False

#: Optical frame (z forward, x right, y down) -> camera body frame (x forward, y left, z up).
R_CAM_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
R_CAM_OPTICAL.flags.writeable = False


def _rotations(rotation) -> "Rotation":
    """The Rotation stack of matrices (..., 3, 3) float, flattened to (n,)."""
    from scipy.spatial.transform import Rotation  # on first use: reading and comparing rigs needs no scipy

    r = np.asarray(rotation, dtype=float)
    return Rotation.from_matrix(r.reshape(-1, 3, 3))


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
    """ISO 8855 rotation ``Rz(yaw) @ Ry(-pitch) @ Rx(roll)`` of a camera body: scipy's
    ``Rotation.from_euler("ZYX", [yaw, -pitch, roll])``.

    yaw, pitch, roll : (...,) float, broadcastable, radians; yaw > 0 turns left, pitch > 0 tilts the lens up,
    roll > 0 turns the camera's top to the right. Returns R_vehicle_cam : (..., 3, 3) float.
    """
    return rot_z(yaw) @ rot_y(-np.asarray(pitch, dtype=float)) @ rot_x(roll)


def yaw_pitch_roll_from_rotation(rotation):
    """Inverse of :func:`rotation_from_yaw_pitch_roll`: scipy's ``as_euler("ZYX")`` read as (yaw, -pitch, roll).

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
    """URDF's fixed-axis ``rpy`` -> rotation ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``: scipy's
    ``Rotation.from_euler("xyz", [roll, pitch, yaw])`` (lower case: extrinsic, fixed axes).

    roll, pitch, yaw : (...,) float, broadcastable, radians (ROS: pitch > 0 tilts the x axis down).
    Returns (..., 3, 3) float.
    """
    return rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)


def rpy_from_rotation(rotation):
    """Inverse of :func:`rotation_from_rpy`: (3, 3) float -> (roll, pitch, yaw) floats in radians (scipy's
    ``as_euler("xyz")`` away from gimbal lock).

    The same decomposition as :func:`yaw_pitch_roll_from_rotation` (ROS's pitch is rigopt's -pitch); at
    gimbal lock (pitch = +-pi/2) all of the turn goes into yaw and roll is 0 (scipy puts it into roll).
    """
    yaw, pitch, roll = yaw_pitch_roll_from_rotation(rotation)
    return float(roll), float(-pitch) + 0.0, float(yaw)


def body_from_optical(r_ego_optical):
    """rigopt's ``R_vehicle_cam`` (..., 3, 3) of cameras whose optical frames map into the vehicle frame by
    ``r_ego_optical`` (..., 3, 3) float."""
    return np.asarray(r_ego_optical, dtype=float) @ R_CAM_OPTICAL.T


def optical_from_body(r_vehicle_cam):
    """``R_vehicle_optical`` (..., 3, 3) of cameras whose body frames are ``r_vehicle_cam`` (..., 3, 3) float."""
    return np.asarray(r_vehicle_cam, dtype=float) @ R_CAM_OPTICAL


def wrap_degrees(angle_deg):
    """Wrap angles to (-180, 180] degrees. angle_deg : (...,) float -> (...,) float."""
    wrapped = -np.mod(-np.asarray(angle_deg, dtype=float) + 180.0, 360.0) + 180.0
    return _half_open(wrapped, 180.0)  # also normalises -0.0 to 0.0


def geodesic_distance(rotation_a, rotation_b):
    """Angle of ``M = Ra^T Rb`` in radians, in [0, pi] (scipy's ``magnitude`` of ``Ra.inv() * Rb``): the
    metric's ``arccos((trace(M) - 1) / 2)``, accurate near 0 and pi; exactly 0 for a rotation with itself.

    rotation_a, rotation_b : (..., 3, 3) float, broadcastable. Returns (...,) float radians.
    """
    a, b = np.broadcast_arrays(np.asarray(rotation_a, dtype=float), np.asarray(rotation_b, dtype=float))
    return (_rotations(a).inv() * _rotations(b)).magnitude().reshape(a.shape[:-2])


def rotation_angle(relative):
    """Angle in radians, in [0, pi], of relative rotations ``M`` (..., 3, 3) (e.g. ``Ra^T Rb``): scipy's
    ``magnitude``. Returns (...,) float."""
    m = np.asarray(relative, dtype=float)
    return _rotations(m).magnitude().reshape(m.shape[:-2])


def quaternion_to_matrix(quaternion, scalar_first: bool = True):
    """Quaternions -> rotation matrices: scipy's ``Rotation.from_quat(q, scalar_first=...).as_matrix()``.

    quaternion : (..., 4) float, normalised here; ``(w, x, y, z)`` when ``scalar_first`` (rigopt's and the
    datasets' order), else ``(x, y, z, w)`` (scipy's default). Returns (..., 3, 3) float.
    """
    q = np.asarray(quaternion, dtype=float)
    if not scalar_first:
        q = q[..., [3, 0, 1, 2]]
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


def matrix_to_quaternion(rotation, scalar_first: bool = True):
    """Rotation matrices -> unit quaternions with w >= 0: scipy's ``Rotation.from_matrix(r).as_quat(
    canonical=True, scalar_first=...)`` (which also fixes the sign where w = 0; here such a quaternion keeps
    the sign its formula gives).

    rotation : (..., 3, 3) float. Returns (..., 4) float (a (3, 3) input gives (4,)), ``(w, x, y, z)`` when
    ``scalar_first``, else ``(x, y, z, w)``. Shepperd's method:
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
    if not scalar_first:
        q = q[:, [1, 2, 3, 0]]
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


def nearest_rotation(matrix):
    """The rotation nearest to ``matrix`` (3, 3) float in the Frobenius norm, ``U @ Vt`` of its SVD (what scipy's
    ``from_matrix`` projects a matrix that is not orthonormal onto; the caller checks that it is close to
    one). Returns (3, 3) float."""
    u, _, vt = np.linalg.svd(np.asarray(matrix, dtype=float))
    return u @ vt


def symbolic_rotation_from_yaw_pitch(ca, yaw, pitch):
    """The casadi twin of :func:`rotation_from_yaw_pitch_roll` at roll 0: ``Rz(yaw) @ Ry(-pitch)`` as a 3x3
    casadi expression of scalar symbols ``yaw``, ``pitch`` (radians); ``ca`` is the casadi module."""
    cy, sy, cp, sp = ca.cos(yaw), ca.sin(yaw), ca.cos(pitch), ca.sin(pitch)
    return ca.vertcat(ca.horzcat(cy * cp, -sy, -cy * sp), ca.horzcat(sy * cp, cy, -sy * sp), ca.horzcat(sp, 0, cp))


def symbolic_rotation_angle(ca, relative, smoothing: float):
    """The casadi twin of :func:`rotation_angle`: ``atan2(sqrt(||M - M^T||_F^2 / 8 + smoothing), (trace(M) - 1) / 2)``
    of a 3x3 casadi expression ``M`` (the sine and cosine of the angle; ``smoothing`` > 0 keeps the gradient
    finite at 0 and adds about sqrt(smoothing) rad there). Returns a casadi scalar, radians."""
    skew = relative - relative.T
    return ca.atan2(ca.sqrt(ca.sumsqr(skew) / 8 + smoothing), (ca.trace(relative) - 1) / 2)


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
