"""rigopt.metrics.matched_fit: the non-negative fit solved two ways and the fit -> rematch -> refit loop of
the shipped rigcd+ metric, on cases with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.errors import RigoptError
from rigopt.metrics.calibration import UNIT_LAMBDAS
from rigopt.metrics.matched_fit import fit_nonneg, fit_rematched


def test_nonneg_fit_recovers_known_betas():
    rng = np.random.default_rng(1)
    x = rng.uniform(0, 1, (40, 5))
    beta = np.array([0.3, 0.0, 1.2, 0.05, 0.0])
    fit = fit_nonneg(x, x @ beta)
    np.testing.assert_allclose(fit.beta_qp, beta, atol=1e-6)
    np.testing.assert_allclose(fit.beta_lbfgsb, beta, atol=1e-4)
    assert fit.objective_qp < 1e-10 and fit.n == 40


def test_nonneg_fit_solvers_agree_on_noisy_data():
    rng = np.random.default_rng(4)
    x = rng.uniform(0, 1, (60, 4))
    fit = fit_nonneg(x, x @ np.array([0.5, 0.0, 0.2, 1.0]) + rng.normal(0, 0.01, 60))
    assert fit.agrees and fit.beta_qp[1] < 0.01
    np.testing.assert_allclose(fit.beta_qp, [0.5, 0.0, 0.2, 1.0], atol=0.02)


def test_nonneg_fit_clips_a_negative_direction_to_zero():
    # delta = 3 - x: the unconstrained slope is -1; with slope >= 0 the optimum is slope 0, intercept mean = 1
    x = np.stack([np.ones(5), np.arange(5.0)], axis=1)
    fit = fit_nonneg(x, 3.0 - np.arange(5.0))
    np.testing.assert_allclose(fit.beta_qp, [1.0, 0.0], atol=1e-7)
    assert fit.beta_qp[1] == 0.0 and fit.agrees


def test_nonneg_fit_rejects_mismatched_shapes():
    with pytest.raises(RigoptError, match="x \\(n, k\\)"):
        fit_nonneg(np.ones((3, 2)), np.ones(4))


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


def test_a_feature_that_is_zero_everywhere_is_a_non_unique_optimum():
    # column 2 is 0 on every pair: QP returns 0 for it, L-BFGS-B keeps its start 0.5, at the same objective
    x = np.stack([np.arange(6.0), np.zeros(6)], axis=1)
    fit = fit_nonneg(x, 0.2 * np.arange(6.0) + np.array([0.01, -0.01] * 3))
    assert fit.beta_qp[1] == 0.0 and fit.beta_lbfgsb[1] == pytest.approx(0.5)
    assert fit.objectives_agree and not fit.agrees
