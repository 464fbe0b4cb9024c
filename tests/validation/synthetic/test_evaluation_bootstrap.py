"""The fast scene bootstrap and matching of ``rigopt.validation.synthetic.evaluation`` against their plain definitions.

Oracles (``evaluation_oracles.py`` beside this file, which the speed benchmark shares), not in the package:

* ``plain_resampled_maps``: one ``MatchedDetections.evaluation(weights)`` per resample (which expands the
  weighted true-positive flags with ``np.repeat`` and scores them with ``average_precision``), the way
  ``resampled_maps`` was computed before it scored chunks of resamples at once;
* ``plain_match``: the greedy matching as a Python loop over the ranked detections, each one looking at
  every object of its class, the way ``_match`` was written before it matched all samples turn by turn.

Equality is checked to 1e-12 for mAPs (sums are ordered differently) and exactly for matchings.
"""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.validation.synthetic import evaluation
from rigopt.validation.synthetic.evaluation import (
    Detections,
    GroundTruth,
    MatchedDetections,
    _match,
    _weighted_maps,
    match,
    resampled_maps,
)
from rigopt.validation.synthetic.scene_model import CLASSES

from evaluation_oracles import plain_match, plain_resampled_maps

TOLERANCE = 1e-12


def random_set(seed: int, n_samples: int = 20, n_classes: int = 4):
    """Detections and ground truth on a coarse grid (equal distances and scores happen), class 3 never
    annotated, class 2 never detected, some samples empty; about a third of the objects unseen."""
    rng = np.random.default_rng(seed)
    grid = np.arange(-4.0, 4.5, 0.5)
    n_gt, n_det = int(rng.integers(0, 6 * n_samples)), int(rng.integers(0, 9 * n_samples))
    gt_sample = rng.integers(0, n_samples - 2, n_gt)  # the last two samples hold no object
    gt_cls = rng.integers(0, n_classes - 1, n_gt)
    gt_xy = rng.choice(grid, (n_gt, 2))
    near = rng.integers(0, max(n_gt, 1), n_det)  # most detections sit near an object
    det_sample = np.where(rng.random(n_det) < 0.8, gt_sample[near] if n_gt else 0, rng.integers(0, n_samples, n_det))
    det_cls = np.where(rng.random(n_det) < 0.8, gt_cls[near] if n_gt else 0, rng.integers(0, n_classes, n_det))
    det_cls = np.where(det_cls == 2, 0, det_cls)
    det_xy = (gt_xy[near] if n_gt else np.zeros((n_det, 2))) + rng.choice([-1.0, -0.5, 0.0, 0.5, 1.0], (n_det, 2))
    scores = rng.choice([0.2, 0.4, 0.6, 0.8], n_det)
    truth = GroundTruth(gt_sample, gt_cls, gt_xy, rng.random(n_gt) < 0.65)
    return Detections(det_sample, det_cls, det_xy, scores), truth


def realistic_set(n_samples: int = 160, per_sample: int = 50, seed: int = 0):
    """A test split shaped like the shipped detectors': 15 objects per sample over the nine classes, 75 %
    seen by the rig, 70 % of the seen ones found (noisy, higher scores) and the rest of ``per_sample``
    detections false (random places, lower scores)."""
    rng = np.random.default_rng(seed)
    gt_sample = np.repeat(np.arange(n_samples), 15)
    gt_cls = rng.integers(len(CLASSES), size=len(gt_sample))
    gt_xy = rng.uniform(-35, 35, (len(gt_sample), 2))
    seen = rng.random(len(gt_sample)) < 0.75
    found = seen & (rng.random(len(gt_sample)) < 0.7)
    false = per_sample * n_samples - int(found.sum())
    detections = Detections(
        np.concatenate([gt_sample[found], rng.integers(n_samples, size=false)]),
        np.concatenate([gt_cls[found], rng.integers(len(CLASSES), size=false)]),
        np.concatenate([gt_xy[found] + rng.normal(0, 1.0, (int(found.sum()), 2)), rng.uniform(-35, 35, (false, 2))]),
        np.concatenate([rng.uniform(0.3, 1.0, int(found.sum())), rng.uniform(0.0, 0.5, false)]))
    return detections, GroundTruth(gt_sample, gt_cls, gt_xy, seen)


def four_classes(seed: int) -> MatchedDetections:
    return match(*random_set(seed), classes=("a", "b", "c", "d"), samples=np.arange(20))


# --- the matching ------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(8))
def test_matching_takes_the_objects_the_plain_loop_takes(seed):
    detections, truth = random_set(seed)
    thresholds = (0.5, 0.75, 1.0, 2.0)
    for c in range(4):
        d_rows, g_rows = detections.cls == c, truth.cls == c
        order = evaluation._rank(detections.sample[d_rows], detections.xy[d_rows], detections.score[d_rows])
        ranked = (detections.sample[d_rows][order], detections.xy[d_rows][order])
        objects = (truth.sample[g_rows], truth.xy[g_rows])
        expected = np.array([plain_match(*ranked, *objects, d) for d in thresholds]).reshape(len(thresholds), -1)
        taken = _match(*ranked, *objects, thresholds)
        np.testing.assert_array_equal(taken, expected)
        assert taken.dtype == expected.dtype


def test_matching_an_object_stolen_by_a_better_detection():
    """Two detections of one sample, one object each side: the better-ranked one takes the object both are
    nearest to, the second then takes the other one only where the threshold allows."""
    det_sample, det_xy = np.array([0, 0]), np.array([[0.6, 0.0], [1.1, 0.0]])
    gt_sample, gt_xy = np.array([0, 0]), np.array([[1.0, 0.0], [0.0, 0.0]])
    np.testing.assert_array_equal(_match(det_sample, det_xy, gt_sample, gt_xy, (0.5, 2.0)), [[0, -1], [0, 1]])


def test_matching_with_nothing_to_match():
    none = np.zeros(0, dtype=int), np.zeros((0, 2))
    assert _match(*none, np.array([0]), np.zeros((1, 2)), (1.0,)).shape == (1, 0)
    np.testing.assert_array_equal(_match(np.array([3]), np.zeros((1, 2)), np.array([0]), np.zeros((1, 2)), (1.0, 2.0)),
                                  [[-1], [-1]])  # the only object is in another sample


# --- the weighted mAP of many resamples at once ---------------------------------------------------


def test_repeated_detections_score_as_their_expanded_copies():
    """Sample 0 ranks TP (0.9), FP (0.8), sample 1 a TP (0.7); one object each. Sample 1 drawn twice gives
    TP, FP, TP, TP against 3: precision 1, 1/2, 2/3, 3/4 at recall 1/3, 1/3, 2/3, 1. Points 0.11..0.33
    read 1; points 0.34..0.66 are first reached at the first copy of sample 1's TP (precision 2/3) but
    read the best to its right, 3/4, from the second copy; so do 0.67..1. AP = (23 * 0.9 + 67 * 0.65) / 81."""
    truth = GroundTruth(np.array([0, 1]), np.array([0, 0]), np.zeros((2, 2)))
    found = Detections(np.array([0, 0, 1]), np.array([0, 0, 0]), np.array([[0.1, 0.0], [20.0, 20.0], [0.1, 0.0]]),
                       np.array([0.9, 0.8, 0.7]))
    matched = match(found, truth, classes=("car",), thresholds=(1.0,))
    weights = np.array([[1, 2], [1, 1], [0, 3], [2, 0], [0, 0]])
    # (1, 1): TP, FP, TP against 2 -> 193/243; (0, 3): all true -> 1; (2, 0): TP, TP, FP, FP against 2 -> 1
    expected = [(23 * 0.9 + 67 * 0.65) / 81, 193 / 243, 1.0, 1.0]
    maps = _weighted_maps(matched, weights, False)
    np.testing.assert_allclose(maps[:4], expected, rtol=0, atol=TOLERANCE)
    assert np.isnan(maps[4])  # nothing drawn: no ground truth, mAP NaN as evaluation gives
    np.testing.assert_allclose([matched.evaluation(w).map for w in weights[:4]], expected, rtol=0, atol=TOLERANCE)


@pytest.mark.parametrize("visible_only", [False, True])
@pytest.mark.parametrize("seed", range(6))
def test_weighted_maps_equal_one_evaluation_per_weighting(seed, visible_only):
    matched = four_classes(seed)
    rng = np.random.default_rng(100 + seed)
    weights = rng.integers(0, 4, (40, 20))  # samples drawn 0 to 3 times
    weights[0] = 0  # nothing drawn
    weights[1] = 0
    weights[1, 18:] = 5  # only the samples without objects
    weights[2] = 1  # the set itself
    weights[3, ::3] = 9  # some samples drawn many times
    expected = np.array([matched.evaluation(w, visible_only).map for w in weights])
    got = _weighted_maps(matched, weights, visible_only)
    np.testing.assert_array_equal(np.isnan(got), np.isnan(expected))
    np.testing.assert_allclose(got, expected, rtol=0, atol=TOLERANCE)
    assert np.isnan(got[:2]).all() and got[2] == pytest.approx(matched.evaluation(visible_only=visible_only).map,
                                                              abs=TOLERANCE)


@pytest.mark.parametrize("visible_only", [False, True])
@pytest.mark.parametrize("seed", range(4))
def test_resampled_maps_equal_the_plain_loop(seed, visible_only):
    runs = [four_classes(seed), four_classes(seed + 50)]
    groups = [[0, 1, 2], [3], [4, 5], [6, 7, 8, 9], [10, 11], [12, 13, 14], [15], [16, 17, 18, 19], [18, 19]]
    expected = plain_resampled_maps(runs, groups, 60, seed, visible_only)
    got = resampled_maps(runs, groups, 60, seed, visible_only)
    assert got.shape == (60, 2)
    np.testing.assert_array_equal(np.isnan(got), np.isnan(expected))
    np.testing.assert_allclose(got, expected, rtol=0, atol=TOLERANCE)


def test_resampling_some_samples_never_drawn():
    """Groups that leave samples out: those are drawn 0 times in every resample."""
    matched = four_classes(3)
    groups = [[0, 1], [5, 6, 7], [12]]
    np.testing.assert_allclose(resampled_maps([matched], groups, 40, 7, True),
                               plain_resampled_maps([matched], groups, 40, 7, True), rtol=0, atol=TOLERANCE)


def test_chunks_of_resamples_give_the_same_maps(monkeypatch):
    matched = four_classes(1)
    groups = [[i] for i in range(20)]
    whole = resampled_maps([matched], groups, 30, 2)
    monkeypatch.setattr(evaluation, "RESAMPLE_CHUNK_ENTRIES", 1)  # one resample a chunk
    np.testing.assert_array_equal(resampled_maps([matched], groups, 30, 2), whole)
    monkeypatch.setattr(evaluation, "RESAMPLE_CHUNK_ENTRIES", 7 * 30)  # chunks of 7 of the widest 30
    np.testing.assert_array_equal(resampled_maps([matched], groups, 30, 2), whole)
    np.testing.assert_allclose(whole, plain_resampled_maps([matched], groups, 30, 2), rtol=0, atol=TOLERANCE)


@pytest.mark.parametrize("visible_only", [False, True])
def test_resampled_maps_on_a_realistic_split(visible_only):
    detections, truth = realistic_set()
    matched = match(detections, truth, samples=np.arange(160))
    assert 0.05 < matched.evaluation(visible_only=visible_only).map < 0.9
    scenes = [np.arange(i, i + 40) for i in range(0, 160, 40)]
    expected = plain_resampled_maps([matched], scenes, 40, 0, visible_only)
    got = resampled_maps([matched], scenes, 40, 0, visible_only)
    np.testing.assert_allclose(got, expected, rtol=0, atol=TOLERANCE)
    assert np.ptp(got) > 0  # the resamples differ


def test_matching_a_realistic_split_is_unchanged():
    """The objects taken, and so the true positives and those on unseen objects, as the plain loop has them."""
    detections, truth = realistic_set(n_samples=60)
    matched = match(detections, truth, samples=np.arange(60))
    codes = evaluation._sample_codes(detections.sample, truth.sample, np.arange(60))
    for c in range(len(CLASSES)):
        d_rows, g_rows = detections.cls == c, truth.cls == c
        order = evaluation._rank(codes[1][d_rows], detections.xy[d_rows], detections.score[d_rows])
        ranked = (codes[1][d_rows][order], detections.xy[d_rows][order])
        objects = (codes[2][g_rows], truth.xy[g_rows])
        expected = np.array([plain_match(*ranked, *objects, d) for d in matched.thresholds])
        taken = _match(*ranked, *objects, matched.thresholds)
        np.testing.assert_array_equal(taken, expected)
        assert (taken >= 0).any() and (taken < 0).any()
        np.testing.assert_array_equal(matched.tp[c], taken >= 0)
        np.testing.assert_array_equal(matched.on_unseen[c], np.append(~truth.visible[g_rows], False)[taken])
