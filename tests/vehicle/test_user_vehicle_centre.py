"""A user vehicle is measured from its body, not from its file's origin: the centre of its footprint box, on
the ground under its tyres. The same mesh moved in its file (by (1.3, 0.2, 0) m here) gives the same vehicle,
and RigCD, coverage and mount checks equal to 1e-6."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import sim_car
from in_process import run_rigopt

pytestmark = pytest.mark.usefixtures("rigopt_home")

REPO = Path(__file__).resolve().parents[2]
NUSCENES = REPO / "measurements" / "rigs" / "real" / "nuscenes.json"  # measured from the rear axle
SHIFT = (1.3, 0.2, 0.0)
#: Cameras on the hugging car (CARLA frame: y right), from its box centre.
RIG = {"cameras": [
    {"id": "CAM_FRONT", "location": [2.28, 0, 0.6], "rotation": [0, 0, 0], "fov": 90},
    {"id": "CAM_BACK", "location": [-2.28, 0, 0.6], "rotation": [0, 180, 0], "fov": 90},
    {"id": "CAM_LEFT", "location": [0.0, -0.91, 0.85], "rotation": [0, -90, 0], "fov": 100},
    {"id": "CAM_ROOF", "location": [0.6, 0, 1.51], "rotation": [0, 0, 0], "fov": 70}]}


def close_to(a, b, tolerance: float = 1e-6) -> bool:
    """Whether two JSON values are equal, numbers to ``tolerance``; keys naming the vehicle or rig are skipped."""
    if isinstance(a, dict):
        named = ("vehicle", "name", "rig")
        return set(a) == set(b) and all(close_to(a[k], b[k], tolerance) for k in a if k not in named)
    if isinstance(a, list):
        return len(a) == len(b) and all(close_to(x, y, tolerance) for x, y in zip(a, b))
    if isinstance(a, float) or isinstance(b, float):
        return a is not None and b is not None and abs(a - b) <= tolerance
    return a == b


@pytest.fixture
def two_hatches(tmp_path, rigopt_home):
    """The hugging car added as 'hatch' from its own file and as 'moved' from a file whose origin is elsewhere."""
    env = {"RIGOPT_HOME": str(rigopt_home)}
    mesh = sim_car.joined(sim_car.hugging_car_parts())
    mesh.export(tmp_path / "hatch.stl")
    moved = mesh.copy()
    moved.apply_translation(SHIFT)
    moved.export(tmp_path / "moved.stl")
    for name in ("hatch", "moved"):
        outcome = run_rigopt("vehicle", "add", name, "--mesh", tmp_path / f"{name}.stl", "--forward", "+x", env=env)
        assert outcome.returncode == 0, outcome.stderr
    for name in ("hatch", "moved"):
        rig = dict(RIG, vehicle_type=name)
        (tmp_path / f"rig_{name}.json").write_text(json.dumps(rig))
    return tmp_path, env


@pytest.mark.slow
def test_the_vehicle_is_centred_on_its_footprint_box_on_the_ground(two_hatches):
    from rigopt.vehicle.library import load_vehicle

    _, env = two_hatches
    for name in ("hatch", "moved"):
        bounds = load_vehicle(name).mesh.bounds
        np.testing.assert_allclose(bounds[:, :2].mean(axis=0), [0.0, 0.0], atol=1e-6)
        assert bounds[0, 2] == pytest.approx(0.0, abs=1e-6)
    np.testing.assert_allclose(load_vehicle("moved").mesh.bounds, load_vehicle("hatch").mesh.bounds, atol=1e-6)
    assert load_vehicle("moved").axles == pytest.approx(load_vehicle("hatch").axles, abs=1e-6)
    np.testing.assert_allclose(load_vehicle("moved").rear_axle, [sim_car.HUG_AXLES[1], 0, 0], atol=0.01)


@pytest.mark.slow
def test_rigcd_to_a_rear_axle_rig_is_the_same(two_hatches):
    _, env = two_hatches
    results = [run_rigopt("rigcd", "R1", NUSCENES, "--vehicle", name, "--json", env=env) for name in ("hatch", "moved")]
    assert all(r.returncode == 0 for r in results), results[0].stderr
    first, second = (json.loads(r.stdout) for r in results)
    assert close_to(first, second), (first, second)
    assert first["rigcd"] > 0


@pytest.mark.slow
def test_coverage_and_check_are_the_same(two_hatches):
    tmp, env = two_hatches
    for command in (["coverage"], ["check"]):
        outcomes = [run_rigopt(*command, tmp / f"rig_{name}.json", "--vehicle", name, "--json", env=env)
                    for name in ("hatch", "moved")]
        assert outcomes[0].returncode in (0, 1), outcomes[0].stderr
        first, second = (json.loads(o.stdout) for o in outcomes)
        assert close_to(first, second), command
    assert [c["valid"] for c in first["cameras"]] == [True] * len(RIG["cameras"]), first
