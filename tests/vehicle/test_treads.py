"""Step treads found on a user mesh (``rigopt.vehicle.treads``): a van's rear step is one, a car's bonnet, a truck's
deep ledge and the tyres' tops are not; ``vehicle add`` stores and states them in the reports' frame, ``vehicle show``
lists them, and a design keeps its lenses off them."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh
from in_process import run_rigopt

from rigopt.vehicle.treads import RISER, step_treads

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
sys.path.insert(0, str(EXAMPLES))
import make_raw_van  # noqa: E402

#: The rear step added to the example van: 0.25 m deep, 1.2 m wide, its tread 0.52 m up, behind the rear face.
STEP_TOP, STEP_DEPTH = 0.52, 0.25


def _box(low, high) -> trimesh.Trimesh:
    low, high = np.asarray(low, float), np.asarray(high, float)
    box = trimesh.creation.box(extents=high - low)
    box.apply_translation((low + high) / 2)
    return box


def _step_van(metres: bool = True) -> trimesh.Trimesh:
    step = _box([make_raw_van.REAR - STEP_DEPTH, -0.6, STEP_TOP - 0.07], [make_raw_van.REAR, 0.6, STEP_TOP])
    van = trimesh.util.concatenate([*make_raw_van.body(), *make_raw_van.wheels(), *make_raw_van.mirrors(), step])
    if not metres:
        van.apply_scale(make_raw_van.MM)
    return van


def _wheels():
    return [(x, make_raw_van.WHEEL_R) for x in (0.0, make_raw_van.WHEELBASE)]


def test_a_vans_rear_step_is_a_tread_and_its_box_holds_tread_and_riser():
    treads = step_treads(_step_van(), _wheels())
    assert len(treads) == 1
    (tread,) = treads
    assert tread["min"][:2] == pytest.approx([make_raw_van.REAR - STEP_DEPTH, -0.6], abs=1e-6)
    assert tread["max"][:2] == pytest.approx([make_raw_van.REAR, 0.6], abs=1e-6)
    assert tread["min"][2] == pytest.approx(STEP_TOP - RISER, abs=1e-3)
    assert tread["min"][2] < STEP_TOP < tread["max"][2] < STEP_TOP + 0.1
    assert "0.52 m" in tread["name"] and tread["mirrored"] is False


def test_a_triangle_soup_finds_the_same_tread():
    """An STL-like export shares no vertex between triangles: the tread is found all the same."""
    van = _step_van()
    soup = trimesh.Trimesh(van.vertices[van.faces].reshape(-1, 3), np.arange(3 * len(van.faces)).reshape(-1, 3),
                           process=False)
    assert step_treads(soup, _wheels()) == step_treads(van, _wheels())


def test_the_van_without_a_step_and_its_tyre_tops_give_none():
    """The example van has no step; its tyres' tops (0.72 m, facing up) are no treads, unless the wheels are not known."""
    van = trimesh.util.concatenate([*make_raw_van.body(), *make_raw_van.wheels(), *make_raw_van.mirrors()])
    assert step_treads(van, _wheels()) == []
    assert step_treads(van, ()) != []  # the tyres' tops, taken for treads when no wheel is given


def test_a_car_bonnet_and_a_deep_ledge_are_no_treads():
    """A 1.4 m car's bonnet faces up at 0.75 m (too low a body to carry steps); on a 3 m truck a ledge 1.2 m deep
    at 0.8 m (a flatbed's deck) is no step; the same ledge 0.3 m deep is."""
    car = trimesh.util.concatenate([_box([-2, -0.9, 0.3], [1.0, 0.9, 1.4]), _box([1.0, -0.9, 0.3], [2.2, 0.9, 0.75])])
    assert step_treads(car) == []
    cab = _box([0.0, -1.2, 0.4], [2.5, 1.2, 3.0])
    assert step_treads(trimesh.util.concatenate([cab, _box([-1.2, -1.0, 0.4], [0.0, 1.0, 0.8])])) == []
    shallow = step_treads(trimesh.util.concatenate([cab, _box([-0.3, -1.0, 0.6], [0.0, 1.0, 0.8])]))
    assert [t["max"][2] - 0.05 for t in shallow] == pytest.approx([0.8])


@pytest.fixture(scope="module")
def stepvan_home(tmp_path_factory):
    folder = tmp_path_factory.mktemp("home")
    mesh = folder / "step_van.obj"
    _step_van(metres=False).export(mesh)
    env = {"RIGOPT_HOME": str(folder)}
    added = run_rigopt("vehicle", "add", "stepvan", "--mesh", mesh, "--scale", "0.001", env=env)
    assert added.returncode == 0, added.stderr
    return folder, added, env


def test_vehicle_add_states_the_tread_in_the_reports_frame_and_show_lists_it(stepvan_home, tmp_path):
    folder, added, env = stepvan_home
    text = " ".join(added.stdout.split())
    # the rear axle is the example's origin: the step runs from the rear face (x -1.25) 0.25 m back
    assert "steps:" in text and "tread 1 (found: faces up at 0.52 m) x -1.50..-1.25 m, y -0.60..0.60 m" in text
    assert "[[steps]] in vehicle.toml" in text and "below the rear axle" in text
    assert "[[steps]]" in (folder / "vehicles" / "stepvan" / "vehicle.toml").read_text()
    shown = run_rigopt("vehicle", "show", "stepvan", "--out", tmp_path / "v.png", env=env)
    assert shown.returncode == 0, shown.stderr
    assert "tread 1 (found: faces up at 0.52 m)" in shown.stdout
    assert "-1.50, -0.60, 0.22 .. -1.25, 0.60, 0.57" in shown.stdout


def test_no_lens_is_placed_on_the_tread(stepvan_home, monkeypatch):
    """The mount rules read the stored step: a point on the tread is refused, naming it; one on the rear face
    above it is not refused for it."""
    from rigopt.mounting.features import on_steps
    from rigopt.vehicle.library import load_vehicle

    monkeypatch.setenv("RIGOPT_HOME", str(stepvan_home[0]))
    van = load_vehicle("stepvan")
    rear_axle = van.rear_axle
    on_tread = rear_axle + np.array([-1.40, 0.0, STEP_TOP])
    above = rear_axle + np.array([-1.25, 0.0, 1.5])
    found = on_steps(van, np.array([on_tread, above]), 0.05)
    assert found[0] and "tread 1" in found[0][0]
    assert found[1] == []
