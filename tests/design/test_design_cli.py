"""``rigopt design``: the JSON summary and the rig file of one real run (firetruck from R1, module-scoped),
and bad input, which exits 2 with one ``rigopt: error:`` line and no traceback (run in-process through the
console script's error handling; tests/cli/test_console_script.py checks that path in real processes). The real
run is a whole design: its tests run with ``-m slow``; a small design on the tt (one lens, one pitch) checks the
same keys and the rig file in the default run.
"""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from typer.testing import CliRunner

from in_process import run_rigopt
from rigopt.cli.app import app
from rigopt.design.settings import DesignSettings
from rigopt.errors import RigoptError
from rigopt.metrics.calibration import load_weights
from rigopt.metrics.rigcd import rigcd
from rigopt.rig.library import load_rig

BAD_INPUT = {
    "unknown vehicle": (["--vehicle", "nosuchcar", "--ref", "R1"], ["nosuchcar", "firetruck"]),
    "unknown ref": (["--vehicle", "firetruck", "--ref", "R99"], ["R99", "R6"]),
    "unknown weights": (["--vehicle", "firetruck", "--ref", "R1", "--weights", "nosuchweights"],
                        ["nosuchweights", "joint"]),
    "zero cameras": (["--vehicle", "firetruck", "--ref", "R1", "--cameras", "0"], ["--cameras", "'0'"]),
    "reversed camera range": (["--vehicle", "firetruck", "--ref", "R1", "--cameras", "9-3"], ["--cameras", "9-3"]),
    "lens outside (0, 180)": (["--vehicle", "firetruck", "--ref", "R1", "--fov", "0,200"], ["(0, 180)"]),
    "pitch not a number": (["--vehicle", "firetruck", "--ref", "R1", "--pitch", "abc"], ["--pitch", "abc"]),
}


@pytest.fixture(scope="module")
def design_run(tmp_path_factory):
    """``rigopt design --vehicle firetruck --ref R1 --json --out OUT`` in a tmp working directory."""
    cwd = tmp_path_factory.mktemp("design_cli")
    out = cwd / "OUT"
    previous = os.getcwd()
    os.chdir(cwd)
    try:
        result = CliRunner().invoke(app, ["design", "--vehicle", "firetruck", "--ref", "R1", "--json", "--out", str(out)])
    finally:
        os.chdir(previous)
    assert result.exit_code == 0, (result.output, result.exception)
    return json.loads(result.stdout), out, cwd


@pytest.fixture(scope="module")
def bad_runs(tmp_path_factory):
    """{case: (exit code, stdout, stderr)} of the BAD_INPUT cases run in-process through the console script's
    error handling, and "cwd": their working directory."""
    cwd = tmp_path_factory.mktemp("design_cli_errors")
    runs = {}
    for case, (args, _) in BAD_INPUT.items():
        outcome = run_rigopt("design", *args, cwd=cwd)
        runs[case] = (outcome.returncode, outcome.stdout, outcome.stderr)
    runs["cwd"] = cwd
    return runs


# --- the JSON summary ---------------------------------------------------------------------------------


#: A small design (the tt, one lens, one pitch, few yaws): the command end to end in the default run.
SMALL = ["--vehicle", "tt", "--ref", "R1", "--fov", "120", "--pitch", "0", "--yaw-step", "30", "--cameras", "6"]


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    """``rigopt design SMALL --json --out OUT``, in-process: (summary, out folder)."""
    out = tmp_path_factory.mktemp("design_cli_small") / "OUT"
    outcome = run_rigopt("design", *SMALL, "--json", "--out", out)
    assert outcome.returncode == 0, outcome.stderr
    return json.loads(outcome.stdout), out


def documented_keys(summary: dict) -> None:
    """The keys docs/cli.md documents for ``design --json``, at every level."""
    assert {"rig_file", "predicted_drop", "rigcd", "n_cameras", "coverage", "reference_coverage", "solver",
            "comparisons"} <= summary.keys()
    assert {"milp_status", "milp_gap", "refine_status", "seconds"} <= summary["solver"].keys()
    assert {"naive_transfer", "benchmark_rig"} <= summary["comparisons"].keys()
    assert {"predicted_drop", "coverage"} <= summary["comparisons"]["naive_transfer"].keys()
    assert {"name", "predicted_drop", "coverage"} <= summary["comparisons"]["benchmark_rig"].keys()
    assert {"interval", "linear_drop", "extrapolation", "fallback"} <= summary.keys()


@pytest.mark.slow
def test_json_has_the_documented_keys(design_run):
    documented_keys(design_run[0])


@pytest.mark.slow
def test_the_python_api_the_command_and_the_studies_make_the_same_rig_file(design_run, tmp_path):
    """``rigopt.design.design_rig("firetruck", "R1")`` (every default), ``DesignSettings.preset()`` (the studies'
    command_default) and ``rigopt design`` by default write the same rig.json, byte for byte."""
    import importlib.util
    from pathlib import Path

    from rigopt.design import design_rig
    from rigopt.rig.pccr_format import write_rig

    study = Path(__file__).resolve().parents[2] / "studies" / "designs" / "run.py"
    spec = importlib.util.spec_from_file_location("designs_run", study)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.command_default() == DesignSettings.preset()
    result = design_rig("firetruck", "R1")
    written = write_rig(result.design.rig, tmp_path / "rig.json", say_frame=True)  # as the command writes it
    assert written.read_bytes() == (design_run[1] / "rig.json").read_bytes()


def test_the_command_default_is_the_nearest_preset_and_one_camera_set_the_free_one():
    from rigopt.design.defaults import FREE_POSE, NEAREST_POSE

    nearest, single = DesignSettings.preset(), DesignSettings.preset(near_field=False, cameras=(6, 8))
    assert all(getattr(nearest, k) == v for k, v in NEAREST_POSE.items()) and nearest.near_field
    assert all(getattr(single, k) == v for k, v in FREE_POSE.items()) and single.cameras == (6, 8)
    assert DesignSettings.preset("nearest", match_height_m=0.2).match_height_m == 0.2  # a field given wins
    with pytest.raises(RigoptError, match="nearest, free"):
        DesignSettings.preset("closest")


def test_a_small_design_has_the_documented_keys_and_its_rig_file(small_run):
    summary, out = small_run
    documented_keys(summary)
    rig = load_rig(str(out / "rig.json"))
    assert rig.vehicle == "vehicle.audi.tt" and len(rig.perception()) == 6  # the CARLA blueprint, as R1 names it
    assert summary["solver"]["milp_status"] == "optimal" and summary["n_cameras"] == len(rig)
    assert {p.name for p in out.iterdir()} >= {"rig.json", "report.json", "report.html"}


def test_the_report_states_the_category_its_fields_and_what_applies_unmodelled(small_run):
    """The tt is M1: r158 by default, and UN R166 applies to it unmodelled, said in the JSON and the page; a truck's
    category names no such regulation."""
    from rigopt.coverage.regulations import category_dict, category_text
    from rigopt.vehicle.library import load_vehicle

    summary, out = small_run
    category = summary["vehicle_category"]
    assert category["category"] == "M1" and category["default_fields"] == ["r158"]
    assert [m["regulation"] for m in category["not_modelled"]] == ["UN R166"]
    page = " ".join((out / "report.html").read_text().split())
    assert "category M1 (stated in its vehicle.toml): fields asked for by default r158; UN R166 also applies" in page
    hgv = category_dict(load_vehicle("hgv"))
    assert hgv["not_modelled"] == [] and category_text(hgv).endswith("r151, r159, r158")


@pytest.mark.slow
def test_each_predicted_drop_is_the_drop_models_with_its_interval(design_run):
    """From R1 the report's predictions are the default shipped drop model's: each drop with its bin's 90 %
    half-width (capped at 1 above, not at 0 below: a rig can measure better than the reference), and RigCD's
    distance beside it."""
    from rigopt.metrics.drop_model import choose_model, interval_bin
    from rigopt.rig.library import load_rig

    summary, _, _ = design_run
    model = choose_model("auto", load_rig("R1"))
    by = f"{model.name} drop model"
    entries = (summary, summary["comparisons"]["naive_transfer"], *summary["comparisons"]["benchmark_rigs"])
    for entry in entries:
        halfwidth = model.halfwidths[interval_bin([entry["predicted_drop"]])[0]]
        assert entry["predictor"] == by and entry["linear_drop"] is None
        assert entry["interval"] == pytest.approx([entry["predicted_drop"] - halfwidth,
                                                   min(1.0, entry["predicted_drop"] + halfwidth)])
        assert entry["rigcd"] > 0
    r6 = summary["comparisons"]["benchmark_rig"]  # R6 on the fire truck, metres from R1's cameras
    assert r6["name"] == "R6" and r6["predicted_drop"] > summary["predicted_drop"]
    assert by in summary["notes"][0]


@pytest.mark.slow
def test_json_values_are_plausible(design_run):
    summary, _, _ = design_run
    # two roles by default: R1's 8 perception cameras and the near-field fisheyes that see the firetruck's fields
    assert summary["roles"]["perception"] == 8 and summary["roles"]["near_field"] >= 1
    assert summary["n_cameras"] == summary["roles"]["perception"] + summary["roles"]["near_field"]
    assert summary["solver"]["near_field"]["status"] == "optimal"
    assert summary["solver"]["near_field"]["cameras"] == summary["roles"]["near_field"]
    assert summary["regions_required"] and summary["regions_fallback"] is None
    assert [r["key"] for r in summary["regions"]] == ["r151", "r159", "r158"]
    assert all(r["covered"] and r["covered_frac"] == 1.0 for r in summary["regions"])
    # the default pose: perception cameras placed freely (R1's layout), the near-field fisheyes in mirrored pairs
    assert not summary["symmetry"]["required"] and summary["symmetry"]["near_field_mirrored"]
    assert summary["pose_tolerance"]["height_m"] == 0.05 and summary["perception_range_m"] == 20.0
    assert 0.0 < summary["coverage"] <= 1.0 and 0.0 < summary["reference_coverage"] <= 1.0
    assert summary["rigcd"] > 0 and summary["predicted_drop"] > 0
    assert summary["solver"]["milp_status"] == "optimal"
    assert 0.0 <= summary["solver"]["milp_gap"] <= 1e-4
    assert summary["solver"]["seconds"] > 0
    assert isinstance(summary["solver"]["refine_status"], str) and summary["solver"]["refine_status"]


@pytest.mark.slow
def test_benchmark_comparison_is_r6_and_the_design_predicts_less_drop(design_run):
    summary, _, _ = design_run
    benchmark = summary["comparisons"]["benchmark_rig"]
    assert benchmark["name"] == "R6"
    assert summary["predicted_drop"] < benchmark["predicted_drop"]


@pytest.mark.slow
def test_rig_file_is_in_the_out_folder(design_run):
    summary, out, _ = design_run
    assert os.path.samefile(summary["rig_file"], out / "rig.json")
    assert json.loads((out / "report.json").read_text())["rig_file"] == "rig.json"  # no machine path in the file


@pytest.mark.slow
def test_rig_file_loads_for_the_firetruck(design_run):
    summary, out, _ = design_run
    rig = load_rig(out / "rig.json")
    assert len(rig) == summary["n_cameras"]
    assert rig.vehicle == "vehicle.carlamotors.firetruck"
    assert json.loads((out / "rig.json").read_text())["vehicle_type"] == "vehicle.carlamotors.firetruck"


@pytest.mark.slow
def test_rig_file_has_the_reported_rigcd(design_run):
    summary, out, _ = design_run
    joint = load_weights("joint")
    value = rigcd(load_rig("R1"), load_rig(out / "rig.json").perception(), joint.alpha, joint.lambdas).rigcd
    assert value == pytest.approx(summary["rigcd"], abs=1e-5)


@pytest.mark.slow
def test_report_json_repeats_the_summary(design_run):
    summary, out, _ = design_run
    report = json.loads((out / "report.json").read_text())
    assert report["rigcd"] == pytest.approx(summary["rigcd"], abs=1e-12)
    assert report["n_cameras"] == summary["n_cameras"]


@pytest.mark.slow
def test_report_html_holds_the_3d_view_offline(design_run):
    import re

    summary, out, _ = design_run
    page = (out / "report.html").read_text(encoding="utf-8")
    view = page[page.index("<h2>3D view</h2>"):page.index("<h2>Pictures</h2>")]
    assert page.count("plotly.js v") == 1 and "plotly.js v" in view  # the library once, inline
    assert not re.search(r"<script[^>]*\bsrc=", page) and 'src="http' not in page
    assert "ISO 8855 vehicle frame" in view and "drawn in grey" not in view  # R1 sits on the etron: no comparison
    data = view[view.index("Plotly.newPlot"):]
    assert all(f'"name":"{camera["id"]}"' in data for camera in summary["cameras"])  # a frustum per camera
    assert '"name":"keep-out: locker_doors_front (roll-up locker doors)"' in data


@pytest.mark.slow
def test_nothing_is_written_outside_the_out_folder(design_run):
    _, out, cwd = design_run
    assert [p.name for p in cwd.iterdir()] == [out.name]


# --- bad input ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("case", list(BAD_INPUT))
def test_bad_input_exits_2_with_one_error_line(bad_runs, case):
    code, _, stderr = bad_runs[case]
    assert code == 2, stderr
    assert "Traceback" not in stderr
    errors = [line for line in stderr.splitlines() if line.startswith("rigopt: error: ")]
    assert len(errors) == 1, stderr
    assert stderr.strip().splitlines()[-1] == errors[0]  # the error is the last word
    for fragment in BAD_INPUT[case][1]:
        assert fragment in errors[0], (fragment, errors[0])


def test_bad_input_writes_no_design_folder(bad_runs):
    assert list(bad_runs["cwd"].iterdir()) == []


@pytest.mark.slow
def test_each_camera_reports_its_pose_from_the_rear_axle_and_the_reference_camera_it_matches(design_run):
    from rigopt.rig.library import load_rig

    summary, out, _ = design_run
    reference = {c.id for c in load_rig("R1").cameras}
    matched = [c["matched_reference_camera"] for c in summary["cameras"] if c["matched_reference_camera"]]
    assert sorted(m["id"] for m in matched) == sorted(reference)  # every reference camera has one partner
    assert summary["frame"] == "ISO 8855, origin on the ground below the rear axle's centre"
    rig = load_rig(out / "rig.json")  # CARLA's frame, from the vehicle centre: the rig file only
    for camera, placed in zip(summary["cameras"], rig.cameras):
        assert "carla" not in camera
        assert camera["position"] == pytest.approx((placed.position - summary["origin_from_vehicle_centre_m"]).tolist())
    report = json.loads((out / "report.json").read_text())
    assert [p["camera"] for p in report["packaging"]] == [c.id for c in rig.cameras]  # one sheet per camera
    assert all(camera["spray"] in ("high", "low") and camera["zone_cost"] == 1.0 for camera in summary["cameras"])
    breakdown = summary["rigcd_breakdown"]
    assert breakdown["t_m"] == pytest.approx(np.mean([m["t_m"] for m in matched]), rel=1e-9)
    # the perception cameras only, as rigopt rigcd compares them: R1's count, so no count term
    assert breakdown["design_cameras"] == summary["roles"]["perception"] == len(reference) and breakdown["count"] == 0
    assert breakdown["rigcd"] == pytest.approx(rigcd(load_rig("R1"), rig.perception()).rigcd, rel=1e-9)
    assert all(c["matched_reference_camera"] is None for c in summary["cameras"] if c["role"] == "near_field")
