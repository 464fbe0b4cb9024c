"""Reliability of predictions: Spearman rho, its bootstrap interval, MAE, RMSE and drop ranks.

Oracles: scipy.stats.spearmanr, a plain per-resample bootstrap loop written here, and hand arithmetic.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import spearmanr

from rigopt.metrics.reliability import bootstrap_rho, drop_ranks, reliability, rho_gain, spearman


def loop_bootstrap(predicted, observed, resamples, seed):
    """The definition, one resample at a time."""
    rng = np.random.default_rng(seed)
    n = len(observed)
    rhos = []
    for _ in range(resamples):
        idx = rng.integers(0, n, n)
        p, o = predicted[idx], observed[idx]
        if np.ptp(p) == 0 or np.ptp(o) == 0:
            continue
        rhos.append(spearmanr(p, o).statistic)
    low, high = np.percentile(rhos, [2.5, 97.5])
    return float(low), float(high)


def correlated(n, seed, noise=0.3):
    rng = np.random.default_rng(seed)
    observed = rng.uniform(0.0, 1.0, n)
    return observed + rng.normal(0.0, noise, n), observed


# --- Spearman ---------------------------------------------------------------------------------------


def test_spearman_is_nan_where_rho_is_undefined_and_exact_on_known_orders():
    assert all(math.isnan(v) for v in spearman(np.array([1.0, 2.0]), np.array([2.0, 1.0])))  # < 3 pairs
    assert all(math.isnan(v) for v in spearman(np.array([1.0, 2.0, 3.0]), np.array([5.0, 5.0, 5.0])))
    assert all(math.isnan(v) for v in spearman(np.array([4.0, 4.0, 4.0]), np.array([1.0, 2.0, 3.0])))
    assert spearman(np.array([1.0, 2.0, 3.0, 4.0]), np.array([10.0, 20.0, 30.0, 40.0]))[0] == pytest.approx(1.0)
    assert spearman(np.array([1.0, 2.0, 3.0, 4.0]), np.array([4.0, 3.0, 2.0, 1.0]))[0] == pytest.approx(-1.0)
    # ranks (1, 2, 3, 4) against (2, 1, 4, 3): 1 - 6 * 4 / (4 * 15) = 0.6; with a tie, Pearson of midranks
    assert spearman(np.array([1.0, 2.0, 3.0, 4.0]), np.array([2.0, 1.0, 4.0, 3.0]))[0] == pytest.approx(0.6)
    x, y = np.array([1.0, 1.0, 2.0, 3.0]), np.array([1.0, 2.0, 3.0, 4.0])
    rx, ry = np.array([1.5, 1.5, 3.0, 4.0]), np.array([1.0, 2.0, 3.0, 4.0])
    assert spearman(x, y)[0] == pytest.approx(np.corrcoef(rx, ry)[0, 1], abs=1e-12)


def test_spearman_of_a_monotone_map_is_one():
    x = np.array([0.1, 0.5, 0.2, 0.9, 0.3])
    assert spearman(np.exp(x), x)[0] == pytest.approx(1.0)
    assert spearman(-x, x)[0] == pytest.approx(-1.0)


@pytest.mark.parametrize("predicted, observed", [
    ([0.2, 0.2, 0.2, 0.2], [0.1, 0.4, 0.3, 0.2]),
    ([0.1, 0.4, 0.3, 0.2], [0.5, 0.5, 0.5, 0.5]),
    ([0.1, 0.2], [0.3, 0.1]),
])
def test_spearman_is_nan_for_constant_input_or_fewer_than_three(predicted, observed):
    rho, p = spearman(np.array(predicted), np.array(observed))
    assert math.isnan(rho) and math.isnan(p)


def test_reliability_of_constant_prediction_has_nan_rho_and_ci():
    r = reliability([0.3] * 10, np.linspace(0, 1, 10), resamples=50)
    assert math.isnan(r.rho) and math.isnan(r.p)
    assert all(math.isnan(v) for v in r.ci)
    assert r.to_dict()["rho"] is None and r.to_dict()["ci"] == [None, None]


# --- bootstrap --------------------------------------------------------------------------------------


def test_bootstrap_is_reproducible_with_a_seed():
    predicted, observed = correlated(50, 1)
    assert bootstrap_rho(predicted, observed, 200, seed=7) == bootstrap_rho(predicted, observed, 200, seed=7)


def test_bootstrap_depends_on_the_seed():
    predicted, observed = correlated(50, 1)
    assert bootstrap_rho(predicted, observed, 200, seed=7) != bootstrap_rho(predicted, observed, 200, seed=8)


def test_bootstrap_interval_contains_rho_of_a_strongly_correlated_sample():
    predicted, observed = correlated(80, 2, noise=0.1)
    rho = spearmanr(predicted, observed).statistic
    assert rho > 0.8
    low, high = bootstrap_rho(predicted, observed, 500, seed=0)
    assert low <= rho <= high
    assert high - low < 0.3


@pytest.mark.parametrize("n, seed", [(36, 0), (37, 3), (160, 0), (161, 11), (5, 1)])
def test_vectorised_bootstrap_equals_a_plain_loop(n, seed):
    predicted, observed = correlated(n, seed + 100, noise=0.5)
    assert bootstrap_rho(predicted, observed, 300, seed) == pytest.approx(
        loop_bootstrap(predicted, observed, 300, seed), abs=1e-12)


def test_vectorised_bootstrap_equals_a_plain_loop_with_ties_and_skipped_resamples():
    # Four pairs, two distinct predictions: many resamples are constant and must be skipped the same way.
    predicted = np.array([0.1, 0.1, 0.2, 0.2])
    observed = np.array([0.3, 0.1, 0.4, 0.2])
    assert bootstrap_rho(predicted, observed, 400, 5) == pytest.approx(
        loop_bootstrap(predicted, observed, 400, 5), abs=1e-12)


def test_reliability_uses_the_default_seed_and_1000_resamples():
    predicted, observed = correlated(30, 4)
    assert reliability(predicted, observed).ci == pytest.approx(loop_bootstrap(predicted, observed, 1000, 0),
                                                                abs=1e-12)


def test_bootstrap_without_resamples_is_nan():
    predicted, observed = correlated(10, 0)
    assert all(math.isnan(v) for v in bootstrap_rho(predicted, observed, 0))


# --- MAE, RMSE, ranks -------------------------------------------------------------------------------


def test_mae_and_rmse_by_hand():
    r = reliability([0.1, 0.2, 0.4], [0.0, 0.4, 0.1], resamples=0)
    # errors 0.1, -0.2, 0.3
    assert r.mae == pytest.approx(0.6 / 3)
    assert r.rmse == pytest.approx(math.sqrt(0.14 / 3))
    assert r.n == 3


def test_reliability_rho_by_hand():
    r = reliability([0.1, 0.2, 0.4, 0.3], [0.0, 0.4, 0.1, 0.2], resamples=0)
    # ranks of predicted: 1 2 4 3; of observed: 1 4 2 3; d = 0 -2 2 0; rho = 1 - 6 * 8 / (4 * 15)
    assert r.rho == pytest.approx(1 - 6 * 8 / 60)


def test_drop_ranks_largest_drop_is_rank_one():
    assert drop_ranks([0.1, 0.5, 0.3, -0.2]).tolist() == [3.0, 1.0, 2.0, 4.0]


def test_drop_ranks_average_ties():
    assert drop_ranks([0.5, 0.2, 0.5, 0.1, 0.2, 0.2]).tolist() == [1.5, 4.0, 1.5, 6.0, 4.0, 4.0]


def _rho_gain_by_loop(a, b, o, resamples, seed):
    """The paired bootstrap written plainly: one resample at a time, scipy's Spearman on each side."""
    index = np.random.default_rng(seed).integers(0, len(o), (resamples, len(o)))
    gains = [spearmanr(a[i], o[i]).statistic - spearmanr(b[i], o[i]).statistic for i in index]
    return np.percentile(gains, [2.5, 97.5])


def test_rho_gain_is_the_difference_of_the_two_rhos_with_a_paired_interval():
    rng = np.random.default_rng(7)
    observed = rng.normal(size=80)
    better, worse = observed + rng.normal(0, 0.3, 80), observed + rng.normal(0, 1.5, 80)
    gain, low, high = rho_gain(better, worse, observed, 200, 3)
    assert gain == pytest.approx(spearman(better, observed)[0] - spearman(worse, observed)[0], abs=1e-12)
    assert [low, high] == pytest.approx(_rho_gain_by_loop(better, worse, observed, 200, 3), abs=1e-12)
    assert 0 < low < gain < high  # a clearly better prediction: the interval excludes 0


def test_rho_gain_of_a_prediction_over_itself_is_exactly_zero():
    rng = np.random.default_rng(1)
    observed, predicted = rng.normal(size=30), rng.normal(size=30)
    assert rho_gain(predicted, predicted, observed, 100, 0) == (0.0, 0.0, 0.0)


def test_rho_gain_of_the_reversed_prediction_is_two():
    observed = np.arange(10.0)
    gain, low, high = rho_gain(observed, -observed, observed, 100, 0)
    assert gain == pytest.approx(2.0) and low == pytest.approx(2.0) and high == pytest.approx(2.0)


def _rig_bootstrap_by_hand(predicted, observed, train, test, resamples, seed):
    """The vertex bootstrap spelled out: every ordered pair of drawn rig instances keeps its pairs."""
    from scipy.stats import spearmanr

    rigs = sorted(set(train) | set(test))
    draws = np.random.default_rng(seed).integers(0, len(rigs), (resamples, len(rigs)))
    rhos = []
    for draw in draws:
        keep = [p for i in draw for j in draw for p in range(len(observed))
                if train[p] == rigs[i] and test[p] == rigs[j]]
        o, q = observed[keep], predicted[keep]
        if len(keep) >= 3 and np.ptp(o) > 0 and np.ptp(q) > 0:
            rhos.append(spearmanr(q, o).statistic)
    return tuple(np.percentile(rhos, [2.5, 97.5]))


def test_the_rig_bootstrap_resamples_rigs_and_keeps_their_pairs():
    from rigopt.metrics.reliability import rig_bootstrap_rho

    rng = np.random.default_rng(3)
    names = [f"R{k}" for k in range(6)]
    train, test = map(np.array, zip(*[(a, b) for a in names for b in names if a != b]))
    effect = dict(zip(names, rng.normal(0, 1, 6)))  # a rig effect the pair bootstrap cannot see
    observed = np.array([effect[b] for b in test]) + rng.normal(0, 0.3, len(test))
    predicted = observed + rng.normal(0, 0.8, len(test))
    low, high = rig_bootstrap_rho(predicted, observed, train, test, 300, 1)
    assert (low, high) == pytest.approx(_rig_bootstrap_by_hand(predicted, observed, train, test, 300, 1), abs=1e-12)
    assert rig_bootstrap_rho(observed * 2, observed, train, test, 50, 0) == pytest.approx((1.0, 1.0))
    rel = reliability(predicted, observed, 300, 1, (train, test))
    assert rel.rig_ci == (low, high) and rel.to_dict()["rig_ci"] == [low, high]
    assert "rig_ci" not in reliability(predicted, observed, 50, 1).to_dict()
