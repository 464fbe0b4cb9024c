"""Predicted transfer from a reference rig to candidate rigs, the number ``rigopt rank`` sorts by."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np

from rigopt.metrics.calibration import Calibration
from rigopt.metrics.drop_model import BodyShare, DropModel
from rigopt.metrics.lifting import lifting_terms
from rigopt.metrics.prediction import Extrapolation, interval_informative
from rigopt.metrics.rigcd import DEFAULT_ALPHA, DEFAULT_LAMBDAS, rigcd_matrix, tie_broken_lambdas
from rigopt.rig.model import Rig


@dataclass(frozen=True)
class TransferPrediction:
    """A reference -> candidate pair.

    ``t`` (m), ``r`` (rad), ``f`` (deg), ``count``: the calibration's input features, under the matching of
    its metric (unit weights for rigcd and without a calibration, its own lambdas for rigcd+);
    ``rigcd`` and ``match``: RigCD under the calibration's alpha and lambdas (the defaults without one);
    ``predicted_drop``: the calibrated relative mAP drop (through the calibration's link, in [0, 1]), None
    without a calibration; ``linear_drop``: the benchmark's linear prediction K x calibrated RigCD
    (unbounded); ``interval``: (low, high) prediction interval of the drop, None without one;
    ``extrapolation``: how the pair lies outside the calibration pairs (None when inside or unknown);
    ``fallback``: the calibration kept no geometric term (Fast-BEV), its predictions ignore geometry's weights;
    ``predictor``: what gave ``predicted_drop`` and its interval ("RigCD (joint)", or a measured-drop model's
    "lss-R1 drop model", :mod:`rigopt.metrics.drop_model`), None without a calibration.
    """

    reference: str
    rig: str
    rigcd: float
    match: float
    count: float
    t: float
    r: float
    f: float
    predicted_drop: float | None
    linear_drop: float | None = None
    interval: tuple[float, float] | None = None
    extrapolation: Extrapolation | None = None
    fallback: bool = False
    interval_halfwidth: float | None = None
    predictor: str | None = None

    @property
    def interval_informative(self) -> bool | None:
        """Whether the interval says anything (``prediction.interval_informative``: it is not, once clipped to
        [0, 1], about the whole range a drop can take); None without an interval."""
        if self.interval is None:
            return None
        return interval_informative(*self.interval, self.interval_halfwidth)

    def to_dict(self) -> dict:
        """JSON form: rig, reference, predicted_drop, interval, interval_informative, linear_drop, rigcd, match, t,
        r, f, count, extrapolation (null or {terms: [...], hull_distance}), fallback, predictor."""
        return {"reference": self.reference, "rig": self.rig, "predicted_drop": self.predicted_drop,
                "predictor": self.predictor,
                "interval": list(self.interval) if self.interval is not None else None,
                "interval_informative": self.interval_informative,
                "linear_drop": self.linear_drop, "rigcd": self.rigcd, "match": self.match, "t": self.t, "r": self.r,
                "f": self.f, "count": self.count,
                "extrapolation": self.extrapolation.to_dict() if self.extrapolation is not None else None,
                "fallback": self.fallback}


def predict_transfer(reference: Rig, candidates: Sequence[Rig], calibration: Calibration | None = None,
                     model: DropModel | None = None, body_share: BodyShare | None = None) -> list[TransferPrediction]:
    """One prediction per candidate, in the candidates' order. A lifting metric's pairs (its per-pair terms need
    heights above the ground) must be measured from their vehicle's centre on the ground, as RigCD's and a drop
    model's. With a ``model`` the predicted drop, its interval and extrapolation flags are the model's; the RigCD
    fields stay the calibration's. ``body_share`` gives the share of ego body each camera sees, which a model with
    that term needs (:func:`rigopt.mounting.candidates.rig_body_share`)."""
    predictions = _rigcd_predictions(reference, candidates, calibration)
    return (predictions if model is None
            else _model_predictions(reference, candidates, predictions, model, body_share))


def _rigcd_predictions(reference: Rig, candidates: Sequence[Rig],
                       calibration: Calibration | None) -> list[TransferPrediction]:
    if calibration is not None and calibration.lifting is not None:
        return _lifting_predictions(reference, candidates, calibration)
    match_lambdas = calibration.match_lambdas if calibration is not None else DEFAULT_LAMBDAS
    features = rigcd_matrix([reference], candidates, DEFAULT_ALPHA, tie_broken_lambdas(match_lambdas))
    n = len(candidates)
    x = np.stack([features.t[0], features.r[0], features.f[0], features.count[0]], axis=1)  # (n, 4)
    linear, drops, intervals, flags = [None] * n, [None] * n, [None] * n, [None] * n
    if calibration is None:
        weighted = rigcd_matrix([reference], candidates, DEFAULT_ALPHA, DEFAULT_LAMBDAS)
    else:
        weighted = rigcd_matrix([reference], candidates, calibration.alpha, calibration.lambdas)
        linear = calibration.linear_drop(*x.T).tolist()
        drops = calibration.bounded_drop(*x.T).tolist()
        if calibration.interval is not None:
            intervals = list(zip(*(v.tolist() for v in calibration.interval.around(drops))))
        if calibration.domain is not None:
            flags = [e if e.flagged else None for e in calibration.domain.check(x)]
    fallback = calibration is not None and calibration.fallback
    return [
        TransferPrediction(reference.name, rig.name, float(weighted.rigcd[0, k]), float(weighted.match[0, k]),
                           float(x[k, 3]), float(x[k, 0]), float(x[k, 1]), float(x[k, 2]), drops[k], linear[k],
                           intervals[k], flags[k], fallback,
                           calibration.interval.halfwidth if intervals[k] is not None else None,
                           rigcd_predictor(calibration))
        for k, rig in enumerate(candidates)
    ]


def rigcd_predictor(calibration: Calibration | None) -> str | None:
    """The name a RigCD prediction goes by: "RigCD (joint)", "RigCD+ (BEVDet)"; None without a calibration."""
    if calibration is None:
        return None
    metric = {"rigcd": "RigCD", "rigcd+": "RigCD+"}.get(calibration.metric, calibration.metric)
    return f"{metric} ({calibration.name})"


def model_predictor(model: DropModel) -> str:
    """The name a drop model's prediction goes by: "lss-R1 drop model"."""
    return f"{model.name} drop model"


def _model_predictions(reference: Rig, candidates: Sequence[Rig], predictions: list[TransferPrediction],
                       model: DropModel, body_share: BodyShare | None) -> list[TransferPrediction]:
    """``predictions`` with the drop, interval and extrapolation flags of ``model``. The interval is capped at 1
    (no rig loses more than everything) but not at 0: a rig can measure better than the reference (a negative
    drop), and the model's interval, as its study's coverage, counts such a drop inside when within the width."""
    drops, halfwidths, beyond = model.predict(reference, candidates, body_share)
    return [replace(p, predicted_drop=float(d), linear_drop=None, fallback=False, interval_halfwidth=float(h),
                    interval=(float(d - h), float(min(d + h, 1.0))) if np.isfinite(h) else None,
                    extrapolation=Extrapolation(flags, 0.0) if flags else None, predictor=model_predictor(model))
            for p, d, h, flags in zip(predictions, drops, halfwidths, beyond)]


def _lifting_predictions(reference: Rig, candidates: Sequence[Rig], calibration: Calibration) -> list[TransferPrediction]:
    """predict_transfer under a lifting metric: its terms over RigCD's unit-weight matching; ``rigcd`` is the
    metric's own distance (alpha x match + (1 - alpha) x count, the quantity the designer minimises), ``match``
    its mean matched-pair cost."""
    terms = lifting_terms([reference] * len(candidates), list(candidates))  # (n, len(TERMS))
    t, r, f, count = terms[:, :4].T
    match = terms[:, :3] @ np.asarray(calibration.lambdas) + terms[:, 4:] @ np.asarray(calibration.lifting)
    distance = calibration.alpha * match + (1.0 - calibration.alpha) * count
    linear = calibration.linear_drop(t, r, f, count, terms[:, 4:])
    drops = calibration.bounded_drop(t, r, f, count, terms[:, 4:])
    return [
        TransferPrediction(reference.name, rig.name, float(distance[k]), float(match[k]), float(count[k]),
                           float(t[k]), float(r[k]), float(f[k]), float(drops[k]), float(linear[k]),
                           predictor=rigcd_predictor(calibration))
        for k, rig in enumerate(candidates)
    ]


def rank_candidates(reference: Rig, candidates: Sequence[Rig], calibration: Calibration,
                    model: DropModel | None = None, body_share: BodyShare | None = None) -> list[TransferPrediction]:
    """Candidates sorted by predicted drop (``predict_transfer``'s), smallest first (ties keep the given order)."""
    predictions = predict_transfer(reference, candidates, calibration, model, body_share)
    order = np.argsort([p.predicted_drop for p in predictions], kind="stable")
    return [predictions[k] for k in order]
