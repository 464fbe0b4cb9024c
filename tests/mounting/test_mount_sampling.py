"""Mount points on the box car: zone samples half a housing off the surface, spread evenly, in the asked zones."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.errors import RigoptError
from rigopt.mounting.records import MountRules
from rigopt.mounting.sampling import sample_zone_points

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


def test_samples_near_given_positions_are_the_whole_sets_points_there(box_car):
    """``near`` checks only the samples around the positions: the answer is exactly the whole set's points within
    the radius, in the same order; positions far from every zone give none, without an error."""
    points, normals, names = sample_zone_points(box_car, 0.05)
    positions, radius = points[[3, len(points) // 2]] + 0.01, 0.2
    close = (np.linalg.norm(points - positions[0], axis=1) <= radius) | (
        np.linalg.norm(points - positions[1], axis=1) <= radius)
    near = sample_zone_points(box_car, 0.05, near=(positions, radius))
    assert 0 < close.sum() < len(points)
    for got, whole in zip(near, (points, normals, names)):
        np.testing.assert_array_equal(got, whole[close])
    nothing = sample_zone_points(box_car, 0.05, near=(np.array([[100.0, 0.0, 0.0]]), radius))
    assert [len(a) for a in nothing] == [0, 0, 0]
