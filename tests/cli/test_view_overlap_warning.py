"""``rigopt rank`` and ``rigopt rigcd`` from the installed console script warn of a candidate that sees little of
what the reference sees (rigopt/metrics/view_overlap.py): one ``rigopt: warning:`` line on stderr per such
candidate, its row marked in the table, its overlap in the --json output (stdout JSON only).

The processes start together (a module fixture) and run side by side."""

from __future__ import annotations

import json
import subprocess
from dataclasses import replace

import numpy as np
import pytest
from console import console_script

from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.metrics.view_overlap import LOW_VIEW_OVERLAP
from rigopt.rig.library import load_rig
from rigopt.rig.model import Rig
from rigopt.rig.pccr_format import write_rig

#: name -> arguments; {tmp} holds sky.json (R1 pitched 80 degrees up) and one.json (R1's front camera alone).
COMMANDS = {
    "rank": ["rank", "R1", "R3", "{tmp}/sky.json", "{tmp}/one.json", "--ref", "R1", "--predictor", "rigcd"],
    "rank --json": ["rank", "R1", "R3", "{tmp}/sky.json", "{tmp}/one.json", "--ref", "R1", "--json"],
    "rigcd": ["rigcd", "R1", "{tmp}/one.json"],
    "rigcd --json": ["rigcd", "R1", "{tmp}/sky.json", "--json"],
    "rigcd real rig": ["rigcd", "R1", "R1-c6", "--json"],
}


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> dict[str, subprocess.CompletedProcess]:
    tmp = tmp_path_factory.mktemp("view_overlap")
    r1 = load_rig("R1")
    up = rotation_from_yaw_pitch_roll(0.0, np.radians(80.0), 0.0)
    write_rig(Rig("sky", r1.vehicle, tuple(replace(c, rotation=c.rotation @ up) for c in r1.cameras)), tmp / "sky.json")
    write_rig(Rig("one", r1.vehicle, r1.cameras[:1]), tmp / "one.json")
    started = {name: subprocess.Popen([str(console_script()), *(a.format(tmp=tmp) for a in args)], cwd=tmp,
                                      stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
               for name, args in COMMANDS.items()}
    done = {}
    for name, process in started.items():
        out, err = process.communicate(timeout=300)
        done[name] = subprocess.CompletedProcess(process.args, process.returncode, out, err)
    return done


def warnings(result: subprocess.CompletedProcess) -> list[str]:
    return [line for line in result.stderr.splitlines() if line.startswith("rigopt: warning:")]


def test_rank_warns_once_per_candidate_that_sees_little_and_marks_its_row(finished):
    result = finished["rank"]
    assert result.returncode == 0, result.stderr
    assert warnings(result) == [
        "rigopt: warning: R1 -> sky: its predicted drop rests on cameras that see 0 % of what R1's see; the predictors "
        "were not calibrated on such rigs (view overlap below 25 %, docs/metrics.md); do not read its rank or drop "
        "as good",
        "rigopt: warning: R1 -> one: its predicted drop rests on cameras that see 18 % of what R1's see; the "
        "predictors were not calibrated on such rigs (view overlap below 25 %, docs/metrics.md); do not read its "
        "rank or drop as good"]
    rows = {line.split("│")[2].strip(): line for line in result.stdout.splitlines() if line.count("│") > 3}
    assert set(rows) == {"R1", "R3", "sky", "one"}
    assert "0 % LOW" in rows["sky"] and "18 % LOW" in rows["one"]
    assert "LOW" not in rows["R1"] + rows["R3"] and "100 %" in rows["R1"]


def test_rank_json_carries_each_candidates_overlap(finished):
    result = finished["rank --json"]
    assert result.returncode == 0, result.stderr
    ranked = {entry["rig"]: entry for entry in json.loads(result.stdout)}
    assert ranked["R1"]["view_overlap"] == 1.0 and ranked["sky"]["view_overlap"] == 0.0
    assert ranked["one"]["view_overlap"] == pytest.approx(0.176, abs=0.001)
    assert ranked["R3"]["view_overlap"] > 0.99
    assert {rig for rig, entry in ranked.items() if entry["low_view_overlap"]} == {"sky", "one"}
    assert len(warnings(result)) == 2


def test_rigcd_warns_in_both_forms(finished):
    table, as_json = finished["rigcd"], finished["rigcd --json"]
    assert table.returncode == 0 and as_json.returncode == 0
    assert [w.split(":")[2].strip() for w in warnings(table)] == ["R1 -> one"]
    assert "18 % LOW" in table.stdout
    data = json.loads(as_json.stdout)
    assert (data["b"], data["view_overlap"], data["low_view_overlap"]) == ("sky", 0.0, True)
    assert [w.split(":")[2].strip() for w in warnings(as_json)] == ["R1 -> sky"]


def test_a_benchmark_rig_gets_no_warning(finished):
    result = finished["rigcd real rig"]
    data = json.loads(result.stdout)
    assert data["view_overlap"] == pytest.approx(0.851, abs=0.001) and data["view_overlap"] > LOW_VIEW_OVERLAP
    assert not data["low_view_overlap"] and warnings(result) == []

