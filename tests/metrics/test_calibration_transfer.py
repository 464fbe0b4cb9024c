"""A calibration fitted on one body of measured transfer, judged on another (``calibration_on``; ``rigopt
calibrate --test-on``): on its own data it gives exactly the protocol's joint figures; fitted on the
committed synthetic transfer and judged on the real benchmark, it reports beside the benchmark's own
calibrations, which still reproduce the published figures."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import spearmanr

from rigopt.metrics.calibration import pair_features
from rigopt.metrics.protocol import calibrate, calibration_on
from rigopt.metrics.transfer import read_transfer
from rigopt.rig.library import load_rig

from in_process import run_rigopt

REPO = Path(__file__).resolve().parents[2]
REAL = REPO / "metrics" / "pccr_transfer.csv"
SYNTHETIC = REPO / "baselines" / "v1" / "transfer"
SYNTHETIC_RIGS = REPO / "baselines" / "rigs"
RESAMPLES = 50


@pytest.fixture(scope="module")
def real_study():
    return calibrate(read_transfer(REAL), resamples=RESAMPLES)


def test_a_calibration_judged_on_its_own_data_gives_the_joint_figures(real_study):
    transfer = calibration_on(real_study.joint.fit.calibration, read_transfer(REAL), resamples=RESAMPLES)
    for ours, theirs in zip(transfer.models, real_study.joint.models):
        assert ours.model == theirs.model
        assert ours.heldout.rho == pytest.approx(theirs.heldout.rho, abs=1e-12)
        assert ours.heldout.mae == pytest.approx(theirs.heldout.mae, abs=1e-12)
        assert ours.bounded_heldout.mae == pytest.approx(theirs.bounded_heldout.mae, abs=1e-12)


def test_the_transferred_rho_is_spearman_of_the_prediction_on_the_held_out_pairs(real_study):
    table = read_transfer(REAL)
    other = calibrate(table, resamples=RESAMPLES).models[0].fit.calibration  # BEVDet's fit, judged on every model
    transfer = calibration_on(other, table, resamples=RESAMPLES)
    drops = table.drops()
    names = list(dict.fromkeys(drops.train.tolist() + drops.test.tolist()))
    rigs = []
    for name in names:
        rig = load_rig(name)
        rigs.append(rig if rig.name == name else type(rig)(name, rig.vehicle, rig.cameras, rig.origin))
    x = pair_features(rigs, drops.train, drops.test)
    held = ~(np.isin(drops.train, list(real_study.control_rigs)) & np.isin(drops.test, list(real_study.control_rigs)))
    for result in transfer.models:
        mine = (drops.model == result.model) & held
        rho = spearmanr(other.predict(*x[mine].T), drops.delta[mine]).statistic
        assert result.heldout.rho == pytest.approx(rho, abs=1e-12)


def test_calibrate_test_on_reports_the_synthetic_fit_beside_the_benchmarks_own():
    outcome = run_rigopt("calibrate", "--results", str(SYNTHETIC), "--rigs", str(SYNTHETIC_RIGS),
                         "--test-on", str(REAL), "--bootstrap", "50", "--json")
    assert outcome.returncode == 0, outcome.stderr
    test = json.loads(outcome.stdout)["test_on"]
    assert set(test["models"]) == {"BEVDet", "BEVFusion", "Fast-BEV", "PETR"}
    published = {"BEVDet": 0.718, "BEVFusion": 0.734, "Fast-BEV": 0.097, "PETR": 0.805}
    for model, entry in test["models"].items():
        assert round(entry["own_per_detector"]["heldout"]["rho"], 3) == published[model]
        assert -1.0 <= entry["heldout"]["rho"] <= 1.0 and entry["heldout"]["n"] > 0
    assert test["weights"]["n"] > 0  # fitted on the synthetic control pairs
