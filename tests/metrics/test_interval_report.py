"""Prediction intervals that mean something: exact leave-one-rig-out refits, the per-bin interval report,
and uninformative intervals said as such by every command that prints one.

Oracles: scipy's nnls on the fold's pairs selected here by hand, a pair set built so that L-BFGS-B stops at
its start, coverages and widths counted by hand on six pairs."""

import json

import numpy as np
import pytest
from in_process import run_rigopt
from scipy.optimize import nnls

from rigopt.metrics.calibration import BETA0, fit_lbfgsb, load_weights, write_weights
from rigopt.metrics.prediction import (UNINFORMATIVE_TEXT, Interval, interval_informative, interval_report,
                                       rig_folds)
from rigopt.metrics.protocol import CONTROL_RIGS, calibrate, fold_calibration
from rigopt.metrics.transfer import read_transfer
from rigopt.resources import data_dir


@pytest.fixture(scope="module")
def study():
    return calibrate(read_transfer(data_dir("metrics") / "pccr_transfer.csv"), resamples=0)


def _control_pairs(pairs):
    c = pairs.control
    return pairs.train[c], pairs.test[c], pairs.features[c], pairs.delta[c]


@pytest.mark.parametrize("fit", ["BEVDet", "PETR", "joint"])
def test_each_fold_refit_is_nnls_on_the_control_pairs_without_its_rig(study, fit):
    pairs, choice = ((study.joint.pairs, study.joint.link_choice) if fit == "joint" else
                     next((m.pairs, m.link_choice) for m in study.models if m.model == fit))
    train, test, x, delta = _control_pairs(pairs)
    assert set(choice.fold_betas) == set(CONTROL_RIGS)  # one fold per control rig, no fold of single pairs
    for rig in CONTROL_RIGS:
        kept = (train != rig) & (test != rig)  # every pair involving the rig is out, of every detector
        expected, _ = nnls(x[kept], delta[kept])
        assert np.allclose(choice.fold_betas[rig], expected, rtol=0, atol=1e-9), rig


def test_folds_drop_every_pair_that_involves_their_rig():
    train = np.array(["A", "A", "B", "B", "C", "A"])
    test = np.array(["A", "B", "A", "C", "C", "C"])
    folds = {rig: (involved, scored) for rig, involved, scored in rig_folds(train, test)}
    assert folds["A"][0].tolist() == [True, True, True, False, False, True]
    assert folds["A"][1].tolist() == [False, True, True, False, False, True]  # the diagonal A -> A is not scored
    assert folds["C"][0].tolist() == [False, False, False, True, True, True]


def test_a_fold_without_r1_f_sets_the_fov_weight_to_zero_where_lbfgsb_keeps_its_start(study):
    """R1-f is the one control rig with another FOV: without it every fold pair has f = 0, so no data informs
    beta_f; L-BFGS-B leaves it at 0.5, the exact refit at 0."""
    bevdet = next(m for m in study.models if m.model == "BEVDet")
    train, test, x, delta = _control_pairs(bevdet.pairs)
    kept = (train != "R1-f") & (test != "R1-f")
    assert np.all(x[kept, 2] == 0.0)
    assert fit_lbfgsb(x[kept], delta[kept])[2] == BETA0[2]
    assert bevdet.link_choice.fold_betas["R1-f"][2] == 0.0


def test_a_pair_set_where_lbfgsb_stops_at_its_start_still_gets_the_exact_optimum():
    # delta = 0.5 (t + r + count) exactly and f = 0 throughout: the gradient at L-BFGS-B's start is 0
    x = np.array([[0.2, 0.1, 0.0, 0.0], [0.5, 0.0, 0.0, 0.25], [0.0, 0.4, 0.0, 0.1], [0.3, 0.3, 0.0, 0.2],
                  [0.1, 0.2, 0.0, 0.5]])
    delta = 0.5 * (x[:, 0] + x[:, 1] + x[:, 3])
    assert np.array_equal(fit_lbfgsb(x, delta), np.array(BETA0))  # it never moves
    refit = fold_calibration(x, delta, "fold")
    assert np.allclose(refit.beta, [0.5, 0.5, 0.0, 0.5], rtol=0, atol=1e-12)
    # a pair 30 deg apart in FOV: the start's beta_f would add 15 to its linear prediction, the optimum nothing
    assert refit.linear_drop(0.2, 0.1, 30.0, 0.0) == pytest.approx(0.15, abs=1e-12)


def test_a_fold_refit_reaches_the_optimum_where_lbfgsb_stops_short():
    # tiny features: L-BFGS-B's projected gradient at its start is below its tolerance, far from the optimum
    x = np.array([[1e-3, 0.0, 0.0, 0.0], [0.0, 1e-3, 0.0, 0.0], [0.0, 0.0, 1e-3, 0.0], [0.0, 0.0, 0.0, 1e-3]])
    delta = np.array([2e-3, 1e-4, 0.0, 3e-3])  # optimum beta = (2, 0.1, 0, 3)
    assert np.allclose(fit_lbfgsb(x, delta), BETA0, atol=1e-3)
    assert np.allclose(fold_calibration(x, delta, "fold").beta, [2.0, 0.1, 0.0, 3.0], rtol=0, atol=1e-9)


def test_the_interval_report_counts_coverage_width_and_clipping_per_bin_as_by_hand():
    drop = np.array([0.10, 0.20, 0.30, 0.60, 0.90, 0.95])
    delta = np.array([0.35, 0.10, 0.45, 0.30, 0.99, 0.70])
    # intervals (h = 0.2): [-0.1, 0.3] [0, 0.4] [0.1, 0.5] [0.4, 0.8] [0.7, 1 (1.1)] [0.75, 1 (1.15)]
    # inside:              no          yes      yes        no         yes            no
    report = interval_report(drop, delta, Interval(0.2, 0.9, "test"), [0.0, 0.1, 0.2, 0.4])
    by_bin = [(b.n, b.coverage, b.mean_width, b.clipped) for b in report.bins]
    expected = [(2, 0.5, 0.35, 0.5), (1, 1.0, 0.4, 0.0), (1, 0.0, 0.4, 0.0), (2, 0.5, 0.275, 1.0)]
    for got, want in zip(by_bin, expected):
        assert got[0] == want[0] and got[1:] == pytest.approx(want[1:], abs=1e-12)
    o = report.overall
    assert (o.n, o.coverage, o.mean_width, o.clipped) == (6, 0.5, pytest.approx(2.05 / 6), 0.5)
    assert report.bounded_mae == pytest.approx(1.14 / 6)
    assert report.constant == pytest.approx(0.15) and report.constant_mae == pytest.approx(2.09 / 6)
    assert report.oracle_constant_mae == pytest.approx(1.39 / 6)  # median of these drops: 0.4
    assert report.informative and report.uninformative_share == 0.0


def test_a_wide_interval_is_reported_uninformative_and_empty_bins_stay_empty():
    report = interval_report([0.1, 0.2], [0.0, 0.5], Interval(0.5, 0.9, "test"), [0.1])
    assert not report.informative and report.uninformative_share == 1.0
    assert [b.n for b in report.bins] == [2, 0, 0, 0] and np.isnan(report.bins[1].coverage)
    assert report.to_dict()["bins"][1]["coverage"] is None and report.to_dict()["interval_informative"] is False


def test_interval_informative_thresholds():
    assert interval_informative(0.1, 0.9)  # 0.8 of [0, 1]
    assert not interval_informative(0.05, 0.95)  # 0.9 of it
    assert not interval_informative(-0.6, 0.4, 0.5)  # only 0.4 inside [0, 1], but a half-width of 0.5
    assert interval_informative([-0.2, 0.6, 0.1], [0.2, 1.0, 1.0], 0.2).tolist() == [True, True, False]
    assert Interval(0.4499, 0.9, "").informative and not Interval(0.45, 0.9, "").informative


def test_calibrate_reports_the_intervals_per_bin_in_its_json_and_table(study):
    result = run_rigopt("calibrate", "--results", data_dir("metrics") / "pccr_transfer.csv", "--bootstrap", "0",
                        "--json")
    assert result.returncode == 0, result.stderr
    intervals = json.loads(result.stdout)["intervals"]
    for m in study.models:
        entry, report = intervals["models"][m.model], m.interval_heldout
        assert entry["overall"]["n"] == (~m.pairs.control).sum() == sum(b["n"] for b in entry["bins"])
        assert entry["overall"]["coverage"] == pytest.approx(m.bounded_heldout.coverage, abs=1e-12)
        assert [b["n"] for b in entry["bins"]] == [b.n for b in report.bins]
        assert entry["halfwidth"] == m.fit.calibration.interval.halfwidth
        assert entry["bounded_mae"] == pytest.approx(m.bounded_heldout.mae, abs=1e-12)
    assert set(intervals["joint"]) == {m.model for m in study.models}
    table = run_rigopt("calibrate", "--results", data_dir("metrics") / "pccr_transfer.csv", "--bootstrap", "0")
    assert "Prediction intervals on held-out pairs" in table.stdout and "[0.75, 1]" in table.stdout


def _weights_with_halfwidth(tmp_path, halfwidth: float):
    from dataclasses import replace

    joint = load_weights("joint")
    return write_weights(replace(joint, interval=replace(joint.interval, halfwidth=halfwidth)),
                         tmp_path / f"joint_{halfwidth}.json")


@pytest.mark.parametrize("command", [("rigcd", "R1", "R3"), ("rank", "R3", "R1-r", "--ref", "R1")])
def test_commands_say_a_wide_interval_is_uninformative_and_print_a_narrow_one(tmp_path, command):
    wide = run_rigopt(*command, "--weights", _weights_with_halfwidth(tmp_path, 0.6))
    assert wide.returncode == 0, wide.stderr
    assert UNINFORMATIVE_TEXT in wide.stderr and "uninformative" in wide.stdout
    narrow = run_rigopt(*command, "--weights", _weights_with_halfwidth(tmp_path, 0.1))
    assert narrow.returncode == 0, narrow.stderr
    assert "uninformative" not in narrow.stderr + narrow.stdout
    assert "[" in narrow.stdout  # the interval itself, printed as a finding


def test_json_keeps_the_numbers_of_an_uninformative_interval(tmp_path):
    wide = json.loads(run_rigopt("rigcd", "R1", "R3", "--weights", _weights_with_halfwidth(tmp_path, 0.6),
                                 "--json").stdout)
    assert wide["interval_informative"] is False
    assert wide["interval"] == pytest.approx([wide["predicted_drop"] - 0.6, min(1.0, wide["predicted_drop"] + 0.6)])
    narrow = json.loads(run_rigopt("rigcd", "R1", "R3", "--weights", _weights_with_halfwidth(tmp_path, 0.1),
                                   "--json").stdout)
    assert narrow["interval_informative"] is True


def test_the_design_page_says_uninformative_in_place_of_the_interval():
    from rigopt.report.design_html import _interval_text

    assert _interval_text({"interval": [0.1, 0.3], "interval_informative": True}) == "[0.10, 0.30]"
    assert _interval_text({"interval": [-0.5, 1.0], "interval_informative": False}) == UNINFORMATIVE_TEXT
    assert _interval_text({"interval": None}) == "-"


def test_a_linear_drop_above_one_falls_in_the_last_bin_and_empty_input_is_refused():
    from rigopt.errors import DataError

    report = interval_report([1.7], [0.9], Interval(0.1, 0.9, "test"), [0.2])
    assert [b.n for b in report.bins] == [0, 0, 0, 1]
    with pytest.raises(DataError, match="P, Q >= 1"):
        interval_report([], [], Interval(0.1, 0.9, "test"), [0.2])
