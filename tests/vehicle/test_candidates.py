"""Mount candidates on the box car: zone samples off the surface and the directions they can face."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.collision import MountRules
from rigopt.errors import RigoptError
from rigopt.vehicle.candidates import clear_directions, mount_candidates, sample_zone_points

SPACING = 0.2


@pytest.fixture(scope="module")
def front_samples(box_car):
    return sample_zone_points(box_car, SPACING, zones=["front"])


def test_samples_sit_half_a_housing_off_the_surface(box_car, front_samples):
    points, _, _ = front_samples
    distance = box_car.surface(points).distance
    np.testing.assert_allclose(distance, MountRules().housing[2] / 2, atol=1e-6)


def test_samples_follow_the_housing_depth(box_car):
    points, _, _ = sample_zone_points(box_car, SPACING, zones=["front"], rules=MountRules(housing=(0.08, 0.06, 0.1)))
    np.testing.assert_allclose(box_car.surface(points).distance, 0.05, atol=1e-6)


def test_sample_normals_are_unit(box_car):
    _, normals, _ = sample_zone_points(box_car, SPACING)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-9)


def test_sample_normals_are_the_surface_normals(box_car, front_samples):
    _, normals, _ = front_samples
    np.testing.assert_allclose(normals, np.tile([1.0, 0.0, 0.0], (len(normals), 1)), atol=1e-9)


def test_samples_come_from_the_requested_zones_only(box_car):
    _, _, names = sample_zone_points(box_car, SPACING, zones=["side"])
    assert set(names.tolist()) == {"side"}


def test_samples_without_zones_cover_every_zone(box_car):
    _, _, names = sample_zone_points(box_car, SPACING)
    assert set(names.tolist()) == {"front", "side"}


def test_mirrored_zone_is_sampled_on_both_sides(box_car):
    points, _, _ = sample_zone_points(box_car, SPACING, zones=["side"])
    assert (points[:, 1] > 0).any() and (points[:, 1] < 0).any()


def test_samples_are_spread_about_spacing_apart(box_car, front_samples):
    points, _, _ = front_samples
    gaps = np.linalg.norm(points[:, None] - points[None], axis=-1) + np.eye(len(points)) * 10
    assert gaps.min() >= SPACING * 0.99
    assert len(points) >= (1.8 * 1.2) / (2 * SPACING) ** 2  # the front face is 1.8 x 1.2 m


def test_unknown_zone_name_raises(box_car):
    with pytest.raises(RigoptError, match="roof"):
        sample_zone_points(box_car, SPACING, zones=["roof"])


@pytest.mark.parametrize("spacing", [0.0, -0.1])
def test_non_positive_spacing_raises(box_car, spacing):
    with pytest.raises(RigoptError, match="spacing"):
        sample_zone_points(box_car, spacing)


def test_front_point_can_look_forward_not_backward(box_car):
    clear = clear_directions(box_car, [[2.03, 0.0, 1.0]], np.deg2rad([0.0, 180.0]), np.array([0.0]), 65.0)
    assert clear.shape == (1, 1, 2)
    assert clear[0, 0].tolist() == [True, False]


def test_side_point_can_look_outward_not_across_the_body(box_car):
    clear = clear_directions(box_car, [[0.0, 0.93, 1.0]], np.deg2rad([90.0, -90.0]), np.array([0.0]), 65.0)
    assert clear[0, 0].tolist() == [True, False]


def test_clear_directions_use_the_frustum_margin(box_car):
    # on the left side looking 40 deg outward with a 120 deg lens: the outer half of the view grazes the body
    args = (box_car, [[0.0, 0.93, 1.0]], np.deg2rad([40.0]), np.array([0.0]), 120.0)
    assert clear_directions(*args)[0, 0, 0]
    assert not clear_directions(*args, rules=MountRules(frustum_margin=0.0))[0, 0, 0]


@pytest.fixture(scope="module")
def front_candidates(box_car):
    return mount_candidates(box_car, 0.3, fov=65.0, zones=["front"], yaws_deg=range(-180, 180, 10),
                            pitches_deg=(-10, 0, 10))


def test_candidate_shapes(front_candidates):
    c = front_candidates
    n = len(c.points)
    assert n > 0
    assert c.normals.shape == (n, 3) and c.zones.shape == (n,)
    assert c.yaws.shape == (36,) and c.pitches.shape == (3,)
    assert c.clear.shape == (n, 3, 36) and c.clear.dtype == bool


def test_candidate_angles_are_radians(front_candidates):
    np.testing.assert_allclose(front_candidates.yaws[[0, 18]], [-np.pi, 0.0], atol=1e-12)
    np.testing.assert_allclose(front_candidates.pitches, np.deg2rad([-10, 0, 10]), atol=1e-12)
    assert front_candidates.fov == 65.0


def test_front_clear_yaws_form_one_band_around_zero(front_candidates):
    c = front_candidates
    zero = int(np.argmin(np.abs(c.yaws)))
    level = int(np.argmin(np.abs(c.pitches)))
    for clear in c.clear[:, level]:
        indices = np.flatnonzero(clear)
        assert clear[zero], "a front-face point must see straight ahead"
        assert indices.max() - indices.min() + 1 == len(indices), f"clear yaws not contiguous: {clear.astype(int)}"
        assert not clear[0], "a front-face point cannot look backward"


def test_front_clear_band_is_symmetric_on_the_centre_line(box_car):
    c = mount_candidates(box_car, 0.3, fov=65.0, zones=["front"], yaws_deg=range(-180, 180, 10), pitches_deg=(0,))
    central = np.flatnonzero(np.abs(c.points[:, 1]) < 0.5)
    assert len(central) > 0
    yaws = np.rad2deg(c.yaws)
    for k in central:
        clear = yaws[c.clear[k, 0]]
        assert clear.min() == pytest.approx(-clear.max(), abs=1e-9)
