"""Ray backends in coverage: visibility under embree and under trimesh's triangle intersector agree (the ray
casts themselves are tested in tests/test_raycast.py)."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.camera import CameraModel, in_frustum
from rigopt.coverage.visibility import visible
from rigopt.geometry import quaternion_to_matrix
from rigopt.raycast import RayCaster, has_embree
from rigopt.vehicle.library import load_vehicle

needs_embree = pytest.mark.skipif(not has_embree(), reason="embreex is not installed")


@pytest.fixture(scope="module")
def etron():
    return load_vehicle("etron")


def random_cameras(rng, count, low, high):
    positions = rng.uniform(low, high, (count, 3))
    quaternions = rng.normal(size=(count, 4))  # normalised Gaussians: uniform rotations
    rotations = quaternion_to_matrix(quaternions)
    fovs = rng.uniform(30.0, 170.0, count)
    sizes = np.tile([1280, 720], (count, 1))
    return positions, rotations, fovs, sizes


def vehicle_volume(vehicle, margin):
    low, high = vehicle.mesh.bounds
    return low - margin, high + margin


@needs_embree
@pytest.mark.parametrize("which", ["box", "etron"])
def test_embree_and_triangle_visibility_agree(which, box_vehicle, etron):
    vehicle = box_vehicle if which == "box" else etron
    rng = np.random.default_rng(11)
    low, high = vehicle_volume(vehicle, np.array([3.0, 3.0, 1.0]))
    cameras = random_cameras(rng, 12, low, high)
    points = rng.uniform(low, high, (400, 3))
    embree = visible(RayCaster(vehicle.mesh, "embree"), *cameras, points)
    triangle = visible(RayCaster(vehicle.mesh, "triangle"), *cameras, points)
    # The comparison means something: the body hides some points that are in a frustum.
    positions, rotations, fovs, sizes = cameras
    assert (in_frustum(CameraModel.from_fov(fovs, sizes), positions, rotations, points) & ~triangle).sum() > 50
    assert triangle.sum() > 100
    np.testing.assert_array_equal(embree, triangle)
