"""Predicted transfer and the ranking of candidate rigs (what ``rigopt rank`` prints).

Oracles: the reference RigCD (plain loops) and the calibrated formula written out here.
"""

from __future__ import annotations

import numpy as np
import pytest

from oracles.metrics import rigcd_reference
from rigopt.metrics.calibration import load_weights, reparameterise
from rigopt.metrics.ranking import predict_transfer, rank_candidates
from rigopt.rig.library import load_rig

CANDIDATES = ("R6", "R4", "R1-f", "R9", "R1-c6", "R2")


@pytest.fixture(scope="module")
def reference():
    return load_rig("R1")


@pytest.fixture(scope="module")
def candidates():
    return [load_rig(name) for name in CANDIDATES]


def formula(c, ref: dict) -> float:
    return c.K * (c.alpha * (c.lambda_t * ref["t"] + c.lambda_r * ref["r"] + c.lambda_f * ref["f"])
                  + (1 - c.alpha) * ref["count"])


@pytest.mark.parametrize("weights", ["joint", "BEVDet", "Fast-BEV", "PETR"])
def test_rank_candidates_is_sorted_by_predicted_drop(reference, candidates, weights):
    ranked = rank_candidates(reference, candidates, load_weights(weights))
    drops = [p.predicted_drop for p in ranked]
    assert drops == sorted(drops)
    assert sorted(p.rig for p in ranked) == sorted(CANDIDATES)


@pytest.mark.parametrize("weights", ["joint", "BEVDet"])
def test_rank_order_equals_sorting_reference_predictions(reference, candidates, weights):
    c = load_weights(weights)
    expected = sorted(CANDIDATES, key=lambda name: formula(c, rigcd_reference(reference, load_rig(name))))
    assert [p.rig for p in rank_candidates(reference, candidates, c)] == expected


def test_identical_rig_predicts_zero_drop_and_ranks_first(reference, candidates):
    ranked = rank_candidates(reference, [*candidates, load_rig("R1")], load_weights("joint"))
    assert ranked[0].rig == "R1"
    assert ranked[0].predicted_drop == pytest.approx(0.0, abs=1e-12)
    assert ranked[0].rigcd == pytest.approx(0.0, abs=1e-12)


def test_ties_keep_the_given_order(reference):
    same = [load_rig("R4"), load_rig("R1"), load_rig("R1")]
    ranked = rank_candidates(reference, same, load_weights("joint"))
    assert [p.rig for p in ranked] == ["R1", "R1", "R4"]


@pytest.mark.parametrize("weights", ["joint", "PETR", "Fast-BEV"])
def test_predicted_drop_equals_the_formula_on_reference_features(reference, candidates, weights):
    c = load_weights(weights)
    for p, rig in zip(predict_transfer(reference, candidates, c), candidates):
        linear = formula(c, rigcd_reference(reference, rig))
        assert p.linear_drop == pytest.approx(linear, rel=1e-9, abs=1e-9)
        assert p.predicted_drop == pytest.approx(float(c.link(linear)), rel=1e-9, abs=1e-9)
        assert 0.0 <= p.predicted_drop <= 1.0
        assert p.fallback is c.fallback


def test_predict_transfer_without_calibration(reference, candidates):
    predictions = predict_transfer(reference, candidates)
    assert [p.rig for p in predictions] == list(CANDIDATES)
    for p, rig in zip(predictions, candidates):
        ref = rigcd_reference(reference, rig)  # default alpha 0.9, unit lambdas
        assert p.predicted_drop is None
        assert p.reference == "R1"
        assert p.rigcd == pytest.approx(ref["rigcd"], abs=1e-9)
        assert p.match == pytest.approx(ref["match"], abs=1e-9)
        assert (p.t, p.r, p.f, p.count) == pytest.approx((ref["t"], ref["r"], ref["f"], ref["count"]), abs=1e-9)


def test_predict_transfer_rigcd_uses_the_calibration_weights(reference, candidates):
    c = load_weights("BEVFusion")
    for p, rig in zip(predict_transfer(reference, candidates, c), candidates):
        ref = rigcd_reference(reference, rig, c.alpha, c.lambdas)
        assert p.rigcd == pytest.approx(ref["rigcd"], abs=1e-9)
        assert p.match == pytest.approx(ref["match"], abs=1e-9)


def test_features_are_unit_weight_whatever_the_calibration(reference, candidates):
    skewed = reparameterise((5.0, 0.01, 0.001, 0.2), "skewed")
    plain = predict_transfer(reference, candidates)
    weighted = predict_transfer(reference, candidates, skewed)
    assert [(p.t, p.r, p.f, p.count) for p in weighted] == [(p.t, p.r, p.f, p.count) for p in plain]


def test_predicted_drop_is_linear_in_k(reference, candidates):
    c = reparameterise((0.3, 0.6, 0.9, 0.4), "k1")
    c2 = reparameterise((0.6, 1.2, 1.8, 0.8), "k2")  # same alpha and lambdas, twice K
    d1 = np.array([p.predicted_drop for p in predict_transfer(reference, candidates, c)])
    d2 = np.array([p.predicted_drop for p in predict_transfer(reference, candidates, c2)])
    assert np.allclose(d2, 2 * d1, rtol=1e-12)
