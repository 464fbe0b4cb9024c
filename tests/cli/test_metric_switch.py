"""``--metric rigcd|rigcd+`` on rank, calibrate, design and rigcd.

Oracles: a rigcd+ prediction is K x RigCD under its own weights (see tests/metrics/test_rigcd_plus_metric.py),
so every rigcd+ number the commands print can be recomputed from the shipped weights file; the default
stays the published RigCD (its predictions equal the rigcd weights' formula on unit-matching features).
"""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from in_process import run_rigopt
from rigopt.cli.app import app
from rigopt.metrics.calibration import load_weights
from rigopt.metrics.ranking import predict_transfer
from rigopt.rig.library import load_rig

runner = CliRunner()
CANDIDATES = ["R1-f", "R2", "R5", "R9", "R1-c6"]


def invoke_json(*args):
    result = runner.invoke(app, list(args))
    assert result.exit_code == 0, (result.output, result.exception)
    return json.loads(result.stdout)


def test_rank_with_rigcd_plus_uses_the_rigcd_plus_weights():
    ranked = invoke_json("rank", *CANDIDATES, "--ref", "R1", "--metric", "rigcd+", "--json")
    plus = load_weights("joint", "rigcd+")
    assert sorted(p["rig"] for p in ranked) == sorted(CANDIDATES)
    drops = [p["predicted_drop"] for p in ranked]
    assert drops == sorted(drops)
    for p in ranked:
        assert p["linear_drop"] == pytest.approx(plus.K * p["rigcd"], rel=1e-9)
        assert p["predicted_drop"] == pytest.approx(float(plus.link(p["linear_drop"])), rel=1e-9)
    default = invoke_json("rank", *CANDIDATES, "--ref", "R1", "--predictor", "rigcd", "--json")
    expected = {p.rig: p.predicted_drop for p in predict_transfer(load_rig("R1"), [load_rig(c) for c in CANDIDATES],
                                                                  load_weights("joint"))}
    assert {p["rig"]: p["predicted_drop"] for p in default} == pytest.approx(expected, rel=1e-12)
    assert {p["rig"]: p["predicted_drop"] for p in default} != pytest.approx(
        {p["rig"]: p["predicted_drop"] for p in ranked}, rel=1e-6)


@pytest.mark.slow
def test_calibrate_with_rigcd_plus_writes_rigcd_plus_weights(tmp_path):
    from rigopt.resources import data_dir

    report = invoke_json("calibrate", "--results", str(data_dir("metrics") / "pccr_transfer.csv"), "--metric",
                         "rigcd+", "--bootstrap", "0", "--out", str(tmp_path), "--json")
    assert report["metric"] == "rigcd+"
    written = load_weights(tmp_path / "weights" / "joint.json", "rigcd+")
    shipped = load_weights("joint", "rigcd+")
    assert written.lambdas == pytest.approx(shipped.lambdas, abs=1e-9) and written.K == pytest.approx(shipped.K)
    assert report["joint"]["weights"]["K"] == pytest.approx(shipped.K)


def test_rigcd_command_with_rigcd_plus_needs_weights_and_reports_its_drop():
    result = run_rigopt("rigcd", "R1", "R5", "--metric", "rigcd+")
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert "rigopt: error:" in result.stderr and "--weights" in result.stderr
    data = invoke_json("rigcd", "R1", "R5", "--metric", "rigcd+", "--weights", "PETR", "--json")
    assert data["linear_drop"] == pytest.approx(load_weights("PETR", "rigcd+").K * data["rigcd"], rel=1e-9)


def test_unknown_metric_is_a_one_line_error():
    result = run_rigopt("rank", "R5", "--ref", "R1", "--metric", "rigcd2")
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert "rigcd2" in result.stderr and "rigcd+" in result.stderr


@pytest.mark.slow
def test_design_with_rigcd_plus_minimises_and_reports_rigcd_plus(tmp_path):
    out = tmp_path / "design"
    summary = invoke_json("design", "--vehicle", "tt", "--ref", "R5", "--metric", "rigcd+", "--yaw-step", "30",
                          "--pitch", "0", "--fov", "90,120", "--pose", "free", "--json", "--out", str(out))
    plus = load_weights("joint", "rigcd+")
    assert summary["metric"] == "rigcd+" and summary["weights"] == "joint"
    assert summary["predicted_drop"] == pytest.approx(float(plus.link(plus.K * summary["rigcd"])), rel=1e-9)
    design = load_rig(out / "rig.json")
    assert predict_transfer(load_rig("R5"), [design.perception()], plus)[0].predicted_drop == pytest.approx(
        summary["predicted_drop"], rel=1e-9)
    assert json.loads((out / "report.json").read_text())["metric"] == "rigcd+"
    # on this coarse grid (yaws every 30 deg, level cameras, two lenses) no 4 cameras in mirrored pairs cover
    # what R5 covers: the design falls back to free placement and says so
    symmetry = summary["symmetry"]
    assert symmetry["required"] is False
    assert "no symmetric design meets the requirements" in symmetry["fallback"]
    assert symmetry["describe"] == symmetry["fallback"]
