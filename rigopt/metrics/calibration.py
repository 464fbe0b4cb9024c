"""Calibrated RigCD: fit non-negative weights that turn rig-pair features into predicted mAP drops.

Features of a pair (A, B) are the unit-weight RigCD components ``x = (t, r, f, count)`` (m, rad, deg, -).
The model ``delta_hat = beta . x`` with ``beta >= 0`` is a non-negative least squares, fitted twice
(:func:`fit_both`): with L-BFGS-B from ``beta0 = (0.5, 0.5, 0.5, 0.5)`` (the benchmark's method, kept to
reproduce its published weights) and exactly with scipy's NNLS (Lawson-Hanson active set: the optimum of the
convex QP, exact zeros, named ``qp`` in the reports), which certifies the first (they must agree). The fit is
reported as

    avg = (beta_t + beta_r + beta_f) / 3,  K = avg + beta_count,  alpha = avg / K,  lambda_x = beta_x / avg
    delta_hat = K (alpha (lt x_t + lr x_r + lf x_f) + (1 - alpha) x_count)

with the fallback alpha = 0.9, lambdas = 1, K = max(avg + beta_count, 1) when ``avg <= 1e-9``.
Predictions always come from (K, alpha, lambdas). That linear prediction is unbounded; a calibration may
also carry a saturating link into [0, 1], a prediction interval and its calibration pairs' domain
(``prediction.py``), which turn it into the predicted drop users see (:meth:`Calibration.drop`).

The published metric and RigCD+ share this model and differ only in the matching under which the features are
measured:

- ``rigcd`` (the published RigCD, the default): the unit-weight matching, lambdas (1, 1, 1);
- ``rigcd+`` (RigCD+ with calibrated matching, variant V6 of ``studies/rigcd_plus``): the matching that
  minimises the calibration's own weighted cost ``lt t + lr r + lf f``, found by iterating fit -> rematch ->
  refit until the training features stop changing (``matched_fit.py``). Its predicted drop is exactly
  K x RigCD under its own weights, the quantity ``rigopt design`` minimises.

A lifting metric (LIFTING_METRICS; ``lifting.py``) keeps RigCD's unit-weight matching and adds per-pair terms for
what a lifting detector's depth network depends on (height, pitch and roll, the depth prior) to the pair cost:
``lifting`` weighs them beside the lambdas. Its weights are fitted and frozen by ``studies/validation`` (a plain
non-negative least squares over the terms, :func:`lifting_calibration` turns them into this form) and its
prediction is linear, clipped to [0, 1] (:meth:`Calibration.bounded_drop`).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Sequence

import numpy as np

from rigopt.errors import DataError, RigoptError, json_loads, not_utf8, unknown_name
from rigopt.metrics.lifting import PAIR_TERMS, TERMS
from rigopt.metrics.prediction import LINKS, Domain, Interval, Link
from rigopt.metrics.rigcd import DEFAULT_ALPHA, rigcd_matrix, tie_broken_lambdas
from rigopt.output import existing_file
from rigopt.resources import data_dir
from rigopt.rig.model import Rig

FEATURES = ("t", "r", "f", "count")
BETA0 = (0.5, 0.5, 0.5, 0.5)
#: Below this the geometric weights are taken as absent and the fallback applies.
AVG_EPSILON = 1e-9
#: Largest difference in fitted objective (relative) and in beta (absolute) for the two fits to agree.
AGREEMENT_OBJECTIVE_RTOL = 1e-6
AGREEMENT_BETA_ATOL = 1e-3
FIT_SOLVERS = ("lbfgsb", "qp")
#: Lifting metrics (see the module docstring): RigCD's matching and terms plus ``lifting.PAIR_TERMS``.
LIFTING_METRICS: tuple[str, ...] = ()
#: The rig distances a calibration can belong to (see the module docstring), and their shipped weights.
METRICS = ("rigcd", "rigcd+") + LIFTING_METRICS
WEIGHTS_FOLDERS = {"rigcd": "weights", "rigcd+": "weights-plus", **{m: f"weights-{m}" for m in LIFTING_METRICS}}
UNIT_LAMBDAS = (1.0, 1.0, 1.0)
#: Features are rounded to this many decimals so that pairs of identical geometry tie exactly whatever
#: the floating-point path (ties change Spearman rho in the fourth decimal); far below any real difference.
FEATURE_DECIMALS = 10


@dataclass(frozen=True)
class Calibration:
    """Calibrated RigCD weights; ``predict`` maps unit-weight features to a relative mAP drop.

    Attributes: ``name``; ``K`` (scale), ``alpha`` in [0, 1], ``lambda_t`` (1/m), ``lambda_r`` (1/rad),
    ``lambda_f`` (1/deg) relative to their mean; ``beta`` (t, r, f, count) the fitted linear weights;
    ``fallback`` true when no geometric weight survived the fit; ``metric`` (one of METRICS) the matching
    its features are measured under: ``rigcd`` unit weights, ``rigcd+`` its own lambdas
    (:attr:`match_lambdas`); ``link``, ``interval``, ``domain``: the bounded link, the prediction interval
    and the calibration pairs' features (None in weights files that predate them: the drop is then the
    linear prediction, unbounded, with no interval); ``lifting`` the weights of ``lifting.PAIR_TERMS`` in the pair
    cost beside the lambdas (a lifting metric's; None for RigCD's).
    """

    name: str
    K: float
    alpha: float
    lambda_t: float
    lambda_r: float
    lambda_f: float
    beta: tuple[float, float, float, float]
    fallback: bool
    metric: str = "rigcd"
    link: Link | None = None
    interval: Interval | None = None
    domain: Domain | None = None
    lifting: tuple[float, ...] | None = None

    @property
    def lambdas(self) -> tuple[float, float, float]:
        return (self.lambda_t, self.lambda_r, self.lambda_f)

    @property
    def match_lambdas(self) -> tuple[float, float, float]:
        """The lambdas of the matching the features are measured under: (1, 1, 1) for rigcd, the
        calibration's own for rigcd+."""
        return self.lambdas if self.metric == "rigcd+" else UNIT_LAMBDAS

    def linear_drop(self, t, r, f, count, extra=None) -> np.ndarray:
        """The linear prediction ``K (alpha (lambda_t t + lambda_r r + lambda_f f) + (1 - alpha) count)``, the score
        the benchmark's calibration fits: unbounded (it can pass 1); t (m), r (rad), f (deg), count (-) are
        broadcastable arrays. A lifting metric adds ``lifting . extra`` to the match, ``extra`` (..., 5) its mean
        matched-pair terms (``lifting.PAIR_TERMS``). The relative mAP drop rigopt reports is :meth:`bounded_drop`."""
        match = self.lambda_t * np.asarray(t) + self.lambda_r * np.asarray(r) + self.lambda_f * np.asarray(f)
        if self.lifting is not None:
            if extra is None:
                raise RigoptError(f"{self.metric} predictions need the lifting terms (rigopt.metrics.lifting)")
            match = match + np.asarray(extra) @ np.asarray(self.lifting)
        return self.K * (self.alpha * match + (1.0 - self.alpha) * np.asarray(count))

    def bounded_drop(self, t, r, f, count, extra=None) -> np.ndarray:
        """The predicted relative mAP drop the commands report: :meth:`linear_drop` through the calibration's
        link (in [0, 1]); without a link the linear prediction itself, clipped to [0, 1] for a lifting metric."""
        linear = self.linear_drop(t, r, f, count, extra)
        if self.link is not None:
            return self.link(linear)
        return np.clip(linear, 0.0, 1.0) if self.lifting is not None else linear

    def knocked_out(self, component: str) -> "Calibration":
        """The same weights with one component removed: lambda_t, lambda_r, lambda_f (set to 0) or count
        (alpha = 1)."""
        if component == "count":
            return _replace(self, alpha=1.0)
        if component in ("lambda_t", "lambda_r", "lambda_f"):
            return _replace(self, **{component: 0.0})
        raise RigoptError(f"unknown knockout component {component!r}; use lambda_t, lambda_r, lambda_f or count")

    def to_dict(self) -> dict:
        data = {k: v for k, v in asdict(self).items() if k not in ("link", "interval", "domain", "lifting")}
        data["beta"] = dict(zip(FEATURES, self.beta))
        if self.lifting is not None:
            data["lifting"] = dict(zip(PAIR_TERMS, self.lifting))
        for key in ("link", "interval", "domain"):
            if getattr(self, key) is not None:
                data[key] = getattr(self, key).to_dict()
        return data


def _replace(calibration: Calibration, **changes) -> Calibration:
    return replace(calibration, **changes)


def reparameterise(beta: Sequence[float], name: str) -> Calibration:
    """The reported (K, alpha, lambdas) of fitted ``beta`` = (t, r, f, count), fallback included."""
    bt, br, bf, bc = (float(b) for b in beta)
    avg = (bt + br + bf) / 3.0
    if avg <= AVG_EPSILON:
        return Calibration(name, max(avg + bc, 1.0), DEFAULT_ALPHA, 1.0, 1.0, 1.0, (bt, br, bf, bc), True)
    k = avg + bc
    return Calibration(name, k, avg / k, bt / avg, br / avg, bf / avg, (bt, br, bf, bc), False)


def lifting_calibration(name: str, weights: dict[str, float], metric: str) -> Calibration:
    """The Calibration of a lifting metric's linear weights ``weights`` {term: weight} over ``lifting.TERMS`` (a
    term left out weighs 0): prediction = sum of weight x term. In this form K alpha = 1, so the lambdas and
    ``lifting`` are the pair cost's weights per unit (1/m, 1/rad, 1/deg, 1/log-m) and K = 1 + the count's weight."""
    unknown = sorted(set(weights) - set(TERMS))
    if unknown or any(not np.isfinite(w) or w < 0 for w in weights.values()):
        raise DataError(f"{name}: lifting weights must be finite and non-negative, over {', '.join(TERMS)}; got "
                        f"{weights}")
    w = {term: float(weights.get(term, 0.0)) for term in TERMS}
    k = 1.0 + w["count"]
    return Calibration(name, k, 1.0 / k, w["t"], w["r"], w["f"], (w["t"], w["r"], w["f"], w["count"]), False,
                       metric, lifting=tuple(w[term] for term in PAIR_TERMS))


def pair_features(rigs: Sequence[Rig], train: Sequence[str], test: Sequence[str],
                  match_lambdas: Sequence[float] = UNIT_LAMBDAS) -> np.ndarray:
    """Features (P, 4) = (t m, r rad, f deg, count) of the pairs (train[p] -> test[p]) under the matching
    with ``match_lambdas`` (unit: the published features; ties broken as ``rigcd.tie_broken_lambdas``),
    rounded to FEATURE_DECIMALS.

    ``rigs`` holds every rig named in ``train`` and ``test`` (matched by ``Rig.name``).
    """
    index = {rig.name: k for k, rig in enumerate(rigs)}
    matrix = rigcd_matrix(rigs, rigs, DEFAULT_ALPHA, tie_broken_lambdas(match_lambdas))
    ia = np.array([index[name] for name in train], dtype=int)
    ib = np.array([index[name] for name in test], dtype=int)
    features = np.stack([getattr(matrix, key)[ia, ib] for key in FEATURES], axis=1)
    return np.round(features, FEATURE_DECIMALS) + 0.0


@dataclass(frozen=True)
class NonnegFit:
    """``min sum (beta . x - delta)^2`` subject to ``beta >= 0`` on n pairs, solved both ways and compared.

    ``beta_qp`` (k,) float: the exact optimum (:func:`fit_nnls`; ``qp``, the convex QP's optimum, in the
    reports); ``beta_lbfgsb`` (k,) float: L-BFGS-B from BETA0 (:func:`fit_lbfgsb`, the benchmark's method);
    their objectives (sums of squared residuals); ``agrees``: objectives within AGREEMENT_OBJECTIVE_RTOL
    (relative) and betas within AGREEMENT_BETA_ATOL.
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
        """(k,) float: the betas of ``solver`` (one of FIT_SOLVERS)."""
        if solver not in FIT_SOLVERS:
            raise RigoptError(f"unknown fit solver {solver!r}; use one of {', '.join(FIT_SOLVERS)}")
        return self.beta_qp if solver == "qp" else self.beta_lbfgsb


@dataclass(frozen=True)
class CalibrationFit:
    """The two fits of one calibration set and the reported weights.

    ``calibration`` uses ``beta_lbfgsb`` or ``beta_qp`` as chosen by ``solver``; ``qp_agrees`` tells
    whether both optima agree within AGREEMENT_OBJECTIVE_RTOL / AGREEMENT_BETA_ATOL (:class:`NonnegFit`).
    ``n`` pairs.
    """

    calibration: Calibration
    solver: str
    beta_lbfgsb: tuple[float, float, float, float]
    beta_qp: tuple[float, float, float, float]
    objective_lbfgsb: float
    objective_qp: float
    qp_agrees: bool
    n: int


def _objective(beta, features, delta) -> float:
    residual = features @ beta - delta
    return float(residual @ residual)


def _objectives_agree(objective_a, objective_b) -> bool:
    return bool(abs(objective_a - objective_b) <= AGREEMENT_OBJECTIVE_RTOL * max(objective_b, 1e-12))


def _checked(features, delta, what: str) -> tuple[np.ndarray, np.ndarray]:
    features, delta = np.asarray(features, dtype=float), np.asarray(delta, dtype=float)
    if features.ndim != 2 or features.shape[0] != len(delta) or len(delta) == 0:
        raise DataError(f"{what} needs features (P, k) and delta (P,) with P >= 1, got {features.shape} and "
                        f"{delta.shape}")
    return features, delta


def fit_lbfgsb(features: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """beta >= 0 minimising sum (beta . x - delta)^2 by L-BFGS-B from BETA0 (0.5 for every feature);
    features (P, k) (k = 4 for RigCD), delta (P,). The benchmark's method: it reproduces the published weights
    (a weight that no pair informs stays at its start 0.5); :func:`fit_nnls` is the exact optimum."""
    from scipy.optimize import minimize

    def value_and_gradient(beta):
        residual = features @ beta - delta
        return float(residual @ residual), 2.0 * features.T @ residual

    start = np.array(BETA0) if features.shape[1] == len(BETA0) else np.full(features.shape[1], BETA0[0])
    result = minimize(value_and_gradient, start, jac=True, method="L-BFGS-B",
                      bounds=[(0.0, None)] * features.shape[1])
    return result.x


def fit_nnls(features: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """(k,) float: the exact optimum of the same least squares with beta >= 0, by scipy's active-set
    non-negative least squares (Lawson-Hanson) on features (P, k), delta (P,): the convex QP's optimum, with
    exact zeros; a weight that no pair informs (a feature that is 0 on every pair) is 0. The certified side of
    every fit (:func:`fit_both`) and the leave-one-rig-out refits of the prediction interval
    (``protocol.fold_calibration``)."""
    from scipy.optimize import nnls

    features, delta = _checked(features, delta, "fit_nnls")
    beta, _ = nnls(features, delta, maxiter=50 * features.shape[1])
    return beta


def fit_both(features, delta) -> NonnegFit:
    """Fit delta (P,) on features (P, k) both ways (:func:`fit_nnls`, :func:`fit_lbfgsb`) and compare."""
    features, delta = _checked(features, delta, "a calibration fit")
    beta_q, beta_l = fit_nnls(features, delta), np.asarray(fit_lbfgsb(features, delta), dtype=float)
    obj_q, obj_l = _objective(beta_q, features, delta), _objective(beta_l, features, delta)
    agrees = _objectives_agree(obj_l, obj_q) and bool(np.max(np.abs(beta_l - beta_q)) <= AGREEMENT_BETA_ATOL)
    return NonnegFit(beta_q, beta_l, obj_q, obj_l, agrees, len(delta))


def fit_calibration(features: np.ndarray, delta: np.ndarray, name: str, solver: str = "lbfgsb") -> CalibrationFit:
    """Fit beta both ways (:func:`fit_both`), check they agree, and reparameterise the ``solver``'s one.

    features : (P, 4) float unit-weight features; delta : (P,) float relative drops.
    """
    if solver not in FIT_SOLVERS:
        raise RigoptError(f"unknown fit solver {solver!r}; use one of {', '.join(FIT_SOLVERS)}")
    if len(delta) == 0:
        raise DataError(f"no calibration pairs for {name!r}: check the control rigs and the results")
    fits = fit_both(features, delta)
    return CalibrationFit(reparameterise(fits.beta(solver), name), solver, tuple(map(float, fits.beta_lbfgsb)),
                          tuple(map(float, fits.beta_qp)), fits.objective_lbfgsb, fits.objective_qp, fits.agrees,
                          fits.n)


# --- Weights files: shipped calibrations and the user's own JSON ---------------------------------------

def check_metric(metric: str) -> str:
    """``metric`` (case-insensitive) as one of METRICS, else an UnknownNameError listing them."""
    by_lower = {m.lower(): m for m in METRICS}
    if str(metric).lower() not in by_lower:
        raise unknown_name("metric", metric, METRICS)
    return by_lower[str(metric).lower()]


def shipped_weight_names(metric: str = "rigcd") -> list[str]:
    """Names of the calibrations shipped for ``metric`` in ``metrics/<WEIGHTS_FOLDERS[metric]>/`` (the four
    detectors and ``joint``)."""
    folder = data_dir("metrics") / WEIGHTS_FOLDERS[check_metric(metric)]
    return sorted(p.stem for p in folder.glob("*.json"))


def write_weights(calibration: Calibration, path) -> Path:
    """Write a weights JSON file; returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(calibration.to_dict(), indent=2) + "\n")
    return path


def load_weights(name_or_path, metric: str = "rigcd") -> Calibration:
    """Calibrated weights of ``metric`` from a shipped name (case-insensitive) or a JSON file written by
    rigopt; a file of the other metric is refused (its predictions would be silently wrong)."""
    metric = check_metric(metric)
    text = str(name_or_path)
    path = Path(text)
    if path.suffix.lower() != ".json" and not path.exists():
        names = shipped_weight_names(metric)
        by_lower = {n.lower(): n for n in names}
        if text.lower() not in by_lower:
            raise unknown_name(f"{metric} weights", text, names)
        path = data_dir("metrics") / WEIGHTS_FOLDERS[metric] / f"{by_lower[text.lower()]}.json"
    existing_file(path, "weights file", "give a shipped name or a JSON file rigopt calibrate wrote",
                  option="--weights", kind=DataError)
    try:
        data = json_loads(path.read_text())
    except OSError as error:
        raise DataError(f"{path}: cannot read the weights file ({error.strerror})") from None
    except UnicodeDecodeError as error:
        raise not_utf8(path, "weights file", error) from None
    except json.JSONDecodeError as error:
        raise DataError(f"{path}: not valid JSON (line {error.lineno}: {error.msg})") from None
    calibration = _calibration_from_dict(data, path)
    if calibration.metric != metric:
        raise DataError(f"{path}: these are {calibration.metric} weights, not {metric}; pass --metric "
                        f"{calibration.metric} or {metric} weights (rigopt calibrate --metric {metric} writes them)")
    return calibration


#: The largest magnitude of any number of a weights file: calibrations are of order 0.01-10 (docs/metrics.md), and
#: beyond this the distances and drops they give overflow into inf and NaN.
MAX_WEIGHT = 1e6


def _calibration_from_dict(data, path: Path) -> Calibration:
    keys = ("K", "alpha", "lambda_t", "lambda_r", "lambda_f")
    if not isinstance(data, dict) or any(k not in data for k in keys):
        raise DataError(f"{path}: a weights file needs the keys {', '.join(keys)}")
    values = {}
    for key in keys:
        value = data[key]
        if (isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value) or value < 0
                or value > MAX_WEIGHT):
            raise DataError(f"{path}: {key} must be a number from 0 to {MAX_WEIGHT:g}, got {value!r}")
        values[key] = float(value)
    if values["alpha"] > 1:
        raise DataError(f"{path}: alpha must be in [0, 1], got {values['alpha']}")
    beta = data.get("beta", {})
    if not isinstance(beta, dict):
        raise DataError(f"{path}: beta must be an object of numbers ({', '.join(FEATURES)}), got {beta!r}")
    for key, value in beta.items():
        if key in FEATURES and (isinstance(value, bool) or not isinstance(value, (int, float))
                                or not abs(value) <= MAX_WEIGHT):
            raise DataError(f"{path}: beta.{key} must be a number within +-{MAX_WEIGHT:g}, got {value!r}; write a "
                            "number or leave the key out")
    beta = tuple(float(beta.get(k, np.nan)) for k in FEATURES)
    metric = data.get("metric", "rigcd")
    if metric not in METRICS:
        raise DataError(f"{path}: metric must be one of {', '.join(METRICS)}, got {metric!r}")
    return Calibration(str(data.get("name", path.stem)), **values, beta=beta, fallback=bool(data.get("fallback", False)),
                       metric=metric, **_prediction_parts(data, path), lifting=_lifting_weights(data, metric, path))


def _lifting_weights(data: dict, metric: str, path: Path) -> tuple[float, ...] | None:
    """The ``lifting`` weights of a lifting metric's file (every term of ``lifting.PAIR_TERMS``, non-negative);
    None for RigCD's metrics, which must not carry them."""
    weights = data.get("lifting")
    if metric not in LIFTING_METRICS:
        if weights is not None:
            raise DataError(f"{path}: 'lifting' weights belong to a lifting metric ({', '.join(LIFTING_METRICS)}), "
                            f"not {metric}; remove them or set the metric")
        return None
    if not isinstance(weights, dict) or set(weights) != set(PAIR_TERMS) or any(
            isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v) or v < 0
            for v in weights.values()):
        raise DataError(f"{path}: a {metric} weights file needs 'lifting': an object of non-negative numbers for "
                        f"{', '.join(PAIR_TERMS)}")
    return tuple(float(weights[term]) for term in PAIR_TERMS)


def _prediction_parts(data: dict, path: Path) -> dict:
    """The optional link, interval and domain of a weights file, checked."""
    parts = {}
    try:
        if "link" in data:
            link = data["link"]
            kind, parameters = link["kind"], tuple(float(v) for v in link["parameters"])
            if kind not in LINKS or len(parameters) != (1 if kind == "exp" else 2) or not all(
                    np.isfinite(v) and 0 < v <= MAX_WEIGHT for v in parameters):
                raise ValueError
            parts["link"] = Link(kind, parameters)
        if "interval" in data:
            interval = data["interval"]
            halfwidth, level = float(interval["halfwidth"]), float(interval["level"])
            if not (np.isfinite(halfwidth) and halfwidth >= 0 and 0 < level < 1):
                raise ValueError
            parts["interval"] = Interval(halfwidth, level, str(interval.get("method", "")))
        if "domain" in data:
            points = np.array(data["domain"]["points"], dtype=float)
            if points.ndim != 2 or points.shape[1] != len(FEATURES) or len(points) == 0 or not np.isfinite(points).all():
                raise ValueError
            parts["domain"] = Domain(points)
    except (KeyError, TypeError, ValueError):
        raise DataError(f"{path}: 'link', 'interval' or 'domain' is malformed; write them as rigopt calibrate does "
                        "(link {kind: exp|hill, parameters}, interval {halfwidth, level}, domain {points: [[t, r, f, "
                        "count], ...]}) or leave them out") from None
    return parts
