"""The ego body's share of a designed camera's image is limited (10 % by default)."""

import numpy as np
import pytest

from rigopt.camera import CameraModel
from rigopt.design.candidates import build_candidates
from rigopt.design.settings import DesignSettings
from rigopt.errors import RigoptError
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.mounting.candidates import body_fraction
from rigopt.vehicle.library import load_vehicle


@pytest.fixture(scope="module")
def tt():
    return load_vehicle("tt")


def test_a_camera_facing_the_body_sees_only_body_and_one_facing_away_none(tt):
    front = tt.mesh.bounds[1][0]
    positions = np.array([[front + 0.5, 0.0, 0.7], [front + 0.5, 0.0, 0.7]])
    rotations = rotation_from_yaw_pitch_roll(np.array([np.pi, 0.0]), np.zeros(2), np.zeros(2))
    share = body_fraction(tt, positions, rotations, CameraModel.from_fov([60.0, 60.0], [(1280, 720)] * 2))
    assert share[0] > 0.5 and share[1] == 0.0


def test_candidates_over_the_limit_are_dropped(tt):
    kwargs = dict(spacing=0.4, yaws_deg=np.arange(-180, 180, 30), pitches_deg=(-20.0, 0.0))
    every = build_candidates(tt, (120.0,), **kwargs)
    limited = build_candidates(tt, (120.0,), max_body_fraction=0.10, **kwargs)
    shares = body_fraction(tt, limited.positions, limited.rotations, limited.model())
    assert 0 < len(limited) < len(every) and (shares <= 0.10).all()


def test_the_limit_is_a_share():
    assert DesignSettings().max_body_fraction == 0.10
    with pytest.raises(RigoptError, match=r"\[0, 1\]"):
        DesignSettings(max_body_fraction=1.5)
