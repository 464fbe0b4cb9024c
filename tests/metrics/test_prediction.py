"""The predicted drop's link, interval and domain (rigopt.metrics.prediction) and their place in calibrations.

Oracles: closed forms worked out here, synthetic data with known parameters, and counts made by hand."""

import json

import numpy as np
import pytest

from rigopt.errors import DataError
from rigopt.metrics.calibration import load_weights, write_weights
from rigopt.metrics.prediction import (Domain, Link, conformal_halfwidth, domain_of, fit_link, hull_distance,
                                       leave_one_rig_out_residuals)
from rigopt.metrics.protocol import calibrate
from rigopt.metrics.transfer import read_transfer
from rigopt.resources import data_dir


@pytest.mark.parametrize("link", [Link("exp", (2.0,)), Link("hill", (1.7, 0.35))])
def test_links_are_monotone_from_zero_towards_one(link):
    s = np.linspace(0.0, 50.0, 2001)
    values = link(s)
    assert values[0] == 0.0 and np.all(np.diff(values) >= 0) and 0.95 < values[-1] <= 1.0
    assert link(-3.0) == 0.0  # a negative linear prediction is no drop


def test_the_hill_link_is_one_half_at_its_scale():
    assert Link("hill", (2.5, 0.4))(0.4) == pytest.approx(0.5)
    assert Link("exp", (2.0,))(np.log(2.0) / 2.0) == pytest.approx(0.5)


@pytest.mark.parametrize("kind, parameters", [("exp", (1.6,)), ("hill", (2.2, 0.5))])
def test_fit_link_recovers_the_parameters_of_noise_free_data(kind, parameters):
    s = np.linspace(0.01, 3.0, 40)
    fitted = fit_link(s, Link(kind, parameters)(s), kind)
    assert fitted.kind == kind and fitted.parameters == pytest.approx(parameters, rel=1e-4)


def test_conformal_halfwidth_is_the_ceil_n_plus_one_level_order_statistic():
    residuals = np.arange(1.0, 11.0) * np.array([1, -1] * 5)  # |r| = 1 .. 10
    assert conformal_halfwidth(residuals, 0.9) == 10.0  # ceil(11 * 0.9) = 10th smallest
    assert conformal_halfwidth(residuals, 0.5) == 6.0  # ceil(5.5) = 6th
    with pytest.raises(DataError):
        conformal_halfwidth([], 0.9)


def test_leave_one_rig_out_never_predicts_a_pair_from_a_fit_that_saw_its_rig():
    train = np.array(["A", "A", "A", "B", "B", "B", "C", "C", "C"])
    test = np.array(["A", "B", "C", "A", "B", "C", "A", "B", "C"])
    delta = np.arange(9.0)
    seen = []

    def fit_and_predict(fit_mask, predict_mask):
        assert not (fit_mask & predict_mask).any()
        seen.append(set(zip(train[predict_mask], test[predict_mask])))
        return np.zeros(predict_mask.sum())

    residuals = leave_one_rig_out_residuals(train, test, delta, fit_and_predict)
    assert len(residuals) == 12  # six off-diagonal pairs, each left out once for each of its two rigs
    assert seen[0] == {("A", "B"), ("A", "C"), ("B", "A"), ("C", "A")}


def test_hull_distance_is_zero_inside_and_euclidean_outside():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    assert hull_distance(square, [0.3, 0.6]) == pytest.approx(0.0, abs=1e-9)
    assert hull_distance(square, [2.0, 0.5]) == pytest.approx(1.0, abs=1e-6)
    assert hull_distance(square, [2.0, 2.0]) == pytest.approx(np.sqrt(2.0), abs=1e-6)


def test_a_domain_flags_each_out_of_range_term_and_by_how_much():
    domain = domain_of([[0.0, 0.0, 0.0, 0.0], [0.5, 0.2, 25.0, 0.25], [0.5, 0.2, 25.0, 0.25]])
    assert len(domain.points) == 2  # duplicates dropped
    inside, outside = domain.check([[0.25, 0.1, 12.5, 0.125], [2.5, 0.1, 12.5, 0.125]])
    assert not inside.flagged and inside.hull_distance == pytest.approx(0.0, abs=1e-9)
    assert outside.flagged and list(outside.terms) == ["t"]
    assert outside.to_dict()["terms"][0]["beyond"] == pytest.approx(2.0)
    assert "t 2.5 m > 0.5" in outside.describe()


def test_a_point_inside_every_range_but_off_the_hull_is_flagged_by_the_hull():
    domain = Domain(np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 1.0, 1.0, 1.0]]))  # a diagonal segment
    (check,) = domain.check([[1.0, 0.0, 0.0, 0.0]])
    assert not check.terms and check.hull_distance > 0.5 and check.flagged


@pytest.fixture(scope="module")
def study():
    return calibrate(read_transfer(data_dir("metrics") / "pccr_transfer.csv"), resamples=0)


def test_every_fit_carries_a_link_interval_and_domain_from_its_control_pairs(study):
    for m in study.models:
        c = m.fit.calibration
        assert c.link.kind == min(m.link_choice.loro_mae, key=m.link_choice.loro_mae.get)
        assert c.interval.level == 0.9 and c.interval.halfwidth > 0
        control = m.pairs.features[m.pairs.control]
        assert len(c.domain.points) == len(np.unique(np.round(control, 9), axis=0))


def test_reported_interval_coverage_is_the_share_of_held_out_drops_inside(study):
    for m in study.models:
        pairs, held = m.pairs, ~m.pairs.control
        low, high = m.fit.calibration.interval.around(m.fit.calibration.bounded_drop(*pairs.features[held].T))
        inside = np.mean((low <= pairs.delta[held]) & (pairs.delta[held] <= high))
        assert m.bounded_heldout.coverage == pytest.approx(inside)
        assert m.bounded_heldout.n == held.sum()


def test_the_link_leaves_held_out_rho_unchanged(study):
    from rigopt.metrics.reliability import spearman

    for m in study.models:
        held = ~m.pairs.control
        assert spearman(m.pairs.drop[held], m.pairs.delta[held])[0] == pytest.approx(m.heldout.rho, abs=1e-12)


@pytest.mark.parametrize("name", ["BEVDet", "joint"])
def test_shipped_weights_carry_the_fresh_link_and_interval(study, name):
    fits = {m.model: m.fit for m in study.models} | {"joint": study.joint.fit}
    fresh, shipped = fits[name].calibration, load_weights(name)
    assert shipped.link.kind == fresh.link.kind
    assert shipped.link.parameters == pytest.approx(fresh.link.parameters, rel=1e-6)
    assert shipped.interval.halfwidth == pytest.approx(fresh.interval.halfwidth, rel=1e-6)
    assert np.allclose(shipped.domain.points, fresh.domain.points, atol=1e-9)


def test_weights_files_round_trip_the_prediction_parts_and_refuse_malformed_ones(tmp_path):
    joint = load_weights("joint")
    back = load_weights(write_weights(joint, tmp_path / "w.json"))
    assert back.link == joint.link and back.interval == joint.interval
    assert np.array_equal(back.domain.points, joint.domain.points)
    data = json.loads((tmp_path / "w.json").read_text())
    data["link"] = {"kind": "cubic", "parameters": [1.0]}
    (tmp_path / "bad.json").write_text(json.dumps(data))
    with pytest.raises(DataError, match="malformed"):
        load_weights(tmp_path / "bad.json")
