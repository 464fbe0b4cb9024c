"""Acceptance (issue 29, parts 3-6): every raw mesh is added by following only the hints ``vehicle add`` prints.

Each raw mesh is written the way a simulator or a CAD tool would (tests/sim_car.py's vehicles in other units,
turned, lifted, split in parts, open, thin). The loop runs ``rigopt vehicle add`` in-process; on a refusal it
reads the flags after the error line's last ": add " (the first of alternatives), adds them and retries, at
most 3 runs (2 are needed). Then the stored vehicle is measured against the truth it was built from.
"""

from __future__ import annotations

import re
import tomllib

import numpy as np
import pytest
import trimesh

import sim_car
from in_process import run_rigopt
from marks import cases

pytestmark = pytest.mark.usefixtures("rigopt_home")

#: A flag with a value (a number or an axis) or one of the value-less flags the hints name.
HINT_FLAG = re.compile(r"(--(?:scale|length|forward|up|pitch) [-+]?[\dxyz.]+[\de.-]*|--ground|--allow-size)")


def hinted_flags(stderr: str) -> list[str]:
    """The flags of the hint on a refusal's error line: the text after its last ': add ', up to the first
    alternative (', or' / ' (or'); '--length L' placeholders are not flags."""
    line = [line for line in stderr.splitlines() if line.startswith("rigopt: error:")][-1]
    hint = line.rsplit(": add ", 1)[1]
    hint = re.split(r",? \(?or ", hint, maxsplit=1)[0]
    return [part for flag in HINT_FLAG.findall(hint) for part in flag.split()]


def add_following_hints(name: str, path, env, rounds: int = 3):
    """Run ``vehicle add`` and follow its hints; (the last run, the flags used, the number of runs)."""
    flags: list[str] = []
    for run in range(1, rounds + 1):
        outcome = run_rigopt("vehicle", "add", name, "--mesh", path, *flags, env=env)
        if outcome.returncode != 2:
            return outcome, flags, run
        new = hinted_flags(outcome.stderr)
        assert new, outcome.stderr
        assert not set(new[::2]) & set(flags[::2]), f"the hint repeats a flag: {outcome.stderr}"
        flags += new
    return outcome, flags, rounds


def write_mesh(path, parts, forward="+x", up="+z", scale=1.0, lift=0.0, shift=(0.0, 0.0, 0.0)):
    """The parts (ISO, m), lifted by ``lift`` m and moved by ``shift`` m, written in a file frame (``forward``,
    ``up``) in units of ``1 / scale`` m; an OBJ keeps the parts as groups."""
    moved = {}
    for key, part in parts.items():
        part = part.copy()
        part.apply_translation(np.add(shift, [0.0, 0.0, lift]))
        moved[key] = part
    if path.suffix == ".obj":
        sim_car.write_obj(path, forward, up, scale, moved)
    else:
        sim_car.to_file_frame(sim_car.joined(moved), forward, up, scale).export(path)
    return path


def write_dae_in_centimetres(path, parts):
    """The parts as COLLADA geometries in centimetres with the unit declared (<unit meter="0.01">)."""
    meshes = [sim_car.to_file_frame(part, scale=0.01) for part in parts.values()]
    text = trimesh.exchange.dae.export_collada(meshes).decode()
    path.write_text(text.replace("<up_axis>", '<unit name="centimeter" meter="0.01"/>\n    <up_axis>', 1))
    return path


def open_body(parts):
    """The dual truck with its box body's floor removed (an open, multi-part mesh)."""
    parts = dict(parts)
    box = parts["box"].subdivide()
    parts["box"] = trimesh.Trimesh(box.vertices, box.faces[box.face_normals[:, 2] > -0.5], process=False)
    return parts


#: name -> (writer(tmp) -> path, (length, width, height) m, axles x m from the box centre, radius m)
def _cases():
    car, hug, dual, thin = (sim_car.sim_car_parts(), sim_car.hugging_car_parts(), sim_car.dual_truck_parts(),
                            sim_car.thin_fire_truck_parts())
    hug_axles = tuple(x - 0.0 for x in sim_car.HUG_AXLES)  # the hugging car's box is centred at x = 0
    dual_axles = tuple(x - (-3.6 + 3.7) / 2 for x in sim_car.DUAL_AXLES)  # box x in [-3.6, 3.7]
    return {
        "car_cm_facing_minus_y": (lambda t: write_mesh(t / "car.obj", car, forward="-y", scale=0.01),
                                  (4.6, 1.8, 1.5), sim_car.AXLES, sim_car.RADIUS),
        "hatch_inch_facing_plus_y": (lambda t: write_mesh(t / "hatch.ply", hug, forward="+y", scale=0.0254),
                                     (4.5, 1.76, 1.48), hug_axles, sim_car.HUG_RADIUS),
        "hatch_scale_0.06_backwards": (lambda t: write_mesh(t / "hatch.stl", hug, forward="-x", scale=0.06),
                                       (4.5, 1.76, 1.48), hug_axles, sim_car.HUG_RADIUS),
        "hatch_scale_0.1_y_up": (lambda t: write_mesh(t / "hatch.glb", hug, forward="+z", up="+y", scale=0.1),
                                 (4.5, 1.76, 1.48), hug_axles, sim_car.HUG_RADIUS),
        "truck_floating_open": (lambda t: write_mesh(t / "truck.obj", open_body(dual), lift=1.3, shift=(0.7, 0, 0)),
                                (7.3, 2.5, 3.6), dual_axles, sim_car.DUAL_RADIUS),
        "thin_fire_truck_dae_cm": (lambda t: write_dae_in_centimetres(t / "fire.dae", thin),
                                   (8.4, 2.5, 3.38), sim_car.THIN_AXLES, sim_car.THIN_RADIUS),
    }


CASES = _cases()


@pytest.mark.parametrize("case", cases(CASES, slow={"thin_fire_truck_dae_cm", "truck_floating_open",
                                                    "car_cm_facing_minus_y", "hatch_scale_0.06_backwards",
                                                    "hatch_scale_0.1_y_up"}))
def test_every_raw_mesh_is_added_by_following_the_hints(case, tmp_path, rigopt_home):
    write, size, axles, radius = CASES[case]
    path = write(tmp_path)
    outcome, flags, runs = add_following_hints("raw", path, {"RIGOPT_HOME": str(rigopt_home)})
    assert outcome.returncode == 0, (flags, outcome.stderr)
    assert runs <= 2  # one retry with the hinted flags is enough
    assert "Traceback" not in outcome.stderr
    spec = tomllib.loads((rigopt_home / "vehicles" / "raw" / "vehicle.toml").read_text())
    # the right scale, the right way round (the fire truck's ladder is filled between its rails and rungs)
    assert spec["box"] == pytest.approx(size, rel=0.03, abs=0.03)
    assert spec["axles"] == pytest.approx(sorted(axles, reverse=True), abs=0.02)  # from the footprint's centre
    assert [w["radius"] for w in spec["wheels"]] == pytest.approx([radius] * len(axles), abs=0.015)
    assert "closing error max" in outcome.stdout


def test_the_hints_name_the_unit_the_mesh_was_drawn_in(tmp_path, rigopt_home):
    env = {"RIGOPT_HOME": str(rigopt_home)}
    hug = sim_car.hugging_car_parts()
    for scale, name in [(0.0254, "inches"), (0.06, None), (0.1, "decimetres"), (0.01, "centimetres")]:
        path = write_mesh(tmp_path / f"hatch_{scale}.stl", hug, scale=scale)
        outcome = run_rigopt("vehicle", "add", "hatch", "--mesh", path, env=env)
        assert outcome.returncode == 2
        assert hinted_flags(outcome.stderr)[:2] == ["--scale", f"{scale:g}"], outcome.stderr
        assert (f"looks like {name}" if name else f"in units of {scale:g} m") in outcome.stderr


def test_one_retry_takes_every_pose_flag_at_once(tmp_path, rigopt_home):
    path = write_mesh(tmp_path / "car.obj", sim_car.sim_car_parts(), forward="-y", scale=0.01)
    outcome = run_rigopt("vehicle", "add", "car", "--mesh", path, env={"RIGOPT_HOME": str(rigopt_home)})
    assert hinted_flags(outcome.stderr) == ["--scale", "0.01", "--forward", "-y"]


def test_length_scales_to_a_known_length(tmp_path, rigopt_home):
    path = write_mesh(tmp_path / "hatch.stl", sim_car.hugging_car_parts(), scale=1 / 37.0)  # an odd unit
    outcome = run_rigopt("vehicle", "add", "hatch", "--mesh", path, "--length", "4.5", "--forward", "+x",
                         env={"RIGOPT_HOME": str(rigopt_home)})
    assert outcome.returncode == 0, outcome.stderr
    spec = tomllib.loads((rigopt_home / "vehicles" / "hatch" / "vehicle.toml").read_text())
    assert spec["box"][0] == pytest.approx(4.5, abs=0.01)
    assert "scaled by" in outcome.stderr and "rigopt: note:" in outcome.stderr


def test_scale_and_length_together_are_refused(tmp_path, rigopt_home):
    path = write_mesh(tmp_path / "hatch.stl", sim_car.hugging_car_parts())
    outcome = run_rigopt("vehicle", "add", "hatch", "--mesh", path, "--length", "4.5", "--scale", "1",
                         env={"RIGOPT_HOME": str(rigopt_home)})
    assert outcome.returncode == 2 and "not both" in outcome.stderr


def test_a_dae_files_declared_unit_is_applied_with_a_note(tmp_path):
    from rigopt.vehicle.user import declared_unit

    path = write_dae_in_centimetres(tmp_path / "car.dae", sim_car.hugging_car_parts())
    assert declared_unit(path) == 0.01
    plain = tmp_path / "plain.dae"
    plain.write_bytes(trimesh.exchange.dae.export_collada([trimesh.creation.box()]))
    assert declared_unit(plain) is None


@pytest.mark.slow
def test_a_floating_mesh_is_stood_on_its_tyres_with_a_note(tmp_path, rigopt_home):
    path = write_mesh(tmp_path / "truck.obj", sim_car.dual_truck_parts(), lift=1.3)
    outcome = run_rigopt("vehicle", "add", "truck", "--mesh", path, env={"RIGOPT_HOME": str(rigopt_home)})
    assert outcome.returncode == 0, outcome.stderr
    assert "stood on its tyres: moved down by 1.300 m" in outcome.stderr
    assert "the file's origin is at (-0.050, +0.000, -1.300) m" in outcome.stderr  # its box is centred at x 0.05
    from rigopt.vehicle.library import load_vehicle

    assert load_vehicle("truck").mesh.bounds[0, 2] == pytest.approx(0.0, abs=0.005)


def test_a_floating_mesh_without_tyres_is_told_to_add_ground(box_car, tmp_path, rigopt_home):
    lifted = box_car.mesh.copy()
    lifted.apply_translation([0, 0, 2.0])
    lifted.export(tmp_path / "box.stl")
    env = {"RIGOPT_HOME": str(rigopt_home)}
    refused = run_rigopt("vehicle", "add", "box", "--mesh", tmp_path / "box.stl", "--forward", "+x", env=env)
    assert refused.returncode == 2 and hinted_flags(refused.stderr) == ["--ground"]
    added = run_rigopt("vehicle", "add", "box", "--mesh", tmp_path / "box.stl", "--forward", "+x", "--ground", env=env)
    assert added.returncode == 0, added.stderr
    from rigopt.vehicle.library import load_vehicle

    assert load_vehicle("box").mesh.bounds[0, 2] == pytest.approx(0.0, abs=1e-4)


@pytest.mark.slow
def test_the_thin_truck_gets_keep_outs_over_its_ladder_and_light_bar(tmp_path, rigopt_home):
    path = write_mesh(tmp_path / "fire.obj", sim_car.thin_fire_truck_parts())
    outcome = run_rigopt("vehicle", "add", "fire", "--mesh", path, env={"RIGOPT_HOME": str(rigopt_home)})
    assert outcome.returncode == 0, outcome.stderr
    assert re.search(r"closed on a 4\.0 cm grid \(distance\), \d+% of the surface thin", outcome.stdout)
    from rigopt.mounting.practice import in_keep_outs
    from rigopt.vehicle.library import load_vehicle

    fire = load_vehicle("fire")
    offset = -0.5 * (fire.mesh.bounds[0, 0] + fire.mesh.bounds[1, 0])  # truth (sim_car) is in the file's frame
    ladder_rail = [-1.0 + offset, 0.45, 3.41]  # 3 cm above the top of a rail
    rung = [0.2 + offset, 0.0, 3.40]
    light_bar = [3.4 + offset, 0.3, 3.03 + 0.03 + 0.03]  # on its top: its shell and the lens's 3 cm
    body_roof = [-2.3 + offset, 1.0, 3.25]  # the roof beside the ladder
    cab_side = [3.0 + offset, 1.28, 2.0]
    found = in_keep_outs(fire, [ladder_rail, rung, light_bar, body_roof, cab_side])
    assert [bool(f) for f in found] == [True, True, True, False, False], found
    assert all("no surface for a housing" in f[0] for f in found[:3])
