"""Monotonic facts of coverage, for random cameras (hypothesis strategies of tests/conftest.py)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rigopt.coverage.measures import CoverageSettings, ring_coverage
from rigopt.camera import CameraModel, in_frustum
from rigopt.coverage.visibility import DEFAULT_MAX_RANGE, visible
from rigopt.rig.model import Camera, Rig


@pytest.fixture(scope="module")
def ring_settings():
    """Two rings (one near, where the body occludes a lot, one far) with 2-degree samples."""
    return CoverageSettings(ring_distances=(1.0, 20.0), ring_heights=(0.8,), ring_samples=180)


def ring_counts(vehicle, rig, settings, footprint):
    return np.stack([r.counts for r in ring_coverage(vehicle, rig, settings, footprint)])


def widened(camera: Camera, extra: float) -> Camera:
    return Camera.pinhole(camera.id, camera.position, camera.rotation, min(camera.fov + extra, 179.0), camera.image_size)


@settings(max_examples=40)
@given(camera=st.from_type(Camera), extra=st.floats(0.0, 60.0))
def test_wider_fov_never_covers_less(box_vehicle, box_footprint, ring_settings, camera, extra):
    narrow = ring_counts(box_vehicle, Rig("a", "v", (camera,)), ring_settings, box_footprint)
    wide = ring_counts(box_vehicle, Rig("b", "v", (widened(camera, extra),)), ring_settings, box_footprint)
    assert np.all(wide >= narrow)


@settings(max_examples=40)
@given(rig=st.from_type(Rig), extra=st.from_type(Camera))
def test_adding_a_camera_adds_exactly_its_own_view(box_vehicle, box_footprint, ring_settings, rig, extra):
    extra = Camera.pinhole("EXTRA", extra.position, extra.rotation, extra.fov, extra.image_size)
    before = ring_counts(box_vehicle, rig, ring_settings, box_footprint)
    after = ring_counts(box_vehicle, Rig(rig.name, rig.vehicle, rig.cameras + (extra,)), ring_settings,
                        box_footprint)
    alone = ring_counts(box_vehicle, Rig("x", "v", (extra,)), ring_settings, box_footprint)
    assert np.all(after >= before)
    np.testing.assert_array_equal(after - before, alone)


@given(rig=st.from_type(Rig), seed=st.integers(0, 2**32 - 1))
def test_occlusion_never_adds_coverage(box_vehicle, rig, seed):
    points = np.random.default_rng(seed).uniform([-8, -6, -1], [8, 6, 4], (200, 3))
    sizes = np.array([c.image_size for c in rig.cameras])
    frustum = in_frustum(CameraModel.from_fov(rig.fovs, sizes), rig.positions, rig.rotations, points, DEFAULT_MAX_RANGE)
    seen = visible(box_vehicle.ray_caster, rig.positions, rig.rotations, rig.fovs, sizes, points)
    assert seen.shape == frustum.shape == (len(rig), 200)
    assert not np.any(seen & ~frustum)


def test_occlusion_check_is_not_vacuous(box_vehicle):
    """With many random cameras around the box, the body does hide some in-frustum points."""
    rng = np.random.default_rng(3)
    from rigopt.geometry import quaternion_to_matrix
    positions = rng.uniform([-5, -5, -1], [5, 5, 4], (30, 3))
    rotations = quaternion_to_matrix(rng.normal(size=(30, 4)))
    points = rng.uniform([-8, -6, -1], [8, 6, 4], (300, 3))
    sizes = np.tile([1280, 720], (30, 1))
    frustum = in_frustum(CameraModel.from_fov(np.full(30, 90.0), sizes), positions, rotations, points, DEFAULT_MAX_RANGE)
    seen = visible(box_vehicle.ray_caster, positions, rotations, np.full(30, 90.0), sizes, points)
    assert (frustum & ~seen).sum() > 50 and seen.sum() > 100
