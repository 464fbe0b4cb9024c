"""Scoring multisets of samples without matching again (MatchedDetections.evaluation with weights), the
paired block bootstrap of mAPs, and the pieces of a design validation's intervals.

Oracle: ``evaluate`` on the samples written out explicitly (a sample counted w times is w copies under new
ids), which shares no code path with the weights.
"""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.validation.synthetic.evaluation import Detections, GroundTruth, evaluate, match, resampled_maps
from rigopt.errors import DataError

pytest.importorskip("torch")
from rigopt.validation.synthetic.evaluation import interval, relative_drops, sample_blocks  # noqa: E402

N_CLASSES = 3
CLASSES = ("car", "truck", "bus")


def random_run(rng, n_samples=12):
    """Ground truth and detections near it (and some far off) on samples s00..; distinct scores."""
    truth, found = [], []
    for i in range(n_samples):
        for _ in range(rng.integers(0, 5)):
            truth.append((f"s{i:02d}", int(rng.integers(N_CLASSES)), *rng.uniform(-30, 30, 2)))
        for row in truth[-3:]:
            if row[0] == f"s{i:02d}" and rng.random() < 0.8:
                found.append((row[0], row[1], *(np.array(row[2:]) + rng.normal(0, 1.5, 2))))
        for _ in range(rng.integers(0, 3)):
            found.append((f"s{i:02d}", int(rng.integers(N_CLASSES)), *rng.uniform(-30, 30, 2)))
    scores = rng.permutation(len(found)) / len(found) + 0.01
    return [row + (score,) for row, score in zip(found, scores)], truth


def as_arrays(found, truth):
    detections = Detections(np.array([r[0] for r in found], dtype=str), np.array([r[1] for r in found], dtype=int),
                            np.array([r[2:4] for r in found], dtype=float).reshape(-1, 2),
                            np.array([r[4] for r in found], dtype=float))
    ground_truth = GroundTruth(np.array([r[0] for r in truth], dtype=str), np.array([r[1] for r in truth], dtype=int),
                               np.array([r[2:4] for r in truth], dtype=float).reshape(-1, 2))
    return detections, ground_truth


def written_out(found, truth, weights, samples):
    """The multiset as explicit copies: copy k of sample s becomes sample 's#k'."""
    count = dict(zip(samples, weights))
    copies = lambda rows: [(f"{r[0]}#{k}",) + tuple(r[1:]) for r in rows for k in range(count[r[0]])]  # noqa: E731
    return as_arrays(copies(found), copies(truth))


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_weighted_samples_score_as_their_written_out_copies(seed):
    rng = np.random.default_rng(seed)
    found, truth = random_run(rng)
    samples = [f"s{i:02d}" for i in range(12)]
    matched = match(*as_arrays(found, truth), CLASSES, samples=samples)
    weights = rng.integers(0, 4, size=12)
    weights[0] = 1  # never an empty multiset
    expected = evaluate(*written_out(found, truth, weights, samples), CLASSES)
    result = matched.evaluation(weights)
    np.testing.assert_allclose(result.ap, expected.ap, atol=1e-12)
    np.testing.assert_array_equal(result.n_ground_truth, expected.n_ground_truth)
    assert result.map == pytest.approx(expected.map, abs=1e-12)


def test_unit_weights_are_the_plain_evaluation_and_a_zero_weight_drops_the_sample():
    found, truth = random_run(np.random.default_rng(7))
    samples = [f"s{i:02d}" for i in range(12)]
    matched = match(*as_arrays(found, truth), CLASSES, samples=samples)
    assert matched.evaluation().map == pytest.approx(evaluate(*as_arrays(found, truth), CLASSES).map, abs=1e-12)
    weights = np.ones(12, dtype=int)
    weights[3] = 0
    kept = lambda rows: [r for r in rows if r[0] != "s03"]  # noqa: E731
    assert matched.evaluation(weights).map == pytest.approx(evaluate(*as_arrays(kept(found), kept(truth)),
                                                                     CLASSES).map, abs=1e-12)


@pytest.mark.parametrize("weights", [[1, 1], [1, -1, 1], [0.5, 1, 1]])
def test_weights_of_the_wrong_shape_sign_or_kind_are_refused(weights):
    detections, truth = as_arrays([("b", 0, 1.0, 0.0, 0.9)], [("b", 0, 1.0, 0.0)])
    with pytest.raises(DataError, match="sample weights"):
        match(detections, truth, CLASSES, samples=["a", "b", "c"]).evaluation(np.array(weights))


def test_given_samples_index_the_result_in_their_order():
    detections, truth = as_arrays([("b", 0, 1.0, 0.0, 0.9)], [("b", 0, 1.0, 0.0), ("a", 1, 5.0, 5.0)])
    matched = match(detections, truth, CLASSES, samples=["c", "b", "a"])
    assert list(matched.samples) == ["c", "b", "a"]
    np.testing.assert_array_equal(matched.gt_count[:2], [[0, 1, 0], [0, 0, 1]])
    assert list(matched.rank_sample[0]) == [1]


def test_samples_that_miss_an_id_or_repeat_one_are_refused():
    detections, truth = as_arrays([("b", 0, 1.0, 0.0, 0.9)], [("b", 0, 1.0, 0.0)])
    with pytest.raises(DataError, match="'b' is not among"):
        match(detections, truth, CLASSES, samples=["a"])
    with pytest.raises(DataError, match="distinct"):
        match(detections, truth, CLASSES, samples=["b", "b"])


def test_resampled_maps_are_paired_and_seeded():
    found, truth = random_run(np.random.default_rng(3))
    samples = [f"s{i:02d}" for i in range(12)]
    matched = match(*as_arrays(found, truth), CLASSES, samples=samples)
    blocks = [np.arange(k, k + 3) for k in range(0, 12, 3)]
    maps = resampled_maps([matched, matched], blocks, resamples=50, seed=5)
    assert maps.shape == (50, 2)
    np.testing.assert_array_equal(maps[:, 0], maps[:, 1])  # the same draw for every run
    assert np.ptp(maps[:, 0]) > 0  # resamples differ
    np.testing.assert_array_equal(maps, resampled_maps([matched, matched], blocks, resamples=50, seed=5))


def test_one_resample_is_the_evaluation_of_the_drawn_blocks():
    found, truth = random_run(np.random.default_rng(4))
    samples = [f"s{i:02d}" for i in range(12)]
    matched = match(*as_arrays(found, truth), CLASSES, samples=samples)
    blocks = [np.arange(k, k + 4) for k in range(0, 12, 4)]
    drawn = np.random.default_rng(11).integers(3, size=3)
    weights = np.bincount(np.concatenate([blocks[i] for i in drawn]), minlength=12)
    expected = evaluate(*written_out(found, truth, weights, samples), CLASSES).map
    assert resampled_maps([matched], blocks, resamples=1, seed=11)[0, 0] == pytest.approx(expected, abs=1e-12)


def test_resampling_refuses_runs_on_other_samples_and_bad_groups():
    found, truth = random_run(np.random.default_rng(5))
    samples = [f"s{i:02d}" for i in range(12)]
    matched = match(*as_arrays(found, truth), CLASSES, samples=samples)
    other = match(*as_arrays(found, truth), CLASSES, samples=samples[::-1])
    with pytest.raises(DataError, match="same samples"):
        resampled_maps([matched, other], [np.arange(12)])
    with pytest.raises(DataError, match="sample indices"):
        resampled_maps([matched], [np.arange(10, 14)])
    with pytest.raises(DataError, match="sample indices"):
        resampled_maps([matched], [])


class Frame:
    def __init__(self, scene):
        self.scene = scene


def test_blocks_follow_scenes_and_hold_at_most_size_frames():
    frames = [Frame("a")] * 25 + [Frame("b")] * 7
    blocks = sample_blocks(frames, 10)
    assert [list(b[[0, -1]]) for b in blocks] == [[0, 9], [10, 19], [20, 24], [25, 31]]
    np.testing.assert_array_equal(np.concatenate(blocks), np.arange(32))
    scenes = sample_blocks(frames + [Frame("a")] * 3)  # whole scenes: a scene seen again later starts a new run
    assert [len(b) for b in scenes] == [25, 7, 3]


def test_relative_drops_and_intervals():
    maps = np.array([[0.2, 0.1, 0.2, 0.3], [0.0, 0.1, 0.0, 0.0]])
    drops = relative_drops(maps)
    np.testing.assert_allclose(drops[0], [0.0, 0.5, 0.0, -0.5])
    assert np.isnan(drops[1]).all()  # own mAP 0: no drop is defined
    assert interval(np.array([np.nan, np.nan])) == [None, None]
    low, high = interval(np.append(np.arange(101.0), np.nan))
    assert (low, high) == pytest.approx((2.5, 97.5))
