"""Calibrated RigCD: the two fits, the reparameterisation, the fallback, and the weights files.

Oracles: the optimality (KKT) conditions of a non-negative least squares, closed forms worked out by hand,
and the shipped CSV parsed here.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from rigopt.errors import DataError, RigoptError, UnknownNameError
from rigopt.metrics.calibration import (
    fit_both,
    fit_calibration,
    fit_lbfgsb,
    fit_nnls,
    load_weights,
    pair_features,
    reparameterise,
    shipped_weight_names,
    write_weights,
)
from rigopt.rig.library import load_rig

REPO = Path(__file__).resolve().parents[2]
SHIPPED_CSV = REPO / "metrics" / "pccr_transfer.csv"
WEIGHTS_DIR = REPO / "metrics" / "weights"
MODELS = ("BEVDet", "BEVFusion", "Fast-BEV", "PETR")
CONTROL = {"R1", "R1-c10", "R1-c6", "R1-f", "R1-r", "R1-t"}


def objective(beta, x, y) -> float:
    residual = np.asarray(x) @ np.asarray(beta) - np.asarray(y)
    return float(residual @ residual)


@pytest.fixture(scope="module")
def control_sets():
    """{model: (features (36, 4), delta (36,))} of the control pairs, parsed from the shipped CSV here."""
    maps = {}
    with SHIPPED_CSV.open(newline="") as handle:
        for row in csv.DictReader(handle):
            maps[(row["model"], row["train_rig"], row["test_rig"])] = float(row["mAP"])
    rigs = [load_rig(name) for name in sorted(CONTROL)]
    out = {}
    for model in MODELS:
        pairs = [(a, b) for (m, a, b) in maps if m == model and a in CONTROL and b in CONTROL]
        delta = np.array([(maps[(model, a, a)] - maps[(model, a, b)]) / maps[(model, a, a)] for a, b in pairs])
        features = pair_features(rigs, [a for a, _ in pairs], [b for _, b in pairs])
        out[model] = (features, delta)
    return out


# --- the two fits ------------------------------------------------------------------------------------


def test_each_model_has_36_control_pairs(control_sets):
    assert {m: len(d) for m, (_, d) in control_sets.items()} == {m: 36 for m in MODELS}


def kkt_violation(beta, x, y) -> float:
    """Largest violation of the optimality conditions of min |x beta - y|^2, beta >= 0, relative to the
    gradient's scale: beta >= 0; gradient g = 2 x^T (x beta - y) zero where beta > 0, >= 0 where beta = 0."""
    beta, x, y = np.asarray(beta), np.asarray(x), np.asarray(y)
    g = 2.0 * x.T @ (x @ beta - y)
    scale = 2.0 * np.abs(x.T) @ (np.abs(x @ beta) + np.abs(y)) + 1e-12
    violation = np.where(beta > 0, np.abs(g), np.maximum(-g, 0.0)) / scale
    return float(max(violation.max(), np.maximum(-beta, 0.0).max()))


@pytest.mark.parametrize("model", MODELS)
def test_lbfgsb_and_nnls_agree_on_the_real_control_pairs(control_sets, model):
    x, y = control_sets[model]
    beta_l, beta_q = fit_lbfgsb(x, y), fit_nnls(x, y)
    assert np.all(beta_l >= 0) and np.all(beta_q >= 0)
    assert np.max(np.abs(beta_l - beta_q)) <= 1e-3
    assert abs(objective(beta_l, x, y) - objective(beta_q, x, y)) <= 1e-6 * objective(beta_q, x, y)


@pytest.mark.parametrize("model", MODELS)
def test_nnls_is_optimal_on_the_real_control_pairs(control_sets, model):
    x, y = control_sets[model]
    assert kkt_violation(fit_nnls(x, y), x, y) <= 1e-9
    assert kkt_violation(fit_nnls(x, y) + np.array([0.0, 0.0, 1e-3, 0.0]), x, y) > 1e-6  # the check can fail


@pytest.mark.parametrize("seed", range(8))
def test_both_fits_are_optimal_on_random_problems(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(12, 60))
    x = rng.uniform(0.0, 1.0, (n, 4))
    truth = rng.uniform(-0.5, 1.0, 4)  # negative entries make the bound active
    y = x @ truth + rng.normal(0.0, 0.05, n)
    beta_l, beta_q = fit_lbfgsb(x, y), fit_nnls(x, y)
    assert kkt_violation(beta_q, x, y) <= 1e-9
    assert np.all(beta_l >= 0) and np.max(np.abs(beta_l - beta_q)) <= 1e-3
    assert objective(beta_q, x, y) <= objective(beta_l, x, y) * (1 + 1e-12) + 1e-15  # the exact one is lowest
    assert abs(objective(beta_l, x, y) - objective(beta_q, x, y)) <= 1e-6 * max(objective(beta_q, x, y), 1e-12)


def test_fit_calibration_reports_agreement_on_random_problem():
    rng = np.random.default_rng(42)
    x = rng.uniform(0.0, 1.0, (40, 4))
    y = x @ np.array([0.4, 0.1, 0.05, 0.2]) + rng.normal(0.0, 0.01, 40)
    fit = fit_calibration(x, y, "random")
    assert fit.qp_agrees
    assert fit.n == 40
    assert fit.objective_qp == pytest.approx(objective(fit.beta_qp, x, y), rel=1e-12)
    assert fit.objective_lbfgsb == pytest.approx(objective(fit.beta_lbfgsb, x, y), rel=1e-12)


def test_known_optimum_of_a_separable_problem():
    # Each row sees one feature, so the problem splits into four 1-D problems: beta_k = max(0, mean of y_k).
    x = np.vstack([np.eye(4), 2 * np.eye(4)])
    y = np.array([0.2, -0.3, 0.5, 0.1, 0.4, -0.6, 1.0, 0.2])
    # 1-D: min (b - y1)^2 + (2b - y2)^2 -> b = (y1 + 2 y2) / 5, clipped at 0
    expected = np.array([(0.2 + 0.8) / 5, 0.0, (0.5 + 2.0) / 5, (0.1 + 0.4) / 5])
    assert fit_nnls(x, y) == pytest.approx(expected, abs=1e-12)
    assert fit_lbfgsb(x, y) == pytest.approx(expected, abs=1e-5)
    assert fit_nnls(x, y)[1] == 0.0  # the active set gives an exact zero


def test_unconstrained_optimum_is_recovered_when_feasible():
    x = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0], [1.0, 1.0, 1.0, 1.0]])
    beta = np.array([0.3, 0.6, 0.9, 0.4])
    y = x @ beta  # exact fit, all positive
    assert fit_nnls(x, y) == pytest.approx(beta, abs=1e-12)
    assert fit_lbfgsb(x, y) == pytest.approx(beta, abs=1e-5)


def test_both_fits_recover_known_betas():
    rng = np.random.default_rng(1)
    x = rng.uniform(0, 1, (40, 5))
    beta = np.array([0.3, 0.0, 1.2, 0.05, 0.0])
    fit = fit_both(x, x @ beta)
    np.testing.assert_allclose(fit.beta_qp, beta, atol=1e-9)
    np.testing.assert_allclose(fit.beta_lbfgsb, beta, atol=1e-4)
    assert fit.objective_qp < 1e-20 and fit.n == 40


def test_both_fits_clip_a_negative_direction_to_zero():
    # delta = 3 - x: the unconstrained slope is -1; with slope >= 0 the optimum is slope 0, intercept mean = 1
    x = np.stack([np.ones(5), np.arange(5.0)], axis=1)
    fit = fit_both(x, 3.0 - np.arange(5.0))
    np.testing.assert_allclose(fit.beta_qp, [1.0, 0.0], atol=1e-12)
    assert fit.beta_qp[1] == 0.0 and fit.agrees


def test_a_feature_that_is_zero_everywhere_is_a_non_unique_optimum():
    # column 2 is 0 on every pair: NNLS returns 0 for it, L-BFGS-B keeps its start 0.5, at the same objective
    x = np.stack([np.arange(6.0), np.zeros(6)], axis=1)
    fit = fit_both(x, 0.2 * np.arange(6.0) + np.array([0.01, -0.01] * 3))
    assert fit.beta_qp[1] == 0.0 and fit.beta_lbfgsb[1] == pytest.approx(0.5)
    assert fit.objectives_agree and not fit.agrees
    assert np.array_equal(fit.beta("qp"), fit.beta_qp) and np.array_equal(fit.beta("lbfgsb"), fit.beta_lbfgsb)


@pytest.mark.parametrize("function", [fit_both, fit_nnls])
@pytest.mark.parametrize("x, y", [(np.ones((3, 2)), np.ones(4)), (np.zeros((0, 4)), np.zeros(0)), (np.ones(3), np.ones(3))],
                         ids=["mismatched", "empty", "one-dimensional"])
def test_fits_reject_bad_shapes(function, x, y):
    with pytest.raises(DataError, match="features \\(P, k\\)"):
        function(x, y)


def test_unknown_solver_is_a_rigopt_error():
    with pytest.raises(RigoptError, match="unknown fit solver"):
        fit_both(np.eye(2), np.ones(2)).beta("cvxpy")
    with pytest.raises(RigoptError, match="unknown fit solver"):
        fit_calibration(np.eye(4), np.ones(4), "x", solver="cvxpy")


def test_fit_calibration_without_pairs_raises_data_error():
    with pytest.raises(DataError):
        fit_calibration(np.zeros((0, 4)), np.zeros(0), "empty")


def test_fit_calibration_solver_choice_picks_that_beta(control_sets):
    x, y = control_sets["PETR"]
    fit = fit_calibration(x, y, "PETR", solver="qp")
    assert fit.calibration.beta == pytest.approx(fit.beta_qp, abs=0)
    fit_l = fit_calibration(x, y, "PETR", solver="lbfgsb")
    assert fit_l.calibration.beta == pytest.approx(fit_l.beta_lbfgsb, abs=0)


# --- reparameterisation and prediction ---------------------------------------------------------------


def test_reparameterise_closed_forms():
    c = reparameterise((0.3, 0.6, 0.9, 0.4), "hand")
    # avg = 1.8 / 3 = 0.6; K = 0.6 + 0.4 = 1.0; alpha = 0.6 / 1.0; lambdas = beta / 0.6
    assert not c.fallback
    assert c.K == pytest.approx(1.0, abs=1e-15)
    assert c.alpha == pytest.approx(0.6, abs=1e-15)
    assert c.lambdas == pytest.approx((0.5, 1.0, 1.5), abs=1e-15)
    assert c.beta == (0.3, 0.6, 0.9, 0.4)


def test_reparameterise_without_count_weight_gives_alpha_one():
    c = reparameterise((0.2, 0.4, 0.6, 0.0), "hand")
    assert c.alpha == pytest.approx(1.0)
    assert c.K == pytest.approx(0.4)
    assert c.lambdas == pytest.approx((0.5, 1.0, 1.5))


@pytest.mark.parametrize("seed", range(5))
def test_prediction_equals_beta_dot_x_without_fallback(seed):
    rng = np.random.default_rng(seed)
    beta = rng.uniform(0.01, 1.0, 4)
    x = rng.uniform(0.0, 3.0, (20, 4))
    c = reparameterise(beta, "random")
    assert not c.fallback
    assert c.linear_drop(*x.T) == pytest.approx(x @ beta, rel=1e-12, abs=1e-14)


@pytest.mark.parametrize("beta_count, expected_k", [(0.0, 1.0), (0.3, 1.0), (1.0, 1.0), (2.5, 2.5)])
def test_fallback_when_no_geometric_weight(beta_count, expected_k):
    c = reparameterise((0.0, 0.0, 0.0, beta_count), "fallback")
    assert c.fallback
    assert c.alpha == 0.9
    assert c.lambdas == (1.0, 1.0, 1.0)
    assert c.K == expected_k
    t, r, f, n = np.array([0.5, 1.0]), np.array([0.2, 0.0]), np.array([10.0, 0.0]), np.array([0.25, 0.5])
    assert c.linear_drop(t, r, f, n) == pytest.approx(expected_k * (0.9 * (t + r + f) + 0.1 * n), rel=1e-14)


def test_fallback_threshold_on_tiny_geometric_weights():
    assert reparameterise((1e-12, 1e-12, 1e-12, 0.2), "tiny").fallback
    assert not reparameterise((1e-6, 0.0, 0.0, 0.2), "small").fallback


@pytest.mark.parametrize("model, falls_back", [("BEVDet", False), ("BEVFusion", False), ("Fast-BEV", True),
                                                ("PETR", False)])
def test_fallback_on_the_real_control_pairs(control_sets, model, falls_back):
    x, y = control_sets[model]
    fit = fit_calibration(x, y, model)
    assert fit.calibration.fallback is falls_back
    if falls_back:
        assert max(fit.beta_qp[:3]) <= 1e-9  # the certified optimum has no geometric weight either


@pytest.mark.parametrize("component, field, value", [("lambda_t", "lambda_t", 0.0), ("lambda_r", "lambda_r", 0.0),
                                                     ("lambda_f", "lambda_f", 0.0), ("count", "alpha", 1.0)])
def test_knocked_out_sets_one_component(component, field, value):
    c = reparameterise((0.3, 0.6, 0.9, 0.4), "hand")
    k = c.knocked_out(component)
    assert getattr(k, field) == value
    untouched = {"K", "alpha", "lambda_t", "lambda_r", "lambda_f"} - {field}
    assert all(getattr(k, name) == getattr(c, name) for name in untouched)


def test_knocked_out_count_prediction_drops_the_count_term():
    c = reparameterise((0.3, 0.6, 0.9, 0.4), "hand")
    # K = 1, lambdas (0.5, 1, 1.5): with alpha = 1 the prediction is 0.5 t + r + 1.5 f
    assert c.knocked_out("count").linear_drop(2.0, 1.0, 0.5, 0.75) == pytest.approx(0.5 * 2 + 1 + 1.5 * 0.5)


def test_knocked_out_unknown_component_raises():
    from rigopt.errors import RigoptError

    with pytest.raises(RigoptError):
        reparameterise((0.3, 0.6, 0.9, 0.4), "hand").knocked_out("lambda_x")


# --- weights files --------------------------------------------------------------------------------


def test_shipped_weight_names():
    assert set(shipped_weight_names()) == {*MODELS, "joint", "sim-lss"}


@pytest.mark.parametrize("name", [*MODELS, "joint"])
def test_shipped_weights_equal_a_fresh_fit_of_the_shipped_csv(control_sets, name):
    if name == "joint":
        x = np.vstack([control_sets[m][0] for m in MODELS])
        y = np.concatenate([control_sets[m][1] for m in MODELS])
    else:
        x, y = control_sets[name]
    fresh = fit_calibration(x, y, name).calibration
    shipped = json.loads((WEIGHTS_DIR / f"{name}.json").read_text())
    for key in ("K", "alpha", "lambda_t", "lambda_r", "lambda_f"):
        assert shipped[key] == pytest.approx(getattr(fresh, key), abs=1e-9), key
    assert [shipped["beta"][k] for k in ("t", "r", "f", "count")] == pytest.approx(fresh.beta, abs=1e-9)
    assert shipped["fallback"] is fresh.fallback


@pytest.mark.parametrize("spelling, name", [("bevdet", "BEVDet"), ("JOINT", "joint"), ("fast-bev", "Fast-BEV"),
                                            ("Petr", "PETR"), ("BEVFUSION", "BEVFusion")])
def test_load_weights_is_case_insensitive(spelling, name):
    c = load_weights(spelling)
    shipped = json.loads((WEIGHTS_DIR / f"{name}.json").read_text())
    assert c.name == name
    assert (c.K, c.alpha, *c.lambdas) == (shipped["K"], shipped["alpha"], shipped["lambda_t"], shipped["lambda_r"],
                                          shipped["lambda_f"])


def test_unknown_weights_name_lists_the_valid_names():
    with pytest.raises(UnknownNameError) as info:
        load_weights("YOLO")
    message = str(info.value)
    assert "YOLO" in message
    for name in (*MODELS, "joint"):
        assert name in message


def test_write_then_load_round_trip(tmp_path):
    c = reparameterise((0.123, 0.0456, 0.789, 0.31), "mine")
    loaded = load_weights(write_weights(c, tmp_path / "sub" / "mine.json"))
    assert loaded == c


def test_round_trip_of_a_fallback_calibration(tmp_path):
    c = reparameterise((0.0, 0.0, 0.0, 0.02), "fb")
    loaded = load_weights(write_weights(c, tmp_path / "fb.json"))
    assert loaded == c and loaded.fallback


def test_hand_written_weights_file_without_beta_loads(tmp_path):
    path = tmp_path / "w.json"
    path.write_text(json.dumps({"K": 0.5, "alpha": 0.8, "lambda_t": 2.0, "lambda_r": 0.5, "lambda_f": 0.1}))
    c = load_weights(path)
    # K (alpha (lt t + lr r + lf f) + (1 - alpha) count) with t = 1, r = 2, f = 10, count = 0.5
    assert c.linear_drop(1.0, 2.0, 10.0, 0.5) == pytest.approx(0.5 * (0.8 * (2.0 + 1.0 + 1.0) + 0.2 * 0.5))


VALID = {"K": 0.5, "alpha": 0.8, "lambda_t": 2.0, "lambda_r": 0.5, "lambda_f": 0.1}


@pytest.mark.parametrize("content", [
    '{"K": 0.5, "alpha": ',                                       # malformed JSON
    json.dumps([1, 2, 3]),                                        # not an object
    json.dumps({k: v for k, v in VALID.items() if k != "alpha"}),  # missing key
    json.dumps({**VALID, "lambda_t": -1.0}),                      # negative
    json.dumps({**VALID, "K": float("nan")}),                     # NaN
    json.dumps({**VALID, "lambda_f": float("inf")}),              # inf
    json.dumps({**VALID, "alpha": 1.5}),                          # alpha > 1
    json.dumps({**VALID, "K": "0.5"}),                            # string
    json.dumps({**VALID, "alpha": True}),                         # bool
], ids=["malformed", "not-object", "missing-key", "negative", "nan", "inf", "alpha>1", "string", "bool"])
def test_bad_weights_file_raises_data_error_naming_it(tmp_path, content):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(DataError) as info:
        load_weights(path)
    assert str(path) in str(info.value)


def test_missing_weights_file_raises_data_error(tmp_path):
    with pytest.raises(DataError):
        load_weights(tmp_path / "absent.json")


def test_calibration_to_dict_has_beta_by_feature():
    data = reparameterise((0.3, 0.6, 0.9, 0.4), "hand").to_dict()
    assert data["beta"] == {"t": 0.3, "r": 0.6, "f": 0.9, "count": 0.4}
