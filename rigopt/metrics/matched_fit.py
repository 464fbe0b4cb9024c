"""The rigcd+ fit: fit -> rematch -> refit to a fixed point.

The shipped ``--metric rigcd+`` (``rigopt.metrics.protocol.calibrate(..., metric="rigcd+")``) is the
published RigCD whose camera matching uses the calibration's own lambdas. Its weights come from
:func:`fit_rematched`: fit the unit-matching features, set the matching's lambdas to the fitted
(beta_t, beta_r, beta_f), recompute the features under that matching and refit, until the training features
stop changing. Every fit is the non-negative least squares solved both ways
(:func:`rigopt.metrics.calibration.fit_both`). The RigCD+ study (``studies/rigcd_plus/``, variant V6) uses the
same loop.

Shapes: n training pairs, k features; features (t m, r rad, f deg, count -) for the loop.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from rigopt.metrics.calibration import UNIT_LAMBDAS, NonnegFit, fit_both

#: Refits after the first before the loop gives up on convergence.
REMATCH_ROUNDS = 10


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
    rounds = [(lambdas, fit_both(x, delta))]
    for _ in range(max_rounds):
        beta = rounds[-1][1].beta(solver)[:3]
        lambdas = tuple(float(b) for b in beta) if np.any(beta > 0) else UNIT_LAMBDAS
        x_next = np.asarray(features_under(lambdas))
        if np.array_equal(x_next, x):
            objectives = tuple(objective(fit) for _, fit in rounds)
            return RematchFit(lambdas, rounds[-1][1], len(rounds) - 1, True, objectives)
        x = x_next
        rounds.append((lambdas, fit_both(x, delta)))
    objectives = tuple(objective(fit) for _, fit in rounds)
    best = int(np.argmin(objectives))
    return RematchFit(rounds[best][0], rounds[best][1], max_rounds, False, objectives)
