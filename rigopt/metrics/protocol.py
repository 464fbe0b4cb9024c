"""The benchmark's calibration protocol: fit on control-rig pairs, evaluate on held-out pairs.

The calibration set of a detector is every pair whose training and test rigs are both control rigs
(diagonal included); the held-out set is every other pair. Each detector is fitted on its own, and all
detectors jointly (calibration pairs stacked, one beta) with each detector then evaluated separately.
Component knockout re-evaluates held-out rho with one fitted component removed (no refit, features kept).

``metric="rigcd+"`` fits RigCD+ (calibrated matching; ``calibration.py``) instead: each fit iterates fit ->
rematch under its lambdas -> refit on its own calibration pairs (``matched_fit.fit_rematched``), and its pairs are predicted from the
features under its final lambdas.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Sequence

import numpy as np

from rigopt.errors import DataError, RigoptError
from rigopt.metrics.calibration import (LIFTING_METRICS, UNIT_LAMBDAS, Calibration, CalibrationFit, check_metric,
                                       fit_calibration, fit_nnls, pair_features, reparameterise)
from rigopt.metrics.matched_fit import fit_rematched
from rigopt.metrics.prediction import (IntervalReport, LinkChoice, choose_link, domain_of, interval_report,
                                       rig_folds)
from rigopt.metrics.reliability import (DEFAULT_BOOTSTRAP, DEFAULT_SEED, Reliability, drop_ranks, finite_or_none,
                                        reliability, rho_gain, spearman)
from rigopt.metrics.transfer import TransferDrops, TransferTable
from rigopt.rig.library import load_rig
from rigopt.rig.model import Rig

CONTROL_RIGS = ("R1", "R1-c10", "R1-c6", "R1-f", "R1-r", "R1-t")
KNOCKOUTS = ("lambda_t", "lambda_r", "lambda_f", "count")
JOINT = "joint"


@dataclass(frozen=True)
class PairPredictions:
    """Every evaluated pair; arrays (P,) unless stated.

    ``features`` (P, 4): unit-weight (t m, r rad, f deg, count); ``delta``: observed relative drop;
    ``predicted``: calibrated prediction; ``control``: both rigs are control rigs;
    ``rank_observed`` / ``rank_predicted``: rank of the drop among the test rigs of the same
    (model, training rig), largest drop = 1, ties averaged; ``drop``, ``low``, ``high``: the bounded
    predicted drop and its interval (the linear prediction and no interval without a link).
    """

    model: np.ndarray
    train: np.ndarray
    test: np.ndarray
    features: np.ndarray
    delta: np.ndarray
    predicted: np.ndarray
    control: np.ndarray
    rank_observed: np.ndarray
    rank_predicted: np.ndarray
    drop: np.ndarray
    low: np.ndarray
    high: np.ndarray

    @property
    def rank_error(self) -> np.ndarray:
        """(P,) float: predicted rank - observed rank."""
        return self.rank_predicted - self.rank_observed


@dataclass(frozen=True)
class BoundedAccuracy:
    """The bounded drop's errors on ``n`` pairs: ``mae``, ``rmse`` (relative drop) and ``coverage``, the
    fraction of pairs whose measured drop lies in the prediction interval (NaN without one)."""

    mae: float
    rmse: float
    coverage: float
    n: int

    def to_dict(self) -> dict:
        return {"mae": finite_or_none(self.mae), "rmse": finite_or_none(self.rmse),
                "interval_coverage": finite_or_none(self.coverage), "n": self.n}


def bounded_accuracy(pairs: "PairPredictions", mask: np.ndarray) -> BoundedAccuracy:
    if not mask.any():  # e.g. no held-out pair when every rig is a control rig
        return BoundedAccuracy(float("nan"), float("nan"), float("nan"), 0)
    error = pairs.drop[mask] - pairs.delta[mask]
    inside = (pairs.low[mask] <= pairs.delta[mask]) & (pairs.delta[mask] <= pairs.high[mask])
    covered = float(inside.mean()) if np.isfinite(pairs.low[mask]).all() else float("nan")
    return BoundedAccuracy(float(np.mean(np.abs(error))), float(np.sqrt(np.mean(error ** 2))), covered, int(mask.sum()))


@dataclass(frozen=True)
class Knockout:
    """Held-out rho of the full fitted metric and with each component removed."""

    full: float
    lambda_t: float
    lambda_r: float
    lambda_f: float
    count: float


@dataclass(frozen=True)
class ModelCalibration:
    """One detector's own fit and its reliability on control and held-out pairs."""

    model: str
    fit: CalibrationFit
    control: Reliability
    heldout: Reliability
    knockout: Knockout
    pairs: PairPredictions
    bounded_control: BoundedAccuracy
    bounded_heldout: BoundedAccuracy
    link_choice: LinkChoice
    #: The prediction interval judged on the held-out pairs, per predicted-drop bin (None without held-out pairs).
    interval_heldout: IntervalReport | None = None


@dataclass(frozen=True)
class ModelReliability:
    """One detector's pairs evaluated under the joint fit."""

    model: str
    control: Reliability
    heldout: Reliability
    bounded_control: BoundedAccuracy
    bounded_heldout: BoundedAccuracy
    #: The prediction interval judged on the held-out pairs, per predicted-drop bin (None without held-out pairs
    #: or without the calibration's own calibration pairs, as for a calibration judged on other data).
    interval_heldout: IntervalReport | None = None


@dataclass(frozen=True)
class JointCalibration:
    """The joint fit over every detector's calibration pairs, evaluated per detector."""

    fit: CalibrationFit
    models: tuple[ModelReliability, ...]
    pairs: PairPredictions
    link_choice: LinkChoice


@dataclass(frozen=True)
class CalibrationStudy:
    """The whole protocol's outcome; ``skipped`` lists (model, training rig) pairs without a positive own mAP."""

    control_rigs: tuple[str, ...]
    models: tuple[ModelCalibration, ...]
    joint: JointCalibration
    skipped: tuple[tuple[str, str], ...]
    metric: str = "rigcd"


def _predictions(drops: TransferDrops, features: np.ndarray, calibration: Calibration,
                 control: np.ndarray) -> PairPredictions:
    predicted = calibration.linear_drop(*features.T)
    drop = calibration.bounded_drop(*features.T)
    low, high = calibration.interval.around(drop) if calibration.interval else (np.full_like(drop, np.nan),) * 2
    rank_observed, rank_predicted = np.zeros(len(predicted)), np.zeros(len(predicted))
    groups = {}
    for k, key in enumerate(zip(drops.model, drops.train)):
        groups.setdefault(key, []).append(k)
    for rows in groups.values():
        rank_observed[rows] = drop_ranks(drops.delta[rows])
        rank_predicted[rows] = drop_ranks(predicted[rows])
    return PairPredictions(drops.model, drops.train, drops.test, features, drops.delta, predicted, control,
                           rank_observed, rank_predicted, drop, low, high)


def _split_reliability(pairs: PairPredictions, resamples: int, seed: int) -> tuple[Reliability, Reliability]:
    return tuple(reliability(pairs.predicted[mask], pairs.delta[mask], resamples, seed,
                             (pairs.train[mask], pairs.test[mask])) for mask in (pairs.control, ~pairs.control))


def _knockout(calibration: Calibration, pairs: PairPredictions) -> Knockout:
    held = ~pairs.control
    x, delta = pairs.features[held], pairs.delta[held]
    rhos = {name: spearman(calibration.knocked_out(name).linear_drop(*x.T), delta)[0] for name in KNOCKOUTS}
    return Knockout(full=spearman(calibration.linear_drop(*x.T), delta)[0], **rhos)


def refuse_lifting(metric: str) -> str:
    """``metric`` checked (:func:`check_metric`) and refused when it is a lifting metric, whose weights the
    validation study fitted and froze (studies/validation/candidates.py): this protocol fits rigcd and rigcd+."""
    metric = check_metric(metric)
    if metric in LIFTING_METRICS:
        raise RigoptError(f"rigopt calibrate fits rigcd and rigcd+; {metric}'s weights were fitted and frozen by the "
                          "validation study (studies/validation/candidates.py): use --metric rigcd or rigcd+")
    return metric


def calibrate(table: TransferTable, control_rigs: Sequence[str] = CONTROL_RIGS,
              rig_lookup: Callable[[str], Rig] = load_rig, resamples: int = DEFAULT_BOOTSTRAP,
              seed: int = DEFAULT_SEED, solver: str = "lbfgsb", metric: str = "rigcd") -> CalibrationStudy:
    """Run the protocol on measured transfer ``table`` for ``metric`` (rigcd or rigcd+); rigs are resolved
    by name with ``rig_lookup``."""
    metric = refuse_lifting(metric)
    control_rigs = tuple(control_rigs)
    drops = table.drops()
    if len(drops.delta) == 0:
        raise DataError("no pair has a training rig with a positive own mAP; nothing to calibrate")
    rig_names = list(dict.fromkeys(drops.train.tolist() + drops.test.tolist()))
    rigs = [_named(rig_lookup(name), name) for name in rig_names]
    features_under = _features_under(rigs, drops.train, drops.test)
    control = np.isin(drops.train, control_rigs) & np.isin(drops.test, control_rigs)
    if not control.any():
        raise DataError(f"no pair has both rigs among the control rigs {', '.join(control_rigs)}; "
                        "name control rigs present in the results with --control")

    models = []
    for model in dict.fromkeys(drops.model.tolist()):
        mine = drops.model == model
        fit, features = _fit(features_under, mine & control, drops.delta, model, solver, metric)
        fit, choice = _with_link(fit, features, mine & control, drops, solver)
        pairs = _predictions(drops.select(mine), features[mine], fit.calibration, control[mine])
        control_rel, heldout_rel = _split_reliability(pairs, resamples, seed)
        models.append(ModelCalibration(model, fit, control_rel, heldout_rel, _knockout(fit.calibration, pairs), pairs,
                                       bounded_accuracy(pairs, pairs.control), bounded_accuracy(pairs, ~pairs.control),
                                       choice, _interval_heldout(pairs, fit.calibration, drops.delta[mine & control])))

    joint_fit, features = _fit(features_under, control, drops.delta, JOINT, solver, metric)
    joint_fit, joint_choice = _with_link(joint_fit, features, control, drops, solver)
    joint_pairs = _predictions(drops, features, joint_fit.calibration, control)
    per_model = []
    for model in dict.fromkeys(drops.model.tolist()):
        mine = joint_pairs.model == model
        subset = PairPredictions(*(getattr(joint_pairs, f)[mine] for f in PairPredictions.__dataclass_fields__))
        per_model.append(ModelReliability(model, *_split_reliability(subset, resamples, seed),
                                          bounded_accuracy(subset, subset.control),
                                          bounded_accuracy(subset, ~subset.control),
                                          _interval_heldout(subset, joint_fit.calibration, drops.delta[control])))
    joint = JointCalibration(joint_fit, tuple(per_model), joint_pairs, joint_choice)
    return CalibrationStudy(control_rigs, tuple(models), joint, drops.skipped, metric)


def _features_under(rigs: Sequence[Rig], train, test) -> Callable[[Sequence[float]], np.ndarray]:
    """A cached function: match lambdas (3,) -> (P, 4) features of every pair (``pair_features``)."""
    cache: dict[tuple[float, ...], np.ndarray] = {}

    def features(match_lambdas) -> np.ndarray:
        key = tuple(float(v) for v in match_lambdas)
        if key not in cache:
            cache[key] = pair_features(rigs, train, test, key)
        return cache[key]

    return features


def _fit(features_under, mask: np.ndarray, delta: np.ndarray, name: str, solver: str,
         metric: str) -> tuple[CalibrationFit, np.ndarray]:
    """The fit of ``metric`` on the pairs in ``mask`` (P,) bool, and the (P, 4) features that it predicts
    every pair from."""
    if metric == "rigcd":
        return fit_calibration(features_under(UNIT_LAMBDAS)[mask], delta[mask], name, solver), features_under(UNIT_LAMBDAS)
    rematch = fit_rematched(lambda lambdas: features_under(lambdas)[mask], delta[mask], solver=solver)
    fit = fit_calibration(features_under(rematch.lambdas)[mask], delta[mask], name, solver)
    fit = replace(fit, calibration=replace(fit.calibration, metric=metric))
    return fit, features_under(fit.calibration.match_lambdas)


def _interval_heldout(pairs: PairPredictions, calibration: Calibration,
                      calibration_delta: np.ndarray) -> IntervalReport | None:
    """``calibration``'s interval on the held-out pairs of ``pairs`` beside the constant median(calibration_delta)
    (the drops of the pairs it was fitted on); None without an interval or held-out pairs."""
    held = ~pairs.control
    if calibration.interval is None or not held.any():
        return None
    return interval_report(pairs.drop[held], pairs.delta[held], calibration.interval, calibration_delta)


def fold_calibration(x: np.ndarray, delta: np.ndarray, name: str) -> Calibration:
    """The linear weights of one leave-one-rig-out fold: the exact non-negative least squares optimum
    (:func:`rigopt.metrics.calibration.fit_nnls`) on the fold's pairs, x (n, 4), delta (n,), reparameterised
    as every fit is (the fallback included), whatever solver the reported weights use. L-BFGS-B from 0.5 would
    leave a weight that the fold's pairs cannot inform at its start value (beta_f when R1-f, the one control rig
    with another FOV, is left out: every remaining pair has f = 0) and so predict the left-out rig's pairs from a
    weight no data chose; the exact optimum sets it to 0."""
    return reparameterise(fit_nnls(x, delta), name)


def _with_link(fit: CalibrationFit, features: np.ndarray, mask: np.ndarray, drops: TransferDrops,
               solver: str) -> tuple[CalibrationFit, LinkChoice]:
    """``fit`` with its calibration given a link, an interval and a domain, all from the pairs in ``mask``.

    The link is fitted to the reported weights' linear predictions of those pairs (``solver``'s fit, refitted
    on the features as they are). The interval's leave-one-rig-out folds are by rig (``prediction.rig_folds``:
    a fold drops every pair that involves one control rig, for every detector in a joint fit) and each fold's
    weights are :func:`fold_calibration`, the exact optimum, whatever ``solver`` is; for rigcd+ they are
    refitted on the features under the final lambdas (the rematching is not repeated per fold). The folds'
    betas are kept in the returned LinkChoice's ``fold_betas`` (left-out rig -> (4,) beta)."""
    x, delta = features[mask], drops.delta[mask]
    cache: dict[bytes, Calibration] = {}

    def refit(fit_mask: np.ndarray):
        key = fit_mask.tobytes()
        if key not in cache:
            cache[key] = (fit_calibration(x, delta, fit.calibration.name, solver).calibration if fit_mask.all()
                          else fold_calibration(x[fit_mask], delta[fit_mask], fit.calibration.name))
        calibration = cache[key]
        return lambda predict_mask: calibration.linear_drop(*x[predict_mask].T)

    train, test = drops.train[mask], drops.test[mask]
    choice = choose_link(train, test, delta, refit)
    fold_betas = {rig: cache[(~involved).tobytes()].beta for rig, involved, _ in rig_folds(train, test)}
    choice = replace(choice, fold_betas=fold_betas)
    calibration = replace(fit.calibration, link=choice.link, interval=choice.interval, domain=domain_of(x))
    return replace(fit, calibration=calibration), choice


def _named(rig: Rig, name: str) -> Rig:
    """The rig under the name the results use (a library lookup may differ in letter case)."""
    return rig if rig.name == name else Rig(name, rig.vehicle, rig.cameras)


@dataclass(frozen=True)
class CalibrationTransfer:
    """A calibration fitted on one body of measured transfer (``source``, e.g. the synthetic benchmark's) and
    judged on another (``target``, e.g. the real benchmark's pairs), beside the target's own calibration.

    ``models``: per target detector, the source's joint calibration on the target's pairs (ModelReliability:
    control and held-out pairs of the target's control rigs, linear and bounded); ``own``: the target's own
    protocol study (its per-detector and joint fits on its control pairs); ``gains``: per detector, the
    held-out rho of ``calibration`` minus that of each own fit (``"own_per_detector"``, ``"own_joint"``) on
    the same held-out pairs, as (gain, low, high) with a paired bootstrap's 95 % interval."""

    calibration: Calibration
    models: tuple[ModelReliability, ...]
    own: CalibrationStudy
    gains: dict


def calibration_on(calibration: Calibration, table: TransferTable, control_rigs: Sequence[str] = CONTROL_RIGS,
                   rig_lookup: Callable[[str], Rig] = load_rig, resamples: int = DEFAULT_BOOTSTRAP,
                   seed: int = DEFAULT_SEED, solver: str = "lbfgsb",
                   own: CalibrationStudy | None = None) -> CalibrationTransfer:
    """Judge ``calibration`` (fitted elsewhere) on the measured transfer ``table``: per detector, Spearman rho
    and MAE of its linear prediction, and the bounded drop's accuracy, on the table's control and held-out
    pairs; with the table's own protocol study (same control rigs; ``own`` if already computed) to compare
    with."""
    if own is None:
        own = calibrate(table, control_rigs, rig_lookup, resamples, seed, solver, calibration.metric)
    drops = table.drops()
    rig_names = list(dict.fromkeys(drops.train.tolist() + drops.test.tolist()))
    rigs = [_named(rig_lookup(name), name) for name in rig_names]
    features = pair_features(rigs, drops.train, drops.test, tuple(float(v) for v in calibration.match_lambdas))
    control = np.isin(drops.train, own.control_rigs) & np.isin(drops.test, own.control_rigs)
    pairs = _predictions(drops, features, calibration, control)
    models = []
    for model in dict.fromkeys(drops.model.tolist()):
        mine = pairs.model == model
        subset = PairPredictions(*(getattr(pairs, f)[mine] for f in PairPredictions.__dataclass_fields__))
        models.append(ModelReliability(model, *_split_reliability(subset, resamples, seed),
                                       bounded_accuracy(subset, subset.control), bounded_accuracy(subset, ~subset.control)))
    per_detector = {m.model: m.pairs for m in own.models}
    gains = {m.model: {name: _heldout_rho_gain(pairs, other, m.model, resamples, seed)
                       for name, other in (("own_per_detector", per_detector.get(m.model)),
                                           ("own_joint", own.joint.pairs))}
             for m in models}
    return CalibrationTransfer(calibration, tuple(models), own, gains)


def _heldout_rho_gain(pairs: PairPredictions, other: PairPredictions | None, model: str, resamples: int, seed: int):
    """rho_gain of ``pairs``' predictions over ``other``'s on ``model``'s held-out pairs, matched by (training
    rig, test rig); NaNs without ``other`` (the target's own study lacks the model)."""
    if other is None:
        return float("nan"), float("nan"), float("nan")
    theirs = {(t, s): p for m, t, s, p in zip(other.model, other.train, other.test, other.predicted) if m == model}
    held = [k for k in range(len(pairs.delta)) if pairs.model[k] == model and not pairs.control[k]
            and (pairs.train[k], pairs.test[k]) in theirs]
    other_predicted = np.array([theirs[(pairs.train[k], pairs.test[k])] for k in held])
    return rho_gain(pairs.predicted[held], other_predicted, pairs.delta[held], resamples, seed)


def null_transfer(table: TransferTable, rng: np.random.Generator) -> TransferTable:
    """``table``'s pairs measured by chance: each (model, training rig)'s own mAP kept, every other pair's
    relative drop drawn uniformly in [0, 1] (mAP = own x (1 - drop)). A calibration fitted on it knows
    RigCD's structure and nothing of the measurements."""
    own = table.own_map()
    base = np.array([own.get((m, a), np.nan) for m, a in zip(table.model, table.train)])
    drop = np.where(table.train == table.test, 0.0, rng.uniform(0.0, 1.0, len(base)))
    return TransferTable(table.model, table.train, table.test, np.where(np.isfinite(base), base * (1 - drop),
                                                                         table.map))


@dataclass(frozen=True)
class NullYardstick:
    """How joint calibrations fitted on ``null_transfer`` copies of the source table (``seeds`` of them) fare
    on the target's held-out pairs: ``heldout_rho`` {target detector: (seeds,) Spearman rho}."""

    seeds: int
    heldout_rho: dict

    def summary(self, figures: dict | None = None) -> dict:
        """Per detector: median, 5th and 95th percentile of the null rhos and, for ``figures`` {detector:
        rho} (a calibration's own held-out rho), the share of null fits that reach it."""
        out = {}
        for model, rhos in self.heldout_rho.items():
            rhos = np.asarray(rhos, dtype=float)
            entry = {"median": float(np.median(rhos)), "p5": float(np.percentile(rhos, 5)),
                     "p95": float(np.percentile(rhos, 95))}
            if figures is not None and model in figures:
                entry["share_reaching"] = float(np.mean(rhos >= figures[model]))
            out[model] = entry
        return out


def null_yardstick(source: TransferTable, target: TransferTable, seeds: int,
                   control_rigs: Sequence[str] = CONTROL_RIGS, rig_lookup: Callable[[str], Rig] = load_rig,
                   solver: str = "lbfgsb", metric: str = "rigcd",
                   target_control: Sequence[str] | None = None) -> NullYardstick:
    """The held-out rho on ``target`` of joint calibrations fitted on ``seeds`` chance copies of ``source``
    (:func:`null_transfer`, seeds 0 ..): what RigCD's structure alone gives, the bar a calibration fitted on
    ``source`` must clear to have learned from its measurements. The fits use ``source``'s ``control_rigs``;
    ``target``'s held-out pairs are those outside ``target_control`` (default: ``control_rigs``)."""
    target_control = control_rigs if target_control is None else target_control
    own = calibrate(target, target_control, rig_lookup, 0, DEFAULT_SEED, solver, metric)
    rhos: dict[str, list] = {}
    for seed in range(seeds):
        chance = null_transfer(source, np.random.default_rng(seed))
        fit = calibrate(chance, control_rigs, rig_lookup, 0, DEFAULT_SEED, solver, metric).joint.fit.calibration
        for model in calibration_on(fit, target, target_control, rig_lookup, 0, DEFAULT_SEED, solver, own).models:
            rhos.setdefault(model.model, []).append(model.heldout.rho)
    return NullYardstick(seeds, {model: np.array(values) for model, values in rhos.items()})
