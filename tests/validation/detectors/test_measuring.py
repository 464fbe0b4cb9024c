"""Measurement protocols (rigopt/validation/detectors/measuring.py) and how shipped.py applies them: the frames a
protocol keeps, its cache folder, and its scores taken by weight from a full matching equal to matching only
its frames (what rendering only those frames gives)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from rigopt.errors import RigoptError
from rigopt.rig.library import load_rig
from rigopt.validation.detectors import shipped
from rigopt.validation.detectors.measuring import FULL, PROTOCOLS, QUICK, protocol_named
from rigopt.validation.synthetic.evaluation import Detections, GroundTruth, match, resampled_maps, sample_blocks
from rigopt.validation.synthetic.scene_model import CLASSES

TEST_DATA = {"split": "test", "scenes": 3, "frames": 10, "seed_offset": 0}


def test_the_new_scenes_protocol_takes_other_seeds_and_says_so():
    from rigopt.validation.detectors.measuring import QUICK_NEW_SCENES
    from rigopt.validation.synthetic.scenes import SEED_OFFSET_STEP

    detector = shipped.ShippedDetector(Path("."), {"test_data": TEST_DATA})
    known, new = shipped.test_scenes(detector, QUICK), shipped.test_scenes(detector, QUICK_NEW_SCENES)
    assert [s.seed + SEED_OFFSET_STEP for s in known] == [s.seed for s in new]
    assert len(new[0].frames) == 3
    assert QUICK_NEW_SCENES.describe(TEST_DATA) == ("protocol quick-s1: every 4th frame (3 of 10) of 3 new test "
                                                    "scenes (seed offset 1), 9 samples")


def test_protocols_count_their_frames_and_samples():
    assert [FULL.frames(TEST_DATA), QUICK.frames(TEST_DATA)] == [10, 3]  # frames 0, 4, 8
    assert [FULL.samples(TEST_DATA), QUICK.samples(TEST_DATA)] == [30, 9]
    assert QUICK.describe(TEST_DATA) == "protocol quick: every 4th frame (3 of 10) of the 3 test scenes, 9 samples"
    assert FULL.describe(TEST_DATA).startswith("protocol full: every frame of the 3 test scenes")


def test_a_protocol_is_found_by_name_and_an_unknown_one_is_refused_with_the_names():
    assert protocol_named("QUICK") is QUICK and set(PROTOCOLS) == {"full", "quick", "quick-s1"}
    with pytest.raises(RigoptError, match="full.*quick"):
        protocol_named("fast")


def test_the_quick_scenes_are_every_fourth_frame_of_the_full_ones():
    detector = shipped.ShippedDetector(Path("."), {"test_data": TEST_DATA})
    full, quick = shipped.test_scenes(detector, FULL), shipped.test_scenes(detector, QUICK)
    assert [s.name for s in quick] == [s.name for s in full]
    for a, b in zip(full, quick):
        assert [f.timestamp_us for f in b.frames] == [f.timestamp_us for f in a.frames[0::4]]
        for x, y in zip(b.frames, a.frames[0::4]):
            np.testing.assert_array_equal(x.T_world_ego, y.T_world_ego)


def test_each_protocol_has_its_own_cache_folder_and_full_keeps_the_old_one():
    rig = load_rig("R1")
    assert shipped.cache_name(rig) == f"R1-{shipped.rig_key(rig)}" == shipped.cache_name(rig, FULL)
    assert shipped.cache_name(rig, QUICK) == f"R1-{shipped.rig_key(rig)}-quick"


def scenes_of_frames(n_scenes: int, frames: int, seed: int):
    """Detections and ground truth of n_scenes x frames samples (sample = scene * frames + frame), shaped like
    a detector's: most objects found near their place, some false detections."""
    rng = np.random.default_rng(seed)
    n = n_scenes * frames
    gt_sample = np.repeat(np.arange(n), 6)
    gt_cls = rng.integers(len(CLASSES), size=len(gt_sample))
    gt_xy = rng.uniform(-30, 30, (len(gt_sample), 2))
    found = rng.random(len(gt_sample)) < 0.7
    false = 3 * n
    detections = Detections(np.concatenate([gt_sample[found], rng.integers(n, size=false)]),
                            np.concatenate([gt_cls[found], rng.integers(len(CLASSES), size=false)]),
                            np.concatenate([gt_xy[found] + rng.normal(0, 0.8, (int(found.sum()), 2)),
                                            rng.uniform(-30, 30, (false, 2))]),
                            np.concatenate([rng.uniform(0.3, 1, int(found.sum())), rng.uniform(0, 0.6, false)]))
    return detections, GroundTruth(gt_sample, gt_cls, gt_xy, rng.random(len(gt_sample)) < 0.8)


@dataclasses.dataclass
class Sample:
    scene: int


@pytest.mark.parametrize("seed", range(3))
def test_quick_scores_taken_by_weight_equal_the_scores_of_its_frames_alone(seed):
    n_scenes, frames = 5, 8
    detections, truth = scenes_of_frames(n_scenes, frames, seed)
    samples = np.arange(n_scenes * frames)
    matched = match(detections, truth, samples=samples)
    blocks = sample_blocks([Sample(k // frames) for k in samples])
    weighed = shipped.scores_on_frames(matched, blocks, QUICK, 300, 0)

    kept = np.concatenate([block[::4] for block in blocks])  # frames 0 and 4 of each scene
    rows = np.isin(detections.sample, kept)
    renumber = {old: new for new, old in enumerate(kept)}
    alone_detections = Detections(np.array([renumber[s] for s in detections.sample[rows]]), detections.cls[rows],
                                  detections.xy[rows], detections.score[rows])
    objects = np.isin(truth.sample, kept)
    alone_truth = GroundTruth(np.array([renumber[s] for s in truth.sample[objects]]), truth.cls[objects],
                              truth.xy[objects], truth.visible[objects])
    alone = match(alone_detections, alone_truth, samples=np.arange(len(kept)))
    alone_blocks = sample_blocks([Sample(k // 2) for k in range(len(kept))])
    assert weighed["mAP"] == pytest.approx(alone.evaluation().map, abs=1e-12)
    assert weighed["mAP_visible"] == pytest.approx(alone.evaluation(visible_only=True).map, abs=1e-12)
    np.testing.assert_allclose(weighed["resampled"], resampled_maps([alone], alone_blocks, 300, 0)[:, 0], atol=1e-12)
    np.testing.assert_allclose(weighed["resampled_visible"],
                               resampled_maps([alone], alone_blocks, 300, 0, visible_only=True)[:, 0], atol=1e-12)
    full = shipped.scores_on_frames(matched, blocks, FULL, 300, 0)
    assert full["mAP"] == pytest.approx(matched.evaluation().map, abs=1e-15) != pytest.approx(weighed["mAP"])


def test_a_pack_without_a_protocol_is_refused_with_how_to_add_it(tmp_path):
    detector = shipped.ShippedDetector(tmp_path, {"test_data": TEST_DATA, "seeds": {"0": {}}})
    with pytest.raises(RigoptError, match="no reference scores for protocol quick.*add_protocol"):
        shipped.reference_scores(detector, QUICK)
