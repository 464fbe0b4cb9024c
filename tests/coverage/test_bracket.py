"""The bracket sheet (rigopt/coverage/bracket.py) on the box car with wheels (4 x 1.8 x 1.2 m, axles at x = +-1.3 m,
tyres 0.35 m in radius and 0.25 m wide on a 1.6 m track), with answers worked out by hand."""

from __future__ import annotations

import numpy as np
import pytest
from box_car import BOX_BODY, BOX_WHEELS, BOX_ZONES, spec_text

from rigopt.coverage import bracket
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.mounting.features import BUMP_TRAVEL_M, STEER_LOCK_DEG, in_wheel_envelopes
from rigopt.rig.model import Camera
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

DOOR = """
[[door_frames]]
name = "left door"
min = [-0.2, 0.85, 0.5]
max = [0.8, 0.9, 1.4]
hinge = "front"
"""


@pytest.fixture(scope="module")
def car(tmp_path_factory) -> Vehicle:
    path = tmp_path_factory.mktemp("bracketcar") / "vehicle.toml"
    path.write_text(spec_text("bracketcar", BOX_BODY + BOX_WHEELS, BOX_ZONES + DOOR))
    return Vehicle.from_spec(read_spec(path))


def camera(position, yaw=0.0, pitch=0.0, roll=0.0) -> Camera:
    rotation = rotation_from_yaw_pitch_roll(*np.deg2rad([yaw, pitch, roll]))
    return Camera.pinhole("C", np.array(position, dtype=float), rotation, 90.0)


@pytest.mark.parametrize("normal, yaw, pitch, expected", [
    ([1.0, 0.0, 0.0], 0.0, 0.0, (0.0, 0.0, 0.0)),  # straight out of the front face
    ([1.0, 0.0, 0.0], 15.0, -10.0, (15.0, -10.0, 0.0)),
    ([0.0, 1.0, 0.0], 90.0, 0.0, (0.0, 0.0, 0.0)),  # straight out of the left side
    ([0.0, 1.0, 0.0], 110.0, -5.0, (20.0, -5.0, 0.0)),  # turned 20 deg towards the back
    ([0.0, 0.0, 1.0], 0.0, 90.0, (0.0, 0.0, 0.0)),  # straight up out of a roof, its up the vehicle's back
])
def test_bracket_angles_are_the_cameras_against_a_bracket_looking_straight_out(normal, yaw, pitch, expected):
    assert bracket.bracket_angles(camera([0, 0, 1], yaw, pitch), normal) == pytest.approx(expected, abs=1e-9)


def test_the_wheel_envelope_holds_the_tyre_its_steer_sweep_and_its_bump_travel(car):
    r, half, bump = 0.35, 0.125, BUMP_TRAVEL_M
    rear, front = np.array([-1.3, 0.8, 0.35]), np.array([1.3, 0.8, 0.35])
    assert bracket.wheel_envelope_distance(car, rear) == 0.0  # the tyre's centre
    # 0.2 m above the rear tyre at full bump
    assert bracket.wheel_envelope_distance(car, rear + [0, 0, r + bump + 0.2]) == pytest.approx(0.2)
    # the rear tyre does not steer: 0.1 m ahead of its tread at axle height
    assert bracket.wheel_envelope_distance(car, rear + [r + 0.1, 0, 0]) == pytest.approx(0.1)
    # the front one steers to 40 deg either way: its outer front corner then stands at (r cos 40 - w/2 sin 40,
    # r sin 40 + w/2 cos 40) from the centre; 0.1 m outward of it the envelope is 0.1 m away, though the
    # straight tyre's side is 0.296 m away
    lock = np.deg2rad(STEER_LOCK_DEG)
    corner = np.array([r * np.cos(lock) - half * np.sin(lock), r * np.sin(lock) + half * np.cos(lock), 0.0])
    assert bracket.wheel_envelope_distance(car, front + corner + [0, 0.1, 0]) == pytest.approx(0.1, abs=1e-9)
    assert bracket.wheel_envelope_distance(car, rear + corner + [0, 0.1, 0]) == pytest.approx(corner[1] + 0.1 - half)
    # inside the sweep, outside the straight tyre: refused as a mount
    inside = front + corner * 0.9
    assert bracket.wheel_envelope_distance(car, inside) == 0.0 and corner[1] * 0.9 > half
    assert in_wheel_envelopes(car, [inside, front + corner + [0, 0.1, 0]]) == [
        ["inside the wheels' envelope (a tyre at up to 40 deg of steer and 0.12 m of bump)"], []]


def test_a_lens_in_a_doors_swing_and_its_clearance_to_the_opening(car):
    assert bracket.door_clearance(car, [0.3, 1.2, 1.0]) == (pytest.approx(0.3), "left door")  # 0.3 m out
    gap, swing = bracket.door_clearance(car, [1.0, 1.0, 1.0])  # ahead of the front hinge: outside the swing
    assert gap == pytest.approx(np.hypot(0.2, 0.1)) and swing is None
    assert bracket.door_clearance(car, [0.3, -1.2, 1.0])[1] is None  # the right side has no door


def test_the_depth_behind_the_skin_is_the_bodys_along_the_normal_capped(car, monkeypatch):
    assert bracket.depth_behind_skin(car, [2.0, 0.0, 1.0], [1.0, 0.0, 0.0]) == pytest.approx(bracket.DEPTH_CAP_M)
    monkeypatch.setattr(bracket, "DEPTH_CAP_M", 10.0)
    assert bracket.depth_behind_skin(car, [0.0, 0.0, 1.5], [0.0, 0.0, 1.0]) == pytest.approx(1.2, abs=1e-3)  # roof
    assert bracket.depth_behind_skin(car, [0.0, 0.9, 1.0], [0.0, 1.0, 0.0]) == pytest.approx(1.8, abs=1e-3)  # side


def test_harness_and_exposure(car):
    ecu = bracket.assumed_ecu(car)
    assert ecu.tolist() == [0.0, 0.0, bracket.ECU_HEIGHT_M]  # halfway between the axles
    sheet = bracket.bracket_sheet(camera([2.04, 0.0, 0.8]), car)
    assert sheet.harness_m == pytest.approx(2.04 + 0.3 + bracket.SERVICE_LOOP_M)
    assert (sheet.stone_chip, sheet.washer) == ("high", True)  # low, front, looking ahead
    assert bracket.exposure(camera([2.04, 0.0, 1.4]), car)[0] == "medium"
    assert bracket.exposure(camera([-2.04, 0.0, 0.8], yaw=180.0), car) == ("low", "high")  # the wake's dirt
    assert bracket.exposure(camera([0.0, 0.94, 1.4], yaw=90.0), car) == ("low", "low")
