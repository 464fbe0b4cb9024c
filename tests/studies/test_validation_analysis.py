"""The validation study's statistics (studies/validation/analysis.py) on hand-made data."""

from __future__ import annotations

import analysis
import numpy as np
import pytest
from scipy.stats import spearmanr


def test_batched_spearman_matches_scipy_with_ties():
    rng = np.random.default_rng(3)
    x = rng.integers(0, 5, size=(50, 9)).astype(float)  # many ties
    y = rng.normal(size=(50, 9))
    expected = [spearmanr(a, b)[0] for a, b in zip(x, y)]
    assert np.allclose(analysis.spearman(x, y), expected, equal_nan=True)
    assert np.isnan(analysis.spearman(np.ones(4), np.arange(4.0)))


def test_bootstrap_draws_stay_within_their_vehicle():
    groups = np.array(["a"] * 4 + ["b"] * 3)
    draws = analysis.bootstrap_draws(groups, resamples=200, seed=1)
    assert draws.shape == (200, 7)
    assert np.all(draws[:, :4] < 4) and np.all(draws[:, 4:] >= 4)
    assert len(np.unique(draws[:, :4])) == 4  # every rig of a group gets drawn somewhere


def test_permutation_p_of_a_perfect_order_is_one_over_n_factorial():
    predicted = np.arange(5.0)
    p = analysis.permutation_p(predicted, predicted * 2, np.array(["a"] * 5), permutations=60_000, seed=2)
    assert p["a"] == pytest.approx(1 / 120, abs=0.002)
    reversed_p = analysis.permutation_p(predicted, -predicted, np.array(["a"] * 5), permutations=2000, seed=2)
    assert reversed_p["a"] == 1.0


def test_resampled_rhos_of_the_identity_draw_are_the_observed_ones():
    groups = np.array(["a"] * 5 + ["b"] * 5)
    rng = np.random.default_rng(0)
    predicted, measured = rng.normal(size=10), rng.normal(size=10)
    draws = np.arange(10)[None]
    out = analysis.resampled_rhos(predicted, measured, groups, draws)
    rho = analysis.within_vehicle_rho(predicted, measured, groups)
    assert out["a"][0] == pytest.approx(rho["a"]) and out["b"][0] == pytest.approx(rho["b"])
    assert out["mean"][0] == pytest.approx((rho["a"] + rho["b"]) / 2)


def _case(strengths: dict[str, float], n=12, vehicles=("a", "b", "c")):
    """Predictions of candidates that follow the measured drops with noise of the given size."""
    rng = np.random.default_rng(5)
    groups = np.repeat(vehicles, n)
    measured = rng.normal(size=len(groups))
    predicted = {c: measured + s * rng.normal(size=len(groups)) for c, s in strengths.items()}
    draws = analysis.bootstrap_draws(groups, resamples=500, seed=0)
    resampled = {c: analysis.resampled_rhos(p, measured, groups, draws) for c, p in predicted.items()}
    observed = {}
    for c, p in predicted.items():
        rho = analysis.within_vehicle_rho(p, measured, groups)
        observed[c] = {**rho, "mean": float(np.mean(list(rho.values())))}
    return resampled, observed, list(vehicles)


def test_the_rule_ships_a_clearly_better_candidate_and_nothing_when_none_is():
    resampled, observed, vehicles = _case({"base": 8.0, "good": 0.1, "same": 8.0}, n=16)
    decision = analysis.decide(resampled, observed, vehicles, new=("good", "same"), baseline="base")
    assert decision["level"] == pytest.approx(0.975)
    assert decision["ships"] == "good" and decision["designer_default"]
    assert not decision["candidates"]["same"]["beats_baseline"]
    resampled, observed, vehicles = _case({"base": 0.1, "worse": 3.0})
    decision = analysis.decide(resampled, observed, vehicles, new=("worse",), baseline="base")
    assert decision["ships"] is None and not decision["designer_default"]


def test_the_results_page_shows_every_candidate_and_the_decision():
    groups = ["a", "b"]
    rho = {"a": 0.5, "b": 0.7, "mean": 0.6, "pooled": 0.55}
    entry = {"rho": rho, "rho_ci": {k: [v - 0.2, v + 0.1] for k, v in rho.items()},
             "rho_visible_only": {**rho, "mean": 0.4}, "permutation_p": {"mean": 0.0123},
             "difference_to_rigcd": {k: {"value": 0.25, "ci": [0.05, 0.4]} for k in [*groups, "mean", "pooled"]}}
    report = {"rigs": 6, "per_vehicle": {"a": 3, "b": 3},
              "candidates": {analysis.BASELINE: entry, "split": entry},
              "decision": {"level": 0.9875, "ships": "split", "designer_default": False,
                           "candidates": {"split": {"mean_rho": 0.6, "difference_lower_bound": 0.01,
                                                    "per_vehicle_lower_bounds": {"a": -0.1, "b": 0.2},
                                                    "beats_baseline": True}}}}
    page = analysis.markdown(report, groups)
    assert "| split | 0.600 [0.400, 0.700] | 0.500 [0.300, 0.600] | 0.700 [0.500, 0.800] |" in page
    assert f"| {analysis.BASELINE} | 0.600" in page and "| 0.01230 | - |" in page
    assert "| split | 0.600 | +0.010 | a -0.100, b +0.200 | yes |" in page
    assert "Ships: split; the designer's default objective for lifting detectors: no." in page
