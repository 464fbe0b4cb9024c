"""``rigopt check`` prints the body-feature rules' reasons (in-process, through the console script's error
handling): a rig file on the fire truck with one camera on its tailboard step, and one with two stacked front
cameras of the same lens."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.rig.model import Camera, Rig
from rigopt.rig.pccr_format import write_rig

from in_process import run_rigopt

FIRETRUCK = "vehicle.carlamotors.firetruck"
BACKWARDS = rotation_from_yaw_pitch_roll(np.pi, 0.0, 0.0)


@pytest.fixture(scope="module")
def tailboard_rig(tmp_path_factory):
    """R6's front camera (valid) and a rear camera on the tailboard's face, 0.86 m up."""
    rig = Rig("tailboard", FIRETRUCK, (Camera.pinhole("CAM_FRONT", np.array([3.98, 0.0, 1.2]), np.eye(3), 120.0),
                                       Camera.pinhole("CAM_TAIL", np.array([-4.40, 0.0, 0.86]), BACKWARDS, 75.0)))
    return write_rig(rig, tmp_path_factory.mktemp("tailboard") / "tailboard.json")


def test_check_prints_the_step_reason_for_the_one_offending_camera(tailboard_rig):
    result = run_rigopt("check", tailboard_rig)
    assert result.returncode == 1, result.stderr
    assert "INVALID" in result.stdout
    tail = next(line for line in result.stdout.splitlines() if "CAM_TAIL" in line)
    assert "NO" in tail and "on the tailboard step (walkable) at 0.86 m" in tail
    front = next(line for line in result.stdout.splitlines() if "CAM_FRONT" in line)
    assert "yes" in front


def test_check_json_carries_the_reason_and_nothing_else(tailboard_rig):
    result = run_rigopt("check", tailboard_rig, "--json")
    cameras = {c["id"]: c for c in json.loads(result.stdout)["cameras"]}
    assert cameras["CAM_TAIL"]["problems"] == ["on the tailboard step (walkable) at 0.86 m"]
    assert cameras["CAM_FRONT"]["valid"] and cameras["CAM_FRONT"]["problems"] == []


def test_check_names_a_duplicate_front_camera(tmp_path):
    rig = Rig("stacked", FIRETRUCK, (Camera.pinhole("CAM_FRONT", np.array([3.98, 0.0, 1.2]), np.eye(3), 120.0),
                                     Camera.pinhole("CAM_FRONT_LOW", np.array([4.10, 0.0, 0.80]), np.eye(3), 120.0)))
    result = run_rigopt("check", write_rig(rig, tmp_path / "stacked.json"), "--json")
    assert result.returncode == 1
    cameras = {c["id"]: c for c in json.loads(result.stdout)["cameras"]}
    assert cameras["CAM_FRONT"]["valid"]
    assert cameras["CAM_FRONT_LOW"]["problems"] == ["duplicates CAM_FRONT: same lens, 0.42 m apart, 0 deg apart"]
