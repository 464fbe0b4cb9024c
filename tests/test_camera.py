"""rigopt.camera: the ideal centred pinhole (focal lengths, FOVs, intrinsics)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rigopt.camera import focal_from_fov, fov_from_focal, intrinsic_matrix, vertical_fov

fov_deg = st.floats(1.0, 179.0)
width_px = st.integers(16, 8192)


def test_focal_of_fov_60_at_320_px():
    expected = 160.0 / math.tan(math.radians(30.0))  # half width over tan(half FOV)
    assert focal_from_fov(60.0, 320) == pytest.approx(expected, rel=1e-12)
    assert focal_from_fov(60.0, 320) == pytest.approx(277.128, abs=5e-4)


def test_fov_90_has_focal_half_the_width():
    assert focal_from_fov(90.0, 1280) == pytest.approx(640.0, rel=1e-12)


@given(fov=fov_deg, width=width_px)
def test_fov_from_focal_inverts_focal_from_fov(fov, width):
    assert fov_from_focal(focal_from_fov(fov, width), width) == pytest.approx(fov, rel=1e-9)


@given(focal=st.floats(1.0, 1e5), width=width_px)
def test_focal_from_fov_inverts_fov_from_focal(focal, width):
    assert focal_from_fov(fov_from_focal(focal, width), width) == pytest.approx(focal, rel=1e-9)


@given(a=fov_deg, b=fov_deg, width=width_px)
def test_wider_fov_has_shorter_focal(a, b, width):
    if a < b:
        assert focal_from_fov(a, width) > focal_from_fov(b, width)


def test_vertical_fov_of_90_at_1280_by_720():
    expected = math.degrees(2.0 * math.atan(math.tan(math.radians(45.0)) * 720.0 / 1280.0))
    assert vertical_fov(90.0, 1280, 720) == pytest.approx(expected, rel=1e-12)


@given(fov=fov_deg, width=width_px)
def test_vertical_fov_of_a_square_image_is_the_horizontal_fov(fov, width):
    assert vertical_fov(fov, width, width) == pytest.approx(fov, rel=1e-9)


@given(fov=fov_deg, width=width_px, height=width_px)
def test_vertical_fov_follows_the_aspect_ratio(fov, width, height):
    expected = 2.0 * math.degrees(math.atan(math.tan(math.radians(fov) / 2.0) * height / width))
    assert vertical_fov(fov, width, height) == pytest.approx(expected, rel=1e-9)


def test_functions_broadcast_over_arrays():
    fovs = np.array([[30.0, 60.0], [90.0, 120.0]])
    focal = focal_from_fov(fovs, 1280)
    assert focal.shape == (2, 2)
    assert focal[1, 0] == pytest.approx(640.0, rel=1e-12)
    np.testing.assert_allclose(fov_from_focal(focal, 1280), fovs, rtol=1e-12)
    assert vertical_fov(fovs, 1280, np.array([720, 1280])).shape == (2, 2)


def test_intrinsic_matrix_layout():
    k = intrinsic_matrix(90.0, 1280, 720)
    np.testing.assert_allclose(k, [[640.0, 0.0, 640.0], [0.0, 640.0, 360.0], [0.0, 0.0, 1.0]], rtol=1e-12)


@given(fov=fov_deg, width=width_px, height=width_px)
def test_intrinsic_matrix_maps_half_fov_ray_to_the_image_edge(fov, width, height):
    k = intrinsic_matrix(fov, width, height)
    centre = k @ np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(centre[:2] / centre[2], [width / 2, height / 2], rtol=1e-12)
    edge = k @ np.array([math.tan(math.radians(fov) / 2.0), 0.0, 1.0])  # optical frame: x right, z forward
    assert edge[0] / edge[2] == pytest.approx(width, rel=1e-9)
    assert edge[1] / edge[2] == pytest.approx(height / 2, rel=1e-12)
