"""The coverage report in the design report's frame (ISO 8855 from the ground below the rear axle's centre):
``rigopt coverage RIG --require r158 --json --out DIR`` on the box car on wheels (rear axle at x = -1.3 m, a
user vehicle under a tmp RIGOPT_HOME) puts each camera where the design report's tables put it, in the JSON
(stdout and coverage.json), the page's camera table, the terminal table, the top views and the 3D view, and
names that frame; on a vehicle whose axles are unknown it stays at the vehicle's centre and says so."""

from __future__ import annotations

import html
import json

import numpy as np
import pytest
from box_car import BOX_BODY, BOX_WHEELS, BOX_ZONES, front_and_left_rig, spec_text
from in_process import run_rigopt

from rigopt.coverage.measures import CoverageSettings, coverage_report
from rigopt.coverage.packaging import CENTRE_ORIGIN
from rigopt.report import coverage_figures
from rigopt.report.coverage_html import write_coverage_folder
from rigopt.report.design_report import camera_rows, frame_dict
from rigopt.rig.pccr_format import write_rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

FRAME = "ISO 8855, origin on the ground below the rear axle's centre"
#: What the design report's tables give for front_and_left_rig on the wheeled box car (m, from the rear axle).
EXPECTED = [[3.34, 0.0, 1.0], [1.3, 0.94, 1.0]]


def _vehicle_file(folder, name: str, solids: str):
    """``folder``/``name``/vehicle.toml: the box car named ``name`` with ``solids``."""
    path = folder / name / "vehicle.toml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(spec_text(name, solids, BOX_ZONES))
    return path


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """(the vehicle, the rig, stdout JSON, coverage.json, the page, the terminal tables, {png name: Figure})."""
    root = tmp_path_factory.mktemp("coverage_frame")
    spec = _vehicle_file(root / "home" / "vehicles", "framecar", BOX_BODY + BOX_WHEELS)
    rig = front_and_left_rig("vehicle.test.framecar", "framerig")
    rig_file, out, env = write_rig(rig, root / "framerig.json"), root / "out", {"RIGOPT_HOME": str(root / "home")}
    drawn, save = {}, coverage_figures._save

    def keep(figure, path):
        drawn[path.name] = figure
        return save(figure, path)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(coverage_figures, "_save", keep)
        result = run_rigopt("coverage", rig_file, "--require", "r158", "--json", "--out", out, env=env)
    assert result.returncode == 0, result.stderr
    tables = run_rigopt("coverage", rig_file, env=env)
    assert tables.returncode == 0, tables.stderr
    return (Vehicle.from_spec(read_spec(spec)), rig, json.loads(result.stdout),
            json.loads((out / "coverage.json").read_text()), (out / "report.html").read_text(encoding="utf-8"),
            tables.stdout, drawn)


def _plotted(ax, marker: str) -> np.ndarray:
    """(n, 2) float: the data of every line of ``ax`` drawn with ``marker``, in the axes' coordinates."""
    return np.concatenate([line.get_xydata() for line in ax.get_lines() if line.get_marker() == marker])


def test_the_json_names_the_design_reports_frame(run):
    car, _, stdout, written, *_ = run
    named = {"frame": FRAME, "origin_from_vehicle_centre_m": pytest.approx([-1.3, 0.0, 0.0])}
    assert frame_dict(car) == named
    for data in (stdout, written):
        assert {key: data[key] for key in named} == named


def test_the_cameras_are_where_the_design_report_puts_them(run):
    car, rig, stdout, written, *_ = run
    design = [row["position"] for row in camera_rows(rig, rig, [], car)]
    assert np.allclose(design, EXPECTED)
    for data in (stdout, written):
        assert [c["id"] for c in data["cameras"]] == [c.id for c in rig.cameras]
        assert np.allclose([c["position"] for c in data["cameras"]], design, atol=1e-9)


def test_the_page_and_the_terminal_table_give_the_same_positions(run):
    *_, page, tables, _ = run
    assert "position x, y, z (m, from the rear axle)</th>" in page
    assert '<td class="num">3.34, 0.00, 1.00</td>' in page and '<td class="num">1.30, 0.94, 1.00</td>' in page
    assert "3.34, 0.00, 1.00" in tables and "1.30, 0.94, 1.00" in tables
    assert "from the vehicle centre" not in page


def test_the_page_names_the_frame_of_its_tables_views_and_pictures(run):
    page = run[4]
    assert page.count(f"{html.escape(FRAME)} (x forward, y left") == 3  # the tables, the 3D view, the pictures
    assert "x forward (m), ISO 8855 vehicle frame from the rear axle" in page  # the 3D view's axis


def test_the_top_views_draw_the_cameras_where_the_tables_put_them(run):
    drawn = run[-1]
    assert {"bev.png", "blind.png", "regions.png", "rings.png"} <= drawn.keys()
    top = np.array(EXPECTED)[:, [1, 0]]  # (y, x): forward up
    for ax in [*drawn["bev.png"].axes[:2], drawn["regions.png"].axes[0]]:
        assert np.allclose(_plotted(ax, "o"), top, atol=1e-9)
        assert ax.get_ylabel() == "x forward (m), from the rear axle"
    ground = drawn["blind.png"].axes[1]  # the blind zone on the ground, the body (drawn last) over it
    assert ground.get_ylabel() == "x forward (m), from the rear axle"
    assert ground.patches[-1].get_xy()[:, 1].max() == pytest.approx(2.0 + 1.3, abs=0.05)  # the body's front


def test_without_known_axles_the_report_stays_at_the_vehicle_centre_and_says_so(tmp_path):
    from rigopt.report.coverage_html import page_datum

    box = Vehicle.from_spec(read_spec(_vehicle_file(tmp_path, "axlefree", BOX_BODY)))
    rig = front_and_left_rig("vehicle.test.axlefree", "plain")
    quick = CoverageSettings(ring_distances=(2.0,), ring_heights=(0.0,), ring_samples=72, sectors=72,
                             bev_extent=10.0, blind_azimuths=36, blind_search=5.0, blind_cell=0.2,
                             image_grid=(16, 9), overlap_ring=(2.0, 0.0))
    assert page_datum(box).origin == CENTRE_ORIGIN
    write_coverage_folder(tmp_path / "out", coverage_report(rig, box, quick), rig, vehicle=box)
    data = json.loads((tmp_path / "out" / "coverage.json").read_text())
    assert data["frame"] == f"ISO 8855, {CENTRE_ORIGIN}" and data["origin_from_vehicle_centre_m"] == [0.0, 0.0, 0.0]
    assert np.allclose([c["position"] for c in data["cameras"]], rig.positions)
    page = (tmp_path / "out" / "report.html").read_text(encoding="utf-8")
    assert html.escape("(the vehicle's axles are unknown)") in page
    assert "position x, y, z (m, from the vehicle centre)" in page and '<td class="num">2.04, 0.00, 1.00</td>' in page
