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
SYNTHETIC = REPO / "measurements" / "v1" / "transfer"
SYNTHETIC_RIGS = REPO / "measurements" / "rigs"
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


@pytest.mark.slow
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
        rho = spearmanr(other.linear_drop(*x[mine].T), drops.delta[mine]).statistic
        assert result.heldout.rho == pytest.approx(rho, abs=1e-12)


def test_the_rho_gain_over_an_own_fit_is_the_difference_of_their_held_out_rhos(real_study):
    table = read_transfer(REAL)
    other = real_study.models[0].fit.calibration  # BEVDet's own fit, judged on every detector
    transfer = calibration_on(other, table, resamples=RESAMPLES, own=real_study)
    own_joint = {m.model: m for m in real_study.joint.models}
    own = {m.model: m for m in real_study.models}
    for result in transfer.models:
        gains = transfer.gains[result.model]
        joint_gain, low, high = gains["own_joint"]
        assert joint_gain == pytest.approx(result.heldout.rho - own_joint[result.model].heldout.rho, abs=1e-12)
        assert low <= joint_gain <= high
        per_detector_gain = gains["own_per_detector"][0]
        assert per_detector_gain == pytest.approx(result.heldout.rho - own[result.model].heldout.rho, abs=1e-12)
    assert transfer.gains["BEVDet"]["own_per_detector"] == (0.0, 0.0, 0.0)  # the same fit on the same pairs


@pytest.mark.slow
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
        gain = entry["own_joint"]["rho_gain"]
        assert gain["value"] == pytest.approx(entry["heldout"]["rho"] - entry["own_joint"]["heldout"]["rho"], abs=1e-12)
        assert gain["ci"][0] <= gain["value"] <= gain["ci"][1]
    assert test["weights"]["n"] > 0  # fitted on the synthetic control pairs


def test_null_transfer_keeps_the_pairs_and_own_maps_and_draws_chance_drops():
    from rigopt.metrics.protocol import null_transfer

    table = read_transfer(SYNTHETIC)
    chance = null_transfer(table, np.random.default_rng(3))
    assert (chance.model == table.model).all() and (chance.train == table.train).all()
    assert (chance.test == table.test).all()
    assert chance.own_map() == table.own_map()
    drops = chance.drops()
    off = drops.train != drops.test
    assert ((drops.delta[off] >= 0) & (drops.delta[off] <= 1)).all() and np.std(drops.delta[off]) > 0.2
    again = null_transfer(table, np.random.default_rng(3))
    assert (again.map == chance.map).all()  # seeded
    assert not np.allclose(null_transfer(table, np.random.default_rng(4)).map, chance.map)


@pytest.mark.slow
def test_null_yardstick_is_the_transferred_rho_of_fits_on_chance_copies(real_study):
    """One chance copy of the synthetic table, fitted and judged by hand, gives the yardstick's first value;
    the summary's share counts the null rhos that reach a figure."""
    from rigopt.metrics.protocol import NullYardstick, null_transfer, null_yardstick
    from rigopt.vehicle.placement import benchmark_rig_lookup

    lookup = benchmark_rig_lookup(SYNTHETIC_RIGS)
    source, target = read_transfer(SYNTHETIC), read_transfer(REAL)
    yardstick = null_yardstick(source, target, 1, rig_lookup=lookup)
    chance = null_transfer(source, np.random.default_rng(0))
    fit = calibrate(chance, rig_lookup=lookup, resamples=0).joint.fit.calibration
    by_hand = {m.model: m.heldout.rho for m in calibration_on(fit, target, rig_lookup=lookup, resamples=0).models}
    assert {m: float(r[0]) for m, r in yardstick.heldout_rho.items()} == pytest.approx(by_hand, abs=1e-12)
    summary = NullYardstick(4, {"A": np.array([0.1, 0.2, 0.3, 0.4])}).summary({"A": 0.25})
    assert summary["A"]["share_reaching"] == 0.5 and summary["A"]["median"] == pytest.approx(0.25)


@pytest.mark.slow
def test_calibrate_null_reports_the_yardstick_and_needs_test_on():
    outcome = run_rigopt("calibrate", "--results", str(SYNTHETIC), "--rigs", str(SYNTHETIC_RIGS),
                         "--test-on", str(REAL), "--bootstrap", "0", "--null", "1", "--json")
    assert outcome.returncode == 0, outcome.stderr
    test = json.loads(outcome.stdout)["test_on"]
    assert test["null"]["seeds"] == 1 and set(test["null"]["models"]) == set(test["models"])
    for model, entry in test["null"]["models"].items():
        assert entry["median"] == entry["p5"] == entry["p95"]  # one chance fit
        assert entry["share_reaching"] == float(entry["median"] >= test["models"][model]["heldout"]["rho"])
    refused = run_rigopt("calibrate", "--results", str(SYNTHETIC), "--null", "3")
    assert refused.returncode == 2 and refused.stderr.count("rigopt: error:") == 1 and "--test-on" in refused.stderr


@pytest.mark.slow
def test_control_all_fits_on_every_pair_and_the_target_keeps_the_benchmarks_control_rigs():
    """--control all: the synthetic fit uses every pair of --results (none held out there), while --test-on's
    held-out pairs stay those outside the benchmark's control rigs unless --test-control names others."""
    common = ["calibrate", "--results", str(SYNTHETIC), "--rigs", str(SYNTHETIC_RIGS), "--test-on", str(REAL),
              "--bootstrap", "0", "--json"]
    default = json.loads(run_rigopt(*common).stdout)
    every = run_rigopt(*common, "--control", "all")
    assert every.returncode == 0, every.stderr
    report = json.loads(every.stdout)
    pairs = len(read_transfer(SYNTHETIC).drops().delta)
    assert report["joint"]["weights"]["n"] == pairs > default["joint"]["weights"]["n"]
    assert all(entry["heldout"]["n"] == 0 and entry["heldout"]["rho"] is None for entry in report["models"].values())
    test = report["test_on"]
    assert test["control_rigs"] == default["test_on"]["control_rigs"] == ["R1", "R1-c10", "R1-c6", "R1-f", "R1-r", "R1-t"]
    for model, entry in test["models"].items():
        assert entry["heldout"]["n"] == default["test_on"]["models"][model]["heldout"]["n"]
        theirs = default["test_on"]["models"][model]["own_joint"]
        assert (entry["own_joint"]["heldout"], entry["own_joint"]["bounded"]) == (theirs["heldout"], theirs["bounded"])
    fewer = json.loads(run_rigopt(*common, "--test-control", "R1,R1-r,R1-t").stdout)["test_on"]
    assert fewer["control_rigs"] == ["R1", "R1-r", "R1-t"]
    for model, entry in fewer["models"].items():
        assert entry["heldout"]["n"] > default["test_on"]["models"][model]["heldout"]["n"]


@pytest.mark.slow
@pytest.mark.parametrize("metric", ["rigcd", "rigcd+"])
def test_the_shipped_sim_calibration_beats_the_benchmarks_joint_on_the_real_held_out_pairs(metric):
    """sim-lss was fitted on synthetic pairs alone (none of the real held-out rigs R2-R9): on the real
    benchmark's held-out pairs it must keep what its file claims for the lss family's counterparts."""
    from rigopt.metrics.calibration import load_weights

    shipped = load_weights("sim-lss", metric)
    transfer = calibration_on(shipped, read_transfer(REAL))  # the default 1000 resamples, as shipped
    own_joint = {m.model: m for m in transfer.own.joint.models}
    for result in transfer.models:
        if result.model in ("BEVDet", "BEVFusion"):
            gain, low, _ = transfer.gains[result.model]["own_joint"]
            assert gain > 0 and low > 0
            assert result.heldout.mae < own_joint[result.model].heldout.mae
            assert result.bounded_heldout.mae < own_joint[result.model].bounded_heldout.mae
        claimed = f"{result.model} rho {result.heldout.rho:.3f} vs the benchmark's joint "
        assert claimed + f"{own_joint[result.model].heldout.rho:.3f}" in shipped_source(metric)


def shipped_source(metric: str) -> str:
    from rigopt.metrics.calibration import WEIGHTS_FOLDERS
    from rigopt.resources import data_dir

    return json.loads((data_dir("metrics") / WEIGHTS_FOLDERS[metric] / "sim-lss.json").read_text())["source"]
