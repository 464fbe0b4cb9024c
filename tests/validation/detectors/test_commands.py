"""The baseline commands end to end on the tiny benchmark: bench train / evaluate / matrix, validate, and
the results layout read by ``rigopt calibrate``; bad input exits 2 with one line."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest
from console import run_console

torch = pytest.importorskip("torch")

from typer.testing import CliRunner  # noqa: E402

from rigopt.validation.detectors.protocol import evaluate_on, write_results  # noqa: E402
from rigopt.cli import INPUT_ERROR, app, run  # noqa: E402

REPO = Path(__file__).resolve().parents[3]
runner = CliRunner()


def invoke(*args):
    result = runner.invoke(app, [str(a) for a in args])
    assert result.exit_code == 0, result.output + repr(result.exception)
    return result.output


def run_cli(capsys, *args) -> tuple[int, str]:
    """(exit code, stderr) of ``rigopt ARGS`` run in-process through the console script's error handling."""
    capsys.readouterr()
    code = run([str(a) for a in args])
    return code, capsys.readouterr().err


def console_script(*args) -> subprocess.CompletedProcess:
    """The installed ``rigopt`` script run in a real process (what a user's shell runs)."""
    return run_console(*args)


@pytest.fixture(scope="module")
def trained(tiny_data, tmp_path_factory):
    """The tiny data with an lss model trained one epoch on R1 by ``rigopt bench train``."""
    data = tmp_path_factory.mktemp("commands") / "data"
    shutil.copytree(tiny_data, data)
    output = invoke("bench", "train", "--data", data, "--rig", "R1", "--model", "lss", "--size", "tiny",
                    "--epochs", "1")
    assert "1/1 epochs" in output
    return data


def test_train_writes_a_checkpoint_and_a_log_and_a_rerun_does_nothing(trained):
    run = trained / "runs" / "lss" / "R1"
    rows = (run / "train_log.csv").read_text().splitlines()
    assert rows[0].startswith("epoch,step,loss") and len(rows) == 1 + 2  # 4 samples, batch 2
    before = (run / "checkpoint.pt").stat().st_mtime_ns
    assert "already trained for 1 epochs" in invoke("bench", "train", "--data", trained, "--rig", "R1", "--model",
                                                     "lss", "--size", "tiny", "--epochs", "1")
    assert (run / "checkpoint.pt").stat().st_mtime_ns == before


@pytest.mark.slow
def test_evaluate_prints_the_metrics_of_the_checkpoint_on_another_rig(trained):
    """--json through the installed console script (stdout JSON only, whatever torch prints); the table in-process."""
    process = console_script("bench", "evaluate", "--data", trained, "--rig", "R5", "--model", "lss",
                             "--trained-on", "R1", "--json")
    assert process.returncode == 0, process.stderr
    metrics = json.loads(process.stdout)
    expected = evaluate_on(trained / "runs" / "lss" / "R1" / "checkpoint.pt", trained, "R5", family="lss")
    assert metrics == json.loads(json.dumps(expected))
    assert len(metrics["raw"]) == len(metrics["raw_visible"]) == 9 * 4
    assert all(metrics[key] is None or 0 <= metrics[key] <= 1 for key in ("mAP", "mAP_visible"))
    table = invoke("bench", "evaluate", "--data", trained, "--rig", "R5", "--model", "lss", "--trained-on", "R1")
    assert "AP@0.5 m" in table and "visible AP@0.5 m" in table and "visible-only mAP" in table and "car" in table


def test_matrix_prints_the_table_and_writes_the_layout(trained, tmp_path):
    output = invoke("bench", "matrix", "--data", trained, "--rigs", "R1", "R5", "--model", "lss", "--size", "tiny",
                    "--epochs", "1", "--out", tmp_path / "results")
    assert "lss trained on R5: done" in output
    # Two tables, fixed-set mAP then visible-only mAP, each with a row per training rig.
    assert [line.split()[1] for line in output.splitlines() if line.startswith("│ R")] == ["R1", "R5"] * 2
    assert "visible-only mAP" in output
    for rig in ("R1", "R5"):
        row = json.loads((tmp_path / "results" / "lss" / f"trained_on_{rig}.json").read_text())
        assert row["trained_on"] == rig and set(row["results"]) == {"R1", "R5"}
        assert all({"mAP", "mAP_visible"} <= set(result["metrics"]) for result in row["results"].values())


def test_calibrate_reads_a_results_folder_the_protocol_writes(tmp_path):
    """Hand-made mAPs for six control rigs and one held-out rig, written by the protocol's writer."""
    control = ["R1", "R1-r", "R1-t", "R1-f", "R1-c6", "R1-c10"]
    rigs = control + ["R2"]
    for a, train in enumerate(rigs):
        results = {test: {"metrics": {"mAP": 0.4 if train == test else 0.4 - 0.03 * ((a * 7 + b * 3) % 9 + 1),
                                      "raw": {}}}
                   for b, test in enumerate(rigs)}
        write_results(tmp_path, {"model": "lss", "trained_on": train, "results": results})
    report = json.loads(invoke("calibrate", "--results", tmp_path, "--bootstrap", "50", "--json"))
    assert sorted(report["control_rigs"]) == sorted(control) and report["skipped"] == []
    fit = report["models"]["lss"]
    assert fit["control"]["n"] == 36 and fit["heldout"]["n"] == 7 * 7 - 36  # pairs among and beyond the control
    assert fit["weights"]["K"] > 0


@pytest.mark.slow
def test_validate_renders_the_design_and_reports_measured_beside_predicted(trained):
    """Through the installed console script: its stdout is JSON only, whatever torch or a C library prints."""
    design = REPO / "measurements" / "rigs" / "firetruck_from_R1.json"
    process = console_script("validate", design, "--ref", "R1", "--model", "lss", "--data", trained, "--json")
    assert process.returncode == 0, process.stderr
    result = json.loads(process.stdout)
    roles = {entry["role"]: entry for entry in result["rigs"]}
    assert set(roles) == {"design", "hand-designed", "naive transfer", "height-matched transfer"}
    assert roles["design"]["rig"] == "firetruck_from_R1" and roles["hand-designed"]["rig"] == "R6"
    for entry in result["rigs"]:
        assert (trained / entry["rig"] / "test" / "v1.0-test" / "sample.json").is_file()
        assert entry["predicted_drop"] is not None and entry["rigcd"] > 0
        assert {"mAP_visible", "measured_drop_visible", "measured_drop_visible_ci"} <= set(entry)
    assert "reference_mAP_visible" in result
    assert result["reference"] == "R1" and result["test_scenes"] == 1 and result["image_size"] == [64, 36]
    by_rig = {entry["rig"]: entry for entry in result["rigs"]}
    assert [e["role"] for e in result["design_minus"]] == ["hand-designed", "naive transfer", "height-matched transfer"]
    for entry in result["design_minus"]:
        design, other = roles["design"]["measured_drop"], by_rig[entry["rig"]]["measured_drop"]
        if None not in (design, other):
            assert entry["difference"] == pytest.approx(design - other)
        low, high = entry["ci"]
        assert low is None or low <= high
    bootstrap = result["bootstrap"]
    assert bootstrap["unit"] == "scene" and bootstrap["blocks"] == 1 and bootstrap["resamples"] == 1000
    for entry in result["rigs"]:  # one test scene: every draw is that scene, so every resampled drop is the drop
        draws = bootstrap["measured_drops"][entry["rig"]]
        assert len(draws) == 1000
        if entry["measured_drop"] is not None:
            assert draws == pytest.approx([entry["measured_drop"]] * 1000, abs=1e-4)


def test_validate_with_data_feeds_the_perception_cameras_and_keeps_the_whole_design_for_the_record(
        trained, tmp_path, capsys, monkeypatch):
    """A design with a near_field fisheye: the detector is fed its perception cameras (the row that stands for
    the design, its predicted drop theirs), the whole design is measured for the record through its lenses, and
    the note says so, as without --data. The comparison rigs are left out (they need the designer)."""
    import dataclasses

    from rigopt.design.near_field import fisheye_190
    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.drop_model import load_drop_model
    from rigopt.metrics.ranking import predict_transfer
    from rigopt.mounting.candidates import rig_body_share
    from rigopt.rig.library import load_rig
    from rigopt.rig.pccr_format import write_rig
    from rigopt.validation import designs
    from rigopt.validation.detectors.data import RigSplit

    monkeypatch.setattr(designs, "comparison_rigs", lambda design, reference, calibration=None: [("design", design)])
    r5 = load_rig("R5")
    fisheye = dataclasses.replace(r5.cameras[0], id="FISHEYE", role="near_field", lens=fisheye_190().lens)
    design = dataclasses.replace(r5, name="fed", cameras=(*r5.cameras, fisheye))
    code, stderr = run_cli(capsys, "validate", write_rig(design, tmp_path / "fed.json"), "--ref", "R1", "--model",
                           "lss", "--data", trained, "--json", "--out", tmp_path / "out.json")
    assert code == 0, stderr
    result = json.loads((tmp_path / "out.json").read_text())
    assert [(e["role"], e["rig"], e["n_cameras"]) for e in result["rigs"]] == [
        ("perception cameras", "fed_perception", 4), ("whole rig", "fed_whole", 5)]
    assert RigSplit(trained, "fed_perception", "test").channels == tuple(sorted(c.id for c in r5.cameras))
    assert "FISHEYE" in RigSplit(trained, "fed_whole", "test").channels
    assert result["design_minus"] == []  # the whole design is not another rig to beat
    assert result["near_field"]["whole_rig"] == {"rig": "fed_whole", "n_cameras": 5, "measured": True, "reason": None}
    model = load_drop_model("lss-R1-v2")  # from R1 the printed prediction is the default shipped drop model's
    perception = predict_transfer(load_rig("R1"), [design.perception()], load_weights("joint", "rigcd"), model,
                                  rig_body_share)[0]
    assert result["rigs"][0]["predicted_drop"] == pytest.approx(perception.predicted_drop)
    assert result["predicted_by"] == "lss-R1-v2 drop model"
    assert ("fed: 1 near_field camera(s) are not fed to the detector: measured on its 4 perception cameras, and "
            "whole (5 cameras) for the record") in stderr


@pytest.mark.parametrize("args, message", [
    (["bench", "train", "--data", "{data}", "--rig", "R1", "--model", "yolo"], "unknown model family 'yolo'"),
    (["bench", "train", "--data", "{data}", "--rig", "R7", "--model", "lss"], "no train split for rig 'R7'"),
    (["bench", "evaluate", "--data", "{data}", "--rig", "R5", "--model", "petr", "--checkpoint",
      "{data}/runs/lss/R1/checkpoint.pt"], "a lss checkpoint, not petr"),
    (["validate", "{design}", "--ref", "R1", "--model", "petr", "--data", "{data}"], "rigopt bench train"),
])
def test_bad_input_exits_2_with_one_line(trained, args, message, capsys):
    design = REPO / "measurements" / "rigs" / "hgv_from_R1.json"
    code, stderr = run_cli(capsys, *[a.format(data=trained, design=design) for a in args])
    assert code == INPUT_ERROR, stderr
    assert message in stderr and "Traceback" not in stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rigopt: error: ")


@pytest.mark.skipif(torch.cuda.is_available(), reason="this machine has CUDA")
def test_cuda_without_cuda_exits_2(trained, capsys):
    code, stderr = run_cli(capsys, "bench", "train", "--data", trained, "--rig", "R1", "--model", "lss",
                           "--device", "cuda")
    assert code == INPUT_ERROR and "no CUDA device" in stderr

