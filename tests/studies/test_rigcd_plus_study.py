"""studies/rigcd_plus/plus_study.py: variants, leave-one-rig-out folds, the choice rule and the paired
bootstrap, on cases with known answers (the fits and the V6 loop it uses: tests/metrics/test_matched_fit.py).
The study's modules are imported from their folder (tests/studies/conftest.py puts it on sys.path)."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.errors import RigoptError
from rigopt.metrics.calibration import fit_calibration, pair_features
from rigopt.rig.library import load_rig

import plus_study as ps  # studies/rigcd_plus, see conftest.py
from plus_terms import PlusSettings

CONTROL = ("R1", "R1-r", "R1-t", "R1-f", "R1-c6", "R1-c10")
OTHERS = ("R2", "R5")


def all_pairs(rigs, models=("m",)):
    grid = [(m, a, b) for m in models for a in rigs for b in rigs]
    return tuple(np.array(column) for column in zip(*grid))


def toy_pairs(x_terms: dict, delta, train=None, test=None) -> ps.StudyPairs:
    n = len(delta)
    names = np.array(["a"] * n) if train is None else train
    published = np.stack([x_terms.get(t, np.zeros(n)) for t in ("t", "r", "f", "count")], axis=1)
    return ps.StudyPairs(np.array(["m"] * n), names, names if test is None else test, np.asarray(delta, float),
                         x_terms, published, lambda lambdas: published)


def test_loro_folds_never_contain_the_left_out_rig():
    model, train, test = all_pairs(CONTROL + OTHERS, models=("A", "B"))
    folds = ps.loro_folds(train, test, CONTROL)
    assert [f.left_out for f in folds] == list(CONTROL)
    for fold in folds:
        assert not np.any(train[fold.fit] == fold.left_out) and not np.any(test[fold.fit] == fold.left_out)
        assert fold.fit.sum() == 2 * 25 and fold.predict.sum() == 2 * 6
        assert np.all(train[fold.predict] == fold.left_out)
        assert np.all(np.isin(test[fold.fit | fold.predict], CONTROL))
    predicted = np.sum([f.predict for f in folds], axis=0)
    calibration = np.isin(train, CONTROL) & np.isin(test, CONTROL)
    np.testing.assert_array_equal(predicted, calibration.astype(int))  # each calibration pair exactly once


def test_loro_folds_within_restricts_to_one_group():
    model, train, test = all_pairs(CONTROL, models=("A", "B"))
    for fold in ps.loro_folds(train, test, CONTROL, model == "B"):
        assert np.all(model[fold.fit | fold.predict] == "B") and fold.fit.sum() == 25


def test_out_of_fold_predicts_each_calibration_pair_once_with_unseen_training_rig():
    model, train, test = all_pairs(CONTROL + OTHERS)
    folds = ps.loro_folds(train, test, CONTROL)
    seen_rig = []

    def fit_predict(fit_mask, predict_mask):
        seen_rig.append(bool(np.any(np.isin(train[fit_mask], train[predict_mask]))))
        return np.full(predict_mask.sum(), float(fit_mask.sum()))

    out = ps.out_of_fold(folds, fit_predict, len(train))
    calibration = np.isin(train, CONTROL) & np.isin(test, CONTROL)
    assert not any(seen_rig)
    assert np.all(out[calibration] == 25.0) and np.all(np.isnan(out[~calibration]))


def test_out_of_fold_rejects_overlapping_folds():
    fold = ps.Fold("a", np.array([True, False]), np.array([False, True]))
    with pytest.raises(RigoptError, match="predicts a pair another fold"):
        ps.out_of_fold([fold, fold], lambda f, p: np.zeros(p.sum()), 2)


def test_paired_bootstrap_of_identical_predictors_is_exactly_zero():
    rng = np.random.default_rng(0)
    observed, predicted = rng.normal(size=60), rng.normal(size=60)
    d = ps.paired_rho_difference(predicted, predicted.copy(), observed, np.repeat(["a", "b", "c"], 20), 200, 0)
    assert d.difference == 0.0 and d.ci == (0.0, 0.0) and d.used == 200


def test_paired_bootstrap_favours_the_better_predictor():
    rng = np.random.default_rng(3)
    observed = rng.normal(size=200)
    good, noisy = observed + 0.1 * rng.normal(size=200), observed + 2.0 * rng.normal(size=200)
    d = ps.paired_rho_difference(good, noisy, observed, resamples=300, seed=0)
    assert d.rho_a > d.rho_b and d.ci[0] > 0 and d.ci[0] <= d.difference <= d.ci[1]


def test_constant_prediction_has_undefined_rho_and_is_not_better():
    observed = np.arange(10.0)
    d = ps.paired_rho_difference(np.zeros(10), observed + 1, observed, resamples=100)
    assert np.isnan(d.rho_a) and np.isnan(d.difference) and d.used == 0
    scores = {"V0": 0.5, "V1": float("nan"), "V2": 0.4}
    assert ps.choose_variant(scores, {"V0": 4, "V1": 5, "V2": 4}) == "V0"


def test_stratified_resamples_stay_within_their_stratum():
    strata = np.array(["x"] * 5 + ["y"] * 3)
    index = ps.stratified_resamples(strata, 50, 0)
    assert index.shape == (50, 8)
    assert np.all(index[:, :5] < 5) and np.all(index[:, 5:] >= 5)


@pytest.mark.parametrize("scores, expected", [
    ({"V0": 0.80, "V1": 0.805, "V2": 0.70}, "V0"),                    # below the margin
    ({"V0": 0.80, "V1": 0.85, "V2": 0.90}, "V2"),                     # clearly best
    ({"V0": 0.80, "V1": 0.895, "V2": 0.90}, "V2"),                    # tie within 0.01: fewer features (V2: 4)
    ({"V0": 0.80, "V1": 0.90, "C1": 0.905}, "V1"),                    # tie, same feature count: table order
    ({"V0": 0.80, "V1": 0.809, "C1": 0.815}, "C1"),                   # V1 itself is not 0.01 above V0
])
def test_choice_rule(scores, expected):
    n = {"V0": 4, "V1": 5, "V2": 4, "C1": 5}
    assert ps.choose_variant(scores, n) == expected


def test_variant_v0_is_the_published_fit():
    rigs = [load_rig(n) for n in CONTROL]
    model, train, test = all_pairs(CONTROL)
    published = pair_features(rigs, train, test)
    delta = published @ np.array([0.3, 0.07, 0.02, 0.2])
    pairs = ps.StudyPairs(model, train, test, delta, {}, published, lambda lambdas: published)
    every = np.ones(len(delta), bool)
    fitted = ps.fit_variant("V0", pairs, every)
    reference = fit_calibration(published, delta, "fit").calibration
    assert fitted.calibration == reference
    np.testing.assert_array_equal(ps.predict_variant(fitted, pairs, every), reference.predict(*published.T))


def test_variant_predictions_use_beta_dot_x_of_their_features():
    rng = np.random.default_rng(2)
    terms = {t: rng.uniform(0, 1, 30) for t in ("t", "r", "f", "count", "cover")}
    pairs = toy_pairs(terms, 0.4 * terms["t"] + 0.1 * terms["cover"])
    every = np.ones(30, bool)
    fitted = ps.fit_variant("V3", pairs, every)
    np.testing.assert_allclose(fitted.beta, [0.4, 0, 0, 0, 0.1], atol=1e-6)
    np.testing.assert_allclose(ps.predict_variant(fitted, pairs, every), pairs.delta, atol=1e-6)
    assert fitted.to_dict()["beta"]["cover"] == pytest.approx(0.1, abs=1e-6)


def test_unknown_variant_is_rejected():
    with pytest.raises(RigoptError, match="unknown variant"):
        ps.fit_variant("V9", toy_pairs({"t": np.ones(3)}, np.ones(3)), np.ones(3, bool))


def test_rematcher_with_unit_lambdas_gives_the_published_features():
    names = list(CONTROL + OTHERS)
    rigs = [load_rig(n) for n in names]
    _, train, test = all_pairs(names)
    features = ps.rematcher(rigs, names, train, test, PlusSettings())
    np.testing.assert_array_equal(features((1.0, 1.0, 1.0)), pair_features(rigs, train, test))
    assert features((1.0, 1.0, 1.0)) is features((1, 1, 1))  # cached
    diagonal = train == test
    assert np.all(features((0.3, 0.0, 0.02))[diagonal] == 0.0)


def test_variant_solver_switch_picks_that_solvers_betas():
    rng = np.random.default_rng(5)
    terms = {t: rng.uniform(0, 1, 20) for t in ("t", "r", "count")}
    terms["f"] = np.zeros(20)  # not identified: the solvers differ only here
    pairs = toy_pairs(terms, 0.3 * terms["t"] + 0.1 * terms["count"] + rng.normal(0, 0.01, 20))
    every = np.ones(20, bool)
    v0_qp, v0_published = (ps.fit_variant("V0", pairs, every, solver=s) for s in ("qp", None))
    assert v0_qp.calibration is None and v0_qp.beta[2] == 0.0
    assert v0_published.calibration is not None and v0_published.beta[2] == pytest.approx(0.5)
    np.testing.assert_allclose(ps.predict_variant(v0_qp, pairs, every), pairs.published @ v0_qp.fit.beta_qp)
    with pytest.raises(RigoptError, match="unknown solver"):
        ps.fit_variant("V0", pairs, every, solver="simplex")


def linear_study(models=("A", "B")) -> ps.StudyPairs:
    """Every pair of the control and two other rigs per model, drops exactly 0.2 t + 0.1 count of random
    features (r, f random too)."""
    model, train, test = all_pairs(CONTROL + OTHERS, models)
    rng = np.random.default_rng(7)
    terms = {t: rng.uniform(0, 1, len(train)) for t in ("t", "r", "f", "count")}
    published = np.stack([terms[t] for t in ("t", "r", "f", "count")], axis=1)
    return ps.StudyPairs(model, train, test, 0.2 * terms["t"] + 0.1 * terms["count"], terms, published,
                         lambda lambdas: published)


def test_study_pairs_groups_and_calibration_set():
    pairs = linear_study()
    assert pairs.groups == ("A", "B")
    assert pairs.both_in(CONTROL).sum() == 2 * 36 and (~pairs.both_in(CONTROL)).sum() == 2 * (64 - 36)


def test_cv_predictions_of_an_exact_linear_model_are_exact():
    pairs = linear_study()
    fits = []
    joint, own = ps.cv_predictions("V0", pairs, CONTROL, solver="qp", fits=fits)
    calibration = pairs.both_in(CONTROL)
    np.testing.assert_allclose(joint[calibration], pairs.delta[calibration], atol=1e-6)
    np.testing.assert_allclose(own[calibration], pairs.delta[calibration], atol=1e-6)
    assert np.all(np.isnan(joint[~calibration])) and len(fits) == 6 * 3  # joint folds + each group's folds


def test_fit_full_predicts_every_pair_jointly_and_per_group():
    pairs = linear_study()
    full = ps.fit_full("V0", pairs, pairs.both_in(CONTROL))
    assert set(full.own) == {"A", "B"} and full.joint.fit.n == 72 and full.own["A"].fit.n == 36
    np.testing.assert_allclose(full.joint_predicted, pairs.delta, atol=1e-4)
    np.testing.assert_allclose(full.own_predicted, pairs.delta, atol=1e-4)


def test_groups_above_counts_groups_and_treats_undefined_as_not_better():
    observed = np.tile(np.arange(10.0), 3)
    groups = np.repeat(["a", "b", "c"], 10)
    better = observed.copy()
    worse = observed + np.tile([0, 5, -5, 0, 3, -3, 0, 1, -1, 0], 3)
    worse[20:] = 0.0  # group c: the other predictor is constant (undefined rho)
    assert ps.groups_above(better, worse, observed, groups) == 3
    assert ps.groups_above(worse, better, observed, groups) == 0


def test_decision_needs_the_interval_above_zero_and_enough_groups():
    above_zero = ps.PairedDifference(0.7, 0.6, 0.1, (0.02, 0.2), 1000, 640)
    touching = ps.PairedDifference(0.7, 0.6, 0.1, (0.0, 0.2), 1000, 640)
    assert ps.beats_baseline(above_zero, 3, 3) and not ps.beats_baseline(above_zero, 2, 3)
    assert not ps.beats_baseline(touching, 4, 3)
