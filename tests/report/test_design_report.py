"""The design report's tables in one frame (ISO 8855 from the ground below the rear axle's centre) and its
packaging sheet, built from a rig and a vehicle (no design run): camera rows, packaging rows, report.json's
frame, the HTML tables."""

from __future__ import annotations

import html
import json
import re

import numpy as np
import pytest
from box_car import BOX_BODY, BOX_ZONES, spec_text

from rigopt.coverage.packaging import REAR_AXLE_ORIGIN, rig_packaging
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.report.design_html import packaging_section, render_design_html
from rigopt.report.design_report import camera_rows, frame_dict, packaging_rows
from rigopt.report.json_values import json_ready
from rigopt.rig.model import Camera, Rig, RigOrigin
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

WHEELS = """
[[solids]]
name = "wheels"
type = "wheels"
axles = [1.3, -1.3]
radius = 0.35
width = 0.25
track = 1.6
"""

FRAME = "ISO 8855, origin on the ground below the rear axle's centre"


@pytest.fixture(scope="module")
def car(tmp_path_factory) -> Vehicle:
    """The box car on wheels: its rear axle at x = -1.3 m."""
    path = tmp_path_factory.mktemp("reportcar") / "vehicle.toml"
    path.write_text(spec_text("reportcar", BOX_BODY + WHEELS, BOX_ZONES))
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
