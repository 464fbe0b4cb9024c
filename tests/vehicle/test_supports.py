"""Narrow parts (no surface for a housing) told from sheets by the spread of their surface samples."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from rigopt.vehicle.supports import NARROW_WIDTH, mirror_zone, narrow_keep_outs, narrow_points


def surface(mesh: trimesh.Trimesh, count: int = 20000) -> np.ndarray:
    return trimesh.sample.sample_surface(mesh, count, seed=0)[0]


@pytest.mark.parametrize("side, narrow", [(0.03, True), (0.05, True), (0.07, False), (0.3, False)])
def test_a_square_bar_is_narrow_below_about_5_7_cm(side, narrow):
    bar = trimesh.creation.box([2.0, side, side])
    points = surface(bar, 3000)
    middle = np.abs(points[:, 0]) < 0.8  # away from its ends
    assert narrow_points(points)[middle].mean() == pytest.approx(1.0 if narrow else 0.0, abs=0.05)


@pytest.mark.parametrize("width, narrow", [(0.05, True), (0.12, False)])
def test_an_open_strip_is_narrow_below_the_housing(width, narrow):
    strip = trimesh.Trimesh([[-1, -width / 2, 0], [1, -width / 2, 0], [1, width / 2, 0], [-1, width / 2, 0]],
                            [[0, 1, 2], [0, 2, 3]])
    points = surface(strip, 8000)
    middle = np.abs(points[:, 0]) < 0.8
    assert narrow_points(points)[middle].mean() == pytest.approx(1.0 if narrow else 0.0, abs=0.05)
    assert (width < NARROW_WIDTH) == narrow


def test_a_box_bodys_edges_and_corners_are_not_narrow():
    body = trimesh.creation.box([4.0, 1.8, 1.2])
    assert not narrow_points(surface(body, 40000)).any()


def test_a_rail_on_a_roof_is_one_keep_out_and_the_roof_none():
    roof = trimesh.creation.box([3.0, 1.8, 0.4])
    rail = trimesh.creation.box([2.0, 0.03, 0.03])
    rail.apply_translation([0.0, 0.5, 0.3])
    boxes = narrow_keep_outs(trimesh.util.concatenate([roof, rail]), margin=0.05)
    assert len(boxes) == 1
    np.testing.assert_allclose(boxes[0]["min"], [-1.05, 0.435, 0.235], atol=0.03)
    np.testing.assert_allclose(boxes[0]["max"], [1.05, 0.565, 0.365], atol=0.03)
    assert "no surface for a housing" in boxes[0]["reason"]


def _arm(low, high) -> dict:
    return {"name": "narrow_1", "reason": "x", "min": list(low), "max": list(high)}


def test_a_narrow_part_high_on_the_front_reaching_beyond_the_side_is_a_mirror_arm():
    """A 12 x 2.5 x 3 m body: an arm at the front top reaching to y 1.45 makes a mirror zone outboard of the side
    (y from 1.25), 0.5 m around the arm in x and z, on both sides; a roof rail (inboard), a low bar and a bar
    at the rear make none."""
    bounds = np.array([[-6.0, -1.5, 0.0], [6.0, 1.5, 3.0]])
    arm = _arm([5.5, 1.1, 2.5], [6.1, 1.45, 2.8])
    zone = mirror_zone([arm], bounds, 1.25)
    assert zone == {"name": "mirror", "min": [5.0, 1.25, 2.0], "max": [6.6, 1.95, 3.3], "normal": [0, 1, 0],
                    "cone_deg": 90, "mirrored": True}
    assert mirror_zone([_arm([2.0, 0.5, 2.9], [4.0, 0.6, 3.0])], bounds, 1.25) is None  # a roof rail
    assert mirror_zone([_arm([5.5, 1.1, 0.5], [6.1, 1.45, 0.8])], bounds, 1.25) is None  # low: a step's bar
    assert mirror_zone([_arm([-6.0, 1.1, 2.5], [-5.5, 1.45, 2.8])], bounds, 1.25) is None  # at the rear: a ladder
    both = mirror_zone([arm, _arm([5.5, -1.5, 2.4], [6.1, -1.1, 2.8])], bounds, 1.25)
    assert both["max"][1] == 2.0 and both["min"][2] == 1.9  # the farther arm's reach, the lower arm's foot


@pytest.mark.slow
def test_vehicle_add_infers_the_example_bus_and_vans_mirrors_and_no_car_mirror(tmp_path, monkeypatch):
    from rigopt.vehicle.user import add_user_vehicle

    monkeypatch.setenv("RIGOPT_HOME", str(tmp_path))
    examples = Path(__file__).resolve().parents[2] / "examples"
    bus = add_user_vehicle("bus", examples / "raw_bus.obj", forward="+x", allow_size=True)
    van = add_user_vehicle("van", examples / "raw_van.obj", scale=0.001)
    car = add_user_vehicle("car", examples / "raw_car.obj", scale=0.01, forward="-y")
    assert bus.mirror is not None and van.mirror is not None and car.mirror is None
    from rigopt.vehicle.library import load_vehicle

    for name in ("bus", "van"):  # the zone selects the mirror heads' faces, outboard of the body's side
        vehicle = load_vehicle(name)
        assert "mirror" in vehicle.zone_names(vehicle.mesh.triangles_center, vehicle.mesh.face_normals)
