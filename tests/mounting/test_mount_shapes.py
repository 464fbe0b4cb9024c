"""The solids of the mount rules: the checked view frustum and the housing's surface frame."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.mounting.records import MountRules
from rigopt.mounting.shapes import frustum_vertices, housing_object, surface_frame
from rigopt.rig.model import Camera

FRONT = [2.03, 0.0, 1.0]


def camera(camera_id, position, yaw_deg=0.0, pitch_deg=0.0, fov=60.0) -> Camera:
    rotation = rotation_from_yaw_pitch_roll(np.deg2rad(yaw_deg), np.deg2rad(pitch_deg), 0.0)
    return Camera.pinhole(camera_id, np.array(position, dtype=float), rotation, fov)


def test_frustum_vertices_span_near_to_range():
    rules = MountRules()
    vertices = frustum_vertices(camera("F", FRONT), rules)
    depth = vertices[:, 0] - FRONT[0]
    np.testing.assert_allclose(depth, [rules.near] * 4 + [rules.frustum_range] * 4, atol=1e-12)


def test_frustum_vertices_shrink_each_half_angle_by_the_margin():
    # 60 deg at 1280 x 720: horizontal half-angle 30 deg; with margin 0.5 the checked one is 15 deg
    rules = MountRules(frustum_margin=0.5)
    far = frustum_vertices(camera("F", [0.0, 0.0, 0.0], yaw_deg=90.0), rules)[4:]  # looking left (+y)
    half_v = math.atan(math.tan(math.radians(30.0)) * 720 / 1280)
    np.testing.assert_allclose(np.abs(far[:, 0]), rules.frustum_range * math.tan(math.radians(15.0)), rtol=1e-9)
    np.testing.assert_allclose(np.abs(far[:, 2]), rules.frustum_range * math.tan(half_v / 2), rtol=1e-9)
    np.testing.assert_allclose(far[:, 1], rules.frustum_range, rtol=1e-9)


def test_housing_object_sits_on_the_surface():
    housing = housing_object(np.array([2.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]),
                             (0.08, 0.06, 0.06))
    np.testing.assert_allclose(housing.getTranslation(), [2.03, 0.0, 1.0], atol=1e-12)


# --- the housing frame ---------------------------------------------------------------------------------------


def test_surface_frame_is_a_rotation_with_the_normal_last():
    for normal, forward in [([1, 0, 0], [1, 0, 0]), ([0, 0, 1], [1, 0, 0]), ([0, 0, 1], [0, 0, 1]),
                            ([0, 0.6, 0.8], [0, 1, 0])]:
        frame = surface_frame(np.array(normal, dtype=float), np.array(forward, dtype=float))
        np.testing.assert_allclose(frame.T @ frame, np.eye(3), atol=1e-12)
        assert np.linalg.det(frame) == pytest.approx(1.0)
        np.testing.assert_allclose(frame[:, 2], normal, atol=1e-12)
        assert abs(frame[2, 0]) < 1e-12  # the width axis is horizontal
