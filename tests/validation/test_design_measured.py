"""Where a design's prediction and its measurement disagree (rigopt/validation/designs.py ``contradictions``), and
``rigopt design --measure``'s refusals before any design work."""

from __future__ import annotations

import pytest
from in_process import run_rigopt

from rigopt.validation.designs import contradictions


def row(role, predicted, measured, interval=None, informative=False):
    return {"role": role, "rig": f"rig of {role}", "predicted_drop": predicted, "measured_drop": measured,
            "predicted_interval": interval, "interval_informative": informative}


def test_predictions_that_the_measurement_agrees_with_give_no_line():
    rows = [row("design", 0.12, 0.10), row("naive transfer", 0.50, 0.45)]
    paired = [{"rig": "rig of naive transfer", "difference": -0.35, "ci": [-0.40, -0.30]}]
    assert contradictions(rows, paired) == []


def test_a_measured_drop_outside_an_informative_interval_is_said():
    lines = contradictions([row("design", 0.30, 0.05, [0.20, 0.40], True)], [])
    assert lines == ["design: measured 0.050, outside the predicted interval [0.200, 0.400] (predicted 0.300)"]


def test_a_prediction_far_off_without_an_informative_interval_is_said():
    lines = contradictions([row("design", 0.809, 0.136, [0.0, 1.0], False)], [])
    assert lines == ["design: predicted 0.809, measured 0.136: the prediction is off by 0.673"]


def test_an_order_the_measurement_reverses_is_said_only_when_its_interval_excludes_0():
    rows = [row("design", 0.07, 0.03), row("naive transfer", 0.04, 0.10)]
    other = "rig of naive transfer"
    reversed_for_sure = contradictions(rows, [{"rig": other, "difference": -0.07, "ci": [-0.12, -0.02]}])
    assert len(reversed_for_sure) == 1 and "orders design and naive transfer one way (+0.030)" in reversed_for_sure[0]
    assert contradictions(rows, [{"rig": other, "difference": -0.07, "ci": [-0.12, 0.01]}]) == []


def test_rows_not_measured_are_left_out_and_rows_can_be_named_by_rig():
    rows = [row("rig", 0.1, None), row("rig", 0.9, 0.2)]
    assert contradictions(rows, [], name=lambda r: r["rig"]) == [
        "rig of rig: predicted 0.900, measured 0.200: the prediction is off by 0.700"]


@pytest.mark.parametrize("args, message", [
    (["--measure", "--pareto"], "--measure measures one design: leave out --pareto"),
    (["--measure", "--protocol", "fast"], "unknown measurement protocol"),
])
def test_design_measure_refuses_bad_combinations_before_designing(args, message, tmp_path):
    outcome = run_rigopt("design", "--vehicle", "tt", "--ref", "R1", "--out", tmp_path / "d", *args)
    assert outcome.returncode == 2 and message in outcome.stderr, outcome.stderr
    assert not (tmp_path / "d").exists()
