"""Fields judged by pixels: a field point counts as seen only where a camera's image holds the field's test
object at least ``min_px`` pixels tall (rigopt.coverage.visibility.object_pixel_heights, fine_enough, resolved_by;
RegionPreset.test_object; region_coverage's covered_frac against in_view_frac)."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.camera import CameraModel, Lens, focal_from_fov
from rigopt.coverage.regulations import MIN_OBJECT_PX, PRESETS, FieldObject, region_coverage
from rigopt.coverage.visibility import no_pixel_demand, object_pixel_heights, resolved_by, visible_by
from rigopt.errors import RigoptError
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.rig.model import Camera, Rig


def _ahead(distances, height=1.0) -> np.ndarray:
    """(n, 3) m: points straight ahead of a lens at (0, 0, 1) looking along +x."""
    return np.array([[d, 0.0, height] for d in distances])


def _pairs(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.zeros(n, int), np.arange(n)


def test_a_pinhole_shows_an_upright_object_f_h_over_d_pixels_tall(camera):
    """v = cy - f z / d is linear in z: an object H m tall d m ahead, all of it in view, is f H / d px tall."""
    lens = camera([0.0, 0.0, 1.0], fov=90.0, image_size=(1280, 720))  # f = 640 px, half vfov tan 0.5625
    model, f = CameraModel.of_cameras([lens]), focal_from_fov(90.0, 1280)
    distances = np.array([2.5, 10.0, 40.0])
    points = _ahead(distances) + np.array([0.0, 0.4, 0.0])  # off the axis too: the depth is what counts
    heights = object_pixel_heights(model, [lens.position], [lens.rotation], points, np.full(3, 1.2), *_pairs(3))
    np.testing.assert_allclose(heights, f * 1.2 / distances, rtol=1e-9)


def test_only_the_part_of_an_object_in_view_counts(camera):
    """1 m ahead the image holds z from 0.4375 to 1.5625 m: of the axis samples 0, 0.15, ..., 1.2 m the six from
    0.45 m up are in view, 0.75 m of the object, 640 x 0.75 = 480 px."""
    lens = camera([0.0, 0.0, 1.0], fov=90.0, image_size=(1280, 720))
    (height,) = object_pixel_heights(CameraModel.of_cameras([lens]), [lens.position], [lens.rotation], _ahead([1.0]),
                                     [1.2], *_pairs(1))
    assert height == pytest.approx(480.0, rel=1e-9)


def test_an_equidistant_fisheye_shows_an_object_through_its_axis_f_times_its_angle():
    """r = f theta: a 2 m object d m ahead of a lens 1 m up spans 2 atan(1 / d) rad, f times that in pixels (its
    image a straight line through the centre)."""
    lens = Lens(1280, 800, 386.0, 386.0, 640.0, 400.0, "fisheye", (0.0, 0.0, 0.0, 0.0))
    fisheye = Camera("FISH", np.array([0.0, 0.0, 1.0]), np.eye(3), lens)
    distances = np.array([1.0, 2.0, 20.0])  # within the image: 400 px up and down, 59 deg
    heights = object_pixel_heights(CameraModel.of_cameras([fisheye]), [fisheye.position], [fisheye.rotation],
                                   _ahead(distances), np.full(3, 2.0), *_pairs(3))
    np.testing.assert_allclose(heights, 386.0 * 2 * np.arctan(1.0 / distances), rtol=1e-9)


def test_resolved_by_keeps_the_points_near_enough_for_the_pixels_asked(box_vehicle, camera):
    """Points 3-30 m ahead of a front camera (f = 640 px), each with a 1.2 m object (768 / d px tall): asking
    100 px keeps those within 7.68 m; asking nothing keeps every point in view; a point behind is never kept."""
    front = camera([2.03, 0.0, 1.0], fov=90.0, image_size=(1280, 720))
    points = np.vstack([_ahead([5.03, 8.03, 12.03, 20.03, 32.03]), [[-20.0, 0.0, 1.0]]])  # 3 ... 30 m, behind
    args = (box_vehicle.ray_caster, CameraModel.of_cameras([front]), [front.position], [front.rotation], points)
    demand = np.tile([1.2, 100.0], (len(points), 1))
    assert resolved_by(*args, demand)[0].tolist() == [True, True, False, False, False, False]
    assert resolved_by(*args, no_pixel_demand(len(points)))[0].tolist() == visible_by(*args)[0].tolist()
    assert visible_by(*args)[0].tolist() == [True, True, True, True, True, False]


def test_a_test_object_states_its_pixels_per_metre_and_refuses_nonsense():
    child = FieldObject("a child", 1.15, 0.3, 25.0)
    assert child.with_min_px(50.0).min_px == 50.0 and child.with_min_px(50.0).height == 1.15
    assert child.describe() == "a child 1.15 m tall at >= 25 px"
    for bad in ((0.0, 0.3, 25.0), (1.0, 0.3, -1.0), (1.0, 0.3, float("nan"))):
        with pytest.raises(RigoptError, match="test object"):
            FieldObject("x", *bad)


def test_every_preset_asks_for_its_test_object_at_the_default_pixels():
    assert all(p.test_object is not None and p.test_object.min_px == MIN_OBJECT_PX for p in PRESETS.values())
    assert PRESETS["r158"].test_object.height == 0.8  # R158's cylinder
    assert PRESETS["r46-ii"].test_object.width == 0.8  # R46's critical object, 0.8 m across
    assert PRESETS["r158"].pixel_demand.tolist() == [0.8, MIN_OBJECT_PX]
    assert PRESETS["r158"].with_min_px(0).pixel_demands(2).tolist() == [[0.8, 0.0], [0.8, 0.0]]


def test_a_coarse_camera_keeps_a_field_in_view_but_not_seen(box_vehicle, camera, rig):
    """The same rear camera at 1280 x 720 and 160 x 90: both have all of R158 in view, the small image resolves
    less of it; asking nothing, the share seen is the share in view; asking a lot, nothing is seen."""
    fine = rig(camera([-2.03, 0.0, 1.45], yaw_deg=180.0, pitch_deg=-50.0, fov=150.0, image_size=(1280, 720)))
    coarse = rig(camera([-2.03, 0.0, 1.45], yaw_deg=180.0, pitch_deg=-50.0, fov=150.0, image_size=(160, 90)))
    preset = PRESETS["r158"]
    (big,), (small,) = (region_coverage(r, box_vehicle, [preset], spacing=0.2) for r in (fine, coarse))
    assert big.in_view_frac == small.in_view_frac == 1.0
    assert small.covered_frac < 0.1 < 0.9 < big.covered_frac <= 1.0
    assert len(small.unseen) == round((1.0 - small.covered_frac) * small.n_points)
    (free,) = region_coverage(coarse, box_vehicle, [preset.with_min_px(0)], spacing=0.2)
    assert free.covered_frac == free.in_view_frac == 1.0
    (strict,) = region_coverage(fine, box_vehicle, [preset.with_min_px(1e6)], spacing=0.2)
    assert strict.covered_frac == 0.0 and strict.in_view_frac == 1.0


def test_a_roof_fisheye_pitched_down_has_r46_class_ii_in_view_but_resolves_little_of_it():
    """The fire truck with one 190 deg fisheye on its rear roof edge pitched 60 deg down: nearly all of R46
    class II's field is in view, under a quarter of it holds R46's critical object at 25 px (its far end lies
    up to 50 m behind the driver)."""
    from rigopt.design.near_field import fisheye_190
    from rigopt.vehicle.library import load_vehicle

    truck = load_vehicle("firetruck")
    rear = truck.mesh.bounds[0][0] - 0.02
    roof = Camera("ROOF", np.array([rear, 0.0, 2.6]), rotation_from_yaw_pitch_roll(np.pi, np.deg2rad(-60.0), 0.0),
                  fisheye_190().lens)
    (field,) = region_coverage(Rig("roof", truck.blueprint, (roof,)), truck, [PRESETS["r46-ii"]], spacing=0.5)
    assert field.in_view_frac > 0.9 and field.covered_frac < 0.25
