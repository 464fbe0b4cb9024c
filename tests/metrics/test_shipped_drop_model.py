"""The shipped drop models (metrics/drop_models/: lss-R1, studies/predictor; lss-R1-v2, studies/predictor_v2, the
default): the prediction `rank`, `rigcd`, `design` and `validate` print from R1 by default, RigCD's on request or
from other references."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from console import run_console
from rigopt.metrics.calibration import load_weights
from rigopt.metrics.drop_model import choose_model, load_drop_model
from rigopt.metrics.ranking import predict_transfer
from rigopt.mounting.candidates import rig_body_share
from rigopt.rig.library import load_rig

STUDY = Path(__file__).resolve().parents[2] / "studies" / "predictor"


def rank_json(*args) -> list[dict]:
    result = run_console("rank", *args, "--json")
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


def test_the_second_model_is_the_default_from_r1_only_and_the_first_stays_by_name():
    model, first = load_drop_model("lss-R1-v2"), load_drop_model("lss-R1")
    assert model.default and model.reference == "R1" and "pre-registered" in model.study and model.needs_body
    assert not first.default and not first.needs_body and "body" not in first.features
    assert choose_model("auto", load_rig("R1")).name == "lss-R1-v2"
    assert choose_model("lss-r1", load_rig("R1")).name == "lss-R1"
    assert all(choose_model("auto", load_rig(name)) is None for name in ("R2", "R6", "R1-f"))


def test_rank_from_r1_prints_the_model_and_rigcd_on_request():
    model, r1 = load_drop_model("lss-R1-v2"), load_rig("R1")
    candidates = ["R6", "R4", "R1-f"]
    expected = model.predict(r1, [load_rig(c) for c in candidates], rig_body_share)[0]
    rows = {r["rig"]: r for r in rank_json("--ref", "R1", *candidates)}
    assert {r["predictor"] for r in rows.values()} == {"lss-R1-v2 drop model"}
    assert [rows[c]["predicted_drop"] for c in candidates] == pytest.approx(expected.tolist(), abs=1e-12)
    rigcd = predict_transfer(r1, [load_rig(c) for c in candidates], load_weights("joint"))
    for option in (["--predictor", "rigcd"], ["--weights", "joint"]):
        named = {r["rig"]: r for r in rank_json("--ref", "R1", *candidates, *option)}
        assert {r["predictor"] for r in named.values()} == {"RigCD (joint)"}
        assert [named[c]["predicted_drop"] for c in candidates] == pytest.approx([p.predicted_drop for p in rigcd])
        assert [named[c]["rigcd"] for c in candidates] == pytest.approx([rows[c]["rigcd"] for c in candidates])


def test_a_model_of_another_reference_is_one_error_line():
    result = run_console("rank", "--ref", "R2", "R1", "--predictor", "lss-R1")
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr.strip().splitlines() == [
        "rigopt: error: the lss-R1 drop model predicts transfers from R1 (its detector's training rig), and R2 is "
        "another rig: pass --ref R1 or --predictor rigcd"]


def test_the_model_predicts_the_measured_default_designs_within_its_study_figures():
    """In sample (the shipped fit saw these rigs): each vehicle's default design within 0.15 of its measured drop,
    the issue's bound for the fire truck's (measured 0.136 under the full protocol, 0.147 under quick)."""
    entries = [json.loads(line) for line in (STUDY / "results" / "measured.jsonl").read_text().splitlines()]
    designs = {e["vehicle"]: e for e in entries if e["rig"] == f"{e['vehicle']}_from_R1_default"}
    r1 = load_rig("R1")
    rigs = [load_rig(STUDY / "rigs" / f"{e['rig']}.json") for e in designs.values()]
    predicted = load_drop_model("lss-R1-v2").predict(r1, rigs, rig_body_share)[0]
    measured = np.array([e["drop"] for e in designs.values()])
    assert len(designs) == 8 and np.all(np.abs(predicted - measured) <= 0.15)
