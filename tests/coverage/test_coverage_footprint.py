"""The footprint and its rings: every ring point is the requested distance from the body's outline, at
the requested azimuth from the footprint's centre."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from rigopt.vehicle.footprint import Footprint
from rigopt.vehicle.library import load_vehicle

AZIMUTHS = np.linspace(-np.pi, np.pi, 721)[:-1]


def test_box_footprint_is_the_rectangle(box_footprint):
    expected = shapely.box(-2.0, -1.0, 2.0, 1.0)
    assert box_footprint.polygon.symmetric_difference(expected).area < 1e-5
    np.testing.assert_allclose(box_footprint.centre, [0.0, 0.0], atol=1e-6)


@pytest.mark.parametrize(("azimuth", "expected"), [
    (0.0, 2.0),                        # the half-length
    (np.pi, 2.0),
    (np.pi / 2, 1.0),                  # the half-width
    (-np.pi / 2, 1.0),
    (math.atan2(1, 2), math.sqrt(5)),  # the corner (2, 1)
    (math.radians(10), 2.0 / math.cos(math.radians(10))),  # on the front face x = 2
])
def test_unbuffered_radius_by_hand(box_footprint, azimuth, expected):
    assert box_footprint.radius([azimuth], 0.0)[0] == pytest.approx(expected, abs=1e-4)


def test_radius_on_the_front_of_the_offset_outline(box_footprint):
    # Where |y| <= 1 the offset outline of the box at distance d is the line x = 2 + d; at azimuth 5 deg
    # that holds while (2 + d) tan 5 deg <= 1, i.e. d <= 9.4.
    azimuth = math.radians(5.0)
    for d in (0.5, 3.0, 8.0):
        assert box_footprint.radius([azimuth], d)[0] == pytest.approx((2 + d) / math.cos(azimuth), abs=1e-4)


def test_radius_on_a_corner_arc(box_footprint):
    # Beyond the corner (2, 1) the offset outline is the circle of radius d around it: r (cos a, sin a) is on
    # it when r^2 - 2 r b + 5 - d^2 = 0 with b = 2 cos a + sin a.
    d, azimuth = 2.0, math.radians(45.0)
    b = 2 * math.cos(azimuth) + math.sin(azimuth)
    r = b + math.sqrt(b * b - 5 + d * d)
    point = r * np.array([math.cos(azimuth), math.sin(azimuth)])
    assert point[0] > 2 and point[1] > 1  # really on the arc
    assert box_footprint.radius([azimuth], d)[0] == pytest.approx(r, abs=1e-3)


@pytest.mark.parametrize("distance", [0.5, 2.0, 10.0, 50.0])
@pytest.mark.parametrize("which", ["box", "etron"])
def test_ring_points_are_distance_from_the_footprint(which, distance, box_vehicle):
    vehicle = box_vehicle if which == "box" else load_vehicle("etron")
    footprint = vehicle.footprint
    points = footprint.ring_points(AZIMUTHS, distance, 0.8)
    measured = shapely.distance(footprint.polygon, shapely.points(points[:, :2]))
    np.testing.assert_allclose(measured, distance, rtol=0, atol=1e-6)
    np.testing.assert_array_equal(points[:, 2], 0.8)


@pytest.mark.parametrize("distance", [0.0, 2.0, 50.0])
def test_ring_points_keep_their_azimuth(box_vehicle, distance):
    footprint = Footprint.of_mesh(load_vehicle("etron").mesh)
    points = footprint.ring_points(AZIMUTHS, distance, 0.0)
    offset = points[:, :2] - footprint.centre
    angle = np.arctan2(offset[:, 1], offset[:, 0])
    difference = np.angle(np.exp(1j * (angle - AZIMUTHS)))  # wrapped to (-pi, pi]
    np.testing.assert_allclose(difference, 0.0, atol=1e-9)


def test_distance_to_is_zero_inside_and_euclidean_outside(box_footprint):
    got = box_footprint.distance_to([[0.0, 0.0], [1.9, 0.9], [5.0, 0.0], [0.0, -4.0], [5.0, 5.0]])
    np.testing.assert_allclose(got, [0.0, 0.0, 3.0, 3.0, math.hypot(3.0, 4.0)], atol=1e-6)
