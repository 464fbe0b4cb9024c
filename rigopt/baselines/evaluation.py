"""Centre-distance mean average precision of 3D detections, as the PCCR benchmark reports it (nuScenes style).

For each class and each distance threshold ``d`` (default 0.5, 1, 2 and 4 m):

1. The class's detections over all samples are ranked by score, highest first. Equal scores are ordered
   by sample id, then x, then y (ascending), so the result does not depend on the order of the inputs.
2. In that order each detection is matched to the *nearest still unmatched* ground truth of the same
   class in the same sample, by bird's-eye distance of the centres (ego x, y). It is a true positive when
   that distance is strictly below ``d`` (a detection exactly ``d`` away is a false positive), and the
   ground truth is then taken; otherwise it is a false positive and no ground truth is taken. Ground
   truths at equal distance are taken in the order x, then y (ascending).
3. Cumulative counts give precision TP / (TP + FP) and recall TP / (ground truths of the class) after
   each detection.
4. Precision is read at the 101 recall points r = 0, 0.01, ..., 1 as the highest precision at any rank
   whose recall is at least r (0 where recall r is never reached); recall is compared with r in exact
   integer arithmetic (100 TP >= i * ground truths) so that e.g. 3/10 reaches r = 0.30.
5. AP keeps the points with r > 0.1 (indices 11..100), subtracts 0.1 from precision, clips at 0,
   averages and divides by 0.9, so a perfect ranking gives 1 and no true positive gives 0.

A class without ground truth has AP NaN and is left out of the mean; a class with ground truth but no
detection has AP 0. mAP is the mean over the classes with ground truth of the class's mean AP over the
thresholds (NaN when no class has ground truth).

Unlike the nuScenes devkit, precision between recall points is not interpolated linearly: the "highest
precision to the right" rule of step 4 is used, and detections are not filtered by range or count.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from rigopt.bench.dataset import TrainingSample
from rigopt.bench.scene_model import CLASSES
from rigopt.errors import DataError
from rigopt.metrics.reliability import finite_or_none

DEFAULT_THRESHOLDS = (0.5, 1.0, 2.0, 4.0)
#: Recall points at which precision is read (r = i / RECALL_STEPS for i = 0..RECALL_STEPS).
RECALL_STEPS = 100
MIN_RECALL = 0.1
MIN_PRECISION = 0.1


@dataclass(frozen=True)
class SamplePrediction:
    """A detector's output for one sample.

    token : the sample's id (str or int); centers : (n, 2) or (n, 3) float m in the ego frame (only x, y
    are used); classes : (n,) int index into the evaluated classes; scores : (n,) float confidence.
    """

    token: object
    centers: np.ndarray
    classes: np.ndarray
    scores: np.ndarray


@dataclass(frozen=True)
class GroundTruth:
    """n ground-truth objects: sample (n,) int or str id; cls (n,) int class index; xy (n, 2) float m centre
    in the ego frame."""

    sample: np.ndarray
    cls: np.ndarray
    xy: np.ndarray

    def __len__(self) -> int:
        return len(self.cls)

    @classmethod
    def from_samples(cls, samples: Iterable[TrainingSample]) -> GroundTruth:
        """The boxes of every sample, keyed by its token; boxes of unevaluated categories (class -1) are dropped."""
        samples = list(samples)
        columns = [(np.asarray(s.classes, dtype=int).reshape(-1), _centers_xy(s.centers, f"sample {s.token!r}"))
                   for s in samples]
        keep = [c >= 0 for c, _ in columns]
        return cls(np.array([s.token for s, k in zip(samples, keep) for _ in range(int(k.sum()))], dtype=str),
                   np.concatenate([c[k] for (c, _), k in zip(columns, keep)] + [np.zeros(0, dtype=int)]),
                   np.concatenate([xy[k] for (_, xy), k in zip(columns, keep)] + [np.zeros((0, 2))]))


@dataclass(frozen=True)
class Detections:
    """n detections: sample (n,) int or str id; cls (n,) int class index; xy (n, 2) float m centre in the ego
    frame; score (n,) float confidence (higher = more confident)."""

    sample: np.ndarray
    cls: np.ndarray
    xy: np.ndarray
    score: np.ndarray

    def __len__(self) -> int:
        return len(self.cls)

    @classmethod
    def from_predictions(cls, predictions: Iterable[SamplePrediction]) -> Detections:
        """All detections of the per-sample predictions, each keyed by its sample's token."""
        predictions = list(predictions)
        xy = [_centers_xy(p.centers, f"prediction for {p.token!r}") for p in predictions]
        classes = [np.asarray(p.classes).reshape(-1) for p in predictions]
        scores = [np.asarray(p.scores, dtype=float).reshape(-1) for p in predictions]
        for p, c, s, centre in zip(predictions, classes, scores, xy):
            if not len(c) == len(s) == len(centre):
                raise DataError(f"prediction for {p.token!r}: {len(centre)} centres, {len(c)} classes and "
                                f"{len(s)} scores; give one of each per detection")
        tokens = [p.token for p, c in zip(predictions, classes) for _ in range(len(c))]
        return cls(np.array(tokens) if tokens else np.zeros(0, dtype=str),
                   np.concatenate(classes + [np.zeros(0, dtype=int)]),
                   np.concatenate(xy + [np.zeros((0, 2))]),
                   np.concatenate(scores + [np.zeros(0)]))


@dataclass(frozen=True)
class Evaluation:
    """Centre-distance AP of C classes at T distance thresholds.

    ``classes`` (C,) names and ``thresholds`` (T,) m as evaluated; ``ap`` (C, T) float, NaN rows for
    classes without ground truth; ``per_class_ap`` (C,) the mean of each row; ``map`` the mean of
    ``per_class_ap`` over the classes with ground truth (NaN if none); ``n_ground_truth`` (C,) int.
    """

    map: float
    ap: np.ndarray
    per_class_ap: np.ndarray
    classes: tuple[str, ...]
    thresholds: tuple[float, ...]
    n_ground_truth: np.ndarray

    def to_dict(self) -> dict:
        """The benchmark's metrics shape: {"mAP": float, "raw": {"<class>_AP_dist_<d>": float}}; NaN -> None."""
        raw = {f"{name}_AP_dist_{d}": finite_or_none(self.ap[i, j])
               for i, name in enumerate(self.classes) for j, d in enumerate(self.thresholds)}
        return {"mAP": finite_or_none(self.map), "raw": raw}


def evaluate(detections: Detections, ground_truth: GroundTruth, classes: Sequence[str] = CLASSES,
             thresholds: Sequence[float] = DEFAULT_THRESHOLDS) -> Evaluation:
    """Centre-distance AP (classes x thresholds) and mAP of ``detections`` against ``ground_truth``.

    Raises DataError for arrays of mismatched lengths, non-finite centres or scores, class indices outside
    ``classes``, sample ids of incompatible kinds (int vs str), or non-positive thresholds.
    """
    classes = tuple(str(c) for c in classes)
    thresholds = tuple(float(d) for d in thresholds)
    if not classes or not thresholds:
        raise DataError("evaluation needs at least one class and one distance threshold")
    if not all(np.isfinite(d) and d > 0 for d in thresholds):
        raise DataError(f"distance thresholds must be positive finite metres, got {thresholds}")
    det_cls, det_xy, det_score = _checked("detections", detections.sample, detections.cls, detections.xy,
                                          len(classes), detections.score)
    gt_cls, gt_xy, _ = _checked("ground truth", ground_truth.sample, ground_truth.cls, ground_truth.xy,
                                len(classes))
    det_sample, gt_sample = _sample_codes(detections.sample, ground_truth.sample)

    n_gt = np.bincount(gt_cls, minlength=len(classes))
    ap = np.full((len(classes), len(thresholds)), np.nan)
    for c in np.flatnonzero(n_gt):
        d_rows, g_rows = det_cls == c, gt_cls == c
        for j, d in enumerate(thresholds):
            tp = _match(det_sample[d_rows], det_xy[d_rows], det_score[d_rows], gt_sample[g_rows], gt_xy[g_rows], d)
            ap[c, j] = average_precision(tp, int(n_gt[c]))
    per_class = ap.mean(axis=1)
    has_gt = n_gt > 0
    mean = float(per_class[has_gt].mean()) if has_gt.any() else float("nan")
    return Evaluation(mean, ap, per_class, classes, thresholds, n_gt)


def average_precision(tp: np.ndarray, n_ground_truth: int) -> float:
    """101-point AP of ranked detections, ``tp`` (n,) bool in rank order, against ``n_ground_truth`` > 0.

    Precision at recall point i / 100 is the highest precision at any rank with recall >= i / 100 (0 if
    none); points i <= 10 are dropped, 0.1 is subtracted (clipped at 0) and the mean is divided by 0.9.
    """
    tp = np.asarray(tp, dtype=bool)
    if len(tp) == 0:
        return 0.0
    tp_count = np.cumsum(tp)
    precision = tp_count / np.arange(1, len(tp) + 1)
    best_to_right = np.maximum.accumulate(precision[::-1])[::-1]  # (n,) best precision at rank >= k
    # recall point i is reached at rank k when tp_count[k] / n_gt >= i / 100, in exact integers.
    points = np.arange(RECALL_STEPS + 1)
    first_rank = np.searchsorted(RECALL_STEPS * tp_count, points * n_ground_truth, side="left")  # (101,)
    reached = first_rank < len(tp)
    curve = np.where(reached, best_to_right[np.minimum(first_rank, len(tp) - 1)], 0.0)
    kept = np.clip(curve[round(RECALL_STEPS * MIN_RECALL) + 1:] - MIN_PRECISION, 0.0, None)
    return math.fsum(kept) / len(kept) / (1.0 - MIN_PRECISION)  # exact sum: a perfect ranking gives 1.0


def _match(det_sample: np.ndarray, det_xy: np.ndarray, det_score: np.ndarray, gt_sample: np.ndarray,
           gt_xy: np.ndarray, threshold: float) -> np.ndarray:
    """Greedy matching of one class's detections (m,) to its ground truths (g,) -> tp (m,) bool in rank order."""
    order = np.lexsort((det_xy[:, 1], det_xy[:, 0], det_sample, -det_score))
    gt_order = np.lexsort((gt_xy[:, 1], gt_xy[:, 0], gt_sample))
    gt_sample, gt_xy = gt_sample[gt_order], gt_xy[gt_order]
    free = np.ones(len(gt_sample), dtype=bool)
    tp = np.zeros(len(order), dtype=bool)
    for rank, k in enumerate(order):
        candidates = np.flatnonzero(free & (gt_sample == det_sample[k]))
        if len(candidates) == 0:
            continue
        distance = np.hypot(*(gt_xy[candidates] - det_xy[k]).T)
        nearest = int(np.argmin(distance))  # first of equal distances: canonical (x, y) order
        if distance[nearest] < threshold:
            tp[rank] = True
            free[candidates[nearest]] = False
    return tp


def _checked(what: str, sample, cls, xy, n_classes: int, score=None):
    """Validated (cls (n,) int, xy (n, 2) float, score (n,) float or None) of one input."""
    cls, xy = np.asarray(cls), np.asarray(xy, dtype=float)
    n = len(cls)
    if cls.ndim != 1 or np.ndim(sample) != 1 or xy.ndim != 2 or xy.shape[1] != 2:
        raise DataError(f"{what}: sample and cls must be (n,) and xy (n, 2); got shapes {np.shape(sample)}, "
                        f"{cls.shape} and {xy.shape}")
    lengths = {"sample": len(sample), "cls": n, "xy": len(xy)}
    if score is not None:
        score = np.asarray(score, dtype=float)
        lengths["score"] = len(score) if score.ndim == 1 else -1
    if len(set(lengths.values())) != 1:
        raise DataError(f"{what}: arrays must all have one entry per object, got lengths {lengths}")
    whole = np.issubdtype(cls.dtype, np.floating) and np.all(np.isfinite(cls)) and np.all(cls == np.round(cls))
    if n and not (np.issubdtype(cls.dtype, np.integer) or whole):
        raise DataError(f"{what}: class indices must be integers, got dtype {cls.dtype}")
    cls = cls.astype(int)
    bad = (cls < 0) | (cls >= n_classes)
    if bad.any():
        raise DataError(f"{what}: unknown class index {int(cls[bad][0])}; valid indices are 0..{n_classes - 1}")
    if not np.all(np.isfinite(xy)):
        raise DataError(f"{what}: {int((~np.isfinite(xy).all(axis=1)).sum())} centre(s) are NaN or infinite")
    if score is not None and not np.all(np.isfinite(score)):
        raise DataError(f"{what}: {int((~np.isfinite(score)).sum())} score(s) are NaN or infinite")
    return cls, xy, score


def _sample_codes(det_sample, gt_sample) -> tuple[np.ndarray, np.ndarray]:
    """Integer codes (m,), (g,) of the sample ids, ordered as the sorted ids; ids must all be int or all str."""
    det_sample, gt_sample = np.asarray(det_sample), np.asarray(gt_sample)
    kinds = {_id_kind(a) for a in (det_sample, gt_sample) if len(a)}
    if None in kinds or len(kinds) > 1:
        raise DataError(f"sample ids must be all integers or all strings, got dtypes {det_sample.dtype} "
                        f"(detections) and {gt_sample.dtype} (ground truth)")
    ids = [a if len(a) else a.astype(int if kinds == {"int"} else str) for a in (det_sample, gt_sample)]
    _, codes = np.unique(np.concatenate(ids), return_inverse=True)
    return codes[:len(det_sample)], codes[len(det_sample):]


def _id_kind(ids: np.ndarray):
    if np.issubdtype(ids.dtype, np.integer):
        return "int"
    if ids.dtype.kind == "U":
        return "str"
    if ids.dtype == object and all(isinstance(v, str) for v in ids):
        return "str"
    return None


def _centers_xy(centers, where: str) -> np.ndarray:
    """(n, 2) ego x, y of (n, 2) or (n, 3) centres."""
    centers = np.asarray(centers, dtype=float)
    if centers.size == 0:
        return np.zeros((0, 2))
    if centers.ndim != 2 or centers.shape[1] not in (2, 3):
        raise DataError(f"{where}: centres must be (n, 2) or (n, 3), got shape {centers.shape}")
    return centers[:, :2]
