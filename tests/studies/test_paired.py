"""Studies measured per (vehicle, scene set): the vehicle-level mean of paired differences with its intervals, and
the resumable cells (a cell measured once; the analysis waits for every cell)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))  # the studies' shared code
from studylib.paired import run_cells, vehicle_draws, vehicle_mean  # noqa: E402


def test_the_vehicle_mean_and_its_intervals_by_hand():
    paired = [{"difference": -0.1, "ci": [-0.2, 0.0]}, {"difference": 0.3, "ci": [0.1, 0.5]}]
    draws = np.array([[0, 0], [0, 1], [1, 1], [1, 0]])  # means -0.1, 0.1, 0.3, 0.1
    out = vehicle_mean(paired, ["a", "b"], draws, level=0.5)
    assert out["per_vehicle"] == {"a": -0.1, "b": 0.3} and out["mean"] == pytest.approx(0.1)
    assert out["ci95"] == pytest.approx([np.percentile([-0.1, 0.1, 0.3, 0.1], 2.5),
                                         np.percentile([-0.1, 0.1, 0.3, 0.1], 97.5)])
    assert out["ci_bonferroni"] == pytest.approx([np.percentile([-0.1, 0.1, 0.3, 0.1], 25),
                                                  np.percentile([-0.1, 0.1, 0.3, 0.1], 75)])
    assert out["vehicles_wholly_above_0"] == ["b"]
    assert vehicle_draws(3, 5, 0).shape == (5, 3) and np.array_equal(vehicle_draws(3, 5, 0), vehicle_draws(3, 5, 0))


def test_cells_are_measured_once_and_the_analysis_waits_for_all(tmp_path, capsys):
    calls = []

    def measure_cell(vehicle, protocol, cache, workers, progress):
        calls.append((vehicle, protocol))
        return {"vehicle": vehicle, "protocol": protocol}

    def analyse(found):
        return {"cells": sorted(f"{v}/{p}" for v, p in found)}

    def report(found, result):
        return f"{len(result['cells'])} cells\n"

    (tmp_path / "b_quick.json").write_text(json.dumps({"vehicle": "b", "protocol": "quick"}))  # measured before
    assert run_cells(["--analyse-only"], "test", tmp_path, ["a", "b"], ["quick"], measure_cell, analyse, report) == 0
    assert calls == [] and not (tmp_path / "results.json").exists()  # one cell missing: no analysis
    assert run_cells([], "test", tmp_path, ["a", "b"], ["quick"], measure_cell, analyse, report) == 0
    assert calls == [("a", "quick")]
    assert json.loads((tmp_path / "results.json").read_text()) == {"cells": ["a/quick", "b/quick"]}
    assert (tmp_path / "results.md").read_text() == "2 cells\n"
