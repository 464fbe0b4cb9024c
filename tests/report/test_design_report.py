"""The design report's tables in one frame (ISO 8855 from the ground below the rear axle's centre) and its
packaging sheet, built from a rig and a vehicle (no design run): camera rows, packaging rows, report.json's
frame, the HTML tables."""

from __future__ import annotations

import html
import json
import re

import numpy as np
import pytest
from box_car import BOX_BODY, BOX_WHEELS, BOX_ZONES, spec_text

from rigopt.coverage.packaging import REAR_AXLE_ORIGIN, rig_packaging
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.report.design_html import packaging_section, render_design_html
from rigopt.report.design_report import camera_rows, frame_dict, packaging_rows
from rigopt.report.json_values import json_ready
from rigopt.rig.model import Camera, Rig, RigOrigin
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

FRAME = "ISO 8855, origin on the ground below the rear axle's centre"


@pytest.fixture(scope="module")
def car(tmp_path_factory) -> Vehicle:
    """The box car on wheels: its rear axle at x = -1.3 m."""
    path = tmp_path_factory.mktemp("reportcar") / "vehicle.toml"
    path.write_text(spec_text("reportcar", BOX_BODY + BOX_WHEELS, BOX_ZONES))
    return Vehicle.from_spec(read_spec(path))


@pytest.fixture(scope="module")
def rig() -> Rig:
    """A front camera turned 20 degrees left and tilted 10 down, and a left camera rolled 5 degrees."""
    return Rig("design", "vehicle.test.reportcar", (
        Camera.pinhole("F", np.array([2.04, 0.0, 1.0]), rotation_from_yaw_pitch_roll(*np.deg2rad([20.0, -10.0, 0.0])), 90.0,
               zone="front"),
        Camera.pinhole("L", np.array([0.5, 0.94, 1.2]), rotation_from_yaw_pitch_roll(*np.deg2rad([90.0, 0.0, 5.0])), 100.0,
               zone="side")))


def test_camera_rows_are_measured_from_the_rear_axle_with_iso_angles(car, rig):
    rows = camera_rows(rig, rig, [("F", "F"), ("L", "L")], car)
    assert np.allclose([r["position"] for r in rows], [[3.34, 0.0, 1.0], [1.8, 0.94, 1.2]])
    assert rows[0]["yaw_pitch_roll_deg"] == pytest.approx([20.0, -10.0, 0.0])
    assert rows[1]["yaw_pitch_roll_deg"] == pytest.approx([90.0, 0.0, 5.0])
    assert all("carla" not in r for r in rows)  # CARLA's frame only in the rig file
    assert rows[0]["matched_reference_camera"]["t_m"] == pytest.approx(0.0)


def test_camera_rows_without_a_vehicle_stay_at_the_vehicle_centre(rig):
    rows = camera_rows(rig, rig, [], None)
    assert rows[0]["position"] == pytest.approx([2.04, 0.0, 1.0])


def test_a_camera_states_the_reference_camera_it_was_designed_for_and_its_pose_against_it(car, rig):
    """The designer's own pairing (stand-ins) beside RigCD's matching: here F stands in for a reference camera 0.3 m
    lower, turned 170 deg (its yaw gap wraps to -150) and 10 deg wider, whatever RigCD pairs; L stands in for none."""
    reference = Rig("ref", "vehicle.test.reportcar", (Camera.pinhole(
        "R_BACK", np.array([-2.0, 0.0, 0.7]), rotation_from_yaw_pitch_roll(*np.deg2rad([170.0, -4.0, 0.0])), 80.0),))
    rows = camera_rows(rig, reference, [], car, stand_ins=[("F", "R_BACK")])
    designed = rows[0]["stands_in_for"]
    assert designed["id"] == "R_BACK"
    assert designed["height_m"] == pytest.approx(0.3) and designed["fov_deg"] == pytest.approx(10.0)
    assert designed["yaw_deg"] == pytest.approx(-150.0) and designed["pitch_deg"] == pytest.approx(-6.0)
    assert designed["lenses_apart_m"] == pytest.approx(np.hypot(4.04, 0.3))
    assert "stands_in_for" not in rows[1] and rows[0]["matched_reference_camera"] is None


def test_the_report_names_its_frame_and_where_its_origin_lies(car):
    assert frame_dict(car) == {"frame": FRAME, "origin_from_vehicle_centre_m": pytest.approx([-1.3, 0.0, 0.0])}


def test_packaging_rows_are_the_sheets_from_the_rear_axle(car, rig):
    rows = packaging_rows(rig, car)
    sheets = rig_packaging(rig, car)
    assert [r["camera"] for r in rows] == ["F", "L"]
    assert rows[0]["position_m"] == pytest.approx((sheets[0].position - [-1.3, 0.0, 0.0]).tolist())
    assert rows[0]["mount_point_m"] == pytest.approx([3.3, 0.0, 1.0])
    assert rows[0]["wedge_angle_deg"] == pytest.approx(np.degrees(np.arccos(np.cos(np.radians(20)) *
                                                                            np.cos(np.radians(10)))))
    assert rows[1]["zone"] == "side" and rows[0]["blocked_frac"] == 0.0
    json.dumps(json_ready({**frame_dict(car), "packaging": rows}), allow_nan=False)


def test_a_rig_measured_from_the_rear_axle_reports_the_same_positions(car, rig):
    moved = Rig("axle", rig.vehicle, tuple(Camera.pinhole(c.id, c.position + [1.3, 0, 0], c.rotation, c.fov, zone=c.zone)
                                          for c in rig.cameras), RigOrigin("rear_axle"))
    assert packaging_rows(moved, car) == packaging_rows(rig, car)


def _summary(rig: Rig, car: Vehicle) -> dict:
    """A design_dict-shaped summary of ``rig`` as its own design (no solver run)."""
    prediction = {"predicted_drop": 0.1, "interval": None, "interval_informative": None, "linear_drop": 0.1,
                  "extrapolation": None, "fallback": False, "rigcd": 0.2, "n_cameras": len(rig), "coverage": 1.0,
                  "meets_coverage_requirements": True}
    return {"rig_file": "rig.json", "vehicle": car.name, **frame_dict(car), "reference": "self", "metric": "rigcd",
            "weights": "joint", **prediction, "per_reference": [{"reference": "self", "predicted_drop": 0.1,
                                                                "rigcd": 0.2}],
            "reference_coverage": 1.0,
            "solver": {"milp_status": "optimal", "milp_gap": 0.0, "milp_seconds": 1.0, "refine_status": "off",
                       "candidates": 2, "offered_to_milp": 2, "repairs": 0, "seconds": 1.0},
            "cameras": camera_rows(rig, rig, [("F", "F"), ("L", "L")], car), "packaging": packaging_rows(rig, car),
            "regions": [], "rigcd_breakdown": {"rigcd": 0.0},
            "comparisons": {"naive_transfer": None, "benchmark_rig": None, "benchmark_rigs": []}}


def test_the_page_has_the_packaging_table_and_one_frame(car, rig):
    page = render_design_html(_summary(rig, car), {})
    packaging = page[page.index("<h2>Packaging</h2>"):]
    rows = re.findall(r"<tr><td>([^<]+)</td><td>([^<]+)</td>", packaging)
    assert rows[:2] == [("F", "front"), ("L", "side")]
    assert f"mount point x, y, z (m, {html.escape(FRAME)})" in packaging and "bracket wedge" in packaging
    assert "1.8 m adult px (left / centre / right)" in packaging and "image blocked by body" in packaging
    cameras = page[page.index("<h2>Cameras</h2>"):page.index("<h2>Packaging</h2>")]
    assert f"x, y, z (m, {html.escape(FRAME)})" in cameras and "3.34, 0.00, 1.00" in cameras  # from the rear axle
    tables = "".join(re.findall(r"<table>.*?</table>", page, flags=re.S))
    assert "CARLA" not in tables and "carla" not in tables  # CARLA only in the note on the rig file


def test_the_packaging_table_says_where_the_camera_sees_no_ground(car):
    sky = Rig("sky", "vehicle.test.reportcar", (Camera.pinhole("U", np.array([2.04, 0.0, 1.0]),
                                                       rotation_from_yaw_pitch_roll(0.0, 1.0, 0.0), 60.0),))
    section = "".join(packaging_section(packaging_rows(sky, car), FRAME))
    row = re.search(r"<tr><td>U</td>(.*?)</tr>", section).group(1)
    assert "5 m: - / -; 10 m: - / -; 20 m: - / -" in row  # no ground there: said, not a number
    assert html.escape(REAR_AXLE_ORIGIN) in section


# --- the RigCD breakdown, the field tables, the pictures' frame ------------------------------------------


def _with_near_field(rig: Rig) -> Rig:
    """``rig`` and two near-field cameras low on the sides, looking down."""
    near = tuple(Camera.pinhole(f"N{k}", np.array([0.0, side * 0.94, 0.6]),
                                rotation_from_yaw_pitch_roll(*np.deg2rad([side * 90.0, -60.0, 0.0])), 120.0,
                                zone="side", role="near_field") for k, side in enumerate((1.0, -1.0)))
    return Rig(rig.name, rig.vehicle, rig.cameras + near)


def test_the_breakdown_compares_the_perception_cameras_only(car, rig):
    from rigopt.report.design_report import perception_breakdown

    designed = _with_near_field(rig)
    breakdown, values = perception_breakdown(rig, designed)
    assert values["count"] == 0.0 and values["rigcd"] == pytest.approx(0.0, abs=1e-12)  # as rigopt rigcd says
    assert (values["reference_cameras"], values["design_cameras"]) == (2, 2)
    assert sorted(b for _, b in breakdown.pairs) == ["F", "L"]  # no near-field camera has a partner
    rows = camera_rows(designed, rig, breakdown.pairs, car)
    assert [r["matched_reference_camera"] is None for r in rows] == [False, False, True, True]
    summary = {**_summary(designed, car), "rigcd_breakdown": values, "roles": {"perception": 2, "near_field": 2},
               "cameras": rows}
    page = html.unescape(render_design_html(summary, {}))
    assert "to the 2 perception cameras of the design" in page and "the design's 2 near-field cameras, not fed to the detector, left out" in page
    assert "count 0.000" in page and "design_cameras" not in page
    assert "near-field camera: not fed to the detector, not compared" in page


def _field(key: str, cameras: list[tuple[str, float, float]], covered: float, weighted: float) -> dict:
    """A ``regions_dict`` entry of a field seen by ``cameras`` [(id, seen, alone)]."""
    overlap = covered - sum(alone for _, _, alone in cameras)
    return {"key": key, "title": f"{key} field", "source": f"UN {key}", "heights_m": [0.0, 0.8], "covered": covered == 1,
            "covered_frac": covered, "weighted_covered_frac": weighted, "in_view_frac": 1.0,
            "test_object": {"name": "a child", "height_m": 1.15, "width_m": 0.3, "min_px": 25.0, "source": "test"},
            "height_covered_frac": [{"height_m": 0.0, "covered_frac": covered}, {"height_m": 0.8, "covered_frac": 1.0}],
            "n_points": 100, "n_unseen": 0, "area_m2": 12.0, "unseen_area_m2": 1.5, "spacing_m": 0.1,
            "cameras": [{"camera": c, "seen_frac": s, "only_frac": a} for c, s, a in cameras], "overlap_frac": overlap}


def test_the_field_tables_give_the_weighted_share_and_which_camera_sees_which_field(car, rig):
    regions = [_field("r158", [("F", 0.0, 0.0), ("N0", 0.62, 0.04), ("N1", 0.9, 0.3)], 0.96, 0.873),
               _field("r151", [("F", 0.0, 0.0), ("N0", 0.5, 0.5), ("N1", 0.0, 0.0)], 0.5, 0.41)]
    summary = {**_summary(rig, car), "regions": regions, "regions_required": True}
    page = render_design_html(summary, {})
    section = page[page.index("<h2>Regulation fields"):]
    fields = re.search(r"<table>.*?</table>", section, flags=re.S).group(0)
    assert "<th>weighted seen</th>" in fields and ">87.3 %<" in fields and ">41.0 %<" in fields
    table_map = re.findall(r"<table>.*?</table>", section, flags=re.S)[1]
    rows = {cells[0]: cells[1:] for cells in (re.findall(r"<td[^>]*>([^<]*)</td>", row)
                                              for row in re.findall(r"<tr>(.*?)</tr>", table_map)) if cells}
    assert "F" not in rows  # it sees no field: no row
    assert rows["N0"] == ["62.0 % (4.0 % alone)", "50.0 % (50.0 % alone)"]
    assert rows["N1"] == ["90.0 % (30.0 % alone)", "0.0 %"]  # alone only where it is the only camera for some
    assert rows["seen by any"] == ["96.0 %", "50.0 %"]


def test_the_coverage_page_builds_its_field_tables_as_the_design_report_does():
    from rigopt.report import coverage_html, design_html
    from rigopt.report.coverage_tables import field_tables_html

    assert coverage_html.field_tables_html is field_tables_html is design_html.field_tables_html


def _plotted(ax, marker: str) -> np.ndarray:
    """(n, 2) float: the data of every line of ``ax`` drawn with ``marker``, in the axes' coordinates."""
    return np.concatenate([line.get_xydata() for line in ax.get_lines() if line.get_marker() == marker])


def test_the_pictures_draw_the_cameras_where_the_tables_put_them(car, rig):
    from rigopt.coverage.measures import ring_report
    from rigopt.coverage.packaging import report_origin
    from rigopt.coverage.regulations import PRESETS, region_coverage
    from rigopt.report.coverage_figures import regions_figure
    from rigopt.report.vehicle_figures import vehicle_figure

    datum = report_origin(car)
    rows = camera_rows(rig, rig, [], car)  # the tables: x 3.34 and 1.8 from the rear axle
    top, side = vehicle_figure(car, rig, datum).axes[:2]
    assert np.allclose(_plotted(top, "o"), [r["position"][:2] for r in rows])
    assert np.allclose(_plotted(side, "o"), [r["position"][::2] for r in rows])
    assert top.get_xlabel() == "x forward (m), from the rear axle" and "rear axle" in top.get_title()
    fields = region_coverage(rig, car, [PRESETS["r158"]], spacing=0.5)
    (ax,) = regions_figure(fields, ring_report(rig, car), rig, datum).axes
    assert np.allclose(_plotted(ax, "o"), [[r["position"][1], r["position"][0]] for r in rows])  # (y, x) top view
    assert ax.get_ylabel() == "x forward (m), from the rear axle"
    (centred,) = regions_figure(fields, ring_report(rig, car), rig).axes  # the default: the vehicle centre
    assert np.allclose(_plotted(centred, "o")[:, 1], rig.positions[:, 0])
    assert centred.get_ylabel() == "x forward (m), from the vehicle centre"


def test_vehicle_show_report_json_and_the_packaging_sheet_put_a_camera_at_the_same_coordinates(monkeypatch, tmp_path):
    """One frame everywhere: R1 on the etron drawn by ``rigopt vehicle show`` (the figure it draws, caught on its way
    to the file) has every camera where report.json's camera table and the packaging sheet put it, from the rear
    axle."""
    import rigopt.report.vehicle_figures as figures
    from in_process import run_rigopt

    from rigopt.rig.library import load_rig
    from rigopt.vehicle.library import load_vehicle

    drawn = []

    def keep(vehicle, path, rig=None, datum=figures.CENTRE_DATUM):
        drawn.append(figures.vehicle_figure(vehicle, rig, datum))
        figures.Path(path).write_bytes(b"picture")  # the file the command publishes
        return figures.Path(path)

    monkeypatch.setattr(figures, "write_vehicle_figure", keep)
    assert run_rigopt("vehicle", "show", "etron", "--rig", "R1", "--out", tmp_path / "etron.png").returncode == 0
    etron, r1 = load_vehicle("etron"), load_rig("R1")
    table = [row["position"] for row in camera_rows(r1, r1, [], etron)]
    sheet = [row["position_m"] for row in packaging_rows(r1, etron)]
    top, side = drawn[0].axes[:2]
    assert np.allclose(table, sheet)
    assert np.allclose(_plotted(top, "o"), np.array(table)[:, :2])
    assert np.allclose(_plotted(side, "o"), np.array(table)[:, ::2])
    assert "rear axle" in top.get_xlabel() and not np.allclose(np.array(table)[:, 0], r1.positions[:, 0])
