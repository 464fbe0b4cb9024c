"""rigopt.geometry: elementary rotations, yaw/pitch/roll, the CARLA <-> ISO 8855 edge, SO(3) helpers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from carla_convention import carla_rotate_vector
from hypothesis import assume, example, given
from hypothesis import strategies as st

from rigopt.geometry import (
    S_CARLA_ISO,
    carla_to_iso,
    geodesic_distance,
    is_rotation,
    iso_to_carla,
    matrix_to_quaternion,
    quaternion_angle,
    quaternion_to_matrix,
    rot_x,
    rot_y,
    rot_z,
    rotation_from_yaw_pitch_roll,
    wrap_degrees,
    yaw_pitch_roll_from_rotation,
)

S = np.diag([1.0, -1.0, 1.0])
EX, EY, EZ = np.eye(3)

angles_rad = st.floats(-2 * math.pi, 2 * math.pi)
angles_deg = st.floats(-720.0, 720.0)
# Pitch kept away from +-90 deg: there yaw and roll are not separately defined (gimbal lock).
pitch_rad = st.floats(-math.pi / 2 + 0.01, math.pi / 2 - 0.01)
pitch_deg = st.floats(-89.0, 89.0)
coordinates = st.floats(-100.0, 100.0)
locations = st.tuples(coordinates, coordinates, coordinates).map(np.array)


@st.composite
def quaternions(draw):
    """Not necessarily normalised quaternions (w, x, y, z), norm in [0.1, 2]."""
    q = np.array(draw(st.tuples(*[st.floats(-1.0, 1.0)] * 4)))
    assume(np.linalg.norm(q) >= 0.1)
    return q


rotations = quaternions().map(quaternion_to_matrix)


def _angle_difference(a, b, period):
    """Signed difference a - b folded into [-period/2, period/2)."""
    return (np.asarray(a) - np.asarray(b) + period / 2) % period - period / 2


# Hand-written right-handed elementary rotations, independent of rigopt's.
def _rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def _axis_angle(axis, angle):
    """Rodrigues' formula."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


# --- elementary rotations -------------------------------------------------------------------------------


@pytest.mark.parametrize("rot", [rot_x, rot_y, rot_z])
@given(angle=angles_rad)
def test_elementary_rotation_is_orthonormal_with_det_one(rot, angle):
    r = rot(angle)
    np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-12)
    assert np.linalg.det(r) == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("rot, hand", [(rot_x, _rx), (rot_y, _ry), (rot_z, _rz)])
@given(angle=angles_rad)
def test_elementary_rotation_matches_right_handed_formula(rot, hand, angle):
    np.testing.assert_allclose(rot(angle), hand(angle), atol=1e-12)


@pytest.mark.parametrize(
    "rot, source, target",
    [(rot_x, EY, EZ), (rot_y, EZ, EX), (rot_z, EX, EY)],
    ids=["x: y->z", "y: z->x", "z: x->y"],
)
def test_quarter_turn_is_right_handed(rot, source, target):
    np.testing.assert_allclose(rot(math.pi / 2) @ source, target, atol=1e-15)


@pytest.mark.parametrize("rot", [rot_x, rot_y, rot_z])
def test_elementary_rotation_broadcasts_over_angles(rot):
    angles = np.linspace(-3.0, 3.0, 12).reshape(3, 4)
    batched = rot(angles)
    assert batched.shape == (3, 4, 3, 3)
    np.testing.assert_allclose(batched[2, 1], rot(angles[2, 1]), atol=0)


# --- yaw / pitch / roll ---------------------------------------------------------------------------------


@given(yaw=st.floats(-math.pi, math.pi), pitch=pitch_rad, roll=st.floats(-math.pi, math.pi))
def test_yaw_pitch_roll_round_trip(yaw, pitch, roll):
    y, p, r = yaw_pitch_roll_from_rotation(rotation_from_yaw_pitch_roll(yaw, pitch, roll))
    assert _angle_difference(y, yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    assert p == pytest.approx(pitch, abs=1e-9)
    assert _angle_difference(r, roll, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)


@given(rotation=rotations)
def test_yaw_pitch_roll_reconstructs_the_rotation(rotation):
    yaw, pitch, roll = yaw_pitch_roll_from_rotation(rotation)
    assert -math.pi / 2 <= pitch <= math.pi / 2
    assume(math.cos(pitch) > 1e-6)  # near gimbal lock the angles are ill-conditioned
    np.testing.assert_allclose(rotation_from_yaw_pitch_roll(yaw, pitch, roll), rotation, atol=1e-9)


@given(rotation=rotations)
@example(rotation=rot_x(-math.pi))
def test_yaw_pitch_roll_yaw_and_roll_in_half_open_range(rotation):
    yaw, _, roll = yaw_pitch_roll_from_rotation(rotation)
    assert -math.pi < yaw <= math.pi and -math.pi < roll <= math.pi


def test_rotation_from_yaw_pitch_roll_is_rz_ry_minus_pitch_rx():
    yaw, pitch, roll = 0.3, -0.7, 1.9
    np.testing.assert_allclose(
        rotation_from_yaw_pitch_roll(yaw, pitch, roll), _rz(yaw) @ _ry(-pitch) @ _rx(roll), atol=1e-14
    )


def test_identity_looks_forward():
    np.testing.assert_allclose(rotation_from_yaw_pitch_roll(0.0, 0.0, 0.0), np.eye(3), atol=0)


def test_yaw_plus_90_looks_left():
    forward = rotation_from_yaw_pitch_roll(math.pi / 2, 0.0, 0.0)[:, 0]
    np.testing.assert_allclose(forward, EY, atol=1e-15)


def test_pitch_plus_10_tilts_optical_axis_up():
    forward = rotation_from_yaw_pitch_roll(0.0, math.radians(10.0), 0.0)[:, 0]
    np.testing.assert_allclose(forward, [math.cos(math.radians(10)), 0.0, math.sin(math.radians(10))], atol=1e-15)
    assert forward[2] > 0


@pytest.mark.parametrize("sign", [1.0, -1.0])
@given(yaw=st.floats(-math.pi, math.pi), roll=st.floats(-math.pi, math.pi))
def test_gimbal_lock_sets_roll_zero_and_keeps_the_rotation(sign, yaw, roll):
    rotation = rotation_from_yaw_pitch_roll(yaw, sign * math.pi / 2, roll)
    y, p, r = yaw_pitch_roll_from_rotation(rotation)
    assert p == pytest.approx(sign * math.pi / 2, abs=1e-7)
    assert r == 0.0
    np.testing.assert_allclose(rotation_from_yaw_pitch_roll(y, p, r), rotation, atol=1e-9)


# --- CARLA <-> ISO 8855 ---------------------------------------------------------------------------------


@given(pitch=angles_deg, yaw=angles_deg, roll=angles_deg)
def test_carla_to_iso_is_carlas_rotate_vector_conjugated_by_s(pitch, yaw, roll):
    _, r_iso = carla_to_iso([0.0, 0.0, 0.0], [pitch, yaw, roll])
    np.testing.assert_allclose(r_iso, S @ carla_rotate_vector(pitch, yaw, roll) @ S, atol=1e-12)


def test_camera_at_pitch_5_yaw_30_roll_10_has_carlas_forward_right_and_up_vectors():
    """CARLA's forward, right and up vectors of the camera (its x, y, z axes rotated by RotateVector), taken to
    ISO 8855 (y left: right = -y), equal rigopt's camera axes to 1e-9."""
    carla = carla_rotate_vector(5.0, 30.0, 10.0)
    forward, right, up = (S @ carla[:, k] for k in range(3))
    _, rotation = carla_to_iso([0.0, 0.0, 0.0], [5.0, 30.0, 10.0])
    np.testing.assert_allclose(rotation[:, 0], forward, atol=1e-9)
    np.testing.assert_allclose(-rotation[:, 1], right, atol=1e-9)  # the camera body's y axis points left
    np.testing.assert_allclose(rotation[:, 2], up, atol=1e-9)
    # CARLA's roll > 0 turns the camera's top towards its right: up leans to the vehicle's right (ISO -y)
    # for a camera looking ahead.
    _, rolled = carla_to_iso([0.0, 0.0, 0.0], [0.0, 0.0, 10.0])
    assert rolled[1, 2] == pytest.approx(-math.sin(math.radians(10.0)), abs=1e-15)


@given(pitch=angles_deg, yaw=angles_deg, roll=angles_deg)
def test_iso_to_carla_gives_angles_carlas_formula_maps_back(pitch, yaw, roll):
    """Whatever angles iso_to_carla writes, CARLA's RotateVector of them is the rotation written."""
    _, r_iso = carla_to_iso([0.0, 0.0, 0.0], [pitch, yaw, roll])
    _, angles = iso_to_carla([0.0, 0.0, 0.0], r_iso)
    np.testing.assert_allclose(S @ carla_rotate_vector(*angles) @ S, r_iso, atol=1e-9)


@given(location=locations)
def test_carla_to_iso_flips_y_of_the_location(location):
    position, _ = carla_to_iso(location, [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(position, [location[0], -location[1], location[2]])


def test_carla_yaw_plus_90_turns_right_towards_iso_minus_y():
    _, rotation = carla_to_iso([0.0, 0.0, 0.0], [0.0, 90.0, 0.0])
    np.testing.assert_allclose(rotation[:, 0], -EY, atol=1e-15)


def test_carla_pitch_plus_tilts_up():
    _, rotation = carla_to_iso([0.0, 0.0, 0.0], [18.0, 0.0, 0.0])
    assert rotation[2, 0] == pytest.approx(math.sin(math.radians(18.0)), abs=1e-15)


def test_carla_location_y_right_is_iso_minus_y():
    position, _ = carla_to_iso([1.09, 0.99, 0.72], [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(position, [1.09, -0.99, 0.72])


def test_s_carla_iso_is_the_read_only_reflection():
    np.testing.assert_array_equal(S_CARLA_ISO, S)
    with pytest.raises(ValueError):
        S_CARLA_ISO[0, 0] = 2.0


@given(
    pitch=angles_deg, yaw=angles_deg, roll=angles_deg,
    turns=st.tuples(*[st.integers(-3, 3)] * 3),
)
@example(pitch=0.0, yaw=214.0, roll=0.0, turns=(0, -1, 0))
def test_carla_angles_equal_modulo_360_give_the_same_matrix(pitch, yaw, roll, turns):
    _, r1 = carla_to_iso([0.0, 0.0, 0.0], [pitch, yaw, roll])
    shifted = np.array([pitch, yaw, roll]) + 360.0 * np.array(turns)
    _, r2 = carla_to_iso([0.0, 0.0, 0.0], shifted)
    np.testing.assert_allclose(r1, r2, atol=1e-12)


def test_carla_yaw_214_equals_minus_146():
    _, r1 = carla_to_iso([0.0, 0.0, 0.0], [0.0, 214.0, 0.0])
    _, r2 = carla_to_iso([0.0, 0.0, 0.0], [0.0, -146.0, 0.0])
    np.testing.assert_allclose(r1, r2, atol=1e-15)


@given(position=locations, rotation=rotations)
def test_iso_to_carla_to_iso_round_trip(position, rotation):
    assume(math.hypot(rotation[0, 0], rotation[1, 0]) > 1e-6)  # away from gimbal lock
    location, angles = iso_to_carla(position, rotation)
    position_back, rotation_back = carla_to_iso(location, angles)
    np.testing.assert_allclose(position_back, position, atol=1e-9, rtol=0)
    np.testing.assert_allclose(rotation_back, rotation, atol=1e-9, rtol=0)


@given(location=locations, pitch=pitch_deg, yaw=angles_deg, roll=angles_deg)
def test_carla_to_iso_to_carla_round_trip_modulo_360(location, pitch, yaw, roll):
    position, rotation = carla_to_iso(location, [pitch, yaw, roll])
    location_back, angles_back = iso_to_carla(position, rotation)
    np.testing.assert_array_equal(location_back, location)
    difference = _angle_difference(angles_back, [pitch, yaw, roll], 360.0)
    np.testing.assert_allclose(difference, 0.0, atol=1e-9)


@given(position=locations, rotation=rotations)
def test_iso_to_carla_angle_ranges(position, rotation):
    _, (pitch, yaw, roll) = iso_to_carla(position, rotation)
    assert -90.0 <= pitch <= 90.0
    assert -180.0 < yaw <= 180.0 and -180.0 < roll <= 180.0


@pytest.mark.parametrize("pitch", [90.0, -90.0])
def test_carla_gimbal_lock_round_trip_keeps_the_matrix(pitch):
    _, rotation = carla_to_iso([0.0, 0.0, 0.0], [pitch, 30.0, 15.0])
    _, angles = iso_to_carla([0.0, 0.0, 0.0], rotation)
    _, back = carla_to_iso([0.0, 0.0, 0.0], angles)
    np.testing.assert_allclose(back, rotation, atol=1e-9)


def test_carla_conversions_broadcast_over_cameras():
    locations_ = np.arange(12.0).reshape(4, 3)
    angles = np.array([[0.0, 10.0, 0.0], [5.0, -20.0, 1.0], [-3.0, 170.0, 2.0], [0.0, 214.0, 0.0]])
    position, rotation = carla_to_iso(locations_, angles)
    assert position.shape == (4, 3) and rotation.shape == (4, 3, 3)
    for k in range(4):
        p_k, r_k = carla_to_iso(locations_[k], angles[k])
        np.testing.assert_allclose(rotation[k], r_k, atol=1e-15)
        np.testing.assert_array_equal(position[k], p_k)
    location_back, angles_back = iso_to_carla(position, rotation)
    assert location_back.shape == (4, 3) and angles_back.shape == (4, 3)


# --- wrap_degrees ---------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "angle, expected",
    [(180.0, 180.0), (-180.0, 180.0), (540.0, 180.0), (214.0, -146.0), (0.0, 0.0), (-0.0, 0.0),
     (360.0, 0.0), (-190.0, 170.0), (179.5, 179.5), (-179.5, -179.5), (720.25, 0.25)],
)
def test_wrap_degrees_known_values(angle, expected):
    assert wrap_degrees(angle) == expected


def test_wrap_degrees_never_returns_negative_zero():
    assert math.copysign(1.0, float(wrap_degrees(-0.0))) == 1.0
    assert math.copysign(1.0, float(wrap_degrees(-360.0))) == 1.0


@given(angle=st.floats(-1e4, 1e4))
def test_wrap_degrees_is_congruent_modulo_360(angle):
    turns = (angle - float(wrap_degrees(angle))) / 360.0
    assert turns == pytest.approx(round(turns), abs=1e-9)


@given(angle=st.floats(-1e4, 1e4))
@example(angle=180.00000000000003)
def test_wrap_degrees_range_is_half_open(angle):
    wrapped = float(wrap_degrees(angle))
    assert -180.0 < wrapped <= 180.0


def test_wrap_degrees_broadcasts():
    np.testing.assert_array_equal(wrap_degrees(np.array([[214.0, -146.0], [540.0, 10.0]])),
                                  [[-146.0, -146.0], [180.0, 10.0]])


# --- geodesic distance ----------------------------------------------------------------------------------


@given(rotation=rotations)
def test_geodesic_distance_to_itself_is_zero(rotation):
    # arccos near 1 resolves angles only to ~sqrt(machine epsilon)
    assert geodesic_distance(rotation, rotation) == pytest.approx(0.0, abs=1e-7)


#: Accepted by is_rotation (orthonormal to 1e-9) but trace(R^T R) = 3 - 2e-9.
NEARLY_ORTHONORMAL = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0 - 1e-9]])


@given(rotation=rotations)
@example(rotation=NEARLY_ORTHONORMAL)
def test_geodesic_distance_to_itself_is_exactly_zero(rotation):
    assert is_rotation(rotation)
    assert geodesic_distance(rotation, rotation) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("axis", [EX, EY, EZ, np.array([1.0, 1.0, 1.0])])
def test_geodesic_distance_of_a_half_turn_is_pi(axis):
    assert geodesic_distance(np.eye(3), _axis_angle(axis, math.pi)) == pytest.approx(math.pi, abs=1e-7)


@given(a=rotations, b=rotations)
def test_geodesic_distance_is_symmetric(a, b):
    assert geodesic_distance(a, b) == geodesic_distance(b, a)


@given(
    base=rotations,
    axis=st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1),
    angle=st.floats(0.0, math.pi),
)
def test_geodesic_distance_is_the_axis_angle_angle(base, axis, angle):
    turn = _axis_angle(axis, angle)
    assert geodesic_distance(np.eye(3), turn) == pytest.approx(angle, abs=1e-7)
    assert geodesic_distance(base, base @ turn) == pytest.approx(angle, abs=1e-7)  # left-invariant


@given(a=rotations, b=rotations)
def test_geodesic_distance_is_in_zero_pi(a, b):
    assert 0.0 <= geodesic_distance(a, b) <= math.pi


def test_geodesic_distance_broadcasts():
    stack = np.stack([np.eye(3), rot_z(0.5), rot_x(1.5)])
    assert geodesic_distance(stack, np.eye(3)).shape == (3,)
    np.testing.assert_allclose(geodesic_distance(stack, np.eye(3))[1:], [0.5, 1.5], atol=1e-12)
    assert geodesic_distance(stack[:, None], stack[None, :]).shape == (3, 3)


# --- quaternions ----------------------------------------------------------------------------------------


@given(q=quaternions())
def test_quaternion_to_matrix_is_a_rotation(q):
    assert is_rotation(quaternion_to_matrix(q), atol=1e-12)


@given(q=quaternions())
def test_quaternion_matrix_round_trip_with_non_negative_w(q):
    unit = q / np.linalg.norm(q)
    back = matrix_to_quaternion(quaternion_to_matrix(q))
    assert back[0] >= 0.0
    assert np.linalg.norm(back) == pytest.approx(1.0, abs=1e-12)
    assert min(np.abs(back - unit).max(), np.abs(back + unit).max()) < 1e-9


@given(q=quaternions())
def test_quaternion_and_its_negative_give_the_same_matrix(q):
    np.testing.assert_allclose(quaternion_to_matrix(q), quaternion_to_matrix(-q), atol=1e-15)


@given(angle=st.floats(-math.pi, math.pi))
def test_quaternion_about_z_is_rz(angle):
    q = [math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2)]
    np.testing.assert_allclose(quaternion_to_matrix(q), _rz(angle), atol=1e-12)


@pytest.mark.parametrize(
    "rotation, expected",
    [(np.eye(3), [1, 0, 0, 0]), (_rx(math.pi), [0, 1, 0, 0]), (_ry(math.pi), [0, 0, 1, 0]),
     (_rz(math.pi), [0, 0, 0, 1]), (_rz(math.pi / 2), [math.sqrt(0.5), 0, 0, math.sqrt(0.5)])],
    ids=["identity", "half-turn x", "half-turn y", "half-turn z", "quarter-turn z"],
)
def test_matrix_to_quaternion_every_branch(rotation, expected):
    q = matrix_to_quaternion(rotation)
    assert min(np.abs(q - expected).max(), np.abs(q + np.asarray(expected)).max()) < 1e-12
    np.testing.assert_allclose(quaternion_to_matrix(q), rotation, atol=1e-12)


def test_quaternion_to_matrix_broadcasts():
    qs = np.array([[1.0, 0, 0, 0], [0.0, 0, 0, 1], [2.0, 0, 0, 0]])
    out = quaternion_to_matrix(qs)
    assert out.shape == (3, 3, 3)
    np.testing.assert_allclose(out[2], np.eye(3), atol=0)


# --- is_rotation ----------------------------------------------------------------------------------------


@given(rotation=rotations)
def test_is_rotation_accepts_rotations(rotation):
    assert is_rotation(rotation)


@pytest.mark.parametrize(
    "matrix",
    [S, -np.eye(3), 2 * np.eye(3), np.array([[1, 0.1, 0], [0, 1, 0], [0, 0, 1]]), np.zeros((3, 3)),
     _rz(0.3) + 1e-3],
    ids=["reflection", "point reflection", "scaled", "shear", "zero", "perturbed"],
)
def test_is_rotation_rejects_non_rotations(matrix):
    assert not is_rotation(matrix)


def test_is_rotation_is_elementwise_on_stacks():
    np.testing.assert_array_equal(is_rotation(np.stack([np.eye(3), S, rot_y(1.0)])), [True, False, True])


# --- quaternion angle and batched conversion ------------------------------------------------------------


def test_matrix_to_quaternion_batched_equals_one_at_a_time():
    rng = np.random.default_rng(3)
    stack = np.concatenate([quaternion_to_matrix(rng.normal(size=(200, 4))),
                            np.stack([np.eye(3), _rx(math.pi), _ry(math.pi), _rz(math.pi)])])
    batched = matrix_to_quaternion(stack.reshape(2, -1, 3, 3)).reshape(-1, 4)
    for rotation, q in zip(stack, batched):
        assert np.array_equal(matrix_to_quaternion(rotation), q)


@given(a=rotations, b=rotations)
def test_quaternion_angle_is_the_geodesic_distance(a, b):
    qa, qb = matrix_to_quaternion(a), matrix_to_quaternion(b)
    assert quaternion_angle(qa, qb) == pytest.approx(geodesic_distance(a, b), abs=1e-12)
    assert quaternion_angle(qa, -qb) == quaternion_angle(qa, qb)
    assert quaternion_angle(qb, qa) == quaternion_angle(qa, qb)
    assert 0.0 <= quaternion_angle(qa, qb) <= math.pi


@given(q=quaternions())
def test_quaternion_angle_to_itself_is_exactly_zero(q):
    unit = q / np.linalg.norm(q)
    assert quaternion_angle(unit, unit) == 0.0 and quaternion_angle(unit, -unit) == 0.0


@pytest.mark.parametrize("angle", [0.0, 1e-9, 1e-6, 0.5, math.pi / 2, math.pi - 1e-6, math.pi])
def test_quaternion_angle_is_exact_near_zero_and_pi(angle):
    turn = [math.cos(angle / 2), 0.0, math.sin(angle / 2), 0.0]
    assert quaternion_angle([1.0, 0.0, 0.0, 0.0], turn) == pytest.approx(angle, rel=1e-14, abs=1e-15)


def test_quaternion_angle_components_on_any_axis_give_the_same_bits():
    rng = np.random.default_rng(4)
    qa, qb = (q / np.linalg.norm(q, axis=-1, keepdims=True) for q in rng.normal(size=(2, 50, 4)))
    np.testing.assert_array_equal(quaternion_angle(qa, qb), quaternion_angle(qa.T, qb.T, axis=0))
