"""studies/rigcd_plus/plus_study.py (protocol 2): frames and origin moves, pair sets, one-solver fits,
cross-validation, the score over groups, the rig bootstrap and the jackknife, on cases with known answers.
The study's modules are imported from their folder (tests/studies/conftest.py puts it on sys.path)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import spearmanr

from rigopt.errors import RigoptError
from rigopt.rig.library import load_rig
from rigopt.vehicle.library import load_vehicle

import plus_study as ps  # studies/rigcd_plus, see conftest.py

BETA = np.array([0.3, 0.2, 0.01, 0.5])  # t, r, f, count


def toy_study(missing=((1, 0, 4),), seed=0) -> ps.Study:
    """5 rigs (3 control), 2 groups; every term random with a zero diagonal; delta = BETA . (t, r, f, count)
    in both groups (the second scaled by 2), NaN at ``missing`` (group, train, test)."""
    rng = np.random.default_rng(seed)
    terms = {}
    for name in sorted({n for features in ps.VARIANTS.values() for n in features}):
        m = rng.uniform(0.1, 1.0, (5, 5))
        np.fill_diagonal(m, 0.0)
        terms[name] = m
    x = np.stack([terms[t] for t in ("t", "r", "f", "count")], axis=-1)
    delta = np.stack([x @ BETA, 2 * x @ BETA])
    for g, a, b in missing:
        delta[g, a, b] = np.nan
    return ps.Study(("c1", "c2", "c3", "o1", "o2"), ("A", "B"), delta, terms,
                    np.array([True, True, True, False, False]), lambda lambdas: x)


def test_frames_do_not_move_with_the_vehicle_origin():
    rig, vehicle = load_rig("R9"), load_vehicle(load_rig("R9").vehicle)
    shift = np.array([1.0, -0.5, 0.3])
    for frame in ps.FRAMES:
        before = ps.repositioned(rig, *ps.frame_of(vehicle, frame)).positions
        after = ps.repositioned(ps.moved(rig, shift), *ps.frame_of(vehicle, frame, shift)).positions
        np.testing.assert_allclose(after, before, atol=1e-12)
    np.testing.assert_allclose(ps.moved(rig, shift).positions, rig.positions - shift)


def test_box_and_extent_frames_are_the_footprint_centre_and_the_vehicle_size():
    vehicle = load_vehicle("hgv")
    low, high = vehicle.mesh.bounds
    reference, scale = ps.frame_of(vehicle, "extent")
    np.testing.assert_allclose(reference, [(low[0] + high[0]) / 2, (low[1] + high[1]) / 2, low[2]])
    np.testing.assert_allclose(scale, high - low)
    np.testing.assert_allclose(ps.frame_of(vehicle, "axle")[0], vehicle.rear_axle)
    with pytest.raises(RigoptError, match="unknown frame"):
        ps.frame_of(vehicle, "roof")


def test_framed_terms_are_origin_invariant_while_the_published_t_is_not():
    rigs = [load_rig("R1"), load_rig("R9")]
    vehicles = [load_vehicle(r.vehicle) for r in rigs]
    shifts = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])  # the hgv's origin moves 1 m forward
    moved = [ps.moved(r, s) for r, s in zip(rigs, shifts)]
    before, after = ps.framed_terms(rigs, vehicles), ps.framed_terms(moved, vehicles, shifts)
    for key in before:
        np.testing.assert_allclose(after[key], before[key], atol=1e-9, err_msg=key)
    t_before = ps.term_matrices(rigs, rigs, ("t",))["t"]
    t_after = ps.term_matrices(moved, moved, ("t",))["t"]
    assert abs(t_after[0, 1] - t_before[0, 1]) > 0.1  # across vehicles the published t moves
    assert t_after[1, 1] == t_before[1, 1] == 0.0


def test_pair_sets_expand_over_groups_and_drop_missing_pairs():
    study = toy_study()
    rows, cols = ps.calibration_pairs(study)
    assert len(rows) == 9 and set(rows) | set(cols) == {0, 1, 2}
    rows, cols = ps.heldout_pairs(study)
    assert len(rows) == 25 - 9 and not np.any(study.control[rows] & study.control[cols])
    pairs = ps.expand(study, rows, cols)
    assert len(pairs.delta) == 2 * 16 - 1  # group B, c1 -> o2 is missing
    assert not np.any((pairs.group == 1) & (pairs.row == 0) & (pairs.col == 4))
    rows, cols = ps.calibration_pairs(study, np.array([0, 0, 2]))  # a rig drawn twice counts twice
    assert len(rows) == 9 and np.sum((rows == 0) & (cols == 0)) == 4


def test_one_solver_recovers_an_exact_linear_model_and_predicts_it():
    study = toy_study(missing=())
    pairs = ps.expand(study, *ps.calibration_pairs(study))
    pairs = ps._take(pairs, pairs.group == 0)
    for solver in ("qp", "lbfgsb"):
        model = ps.fit("V0", study, pairs, solver)
        np.testing.assert_allclose(model.beta, BETA, atol=1e-4)
        np.testing.assert_allclose(model.predict(study, pairs), pairs.delta, atol=1e-4)
    with pytest.raises(RigoptError, match="unknown solver"):
        ps.fit("V0", study, pairs, "adam")
    with pytest.raises(RigoptError, match="unknown variant"):
        ps.fit("V99", study, pairs, "qp")


def test_score_is_the_mean_of_the_groups_rhos():
    study = toy_study()
    pairs = ps.expand(study, *ps.heldout_pairs(study))
    exact = study.delta[pairs.group, pairs.row, pairs.col]
    assert ps.score(exact, pairs, 2) == pytest.approx(1.0)
    flipped = np.where(pairs.group == 1, -exact, exact)
    np.testing.assert_allclose(ps.group_rhos(flipped, pairs, 2), [1.0, -1.0])
    assert ps.score(flipped, pairs, 2) == pytest.approx(0.0)
    assert np.isnan(ps.score(np.where(pairs.group == 1, 0.0, exact), pairs, 2))  # a constant group: undefined


def test_rank_rho_matches_scipy_with_ties():
    rng = np.random.default_rng(3)
    a, b = rng.integers(0, 4, 30).astype(float), rng.normal(size=30)
    assert ps.rank_rho(a, b) == pytest.approx(spearmanr(a, b).statistic)
    assert np.isnan(ps.rank_rho(np.ones(5), b[:5]))


def test_cv_predicts_every_calibration_pair_once_by_a_fit_without_its_training_rig():
    study = toy_study(missing=())
    pairs, predicted = ps.cv_predictions("V0", study, "qp")
    assert len(pairs.delta) == 2 * 9 and np.all(np.isfinite(predicted))
    # an exact model shared by both groups up to scale: the joint fit is not exact, but ranks within a group are
    assert ps.score(predicted, pairs, 2) > 0.5


def test_choice_rule():
    assert ps.choose({"V0": 0.5, "V1": 0.6, "V6": 0.55}) == "V1"
    assert ps.choose({"V0": 0.6, "V1": 0.6, "V6": 0.55}) == "V0"  # must exceed the baseline
    assert ps.choose({"V0": 0.5, "V1": 0.6001, "V8": 0.6003}) == "V8"  # tie to 3 decimals: fewer features
    assert ps.choose({"V0": 0.5, "V1": float("nan")}) == "V0"


def test_rig_draws_stay_within_control_and_other_rigs():
    study = toy_study()
    draws = ps.rig_draws(study, 50, seed=1)
    assert len(draws) == 50
    for control, every in draws:
        assert len(control) == 3 and np.all(study.control[control])
        assert len(every) == 5 and np.all(~study.control[every[3:]]) and np.array_equal(every[:3], control)
    again = ps.rig_draws(study, 50, seed=1)
    assert all(np.array_equal(a[1], b[1]) for a, b in zip(draws, again))


def test_bootstrap_and_jackknife_of_an_exact_model_are_tight_and_paired_differences_of_equals_zero():
    study = toy_study(missing=())
    draws = ps.rig_draws(study, 30, seed=0)
    rhos = ps.bootstrap_rhos("V0", study, "qp", draws)
    assert rhos.shape == (30, 2)
    finite = rhos[np.isfinite(rhos)]
    # resamples drawing every control rig fit exactly; those drawing few leave betas unidentified
    assert np.median(finite) > 0.75 and finite.max() == pytest.approx(1.0)
    (low, high), used = ps.paired_interval(rhos, rhos)
    assert low == high == 0.0 and used == int(np.isfinite(ps.bootstrap_scores(rhos)).sum())
    jack = ps.jackknife_scores("V0", study, "qp")
    assert jack.shape == (5,)
    assert ps.jackknife_interval(0.7, np.full(5, 0.7)) == (0.7, 0.7)
    low, high = ps.jackknife_interval(0.0, [0.0, 1.0, 0.0, 1.0])
    assert low < 0 < high


def test_percentile_interval_ignores_undefined_resamples():
    assert ps.percentile_interval([np.nan, 1.0, 1.0]) == (1.0, 1.0)
    assert np.isnan(ps.percentile_interval([np.nan])[0])


def test_subset_keeps_the_named_rigs():
    study = toy_study()
    sub = study.subset(["c1", "o2"])
    assert sub.rigs == ("c1", "o2") and list(sub.control) == [True, False]
    assert sub.terms["t"][0, 1] == study.terms["t"][0, 4]
    assert np.isnan(sub.delta[1, 0, 1])
