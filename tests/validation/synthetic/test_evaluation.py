"""Centre-distance AP / mAP of detections (nuScenes-style, 101 recall points, greedy matching by score).

Oracles: hand arithmetic of the 101-point rule. With 2 ground truths and ranks (TP, FP) the curve is
precision 1 up to recall 0.5 and 0 beyond: 40 of the 90 kept points (r = 0.11..0.50) score 1 - 0.1, so
AP = 40 * 0.9 / 90 / 0.9 = 4/9. With ranks (TP, FP, TP) the points r = 0.51..1.00 (50 of them) also get
the best precision to their right, 2/3, so AP = (40 * 0.9 + 50 * (2/3 - 0.1)) / 90 / 0.9 = 193/243.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rigopt.validation.synthetic.evaluation import (
    EVAL_RANGE,
    Detections,
    GroundTruth,
    SamplePrediction,
    average_precision,
    evaluate,
)
from rigopt.validation.synthetic.dataset import TrainingSample
from rigopt.validation.synthetic.scene_model import CLASSES
from rigopt.errors import DataError

CAR, TRUCK, BUS = 0, 1, 2
TWO_OF_TWO_FIRST = 4 / 9  # ranks (TP, FP) against 2 ground truths
ALL_AFTER_FP = 193 / 243  # ranks (TP, FP, TP) against 2 ground truths


def gt(rows):
    """GroundTruth from (sample, class, x, y) rows."""
    return GroundTruth(np.array([r[0] for r in rows]), np.array([r[1] for r in rows], dtype=int),
                       np.array([r[2:4] for r in rows], dtype=float).reshape(-1, 2))


def det(rows):
    """Detections from (sample, class, x, y, score) rows."""
    return Detections(np.array([r[0] for r in rows]), np.array([r[1] for r in rows], dtype=int),
                      np.array([r[2:4] for r in rows], dtype=float).reshape(-1, 2),
                      np.array([r[4] for r in rows], dtype=float))


def no_detections():
    return Detections(np.zeros(0, dtype=str), np.zeros(0, dtype=int), np.zeros((0, 2)), np.zeros(0))


def hand_case():
    """2 cars; detections TP 0.3 m away (0.9), FP far from everything (0.8), TP 1.5 m away (0.7)."""
    truth = gt([("s0", CAR, 10.0, 0.0), ("s1", CAR, 0.0, 5.0)])
    found = det([("s0", CAR, 10.3, 0.0, 0.9), ("s0", CAR, 40.0, 40.0, 0.8), ("s1", CAR, 0.0, 6.5, 0.7)])
    return found, truth


def test_hand_computed_ap_at_each_threshold():
    result = evaluate(*hand_case())
    expected = [TWO_OF_TWO_FIRST, TWO_OF_TWO_FIRST, ALL_AFTER_FP, ALL_AFTER_FP]  # 1.5 m is a FP below 2 m
    np.testing.assert_allclose(result.ap[CAR], expected, rtol=0, atol=1e-12)
    assert abs(result.per_class_ap[CAR] - 301 / 486) < 1e-12
    assert abs(result.map - 301 / 486) < 1e-12  # only car has ground truth
    assert np.isnan(result.ap[1:]).all() and np.isnan(result.per_class_ap[1:]).all()


def test_average_precision_by_hand():
    assert average_precision(np.array([True, False]), 2) == pytest.approx(4 / 9, abs=1e-12)
    assert average_precision(np.array([True, False, True]), 2) == pytest.approx(193 / 243, abs=1e-12)
    # FP first: precision 0, then 1/2 at recall 1 -> 0.5 on all kept points -> 0.4 / 0.9
    assert average_precision(np.array([False, True]), 1) == pytest.approx(4 / 9, abs=1e-12)
    assert average_precision(np.array([False, False]), 1) == 0.0
    # FP, TP, TP against 2: precision 0, 1/2, 2/3; the best precision at recall >= r is 2/3 for every r, not
    # the 1/2 where recall 0.5 is first reached -> (2/3 - 0.1) / 0.9 = 17/27
    assert average_precision(np.array([False, True, True]), 2) == pytest.approx(17 / 27, abs=1e-12)
    assert average_precision(np.zeros(0, dtype=bool), 3) == 0.0


def test_recall_points_compared_exactly():
    """7 of 10 found, all first: recall 0.7 must reach r = 0.70 (np.linspace(0, 1, 101)[70] is 0.7000000000000001)."""
    # points 11..70 (60 of 90) have precision 1 -> 60 * 0.9 / 90 / 0.9 = 2/3
    assert average_precision(np.array([True] * 7), 10) == pytest.approx(2 / 3, abs=1e-12)
    # 7 of 20: points 11..35 (25 of 90) -> 25 / 90
    assert average_precision(np.array([True] * 7), 20) == pytest.approx(25 / 90, abs=1e-12)


def test_perfect_detector_gives_one():
    truth = gt([("a", CAR, 1.0, 2.0), ("a", BUS, -5.0, 3.0), ("b", CAR, 7.0, -1.0), ("b", TRUCK, 0.0, 0.0)])
    found = det([(s, c, x, y, 0.5) for s, c, x, y in
                 [("a", CAR, 1.0, 2.0), ("a", BUS, -5.0, 3.0), ("b", CAR, 7.0, -1.0), ("b", TRUCK, 0.0, 0.0)]])
    result = evaluate(found, truth)
    assert result.map == 1.0
    assert (result.ap[[CAR, TRUCK, BUS]] == 1.0).all()
    assert np.isnan(result.ap[3:]).all()


def test_no_detections_gives_zero():
    result = evaluate(no_detections(), gt([("a", CAR, 1.0, 2.0), ("a", BUS, 0.0, 0.0)]))
    assert result.map == 0.0
    assert (result.ap[[CAR, BUS]] == 0.0).all()


def test_high_score_detection_steals_nearest_ground_truth():
    truth = gt([("s", CAR, 0.0, 0.0), ("s", CAR, 1.0, 0.0)])
    # A at 0.6 m from the first truth and 0.4 m from the second; B 0.1 m from the second, 1.1 m from the first.
    a, b = ("s", CAR, 0.6, 0.0), ("s", CAR, 1.1, 0.0)
    a_first = evaluate(det([a + (0.9,), b + (0.8,)]), truth)
    # A takes the second truth; B is left 1.1 m from the first: TP, FP at 0.5 and 1 m, TP, TP at 2 and 4 m
    np.testing.assert_allclose(a_first.ap[CAR], [4 / 9, 4 / 9, 1, 1], atol=1e-12)
    b_first = evaluate(det([a + (0.8,), b + (0.9,)]), truth)
    # B takes the second truth; A is 0.6 m from the first: a TP from 1 m on
    np.testing.assert_allclose(b_first.ap[CAR], [4 / 9, 1, 1, 1], atol=1e-12)


def test_false_positive_does_not_take_its_ground_truth():
    """A detection too far away at this threshold leaves the truth for a later, closer one."""
    truth = gt([("s", CAR, 0.0, 0.0)])
    result = evaluate(det([("s", CAR, 0.8, 0.0, 0.9), ("s", CAR, 0.1, 0.0, 0.5)]), truth)
    # 0.5 m: FP then TP -> precision 1/2 at recall 1 -> 4/9; 1 m on: TP (then a FP) -> 1
    np.testing.assert_allclose(result.ap[CAR], [4 / 9, 1, 1, 1], atol=1e-12)


def test_detections_in_another_sample_or_class_never_match():
    truth = gt([("a", CAR, 3.0, 3.0)])
    result = evaluate(det([("b", CAR, 3.0, 3.0, 0.9), ("a", TRUCK, 3.0, 3.0, 0.8)]), truth)
    np.testing.assert_array_equal(result.ap[CAR], [0, 0, 0, 0])
    assert result.map == 0.0
    assert np.isnan(result.ap[TRUCK]).all()  # truck has no ground truth: excluded, false positives or not


def test_classes_without_ground_truth_are_excluded_from_map():
    truth = gt([("a", CAR, 0.0, 0.0), ("a", BUS, 10.0, 0.0)])
    found = det([("a", CAR, 0.0, 0.0, 0.9), ("a", TRUCK, 50.0, 0.0, 0.95)])
    result = evaluate(found, truth)
    assert result.per_class_ap[CAR] == 1.0 and result.per_class_ap[BUS] == 0.0
    assert result.map == 0.5  # (1 + 0) / 2, not / 9 and not counting truck
    assert list(result.n_ground_truth) == [1, 0, 1, 0, 0, 0, 0, 0, 0]
    assert np.isnan(evaluate(found, gt([])).map)


def test_threshold_is_strict():
    result = evaluate(det([("a", CAR, 0.5, 0.0, 0.9)]), gt([("a", CAR, 0.0, 0.0)]))
    np.testing.assert_array_equal(result.ap[CAR], [0, 1, 1, 1])  # exactly 0.5 m is not < 0.5 m
    result = evaluate(det([("a", CAR, 3.0, 4.0, 0.9)]), gt([("a", CAR, 0.0, 0.0)]))  # 5 m in bird's eye
    np.testing.assert_array_equal(result.ap[CAR], [0, 0, 0, 0])
    result = evaluate(det([("a", CAR, 0.3, 0.3, 0.9)]), gt([("a", CAR, 0.0, 0.0)]))  # Euclidean 0.42 m, not 0.6
    np.testing.assert_array_equal(result.ap[CAR], [1, 1, 1, 1])


def test_tied_scores_have_a_fixed_order():
    """Equal scores rank by sample, then x, then y: here the TP (x = 0.1) before the FP (x = 10)."""
    truth = gt([("s", CAR, 0.0, 0.0)])
    rows = [("s", CAR, 10.0, 0.0, 0.5), ("s", CAR, 0.1, 0.0, 0.5)]
    for order in (rows, rows[::-1]):
        np.testing.assert_array_equal(evaluate(det(order), truth).ap[CAR], [1, 1, 1, 1])
    # the FP first would give 4/9: the sample id decides before x
    rows = [("s0", CAR, 10.0, 0.0, 0.5), ("s1", CAR, 0.1, 0.0, 0.5)]
    truth = gt([("s1", CAR, 0.0, 0.0)])
    for order in (rows, rows[::-1]):
        np.testing.assert_allclose(evaluate(det(order), truth).ap[CAR], [4 / 9] * 4, atol=1e-12)


def test_equidistant_ground_truths_taken_in_x_order():
    """A detection midway between two truths takes the one with the smaller x, whatever the input order."""
    rows = [("s", CAR, -1.0, 0.0), ("s", CAR, 1.0, 0.0)]
    found = det([("s", CAR, 0.0, 0.0, 0.9), ("s", CAR, 1.5, 0.0, 0.8)])
    for order in (rows, rows[::-1]):
        # 0.5 m: both FP (1 m, then exactly 0.5 m). 1 m: FP, TP -> precision 1/2 up to recall 1/2 -> 40 * 0.4 / 81.
        # 2 and 4 m: the first takes x = -1 and the second is 0.5 m from x = 1 -> TP, TP
        np.testing.assert_allclose(evaluate(found, gt(order)).ap[CAR], [0, 16 / 81, 1, 1], atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(st.data())
def test_invariant_to_input_order(data):
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    n_gt, n_det = data.draw(st.integers(0, 12)), data.draw(st.integers(0, 15))
    grid = np.arange(-3.0, 3.5, 0.5)  # coarse positions and scores so that ties happen
    truth = gt([(f"s{rng.integers(3)}", int(rng.integers(3)), rng.choice(grid), rng.choice(grid))
                for _ in range(n_gt)])
    found = det([(f"s{rng.integers(3)}", int(rng.integers(3)), rng.choice(grid), rng.choice(grid),
                  rng.choice([0.2, 0.5, 0.9])) for _ in range(n_det)])
    p, q = rng.permutation(n_det), rng.permutation(n_gt)
    shuffled = evaluate(Detections(found.sample[p], found.cls[p], found.xy[p], found.score[p]),
                        GroundTruth(truth.sample[q], truth.cls[q], truth.xy[q]))
    reference = evaluate(found, truth)
    np.testing.assert_array_equal(shuffled.ap, reference.ap)
    assert shuffled.map == reference.map or (math.isnan(shuffled.map) and math.isnan(reference.map))


def test_to_dict_keys_and_values():
    result = evaluate(*hand_case())
    out = result.to_dict()
    assert set(out) == {"mAP", "raw"}
    assert out["mAP"] == pytest.approx(301 / 486, abs=1e-12) and isinstance(out["mAP"], float)
    assert list(out["raw"]) == [f"{c}_AP_dist_{d}" for c in CLASSES for d in ("0.5", "1.0", "2.0", "4.0")]
    assert out["raw"]["car_AP_dist_0.5"] == pytest.approx(4 / 9, abs=1e-12)
    assert out["raw"]["car_AP_dist_2.0"] == pytest.approx(193 / 243, abs=1e-12)
    assert out["raw"]["truck_AP_dist_4.0"] is None  # NaN (no ground truth) is written as JSON null
    assert evaluate(no_detections(), gt([])).to_dict()["mAP"] is None


def test_builders_from_samples_and_predictions():
    def sample(token, centers, classes):
        n = len(classes)
        return TrainingSample(token, "scene", 0, {}, {}, {}, np.eye(4), np.array(centers, dtype=float).reshape(-1, 3),
                              np.ones((n, 3)), np.zeros(n), np.array(classes, dtype=int), np.array(["4"] * n),
                              np.array([f"i{k}" for k in range(n)]))

    truth = GroundTruth.from_samples([sample("t0", [[1, 2, 0.5], [3, 4, 0.5]], [CAR, -1]),
                                      sample("t1", [], []), sample("t2", [[0, 0, 1.0]], [BUS])])
    assert truth.sample.tolist() == ["t0", "t2"] and truth.cls.tolist() == [CAR, BUS]  # class -1 dropped
    np.testing.assert_array_equal(truth.xy, [[1, 2], [0, 0]])
    found = Detections.from_predictions([SamplePrediction("t0", np.array([[1.0, 2.2, 0.0]]), np.array([CAR]),
                                                          np.array([0.7])),
                                         SamplePrediction("t1", np.zeros((0, 3)), np.zeros(0, dtype=int), np.zeros(0)),
                                         SamplePrediction("t2", np.array([[0.0, 0.1]]), np.array([BUS]),
                                                          np.array([0.6]))])
    assert found.sample.tolist() == ["t0", "t2"] and found.score.tolist() == [0.7, 0.6]
    assert evaluate(found, truth).map == 1.0
    with pytest.raises(DataError, match="prediction for 't0'"):
        Detections.from_predictions([SamplePrediction("t0", np.zeros((2, 3)), np.zeros(2, dtype=int), np.zeros(1))])


@pytest.mark.parametrize("found, truth, message", [
    (Detections(np.array(["a"]), np.array([0, 0]), np.zeros((2, 2)), np.ones(2)), gt([]), "lengths"),
    (Detections(np.array(["a"]), np.array([0]), np.zeros((1, 2)), np.ones(2)), gt([]), "lengths"),
    (det([("a", CAR, np.nan, 0.0, 0.5)]), gt([("a", CAR, 0, 0)]), "NaN"),
    (det([("a", CAR, 0.0, 0.0, np.nan)]), gt([("a", CAR, 0, 0)]), "score"),
    (det([("a", CAR, 0.0, 0.0, 0.5)]), gt([("a", CAR, np.inf, 0)]), "ground truth: 1 centre"),
    (det([("a", 9, 0.0, 0.0, 0.5)]), gt([("a", CAR, 0, 0)]), "unknown class index 9"),
    (det([("a", CAR, 0.0, 0.0, 0.5)]), gt([("a", -1, 0, 0)]), "unknown class index -1"),
    (Detections(np.array(["a"]), np.array([0]), np.zeros((1, 3)), np.ones(1)), gt([]), r"\(n, 2\)"),
    (Detections(np.array([0]), np.array([0]), np.zeros((1, 2)), np.ones(1)), gt([("a", CAR, 0, 0)]), "all integers"),
])
def test_bad_input_raises_data_error(found, truth, message):
    with pytest.raises(DataError, match=message):
        evaluate(found, truth)


def test_bad_thresholds_raise_data_error():
    with pytest.raises(DataError, match="thresholds"):
        evaluate(*hand_case(), thresholds=(0.5, 0.0))


# --- the benchmark's evaluation range ----------------------------------------------------------------


def test_ground_truth_within_the_range_keeps_the_near_objects():
    truth = GroundTruth(np.array(["a", "a", "b"]), np.array([CAR, TRUCK, BUS]),
                       np.array([[30.0, 40.0], [30.0, 40.1], [-10.0, 0.0]]))
    near = truth.within(50.0)
    assert list(near.cls) == [CAR, BUS]  # (30, 40) is exactly 50 m away: kept; (30, 40.1) is not
    assert list(near.sample) == ["a", "b"]
    assert near.xy.shape == (2, 2)


def test_a_prediction_within_the_range_keeps_each_kept_detection_whole():
    prediction = SamplePrediction("s", np.array([[60.0, 0.0, 1.0], [1.0, 2.0, 0.5]]), np.array([TRUCK, CAR]),
                                  np.array([0.9, 0.4]))
    near = prediction.within()
    assert EVAL_RANGE == 50.0
    assert near.token == "s"
    assert near.centers.tolist() == [[1.0, 2.0, 0.5]]
    assert near.classes.tolist() == [CAR] and near.scores.tolist() == [0.4]


# --- fixed set and visible-only score --------------------------------------------------------------


def seen_gt(rows):
    """GroundTruth from (sample, class, x, y, visible) rows."""
    base = gt([r[:4] for r in rows])
    return GroundTruth(base.sample, base.cls, base.xy, np.array([r[4] for r in rows], dtype=bool))


# One visible car in front, one car behind that no camera sees.
FRONT_SEEN_REAR_UNSEEN = [("s0", CAR, 10.0, 0.0, True), ("s0", CAR, -10.0, 0.0, False)]


def test_missing_an_unseen_object_costs_the_fixed_set_only():
    # The seen car found, the unseen one missed: fixed recall stops at 1/2 (AP 4/9), visible-only is perfect.
    found = det([("s0", CAR, 10.0, 0.0, 0.9)])
    truth = seen_gt(FRONT_SEEN_REAR_UNSEEN)
    assert evaluate(found, truth).map == pytest.approx(TWO_OF_TWO_FIRST, abs=1e-12)
    assert evaluate(found, truth, visible_only=True).map == pytest.approx(1.0, abs=1e-12)
    assert evaluate(found, truth).n_ground_truth[CAR] == 2
    assert evaluate(found, truth, visible_only=True).n_ground_truth[CAR] == 1


def test_a_detection_of_an_unseen_object_is_neither_credited_nor_penalised_when_visible_only():
    # Ranks: FP (0.95), the unseen car (0.9), the seen car (0.8). Fixed: FP, TP, TP against 2 (precision
    # 2/3 at every recall point: AP (2/3 - 0.1) / 0.9 = 17/27). Visible-only: the unseen car's detection
    # leaves the ranking, leaving FP, TP against 1 (precision 1/2 throughout: AP 4/9).
    found = det([("s0", CAR, 30.0, 0.0, 0.95), ("s0", CAR, -10.0, 0.0, 0.9), ("s0", CAR, 10.0, 0.0, 0.8)])
    truth = seen_gt(FRONT_SEEN_REAR_UNSEEN)
    assert evaluate(found, truth).map == pytest.approx(17 / 27, abs=1e-12)
    assert evaluate(found, truth, visible_only=True).map == pytest.approx(4 / 9, abs=1e-12)


def test_a_second_detection_of_an_unseen_object_is_a_false_positive():
    # The unseen car is taken by the first detection; the duplicate's nearest free object is 20 m away.
    found = det([("s0", CAR, -10.0, 0.0, 0.9), ("s0", CAR, -10.1, 0.0, 0.8), ("s0", CAR, 10.0, 0.0, 0.7)])
    truth = seen_gt(FRONT_SEEN_REAR_UNSEEN)
    assert evaluate(found, truth).map == pytest.approx(ALL_AFTER_FP, abs=1e-12)  # TP, FP, TP against 2
    assert evaluate(found, truth, visible_only=True).map == pytest.approx(TWO_OF_TWO_FIRST, abs=1e-12)  # FP, TP / 1


def test_without_visibility_both_scores_agree():
    found, truth = hand_case()
    assert truth.visible is None
    assert evaluate(found, truth, visible_only=True).map == evaluate(found, truth).map == pytest.approx(301 / 486)


def test_a_class_whose_objects_are_all_unseen_leaves_the_visible_only_mean():
    truth = seen_gt([("s0", CAR, 10.0, 0.0, True), ("s0", BUS, -10.0, 0.0, False)])
    found = det([("s0", CAR, 10.0, 0.0, 0.9)])
    assert evaluate(found, truth).map == pytest.approx(0.5, abs=1e-12)  # car 1, bus 0
    visible = evaluate(found, truth, visible_only=True)
    assert visible.map == pytest.approx(1.0, abs=1e-12) and np.isnan(visible.per_class_ap[BUS])


def test_metrics_hold_both_scores_and_resampling_can_use_either():
    from rigopt.validation.synthetic.evaluation import match, resampled_maps

    found = det([("s0", CAR, 10.0, 0.0, 0.9), ("s1", CAR, 0.0, 5.0, 0.8)])
    truth = seen_gt(FRONT_SEEN_REAR_UNSEEN + [("s1", CAR, 0.0, 5.0, True)])
    matched = match(found, truth)
    metrics = matched.metrics()
    assert set(metrics) == {"mAP", "mAP_visible", "raw", "raw_visible"}
    assert metrics["mAP"] == pytest.approx(evaluate(found, truth).map) and metrics["mAP"] < 1
    assert metrics["mAP_visible"] == pytest.approx(1.0) and metrics["raw_visible"]["car_AP_dist_0.5"] == 1.0
    # One group holding every sample: each resample is the whole set once.
    maps = resampled_maps([matched], [np.arange(2)], resamples=3, seed=1, visible_only=True)
    np.testing.assert_allclose(maps, 1.0)
    np.testing.assert_allclose(resampled_maps([matched], [np.arange(2)], resamples=3, seed=1), metrics["mAP"])


def test_within_the_range_keeps_visibility_and_bad_visibility_is_refused():
    truth = seen_gt([("a", CAR, 60.0, 0.0, True), ("a", CAR, 5.0, 0.0, False)])
    assert truth.within().visible.tolist() == [False]
    bad = GroundTruth(truth.sample, truth.cls, truth.xy, np.array([True]))
    with pytest.raises(DataError, match="visible"):
        evaluate(no_detections(), bad)


def test_samples_give_their_visibility_to_the_ground_truth():
    def sample(token, fractions):
        n = len(fractions)
        return TrainingSample(token, "scene", 0, {}, {}, {}, np.eye(4), np.arange(3.0 * n).reshape(-1, 3),
                              np.ones((n, 3)), np.zeros(n), np.zeros(n, dtype=int), np.array(["1"] * n),
                              np.array([f"i{k}" for k in range(n)]), np.array(fractions, dtype=float))

    truth = GroundTruth.from_samples([sample("t0", [0.0, 0.3, np.nan]), sample("t1", [])])
    assert truth.visible.tolist() == [False, True, True]  # NaN: not recorded, counted as seen
