"""What a calibrated prediction is worth: a bounded link, a prediction interval and the calibration's domain.

The calibrated linear model ``s = K * (alpha * (lt x_t + lr x_r + lf x_f) + (1 - alpha) x_count)`` (the
benchmark's, :meth:`rigopt.metrics.calibration.Calibration.predict`) is unbounded, while a relative mAP drop
saturates at 1. Three pieces turn ``s`` into a number a user can act on, all fitted on the calibration
(control) pairs only, never on held-out pairs:

- :class:`Link`: a monotone, saturating map of ``s`` into [0, 1]. Spearman rho is unchanged by it, so the
  benchmark's published figures keep reproducing from ``s``; MAE and RMSE are reported for both.
- :class:`Interval`: a split-conformal half-width from leave-one-control-rig-out residuals: for every
  control rig, the model (linear fit and link) is refitted on the control pairs that do not involve it, and
  the pairs that do are predicted; the ``level`` quantile of the absolute residuals is the half-width. An
  interval that spans (nearly) the whole range a drop can take says nothing and is reported as
  uninformative (:func:`interval_informative`); :func:`interval_report` measures an interval on held-out
  pairs per predicted-drop bin, beside the best constant predictor.
- :class:`Domain`: the control pairs' features. A pair outside their per-term range, or far from their
  convex hull, is an extrapolation and is flagged with the terms and by how much.

Features everywhere are (P, 4) float: unit-weight (t m, r rad, f deg, count -).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from rigopt.errors import DataError
from rigopt.metrics.drop_model import FEATURE_UNITS

#: Features of a pair, in order, with their units.
TERMS = ("t", "r", "f", "count")
TERM_UNITS = {"t": "m", "r": "rad", "f": "deg", "count": "-"}
#: Units of every term a prediction can be flagged on: the calibration's and a drop model's.
UNITS = {**TERM_UNITS, **FEATURE_UNITS}

#: Link shapes: ``exp`` 1 - exp(-a s); ``hill`` s^b / (c^b + s^b) (a log-logistic in s).
LINKS = ("exp", "hill")

#: Nominal coverage of the shipped prediction intervals.
DEFAULT_LEVEL = 0.9

#: A pair farther than this from the control features' convex hull (in units of each term's control range)
#: counts as an extrapolation even when every term is within its range.
HULL_TOLERANCE = 0.05


@dataclass(frozen=True)
class Link:
    """A monotone map from the linear prediction ``s`` >= 0 to a drop in [0, 1].

    kind : one of LINKS; parameters : ``(a,)`` for exp (1/drop units), ``(b, c)`` for hill (shape, the
    ``s`` at which the drop is 0.5).
    """

    kind: str
    parameters: tuple[float, ...]

    def __call__(self, s) -> np.ndarray:
        """(...,) float in [0, 1] of the linear predictions ``s`` (...,) (negative ``s`` counts as 0)."""
        s = np.maximum(np.asarray(s, dtype=float), 0.0)
        if self.kind == "exp":
            return -np.expm1(-self.parameters[0] * s)
        b, c = self.parameters
        ratio = np.power(s / c, b)
        return ratio / (1.0 + ratio)

    def to_dict(self) -> dict:
        return {"kind": self.kind, "parameters": list(self.parameters)}


def fit_link(s, delta, kind: str = "exp") -> Link:
    """The ``kind`` link minimising sum (link(s) - delta)^2 over calibration pairs; s, delta (P,) float."""
    from scipy.optimize import least_squares

    s, delta = np.maximum(np.asarray(s, dtype=float), 0.0), np.clip(np.asarray(delta, dtype=float), 0.0, 1.0)
    if kind == "exp":
        result = least_squares(lambda p: Link("exp", (p[0],))(s) - delta, x0=[1.0], bounds=([1e-9], [1e6]))
        return Link("exp", (float(result.x[0]),))
    if kind == "hill":
        middle = float(np.median(s[s > 0])) if np.any(s > 0) else 1.0
        result = least_squares(lambda p: Link("hill", (p[0], p[1]))(s) - delta, x0=[1.0, middle],
                               bounds=([0.1, 1e-9], [20.0, 1e6]))
        return Link("hill", (float(result.x[0]), float(result.x[1])))
    raise DataError(f"unknown link {kind!r}; use one of {', '.join(LINKS)}")


@dataclass(frozen=True)
class Interval:
    """A symmetric prediction interval: drop +- ``halfwidth``, nominal coverage ``level``; ``method`` says how
    the half-width was obtained. The high end is clipped at 1 (mAP cannot fall below 0); the low end is not
    clipped at 0, since a rig change can also raise mAP (a negative measured drop)."""

    halfwidth: float
    level: float
    method: str

    def around(self, drop) -> tuple[np.ndarray, np.ndarray]:
        """(low, high), each shaped like ``drop``."""
        drop = np.asarray(drop, dtype=float)
        return drop - self.halfwidth, np.minimum(drop + self.halfwidth, 1.0)

    @property
    def informative(self) -> bool:
        """False when every interval of this half-width is uninformative (:func:`interval_informative`)."""
        return self.halfwidth < UNINFORMATIVE_HALFWIDTH

    def to_dict(self) -> dict:
        return {"halfwidth": self.halfwidth, "level": self.level, "method": self.method}


CONFORMAL_METHOD = "split conformal, leave-one-control-rig-out residuals"

#: An interval is uninformative when, clipped to [0, 1], it covers at least this share of [0, 1], or when its
#: half-width is at least UNINFORMATIVE_HALFWIDTH (for the symmetric Interval the first implies the second).
UNINFORMATIVE_SHARE = 0.9
UNINFORMATIVE_HALFWIDTH = 0.45
#: What every command says in place of an uninformative interval.
UNINFORMATIVE_TEXT = "interval uninformative (wider than the range it could take)"


def interval_informative(low, high, halfwidth=None):
    """Whether intervals (low, high) say something: clipped to [0, 1] they cover less than UNINFORMATIVE_SHARE
    of it, and ``halfwidth`` (when given) is below UNINFORMATIVE_HALFWIDTH.

    low, high : (...,) float, the interval's ends as reported (relative drop); halfwidth : float or (...,).
    Returns a bool for scalar ends, else a (...,) bool array.
    """
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    share = np.clip(np.minimum(high, 1.0) - np.maximum(low, 0.0), 0.0, None)
    informative = share < UNINFORMATIVE_SHARE - 1e-12  # [0.05, 0.95] covers 0.9 despite rounding
    if halfwidth is not None:
        informative = informative & (np.asarray(halfwidth, dtype=float) < UNINFORMATIVE_HALFWIDTH)
    return bool(informative) if informative.ndim == 0 else informative


def conformal_halfwidth(residuals, level: float = DEFAULT_LEVEL) -> float:
    """The split-conformal half-width: the ceil((n + 1) level)-th smallest of n absolute residuals (the
    largest when that exceeds n)."""
    r = np.sort(np.abs(np.asarray(residuals, dtype=float)))
    if len(r) == 0:
        raise DataError("no residuals to size a prediction interval with")
    rank = min(int(np.ceil((len(r) + 1) * level)), len(r))
    return float(r[rank - 1])


def rig_folds(train, test) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """The folds of leave-one-rig-out, by rig: for each rig named in ``train`` or ``test`` (P,) str, in order of
    first appearance, ``(rig, involved, scored)``: ``involved`` (P,) bool the pairs with that rig on either side
    (all left out of the fold's fit, for every detector when pairs of several are stacked), ``scored`` those of
    them that are off-diagonal (predicted by the fold). Rigs whose fold would leave nothing to fit or nothing to
    score are skipped."""
    train, test = np.asarray(train), np.asarray(test)
    folds = []
    for rig in dict.fromkeys(train.tolist() + test.tolist()):
        involved = (train == rig) | (test == rig)
        scored = involved & (train != test)
        if scored.any() and not involved.all():
            folds.append((rig, involved, scored))
    return folds


def leave_one_rig_out_residuals(train, test, delta, fit_and_predict: Callable[[np.ndarray, np.ndarray], np.ndarray]
                                ) -> np.ndarray:
    """Residuals delta - prediction of every off-diagonal calibration pair, each predicted by a model fitted
    without one of its rigs (a pair involving two rigs appears twice). The folds are :func:`rig_folds`: a fold
    drops every pair involving one rig, never single pairs.

    train, test : (P,) str rig names; delta : (P,) float; fit_and_predict(fit_mask (P,) bool, predict_mask
    (P,) bool) -> predictions of the ``predict_mask`` pairs from a model fitted on the ``fit_mask`` pairs.
    """
    delta = np.asarray(delta, dtype=float)
    residuals = [delta[scored] - fit_and_predict(~involved, scored) for _, involved, scored in rig_folds(train, test)]
    if not residuals:
        raise DataError("leave-one-rig-out residuals need at least two rigs in the calibration pairs")
    return np.concatenate(residuals)


@dataclass(frozen=True)
class Extrapolation:
    """How a pair lies outside the calibration data: ``terms`` maps each out-of-range term to (value, low,
    high) of the control range; ``hull_distance`` is its distance from the control features' convex hull in
    units of each term's control range (0 inside)."""

    terms: dict
    hull_distance: float

    @property
    def flagged(self) -> bool:
        return bool(self.terms) or self.hull_distance > HULL_TOLERANCE

    def to_dict(self) -> dict:
        return {"terms": [{"term": t, "value": v, "low": lo, "high": hi, "unit": UNITS[t],
                           "beyond": v - hi if v > hi else v - lo} for t, (v, lo, hi) in self.terms.items()],
                "hull_distance": self.hull_distance}

    def describe(self) -> str:
        """'t 1.37 m > 0.555; 2.10 control ranges from the calibration pairs' (empty when not flagged)."""
        return describe_extrapolation(self.to_dict())


def describe_extrapolation(data: dict) -> str:
    """One line of an Extrapolation in its JSON form (``Extrapolation.to_dict``), for tables and reports."""
    parts = [f"{t['term']} {t['value']:.3g}{'' if t['unit'] == '-' else ' ' + t['unit']} "
             f"{'>' if t['beyond'] > 0 else '<'} {t['high'] if t['beyond'] > 0 else t['low']:.3g}" for t in data["terms"]]
    if data["hull_distance"] > HULL_TOLERANCE:
        parts.append(f"{data['hull_distance']:.2f} control ranges from the calibration pairs")
    return "; ".join(parts)


@dataclass(frozen=True, eq=False)
class Domain:
    """The calibration pairs' features ``points`` (n, 4), distinct rows: what predictions are supported by."""

    points: np.ndarray

    @property
    def low(self) -> np.ndarray:
        return self.points.min(axis=0)

    @property
    def high(self) -> np.ndarray:
        return self.points.max(axis=0)

    def check(self, features) -> list[Extrapolation]:
        """One Extrapolation per row of ``features`` (P, 4)."""
        features = np.atleast_2d(np.asarray(features, dtype=float))
        low, high = self.low, self.high
        scale = np.where(high - low > 0, high - low, 1.0)
        out = []
        for x in features:
            terms = {t: (float(v), float(lo), float(hi)) for t, v, lo, hi in zip(TERMS, x, low, high)
                     if v > hi + 1e-12 or v < lo - 1e-12}
            out.append(Extrapolation(terms, hull_distance(self.points / scale, x / scale)))
        return out

    def to_dict(self) -> dict:
        return {"terms": list(TERMS), "points": np.round(self.points, 9).tolist()}


def hull_distance(points, x) -> float:
    """Euclidean distance from ``x`` (k,) to the convex hull of ``points`` (n, k): min ||P^T w - x|| over
    w >= 0, sum w = 1 (non-negative least squares with the sum enforced by a heavily weighted row)."""
    from scipy.optimize import nnls

    points, x = np.asarray(points, dtype=float), np.asarray(x, dtype=float)
    weight = 1e3 * max(1.0, float(np.abs(points).max()), float(np.abs(x).max()))
    a = np.vstack([points.T, np.full((1, len(points)), weight)])
    w, _ = nnls(a, np.concatenate([x, [weight]]), maxiter=50 * a.shape[1])
    return float(np.linalg.norm(points.T @ w - x))


def domain_of(features: Sequence[Sequence[float]]) -> Domain:
    """The Domain of calibration features (P, 4), duplicate rows dropped."""
    return Domain(np.unique(np.round(np.asarray(features, dtype=float), 9), axis=0))


@dataclass(frozen=True)
class LinkChoice:
    """The link chosen for a calibration and the evidence: ``loro_mae`` maps each candidate link kind to its
    leave-one-control-rig-out mean absolute error on the calibration pairs (the choice is the smallest);
    ``fold_betas`` maps each left-out rig to its fold's linear weights (4,) where the caller records them."""

    link: Link
    interval: Interval
    loro_mae: dict
    fold_betas: dict = field(default_factory=dict)


def choose_link(train, test, delta, refit: Callable[[np.ndarray], Callable[[np.ndarray], np.ndarray]],
                level: float = DEFAULT_LEVEL) -> LinkChoice:
    """Fit every link kind on the calibration pairs, keep the one with the smallest leave-one-rig-out MAE,
    and size its interval from the same residuals.

    train, test : (P,) rig names of the calibration pairs; delta : (P,) their drops; refit(fit_mask) -> a
    function giving the linear predictions of pairs (mask) from the linear model refitted on ``fit_mask``.
    """
    delta = np.asarray(delta, dtype=float)
    everything = np.ones(len(delta), dtype=bool)
    full_linear = refit(everything)(everything)
    residuals, links = {}, {}
    for kind in LINKS:
        links[kind] = fit_link(full_linear, delta, kind)

        def fit_and_predict(fit_mask, predict_mask, kind=kind):
            linear = refit(fit_mask)
            return fit_link(linear(fit_mask), delta[fit_mask], kind)(linear(predict_mask))

        residuals[kind] = leave_one_rig_out_residuals(train, test, delta, fit_and_predict)
    loro_mae = {kind: float(np.mean(np.abs(r))) for kind, r in residuals.items()}
    best = min(LINKS, key=lambda kind: loro_mae[kind])
    interval = Interval(conformal_halfwidth(residuals[best], level), level, CONFORMAL_METHOD)
    return LinkChoice(links[best], interval, loro_mae)


#: Edges of the predicted-drop bins of :func:`interval_report`: [0, 0.25), [0.25, 0.5), [0.5, 0.75), [0.75, 1].
DROP_BIN_EDGES = (0.0, 0.25, 0.5, 0.75, 1.0)


@dataclass(frozen=True)
class IntervalBin:
    """The intervals of the pairs whose predicted drop lies in [``low``, ``high``) ([0.75, 1] for the last bin,
    predicted drops above 1 included): ``n`` pairs; ``coverage`` the share whose measured drop lies in its
    interval; ``mean_width`` the mean length of the interval clipped to [0, 1] (1 = it spans every drop from 0
    to 1); ``clipped`` the share whose interval reaches past 1 (cut there) or below 0; NaN without pairs."""

    low: float
    high: float
    n: int
    coverage: float
    mean_width: float
    clipped: float

    def to_dict(self) -> dict:
        return {"bin": [self.low, self.high], "n": self.n, **{k: _finite(getattr(self, k))
                                                             for k in ("coverage", "mean_width", "clipped")}}


@dataclass(frozen=True)
class IntervalReport:
    """A calibration's prediction intervals judged on pairs it was not fitted on (held-out pairs).

    ``bins``: one IntervalBin per predicted-drop bin (DROP_BIN_EDGES); ``overall``: all pairs; ``halfwidth``
    and ``informative`` (:attr:`Interval.informative`); ``uninformative_share``: the share of the pairs whose
    interval is uninformative; ``bounded_mae``: MAE of the predicted drop; ``constant``: the best constant
    predictor a calibration set gives (the median of its pairs' drops) and ``constant_mae`` its MAE on the same
    pairs; ``oracle_constant_mae``: the MAE of the median of these pairs' own drops, the best any constant can
    do on them (known only afterwards)."""

    bins: tuple[IntervalBin, ...]
    overall: IntervalBin
    halfwidth: float
    informative: bool
    uninformative_share: float
    bounded_mae: float
    constant: float
    constant_mae: float
    oracle_constant_mae: float

    def to_dict(self) -> dict:
        return {"bins": [b.to_dict() for b in self.bins], "overall": self.overall.to_dict(),
                "halfwidth": self.halfwidth, "interval_informative": self.informative,
                "uninformative_share": _finite(self.uninformative_share), "bounded_mae": _finite(self.bounded_mae),
                "constant": _finite(self.constant), "constant_mae": _finite(self.constant_mae),
                "oracle_constant_mae": _finite(self.oracle_constant_mae)}


def _finite(value: float):
    return float(value) if np.isfinite(value) else None


def interval_report(drop, delta, interval: Interval, calibration_delta) -> IntervalReport:
    """How ``interval`` does around the predicted drops ``drop`` (P,) of pairs with measured drops ``delta``
    (P,), per predicted-drop bin and overall, beside the constant median(``calibration_delta``) (the drops of
    the pairs the calibration was fitted on, (Q,))."""
    drop, delta = np.asarray(drop, dtype=float), np.asarray(delta, dtype=float)
    calibration_delta = np.asarray(calibration_delta, dtype=float)
    if drop.shape != delta.shape or drop.ndim != 1 or len(drop) == 0 or len(calibration_delta) == 0:
        raise DataError(f"interval_report needs drop and delta (P,) and calibration drops (Q,), P, Q >= 1; got "
                        f"{drop.shape}, {delta.shape}, {calibration_delta.shape}")
    low, high = interval.around(drop)
    inside = (low <= delta) & (delta <= high)
    width = np.clip(np.minimum(high, 1.0) - np.maximum(low, 0.0), 0.0, None)
    clipped = (drop + interval.halfwidth > 1.0) | (low < 0.0)
    bin_of = np.clip(np.digitize(drop, DROP_BIN_EDGES[1:-1]), 0, len(DROP_BIN_EDGES) - 2)  # above 1: the last

    def summary(mask, lo, hi) -> IntervalBin:
        if not mask.any():
            return IntervalBin(lo, hi, 0, float("nan"), float("nan"), float("nan"))
        return IntervalBin(lo, hi, int(mask.sum()), float(inside[mask].mean()), float(width[mask].mean()),
                           float(clipped[mask].mean()))

    def mae(errors) -> float:
        return float(np.mean(np.abs(errors)))

    bins = tuple(summary(bin_of == k, DROP_BIN_EDGES[k], DROP_BIN_EDGES[k + 1]) for k in range(len(DROP_BIN_EDGES) - 1))
    overall = summary(np.ones(len(drop), dtype=bool), DROP_BIN_EDGES[0], DROP_BIN_EDGES[-1])
    uninformative = ~np.asarray(interval_informative(low, high, interval.halfwidth), dtype=bool)
    constant = float(np.median(calibration_delta))
    return IntervalReport(bins, overall, interval.halfwidth, interval.informative, float(uninformative.mean()),
                          mae(drop - delta), constant, mae(delta - constant), mae(delta - np.median(delta)))
