"""The rigcd+ fit: non-negative least squares solved two ways, and fit -> rematch -> refit to a fixed point.

The shipped ``--metric rigcd+`` (``rigopt.metrics.protocol.calibrate(..., metric="rigcd+")``) is the
published RigCD whose camera matching uses the calibration's own lambdas. Its weights come from
:func:`fit_rematched`: fit the unit-matching features, set the matching's lambdas to the fitted
(beta_t, beta_r, beta_f), recompute the features under that matching and refit, until the training features
stop changing. The RigCD+ study (``studies/rigcd_plus/``, variant V6) uses the same loop.

Shapes: n training pairs, k features; features (t m, r rad, f deg, count -) for the loop.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from rigopt.errors import RigoptError
from rigopt.metrics.calibration import AGREEMENT_BETA_ATOL, AGREEMENT_OBJECTIVE_RTOL, UNIT_LAMBDAS, fit_lbfgsb, fit_qp

#: Refits after the first before the loop gives up on convergence.
REMATCH_ROUNDS = 10
#: The solvers whose betas a fit can predict with (cvxpy QP, the certified optimum; L-BFGS-B from 0.5).
SOLVERS = ("qp", "lbfgsb")


@dataclass(frozen=True)
class NonnegFit:
    """``min sum (beta . x - delta)^2, beta >= 0`` on n pairs, solved twice.

    ``beta_qp`` (k,) float: cvxpy + HiGHS, the certified optimum; ``beta_lbfgsb`` (k,) float: L-BFGS-B from
    0.5 each; their objectives; ``agrees``: objectives within AGREEMENT_OBJECTIVE_RTOL (relative) and
    betas within AGREEMENT_BETA_ATOL.
    """

    beta_qp: np.ndarray
    beta_lbfgsb: np.ndarray
    objective_qp: float
    objective_lbfgsb: float
    agrees: bool
    n: int

    @property
    def objectives_agree(self) -> bool:
        """The two objectives agree (relative AGREEMENT_OBJECTIVE_RTOL), whether or not the betas do: betas
        that differ at equal objectives mean a non-unique optimum (e.g. a feature that is 0 on every pair)."""
        return _objectives_agree(self.objective_lbfgsb, self.objective_qp)

    def beta(self, solver: str) -> np.ndarray:
        """(k,) float: the betas of ``solver`` ("qp" or "lbfgsb")."""
        if solver not in SOLVERS:
            raise RigoptError(f"unknown solver {solver!r}; use one of {', '.join(SOLVERS)}")
        return self.beta_qp if solver == "qp" else self.beta_lbfgsb


def _objective(beta, x, delta) -> float:
    residual = x @ beta - delta
    return float(residual @ residual)


def _objectives_agree(objective_a, objective_b) -> bool:
    return bool(abs(objective_a - objective_b) <= AGREEMENT_OBJECTIVE_RTOL * max(objective_b, 1e-12))


def _agree(beta_a, beta_b, objective_a, objective_b) -> bool:
    return _objectives_agree(objective_a, objective_b) and bool(
        np.max(np.abs(np.asarray(beta_a) - np.asarray(beta_b))) <= AGREEMENT_BETA_ATOL)


def fit_nonneg(x, delta) -> NonnegFit:
    """Non-negative least squares of delta (n,) on x (n, k), by QP and by L-BFGS-B."""
    x, delta = np.asarray(x, dtype=float), np.asarray(delta, dtype=float)
    if x.ndim != 2 or x.shape[0] != len(delta) or len(delta) == 0:
        raise RigoptError(f"fit_nonneg needs x (n, k) and delta (n,) with n >= 1, got {x.shape} and {delta.shape}")
    beta_q, beta_l = fit_qp(x, delta), np.asarray(fit_lbfgsb(x, delta), dtype=float)
    obj_q, obj_l = _objective(beta_q, x, delta), _objective(beta_l, x, delta)
    return NonnegFit(beta_q, beta_l, obj_q, obj_l, _agree(beta_l, beta_q, obj_l, obj_q), len(delta))


@dataclass(frozen=True)
class RematchFit:
    """The V6 loop's outcome: the kept ``fit`` on features under ``lambdas`` (3,); ``rounds`` refits after the
    first fit; ``converged``: the training features stopped changing; ``objectives`` (QP) of every round."""

    lambdas: tuple[float, float, float]
    fit: NonnegFit
    rounds: int
    converged: bool
    objectives: tuple[float, ...]


def fit_rematched(features_under: Callable[[tuple[float, float, float]], np.ndarray], delta,
                  max_rounds: int = REMATCH_ROUNDS, solver: str = "qp") -> RematchFit:
    """The V6 iteration on one training set.

    ``features_under(lambdas)`` -> (n, 4) float (t, r, f, count) of the training pairs under the matching
    with ``lambdas``; delta (n,). Round 0 fits the unit-matching features; each next round sets the lambdas
    to the last fit's (beta_t, beta_r, beta_f) of ``solver`` (unit when all three are 0), recomputes the
    features and refits. Stops when no training pair's features change (keeping the lambdas that reproduced
    them), or after ``max_rounds`` refits, then keeping the round with the lowest training objective.
    """
    objective = (lambda fit: fit.objective_qp) if solver == "qp" else (lambda fit: fit.objective_lbfgsb)
    lambdas = UNIT_LAMBDAS
    x = np.asarray(features_under(lambdas))
    rounds = [(lambdas, fit_nonneg(x, delta))]
    for _ in range(max_rounds):
        beta = rounds[-1][1].beta(solver)[:3]
        lambdas = tuple(float(b) for b in beta) if np.any(beta > 0) else UNIT_LAMBDAS
        x_next = np.asarray(features_under(lambdas))
        if np.array_equal(x_next, x):
            objectives = tuple(objective(fit) for _, fit in rounds)
            return RematchFit(lambdas, rounds[-1][1], len(rounds) - 1, True, objectives)
        x = x_next
        rounds.append((lambdas, fit_nonneg(x, delta)))
    objectives = tuple(objective(fit) for _, fit in rounds)
    best = int(np.argmin(objectives))
    return RematchFit(rounds[best][0], rounds[best][1], max_rounds, False, objectives)
