"""Rig-distance terms for lifting detectors (rigopt/metrics/lifting.py)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.metrics.calibration import LIFTING_METRICS
from rigopt.camera import CameraModel
from rigopt.metrics.lifting import DEPTH_RANGE, PAIR_TERMS, TERMS, ground_depths, lifting_terms, pair_terms
from rigopt.metrics.rigcd import DEFAULT_ALPHA, DEFAULT_LAMBDAS, RigBatch, match_pairs, rigcd
from rigopt.rig.library import load_rig
from rigopt.rig.model import Camera, Rig


def _moved(rig: Rig, transform) -> Rig:
    return dataclasses.replace(rig, name=rig.name + "'", cameras=tuple(transform(c) for c in rig.cameras))


def _column(values, name):
    return values[:, TERMS.index(name)]


def test_a_rig_against_itself_is_zero_and_rigcd_terms_are_the_published_ones():
    r1, r6 = load_rig("R1"), load_rig("R6")
    values = lifting_terms([r1, r1], [r1, r6])
    assert np.all(values[0] == 0)
    published = rigcd(r1, r6)
    assert values[1, :4] == pytest.approx([published.t, published.r, published.f, published.count], abs=1e-12)


def test_yaw_and_plan_moves_leave_the_depth_prior_alone():
    r1 = load_rig("R1")
    turned = _moved(r1, lambda c: dataclasses.replace(
        c, position=c.position + np.array([0.7, -0.4, 0.0]), rotation=rotation_from_yaw_pitch_roll(0.3, 0, 0) @ c.rotation))
    values = lifting_terms([r1], [turned])[0]
    assert _column(values[None], "dpm")[0] == pytest.approx(0, abs=1e-12)
    assert _column(values[None], "t_vert")[0] == pytest.approx(0, abs=1e-12)
    assert _column(values[None], "t_plan")[0] == pytest.approx(np.hypot(0.7, 0.4))
    assert _column(values[None], "r_yaw")[0] == pytest.approx(0.3)
    assert _column(values[None], "r_tilt")[0] == pytest.approx(0, abs=1e-12)


def test_a_camera_twice_as_high_sees_the_ground_twice_as_far():
    level = Camera.pinhole("C", np.array([0.0, 0.0, 0.5]), np.eye(3), 90.0)
    high = dataclasses.replace(level, position=np.array([0.0, 0.0, 1.0]))
    low, up = (np.exp(ground_depths([c], grid=(4, 8))[0]) for c in (level, high))
    ground = (up < DEPTH_RANGE[1]) & (low > DEPTH_RANGE[0])
    assert ground.sum() >= 4 and np.allclose(up[ground], 2 * low[ground])
    assert np.allclose(low[:16], DEPTH_RANGE[1])  # the upper half of a level camera sees no ground


def test_pitch_counts_as_tilt_and_changes_the_depth_prior():
    r1 = load_rig("R1")
    pitched = _moved(r1, lambda c: dataclasses.replace(c, rotation=c.rotation @ rotation_from_yaw_pitch_roll(0, -0.2, 0)))
    values = lifting_terms([r1], [pitched])
    assert _column(values, "r_tilt")[0] == pytest.approx(0.2)
    assert _column(values, "r_yaw")[0] == pytest.approx(0, abs=1e-12)
    assert _column(values, "dpm")[0] > 0.3


def test_pair_terms_averaged_over_the_matching_are_the_lifting_terms():
    r1, r6 = load_rig("R1"), load_rig("R6")
    pairs = pair_terms(r6.positions, r6.rotations, CameraModel.of_cameras(r6.cameras), r1)  # (9, 8, 5)
    assert pairs.shape == (len(r6), len(r1), len(PAIR_TERMS))
    _, assignment = match_pairs(RigBatch.from_rigs([r6]), np.arange(1), RigBatch.from_rigs([r1]), np.arange(1),
                                DEFAULT_ALPHA, DEFAULT_LAMBDAS, keep_assignment=True)
    rows, cols = assignment[0]
    assert pairs[rows, cols].mean(axis=0) == pytest.approx(lifting_terms([r6], [r1])[0, 4:], rel=1e-12, abs=1e-12)
    itself = pair_terms(r1.positions, r1.rotations, CameraModel.of_cameras(r1.cameras), r1)
    assert np.allclose(np.diagonal(itself, axis1=0, axis2=1), 0)


def test_a_lifting_calibration_predicts_its_weighted_terms_clipped_to_one():
    from rigopt.metrics.calibration import lifting_calibration
    from rigopt.metrics.ranking import predict_transfer

    r1, r6, r4 = load_rig("R1"), load_rig("R6"), load_rig("R4")
    weights = {"t": 0.05, "f": 0.01, "count": 0.3, "t_vert": 0.2, "r_tilt": 2.0, "dpm": 0.7}
    calibration = lifting_calibration("test", weights, "test-metric")
    terms = lifting_terms([r1, r1], [r6, r4])
    expected = sum(w * _column(terms, name) for name, w in weights.items())
    predicted = predict_transfer(r1, [r6, r4], calibration)
    assert [p.linear_drop for p in predicted] == pytest.approx(expected, rel=1e-12)
    assert [p.predicted_drop for p in predicted] == pytest.approx(np.clip(expected, 0, 1), rel=1e-12)
    assert [p.rigcd * calibration.K for p in predicted] == pytest.approx(expected, rel=1e-12)
    with pytest.raises(Exception, match="lifting weights"):
        lifting_calibration("bad", {"height": 1.0}, "test-metric")


@pytest.mark.parametrize("metric", LIFTING_METRICS)
def test_a_shipped_lifting_metric_predicts_with_the_study_s_frozen_weights(metric):
    """The shipped weights are the validation study's candidate, fitted before its measurement, unchanged."""
    import json
    from pathlib import Path

    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.ranking import predict_transfer

    frozen = json.loads((Path(__file__).resolve().parents[2] / "studies" / "validation" / "candidates.json")
                        .read_text())["candidates"][metric.replace("-", "_")]["weights"]
    r1, others = load_rig("R1"), [load_rig(name) for name in ("R2", "R5", "R6", "R9")]
    terms = lifting_terms([r1] * len(others), others)
    expected = sum(w * _column(terms, name) for name, w in frozen.items())
    calibration = load_weights("joint", metric)
    assert [p.linear_drop for p in predict_transfer(r1, others, calibration)] == pytest.approx(expected, rel=1e-12)
