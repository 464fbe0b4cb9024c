"""The continuous stage (casadi + IPOPT, ``rigopt.design.refine``) on problems whose optimum is known: a camera on
a flat plate slides back to its reference camera's place, stops at its radius, and turns only as far as the pitch
range lets it."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.design.refine import RefineProblem, refine
from rigopt.geometry import rotation_from_yaw_pitch_roll, yaw_pitch_roll_from_rotation
from rigopt.rig.model import Camera, Rig

#: A plate facing ahead (outward normal +x) at x = 2 m: cameras on it slide in y and z.
NORMAL = np.array([[1.0, 0.0, 0.0]])


def one(position, pitch_deg: float = 0.0, fov: float = 90.0) -> Rig:
    rotation = rotation_from_yaw_pitch_roll(0.0, np.radians(pitch_deg), 0.0)
    return Rig("one", "vehicle.audi.etron", (Camera.pinhole("CAM", np.array(position, float), rotation, fov),))


def solve(design: Rig, reference: Rig, radius: float = 1.0, pitch_range=(-0.5, 0.5)) -> Rig:
    problem = RefineProblem(design, reference, np.array([0]), NORMAL, np.zeros((1, 0), bool), np.zeros((0, 3)),
                            alpha=1.0, lambdas=(1.0, 1.0, 0.01), pitch_range=pitch_range, fov_range=None,
                            radius=radius)
    outcome = refine(problem)
    assert outcome.status == "Solve_Succeeded" and outcome.rig is not None
    return outcome.rig


def test_a_camera_off_its_reference_on_a_flat_plate_slides_back_to_it():
    refined = solve(one([2.0, 0.3, 1.2]), one([2.0, 0.0, 1.0]))
    assert refined.positions[0] == pytest.approx([2.0, 0.0, 1.0], abs=1e-3)
    assert np.degrees(yaw_pitch_roll_from_rotation(refined.rotations)[1][0]) == pytest.approx(0.0, abs=0.05)


def test_the_slide_stops_at_the_cameras_radius():
    refined = solve(one([2.0, 0.3, 1.0]), one([2.0, 0.0, 1.0]), radius=0.1)
    assert refined.positions[0] == pytest.approx([2.0, 0.2, 1.0], abs=1e-3)  # 0.1 m nearer, on the plate


def test_the_pitch_turns_to_the_reference_only_within_its_range():
    free = solve(one([2.0, 0.0, 1.0]), one([2.0, 0.0, 1.0], pitch_deg=-10.0))
    assert np.degrees(yaw_pitch_roll_from_rotation(free.rotations)[1][0]) == pytest.approx(-10.0, abs=0.05)
    bounded = solve(one([2.0, 0.0, 1.0]), one([2.0, 0.0, 1.0], pitch_deg=-10.0), pitch_range=np.radians([-5.0, 5.0]))
    assert np.degrees(yaw_pitch_roll_from_rotation(bounded.rotations)[1][0]) == pytest.approx(-5.0, abs=1e-3)
