"""The designer's candidate cameras (``build_candidates``) on a box car written as a spec in tmp_path.

The box car is one prism, the box [-2, 2] x [-0.9, 0.9] x [0.3, 1.5] m (ISO frame), with a front zone
(normal +x), a mirrored side zone (normal +-y) and a small roof patch ([-0.3, 0.3]^2 on the top face).
Expected values come from the box's geometry: distances to the box and ray-box intersections are
computed here analytically (slab method), independently of trimesh.
"""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.mounting.records import MountRules
from rigopt.design.candidates import CandidateSet, build_candidates
from rigopt.errors import RigoptError
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

from box_car import BOX_ZONES, ROOF_ZONE, spec_text

BOX_LOW = np.array([-2.0, -0.9, 0.3])
BOX_HIGH = np.array([2.0, 0.9, 1.5])

BOX_CAR = spec_text("designbox", zones=BOX_ZONES + ROOF_ZONE)

LENSES = (90.0, 60.0, 90.0)  # a duplicate: the catalogue is {60, 90}
SPACING = 0.3
YAWS_DEG = tuple(range(-180, 180, 30))
PITCHES_DEG = (-10.0, 0.0, 10.0)


@pytest.fixture(scope="module")
def box_car(tmp_path_factory) -> Vehicle:
    path = tmp_path_factory.mktemp("designbox") / "vehicle.toml"
    path.write_text(BOX_CAR)
    return Vehicle.from_spec(read_spec(path))


@pytest.fixture(scope="module")
def candidates(box_car) -> CandidateSet:
    return build_candidates(box_car, LENSES, SPACING, YAWS_DEG, PITCHES_DEG)


def distance_to_box(points: np.ndarray) -> np.ndarray:
    """(n,) Euclidean distance of points outside the box to it (0 inside)."""
    gap = np.maximum(np.maximum(BOX_LOW - points, points - BOX_HIGH), 0.0)
    return np.linalg.norm(gap, axis=1)


def segment_enters_box(start: np.ndarray, end: np.ndarray, shrink: float = 1e-6) -> bool:
    """Slab test: does the segment start -> end pass through the (slightly shrunk) box's interior?"""
    low, high = BOX_LOW + shrink, BOX_HIGH - shrink
    direction = end - start
    t0, t1 = 0.0, 1.0
    for k in range(3):
        if abs(direction[k]) < 1e-15:
            if start[k] < low[k] or start[k] > high[k]:
                return False
            continue
        a, b = (low[k] - start[k]) / direction[k], (high[k] - start[k]) / direction[k]
        t0, t1 = max(t0, min(a, b)), min(t1, max(a, b))
        if t0 > t1:
            return False
    return True


def probe_rays(fov: float, margin: float) -> np.ndarray:
    """(9, 3) body-frame rays: centre, edge midpoints and corners of the image (1280 x 720) with each
    half-angle shrunk by ``margin``."""
    half_h = np.deg2rad(fov) / 2
    half_v = np.arctan(np.tan(half_h) * 720 / 1280)
    tan_h, tan_v = np.tan(half_h * (1 - margin)), np.tan(half_v * (1 - margin))
    rays = np.array([[1.0, sy * tan_h, sz * tan_v] for sy in (-1, 0, 1) for sz in (-1, 0, 1)])
    return rays / np.linalg.norm(rays, axis=1, keepdims=True)


def yaw_pitch_index(candidates, yaw_deg, pitch_deg):
    return (np.isclose(candidates.yaws, np.deg2rad(yaw_deg)) & np.isclose(candidates.pitches, np.deg2rad(pitch_deg)))


# --- positions --------------------------------------------------------------------------------------


def test_candidates_exist_on_every_zone(candidates):
    zones = set(candidates.mount_zones[candidates.mount].tolist())
    assert zones == {"front", "side", "roof"}


def test_every_position_is_three_centimetres_outside_the_body(candidates):
    np.testing.assert_allclose(distance_to_box(candidates.positions), 0.03, atol=1e-6)


def test_positions_follow_the_housing_depth(box_car):
    rules = MountRules(housing=(0.08, 0.06, 0.10))
    deep = build_candidates(box_car, (60.0,), SPACING, YAWS_DEG, (0.0,), zones=("front",), rules=rules)
    np.testing.assert_allclose(distance_to_box(deep.positions), 0.05, atol=1e-6)


def test_positions_are_their_mount_points(candidates):
    np.testing.assert_array_equal(candidates.positions, candidates.mount_points[candidates.mount])


def test_mount_normals_are_the_box_face_normals(candidates):
    expected = {"front": [[1.0, 0.0, 0.0]], "side": [[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]], "roof": [[0.0, 0.0, 1.0]]}
    for normal, zone in zip(candidates.mount_normals, candidates.mount_zones):
        assert any(np.allclose(normal, e, atol=1e-9) for e in expected[zone]), (zone, normal)


def test_mirrored_side_zone_gives_candidates_on_both_sides(candidates):
    side = candidates.positions[candidates.mount_zones[candidates.mount] == "side"]
    assert np.any(side[:, 1] > 0.9) and np.any(side[:, 1] < -0.9)


def test_zone_restriction_keeps_only_that_zone(box_car):
    front = build_candidates(box_car, (60.0,), SPACING, YAWS_DEG, PITCHES_DEG, zones=("front",))
    assert set(front.mount_zones[front.mount].tolist()) == {"front"}
    np.testing.assert_allclose(front.positions[:, 0], 2.03, atol=1e-6)


def test_unknown_zone_is_an_error(box_car):
    with pytest.raises(RigoptError, match="unknown zones"):
        build_candidates(box_car, (60.0,), SPACING, YAWS_DEG, PITCHES_DEG, zones=("bonnet",))


# --- orientations -----------------------------------------------------------------------------------


def test_rotations_are_proper_rotations(candidates):
    r = candidates.rotations
    np.testing.assert_allclose(np.swapaxes(r, 1, 2) @ r, np.broadcast_to(np.eye(3), r.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(r), 1.0, atol=1e-12)


def test_rotations_have_the_recorded_yaw_and_pitch(candidates):
    yaw, pitch = candidates.yaws, candidates.pitches
    forward = np.stack([np.cos(pitch) * np.cos(yaw), np.cos(pitch) * np.sin(yaw), np.sin(pitch)], axis=1)
    left = np.stack([-np.sin(yaw), np.cos(yaw), np.zeros_like(yaw)], axis=1)  # roll 0: the y axis stays level
    np.testing.assert_allclose(candidates.rotations[:, :, 0], forward, atol=1e-12)
    np.testing.assert_allclose(candidates.rotations[:, :, 1], left, atol=1e-12)


def test_yaws_and_pitches_come_from_the_grid(candidates):
    assert np.all(np.isclose(candidates.yaws[:, None], np.deg2rad(YAWS_DEG)[None]).any(axis=1))
    assert np.all(np.isclose(candidates.pitches[:, None], np.deg2rad(PITCHES_DEG)[None]).any(axis=1))


def test_no_duplicate_candidates(candidates):
    keys = np.stack([candidates.mount, np.round(np.rad2deg(candidates.yaws)), np.round(np.rad2deg(candidates.pitches)),
                     candidates.fovs], axis=1)
    assert len(np.unique(keys, axis=0)) == len(candidates)


def test_checked_frustum_of_every_candidate_is_clear_of_the_body(candidates):
    rules = MountRules()
    for fov in np.unique(candidates.fovs):
        rays = probe_rays(fov, rules.frustum_margin)
        for k in np.flatnonzero(candidates.fovs == fov):
            world = rays @ candidates.rotations[k].T
            p = candidates.positions[k]
            for ray in world:
                assert not segment_enters_box(p + rules.near * ray, p + rules.frustum_range * ray), (k, ray)


def test_straight_out_of_the_front_face_is_always_clear(candidates):
    """Every front mount point can look straight ahead (yaw 0) at every pitch of the grid, with every lens."""
    front = np.flatnonzero(candidates.mount_zones == "front")
    for lens in (60.0, 90.0):
        for pitch in PITCHES_DEG:
            have = set(candidates.mount[yaw_pitch_index(candidates, 0, pitch) & (candidates.fovs == lens)].tolist())
            assert set(front.tolist()) <= have, (lens, pitch)


def test_front_candidates_never_look_back_into_the_body(candidates):
    on_front = candidates.mount_zones[candidates.mount] == "front"
    assert not np.any(on_front & np.isclose(np.abs(candidates.yaws), np.pi))


def test_roof_patch_candidates_by_hand(candidates):
    """From the roof patch (1.53 m, at least 0.6 m from the roof's edges, checked up to 1 m): a 60 deg lens
    (checked half-angle 8.4 deg vertically) at pitch 10 clears the roof in every yaw; pitched -10 it looks
    into the roof; a 90 deg lens (checked half-angle 14.7 deg) at pitch 10 dips into the roof."""
    roof = candidates.mount_zones[candidates.mount] == "roof"
    for yaw in YAWS_DEG:
        up_60 = roof & yaw_pitch_index(candidates, yaw, 10) & (candidates.fovs == 60.0)
        assert set(candidates.mount[up_60].tolist()) == set(np.flatnonzero(candidates.mount_zones == "roof").tolist())
    assert not np.any(roof & np.isclose(candidates.pitches, np.deg2rad(-10)))
    assert not np.any(roof & (candidates.fovs == 90.0))


# --- lenses -----------------------------------------------------------------------------------------


def test_fovs_come_from_the_catalogue_only(candidates):
    assert set(np.unique(candidates.fovs).tolist()) == {60.0, 90.0}


def test_single_lens_catalogue(box_car):
    single = build_candidates(box_car, (75.0,), SPACING, YAWS_DEG, (0.0,), zones=("front",))
    assert np.all(single.fovs == 75.0)


@pytest.mark.parametrize("lenses", [(0.0, 90.0), (60.0, 180.0), (-30.0,), (200.0,)])
def test_lens_catalogue_outside_0_180_is_an_error(box_car, lenses):
    with pytest.raises(RigoptError, match=r"\(0, 180\)"):
        build_candidates(box_car, lenses, SPACING, YAWS_DEG, PITCHES_DEG)


def test_an_empty_lens_catalogue_is_an_error(box_car):
    with pytest.raises(RigoptError, match="at least one camera"):
        build_candidates(box_car, (), SPACING, YAWS_DEG, PITCHES_DEG)


def test_no_clear_direction_anywhere_is_an_error(box_car):
    # From the roof patch, pitched down 20 deg, every checked frustum meets the roof within 1 m.
    with pytest.raises(RigoptError, match="no mount point"):
        build_candidates(box_car, (60.0,), SPACING, YAWS_DEG, (-20.0,), zones=("roof",))


# --- subset -------------------------------------------------------------------------------------------


def test_subset_takes_rows_and_keeps_the_mount_points(candidates):
    index = np.array([5, 0, 3])
    part = candidates.subset(index)
    assert len(part) == 3
    np.testing.assert_array_equal(part.positions, candidates.positions[index])
    np.testing.assert_array_equal(part.rotations, candidates.rotations[index])
    np.testing.assert_array_equal(part.fovs, candidates.fovs[index])
    np.testing.assert_array_equal(part.mount, candidates.mount[index])
    assert part.mount_points is candidates.mount_points


def test_windscreen_mounts_keep_only_the_yaws_looking_out_through_the_glass():
    from rigopt.design.candidates import windscreen_aside

    yaws = np.radians([0.0, 55.0, 65.0, -90.0, 180.0])
    assert windscreen_aside(["windshield_front", "b_pillar"], yaws).tolist() == [
        [False, False, True, True, True], [False] * 5]
