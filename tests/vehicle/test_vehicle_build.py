"""Building spec solids into one watertight mesh (manifold3d booleans)."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.errors import DataError
from rigopt.vehicle.build import build_mesh
from rigopt.vehicle.spec import read_spec

BOX_VOLUME = 4 * 1.8 * 1.2
WHEELS = """
[[solids]]
type = "wheels"
axles = [1.3, -1.3]
radius = 0.35
width = 0.2
track = 1.6
"""
MIRRORED_BOXES = """
[[solids]]
type = "box"
center = [0, 1.0, 1.0]
size = [0.2, 0.2, 0.2]
mirrored = {mirrored}
"""


def test_box_car_is_watertight(box_car):
    assert box_car.mesh.is_watertight


def test_box_car_bounds_equal_the_box(box_car):
    np.testing.assert_allclose(box_car.mesh.bounds, [[-2, -0.9, 0.3], [2, 0.9, 1.5]], atol=1e-5)


def test_box_car_volume(box_car):
    assert box_car.mesh.volume == pytest.approx(BOX_VOLUME, abs=1e-4)


def test_box_car_size(box_car):
    np.testing.assert_allclose(box_car.size, [4.0, 1.8, 1.2], atol=1e-5)


def test_taper_makes_the_top_narrower(build_vehicle, make_spec_text, box_body):
    tapered = build_vehicle(make_spec_text(solids=box_body + 'taper = [1.0, 0.5]\n'))
    vertices = tapered.mesh.vertices
    top = np.abs(vertices[vertices[:, 2] > 1.5 - 1e-4, 1]).max()
    bottom = np.abs(vertices[vertices[:, 2] < 0.3 + 1e-4, 1]).max()
    assert bottom == pytest.approx(0.9, abs=0.02)
    assert top < 0.6 * bottom


def test_untapered_prism_has_straight_sides(box_car):
    vertices = box_car.mesh.vertices
    top = np.abs(vertices[vertices[:, 2] > 1.5 - 1e-4, 1]).max()
    assert top == pytest.approx(0.9, abs=1e-5)


def test_wheels_reach_the_ground(build_vehicle, make_spec_text, box_body):
    car = build_vehicle(make_spec_text(solids=box_body + WHEELS))
    assert car.mesh.bounds[0, 2] == pytest.approx(0.0, abs=1e-4)


def test_wheels_add_their_volume_below_the_body(build_vehicle, make_spec_text, box_body):
    car = build_vehicle(make_spec_text(solids=box_body + WHEELS))
    r, h = 0.35, 0.3  # wheel radius; the body's floor is 0.3 m above the wheels' lowest point
    segment = r**2 * np.arccos((r - h) / r) - (r - h) * np.sqrt(2 * r * h - h**2)
    assert car.mesh.is_watertight
    assert car.mesh.volume - BOX_VOLUME == pytest.approx(4 * 0.2 * segment, rel=0.02)


def test_mirrored_box_appears_on_both_sides(build_vehicle, make_spec_text, box_body):
    car = build_vehicle(make_spec_text(solids=box_body + MIRRORED_BOXES.format(mirrored="true")))
    np.testing.assert_allclose(car.mesh.bounds[:, 1], [-1.1, 1.1], atol=1e-5)
    assert car.mesh.contains([[0, 1.05, 1.0], [0, -1.05, 1.0]]).all()
    assert car.mesh.volume == pytest.approx(BOX_VOLUME + 2 * 0.2**3, abs=1e-4)


def test_unmirrored_box_appears_on_one_side(build_vehicle, make_spec_text, box_body):
    car = build_vehicle(make_spec_text(solids=box_body + MIRRORED_BOXES.format(mirrored="false")))
    assert car.mesh.contains([[0, 1.05, 1.0], [0, -1.05, 1.0]]).tolist() == [True, False]


def test_disjoint_profiles_build_an_empty_body(write_spec, make_spec_text):
    solids = """
[[solids]]
type = "prism"
side = [[-2, 0.3], [2, 0.3], [2, 1.5], [-2, 1.5]]
plan = [[10, 0], [10, 0.9], [8, 0.9], [8, 0]]
"""
    path = write_spec(make_spec_text(solids=solids, zones=""))
    with pytest.raises(DataError, match="empty"):
        build_mesh(read_spec(path))

