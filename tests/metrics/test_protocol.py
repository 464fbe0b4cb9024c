"""The benchmark's calibration protocol on the real data, re-derived here from the CSV and reference RigCD.

Independent pieces: the CSV is parsed with ``csv``, drops computed by hand, features of every rig pair
computed with ``oracles.metrics.rigcd_reference`` (tests/oracles: plain loops, unit weights), and rho with
``scipy.stats.spearmanr``.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import rankdata, spearmanr

from oracles.metrics import rigcd_reference
from rigopt.errors import DataError
from rigopt.metrics.protocol import calibrate
from rigopt.metrics.transfer import TransferTable, read_transfer
from rigopt.rig.library import load_rig

REPO = Path(__file__).resolve().parents[2]
SHIPPED_CSV = REPO / "metrics" / "pccr_transfer.csv"
MODELS = ("BEVDet", "BEVFusion", "Fast-BEV", "PETR")
CONTROL = {"R1", "R1-c10", "R1-c6", "R1-f", "R1-r", "R1-t"}
RESAMPLES = 50


@pytest.fixture(scope="module")
def study():
    return calibrate(read_transfer(SHIPPED_CSV), resamples=RESAMPLES)


@pytest.fixture(scope="module")
def drops_by_hand():
    """{(model, train, test): delta} from the CSV parsed here."""
    maps = {}
    with SHIPPED_CSV.open(newline="") as handle:
        for row in csv.DictReader(handle):
            maps[(row["model"], row["train_rig"], row["test_rig"])] = float(row["mAP"])
    return {(m, a, b): (maps[(m, a, a)] - v) / maps[(m, a, a)] for (m, a, b), v in maps.items()}


@pytest.fixture(scope="module")
def reference_features():
    """{(train, test): (t, r, f, count)} of every rig pair by the reference implementation, unit weights."""
    names = sorted({a for a in CONTROL} | {f"R{k}" for k in range(2, 10)})
    rigs = {name: load_rig(name) for name in names}
    out = {}
    for a in names:
        for b in names:
            ref = rigcd_reference(rigs[a], rigs[b], alpha=0.9, lambdas=(1.0, 1.0, 1.0))
            out[(a, b)] = np.array([ref["t"], ref["r"], ref["f"], ref["count"]])
    return out


def heldout_by_hand(model, drops_by_hand, reference_features):
    """(features (P, 4), delta (P,)) of one model's held-out pairs."""
    keys = [(a, b) for (m, a, b) in drops_by_hand if m == model and not (a in CONTROL and b in CONTROL)]
    x = np.array([reference_features[k] for k in keys])
    y = np.array([drops_by_hand[(model, a, b)] for a, b in keys])
    return x, y


def model_entry(study, model):
    return next(m for m in study.models if m.model == model)


# --- split sizes ------------------------------------------------------------------------------------


@pytest.mark.parametrize("model", MODELS)
def test_36_control_and_160_heldout_pairs_per_model(study, model):
    entry = model_entry(study, model)
    assert int(entry.pairs.control.sum()) == 36
    assert int((~entry.pairs.control).sum()) == 160
    assert entry.fit.n == 36
    assert entry.control.n == 36 and entry.heldout.n == 160


def test_control_flag_means_both_rigs_are_control_rigs(study):
    pairs = study.joint.pairs
    expected = np.array([a in CONTROL and b in CONTROL for a, b in zip(pairs.train, pairs.test)])
    assert np.array_equal(pairs.control, expected)


def test_joint_fit_uses_144_pairs(study):
    assert study.joint.fit.n == 144
    assert len(study.joint.pairs.delta) == 4 * 196


def test_models_in_order_and_nothing_skipped(study):
    assert [m.model for m in study.models] == [r.model for r in study.joint.models]
    assert set(m.model for m in study.models) == set(MODELS)
    assert study.skipped == ()


# --- features, drops, predictions -----------------------------------------------------------------------


@pytest.mark.parametrize("a, b", [("R1", "R6"), ("R6", "R1"), ("R1-c10", "R5"), ("R9", "R9"), ("R1-f", "R1"),
                                  ("R4", "R8"), ("R2", "R3"), ("R1-c6", "R1-t"), ("R7", "R1-r"), ("R5", "R9")])
def test_pair_features_equal_the_reference(study, reference_features, a, b):
    pairs = study.joint.pairs
    rows = np.flatnonzero((pairs.train == a) & (pairs.test == b))
    assert len(rows) == 4  # one per model
    for row in rows:
        assert pairs.features[row] == pytest.approx(reference_features[(a, b)], abs=1e-7)


def test_all_pair_features_equal_the_reference(study, reference_features):
    pairs = study.joint.pairs
    expected = np.array([reference_features[(a, b)] for a, b in zip(pairs.train, pairs.test)])
    assert np.max(np.abs(pairs.features - expected)) <= 1e-7


def test_features_of_reversed_pairs_are_identical(study):
    # RigCD is symmetric: A -> B and B -> A must have bit-identical features so that they tie exactly.
    pairs = study.joint.pairs
    row = {k: i for i, k in enumerate(zip(pairs.model, pairs.train, pairs.test))}
    for (m, a, b), i in row.items():
        assert np.array_equal(pairs.features[i], pairs.features[row[(m, b, a)]]), (a, b)


def test_diagonal_features_are_zero(study):
    pairs = study.joint.pairs
    assert np.all(pairs.features[pairs.train == pairs.test] == 0.0)


def test_observed_drops_equal_the_csv_by_hand(study, drops_by_hand):
    pairs = study.joint.pairs
    expected = np.array([drops_by_hand[k] for k in zip(pairs.model, pairs.train, pairs.test)])
    assert np.allclose(pairs.delta, expected, rtol=0, atol=1e-15)


def by_formula(c, x):
    """K (alpha (lt t + lr r + lf f) + (1 - alpha) count) of features x (P, 4), written out here."""
    t, r, f, n = x.T
    return c.K * (c.alpha * (c.lambda_t * t + c.lambda_r * r + c.lambda_f * f) + (1 - c.alpha) * n)


def heldout_of(pairs, drops_by_hand):
    """The held-out rows of ``pairs`` (split decided here) with the hand-computed drops."""
    held = np.array([not (a in CONTROL and b in CONTROL) for a, b in zip(pairs.train, pairs.test)])
    delta = np.array([drops_by_hand[k] for k in zip(pairs.model[held], pairs.train[held], pairs.test[held])])
    return pairs.features[held], delta


@pytest.mark.parametrize("model", MODELS)
def test_heldout_rho_equals_scipy_on_the_formula(study, drops_by_hand, model):
    # Features are the tool's (checked against the reference above), bit for bit, so that exactly tied
    # predictions (A -> B and B -> A) tie the same way here.
    entry = model_entry(study, model)
    x, y = heldout_of(entry.pairs, drops_by_hand)
    assert len(y) == 160
    expected = spearmanr(by_formula(entry.fit.calibration, x), y)
    assert entry.heldout.rho == pytest.approx(expected.statistic, abs=1e-12)
    assert entry.heldout.p == pytest.approx(expected.pvalue, rel=1e-9)
    assert entry.knockout.full == pytest.approx(expected.statistic, abs=1e-12)


@pytest.mark.parametrize("model", MODELS)
def test_heldout_rho_on_reference_features_agrees_to_three_decimals(study, drops_by_hand, reference_features,
                                                                    model):
    entry = model_entry(study, model)
    x, y = heldout_by_hand(model, drops_by_hand, reference_features)
    expected = spearmanr(entry.fit.calibration.linear_drop(*x.T), y).statistic
    assert entry.heldout.rho == pytest.approx(expected, abs=1e-3)


def test_heldout_rho_treats_equal_predictions_as_ties(study, drops_by_hand, reference_features):
    """RigCD is symmetric, so A -> B and B -> A (both held out) have equal predictions; float noise in the
    features must not break those ties (77 distinct predictions among 160 pairs; breaking them arbitrarily
    moves rho by up to ~3e-4)."""
    for model in MODELS:
        entry = model_entry(study, model)
        x, y = heldout_by_hand(model, drops_by_hand, reference_features)
        exact = spearmanr(np.round(entry.fit.calibration.linear_drop(*x.T), 10), y).statistic
        assert entry.heldout.rho == pytest.approx(exact, abs=1e-9), model


@pytest.mark.parametrize("model", MODELS)
def test_joint_heldout_rho_per_model_equals_scipy(study, drops_by_hand, model):
    pairs = study.joint.pairs
    mine = pairs.model == model
    held = mine & ~np.array([a in CONTROL and b in CONTROL for a, b in zip(pairs.train, pairs.test)])
    y = np.array([drops_by_hand[k] for k in zip(pairs.model[held], pairs.train[held], pairs.test[held])])
    expected = spearmanr(by_formula(study.joint.fit.calibration, pairs.features[held]), y).statistic
    joint = next(r for r in study.joint.models if r.model == model)
    assert joint.heldout.rho == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize("model", MODELS)
def test_predictions_come_from_k_alpha_lambdas(study, model):
    entry = model_entry(study, model)
    assert np.allclose(entry.pairs.predicted, by_formula(entry.fit.calibration, entry.pairs.features),
                       rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("model", MODELS)
def test_predictions_on_reference_features(study, reference_features, model):
    entry = model_entry(study, model)
    x = np.array([reference_features[k] for k in zip(entry.pairs.train, entry.pairs.test)])
    assert np.allclose(entry.pairs.predicted, entry.fit.calibration.linear_drop(*x.T), rtol=0, atol=1e-7)


def test_fast_bev_uses_the_fallback_prediction(study):
    entry = model_entry(study, "Fast-BEV")
    assert entry.fit.calibration.fallback
    t, r, f, n = entry.pairs.features.T
    k = entry.fit.calibration.K
    assert np.allclose(entry.pairs.predicted, k * (0.9 * (t + r + f) + 0.1 * n), rtol=1e-12, atol=1e-15)


# --- knockout ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("model", MODELS)
def test_knockout_count_equals_rho_with_alpha_one(study, drops_by_hand, model):
    entry = model_entry(study, model)
    c = entry.fit.calibration
    x, y = heldout_of(entry.pairs, drops_by_hand)
    # alpha = 1: K (lt t + lr r + lf f), the count term gone
    predicted = c.K * (c.lambda_t * x[:, 0] + c.lambda_r * x[:, 1] + c.lambda_f * x[:, 2])
    assert entry.knockout.count == pytest.approx(spearmanr(predicted, y).statistic, abs=1e-12)


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("component, column", [("lambda_t", 0), ("lambda_r", 1), ("lambda_f", 2)])
def test_knockout_of_one_lambda(study, drops_by_hand, model, component, column):
    entry = model_entry(study, model)
    c = entry.fit.calibration
    x, y = heldout_of(entry.pairs, drops_by_hand)
    lambdas = list(c.lambdas)
    lambdas[column] = 0.0
    match = lambdas[0] * x[:, 0] + lambdas[1] * x[:, 1] + lambdas[2] * x[:, 2]
    predicted = c.K * (c.alpha * match + (1 - c.alpha) * x[:, 3])
    assert getattr(entry.knockout, component) == pytest.approx(spearmanr(predicted, y).statistic, abs=1e-12)


def test_knockouts_differ_from_the_full_metric(study):
    # Removing the dominant translation term of PETR must change its held-out rho a lot.
    entry = model_entry(study, "PETR")
    assert abs(entry.knockout.lambda_t - entry.knockout.full) > 0.1


# --- ranks ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("model", MODELS)
def test_rank_error_sums_to_zero_in_each_group(study, model):
    pairs = model_entry(study, model).pairs
    for train in set(pairs.train.tolist()):
        group = pairs.train == train
        assert group.sum() == 14
        assert abs(pairs.rank_error[group].sum()) <= 1e-9


def test_observed_ranks_by_hand(study):
    pairs = model_entry(study, "PETR").pairs
    group = pairs.train == "R1"
    # largest drop rank 1, ties averaged
    assert np.array_equal(pairs.rank_observed[group], rankdata(-pairs.delta[group], method="average"))
    assert pairs.rank_observed[group & (pairs.test == "R1")] > 1  # the diagonal (drop 0) is not the largest


def test_joint_rank_error_sums_to_zero_per_model_and_train(study):
    pairs = study.joint.pairs
    for key in set(zip(pairs.model.tolist(), pairs.train.tolist())):
        group = (pairs.model == key[0]) & (pairs.train == key[1])
        assert abs(pairs.rank_error[group].sum()) <= 1e-9


# --- options and bad input ---------------------------------------------------------------------------


def test_control_rigs_option_changes_the_split():
    study = calibrate(read_transfer(SHIPPED_CSV), control_rigs=("R1", "R1-f", "R1-r"), resamples=0)
    for entry in study.models:
        assert int(entry.pairs.control.sum()) == 9
        assert int((~entry.pairs.control).sum()) == 196 - 9
    assert study.joint.fit.n == 4 * 9
    assert study.control_rigs == ("R1", "R1-f", "R1-r")


def small_table(rows) -> TransferTable:
    model, train, test, value = (np.array(c) for c in zip(*rows))
    return TransferTable(model, train, test, value.astype(float))


def test_table_without_control_pair_raises_data_error():
    rows = [("M", a, b, 0.5 if a == b else 0.3) for a in ("R2", "R3", "R4") for b in ("R2", "R3", "R4")]
    with pytest.raises(DataError):
        calibrate(small_table(rows), resamples=0)


def test_control_rig_only_as_test_rig_gives_no_control_pair():
    rows = [("M", "R2", "R2", 0.5), ("M", "R2", "R1", 0.3), ("M", "R3", "R3", 0.4), ("M", "R3", "R1", 0.1)]
    with pytest.raises(DataError):
        calibrate(small_table(rows), resamples=0)


def test_skipped_training_rigs_are_reported():
    rigs = ("R1", "R1-f", "R1-r", "R2")
    rows = [("M", a, b, (0.0 if a == "R2" else 0.5) if a == b else 0.1 + 0.05 * i)
            for a in rigs for i, b in enumerate(rigs)]
    study = calibrate(small_table(rows), resamples=0)
    assert study.skipped == (("M", "R2"),)
    assert "R2" not in study.models[0].pairs.train.tolist()
