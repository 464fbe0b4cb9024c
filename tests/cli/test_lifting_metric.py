"""A shipped lifting metric (``--metric NAME``, rigopt.metrics.calibration.LIFTING_METRICS) in the commands:
rigcd and rank predict with it, calibrate refuses to refit it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from in_process import run_rigopt
from rigopt.metrics.calibration import LIFTING_METRICS, load_weights
from rigopt.metrics.ranking import predict_transfer
from rigopt.rig.library import load_rig
from rigopt.vehicle.placement import in_vehicle_frame

SHIPPED_CSV = Path(__file__).resolve().parents[2] / "metrics" / "pccr_transfer.csv"


def _centred(name: str):
    return in_vehicle_frame(load_rig(name))[0]


@pytest.mark.parametrize("metric", LIFTING_METRICS)
def test_rigcd_and_rank_predict_with_the_lifting_metric(metric):
    done = run_rigopt("rigcd", "R1", "R6", "--metric", metric, "--json")
    assert done.returncode == 0, done.stderr
    pair = json.loads(done.stdout)
    expected = predict_transfer(_centred("R1"), [_centred("R6")], load_weights("joint", metric))[0]
    assert pair["linear_drop"] == pytest.approx(expected.linear_drop, rel=1e-9)
    assert pair["predicted_drop"] == pytest.approx(np.clip(expected.linear_drop, 0, 1), rel=1e-9)
    ranked = run_rigopt("rank", "R5", "R6", "R9", "--ref", "R1", "--metric", metric, "--json")
    assert ranked.returncode == 0, ranked.stderr
    drops = [row["predicted_drop"] for row in json.loads(ranked.stdout)]
    assert drops == sorted(drops) and len(drops) == 3


@pytest.mark.parametrize("metric", LIFTING_METRICS)
def test_calibrate_refuses_to_refit_a_lifting_metric(metric):
    done = run_rigopt("calibrate", "--results", SHIPPED_CSV, "--metric", metric, "--bootstrap", "0")
    assert done.returncode == 2 and "studies/validation" in done.stderr and "Traceback" not in done.stderr
    unknown = run_rigopt("rank", "R5", "--ref", "R1", "--metric", metric, "--weights", "PETR")
    assert unknown.returncode == 2 and "joint" in unknown.stderr
