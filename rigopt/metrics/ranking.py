"""Predicted transfer from a reference rig to candidate rigs, the number ``rigopt rank`` sorts by."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from rigopt.metrics.calibration import Calibration
from rigopt.metrics.rigcd import DEFAULT_ALPHA, DEFAULT_LAMBDAS, rigcd_matrix, tie_broken_lambdas
from rigopt.rig.model import Rig


@dataclass(frozen=True)
class TransferPrediction:
    """A reference -> candidate pair.

    ``t`` (m), ``r`` (rad), ``f`` (deg), ``count``: the calibration's input features, under the matching of
    its metric (unit weights for rigcd and without a calibration, its own lambdas for rigcd+);
    ``rigcd`` and ``match``: RigCD under the calibration's alpha and lambdas (the defaults without one);
    ``predicted_drop``: the calibrated relative mAP drop, None without a calibration.
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


def predict_transfer(reference: Rig, candidates: Sequence[Rig],
                     calibration: Calibration | None = None) -> list[TransferPrediction]:
    """One prediction per candidate, in the candidates' order."""
    match_lambdas = calibration.match_lambdas if calibration is not None else DEFAULT_LAMBDAS
    features = rigcd_matrix([reference], candidates, DEFAULT_ALPHA, tie_broken_lambdas(match_lambdas))
    if calibration is None:
        weighted = rigcd_matrix([reference], candidates, DEFAULT_ALPHA, DEFAULT_LAMBDAS)
        drops = [None] * len(candidates)
    else:
        weighted = rigcd_matrix([reference], candidates, calibration.alpha, calibration.lambdas)
        drops = calibration.predict(features.t[0], features.r[0], features.f[0], features.count[0]).tolist()
    return [
        TransferPrediction(reference.name, rig.name, float(weighted.rigcd[0, k]), float(weighted.match[0, k]),
                           float(features.count[0, k]), float(features.t[0, k]), float(features.r[0, k]),
                           float(features.f[0, k]), drops[k])
        for k, rig in enumerate(candidates)
    ]


def rank_candidates(reference: Rig, candidates: Sequence[Rig], calibration: Calibration) -> list[TransferPrediction]:
    """Candidates sorted by predicted drop, smallest first (ties keep the given order)."""
    predictions = predict_transfer(reference, candidates, calibration)
    order = np.argsort([p.predicted_drop for p in predictions], kind="stable")
    return [predictions[k] for k in order]
