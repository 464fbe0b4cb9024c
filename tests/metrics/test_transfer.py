"""Measured transfer: the results folder and the shipped CSV, relative drops, and bad input.

Expected values come from the benchmark's JSON files parsed here with ``json`` and from hand-made tables.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from rigopt.errors import DataError
from rigopt.metrics.transfer import TransferTable, read_transfer

REPO = Path(__file__).resolve().parents[2]
SHIPPED_CSV = REPO / "metrics" / "pccr_transfer.csv"
RESULTS = Path(__file__).resolve().parents[3] / "shared" / "pccr" / "results"  # beside the checkout
MODELS = ("BEVDet", "BEVFusion", "Fast-BEV", "PETR")

needs_results = pytest.mark.skipif(not RESULTS.is_dir(), reason="the benchmark's results folder is not here")


def json_maps(root: Path = RESULTS) -> dict[tuple[str, str, str], float]:
    """(model, train, test) -> mAP straight from the benchmark's JSON files."""
    out = {}
    for file in root.glob("*/trained_on_*.json"):
        data = json.loads(file.read_text())
        train = file.stem[len("trained_on_"):]
        for test, entry in data["results"].items():
            out[(file.parent.name, train, test)] = entry["metrics"]["mAP"]
    return out


def table_maps(table: TransferTable) -> dict[tuple[str, str, str], float]:
    rows = {(m, a, b): float(v) for m, a, b, v in zip(table.model, table.train, table.test, table.map)}
    assert len(rows) == len(table.map), "the table holds a pair twice"
    return rows


def write_results(root: Path, results: dict) -> Path:
    """A results folder: results = {model: {train: {test: mAP or raw metrics entry}}}."""
    for model, trains in results.items():
        (root / model).mkdir(parents=True, exist_ok=True)
        for train, tests in trains.items():
            body = {"model": model, "trained_on": train,
                    "results": {test: {"metrics": {"mAP": value, "NDS": None}} for test, value in tests.items()}}
            (root / model / f"trained_on_{train}.json").write_text(json.dumps(body))
    return root


def write_csv(path: Path, lines: list[str]) -> Path:
    path.write_text("\n".join(lines) + "\n")
    return path


GOOD = {"M": {"A": {"A": 0.5, "B": 0.25}, "B": {"B": 0.4, "A": 0.1}}}


# --- the real data --------------------------------------------------------------------------------


@needs_results
def test_results_folder_and_shipped_csv_give_the_same_table():
    folder = table_maps(read_transfer(RESULTS))
    shipped = table_maps(read_transfer(SHIPPED_CSV))
    assert folder.keys() == shipped.keys()
    assert all(folder[key] == shipped[key] for key in folder)


@needs_results
def test_results_folder_reads_every_json_value():
    assert table_maps(read_transfer(RESULTS)) == json_maps()


def test_shipped_csv_has_four_models_on_14_by_14_rigs():
    table = read_transfer(SHIPPED_CSV)
    assert set(table.models()) == set(MODELS)
    assert len(table.rigs()) == 14
    assert len(table.map) == 4 * 14 * 14


@needs_results
@pytest.mark.parametrize("model, a, b", [("BEVDet", "R1", "R6"), ("PETR", "R1-c10", "R1-f"),
                                          ("Fast-BEV", "R9", "R2"), ("BEVFusion", "R4", "R1-t")])
def test_drops_equal_the_relative_drop_from_the_json_files(model, a, b):
    maps = json_maps()
    expected = (maps[(model, a, a)] - maps[(model, a, b)]) / maps[(model, a, a)]
    drops = read_transfer(RESULTS).drops()
    row = np.flatnonzero((drops.model == model) & (drops.train == a) & (drops.test == b))
    assert len(row) == 1
    assert drops.delta[row[0]] == expected


def test_diagonal_drop_is_zero():
    drops = read_transfer(SHIPPED_CSV).drops()
    diagonal = drops.train == drops.test
    assert diagonal.sum() == 4 * 14
    assert np.all(drops.delta[diagonal] == 0.0)


def test_every_pair_of_the_shipped_data_has_a_drop():
    drops = read_transfer(SHIPPED_CSV).drops()
    assert len(drops.delta) == 4 * 14 * 14
    assert drops.skipped == ()


def test_training_rig_with_zero_own_map_is_skipped(tmp_path):
    path = write_csv(tmp_path / "t.csv", ["model,train_rig,test_rig,mAP",
                                          "M,A,A,0.0", "M,A,B,0.1", "M,B,B,0.5", "M,B,A,0.25"])
    drops = read_transfer(path).drops()
    assert drops.skipped == (("M", "A"),)
    assert set(drops.train.tolist()) == {"B"}
    got = dict(zip(drops.test.tolist(), drops.delta.tolist()))
    assert got == {"B": 0.0, "A": 0.5}


def test_null_map_is_treated_as_missing(tmp_path):
    root = write_results(tmp_path / "res", {"M": {"A": {"A": 0.5, "B": None}}})
    table = read_transfer(root)
    assert table_maps(table) == {("M", "A", "A"): 0.5}


def test_csv_round_trip(tmp_path):
    table = read_transfer(SHIPPED_CSV)
    again = read_transfer(table.write_csv(tmp_path / "copy.csv"))
    assert table_maps(again) == table_maps(table)


# --- bad input: DataError naming the file -------------------------------------------------------------


def assert_data_error_naming(path, names):
    with pytest.raises(DataError) as info:
        read_transfer(path)
    assert str(names) in str(info.value)
    return str(info.value)


def test_malformed_json_names_the_file(tmp_path):
    root = write_results(tmp_path / "res", GOOD)
    bad = root / "M" / "trained_on_A.json"
    bad.write_text('{"results": {"A": ')
    assert_data_error_naming(root, bad)


def test_missing_results_object_names_the_file(tmp_path):
    root = write_results(tmp_path / "res", GOOD)
    bad = root / "M" / "trained_on_B.json"
    bad.write_text(json.dumps({"model": "M", "trained_on": "B"}))
    message = assert_data_error_naming(root, bad)
    assert "results" in message


def test_test_entry_without_map_names_the_file(tmp_path):
    root = write_results(tmp_path / "res", GOOD)
    bad = root / "M" / "trained_on_A.json"
    bad.write_text(json.dumps({"results": {"A": {"metrics": {"mAP": 0.5}}, "B": {"metrics": {"NDS": 0.3}}}}))
    message = assert_data_error_naming(root, bad)
    assert "'B'" in message


def test_test_entry_without_metrics_names_the_file(tmp_path):
    root = write_results(tmp_path / "res", GOOD)
    bad = root / "M" / "trained_on_A.json"
    bad.write_text(json.dumps({"results": {"A": {"metrics": {"mAP": 0.5}}, "B": 0.3}}))
    assert_data_error_naming(root, bad)


@pytest.mark.parametrize("value", [float("nan"), 1.5, -0.1, "n/a", float("inf"), True])
def test_bad_map_value_in_json_names_the_file(tmp_path, value):
    results = {"M": {"A": {"A": 0.5, "B": value}, "B": {"B": 0.4}}}
    root = write_results(tmp_path / "res", results)
    assert_data_error_naming(root, root / "M" / "trained_on_A.json")


def test_numeric_string_map_in_json_is_rejected(tmp_path):
    results = {"M": {"A": {"A": 0.5, "B": "0.25"}, "B": {"B": 0.4}}}
    root = write_results(tmp_path / "res", results)
    assert_data_error_naming(root, root / "M" / "trained_on_A.json")


@pytest.mark.parametrize("value", ["nan", "1.5", "abc", "-0.2"])
def test_bad_map_value_in_csv_names_the_file_and_line(tmp_path, value):
    path = write_csv(tmp_path / "t.csv", ["model,train_rig,test_rig,mAP", "M,A,A,0.5", f"M,A,B,{value}"])
    message = assert_data_error_naming(path, path)
    assert "line 3" in message


def test_csv_with_wrong_header_names_the_file(tmp_path):
    path = write_csv(tmp_path / "t.csv", ["model,train,test,map", "M,A,A,0.5"])
    assert_data_error_naming(path, path)


def test_csv_row_with_three_fields_names_the_file_and_line(tmp_path):
    path = write_csv(tmp_path / "t.csv", ["model,train_rig,test_rig,mAP", "M,A,A,0.5", "M,A,0.3"])
    message = assert_data_error_naming(path, path)
    assert "line 3" in message


def test_csv_duplicated_pair_names_the_file(tmp_path):
    path = write_csv(tmp_path / "t.csv", ["model,train_rig,test_rig,mAP", "M,A,A,0.5", "M,A,B,0.3", "M,A,B,0.3"])
    message = assert_data_error_naming(path, path)
    assert "twice" in message


def test_empty_folder_names_the_folder(tmp_path):
    (tmp_path / "empty").mkdir()
    assert_data_error_naming(tmp_path / "empty", tmp_path / "empty")


def test_empty_csv_names_the_file(tmp_path):
    path = write_csv(tmp_path / "t.csv", ["model,train_rig,test_rig,mAP"])
    assert_data_error_naming(path, path)


def test_nonexistent_path_names_the_path(tmp_path):
    assert_data_error_naming(tmp_path / "nowhere", tmp_path / "nowhere")


def test_results_folder_without_diagonal_names_the_file(tmp_path):
    root = write_results(tmp_path / "res", {"M": {"A": {"A": 0.5, "B": 0.2}, "B": {"A": 0.1, "C": 0.3}}})
    message = assert_data_error_naming(root, root / "M" / "trained_on_B.json")
    assert "diagonal" in message


def test_csv_without_diagonal_names_the_file(tmp_path):
    path = write_csv(tmp_path / "t.csv", ["model,train_rig,test_rig,mAP", "M,A,B,0.3"])
    assert_data_error_naming(path, path)


def test_csv_reader_ignores_surrounding_spaces(tmp_path):
    path = write_csv(tmp_path / "t.csv", ["model, train_rig, test_rig, mAP", "M, A, A, 0.5", "M, A, B, 0.125"])
    rows = table_maps(read_transfer(path))
    assert rows == {("M", "A", "A"): 0.5, ("M", "A", "B"): 0.125}


def test_csv_layout_written_by_hand_is_read(tmp_path):
    path = tmp_path / "t.csv"
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["model", "train_rig", "test_rig", "mAP"])
        writer.writerows([["X", "R1", "R1", "0.4"], ["X", "R1", "R6", "0.1"]])
    drops = read_transfer(path).drops()
    assert dict(zip(drops.test.tolist(), drops.delta.tolist())) == {"R1": 0.0, "R6": (0.4 - 0.1) / 0.4}
