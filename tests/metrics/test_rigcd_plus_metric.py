"""RigCD+ as a selectable metric (``--metric rigcd+``): calibrated matching, its shipped weights, the switch.

Oracles:
* the shipped rigcd+ weights are a fresh run of the protocol with ``metric="rigcd+"`` on the shipped CSV;
* a rigcd+ fit is a fixed point of rematching: features under its own lambdas refit to the same beta;
* a rigcd+ prediction is exactly K x RigCD under its own weights (the features come from the matching that
  minimises the weighted cost); a rigcd prediction (unit matching) is never below that and above it for
  some pair, since the weighted matching is the minimiser.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from rigopt.errors import DataError, UnknownNameError
from rigopt.metrics.calibration import (FEATURES, METRICS, fit_calibration, load_weights, pair_features,
                                        shipped_weight_names, write_weights)
from rigopt.metrics.protocol import CONTROL_RIGS, calibrate
from rigopt.metrics.ranking import predict_transfer
from rigopt.metrics.transfer import read_transfer
from rigopt.resources import data_dir
from rigopt.rig.library import load_rig, rig_names

PLUS_DIR = data_dir("metrics") / "weights-plus"


@pytest.fixture(scope="module")
def plus_study():
    return calibrate(read_transfer(data_dir("metrics") / "pccr_transfer.csv"), metric="rigcd+", resamples=0)


def test_both_metrics_ship_the_same_names():
    assert METRICS == ("rigcd", "rigcd+")
    assert shipped_weight_names("rigcd+") == shipped_weight_names("rigcd") == sorted(
        ["BEVDet", "BEVFusion", "Fast-BEV", "PETR", "joint", "sim-lss"])


@pytest.mark.parametrize("name", ["BEVDet", "BEVFusion", "Fast-BEV", "PETR", "joint"])
def test_shipped_rigcd_plus_weights_equal_a_fresh_calibration(plus_study, name):
    fits = {m.model: m.fit for m in plus_study.models} | {"joint": plus_study.joint.fit}
    fresh = fits[name].calibration
    shipped = load_weights(name, "rigcd+")
    assert shipped.metric == fresh.metric == "rigcd+"
    for key in ("K", "alpha", "lambda_t", "lambda_r", "lambda_f"):
        assert getattr(shipped, key) == pytest.approx(getattr(fresh, key), abs=1e-9), key
    assert shipped.beta == pytest.approx(fresh.beta, abs=1e-9)
    assert shipped.fallback is fresh.fallback


def test_rigcd_plus_fits_are_fixed_points_of_rematching(plus_study):
    """Refitting on the features under the fit's own matching returns the same beta."""
    pairs = plus_study.joint.pairs
    rigs = [load_rig(name) for name in dict.fromkeys([*pairs.train, *pairs.test])]
    calibration = plus_study.joint.fit.calibration
    x = pair_features(rigs, pairs.train[pairs.control], pairs.test[pairs.control], calibration.match_lambdas)
    refit = fit_calibration(x, pairs.delta[pairs.control], "joint").calibration
    assert refit.beta == pytest.approx(calibration.beta, abs=1e-6)
    # and the rematching changed something: unit-matching features differ on some calibration pair
    unit = pair_features(rigs, pairs.train[pairs.control], pairs.test[pairs.control])
    assert not np.array_equal(unit, x)


def test_rigcd_plus_predicts_K_times_its_own_rigcd_and_rigcd_never_less():
    reference = load_rig("R1")
    candidates = [load_rig(name) for name in rig_names()]
    plus, published = load_weights("joint", "rigcd+"), load_weights("joint")
    for p in predict_transfer(reference, candidates, plus):
        assert p.linear_drop == pytest.approx(plus.K * p.rigcd, rel=1e-9, abs=1e-12), p.rig
    # the same weights under the unit matching: never below the weighted minimum, above it for some rig
    as_published = type(plus)(**{**plus.__dict__, "metric": "rigcd"})
    weighted = [plus.K * p.rigcd for p in predict_transfer(reference, candidates, plus)]
    unit = [p.linear_drop for p in predict_transfer(reference, candidates, as_published)]
    assert all(u >= w - 1e-12 for u, w in zip(unit, weighted))
    assert any(u > w + 1e-6 for u, w in zip(unit, weighted))
    assert predict_transfer(reference, [reference], plus)[0].predicted_drop == pytest.approx(0.0, abs=1e-12)
    assert published.metric == "rigcd"


def test_a_weights_file_of_the_other_metric_is_refused(tmp_path):
    path = write_weights(load_weights("joint", "rigcd+"), tmp_path / "plus.json")
    with pytest.raises(DataError) as caught:
        load_weights(path)
    assert "rigcd+" in str(caught.value) and "--metric" in str(caught.value)
    assert load_weights(path, "RigCD+").metric == "rigcd+"  # case-insensitive metric names
    unit = write_weights(load_weights("joint"), tmp_path / "unit.json")
    with pytest.raises(DataError, match="rigcd weights, not rigcd\\+"):
        load_weights(unit, "rigcd+")


def test_unknown_metric_and_bad_metric_field_are_clear_errors(tmp_path):
    with pytest.raises(UnknownNameError) as caught:
        load_weights("joint", "rigcd++")
    assert "rigcd++" in str(caught.value) and "rigcd+" in str(caught.value)
    data = json.loads((PLUS_DIR / "joint.json").read_text())
    (tmp_path / "bad.json").write_text(json.dumps({**data, "metric": "mystery"}))
    with pytest.raises(DataError, match="metric must be one of rigcd, rigcd\\+"):
        load_weights(tmp_path / "bad.json", "rigcd+")


def test_calibrating_rigcd_plus_on_the_control_rigs_keeps_the_protocol_sets(plus_study):
    assert plus_study.metric == "rigcd+" and plus_study.control_rigs == tuple(CONTROL_RIGS)
    pairs = plus_study.joint.pairs
    assert pairs.control.sum() == 4 * 36 and (~pairs.control).sum() == 4 * 160
    assert set(FEATURES) == {"t", "r", "f", "count"}
