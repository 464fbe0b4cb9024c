"""Agreement of two transfer tables on the same rig pairs: does a synthetic detector lose where a real
one does?

For a model of each table, the relative drops of the off-diagonal (train rig, test rig) pairs that both
tables hold are compared by Spearman rho (with a bootstrap interval over the pairs) and by the mean
absolute difference of the drops.
"""

from __future__ import annotations

import numpy as np

from rigopt.errors import DataError
from rigopt.metrics.reliability import DEFAULT_BOOTSTRAP, DEFAULT_SEED, Reliability, reliability
from rigopt.metrics.transfer import TransferDrops


def shared_drops(a: TransferDrops, model_a: str, b: TransferDrops, model_b: str) -> tuple[list, np.ndarray, np.ndarray]:
    """The off-diagonal pairs (train, test) both hold for their models, in sorted order, and the two
    (P,) drop arrays on them."""
    def by_pair(drops: TransferDrops, model: str) -> dict:
        rows = drops.model == model
        if not rows.any():
            raise DataError(f"no transfer results for model {model!r} (models: {sorted(set(drops.model))})")
        return {(t, s): d for t, s, d in zip(drops.train[rows], drops.test[rows], drops.delta[rows]) if t != s}

    first, second = by_pair(a, model_a), by_pair(b, model_b)
    pairs = sorted(first.keys() & second.keys())
    return pairs, np.array([first[p] for p in pairs]), np.array([second[p] for p in pairs])


def drop_agreement(a: TransferDrops, model_a: str, b: TransferDrops, model_b: str,
                   resamples: int = DEFAULT_BOOTSTRAP, seed: int = DEFAULT_SEED) -> Reliability:
    """Spearman rho (and interval, MAE, RMSE) of ``model_a``'s drops in ``a`` against ``model_b``'s in ``b``
    on their shared off-diagonal pairs."""
    _, first, second = shared_drops(a, model_a, b, model_b)
    return reliability(first, second, resamples, seed)
