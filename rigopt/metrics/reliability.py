"""How well predicted drops track measured ones: Spearman rho with a bootstrap interval, MAE, RMSE, ranks."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import rankdata, spearmanr

DEFAULT_BOOTSTRAP = 1000
DEFAULT_SEED = 0


@dataclass(frozen=True)
class Reliability:
    """Agreement of ``n`` predictions with observations.

    ``rho`` and ``p``: Spearman rank correlation and its two-sided p-value (NaN when either side is
    constant or n < 3); ``ci``: (2.5, 97.5) percentiles of rho over bootstrap resamples of the pairs (the
    benchmark's interval: the rigs held fixed); ``rig_ci``: the same over resamples of the rigs
    (:func:`rig_bootstrap_rho`: what the rho says about other rigs; None when the pairs' rigs are not given);
    ``mae``, ``rmse``: in units of relative drop.
    """

    rho: float
    p: float
    ci: tuple[float, float]
    mae: float
    rmse: float
    n: int
    rig_ci: tuple[float, float] | None = None

    def to_dict(self) -> dict:
        data = {"rho": finite_or_none(self.rho), "p": finite_or_none(self.p),
                "ci": [finite_or_none(v) for v in self.ci], "mae": finite_or_none(self.mae),
                "rmse": finite_or_none(self.rmse), "n": self.n}
        if self.rig_ci is not None:
            data["rig_ci"] = [finite_or_none(v) for v in self.rig_ci]
        return data


def finite_or_none(value: float):
    """The float, or None (JSON null) when it is NaN or infinite."""
    return None if not np.isfinite(value) else float(value)


def spearman(predicted: np.ndarray, observed: np.ndarray) -> tuple[float, float]:
    """Spearman rho and p-value; (nan, nan) when a side is constant or there are fewer than 3 pairs."""
    if len(observed) < 3 or np.ptp(observed) == 0 or np.ptp(predicted) == 0:
        return float("nan"), float("nan")
    result = spearmanr(predicted, observed)
    return float(result.statistic), float(result.pvalue)


def bootstrap_rho(predicted: np.ndarray, observed: np.ndarray, resamples: int = DEFAULT_BOOTSTRAP,
                  seed: int = DEFAULT_SEED) -> tuple[float, float]:
    """95 % interval (2.5, 97.5 percentiles) of Spearman rho over resamples of the pairs with replacement.

    Resamples whose observed or predicted values are constant are skipped; (nan, nan) if none remain.
    """
    rhos = _resampled_rhos([np.asarray(predicted)], np.asarray(observed), resamples, seed)
    return _interval(rhos[0]) if rhos is not None else (float("nan"), float("nan"))


def rho_gain(predicted: np.ndarray, other: np.ndarray, observed: np.ndarray, resamples: int = DEFAULT_BOOTSTRAP,
             seed: int = DEFAULT_SEED) -> tuple[float, float, float]:
    """(gain, low, high): Spearman rho of ``predicted`` (n,) against ``observed`` (n,) minus that of ``other``
    (n,), the same pairs' other prediction, with its 95 % interval over paired resamples of the pairs (both
    predictions judged on the same resample: the interval of the difference, not of either rho)."""
    predicted, other, observed = (np.asarray(v, dtype=float) for v in (predicted, other, observed))
    gain = spearman(predicted, observed)[0] - spearman(other, observed)[0]
    rhos = _resampled_rhos([predicted, other], observed, resamples, seed) if np.isfinite(gain) else None
    return (gain, *(_interval(rhos[0] - rhos[1]) if rhos is not None else (float("nan"), float("nan"))))


def rig_bootstrap_rho(predicted: np.ndarray, observed: np.ndarray, train, test, resamples: int = DEFAULT_BOOTSTRAP,
                      seed: int = DEFAULT_SEED) -> tuple[float, float]:
    """95 % interval of Spearman rho over resamples of the rigs: the rigs named in ``train`` and ``test`` (n,)
    (each pair's two rigs) drawn with replacement, each pair kept as often as the product of its rigs' draws
    (the vertex bootstrap of pairwise data). Unlike :func:`bootstrap_rho`, which holds the rigs fixed, its width
    is what the rho says about other rigs. Resamples with fewer than 3 pairs or a constant side are skipped;
    (nan, nan) if none remain."""
    predicted, observed = np.asarray(predicted, dtype=float), np.asarray(observed, dtype=float)
    rigs, codes = np.unique(np.concatenate([np.asarray(train, dtype=str), np.asarray(test, dtype=str)]),
                            return_inverse=True)
    a, b = codes[:len(observed)], codes[len(observed):]
    if len(observed) < 3 or resamples <= 0:
        return float("nan"), float("nan")
    draws = np.random.default_rng(seed).integers(0, len(rigs), (resamples, len(rigs)))
    rhos = []
    for draw in draws:
        counts = np.bincount(draw, minlength=len(rigs))
        index = np.repeat(np.arange(len(observed)), counts[a] * counts[b])
        if len(index) >= 3 and np.ptp(observed[index]) > 0 and np.ptp(predicted[index]) > 0:
            rhos.append(_pearson_rows(rankdata(predicted[index])[None], rankdata(observed[index])[None])[0])
    return _interval(np.array(rhos)) if rhos else (float("nan"), float("nan"))


def _resampled_rhos(predictions: list[np.ndarray], observed: np.ndarray, resamples: int,
                    seed: int) -> np.ndarray | None:
    """Spearman rho (k, m) of each of k predictions (n,) against ``observed`` (n,) on the same m resamples of
    the pairs with replacement, those where no side is constant; None if there are none (or n < 3)."""
    n = len(observed)
    if n < 3 or resamples <= 0:
        return None
    index = np.random.default_rng(seed).integers(0, n, (resamples, n))
    sides = [p[index] for p in predictions]  # each (resamples, n)
    o = observed[index]
    usable = np.ptp(o, axis=1) > 0
    for side in sides:
        usable &= np.ptp(side, axis=1) > 0
    if not usable.any():
        return None
    ranks = rankdata(o[usable], axis=1)  # Spearman = Pearson of ranks
    return np.stack([_pearson_rows(rankdata(side[usable], axis=1), ranks) for side in sides])


def _interval(values: np.ndarray) -> tuple[float, float]:
    low, high = np.percentile(values, [2.5, 97.5])
    return float(low), float(high)


def _pearson_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pearson correlation of each row of a (m, n) with the same row of b (m, n) -> (m,)."""
    a = a - a.mean(axis=1, keepdims=True)
    b = b - b.mean(axis=1, keepdims=True)
    return np.einsum("ij,ij->i", a, b) / np.sqrt(np.einsum("ij,ij->i", a, a) * np.einsum("ij,ij->i", b, b))


def reliability(predicted, observed, resamples: int = DEFAULT_BOOTSTRAP, seed: int = DEFAULT_SEED,
                rigs: tuple | None = None) -> Reliability:
    """All agreement measures of predictions (n,) against observations (n,); ``rigs`` (train (n,), test (n,)),
    the pairs' rig names, adds the rig-level interval."""
    predicted, observed = np.asarray(predicted, dtype=float), np.asarray(observed, dtype=float)
    rho, p = spearman(predicted, observed)
    error = predicted - observed
    mae = float(np.mean(np.abs(error))) if len(error) else float("nan")
    rmse = float(np.sqrt(np.mean(error**2))) if len(error) else float("nan")
    rig_ci = rig_bootstrap_rho(predicted, observed, *rigs, resamples, seed) if rigs is not None else None
    return Reliability(rho, p, bootstrap_rho(predicted, observed, resamples, seed), mae, rmse, len(observed), rig_ci)


def drop_ranks(drops) -> np.ndarray:
    """Ranks (n,) float of drops, largest drop = rank 1, ties sharing their average rank."""
    return rankdata(-np.asarray(drops, dtype=float), method="average")
