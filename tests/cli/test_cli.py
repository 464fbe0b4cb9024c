"""The ``rigopt`` command line: JSON shapes and values, files written, and one-line errors on bad input.

Normal output goes through typer's CliRunner; exit codes and stderr of bad input through the console
script's error handling, in-process (tests/console.py).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from in_process import run_rigopt
from oracles.metrics import rigcd_reference
from rigopt.cli.app import app
from rigopt.metrics.rigcd import rigcd_matrix
from rigopt.rig.library import load_rig

REPO = Path(__file__).resolve().parents[2]
SHIPPED_CSV = REPO / "metrics" / "pccr_transfer.csv"
WEIGHTS_DIR = REPO / "metrics" / "weights"
BENCHMARK_RIGS = REPO.parent / "shared" / "pccr" / "rigs"  # the shared data beside the checkout
MODELS = {"BEVDet", "BEVFusion", "Fast-BEV", "PETR"}

runner = CliRunner()


def invoke_json(*args):
    result = runner.invoke(app, list(args))
    assert result.exit_code == 0, (result.output, result.exception)
    return json.loads(result.stdout)


def shipped_weights(name: str) -> dict:
    return json.loads((WEIGHTS_DIR / f"{name}.json").read_text())


def formula(w: dict, t, r, f, count) -> float:
    return w["K"] * (w["alpha"] * (w["lambda_t"] * t + w["lambda_r"] * r + w["lambda_f"] * f)
                     + (1 - w["alpha"]) * count)


def bounded(w: dict, linear: float) -> float:
    """The weights file's link applied to a linear prediction, written out here from its definition."""
    if "link" not in w:
        return linear
    kind, parameters = w["link"]["kind"], w["link"]["parameters"]
    if kind == "exp":
        return 1.0 - math.exp(-parameters[0] * linear)
    b, c = parameters
    return (linear / c) ** b / (1.0 + (linear / c) ** b)


# --- rigs, rigv, rigcd, rank ------------------------------------------------------------------------


def test_rigs_lists_the_14_benchmark_rigs():
    rows = invoke_json("rigs", "--json")
    assert len(rows) == 14
    assert len({r["rig"] for r in rows}) == 14


@pytest.mark.skipif(not BENCHMARK_RIGS.is_dir(), reason="the benchmark's rig files are not here")
def test_rigs_camera_counts_and_vehicles_match_the_benchmark_files():
    rows = {r["rig"]: r for r in invoke_json("rigs", "--json")}
    files = {p.stem: json.loads(p.read_text()) for p in BENCHMARK_RIGS.glob("*.json")}
    assert rows.keys() == files.keys()
    for name, data in files.items():
        assert rows[name]["cameras"] == len(data["cameras"]), name
        assert rows[name]["vehicle"] == data["vehicle_type"], name
        assert rows[name]["fovs"] == sorted({float(c["fov"]) for c in data["cameras"]}), name


def test_rigs_table_output_names_every_rig():
    result = runner.invoke(app, ["rigs"])
    assert result.exit_code == 0
    for name in ("R1-c10", "R9", "R5"):
        assert name in result.stdout


def test_rigv_json_keys():
    rows = invoke_json("rigv", "R1", "--json")
    assert len(rows) == 1
    assert set(rows[0]) == {"rig", "rigv", "tv", "rv", "fv", "tv_norm", "rv_norm", "fv_norm", "dmax"}
    assert rows[0]["rig"] == "R1"


def test_rigv_json_values_by_hand():
    rig = load_rig("R5")
    row = invoke_json("rigv", "R5", "--json")[0]
    i, j = np.triu_indices(len(rig), k=1)
    dist = np.linalg.norm(rig.positions[i] - rig.positions[j], axis=1)
    fv = np.mean(np.abs(rig.fovs[i] - rig.fovs[j]))
    assert row["tv"] == pytest.approx(dist.mean(), abs=1e-9)
    assert row["dmax"] == pytest.approx(dist.max(), abs=1e-9)
    assert row["fv"] == pytest.approx(fv, abs=1e-9)


def test_rigv_with_weights_uses_their_lambdas():
    plain = invoke_json("rigv", "R3", "--json")[0]
    weighted = invoke_json("rigv", "R3", "--weights", "PETR", "--json")[0]
    w = shipped_weights("PETR")
    expected = w["lambda_t"] * plain["tv_norm"] + w["lambda_r"] * plain["rv_norm"] + w["lambda_f"] * plain["fv_norm"]
    assert weighted["rigv"] == pytest.approx(expected, rel=1e-12)


def test_rigcd_json_keys_and_the_joint_drop_without_weights():
    # from R3, a reference no shipped drop model was fitted from, the default prediction is RigCD's (joint)
    data = invoke_json("rigcd", "R3", "R6", "--json")
    assert set(data) == {"a", "b", "rigcd", "match", "count", "t", "r", "f", "predicted_drop", "interval",
                         "interval_informative", "linear_drop", "extrapolation", "fallback", "weights",
                         "origin_changes", "near_field_left_out", "predictor", "view_overlap", "low_view_overlap"}
    assert (data["a"], data["b"], data["predictor"]) == ("R3", "R6", "RigCD (joint)")
    w = shipped_weights("joint")
    assert data["weights"] == "joint (default)" and data["fallback"] is False
    assert data["linear_drop"] == pytest.approx(formula(w, data["t"], data["r"], data["f"], data["count"]), rel=1e-12)
    assert 0.0 <= data["predicted_drop"] <= 1.0
    assert data["origin_changes"] == []  # both benchmark rigs: measured from the vehicle centre


def test_a_pair_beyond_the_calibration_pairs_is_flagged_with_its_terms_and_one_inside_is_not():
    far = invoke_json("rigcd", "R1", "R6", "--predictor", "rigcd", "--json")  # RigCD's calibration domain
    w = shipped_weights("joint")
    control_t = max(point[0] for point in w["domain"]["points"])
    assert [t["term"] for t in far["extrapolation"]["terms"]] == ["t"]  # the fire truck's cameras, metres away
    assert far["extrapolation"]["terms"][0]["beyond"] == pytest.approx(far["t"] - control_t)
    low, high = far["interval"]
    assert low <= far["predicted_drop"] <= high and high - low > 0
    near = invoke_json("rigcd", "R1", "R1-r", "--predictor", "rigcd", "--json")  # a calibration pair itself
    assert near["extrapolation"] is None


def test_rigcd_json_values_equal_the_reference():
    data = invoke_json("rigcd", "R1", "R6", "--json")
    ref = rigcd_reference(load_rig("R1"), load_rig("R6"))
    for key in ("rigcd", "match", "count", "t", "r", "f"):
        assert data[key] == pytest.approx(ref[key], abs=1e-9), key
    assert data["count"] == pytest.approx(abs(8 - 9) / 9)


@pytest.mark.parametrize("weights", ["joint", "JOINT", "PETR"])
def test_rigcd_predicted_drop_with_weights(weights):
    data = invoke_json("rigcd", "R1", "R6", "--weights", weights, "--json")
    w = shipped_weights("joint" if weights.lower() == "joint" else weights)
    linear = formula(w, data["t"], data["r"], data["f"], data["count"])
    assert data["linear_drop"] == pytest.approx(linear, rel=1e-12)
    assert data["predicted_drop"] == pytest.approx(bounded(w, linear), rel=1e-9)
    assert data["interval"] == pytest.approx([data["predicted_drop"] - w["interval"]["halfwidth"],
                                              min(1.0, data["predicted_drop"] + w["interval"]["halfwidth"])])


def test_rigcd_with_weights_uses_their_alpha_and_lambdas():
    data = invoke_json("rigcd", "R1", "R6", "--weights", "joint", "--json")
    w = shipped_weights("joint")
    m = rigcd_matrix([load_rig("R1")], [load_rig("R6")], w["alpha"], (w["lambda_t"], w["lambda_r"], w["lambda_f"]))
    assert data["rigcd"] == pytest.approx(float(m.rigcd[0, 0]), rel=1e-12)
    assert data["match"] == pytest.approx(float(m.match[0, 0]), rel=1e-12)
    plain = invoke_json("rigcd", "R1", "R6", "--json")
    assert data["rigcd"] != pytest.approx(plain["rigcd"])


def test_rigcd_with_a_weights_file(tmp_path):
    path = tmp_path / "w.json"
    path.write_text(json.dumps({"K": 2.0, "alpha": 0.5, "lambda_t": 1.0, "lambda_r": 0.0, "lambda_f": 0.0}))
    data = invoke_json("rigcd", "R1", "R1-c6", "--weights", str(path), "--json")
    # 2 (0.5 t + 0.5 count), count = (8 - 6) / 8; a file without a link predicts linearly, with no interval
    assert data["predicted_drop"] == pytest.approx(2.0 * (0.5 * data["t"] + 0.5 * 0.25), rel=1e-12)
    assert data["interval"] is None and data["extrapolation"] is None


def test_rigcd_of_a_rig_file(tmp_path):
    from rigopt.rig.pccr_format import write_rig

    path = write_rig(load_rig("R4"), tmp_path / "mine.json")
    data = invoke_json("rigcd", str(path), "R4", "--json")
    assert data["rigcd"] == pytest.approx(0.0, abs=1e-9)
    assert data["a"] == "mine"


def test_rank_json_is_sorted_with_documented_keys():
    rows = invoke_json("rank", "--ref", "R1", "R6", "R4", "R1-f", "--json")
    assert [set(r) for r in rows] == [{"reference", "rig", "predicted_drop", "interval", "interval_informative",
                                       "linear_drop", "rigcd", "match", "t", "r", "f", "count", "extrapolation",
                                       "fallback", "near_field_left_out", "predictor", "view_overlap",
                                       "low_view_overlap"}] * 3
    assert sorted(r["rig"] for r in rows) == ["R1-f", "R4", "R6"]
    drops = [r["predicted_drop"] for r in rows]
    assert drops == sorted(drops)


def test_rank_uses_joint_weights_by_default_from_a_reference_no_drop_model_was_fitted_from():
    rows = invoke_json("rank", "--ref", "R3", "R6", "R4", "R1-f", "--json")
    w = shipped_weights("joint")
    for r in rows:
        assert r["linear_drop"] == pytest.approx(formula(w, r["t"], r["r"], r["f"], r["count"]), rel=1e-12)
        assert r["predicted_drop"] == pytest.approx(bounded(w, r["linear_drop"]), rel=1e-9)


def test_rank_table_output():
    result = runner.invoke(app, ["rank", "--ref", "R1", "R6", "R1-t"])
    assert result.exit_code == 0
    assert "R6" in result.stdout and "R1-t" in result.stdout


# --- calibrate ---------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def calibrate_report():
    return invoke_json("calibrate", "--results", str(SHIPPED_CSV), "--json", "--bootstrap", "50")


def test_calibrate_json_shape(calibrate_report):
    report = calibrate_report
    assert set(report) >= {"models", "joint"}
    assert set(report["models"]) == MODELS
    for entry in report["models"].values():
        assert set(entry) == {"weights", "link", "control", "heldout", "bounded", "knockout"}
        assert entry["link"]["kind"] in ("exp", "hill") and set(entry["link"]["loro_mae"]) == {"exp", "hill"}
        assert entry["link"]["loro_mae"][entry["link"]["kind"]] == min(entry["link"]["loro_mae"].values())
        for split in ("control", "heldout"):
            assert set(entry["bounded"][split]) == {"mae", "rmse", "interval_coverage", "n"}
            assert 0.0 <= entry["bounded"][split]["interval_coverage"] <= 1.0
        assert set(entry["knockout"]) == {"full", "lambda_t", "lambda_r", "lambda_f", "count"}
        for split in ("control", "heldout"):
            assert set(entry[split]) == {"rho", "p", "ci", "rig_ci", "mae", "rmse", "n"}
            for interval in (entry[split]["ci"], entry[split]["rig_ci"]):
                assert len(interval) == 2 and -1.0 <= interval[0] <= interval[1] <= 1.0
    assert set(report["joint"]) == {"weights", "link", "models"}
    assert set(report["joint"]["models"]) == MODELS
    assert all(set(entry) == {"control", "heldout", "bounded"} for entry in report["joint"]["models"].values())


def test_calibrate_json_split_sizes(calibrate_report):
    for entry in calibrate_report["models"].values():
        assert (entry["control"]["n"], entry["heldout"]["n"], entry["weights"]["n"]) == (36, 160, 36)
    assert calibrate_report["joint"]["weights"]["n"] == 144


def test_calibrate_qp_agrees_everywhere(calibrate_report):
    fits = [e["weights"] for e in calibrate_report["models"].values()] + [calibrate_report["joint"]["weights"]]
    assert all(w["qp_agrees"] is True for w in fits)


def test_calibrate_weights_equal_the_shipped_files(calibrate_report):
    fits = {**{m: e["weights"] for m, e in calibrate_report["models"].items()},
            "joint": calibrate_report["joint"]["weights"]}
    for name, w in fits.items():
        shipped = shipped_weights(name)
        for key in ("K", "alpha", "lambda_t", "lambda_r", "lambda_f", "fallback"):
            assert w[key] == pytest.approx(shipped[key], abs=1e-9), (name, key)


@pytest.fixture(scope="module")
def calibrate_out(tmp_path_factory):
    pytest.importorskip("rigopt.report.calibration_figures")
    out = tmp_path_factory.mktemp("calibrate") / "out"
    result = runner.invoke(app, ["calibrate", "--results", str(SHIPPED_CSV), "--bootstrap", "50", "--out", str(out)])
    assert result.exit_code == 0, (result.output, result.exception)
    return out


@pytest.mark.slow
def test_calibrate_out_writes_the_report(calibrate_out, calibrate_report):
    report = json.loads((calibrate_out / "calibration.json").read_text())
    assert report == calibrate_report  # same data, same seed, same bootstrap


@pytest.mark.slow
def test_calibrate_out_writes_the_pairs_table(calibrate_out):
    lines = (calibrate_out / "pairs.csv").read_text().splitlines()
    assert len(lines) == 1 + 2 * 4 * 196  # header, every model's own fit, then the joint fit
    header = lines[0].split(",")
    assert header[:5] == ["fit", "model", "train_rig", "test_rig", "split"]
    fits = [line.split(",")[0] for line in lines[1:]]
    assert fits.count("joint") == 4 * 196


@pytest.mark.slow
def test_calibrate_out_writes_weights_that_load_back(calibrate_out):
    from rigopt.metrics.calibration import load_weights

    assert {p.name for p in (calibrate_out / "weights").iterdir()} == {f"{m}.json" for m in MODELS} | {"joint.json"}
    for name in (*MODELS, "joint"):
        mine, shipped = load_weights(calibrate_out / "weights" / f"{name}.json"), load_weights(name)
        assert (mine.K, mine.alpha, *mine.lambdas) == pytest.approx((shipped.K, shipped.alpha, *shipped.lambdas),
                                                                    abs=1e-9)


@pytest.mark.slow
def test_calibrate_out_writes_png_figures(calibrate_out):
    pngs = sorted(calibrate_out.glob("*.png"))
    assert len(pngs) >= 2
    assert all(p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for p in pngs)


def test_calibrate_control_option(tmp_path):
    report = invoke_json("calibrate", "--results", str(SHIPPED_CSV), "--json", "--bootstrap", "0",
                         "--control", "R1, R1-f,R1-r")
    assert report["control_rigs"] == ["R1", "R1-f", "R1-r"]
    assert all(e["control"]["n"] == 9 and e["heldout"]["n"] == 187 for e in report["models"].values())


def test_calibrate_table_output():
    result = runner.invoke(app, ["calibrate", "--results", str(SHIPPED_CSV), "--bootstrap", "0"])
    assert result.exit_code == 0
    for model in MODELS:
        assert model in result.stdout


# --- import nuscenes ---------------------------------------------------------------------------------


def test_import_nuscenes_round_trip(tmp_path):
    from rigopt.rig.formats.nuscenes import write_nuscenes_calibration

    r1 = load_rig("R1")
    tables = write_nuscenes_calibration(r1, tmp_path / "tables")
    out = tmp_path / "imported.json"
    result = runner.invoke(app, ["import", "nuscenes", str(tables), "--out", str(out), "--image-size", "1280x720"])
    assert result.exit_code == 0, (result.output, result.exception)
    back = load_rig(out)
    assert [c.id for c in back.cameras] == [c.id for c in r1.cameras]
    assert np.allclose(back.positions, r1.positions, atol=1e-6)
    assert np.allclose(back.rotations, r1.rotations, atol=1e-6)
    assert np.allclose(back.fovs, r1.fovs, atol=1e-6)


# --- bad input: exit 2, one line on stderr ------------------------------------------------------------


def run_cli(*args, cwd=None):
    return run_rigopt(*args, cwd=cwd)


def assert_one_line_error(result, *fragments):
    assert result.returncode == 2, (result.stdout, result.stderr)
    assert "Traceback" not in result.stderr
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("rigopt: error: ")
    for fragment in fragments:
        assert str(fragment) in lines[0]
    return lines[0]


def rig_file(tmp_path, content) -> Path:
    path = tmp_path / "rig.json"
    path.write_text(content if isinstance(content, str) else json.dumps(content))
    return path


def test_unknown_rig_name(tmp_path):
    line = assert_one_line_error(run_cli("rigcd", "R1", "R99", cwd=tmp_path), "R99")
    assert "R1-c10" in line  # lists the valid names


def test_malformed_rig_json(tmp_path):
    path = rig_file(tmp_path, '{"vehicle_type": "x", "cameras": [')
    assert_one_line_error(run_cli("rigv", path), path)


def test_nan_in_a_rig(tmp_path):
    path = rig_file(tmp_path, '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, NaN, 1], '
                              '"rotation": [0, 0, 0], "fov": 60}]}')
    assert_one_line_error(run_cli("rigv", path), path)


def test_rig_with_empty_cameras(tmp_path):
    path = rig_file(tmp_path, {"vehicle_type": "v", "cameras": []})
    assert_one_line_error(run_cli("rigcd", path, "R1"), path)


def test_unknown_weights_name(tmp_path):
    line = assert_one_line_error(run_cli("rigcd", "R1", "R6", "--weights", "YOLO", cwd=tmp_path), "YOLO")
    assert "joint" in line


def test_nonexistent_results_path(tmp_path):
    missing = tmp_path / "no_results"
    assert_one_line_error(run_cli("calibrate", "--results", missing), missing)


def test_results_folder_without_diagonal(tmp_path):
    root = tmp_path / "results"
    (root / "M").mkdir(parents=True)
    bad = root / "M" / "trained_on_R1.json"
    bad.write_text(json.dumps({"results": {"R6": {"metrics": {"mAP": 0.2}}}}))
    assert_one_line_error(run_cli("calibrate", "--results", root), bad)


def test_bad_image_size(tmp_path):
    from rigopt.rig.formats.nuscenes import write_nuscenes_calibration

    tables = write_nuscenes_calibration(load_rig("R1"), tmp_path / "tables")
    result = run_cli("import", "nuscenes", tables, "--out", tmp_path / "x.json", "--image-size", "1280by720")
    assert_one_line_error(result, "1280by720")
    assert not (tmp_path / "x.json").exists()


def test_a_fallback_calibration_is_marked_where_it_is_used():
    from tests.in_process import run_rigopt

    for args in (("rank", "--ref", "R1", "R4", "--weights", "Fast-BEV"), ("rigcd", "R1", "R4", "--weights", "Fast-BEV")):
        outcome = run_rigopt(*args)
        assert outcome.returncode == 0 and "Fast-BEV calibration is a fallback" in outcome.stderr
    assert "fallback" not in run_rigopt("rank", "--ref", "R1", "R4").stderr
    assert invoke_json("rigcd", "R1", "R4", "--weights", "Fast-BEV", "--json")["fallback"] is True
