"""Centre-distance mean average precision of 3D detections, as the PCCR benchmark reports it (nuScenes style).

Torch-free and detector-agnostic: any detector's per-sample predictions are scored here (the torch
families in ``rigopt.validation.detectors`` call it through ``baselines.inference``).

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

Two ground-truth sets, one matching. The *fixed set* counts every annotated object, seen by the rig or
not (rigopt's ground truth is the same for every rig), so an object in a blind zone that no detection
finds is a missed detection: this is the reported ``mAP``. The *visible-only* score (``mAP_visible``)
counts only the objects some camera sees (``GroundTruth.visible``); the matching of step 2 is the same,
and a detection matched there to an unseen object is left out of the ranking (neither a true nor a false
positive), as nuScenes and COCO treat detections on ignored objects. A detector that finds every seen
object and nothing else thus gets visible-only AP 1 and a fixed-set AP that falls with the unseen share:
the gap between the two is the coverage effect, the visible-only score the viewpoint effect.

A class without ground truth has AP NaN and is left out of the mean; a class with ground truth but no
detection has AP 0. mAP is the mean over the classes with ground truth of the class's mean AP over the
thresholds (NaN when no class has ground truth).

Unlike the nuScenes devkit, precision between recall points is not interpolated linearly: the "highest
precision to the right" rule of step 4 is used, and detections are not filtered by count. The benchmark's
protocol keeps ground truth and detections within ``EVAL_RANGE`` m (bird's-eye distance) of the ego, as
nuScenes keeps each class within its range (``GroundTruth.within``, ``SamplePrediction.within``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from rigopt.validation.synthetic.dataset import TrainingSample
from rigopt.validation.synthetic.scene_model import CLASSES
from rigopt.errors import DataError
from rigopt.metrics.reliability import DEFAULT_BOOTSTRAP, DEFAULT_SEED, finite_or_none

DEFAULT_THRESHOLDS = (0.5, 1.0, 2.0, 4.0)
#: Ground truth and detections are evaluated within this bird's-eye distance (m) of the ego.
EVAL_RANGE = 50.0
#: Recall points at which precision is read (r = i / RECALL_STEPS for i = 0..RECALL_STEPS).
RECALL_STEPS = 100
MIN_RECALL = 0.1
MIN_PRECISION = 0.1
#: ``resampled_maps`` scores its resamples in chunks of about this many (resample, detection) entries per
#: working array (int64: 2 MB each, a handful alive at once; small enough to stay in the cache).
RESAMPLE_CHUNK_ENTRIES = 250_000
#: The recall points AP keeps (i = 11..100: r > MIN_RECALL).
KEPT_POINTS = np.arange(round(RECALL_STEPS * MIN_RECALL) + 1, RECALL_STEPS + 1)


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

    def within(self, radius: float = EVAL_RANGE) -> SamplePrediction:
        """The detections whose centre lies within ``radius`` m (bird's-eye distance) of the ego."""
        centers = np.asarray(self.centers, dtype=float)
        keep = np.hypot(centers[:, 0], centers[:, 1]) <= radius
        return SamplePrediction(self.token, centers[keep], np.asarray(self.classes)[keep],
                                np.asarray(self.scores, dtype=float)[keep])


@dataclass(frozen=True)
class GroundTruth:
    """n ground-truth objects: sample (n,) int or str id; cls (n,) int class index; xy (n, 2) float m centre
    in the ego frame; visible (n,) bool, whether some camera of the rig sees the object (None: all do)."""

    sample: np.ndarray
    cls: np.ndarray
    xy: np.ndarray
    visible: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.cls)

    def seen(self) -> np.ndarray:
        """(n,) bool ``visible``, all True when it is None."""
        return np.ones(len(self.cls), dtype=bool) if self.visible is None else np.asarray(self.visible, dtype=bool)

    def within(self, radius: float = EVAL_RANGE) -> GroundTruth:
        """The objects whose centre lies within ``radius`` m (bird's-eye distance) of the ego."""
        keep = np.hypot(self.xy[:, 0], self.xy[:, 1]) <= radius
        return GroundTruth(self.sample[keep], self.cls[keep], self.xy[keep],
                           None if self.visible is None else np.asarray(self.visible)[keep])

    @classmethod
    def from_samples(cls, samples: Iterable[TrainingSample]) -> GroundTruth:
        """The boxes of every sample, keyed by its token, with their visibility (``TrainingSample.visible``);
        boxes of unevaluated categories (class -1) are dropped."""
        samples = list(samples)
        columns = [(np.asarray(s.classes, dtype=int).reshape(-1), _centers_xy(s.centers, f"sample {s.token!r}"),
                    s.visible) for s in samples]
        keep = [c >= 0 for c, _, _ in columns]
        return cls(np.array([s.token for s, k in zip(samples, keep) for _ in range(int(k.sum()))], dtype=str),
                   np.concatenate([c[k] for (c, _, _), k in zip(columns, keep)] + [np.zeros(0, dtype=int)]),
                   np.concatenate([xy[k] for (_, xy, _), k in zip(columns, keep)] + [np.zeros((0, 2))]),
                   np.concatenate([v[k] for (_, _, v), k in zip(columns, keep)] + [np.zeros(0, dtype=bool)]))


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
    ``per_class_ap`` over the classes with ground truth (NaN if none); ``n_ground_truth`` (C,) int, the
    ground truths counted (every object for the fixed set, the seen ones for the visible-only score).
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
             thresholds: Sequence[float] = DEFAULT_THRESHOLDS, visible_only: bool = False) -> Evaluation:
    """Centre-distance AP (classes x thresholds) and mAP of ``detections`` against ``ground_truth``: the
    fixed set, or with ``visible_only`` the seen objects only (rules in the module docstring).

    Raises DataError for arrays of mismatched lengths, non-finite centres or scores, class indices outside
    ``classes``, sample ids of incompatible kinds (int vs str), or non-positive thresholds.
    """
    return match(detections, ground_truth, classes, thresholds).evaluation(visible_only=visible_only)


@dataclass(frozen=True)
class MatchedDetections:
    """Detections matched to ground truth once, so that the AP of any multiset of the S samples follows
    without matching again (a detection is matched only within its own sample).

    ``samples`` (S,) ids; ``rank_sample[c]`` (m_c,) int sample index of class c's detections in rank order;
    ``tp[c]`` (T, m_c) bool, true positive at each threshold (fixed set); ``on_unseen[c]`` (T, m_c) bool,
    those true positives whose object no camera sees (left out of the visible-only ranking); ``gt_count``
    and ``gt_count_visible`` (C, S) int ground truths (all, seen) per class and sample.
    """

    samples: np.ndarray
    rank_sample: tuple[np.ndarray, ...]
    tp: tuple[np.ndarray, ...]
    gt_count: np.ndarray
    classes: tuple[str, ...]
    thresholds: tuple[float, ...]
    on_unseen: tuple[np.ndarray, ...]
    gt_count_visible: np.ndarray

    def evaluation(self, weights: np.ndarray | None = None, visible_only: bool = False) -> Evaluation:
        """AP and mAP with sample i counted ``weights[i]`` times ((S,) int >= 0; default all once), against
        the fixed set or, with ``visible_only``, the seen objects only.

        Repeated samples are scored as distinct samples whose detections are ranked next to each other;
        with all weights 1 this is exactly ``evaluate``.
        """
        weights = np.ones(len(self.samples), dtype=int) if weights is None else np.asarray(weights)
        if weights.shape != (len(self.samples),) or not np.issubdtype(weights.dtype, np.integer) or (weights < 0).any():
            raise DataError(f"sample weights must be ({len(self.samples)},) integers >= 0, got {weights.dtype} "
                            f"{weights.shape}")
        n_gt = (self.gt_count_visible if visible_only else self.gt_count) @ weights
        ap = np.full((len(self.classes), len(self.thresholds)), np.nan)
        for c in np.flatnonzero(n_gt):
            repeats = weights[self.rank_sample[c]]
            for j in range(len(self.thresholds)):
                ranked = ~self.on_unseen[c][j] if visible_only else slice(None)
                ap[c, j] = average_precision(np.repeat(self.tp[c][j][ranked], repeats[ranked]), int(n_gt[c]))
        per_class = ap.mean(axis=1)
        has_gt = n_gt > 0
        mean = float(per_class[has_gt].mean()) if has_gt.any() else float("nan")
        return Evaluation(mean, ap, per_class, self.classes, self.thresholds, n_gt)

    def metrics(self) -> dict:
        """The benchmark's metrics shape, fixed set first: {"mAP", "raw"} as ``Evaluation.to_dict`` gives
        them, plus "mAP_visible" and "raw_visible" for the seen objects only; NaN -> None."""
        fixed, visible = self.evaluation().to_dict(), self.evaluation(visible_only=True).to_dict()
        return {"mAP": fixed["mAP"], "mAP_visible": visible["mAP"], "raw": fixed["raw"], "raw_visible": visible["raw"]}


def resampled_maps(matched: Sequence[MatchedDetections], groups: Sequence[Sequence[int]],
                   resamples: int = DEFAULT_BOOTSTRAP, seed: int = DEFAULT_SEED,
                   visible_only: bool = False) -> np.ndarray:
    """(resamples, K) mAP (fixed set, or ``visible_only``) of K matched runs over the same samples, each
    resample drawing ``len(groups)`` groups of sample indices with replacement (the same draw for all K,
    so differences are paired).

    Groups are the resampling unit: samples that are not independent (consecutive frames) belong together.
    Resample r counts sample i ``weights[r, i]`` times (how often the drawn groups hold it), and its mAP is
    ``matched[k].evaluation(weights[r], visible_only).map`` (to rounding, about 1e-16: its sums run in
    another order), computed for a chunk of resamples at once (``RESAMPLE_CHUNK_ENTRIES``) from the ranked
    true positives, without expanding the weights.
    """
    if not matched:
        raise DataError("resampling needs at least one matched run")
    samples = matched[0].samples
    if not all(np.array_equal(m.samples, samples) for m in matched):
        raise DataError("resampled runs must be matched on the same samples in the same order")
    members = [np.asarray(g, dtype=int) for g in groups]
    if not members or any(len(g) == 0 or g.min() < 0 or g.max() >= len(samples) for g in members):
        raise DataError(f"groups must be non-empty lists of sample indices in 0..{len(samples) - 1}")
    rng = np.random.default_rng(seed)
    widest = max([len(samples), len(KEPT_POINTS)] + [len(ranked) for m in matched for ranked in m.rank_sample])
    chunk = max(1, RESAMPLE_CHUNK_ENTRIES // widest)
    maps = np.empty((resamples, len(matched)))
    for start in range(0, resamples, chunk):
        weights = np.array([np.bincount(np.concatenate([members[i] for i in rng.integers(len(members),
                                                                                         size=len(members))]),
                                        minlength=len(samples))
                            for _ in range(min(chunk, resamples - start))])  # (R, S) one draw per row
        for k, m in enumerate(matched):
            maps[start:start + len(weights), k] = _weighted_maps(m, weights, visible_only)
    return maps


def _weighted_maps(matched: MatchedDetections, weights: np.ndarray, visible_only: bool) -> np.ndarray:
    """(R,) mAP of ``matched`` with sample i counted ``weights[r, i]`` times in row r of ``weights`` (R, S)
    int >= 0: ``MatchedDetections.evaluation`` for R weightings at once."""
    n_gt = weights @ (matched.gt_count_visible if visible_only else matched.gt_count).T  # (R, C)
    ap = np.full(n_gt.shape + (len(matched.thresholds),), np.nan)  # (R, C, T)
    for c in np.flatnonzero(n_gt.any(axis=0)):
        depth = int(np.flatnonzero(matched.tp[c].any(axis=0)).max(initial=-1)) + 1  # none below the last TP counts
        copies = np.take(weights, matched.rank_sample[c][:depth], axis=1)  # (R, m) copies of each ranked detection
        ranked = np.cumsum(copies, axis=1)  # (R, m) detections ranked up to each one's last copy
        # true positives that reach each kept recall point i: 100 tp >= i n_gt <=> tp >= ceil(i n_gt / 100)
        needed = -(-KEPT_POINTS * n_gt[:, c, None] // RECALL_STEPS)  # (R, 90)
        for j in range(len(matched.thresholds)):
            left_out = matched.on_unseen[c][j] if visible_only else None
            ap[:, c, j] = _weighted_ap(copies, ranked, matched.tp[c][j], left_out, needed)
    ap[n_gt == 0] = np.nan
    per_class = ap.mean(axis=2)  # (R, C), NaN for the classes without ground truth
    has_gt = n_gt > 0
    counted = has_gt.sum(axis=1)
    total = np.where(has_gt, per_class, 0.0).sum(axis=1)
    return np.where(counted > 0, total / np.maximum(counted, 1), np.nan)


def _weighted_ap(copies: np.ndarray, ranked: np.ndarray, tp: np.ndarray, left_out: np.ndarray | None,
                 needed: np.ndarray) -> np.ndarray:
    """(R,) ``average_precision`` of one class at one threshold under R weightings, without expanding them.

    ``copies`` (R, m) int: copies of each ranked detection (its sample's weight; the copies are ranked next
    to each other); ``ranked`` (R, m) int: their cumulative sum along the ranking; ``tp`` (m,) bool;
    ``left_out`` (m,) bool or None: detections left out of the ranking (visible only: those on unseen
    objects); ``needed`` (R, 90) int: the true positives that reach each kept recall point.

    Why the true positives alone decide it, in the expanded sequence: within a run of copies of a true
    positive the precision (a + q) / (b + q) rises with q, so the run's best is its last copy, reached
    after ``ranked`` detections of which ``tp_count`` are true; a run of copies of a false positive is
    never better than the rank just before it (a / (b + 1) <= a / b). So the best precision at or after any
    rank inside a true positive's run is the best of the last copies of that and the later true
    positives. A recall point is first reached inside the run of the first true positive whose cumulative
    count reaches it (that run has copies: the count rose there). A true positive with no copies has the
    precision of the last rank before it, which lies after any such first rank, so it changes no maximum.
    """
    kept = tp & ~left_out if left_out is not None else tp
    hits = np.flatnonzero(kept)  # (P,) the true positives' ranks
    rows, n_hits = len(copies), len(hits)
    if n_hits == 0:
        return np.zeros(rows)
    tp_count = np.cumsum(np.take(copies, hits, axis=1), axis=1)  # (R, P) true positives up to each hit's last copy
    ranked = np.take(ranked, hits, axis=1)  # (R, P) detections ranked up to each hit's last copy
    if left_out is not None and left_out.any():
        dropped = np.flatnonzero(left_out)
        dropped_count = np.zeros((rows, len(dropped) + 1), dtype=ranked.dtype)  # (R, D + 1) of the first 0..D
        np.cumsum(np.take(copies, dropped, axis=1), axis=1, out=dropped_count[:, 1:])
        ranked -= np.take(dropped_count, np.searchsorted(dropped, hits), axis=1)  # those ranked above each hit
    if not ranked[:, 0].all():  # nothing ranked up to a row's first hits (no copies): 0 / 0 read as 0
        np.maximum(ranked, 1, out=ranked)
    # Best precision at or after each hit, [:, P - 1 - p] for hit p. Precisions are >= 0 and non-negative
    # doubles order as their bit patterns do, so the running maximum runs on int64 (exact, no NaN checks).
    precision_bits = (tp_count / ranked).view(np.int64)
    best_to_right = np.maximum.accumulate(precision_bits[:, ::-1], axis=1).view(np.float64)
    # The first hit reaching each point, for every row at once in one sorted array: row r's counts raised
    # by r * span, above every earlier row's.
    span = int(max(tp_count[:, -1].max(), needed.max())) + 1
    raised = np.arange(rows)[:, None] * span
    tp_count += raised
    first = np.searchsorted(tp_count.ravel(), (needed + raised).ravel()).reshape(rows, -1)
    first -= np.arange(rows)[:, None] * n_hits  # (R, 90) index into the hits; P where never reached
    best = np.take_along_axis(best_to_right, n_hits - 1 - np.minimum(first, n_hits - 1), axis=1)
    curve = np.where(first < n_hits, best, 0.0)
    return np.clip(curve - MIN_PRECISION, 0.0, None).sum(axis=1) / len(KEPT_POINTS) / (1.0 - MIN_PRECISION)


def match(detections: Detections, ground_truth: GroundTruth, classes: Sequence[str] = CLASSES,
          thresholds: Sequence[float] = DEFAULT_THRESHOLDS, samples: Sequence | None = None) -> MatchedDetections:
    """Match ``detections`` to ``ground_truth`` per class and threshold (rules in the module docstring).

    ``samples``: the ids that index the result (default: every id either side holds, sorted); they must
    include every id of the detections and the ground truth. Raises DataError as ``evaluate`` does.
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
    gt_seen = ground_truth.seen()
    if gt_seen.shape != gt_cls.shape:
        raise DataError(f"ground truth: visible must be (n,) like cls, got shape {gt_seen.shape} for {len(gt_cls)} "
                        "objects")
    ids, det_sample, gt_sample = _sample_codes(detections.sample, ground_truth.sample, samples)

    gt_count = np.zeros((len(classes), len(ids)), dtype=int)
    np.add.at(gt_count, (gt_cls, gt_sample), 1)
    gt_count_visible = np.zeros_like(gt_count)
    np.add.at(gt_count_visible, (gt_cls[gt_seen], gt_sample[gt_seen]), 1)
    rank_sample, tp, on_unseen = [], [], []
    for c in range(len(classes)):
        d_rows, g_rows = det_cls == c, gt_cls == c
        order = _rank(det_sample[d_rows], det_xy[d_rows], det_score[d_rows])
        ranked_sample, ranked_xy = det_sample[d_rows][order], det_xy[d_rows][order]
        rank_sample.append(ranked_sample)
        if not g_rows.any():  # nothing to match: every detection is a false positive
            tp.append(np.zeros((len(thresholds), len(order)), dtype=bool))
            on_unseen.append(np.zeros((len(thresholds), len(order)), dtype=bool))
            continue
        taken = _match(ranked_sample, ranked_xy, gt_sample[g_rows], gt_xy[g_rows], thresholds)  # (T, m), -1 none
        unseen = np.append(~gt_seen[g_rows], False)  # index -1: no object taken
        tp.append(taken >= 0)
        on_unseen.append(unseen[taken])
    return MatchedDetections(ids, tuple(rank_sample), tuple(tp), gt_count, classes, thresholds, tuple(on_unseen),
                             gt_count_visible)


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


def _rank(det_sample: np.ndarray, det_xy: np.ndarray, det_score: np.ndarray) -> np.ndarray:
    """Rank order of one class's detections: score descending, then sample, x, y ascending."""
    return np.lexsort((det_xy[:, 1], det_xy[:, 0], det_sample, -det_score))


def _match(det_sample: np.ndarray, det_xy: np.ndarray, gt_sample: np.ndarray, gt_xy: np.ndarray,
           thresholds: Sequence[float]) -> np.ndarray:
    """Greedy matching of one class's ranked detections (m,) to its ground truths (g,) at each of T
    thresholds -> (T, m) int: the index into the ground truths of the object each detection takes (a true
    positive), -1 for none.

    Samples never share objects, so all samples are matched at once, turn by turn: turn t takes the t-th
    ranked detection of every sample, which finds the nearest object still free in a table of its sample's
    objects (one row per sample, in the canonical x, y order, so the first of equal distances wins).
    """
    taken = np.full((len(thresholds), len(det_sample)), -1, dtype=int)
    gt_order = np.lexsort((gt_xy[:, 1], gt_xy[:, 0], gt_sample))
    gt_sample, gt_xy = gt_sample[gt_order], gt_xy[gt_order]
    row_sample, row_start, row_size = np.unique(gt_sample, return_index=True, return_counts=True)
    row = np.repeat(np.arange(len(row_sample)), row_size)  # (g,) each object's table row and column
    column = np.arange(len(gt_sample)) - np.repeat(row_start, row_size)
    table_xy = np.zeros((len(row_sample), int(row_size.max(initial=0)), 2))  # (rows, width, 2) m
    table_xy[row, column] = gt_xy
    table_object = np.zeros(table_xy.shape[:2], dtype=int)  # index into the caller's ground truths
    table_object[row, column] = gt_order
    free = np.zeros((len(thresholds),) + table_xy.shape[:2], dtype=bool)  # (T, rows, width)
    free[:, row, column] = True

    det_row = np.searchsorted(row_sample, det_sample)
    has_objects = det_row < len(row_sample)
    has_objects[has_objects] = row_sample[det_row[has_objects]] == det_sample[has_objects]
    matchable = np.flatnonzero(has_objects)  # detections whose sample has objects, in rank order
    by_row = matchable[np.argsort(det_row[matchable], kind="stable")]  # grouped by row, rank order within
    turn = np.arange(len(by_row)) - np.searchsorted(det_row[by_row], det_row[by_row])  # rank within its sample
    by_turn = np.argsort(turn, kind="stable")
    turn_start = np.searchsorted(turn[by_turn], np.arange(int(turn.max(initial=-1)) + 2))
    for t in range(len(turn_start) - 1):
        ranks = by_row[by_turn[turn_start[t]:turn_start[t + 1]]]  # at most one detection per sample
        rows = det_row[ranks]
        offset = table_xy[rows] - det_xy[ranks][:, None, :]
        distance = np.hypot(offset[..., 0], offset[..., 1])  # (n, width) m, as np.hypot of (object - detection)
        for j, threshold in enumerate(thresholds):
            candidate = np.where(free[j, rows], distance, np.inf)
            nearest = np.argmin(candidate, axis=1)  # first of equal distances: canonical (x, y) order
            hit = candidate[np.arange(len(rows)), nearest] < threshold
            taken[j, ranks[hit]] = table_object[rows[hit], nearest[hit]]
            free[j, rows[hit], nearest[hit]] = False
    return taken


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


def _sample_codes(det_sample, gt_sample, samples=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ids (S,), detection codes (m,), ground-truth codes (g,)): integer codes index ``ids``, which are
    ``samples`` when given (else the sorted ids of both sides); ids must all be int or all str."""
    det_sample, gt_sample = np.asarray(det_sample), np.asarray(gt_sample)
    given = None if samples is None else np.asarray(samples)
    kinds = {_id_kind(a) for a in (det_sample, gt_sample, given) if a is not None and len(a)}
    if None in kinds or len(kinds) > 1:
        raise DataError(f"sample ids must be all integers or all strings, got dtypes {det_sample.dtype} "
                        f"(detections) and {gt_sample.dtype} (ground truth)")
    kind = int if kinds == {"int"} else str
    det_sample, gt_sample = (a if len(a) else a.astype(kind) for a in (det_sample, gt_sample))
    if given is None:
        ids, codes = np.unique(np.concatenate([det_sample, gt_sample]), return_inverse=True)
        return ids, codes[:len(det_sample)], codes[len(det_sample):]
    if len(np.unique(given)) != len(given):
        raise DataError("the sample ids to index by must be distinct")
    order = np.argsort(given, kind="stable")
    codes = []
    for side, name in ((det_sample, "detections"), (gt_sample, "ground truth")):
        at = np.searchsorted(given[order], side)
        found = at < len(given)
        found[found] = given[order][at[found]] == side[found]
        if not found.all():
            raise DataError(f"{name}: sample id {side[~found][0].item()!r} is not among the samples to index by")
        codes.append(order[at])
    return given, codes[0], codes[1]


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


def sample_blocks(samples, size: int | None = None) -> list[np.ndarray]:
    """Indices into ``samples`` in runs of consecutive frames of one scene, at most ``size`` long (None: whole
    scenes): the resampling unit, since neighbouring frames see nearly the same objects."""
    blocks, start = [], 0
    for k in range(1, len(samples) + 1):
        if k == len(samples) or samples[k].scene != samples[start].scene or k - start == size:
            blocks.append(np.arange(start, k))
            start = k
    return blocks


def relative_drops(maps: np.ndarray) -> np.ndarray:
    """(..., K) relative drops (maps[..., 0] - maps[..., k]) / maps[..., 0] of K mAPs, the first the
    reference's own; NaN where the own mAP is 0 or an mAP is NaN."""
    own = maps[..., :1]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(own > 0, (own - maps) / own, np.nan)


def interval(values: np.ndarray) -> list:
    """95 % percentile interval of the finite values ([None, None] when there are none)."""
    finite = values[np.isfinite(values)]
    return [float(v) for v in np.percentile(finite, [2.5, 97.5])] if len(finite) else [None, None]
