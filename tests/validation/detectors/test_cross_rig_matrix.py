"""The cross-rig protocol on the tiny benchmark: train on R1 (8 cameras) and R5 (4 cameras), test each on
both, write the benchmark's results files, read them back as measured transfer, and never redo a row
that is done.

Oracles: the results files themselves (the reader must return exactly their numbers), a direct
``evaluate_on`` of each saved checkpoint (the files must hold its metrics), and file modification times
and bytes (a rerun must leave finished rows and their checkpoints untouched).
"""

from __future__ import annotations

import json
import math

import pytest

torch = pytest.importorskip("torch")

from rigopt.validation.detectors import protocol  # noqa: E402
from rigopt.validation.detectors.config import model_config  # noqa: E402
from rigopt.validation.detectors.models import load_checkpoint  # noqa: E402
from rigopt.validation.detectors.protocol import configured, evaluate_on, transfer_matrix  # noqa: E402
from rigopt.errors import DataError, RigoptError  # noqa: E402
from rigopt.metrics.transfer import read_transfer  # noqa: E402

RIGS = ["R1", "R5"]
PAIRS = {(a, b) for a in RIGS for b in RIGS}


def tiny_one_epoch(family: str = "lss"):
    return configured(model_config(family, "tiny"), 1)


def snapshot(paths) -> dict:
    return {p: (p.stat().st_mtime_ns, p.read_bytes()) for p in paths}


def check_results_files(out, family: str = "lss") -> dict:
    """The results rows of ``out``, checked for the benchmark's layout; {(train, test): mAP}."""
    values = {}
    for rig in RIGS:
        path = out / family / f"trained_on_{rig}.json"
        assert path.is_file(), path
        row = json.loads(path.read_text())
        assert row["model"] == family and row["trained_on"] == rig
        assert set(row["results"]) == set(RIGS)
        assert row["training"]["epochs"] == 1 and row["training"]["config"]["family"] == family
        for test, entry in row["results"].items():
            value = entry["metrics"]["mAP"]
            assert isinstance(value, float) and 0.0 <= value <= 1.0 and math.isfinite(value)
            assert entry["metrics"]["raw"] and all("_AP_dist_" in k for k in entry["metrics"]["raw"])
            values[rig, test] = value
    assert set(values) == PAIRS
    return values


@pytest.fixture(scope="module")
def matrix(tiny_data, tmp_path_factory):
    """One finished lss matrix: (out, runs, returned paths, progress messages)."""
    base = tmp_path_factory.mktemp("matrix")
    out, runs, messages = base / "results", base / "runs", []
    paths = transfer_matrix(tiny_data, RIGS, tiny_one_epoch(), out, runs=runs, progress=messages.append)
    return out, runs, paths, messages


def test_matrix_writes_one_results_file_per_training_rig(matrix):
    out, runs, paths, messages = matrix
    assert paths == [out / "lss" / "trained_on_R1.json", out / "lss" / "trained_on_R5.json"]
    check_results_files(out)
    for rig in RIGS:
        state = load_checkpoint(runs / "lss" / rig / "checkpoint.pt", family="lss")
        assert state["rig"] == rig and state["epoch"] == 1
    assert len(state["channels"]) == 4  # R5's run
    assert sum("done" in m for m in messages) == 2 and sum("1 epochs" in m for m in messages) == 2


def test_results_hold_the_checkpoints_own_metrics(matrix, tiny_data):
    out, runs, _, _ = matrix
    for rig in RIGS:
        row = json.loads((out / "lss" / f"trained_on_{rig}.json").read_text())
        for test in RIGS:  # includes the 8-camera model on the 4-camera rig and the other way round
            metrics = evaluate_on(runs / "lss" / rig / "checkpoint.pt", tiny_data, test, family="lss")
            assert metrics["mAP"] == pytest.approx(row["results"][test]["metrics"]["mAP"], abs=1e-9)
            assert set(metrics["raw"]) == set(row["results"][test]["metrics"]["raw"])


def test_transfer_reader_reads_the_results_folder_back(matrix):
    out, _, _, _ = matrix
    expected = check_results_files(out)
    table = read_transfer(out)
    assert len(table.map) == 4
    assert set(table.model.tolist()) == {"lss"}
    read = {(a, b): float(v) for a, b, v in zip(table.train, table.test, table.map)}
    assert read == expected  # the very numbers of the files
    assert sorted(table.rigs()) == RIGS
    assert table.own_map() == {("lss", r): expected[r, r] for r in RIGS}


@pytest.mark.slow
def test_matrix_in_worker_processes_gives_the_same_results(matrix, tiny_data, tmp_path):
    """Two worker processes: the trainings run in parallel, then each test rig is its own job; the numbers are
    those of the matrix run in order (same seeds, same checkpoints' steps)."""
    out, _, _, _ = matrix
    parallel, messages = tmp_path / "results", []
    paths = transfer_matrix(tiny_data, RIGS, tiny_one_epoch(), parallel, runs=tmp_path / "runs",
                            progress=messages.append, workers=2)
    assert paths == [parallel / "lss" / f"trained_on_{rig}.json" for rig in RIGS]
    assert check_results_files(parallel) == check_results_files(out)
    assert sum("done" in m for m in messages) == 2


def test_rerun_keeps_finished_rows_and_does_not_retrain(matrix, tiny_data, monkeypatch):
    out, runs, paths, _ = matrix
    files = [*paths, *(runs / "lss" / rig / name for rig in RIGS for name in ("checkpoint.pt", "train_log.csv"))]
    before = snapshot(files)

    def no_training(*args, **kwargs):
        raise AssertionError("a finished row was trained again")

    monkeypatch.setattr(protocol, "train_on", no_training)
    messages = []
    again = transfer_matrix(tiny_data, RIGS, tiny_one_epoch(), out, runs=runs, progress=messages.append)
    assert again == paths
    assert snapshot(files) == before
    assert len(messages) == 2 and all("kept" in m for m in messages)


def test_a_lost_results_file_is_rewritten_without_retraining(matrix, tiny_data, tmp_path):
    """Results of R5 lost, its checkpoint kept (the checkpoint's epoch already reaches the asked epochs):
    the row is evaluated again from the same checkpoint and gives the same numbers."""
    out, runs, _, _ = matrix
    copy = tmp_path / "results"
    (copy / "lss").mkdir(parents=True)
    kept = copy / "lss" / "trained_on_R1.json"
    kept.write_bytes((out / "lss" / "trained_on_R1.json").read_bytes())
    checkpoints = [runs / "lss" / rig / "checkpoint.pt" for rig in RIGS]
    before = snapshot([kept, *checkpoints])
    transfer_matrix(tiny_data, RIGS, tiny_one_epoch(), copy, runs=runs)
    assert snapshot([kept, *checkpoints]) == before
    assert check_results_files(copy) == check_results_files(out)


def test_matrix_with_a_missing_rig_fails_before_training(tiny_data, tmp_path):
    with pytest.raises(DataError) as caught:
        transfer_matrix(tiny_data, ["R5", "R9"], tiny_one_epoch(), tmp_path / "out", runs=tmp_path / "runs")
    assert "R9" in str(caught.value) and "R1" in str(caught.value)
    assert not (tmp_path / "runs").exists() and not (tmp_path / "out").exists()


def test_matrix_settings_are_checked(tiny_data, tmp_path):
    with pytest.raises(RigoptError, match="at least one rig"):
        transfer_matrix(tiny_data, [], tiny_one_epoch(), tmp_path / "out")
    with pytest.raises(RigoptError, match="--epochs"):
        configured(model_config("lss", "tiny"), 0)
    assert configured(model_config("lss", "tiny"), None) == model_config("lss", "tiny")


@pytest.mark.slow
def test_matrix_on_ray(tiny_data, tmp_path):
    """The same matrix with each training rig as a task of a local Ray instance."""
    ray = pytest.importorskip("ray")
    if ray.is_initialized():
        pytest.skip("a Ray instance is already running in this process")
    out, runs = tmp_path / "results", tmp_path / "runs"
    messages = []
    try:
        paths = transfer_matrix(tiny_data, RIGS, tiny_one_epoch(), out, runs=runs, ray_address="local",
                                progress=messages.append)
    finally:
        ray.shutdown()
    assert paths == [out / "lss" / f"trained_on_{rig}.json" for rig in RIGS]
    values = check_results_files(out)
    for rig in RIGS:  # the tasks trained in the runs folder given
        assert load_checkpoint(runs / "lss" / rig / "checkpoint.pt")["rig"] == rig
    table = read_transfer(out)
    assert {(a, b): float(v) for a, b, v in zip(table.train, table.test, table.map)} == values
    assert sum("done" in m for m in messages) == 2
