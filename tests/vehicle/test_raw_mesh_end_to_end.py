"""Acceptance: a raw simulator-like mesh (centimetres, facing -y, no floor, body, cabin and four wheels as
separate OBJ groups) added through the CLI with the flags its error suggests (all at once), then shown,
checked and designed for, all in-process."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from in_process import run_rigopt
from sim_car import AXLES, write_obj

pytestmark = pytest.mark.slow  # a design end to end (about 25 s)

RIG = {"vehicle_type": "simcar", "cameras": [
    {"id": "CAM_FRONT", "location": [2.33, 0, 0.6], "rotation": [0, 0, 0], "fov": 90},
    {"id": "CAM_BACK", "location": [-2.33, 0, 0.6], "rotation": [0, 180, 0], "fov": 90},
    {"id": "CAM_LEFT", "location": [0.0, -0.83, 1.3], "rotation": [0, -90, 0], "fov": 90}]}


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    """Runs of the whole story; RIGOPT_HOME in a tmp folder."""
    tmp = tmp_path_factory.mktemp("raw_mesh")
    env = {"RIGOPT_HOME": str(tmp / "home")}
    mesh = tmp / "car.obj"
    write_obj(mesh, forward="-y", scale=0.01)
    runs = {"plain": run_rigopt("vehicle", "add", "simcar", "--mesh", mesh, env=env)}
    scale = re.search(r"add (--scale \S+)", runs["plain"].stderr).group(1).split()
    forward = re.search(r"add --scale \S+ (--forward \S+),", runs["plain"].stderr).group(1).split()
    runs["scaled"] = run_rigopt("vehicle", "add", "simcar", "--mesh", mesh, *scale, env=env)
    runs["added"] = run_rigopt("vehicle", "add", "simcar", "--mesh", mesh, *scale, *forward, env=env)
    runs["show"] = run_rigopt("vehicle", "show", "simcar", "--out", tmp / "simcar.png", env=env)
    (tmp / "rig.json").write_text(json.dumps(RIG))
    runs["check"] = run_rigopt("check", tmp / "rig.json", "--json", env=env)
    runs["design"] = run_rigopt("design", "--vehicle", "simcar", "--ref", "R1", "--yaw-step", "30", "--pitch", "0",
                                "--fov", "90,120", "--json", "--out", tmp / "design", env=env)
    return runs, tmp, scale, forward


def test_the_error_suggests_scale_and_forward_at_once(session):
    runs, _, scale, forward = session
    assert runs["plain"].returncode == 2 and re.search(r"looks like centimetres \([\d.]+ m long\); scaled by it, the "
                                                       r"mesh is longest along y", runs["plain"].stderr)
    assert "add --scale 0.01 --forward -y," in runs["plain"].stderr
    assert runs["scaled"].returncode == 2 and "seems to face -y" in runs["scaled"].stderr  # the scale alone is not enough
    assert scale == ["--scale", "0.01"] and forward == ["--forward", "-y"]


def test_the_suggested_flags_add_it(session):
    runs, tmp, _, _ = session
    added = runs["added"]
    assert added.returncode == 0, added.stderr
    assert "closed on a 2.3 cm grid (distance)" in added.stdout and "closing error max" in added.stdout
    assert (tmp / "home" / "vehicles" / "simcar" / "body.ply").is_file()


def test_the_wheels_are_stored(session):
    _, tmp, _, _ = session
    import tomllib

    spec = tomllib.loads((tmp / "home" / "vehicles" / "simcar" / "vehicle.toml").read_text())
    assert spec["axles"] == pytest.approx(AXLES, abs=0.02)
    assert len(spec["wheels"]) == 2 and all(w["radius"] == pytest.approx(0.33, abs=0.03) for w in spec["wheels"])


def test_show_check_and_design_work_on_it(session):
    runs, tmp, _, _ = session
    assert runs["show"].returncode == 0 and (tmp / "simcar.png").stat().st_size > 0
    check = json.loads(runs["check"].stdout)
    assert runs["check"].returncode == 0, check
    assert [c["zone"] for c in check["cameras"]] == ["bumper_front", "bumper_rear", "b_pillar"]
    design = runs["design"]
    assert design.returncode == 0, design.stderr
    summary = json.loads(design.stdout)
    assert summary["vehicle"] == "simcar" if "vehicle" in summary else True
    assert (tmp / "design").is_dir()


def test_the_design_puts_no_camera_on_a_wheel_or_below_half_a_metre(session, monkeypatch):
    runs, tmp, _, _ = session
    from rigopt.mounting.practice import on_wheels
    from rigopt.vehicle.library import load_vehicle

    monkeypatch.setenv("RIGOPT_HOME", str(tmp / "home"))
    vehicle = load_vehicle("simcar")
    assert len(vehicle.wheels) == 4  # found on the mesh
    summary = json.loads(runs["design"].stdout)  # positions from the rear axle: back to the vehicle centre
    positions = np.array([c["position"] for c in summary["cameras"]]) + summary["origin_from_vehicle_centre_m"]
    assert on_wheels(vehicle, positions, clearance=0.05) == [[]] * len(positions)
    assert (positions[:, 2] >= 0.5 - 1e-6).all()


def test_the_vehicle_knows_its_rear_axle(session, monkeypatch):
    _, tmp, _, _ = session
    from rigopt.vehicle.library import load_vehicle

    monkeypatch.setenv("RIGOPT_HOME", str(tmp / "home"))
    vehicle = load_vehicle("simcar")
    np.testing.assert_allclose(vehicle.rear_axle, [AXLES[1], 0, 0], atol=0.02)
    assert len(vehicle.wheels) == 4
