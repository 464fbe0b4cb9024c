"""Regulation fields as the texts say (rigopt/coverage/regulations.py): R151's reference lines (no mirrors, nothing
above 2.0 m, a coupled trailer's rear), R46 class II on both sides and class IV's straight outer edge, the
criticality weights and the camera -> field shares.

Every expectation is computed by hand from a box vehicle's dimensions:

- the box car of conftest.py: x in [-2, 2], y in [-1, 1], z in [0.3, 1.5] m, category M1 by its size, so its
  driver's eyes are 2.2 m behind its front (x = -0.2);
- the "truck" below: a body x in [-3, 3], y in [-1.2, 1.2], z in [0.3, 2.8] m; a roof overhang x in [-3, 3.5],
  y in [-1.5, 1.5], z in [2.2, 2.8] m (wider and longer than the body, all above 2.0 m); mirrors x in [2.4, 2.6],
  |y| in [1.1, 1.6], z in [1.6, 1.9] m (below 2.0 m) inside a mirror zone; optionally a trailer keep-out.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely

from rigopt.coverage.regulations import (
    PRESETS,
    R46_HORIZON_CUT,
    FieldPolygon,
    boundary_samples,
    criticality_weights,
    grid_inside,
    region_coverage,
    required_mask,
)
from rigopt.errors import RigoptError
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

TOL = 1e-6

TRUCK = """name = "r151box"
blueprint = "vehicle.test.r151box"
category = "N3"

[[solids]]
name = "body"
type = "box"
center = [0.0, 0.0, 1.55]
size = [6.0, 2.4, 2.5]

[[solids]]
name = "roof_overhang"
type = "box"
center = [0.25, 0.0, 2.5]
size = [6.5, 3.0, 0.6]

[[solids]]
name = "mirror"
type = "box"
center = [2.5, 1.35, 1.75]
size = [0.2, 0.5, 0.3]
mirrored = true

[[zones]]
name = "mirror"
min = [2.3, 1.1, 1.5]
max = [2.7, 1.7, 2.0]
normal = [0, 1, 0]
cone_deg = 70
mirrored = true
"""


def _trailer(x_min: float, half_width: float, x_max: float = -2.5) -> str:
    return f"""
[[keep_out]]
name = "trailer"
reason = "a coupled trailer"
min = [{x_min}, {-half_width}, 0.0]
max = [{x_max}, {half_width}, 4.0]
optional = true
occludes = true
"""


def _vehicle(tmp_path_factory, text: str) -> Vehicle:
    path = tmp_path_factory.mktemp("truck") / "vehicle.toml"
    path.write_text(text)
    return Vehicle.from_spec(read_spec(path))


@pytest.fixture(scope="module")
def truck(tmp_path_factory) -> Vehicle:
    vehicle = _vehicle(tmp_path_factory, TRUCK)
    np.testing.assert_allclose(vehicle.mesh.bounds, [[-3.0, -1.6, 0.3], [3.5, 1.6, 2.8]], atol=1e-6)
    return vehicle


@pytest.fixture(scope="module")
def long_trailer(tmp_path_factory) -> Vehicle:
    """The truck with a 1.5 m wide trailer reaching 40 m back (past R151's 30 m band)."""
    return _vehicle(tmp_path_factory, TRUCK + _trailer(-40.0, 1.5))


def _inside(polygon, x, y) -> bool:
    return bool(polygon.contains(shapely.Point(x, y)))


# ------------------------------------------------------------------------------------------------ R151


def test_r151_lines_leave_out_the_mirrors_and_everything_above_2_m(truck):
    whole = PRESETS["r158"].lines(truck)  # the whole body: roof overhang and mirrors count
    assert (whole.front, whole.rear, whole.nearside) == pytest.approx((3.5, -3.0, -1.6), abs=TOL)
    lines = PRESETS["r151"].lines(truck)
    assert (lines.front, lines.rear, lines.nearside, lines.offside) == pytest.approx((3.0, -3.0, -1.2, 1.2), abs=TOL)


def test_r151_field_runs_30_m_back_from_the_front_corner_4_5_m_out(truck):
    polygon = PRESETS["r151"].polygon(truck)
    assert polygon.bounds == pytest.approx((3.0 - 30.0, -1.2 - 4.5, 3.0, -1.2), abs=TOL)
    assert _inside(polygon, 0.0, -1.55)  # under the mirror line: R151 asks for it
    assert not _inside(polygon, 0.0, -1.45)  # within 0.3 m of the body's side
    assert not _inside(polygon, 3.2, -2.0)  # ahead of the body's front (the roof overhang does not count)


def test_r151_with_a_coupled_trailer_runs_to_the_trailer_rear(long_trailer):
    coupled = PRESETS["r151"].polygon(long_trailer)
    solo = PRESETS["r151"].polygon(long_trailer, lifted=("trailer",))
    # coupled: the trailer's rear (x -40) and its side (y -1.5, wider than the body) are the vehicle's
    assert coupled.bounds == pytest.approx((-40.0, -1.5 - 4.5, 3.0, -1.5), abs=TOL)
    assert not _inside(coupled, -20.0, -1.7) and _inside(coupled, -20.0, -1.9)
    # driven solo: the body's lines, and the band's 30 m
    assert solo.bounds == pytest.approx((-27.0, -1.2 - 4.5, 3.0, -1.2), abs=TOL)


def test_a_short_trailer_lies_inside_the_30_m_band(tmp_path_factory):
    short = _vehicle(tmp_path_factory, TRUCK + _trailer(-14.0, 1.0))
    assert PRESETS["r151"].polygon(short).bounds == pytest.approx((-27.0, -5.7, 3.0, -1.2), abs=TOL)


def test_r151_on_the_hgv_measures_from_its_cab_side_and_its_trailer():
    from rigopt.vehicle.library import load_vehicle

    hgv = load_vehicle("hgv")
    coupled, solo = PRESETS["r151"].lines(hgv), PRESETS["r151"].lines(hgv, lifted=("trailer",))
    # the cab's plan is 1.37 m to each side (vehicles/hgv/vehicle.toml); the right mirror reaches 1.511 m
    assert coupled.nearside == pytest.approx(-1.37, abs=0.005) and solo.nearside == coupled.nearside
    assert hgv.mesh.bounds[0][1] == pytest.approx(-1.511, abs=0.001)
    assert coupled.rear == pytest.approx(-14.0) and solo.rear == pytest.approx(hgv.mesh.bounds[0][0])


def test_the_other_presets_keep_the_whole_body_and_ignore_the_trailer(long_trailer):
    assert PRESETS["r158"].lines(long_trailer).rear == pytest.approx(-3.0, abs=TOL)
    assert PRESETS["r46-v"].lines(long_trailer).nearside == pytest.approx(-1.6, abs=TOL)


# ------------------------------------------------------------------------------------------------ R46


def test_r46_iv_outer_edge_runs_straight_and_gives_the_directive_area():
    corners = PRESETS["r46-iv"].boxes[0]
    assert isinstance(corners, FieldPolygon)
    # on lines at 0 (eye and nearside, outward -y): 15 m x 15 m plus the trapezoid 8.5 m x (4.5 + 15) / 2
    from rigopt.coverage.regulations import BodyLines

    shape = corners.shape(BodyLines(front=5.0, rear=-5.0, eye=0.0, nearside=0.0, offside=2.0, outward=-1.0))
    assert shape.area == pytest.approx(225.0 + 8.5 * 19.5 / 2)  # 307.875 m2: 2007/38/EC's 307.9
    assert shape.bounds == pytest.approx((-25.0, -15.0, -1.5, 0.0))


def test_r46_ii_lies_on_both_sides_from_4_m_behind_the_eyes(box_vehicle):
    eye = 2.0 - 2.2  # the box car is M1: eyes 2.2 m behind its front
    polygon = PRESETS["r46-ii"].polygon(box_vehicle)
    left, right = sorted(shapely.get_parts(polygon), key=lambda part: part.bounds[1], reverse=True)
    assert left.bounds == pytest.approx((eye - R46_HORIZON_CUT, 1.0, eye - 4.0, 6.0), abs=TOL)
    assert right.bounds == pytest.approx((eye - R46_HORIZON_CUT, -6.0, eye - 4.0, -1.0), abs=TOL)
    mirrored = shapely.affinity.scale(right, 1.0, -1.0, origin=(0, 0))
    assert left.symmetric_difference(mirrored).area < 1e-9
    # 1 m wide at 4 m back, 5 m from 30 m back; 5 m back the outer edge is 1 + 4 * 1 / 26 = 1.154 m out
    for y_sign in (1.0, -1.0):
        assert _inside(polygon, eye - 40.0, y_sign * 5.9) and not _inside(polygon, eye - 40.0, y_sign * 6.1)
        assert _inside(polygon, eye - 5.0, y_sign * 2.1) and not _inside(polygon, eye - 5.0, y_sign * 2.2)
        assert not _inside(polygon, eye - 3.9, y_sign * 1.5)
    assert polygon.area == pytest.approx(2 * (20.0 * 5.0 + 26.0 * 3.0))


def test_a_field_polygon_refuses_too_few_and_crossing_corners():
    from rigopt.coverage.regulations import BodyLines

    with pytest.raises(RigoptError, match="at least 3"):
        FieldPolygon(((("eye", 0.0), ("nearside", 0.0)), (("eye", -1.0), ("nearside", 1.0))))
    with pytest.raises(RigoptError, match="corner's side edge"):
        FieldPolygon(((("eye", 0.0), ("front", 0.0)),) * 3)
    bowtie = FieldPolygon(((("eye", 0.0), ("nearside", 0.0)), (("eye", -1.0), ("nearside", 1.0)),
                           (("eye", 0.0), ("nearside", 1.0)), (("eye", -1.0), ("nearside", 0.0))))
    with pytest.raises(RigoptError, match="cross"):
        bowtie.shape(BodyLines(1.0, -1.0, 0.0, -1.0, 1.0, -1.0))


# ------------------------------------------------------------------------------------------- criticality


def test_criticality_weights_by_hand():
    body = shapely.box(-2.0, -1.0, 2.0, 1.0)
    corner = (2.0, -1.0)
    points = [[2.0, -1.0], [2.0, -2.0], [5.0, -1.0], [0.0, -3.0], [-2.0, 3.0]]
    expected = [1.0 + 1.0,
                1 / (1 + 1.0) + 1 / (1 + 1.0),
                1 / (1 + 3.0) + 1 / (1 + 3.0),
                1 / (1 + 2.0) + 1 / (1 + np.hypot(2.0, 2.0)),
                1 / (1 + 2.0) + 1 / (1 + np.hypot(4.0, 4.0))]
    np.testing.assert_allclose(criticality_weights(points, body, corner), expected)


def test_the_weighted_share_weights_each_required_point_by_its_criticality(box_vehicle, camera, rig):
    narrow = rig(camera([-2.03, 0.0, 1.45], yaw_deg=180.0, pitch_deg=-40.0, fov=100.0, id="REAR"))
    preset = PRESETS["r158"]
    (result,) = region_coverage(narrow, box_vehicle, [preset], spacing=0.1)
    points = preset.points(box_vehicle, 0.1)
    points = points[required_mask(box_vehicle, points)]
    unseen = {tuple(p) for p in np.round(result.unseen, 9)}
    seen = np.array([tuple(p) not in unseen for p in np.round(points, 9)])
    weights = preset.criticality(box_vehicle, points[:, :2])
    assert seen.mean() == pytest.approx(result.covered_frac)
    assert result.weighted_covered_frac == pytest.approx(np.sum(weights * seen) / np.sum(weights))
    assert result.weighted_covered_frac != pytest.approx(result.covered_frac, abs=1e-3)


# ------------------------------------------------------------------------------------------ camera shares


def test_camera_shares_add_up_to_the_covered_share(box_vehicle, camera, rig):
    wide = camera([-2.03, 0.0, 1.45], yaw_deg=180.0, pitch_deg=-50.0, fov=150.0, id="REAR")
    twin = camera([-2.03, 0.1, 1.45], yaw_deg=180.0, pitch_deg=-50.0, fov=150.0, id="TWIN")
    narrow = camera([-2.03, 0.0, 1.45], yaw_deg=180.0, pitch_deg=-40.0, fov=100.0, id="NARROW")
    front = camera([2.03, 0.0, 1.0], yaw_deg=0.0, fov=120.0, id="FRONT")
    preset = [PRESETS["r158"].with_min_px(0)]  # in view is enough: the shares' arithmetic alone

    (alone,) = region_coverage(rig(front, wide), box_vehicle, preset, spacing=0.2)
    assert [(c.camera, c.seen_frac, c.only_frac) for c in alone.cameras] == [("FRONT", 0.0, 0.0), ("REAR", 1.0, 1.0)]
    assert alone.overlap_frac == 0.0

    (both,) = region_coverage(rig(wide, twin), box_vehicle, preset, spacing=0.2)
    assert [(c.seen_frac, c.only_frac) for c in both.cameras] == [(1.0, 0.0), (1.0, 0.0)]
    assert both.overlap_frac == 1.0

    parts = region_coverage(rig(narrow, front), box_vehicle, [PRESETS["r158"], PRESETS["r159"]], spacing=0.2)
    assert all(0.0 < result.covered_frac < 1.0 for result in parts)
    for result in (alone, both, *parts):
        assert sum(c.only_frac for c in result.cameras) + result.overlap_frac == pytest.approx(result.covered_frac)
        assert all(c.only_frac <= c.seen_frac <= result.covered_frac + TOL for c in result.cameras)


def test_a_field_with_no_required_point_has_no_camera_share(tmp_path_factory, box_vehicle, camera, rig):
    text = Path(box_vehicle.spec.source).read_text() + _trailer(-20.0, 1.5, x_max=-2.0)  # covers all of r158
    coupled = _vehicle(tmp_path_factory, text)
    (result,) = region_coverage(rig(camera([2.03, 0.0, 1.0], id="FRONT")), coupled, [PRESETS["r158"]], spacing=0.2)
    assert result.n_points == 0 and result.covered and result.covered_frac == 1.0
    assert result.cameras[0].seen_frac == 0.0 and result.overlap_frac == 0.0
    # every point of the field lies under the trailer: counted as not asked for, so a "100 %" says what it rests on
    polygon = PRESETS["r158"].polygon(coupled)
    total = len(grid_inside(polygon, 0.2)) + len(boundary_samples(polygon, 0.2))
    assert result.n_excluded == total * len(PRESETS["r158"].heights) > 0
    (solo,) = region_coverage(rig(camera([2.03, 0.0, 1.0], id="FRONT")), coupled, [PRESETS["r158"]], spacing=0.2,
                              lifted=("trailer",))
    assert solo.n_excluded == 0 and solo.n_points == result.n_excluded


def test_the_camera_field_table_lists_every_camera_seeing_a_field_and_the_totals(box_vehicle, camera, rig):
    from rigopt.report.coverage_tables import camera_field_rows, regions_dict

    cameras = rig(camera([-2.03, 0.0, 1.45], yaw_deg=180.0, pitch_deg=-50.0, fov=150.0, id="REAR"),
                  camera([2.03, 0.0, 1.0], fov=120.0, id="FRONT"),
                  camera([0.0, 0.0, 1.51], pitch_deg=80.0, fov=60.0, id="SKY"))
    in_view = [PRESETS["r158"].with_min_px(0), PRESETS["r159"].with_min_px(0)]  # the table's layout alone
    regions = regions_dict(region_coverage(cameras, box_vehicle, in_view, spacing=0.2))
    columns, rows = camera_field_rows(regions)
    assert columns == ["camera", "r158", "r159"]
    assert [row[0] for row in rows] == ["REAR", "FRONT", "seen by >= 2", "seen by any"]  # SKY sees no field
    assert rows[0][1] == "100.0 % (100.0 % alone)" and rows[1][1] == "0.0 %"  # alone: only where it is so
    assert rows[3][2] == f"{100 * regions[1]['covered_frac']:.1f} %"


@pytest.mark.slow
def test_the_report_folder_draws_a_two_sided_field_piece_by_piece(box_vehicle, camera, rig, small_settings, tmp_path):
    from rigopt.coverage.measures import coverage_report
    from rigopt.report.coverage_html import write_coverage_folder

    cameras = rig(camera([-2.03, 0.0, 1.45], yaw_deg=180.0, pitch_deg=-20.0, fov=150.0, id="REAR"))
    regions = region_coverage(cameras, box_vehicle, [PRESETS["r46-ii"]], spacing=0.5)
    assert regions[0].polygon.geom_type == "MultiPolygon"
    written = write_coverage_folder(tmp_path, coverage_report(cameras, box_vehicle, small_settings), cameras,
                                    vehicle=box_vehicle, regions=regions)
    page = (tmp_path / "report.html").read_text(encoding="utf-8")
    assert [p.name for p in written][-2:] == ["regions.png", "report.html"]
    assert page.count('"name":"r46-ii"') == 2 * 2  # the 3D view: each side's fill and outline
    assert "seen by &gt;= 2" in page and "REAR" in page  # the camera -> field table
