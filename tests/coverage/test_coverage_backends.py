"""Ray backends: embree and trimesh's triangle intersector agree, and both agree with a brute-force
Möller–Trumbore intersection written here."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.camera import CameraModel, in_frustum
from rigopt.coverage.visibility import first_hit_distance, has_embree, ray_caster, segments_clear, visible
from rigopt.errors import RigoptError
from rigopt.geometry import quaternion_to_matrix
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


def random_rays(rng, count, low, high, aim_low, aim_high):
    """Rays from random origins in [low, high] towards random targets in [aim_low, aim_high] (unit directions)."""
    origins = rng.uniform(low, high, (count, 3))
    targets = rng.uniform(aim_low, aim_high, (count, 3))
    directions = targets - origins
    return origins, directions / np.linalg.norm(directions, axis=1, keepdims=True)


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
    embree = visible(vehicle.mesh, *cameras, points, backend="embree")
    triangle = visible(vehicle.mesh, *cameras, points, backend="triangle")
    # The comparison means something: the body hides some points that are in a frustum.
    positions, rotations, fovs, sizes = cameras
    assert (in_frustum(CameraModel.from_fov(fovs, sizes), positions, rotations, points) & ~triangle).sum() > 50
    assert triangle.sum() > 100
    np.testing.assert_array_equal(embree, triangle)


@needs_embree
@pytest.mark.parametrize("which", ["box", "etron"])
def test_embree_and_triangle_first_hit_agree(which, box_vehicle, etron):
    vehicle = box_vehicle if which == "box" else etron
    rng = np.random.default_rng(12)
    low, high = vehicle_volume(vehicle, np.array([4.0, 4.0, 1.5]))
    origins, directions = random_rays(rng, 500, low, high, *vehicle.mesh.bounds)
    embree = first_hit_distance(vehicle.mesh, origins, directions, backend="embree")
    triangle = first_hit_distance(vehicle.mesh, origins, directions, backend="triangle")
    np.testing.assert_array_equal(np.isinf(embree), np.isinf(triangle))
    assert np.isfinite(triangle).sum() > 200
    hit = np.isfinite(triangle)
    np.testing.assert_allclose(embree[hit], triangle[hit], rtol=0, atol=1e-6)


@pytest.mark.parametrize("backend", ["embree!", "pyembree", "", "Triangle"])
def test_unknown_backend_raises(box_vehicle, backend):
    with pytest.raises(RigoptError):
        ray_caster(box_vehicle.mesh, backend)
    with pytest.raises(RigoptError):
        first_hit_distance(box_vehicle.mesh, [[5.0, 0, 0.9]], [[-1.0, 0, 0]], backend=backend)
    with pytest.raises(RigoptError):
        segments_clear(box_vehicle.mesh, [[5.0, 0, 0.9]], [[-5.0, 0, 0.9]], backend=backend)


def test_no_rays_gives_no_distances(box_vehicle):
    assert first_hit_distance(box_vehicle.mesh, np.zeros((0, 3)), np.zeros((0, 3))).shape == (0,)


# --- brute force ---------------------------------------------------------------------------------------------

def moller_trumbore(triangles, origin, direction, eps=1e-12):
    """Distance along one unit ray to the nearest of ``triangles`` (t, 3, 3) it crosses (two-sided); inf if none."""
    v0, v1, v2 = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    e1, e2 = v1 - v0, v2 - v0
    p = np.cross(direction, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = np.abs(det) > eps
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = origin - v0
    u = np.einsum("ij,ij->i", s, p) * inv
    q = np.cross(s, e1)
    v = (q @ direction) * inv
    t = np.einsum("ij,ij->i", e2, q) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > eps)
    return float(t[hit].min()) if hit.any() else np.inf


@pytest.mark.parametrize("backend", ["auto", "triangle"])
def test_first_hit_equals_brute_force(box_vehicle, backend):
    rng = np.random.default_rng(5)
    mesh = box_vehicle.mesh
    low, high = vehicle_volume(box_vehicle, np.array([4.0, 4.0, 1.5]))
    origins, directions = random_rays(rng, 400, low, high, *vehicle_volume(box_vehicle, 0.5))
    outside = ~mesh.contains(origins)
    origins, directions = origins[outside][:200], directions[outside][:200]
    assert len(origins) == 200
    triangles = np.asarray(mesh.triangles, dtype=float)
    expected = np.array([moller_trumbore(triangles, o, d) for o, d in zip(origins, directions)])
    assert 50 < np.isfinite(expected).sum() < 190  # both hits and misses
    got = first_hit_distance(mesh, origins, directions, backend)
    np.testing.assert_array_equal(np.isinf(got), np.isinf(expected))
    hit = np.isfinite(expected)
    np.testing.assert_allclose(got[hit], expected[hit], rtol=0, atol=1e-6)


def test_brute_force_reference_by_hand(box_vehicle):
    """The reference itself: a ray along -x from (5, 0, 0.9) meets the front face x = 2 at 3 m."""
    triangles = np.asarray(box_vehicle.mesh.triangles, dtype=float)
    assert moller_trumbore(triangles, np.array([5.0, 0, 0.9]), np.array([-1.0, 0, 0])) == pytest.approx(3.0)
    assert moller_trumbore(triangles, np.array([5.0, 0, 0.9]), np.array([1.0, 0, 0])) == np.inf
    assert moller_trumbore(triangles, np.array([0.0, 0, 3.0]), np.array([0.0, 0, -1.0])) == pytest.approx(1.5)
