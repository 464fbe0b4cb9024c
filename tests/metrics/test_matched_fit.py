"""rigopt.metrics.matched_fit: the fit -> rematch -> refit loop of the shipped rigcd+ metric, on cases with
known answers (its fits, calibration.fit_both, are tested in test_calibration.py)."""

from __future__ import annotations

import numpy as np

from rigopt.metrics.calibration import UNIT_LAMBDAS
from rigopt.metrics.matched_fit import fit_rematched


def test_rematch_loop_stops_when_features_stop_changing():
    # the matching (so the features) changes once: t halves under the unit lambdas, not when lambda_t > lambda_r
    delta = np.array([0.0, 1.0, 2.0, 3.0])
    calls = []

    def features_under(lambdas):
        calls.append(tuple(lambdas))
        t = delta / 2 if lambdas == UNIT_LAMBDAS else delta.copy()
        return np.stack([t, np.zeros(4), np.zeros(4), np.zeros(4)], axis=1)

    loop = fit_rematched(features_under, delta)
    assert loop.converged and loop.rounds == 1 and len(calls) == 3
    np.testing.assert_allclose(calls[1], [2.0, 0.0, 0.0], atol=1e-6)  # round 0 fitted beta_t = 2 on t / 2
    np.testing.assert_allclose(loop.lambdas, [1.0, 0.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(loop.fit.beta_qp, [1, 0, 0, 0], atol=1e-6)


def test_rematch_loop_with_all_zero_betas_keeps_the_unit_matching():
    x = np.zeros((4, 4))
    x[:, 3] = [0, 1, 1, 0]
    loop = fit_rematched(lambda lambdas: x, np.array([0.0, 1.0, 1.0, 0.0]))
    assert loop.converged and loop.lambdas == UNIT_LAMBDAS


def test_rematch_loop_without_convergence_keeps_the_lowest_objective():
    rng = np.random.default_rng(0)
    delta = rng.uniform(0, 1, 6)
    counter = iter(range(100))

    def features_under(lambdas):  # changes every call; round k fits delta to within 1 / (k + 1)
        k = next(counter)
        return np.stack([delta + rng.normal(0, 1.0 / (k + 1), 6), np.zeros(6), np.zeros(6), np.zeros(6)], axis=1)

    loop = fit_rematched(features_under, delta, max_rounds=3)
    assert not loop.converged and loop.rounds == 3 and len(loop.objectives) == 4
    assert loop.fit.objective_qp == min(loop.objectives)
