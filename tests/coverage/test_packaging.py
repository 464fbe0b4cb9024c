"""The packaging sheet on the box car (x in [-2, 2], y in [-0.9, 0.9], z in [0.3, 1.5]), each number against a
value computed by hand: wedge angles, protrusion, the pinhole's ground resolution, people by similar
triangles, the nearest ground past the roof's edge, the share of the image the body blocks."""

from __future__ import annotations

import numpy as np
import pytest
from box_car import BOX_BODY, BOX_WHEELS, BOX_ZONES, spec_text

from rigopt.camera import Lens, focal_from_fov
from rigopt.coverage import packaging
from rigopt.coverage.packaging import (CENTRE_ORIGIN, REAR_AXLE_ORIGIN, blocked_fraction, camera_packaging,
                                       ground_resolution, nearest_visible_ground, person_directions,
                                       person_height_px, report_origin, rig_packaging)
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.rig.model import Camera, Rig, RigOrigin
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

FRONT = np.array([2.04, 0.0, 1.0])  # 4 cm in front of the front face, in the front zone
F_90 = float(focal_from_fov(90.0, 1280))  # 640 px


def camera(position, yaw=0.0, pitch=0.0, roll=0.0, fov=90.0, size=(1280, 720), name="c") -> Camera:
    """A benchmark pinhole; angles in degrees (yaw > 0 left, pitch > 0 up)."""
    angles = np.deg2rad([yaw, pitch, roll])
    return Camera.pinhole(name, np.asarray(position, dtype=float), rotation_from_yaw_pitch_roll(*angles), fov, size)


@pytest.fixture(scope="module")
def box(tmp_path_factory) -> Vehicle:
    path = tmp_path_factory.mktemp("box") / "vehicle.toml"
    path.write_text(spec_text("packbox", BOX_BODY, BOX_ZONES))
    return Vehicle.from_spec(read_spec(path))


@pytest.fixture(scope="module")
def wheeled(tmp_path_factory) -> Vehicle:
    path = tmp_path_factory.mktemp("wheeled") / "vehicle.toml"
    path.write_text(spec_text("packwheels", BOX_BODY + BOX_WHEELS, BOX_ZONES))
    return Vehicle.from_spec(read_spec(path))


# --- body feature, bracket, protrusion -----------------------------------------------------------------


def test_a_camera_looking_out_of_its_surface_needs_no_wedge(box):
    sheet = camera_packaging(camera(FRONT), box)
    assert sheet.zone == "front" and sheet.nearest_zone == "front" and sheet.nearest_zone_m == 0.0
    assert np.allclose(sheet.mount_point, [2.0, 0.0, 1.0]) and np.allclose(sheet.surface_normal, [1.0, 0.0, 0.0])
    assert sheet.wedge_deg == pytest.approx(0.0, abs=1e-6)
    assert sheet.protrusion_m == pytest.approx(0.04, abs=1e-9)


@pytest.mark.parametrize("yaw, pitch", [(30.0, 0.0), (-30.0, 0.0), (0.0, -30.0)])
def test_a_camera_turned_30_degrees_off_its_surface_needs_a_30_degree_wedge(box, yaw, pitch):
    assert camera_packaging(camera(FRONT, yaw, pitch), box).wedge_deg == pytest.approx(30.0, abs=1e-9)


def test_a_side_camera_looking_ahead_needs_a_90_degree_wedge(box):
    sheet = camera_packaging(camera([0.0, 0.94, 1.0], yaw=0.0), box)
    assert sheet.zone == "side" and sheet.wedge_deg == pytest.approx(90.0, abs=1e-6)


def test_a_lens_behind_the_surface_protrudes_negatively(box):
    assert camera_packaging(camera([1.9, 0.0, 1.0]), box).protrusion_m == pytest.approx(-0.1, abs=1e-9)


def test_outside_every_zone_the_nearest_zone_and_its_distance_are_given(box):
    sheet = camera_packaging(camera([-2.04, 0.0, 1.0], yaw=180.0), box)  # the rear face: no zone there
    assert sheet.zone is None and sheet.nearest_zone == "side"
    assert sheet.nearest_zone_m == pytest.approx(0.9, abs=0.05)  # the side faces are 0.9 m away (5 cm faces)


# --- ground resolution -----------------------------------------------------------------------------------


@pytest.mark.parametrize("height, pitch", [(1.0, 0.0), (1.0, -15.0), (1.4, -8.0)])
@pytest.mark.parametrize("distance", packaging.GROUND_DISTANCES_M)
def test_ground_resolution_of_a_pinhole_is_the_pinhole_formula(box, height, pitch, distance):
    lens = camera([2.04, 0.0, height], pitch=pitch)
    result = ground_resolution(lens, box, distance)
    tilt = np.deg2rad(-pitch)  # down
    depth = distance * np.cos(tilt) + height * np.sin(tilt)  # the ground point's depth along the axis
    below = np.arctan2(height, distance) - tilt  # its angle below the axis
    assert result.lateral_px_per_m == pytest.approx(F_90 / depth, rel=1e-6)  # across: f / depth
    along = F_90 / np.cos(below) ** 2 * height / (distance**2 + height**2)  # d(f tan(below)) / d(distance)
    assert result.longitudinal_px_per_m == pytest.approx(along, rel=1e-5)


def test_ground_the_camera_does_not_see_has_no_resolution(box):
    sky = camera(FRONT, pitch=60.0)  # its lowest ray points 30 degrees up
    assert all(ground_resolution(sky, box, d).lateral_px_per_m is None for d in packaging.GROUND_DISTANCES_M)
    through = camera([-2.04, 0.0, 1.0])  # at the rear, looking ahead through the body
    assert ground_resolution(through, box, 10.0).longitudinal_px_per_m is None
    straight_down = camera(FRONT, pitch=-90.0)  # no direction ahead on the ground
    assert ground_resolution(straight_down, box, 5.0).lateral_px_per_m is None


# --- people ----------------------------------------------------------------------------------------------


def test_a_person_ahead_of_a_level_pinhole_is_f_h_over_d_pixels(box):
    lens = camera(FRONT)  # 1.0 m up: 1.8 m at 5 m is within 29 degrees up and down
    directions = person_directions(lens)
    for height in (1.8, 0.8):
        assert person_height_px(lens, box, height, directions["centre"], 5.0) == pytest.approx(
            F_90 * height / 5.0, rel=1e-9)


@pytest.mark.parametrize("place", ["left", "right"])
def test_a_person_at_a_field_edge_is_farther_along_the_axis(box, place):
    lens = camera(FRONT, yaw=20.0)
    edge = np.arctan((640.0 - 0.5) / F_90)  # the first (last) pixel column's centre, off the axis
    expected = F_90 * 1.8 / (5.0 * np.cos(edge))  # similar triangles at depth d cos(edge)
    assert person_height_px(lens, box, 1.8, person_directions(lens)[place], 5.0) == pytest.approx(expected, rel=1e-9)


def test_only_the_seen_part_of_a_person_counts(box):
    low = camera([2.04, 0.0, 0.4], pitch=35.0)  # looks up: the feet 5 m away are below the image
    height = person_height_px(low, box, 1.8, person_directions(low)["centre"], 5.0)
    half = np.arctan(360.0 / F_90)  # half the vertical FOV
    seen_from = 0.4 + 5.0 * np.tan(np.deg2rad(35.0) - half)  # the lowest height in view 5 m away
    head_below_axis = np.deg2rad(35.0) - np.arctan((1.8 - 0.4) / 5.0)
    expected = 360.0 - F_90 * np.tan(head_below_axis)  # from the image's bottom edge up to the head
    assert 0.4 < seen_from < 1.8  # the feet are cut off, the head is in the image
    assert height == pytest.approx(expected, abs=F_90 / 5.0 * packaging.PERSON_STEP_M)  # to one sample
    behind = camera([-2.04, 0.0, 1.0])  # the body hides everyone ahead
    assert person_height_px(behind, box, 1.8, person_directions(behind)["centre"], 5.0) == 0.0


def test_a_person_through_a_fisheye_follows_its_equidistant_projection(box):
    fisheye = Lens(1280, 960, 380.0, 380.0, 640.0, 480.0, "fisheye", (0.0, 0.0, 0.0, 0.0))  # r = f theta
    lens = Camera("fish", FRONT, np.eye(3), fisheye)
    height = person_height_px(lens, box, 1.8, person_directions(lens)["centre"], 5.0)
    assert height == pytest.approx(380.0 * (np.arctan(0.8 / 5.0) + np.arctan(1.0 / 5.0)), rel=1e-9)


def test_the_sheet_lists_both_people_at_three_places(box):
    sheet = camera_packaging(camera(FRONT), box)
    assert [(p.person, p.height_m, p.distance_m) for p in sheet.people] == [("adult", 1.8, 5.0), ("child", 0.8, 5.0)]
    adult, child = sheet.people
    assert adult.left == pytest.approx(adult.right) and adult.left > adult.centre  # symmetric, farther at the edges
    assert adult.centre / child.centre == pytest.approx(1.8 / 0.8)


# --- nearest visible ground, blocked share -----------------------------------------------------------------


@pytest.mark.parametrize("pitch", [0.0, -10.0, -25.0])
def test_the_nearest_ground_of_a_pinhole_is_below_its_lowest_row(box, pitch):
    lens = camera(FRONT, pitch=pitch)
    from_lens, from_body = nearest_visible_ground(lens, box)
    expected = 1.0 / np.tan(np.deg2rad(-pitch) + np.arctan(360.0 / F_90))  # h / tan(tilt + half vFOV)
    assert from_lens == pytest.approx(expected, rel=1e-9)
    assert from_body == pytest.approx(expected + 0.04, rel=1e-9)  # the lens stands 4 cm off the front face


def test_the_nearest_ground_past_the_roof_is_where_its_edge_lets_the_view_down(box):
    above = camera([0.0, 0.0, 2.5], pitch=-90.0, size=(1000, 1000))  # 1 m over the roof, looking down
    from_lens, from_body = nearest_visible_ground(above, box)
    shadow = 0.9 * 2.5 / 1.0  # the ray past the roof's side edge (0.9 m out, 1 m down) reaches the ground here
    step = 2.5 * 2.0 / (packaging.GROUND_LATTICE[0] - 1)  # ground spacing of the lattice's rays there
    assert shadow <= from_lens <= shadow + step
    assert shadow - 0.9 <= from_body <= shadow - 0.9 + step
    assert nearest_visible_ground(camera(FRONT, pitch=30.0), box) == (None, None)  # sees no ground at all


def test_a_camera_that_sees_straight_down_sees_the_ground_below_it(box):
    from_lens, from_body = nearest_visible_ground(camera(FRONT, pitch=-80.0), box)
    assert from_lens == 0.0  # the lens's own ground point
    assert from_body == 0.0  # and, past the front face's lower edge (0.3 m up), ground under the body


def test_the_blocked_share_is_one_into_the_body_and_zero_away_from_it(box):
    assert blocked_fraction(camera(FRONT, yaw=180.0), box) == 1.0  # 4 cm from the front face, facing it
    assert blocked_fraction(camera(FRONT), box) == 0.0


def test_the_roof_blocks_the_share_of_the_image_within_its_edges(box):
    above = camera([0.0, 0.0, 2.5], pitch=-90.0, size=(1000, 1000))
    columns = (np.arange(64) + 0.5) / 32 - 1.0  # tangents of the grid's column rays; the roof spans |t| <= 0.9
    assert blocked_fraction(above, box) == pytest.approx(np.mean(np.abs(columns) <= 0.9), abs=1e-12)


# --- the datum and JSON ------------------------------------------------------------------------------------


def test_the_report_datum_is_the_ground_below_the_rear_axle(box, wheeled):
    datum = report_origin(wheeled)
    assert np.allclose(datum.point, [-1.3, 0.0, 0.0]) and datum.origin == REAR_AXLE_ORIGIN
    assert datum.frame == "ISO 8855, origin on the ground below the rear axle's centre"
    fallback = report_origin(box)  # no axles known
    assert np.allclose(fallback.point, 0.0) and fallback.origin == CENTRE_ORIGIN


def test_a_rig_from_the_rear_axle_gets_the_same_sheet(wheeled):
    centre = Rig("c", "vehicle.test.packwheels", (camera(FRONT, name="F"),))
    axle = Rig("a", "vehicle.test.packwheels", (camera(FRONT + [1.3, 0, 0], name="F"),), RigOrigin("rear_axle"))
    (a,), (b,) = rig_packaging(centre, wheeled), rig_packaging(axle, wheeled)
    origin = report_origin(wheeled).point
    assert a.to_dict(origin) == b.to_dict(origin)
    assert np.allclose(a.to_dict(origin)["position_m"], [3.34, 0.0, 1.0])  # 1.3 m ahead of the rear axle


def test_the_sheet_as_json(box):
    import json

    entry = camera_packaging(camera(FRONT, pitch=60.0), box).to_dict()
    assert set(entry) == {"camera", "zone", "nearest_zone", "nearest_zone_m", "position_m", "mount_point_m",
                          "surface_normal", "wedge_angle_deg", "protrusion_m", "nearest_ground_m",
                          "nearest_ground_from_body_m", "ground_resolution_px_per_m", "person_height_px",
                          "blocked_frac", "blocked_by_keep_outs"}
    assert [g["distance_m"] for g in entry["ground_resolution_px_per_m"]] == [5.0, 10.0, 20.0]
    assert entry["ground_resolution_px_per_m"][0]["lateral"] is None and entry["nearest_ground_m"] is None
    json.dumps(entry, allow_nan=False)  # plain, strict JSON values
