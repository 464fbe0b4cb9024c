"""Mud flaps found on a user mesh (``rigopt.vehicle.mud_flaps``): thin plates behind the tyres are, a block as thick
as a bumper is not; ``vehicle add`` stores and states them, and the mount rules read them."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh
from in_process import run_rigopt

from rigopt.vehicle.mud_flaps import MARGIN, mud_flaps
from rigopt.vehicle.wheels import FoundWheels

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
sys.path.insert(0, str(EXAMPLES))
import make_raw_van  # noqa: E402

#: The rear tyres' middle (|y|, m) of the example van: its wheels' outer faces 6 cm inside the body's sides.
TYRE_Y = make_raw_van.WIDTH / 2 - 0.06 - make_raw_van.WHEEL_W / 2
FLAP_X = -0.55  # m, from the rear axle: 0.19 m behind the tyre


def _plates(thickness: float) -> list[trimesh.Trimesh]:
    plates = []
    for side in (1.0, -1.0):
        plate = trimesh.creation.box(extents=[thickness, 0.3, 0.5])
        plate.apply_translation([FLAP_X, side * TYRE_Y, 0.42])
        plates.append(plate)
    return plates


def _van(thickness: float | None) -> trimesh.Trimesh:
    extra = _plates(thickness) if thickness else []
    return trimesh.util.concatenate([*make_raw_van.body(), *make_raw_van.wheels(), *make_raw_van.mirrors(), *extra])


def _wheels() -> list[FoundWheels]:
    track = 2 * TYRE_Y
    return [FoundWheels(x, make_raw_van.WHEEL_R, make_raw_van.WHEEL_W, track) for x in (make_raw_van.WHEELBASE, 0.0)]


def test_thin_plates_behind_the_rear_tyres_are_mud_flaps():
    flaps = mud_flaps(_van(0.01), _wheels())
    assert [f["name"] for f in flaps] == ["mud flap behind the rear-left wheel (found)",
                                          "mud flap behind the rear-right wheel (found)"]
    left = flaps[0]
    assert left["kind"] == "mud_flap"
    assert left["min"] == pytest.approx([FLAP_X - 0.005 - MARGIN, TYRE_Y - 0.15 - MARGIN, 0.17 - MARGIN], abs=1e-6)
    assert left["max"] == pytest.approx([FLAP_X + 0.005 + MARGIN, TYRE_Y + 0.15 + MARGIN, 0.67 + MARGIN], abs=1e-6)


def test_no_flap_on_the_plain_van_nor_a_block_as_thick_as_a_bumper():
    assert mud_flaps(_van(None), _wheels()) == []
    assert mud_flaps(_van(0.12), _wheels()) == []


def test_vehicle_add_stores_the_flaps_and_no_lens_may_sit_on_them(tmp_path, monkeypatch):
    from rigopt.mounting.features import on_fixtures
    from rigopt.vehicle.library import load_vehicle

    mesh = tmp_path / "flap_van.obj"
    van = _van(0.01)
    van.apply_scale(make_raw_van.MM)
    van.export(mesh)
    env = {"RIGOPT_HOME": str(tmp_path / "home")}
    added = run_rigopt("vehicle", "add", "flapvan", "--mesh", mesh, "--scale", "0.001", env=env)
    assert added.returncode == 0, added.stderr
    flat = " ".join(added.stdout.split())
    # the rear axle is the example's origin: the reports' frame gives the plate's own x (within the found axle's cm)
    found = re.search(r"mud flaps: thin plates hanging behind the tyres, where no lens sits: mud flap behind the "
                      r"rear-left wheel \(found\) x (-?[\d.]+)\.\.(-?[\d.]+) m", flat)
    assert found, flat
    assert [float(v) for v in found.groups()] == pytest.approx([FLAP_X - 0.015, FLAP_X + 0.015], abs=0.011)
    monkeypatch.setenv("RIGOPT_HOME", env["RIGOPT_HOME"])
    stored = load_vehicle("flapvan")
    on_flap = stored.rear_axle + np.array([FLAP_X, -TYRE_Y, 0.4])
    found = on_fixtures(stored, [on_flap], 0.05)
    assert found[0] and "mud flap behind the rear-right wheel" in found[0][0]
