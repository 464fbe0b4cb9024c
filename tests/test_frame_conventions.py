"""Each frame convention of rigopt.geometry against scipy's Rotation (the sequence letters and quaternion order
stated in the module) and against the tool's own documented formula or example values: ISO 8855 yaw/pitch/roll,
CARLA's RotateVector, URDF's fixed-axis rpy and the ROS optical frame, scalar-first quaternions (nuScenes), the
casadi twins used by the designer's refinement."""

from __future__ import annotations

import math

import numpy as np
import pytest
from carla_convention import carla_rotate_vector
from hypothesis import example, given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from rigopt.geometry import (
    R_CAM_OPTICAL,
    S_CARLA_ISO,
    body_from_optical,
    carla_to_iso,
    geodesic_distance,
    iso_to_carla,
    matrix_to_quaternion,
    nearest_rotation,
    optical_from_body,
    quaternion_angle,
    quaternion_to_matrix,
    rot_x,
    rot_y,
    rot_z,
    rotation_angle,
    rotation_from_rpy,
    rotation_from_yaw_pitch_roll,
    rpy_from_rotation,
    symbolic_rotation_angle,
    symbolic_rotation_from_yaw_pitch,
    yaw_pitch_roll_from_rotation,
)
from rigopt.rig.formats.urdf import OPTICAL_RPY

angle = st.floats(-math.pi, math.pi)
away_from_lock = st.floats(-math.pi / 2 + 0.01, math.pi / 2 - 0.01)
unit_quaternions = st.tuples(*[st.floats(-1.0, 1.0)] * 4).map(np.array).filter(lambda q: np.linalg.norm(q) > 0.1)
ULPS = 1e-15  # a few ulps of a matrix entry (4.4e-16 apart seen between the two routes)


# --- ISO 8855 camera angles: scipy's intrinsic "ZYX" of (yaw, -pitch, roll) ------------------------------------


@given(yaw=angle, pitch=angle, roll=angle)
def test_yaw_pitch_roll_is_scipy_intrinsic_zyx(yaw, pitch, roll):
    expected = Rotation.from_euler("ZYX", [yaw, -pitch, roll]).as_matrix()
    np.testing.assert_allclose(rotation_from_yaw_pitch_roll(yaw, pitch, roll), expected, rtol=0, atol=ULPS)


@given(yaw=angle, pitch=away_from_lock, roll=angle)
def test_yaw_pitch_roll_decomposition_is_scipy_as_euler_zyx(yaw, pitch, roll):
    rotation = Rotation.from_euler("ZYX", [yaw, -pitch, roll])
    expected_yaw, minus_pitch, expected_roll = rotation.as_euler("ZYX")
    got = yaw_pitch_roll_from_rotation(rotation.as_matrix())
    # the same angles, modulo the half-open range's choice at +-pi
    for value, reference in zip(got, (expected_yaw, -minus_pitch, expected_roll)):
        assert abs(math.remainder(float(value) - reference, 2 * math.pi)) < 1e-12


def test_batched_yaw_pitch_roll_equals_one_at_a_time():
    rng = np.random.default_rng(3)
    yaw, pitch = rng.uniform(-3, 3, (4, 5)), rng.uniform(-1.5, 1.5, (4, 5))
    batch = rotation_from_yaw_pitch_roll(yaw, pitch, 0.0 * yaw)
    assert batch.shape == (4, 5, 3, 3)
    for i, j in np.ndindex(4, 5):
        assert np.array_equal(batch[i, j], rotation_from_yaw_pitch_roll(yaw[i, j], pitch[i, j], 0.0))


@pytest.mark.parametrize("builder, axis", [(rot_x, "x"), (rot_y, "y"), (rot_z, "z")])
@given(value=angle)
def test_elementary_rotations_are_scipy_s(builder, axis, value):
    np.testing.assert_allclose(builder(value), Rotation.from_euler(axis, value).as_matrix(), rtol=0, atol=ULPS)


def test_a_rolled_camera_turns_its_top_to_the_right():
    # roll > 0 is a right-handed turn about the optical axis (x): the top (z) goes to -y, the right in ISO 8855
    up = rotation_from_yaw_pitch_roll(0.0, 0.0, math.radians(30)) @ [0.0, 0.0, 1.0]
    np.testing.assert_allclose(up, [0.0, -0.5, math.sqrt(3) / 2], atol=1e-15)
    # and CARLA's roll > 0 is the same turn (issue 29: roll keeps its sign between the two frames)
    _, carla = carla_to_iso([0.0, 0.0, 0.0], [0.0, 0.0, 30.0])
    np.testing.assert_allclose(carla, rotation_from_yaw_pitch_roll(0.0, 0.0, math.radians(30)), atol=1e-15)


# --- CARLA: RotateVector in CARLA's left-handed axes, reflected by S ----------------------------------------------


@given(pitch=st.floats(-89.0, 89.0), yaw=st.floats(-180.0, 180.0), roll=st.floats(-180.0, 180.0))
def test_carla_is_scipy_zyx_of_its_angles_reflected(pitch, yaw, roll):
    carla = Rotation.from_euler("ZYX", [yaw, -pitch, -roll], degrees=True).as_matrix()
    np.testing.assert_allclose(carla, carla_rotate_vector(pitch, yaw, roll), rtol=0, atol=1e-15)
    _, iso = carla_to_iso([0.0, 0.0, 0.0], [pitch, yaw, roll])
    np.testing.assert_allclose(iso, S_CARLA_ISO @ carla @ S_CARLA_ISO, rtol=0, atol=ULPS)


@pytest.mark.parametrize("pitch, yaw, roll, forward_carla", [
    (0.0, 90.0, 0.0, [0.0, 1.0, 0.0]),     # CARLA: yaw 90 faces +y, to the right
    (0.0, -90.0, 0.0, [0.0, -1.0, 0.0]),
    (90.0, 0.0, 0.0, [0.0, 0.0, 1.0]),     # pitch 90 looks up
    (0.0, 180.0, 0.0, [-1.0, 0.0, 0.0]),
])
def test_carla_documented_directions(pitch, yaw, roll, forward_carla):
    _, iso = carla_to_iso([0.0, 0.0, 0.0], [pitch, yaw, roll])
    np.testing.assert_allclose(S_CARLA_ISO @ iso[:, 0], forward_carla, atol=1e-15)


def test_carla_roll_turns_the_camera_top_to_the_right():
    _, iso = carla_to_iso([0.0, 0.0, 0.0], [0.0, 0.0, 30.0])
    up_carla = S_CARLA_ISO @ iso[:, 2]
    assert up_carla[1] > 0.4  # toward CARLA's +y, the right
    np.testing.assert_allclose(up_carla, carla_rotate_vector(0.0, 0.0, 30.0)[:, 2], atol=1e-15)


@pytest.mark.parametrize("degrees", [0.0, 41.0, 90.0, 135.0, 148.5, 180.0, -146.0, -33.5])
def test_carla_round_trip_keeps_whole_and_half_degrees_exactly(degrees):
    # The benchmark's rig files hold whole and half degrees; writing them back gives the same bytes.
    _, iso = carla_to_iso([0.0, 0.0, 0.0], [0.0, degrees, 0.0])
    _, back = iso_to_carla([0.0, 0.0, 0.0], iso)
    assert back.tolist() == [0.0, degrees, 0.0]


# --- URDF: fixed-axis rpy, scipy's extrinsic "xyz" --------------------------------------------------------------


@given(roll=angle, pitch=angle, yaw=angle)
def test_urdf_rpy_is_scipy_extrinsic_xyz_and_rz_ry_rx(roll, pitch, yaw):
    expected = Rotation.from_euler("xyz", [roll, pitch, yaw]).as_matrix()
    got = rotation_from_rpy(roll, pitch, yaw)
    np.testing.assert_allclose(got, expected, rtol=0, atol=ULPS)
    # URDF's documented composition: roll about the fixed x, then pitch about the fixed y, then yaw about fixed z
    np.testing.assert_allclose(got, rot_z(yaw) @ rot_y(pitch) @ rot_x(roll), rtol=0, atol=ULPS)


@given(roll=angle, pitch=away_from_lock, yaw=angle)
def test_urdf_rpy_round_trip_and_scipy_as_euler(roll, pitch, yaw):
    matrix = rotation_from_rpy(roll, pitch, yaw)
    got = rpy_from_rotation(matrix)
    expected = Rotation.from_matrix(matrix).as_euler("xyz")
    for value, reference, original in zip(got, expected, (roll, pitch, yaw)):
        assert abs(math.remainder(value - reference, 2 * math.pi)) < 1e-12
        assert abs(math.remainder(value - original, 2 * math.pi)) < 1e-12


def test_ros_optical_frame_rpy_is_the_optical_rotation():
    # REP 103: a camera's *_optical_frame sits at rpy (-pi/2, 0, -pi/2) from its body frame (x forward, z up)
    np.testing.assert_allclose(rotation_from_rpy(*OPTICAL_RPY), R_CAM_OPTICAL, atol=1e-15)


def test_urdf_gimbal_lock_puts_the_turn_into_yaw():
    matrix = rotation_from_rpy(0.3, math.pi / 2, 0.5)
    roll, pitch, yaw = rpy_from_rotation(matrix)
    assert roll == 0.0 and pitch == pytest.approx(math.pi / 2)
    np.testing.assert_allclose(rotation_from_rpy(roll, pitch, yaw), matrix, atol=1e-12)


# --- optical frame ------------------------------------------------------------------------------------------------


def test_optical_axes_in_the_body_frame():
    # OpenCV: z along the optical axis, x right, y down; rigopt's body: x forward, y left, z up
    np.testing.assert_array_equal(R_CAM_OPTICAL @ [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    np.testing.assert_array_equal(R_CAM_OPTICAL @ [1.0, 0.0, 0.0], [0.0, -1.0, 0.0])
    np.testing.assert_array_equal(R_CAM_OPTICAL @ [0.0, 1.0, 0.0], [0.0, 0.0, -1.0])


@given(yaw=angle, pitch=angle, roll=angle)
def test_body_and_optical_conversions_are_inverse(yaw, pitch, roll):
    body = rotation_from_yaw_pitch_roll(yaw, pitch, roll)
    np.testing.assert_allclose(body_from_optical(optical_from_body(body)), body, rtol=0, atol=1e-15)
    np.testing.assert_allclose(optical_from_body(body)[:, 2], body[:, 0], atol=1e-15)  # same optical axis


# --- quaternions: scalar first (nuScenes, Argoverse, DGP) vs scipy's scalar last ----------------------------------

#: nuScenes v1.0, log n015-2018-07-24-11-22-45+0800, calibrated_sensor ``rotation`` [w, x, y, z] of R_ego_optical
#: (baselines/rigs/real/write_sources.py), and the yaw (deg) of each camera in nuScenes' documented layout.
NUSCENES = {"CAM_FRONT": ([0.4998015430569128, -0.5030316162024876, 0.4997798114386805, -0.49737083824542755], 0.0),
            "CAM_FRONT_LEFT": ([0.6757265034669446, -0.6736266522251881, 0.21214015046209478, -0.21122827103904068],
                               55.0),
            "CAM_BACK": ([0.5037872666382278, -0.49740249788611096, -0.4941850223835201, 0.5045496097725578], 180.0)}


@pytest.mark.parametrize("channel", list(NUSCENES))
def test_nuscenes_quaternions_are_scalar_first(channel):
    quaternion, yaw_deg = NUSCENES[channel]
    body = body_from_optical(quaternion_to_matrix(quaternion))
    yaw, pitch, roll = (math.degrees(float(a)) for a in yaw_pitch_roll_from_rotation(body))
    assert abs(math.remainder(yaw - yaw_deg, 360.0)) < 3.0 and abs(pitch) < 3.0 and abs(roll) < 3.0
    if channel != "CAM_FRONT":  # read scalar last, the same numbers are another rotation
        misread = body_from_optical(quaternion_to_matrix(quaternion, scalar_first=False))
        assert math.degrees(geodesic_distance(misread, body)) > 30.0


#: Quaternions of any norm are normalised by both routes in a different order: up to 5 ulps of 1 apart (1.1e-15,
#: at q = (0.08, 0.08, 0.745, 0.745)).
NORMALISED_ULPS = 8 * np.finfo(float).eps


@given(q=unit_quaternions)
@example(q=np.array([0.08, 0.08, 0.74502604, 0.74502604]))
def test_quaternion_to_matrix_is_scipy_from_quat_in_both_orders(q):
    np.testing.assert_allclose(quaternion_to_matrix(q), Rotation.from_quat(q, scalar_first=True).as_matrix(),
                               rtol=0, atol=NORMALISED_ULPS)
    np.testing.assert_allclose(quaternion_to_matrix(q, scalar_first=False), Rotation.from_quat(q).as_matrix(),
                               rtol=0, atol=NORMALISED_ULPS)


@given(q=unit_quaternions)
def test_matrix_to_quaternion_is_scipy_s_canonical_quaternion(q):
    q = q / np.linalg.norm(q)
    if abs(q[0]) < 1e-6:  # w = 0: scipy's sign rule on x, y, z is not rigopt's (either is the rotation)
        q[0] = 1e-3
    matrix = Rotation.from_quat(q, scalar_first=True).as_matrix()
    expected = Rotation.from_matrix(matrix).as_quat(canonical=True, scalar_first=True)
    np.testing.assert_allclose(matrix_to_quaternion(matrix), expected, rtol=0, atol=1e-15)
    np.testing.assert_allclose(matrix_to_quaternion(matrix, scalar_first=False), expected[[1, 2, 3, 0]], atol=1e-15)


# --- angles -------------------------------------------------------------------------------------------------------


@given(a=unit_quaternions, b=unit_quaternions)
def test_quaternion_angle_is_scipy_s_relative_magnitude(a, b):
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    expected = (Rotation.from_quat(a, scalar_first=True).inv() * Rotation.from_quat(b, scalar_first=True)).magnitude()
    assert quaternion_angle(a, b) == pytest.approx(expected, abs=1e-12)


@given(a=unit_quaternions, b=unit_quaternions)
def test_geodesic_distance_is_the_documented_arccos_of_the_trace(a, b):
    ra, rb = quaternion_to_matrix(a), quaternion_to_matrix(b)
    cosine = (np.trace(ra.T @ rb) - 1.0) / 2.0
    if abs(cosine) < 0.99:  # where the arccos is well conditioned
        assert geodesic_distance(ra, rb) == pytest.approx(math.acos(cosine), abs=1e-12)
    assert rotation_angle(ra.T @ rb) == pytest.approx(geodesic_distance(ra, rb), abs=1e-12)


def test_nearest_rotation_projects_onto_so3_as_scipy_does():
    rng = np.random.default_rng(5)
    rotation = quaternion_to_matrix(rng.normal(size=4))
    noisy = rotation + 1e-4 * rng.normal(size=(3, 3))
    nearest = nearest_rotation(noisy)
    np.testing.assert_allclose(nearest @ nearest.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(nearest) == pytest.approx(1.0, abs=1e-14)
    np.testing.assert_allclose(nearest, Rotation.from_matrix(noisy).as_matrix(), atol=1e-12)


# --- the casadi twins ---------------------------------------------------------------------------------------------


@given(yaw=angle, pitch=away_from_lock)
def test_symbolic_rotation_is_the_numeric_one(yaw, pitch):
    ca = pytest.importorskip("casadi")
    y, p = ca.MX.sym("yaw"), ca.MX.sym("pitch")
    evaluate = ca.Function("rotation", [y, p], [symbolic_rotation_from_yaw_pitch(ca, y, p)])
    np.testing.assert_allclose(np.array(evaluate(yaw, pitch)), rotation_from_yaw_pitch_roll(yaw, pitch, 0.0),
                               rtol=0, atol=ULPS)


def test_symbolic_angle_is_the_numeric_one():
    ca = pytest.importorskip("casadi")
    rng = np.random.default_rng(7)
    m = ca.MX.sym("m", 3, 3)
    for smoothing in (0.0, 1e-6):
        evaluate = ca.Function("angle", [m], [symbolic_rotation_angle(ca, m, smoothing)])
        for q in rng.normal(size=(20, 4)):
            relative = quaternion_to_matrix(q)
            expected = math.atan2(math.sqrt(math.sin(rotation_angle(relative)) ** 2 + smoothing),
                                  math.cos(rotation_angle(relative)))
            assert float(evaluate(relative)) == pytest.approx(expected, abs=1e-12)
