"""Ray casting: embree and trimesh's triangle intersector agree with each other and with the brute-force
Möller–Trumbore oracle (tests/oracles/raycast.py); segments and first hits by hand on a box.

The box is the coverage tests' box car as a plain trimesh box: x in [-2, 2], y in [-1, 1], z in [0.3, 1.5] m.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from oracles.raycast import first_hit_distance_bruteforce
from rigopt.errors import RigoptError
from rigopt.raycast import RayCaster, has_embree
from rigopt.vehicle.library import load_vehicle

needs_embree = pytest.mark.skipif(not has_embree(), reason="embreex is not installed")
CAMERA = np.array([5.0, 0.0, 0.9])  # 3 m in front of the box's front face x = 2, at mid-height


class Body:
    """A mesh under the name the tests use for vehicles (``.mesh``)."""

    def __init__(self, mesh):
        self.mesh = mesh


@pytest.fixture(scope="module")
def box_vehicle():
    box = trimesh.creation.box(extents=(4.0, 2.0, 1.2))
    box.apply_translation([0.0, 0.0, 0.9])
    np.testing.assert_allclose(box.bounds, [[-2, -1, 0.3], [2, 1, 1.5]])
    return Body(box)


@pytest.fixture(scope="module")
def etron():
    return load_vehicle("etron")


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
def test_embree_and_triangle_first_hit_agree(which, box_vehicle, etron):
    vehicle = box_vehicle if which == "box" else etron
    rng = np.random.default_rng(12)
    low, high = vehicle_volume(vehicle, np.array([4.0, 4.0, 1.5]))
    origins, directions = random_rays(rng, 500, low, high, *vehicle.mesh.bounds)
    embree = RayCaster(vehicle.mesh, "embree").first_hit_distance(origins, directions)
    triangle = RayCaster(vehicle.mesh, "triangle").first_hit_distance(origins, directions)
    np.testing.assert_array_equal(np.isinf(embree), np.isinf(triangle))
    assert np.isfinite(triangle).sum() > 200
    hit = np.isfinite(triangle)
    np.testing.assert_allclose(embree[hit], triangle[hit], rtol=0, atol=1e-6)


@pytest.mark.parametrize("backend", ["embree!", "pyembree", "", "Triangle"])
def test_unknown_backend_raises(box_vehicle, backend):
    with pytest.raises(RigoptError, match="unknown ray backend"):
        RayCaster(box_vehicle.mesh, backend)


def test_no_rays_gives_no_distances(box_vehicle):
    assert RayCaster(box_vehicle.mesh).first_hit_distance(np.zeros((0, 3)), np.zeros((0, 3))).shape == (0,)


@pytest.mark.parametrize("backend", ["auto", "triangle"])
def test_segments_clear(box_vehicle, backend):
    starts = np.array([CAMERA, CAMERA, CAMERA, [5.0, 1.5, 0.9], [-3.0, 0.0, 0.9], [0.0, 0.0, 2.0]])
    ends = np.array([
        [2.5, 0.0, 0.9],   # stops 0.5 m before the front face: clear
        [-3.0, 0.0, 0.9],  # through the body: blocked
        [1.0, 0.0, 0.9],   # ends inside the body: blocked by the front face
        [-5.0, 1.5, 0.9],  # alongside the body at y = 1.5: clear
        [5.0, 0.0, 0.9],   # the second one reversed: blocked
        [0.0, 0.0, 1.6],   # from above, stops 0.1 m over the roof: clear
    ])
    clear = RayCaster(box_vehicle.mesh, backend).segments_clear(starts, ends)
    assert clear.tolist() == [True, False, False, True, False, True]


# --- the body as a solid: blocked wherever a ray starts ----------------------------------------------------------

FRONT = np.array([2.0, 0.0, 0.9])  # on the front face x = 2
IN, OUT = np.array([-1.0, 0, 0]), np.array([1.0, 0, 0])


@pytest.mark.parametrize("backend", ["auto", "triangle"])
def test_blocked_distance_by_hand(box_vehicle, backend):
    """On the skin heading in: 0; heading out: clear; inside: 0 every way; outside: the first hit, as first_hits."""
    origins = np.array([FRONT, FRONT, FRONT + [5e-5, 0, 0], [0.0, 0, 0.9], [0.0, 0, 0.9], [0.0, 0, 1.5],
                        [0.0, 0, 1.5], [5.0, 0, 0.9], FRONT + [0.005, 0, 0]])
    directions = np.array([IN, OUT, IN, OUT, [0, 0, 1.0], [0, 0, 1.0], [0, 0, -1.0], IN, IN])
    got = RayCaster(box_vehicle.mesh, backend).blocked_distance(origins, directions)
    np.testing.assert_allclose(got, [0, np.inf, 5e-5, 0, 0, np.inf, 0, 3.0, 0.005], atol=1e-9)


@pytest.mark.parametrize("backend", ["auto", "triangle"])
def test_segments_from_the_skin(box_vehicle, backend):
    """A flush lens sees out past the face it stands on and not into the body; a lens inside sees nothing."""
    starts = np.array([FRONT, FRONT, FRONT, [0.0, 0, 0.9], [0.0, 0, 1.5]])
    ends = np.array([[4.0, 0, 0.9], [-3.0, 0, 0.9], [1.0, 0.5, 0.9], [0.0, 0, 3.0], [0.0, 0, 2.5]])
    clear = RayCaster(box_vehicle.mesh, backend).segments_clear(starts, ends)
    assert clear.tolist() == [True, False, False, False, True]


@pytest.mark.parametrize("backend", ["auto", "triangle"])
def test_blocked_distance_is_the_first_hit_from_outside(box_vehicle, backend):
    """Rays from outside the body are blocked where first_hits says, to the bit (nothing changes for them)."""
    rng = np.random.default_rng(5)
    origins, directions = random_rays(rng, 400, *vehicle_volume(box_vehicle, np.array([4.0, 4.0, 1.5])),
                                      *vehicle_volume(box_vehicle, 0.5))
    outside = ~box_vehicle.mesh.contains(origins)
    caster = RayCaster(box_vehicle.mesh, backend)
    np.testing.assert_array_equal(caster.blocked_distance(origins[outside], directions[outside]),
                                  caster.first_hit_distance(origins[outside], directions[outside]))


@pytest.mark.parametrize("backend", ["auto", "triangle"])
@pytest.mark.parametrize("off", [0.0, 5e-5])
def test_rays_into_the_etron_from_its_skin_are_blocked(etron, backend, off):
    """From each face's centre (``off`` m out; faces of at least 10 cm^2, no slivers at sharp edges), rays at
    most 60 deg off the inward normal are blocked within a millimetre (embree misses some entries at distance 0
    and reports only the far side, metres on)."""
    rng = np.random.default_rng(11)
    normals = etron.mesh.face_normals
    keep = etron.mesh.area_faces >= 1e-3
    normals, centres = normals[keep], etron.mesh.triangles_center[keep] + off * normals[keep]
    tilt = rng.normal(size=normals.shape)
    tilt -= np.einsum("ij,ij->i", tilt, normals)[:, None] * normals
    tilt *= (np.tan(np.deg2rad(rng.uniform(0, 60, len(normals)))) / np.linalg.norm(tilt, axis=1))[:, None]
    inward = -normals + tilt
    inward /= np.linalg.norm(inward, axis=1, keepdims=True)
    got = RayCaster(etron.mesh, backend).blocked_distance(centres, inward)
    assert len(got) > 500 and np.all(got < 1e-3)




@pytest.mark.parametrize("backend", ["auto", "triangle"])
def test_first_hits_by_hand(box_vehicle, backend):
    origins = np.array([[5.0, 0, 0.9], [5.0, 0, 0.9], [0.0, 0.5, 3.0]])
    directions = np.array([[-1.0, 0, 0], [1.0, 0, 0], [0.0, 0, -1.0]])
    hits = RayCaster(box_vehicle.mesh, backend).first_hits(origins, directions)
    np.testing.assert_allclose(hits.distance, [3.0, np.inf, 1.5], atol=1e-9)
    np.testing.assert_allclose(hits.location[[0, 2]], [[2.0, 0, 0.9], [0.0, 0.5, 1.5]], atol=1e-9)
    assert np.isnan(hits.location[1]).all() and hits.face[1] == -1
    normals = box_vehicle.mesh.face_normals[hits.face[[0, 2]]]
    np.testing.assert_allclose(normals, [[1.0, 0, 0], [0, 0, 1.0]], atol=1e-9)  # the front face, the roof


@pytest.mark.parametrize("backend", ["auto", "triangle"])
def test_first_hits_lie_on_their_rays_and_faces(box_vehicle, backend):
    rng = np.random.default_rng(7)
    origins, directions = random_rays(rng, 300, *vehicle_volume(box_vehicle, np.array([4.0, 4.0, 1.5])),
                                      *vehicle_volume(box_vehicle, 0.5))
    hits = RayCaster(box_vehicle.mesh, backend).first_hits(origins, directions)
    hit = hits.face >= 0
    assert 50 < hit.sum() < 300
    np.testing.assert_array_equal(np.isfinite(hits.distance), hit)
    np.testing.assert_allclose(hits.location[hit], origins[hit] + hits.distance[hit, None] * directions[hit], atol=1e-6)
    plane = box_vehicle.mesh.face_normals[hits.face[hit]]
    on_plane = np.einsum("ij,ij->i", plane, hits.location[hit] - box_vehicle.mesh.triangles[hits.face[hit], 0])
    np.testing.assert_allclose(on_plane, 0.0, atol=1e-6)
    np.testing.assert_array_equal(RayCaster(box_vehicle.mesh, backend).first_hit_distance(origins, directions),
                                  hits.distance)



@pytest.mark.parametrize("backend", ["auto", "triangle"])
def test_inside_by_hand(box_vehicle, backend):
    points = np.array([[0.0, 0, 0.9], [1.9, 0.9, 1.4], [2.1, 0, 0.9], [0, 0, 0.2], [0, 0, 1.6], [0, -1.1, 0.9]])
    caster = RayCaster(box_vehicle.mesh, backend)
    assert caster.inside(points).tolist() == [True, True, False, False, False, False]
    assert caster.inside(np.zeros((0, 3))).shape == (0,)


# --- brute force ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("backend", ["auto", "triangle"])
def test_first_hit_equals_brute_force(box_vehicle, backend):
    rng = np.random.default_rng(5)
    mesh = box_vehicle.mesh
    low, high = vehicle_volume(box_vehicle, np.array([4.0, 4.0, 1.5]))
    origins, directions = random_rays(rng, 400, low, high, *vehicle_volume(box_vehicle, 0.5))
    outside = ~mesh.contains(origins)
    origins, directions = origins[outside][:200], directions[outside][:200]
    assert len(origins) == 200
    expected = first_hit_distance_bruteforce(mesh.triangles, origins, directions)
    assert 50 < np.isfinite(expected).sum() < 190  # both hits and misses
    got = RayCaster(mesh, backend).first_hit_distance(origins, directions)
    np.testing.assert_array_equal(np.isinf(got), np.isinf(expected))
    hit = np.isfinite(expected)
    np.testing.assert_allclose(got[hit], expected[hit], rtol=0, atol=1e-6)


def test_brute_force_reference_by_hand(box_vehicle):
    """The reference itself: a ray along -x from (5, 0, 0.9) meets the front face x = 2 at 3 m; along +x it
    meets nothing; down from (0, 0, 3) it meets the roof z = 1.5 at 1.5 m."""
    got = first_hit_distance_bruteforce(box_vehicle.mesh.triangles, [[5.0, 0, 0.9], [5.0, 0, 0.9], [0.0, 0, 3.0]],
                                        [[-1.0, 0, 0], [1.0, 0, 0], [0.0, 0, -1.0]], chunk=2)
    assert got[0] == pytest.approx(3.0) and got[1] == np.inf and got[2] == pytest.approx(1.5)


# --- the vehicle's own caster ------------------------------------------------------------------------------------

def test_a_vehicle_owns_one_caster(etron):
    caster = etron.ray_caster
    assert caster is etron.ray_caster and caster.mesh is etron.mesh  # built once, on the vehicle's body
    assert etron.caster("auto") is caster and etron.caster(caster.backend) is caster
    other = etron.caster("triangle")
    assert other.backend == "triangle" and other.mesh is etron.mesh
    if caster.backend == "embree":
        assert other is not caster


def test_the_vehicle_caster_answers_as_a_fresh_one(etron):
    rng = np.random.default_rng(3)
    origins, directions = random_rays(rng, 300, *vehicle_volume(etron, np.array([3.0, 3.0, 1.0])), *etron.mesh.bounds)
    np.testing.assert_array_equal(etron.ray_caster.first_hit_distance(origins, directions),
                                  RayCaster(etron.mesh).first_hit_distance(origins, directions))


def test_no_cache_at_module_level():
    """Derived data belongs to its owner (the vehicle): the ray-casting module keeps no cache keyed by mesh."""
    import rigopt.raycast as raycast

    cached = [name for name, value in vars(raycast).items() if hasattr(value, "cache_info")]
    assert cached == []
