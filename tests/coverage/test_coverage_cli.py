"""``rigopt coverage`` answers: a rig that sees nothing is an error with the mount check's reasons."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from in_process import run_rigopt

from rigopt.geometry import rot_z
from rigopt.rig.library import load_rig
from rigopt.rig.model import Rig
from rigopt.rig.pccr_format import write_rig


@pytest.mark.slow
def test_a_rig_that_sees_only_its_own_body_is_an_error_naming_the_check(tmp_path):
    """R1's cameras turned to face the way they came, into the etron's body: coverage 0 % is no answer."""
    r1 = load_rig("R1")
    inward = Rig("R1_inward", r1.vehicle, tuple(replace(c, rotation=c.rotation @ rot_z(np.pi)) for c in r1.cameras))
    result = run_rigopt("coverage", write_rig(inward, tmp_path / "inward.json"), "--json")
    assert result.returncode == 2 and result.stdout == ""
    assert "sees nothing on any ring" in result.stderr and "rigopt check" in result.stderr
    assert "the body is in its view" in result.stderr  # check's reason, per camera
    # one error line, naming every camera: the two within 1.2 cm of the skin too (their frustums lie in the body)
    assert result.stderr.count("rigopt: error:") == 1
    assert all(f"{c.id} (the body is in its view" in result.stderr for c in r1.cameras)
    assert run_rigopt("coverage", "R1", "--json").returncode == 0  # the same cameras facing out are fine


def test_the_hgvs_trailer_blocks_views_unless_lifted():
    """R9 on the hgv sees less of the rings with its coupled trailer in the way than with --no-trailer, never more."""
    import json

    runs = [run_rigopt("coverage", "R9", "--vehicle", "hgv", "--json", *flag) for flag in ((), ("--no-trailer",))]
    assert all(run.returncode == 0 for run in runs), [run.stderr for run in runs]
    coupled, lifted = ([ring["covered_frac"] for ring in json.loads(run.stdout)["rings"]] for run in runs)
    assert all(a <= b + 1e-12 for a, b in zip(coupled, lifted)) and sum(lifted) - sum(coupled) > 0.3


def test_the_fields_with_the_trailer_turned_both_ways():
    """--articulation 30 on the hgv: the fields again with its trailer turned +30 and -30 deg (R158's ground behind
    the tractor is asked for once the trailer no longer covers it); a car has no trailer to turn."""
    import json

    run = run_rigopt("coverage", "R9", "--vehicle", "hgv", "--require", "r151,r158", "--articulation", "30", "--json")
    assert run.returncode == 0, run.stderr
    data = json.loads(run.stdout)
    turned = data["regions_articulated"]
    assert [t["articulation_deg"] for t in turned] == [30.0, -30.0]
    assert all([r["key"] for r in t["regions"]] == ["r151", "r158"] for t in turned)
    straight = {r["key"]: r for r in data["regions"]}
    assert all(t["regions"][1]["n_points"] > straight["r158"]["n_points"] for t in turned)
    refused = run_rigopt("coverage", "R1", "--require", "r158", "--articulation", "30")
    assert refused.returncode == 2 and refused.stderr.count("rigopt: error:") == 1
    assert "has none" in refused.stderr and "drop --articulation" in refused.stderr


def test_the_report_states_the_vehicle_category_and_what_applies_unmodelled():
    """R1 on its etron (M1): the JSON and the text name the category, its default field r158 and UN R166 unmodelled;
    R9 on the hgv (N3) asks for r151, r159, r158 and names nothing unmodelled."""
    import json

    car, truck = run_rigopt("coverage", "R1", "--json"), run_rigopt("coverage", "R9", "--json")
    assert car.returncode == truck.returncode == 0, car.stderr + truck.stderr
    category = json.loads(car.stdout)["vehicle_category"]
    assert category["category"] == "M1" and [m["regulation"] for m in category["not_modelled"]] == ["UN R166"]
    assert json.loads(truck.stdout)["vehicle_category"]["not_modelled"] == []
    text = " ".join(run_rigopt("coverage", "R1").stdout.split())
    assert "category M1 (stated in its vehicle.toml): fields asked for by default r158; UN R166 also applies" in text
