"""import(export(rig)) same_as rig for every export format, on the benchmark's R1 and on rigs with real lenses
where the format carries them; the CLI's import/export; a CARLA export renders like the original rig."""

from __future__ import annotations

import json

import numpy as np
import pytest

from in_process import run_rigopt
from rigopt.camera import Lens
from rigopt.errors import RigoptError
from rigopt.rig.formats.registry import export_rig
from rigopt.rig.library import load_rig
from rigopt.rig.model import Camera, Rig, RigOrigin

FILES = {"nuscenes": "tables", "urdf": "rig.urdf", "opencv": "camchain.yaml", "carla": "carla.json"}


def lens_rig(distortions=("radtan", "fisheye"), origin=RigOrigin()) -> Rig:
    """R1's first three poses with real lenses: off-centre principal points, fx != fy, distortion."""
    r1 = load_rig("R1")
    lenses = {
        "none": Lens(1600, 900, 1266.4, 1266.9, 816.27, 491.5),
        "radtan": Lens(1920, 1280, 2059.6, 2061.2, 944.5, 638.9, "radtan", (0.0436, -0.3373, 0.0011, -0.0008, 0.012)),
        "fisheye": Lens(1280, 960, 330.2, 330.9, 641.3, 479.4, "fisheye", (0.0348, 0.0071, -0.0021, 0.0002)),
    }
    cameras = [Camera(c.id, c.position, c.rotation, lenses[d]) for c, d in zip(r1.cameras, ("none", *distortions))]
    return Rig("lensy", "vehicle.audi.etron", tuple(cameras), origin)


def round_trip(tmp_path, rig, format_name, *extra):
    exported = tmp_path / FILES[format_name]
    result = run_rigopt("export", tmp_path / "rig_in.json" if rig.name == "lensy" else rig.name, "--format",
                        format_name, "--out", exported)
    assert result.returncode == 0, result.stderr
    out = tmp_path / "back" / f"{rig.name}.json"  # a rig file is named by its stem
    result = run_rigopt("import", format_name, exported, "--out", out, "--name", rig.name, "--vehicle", rig.vehicle,
                        *extra)
    assert result.returncode == 0, result.stderr
    return load_rig(out), result


def save(tmp_path, rig):
    from rigopt.rig.pccr_format import write_rig

    write_rig(rig, tmp_path / "rig_in.json")


@pytest.mark.parametrize("format_name", list(FILES))
def test_r1_round_trips_exactly(tmp_path, format_name):
    from rigopt.vehicle.library import load_vehicle
    from rigopt.vehicle.placement import to_vehicle_centre

    r1, etron = load_rig("R1"), load_vehicle("etron")
    back, result = round_trip(tmp_path, r1, format_name)
    if format_name == "nuscenes":  # written from the etron's rear axle, as nuScenes readers expect
        assert back.origin.kind == "rear_axle"
        assert back.positions[:, 0] == pytest.approx(r1.positions[:, 0] - etron.rear_axle[0])
    back, _ = to_vehicle_centre(back, etron)
    assert back.same_as(r1, atol=1e-9)


@pytest.mark.parametrize("format_name", ["opencv"])
def test_radtan_and_fisheye_lenses_round_trip(tmp_path, format_name):
    rig = lens_rig()
    save(tmp_path, rig)
    back, _ = round_trip(tmp_path, rig, format_name)
    assert back.same_as(rig, atol=1e-9)


def test_urdf_carries_radtan_lenses_and_refuses_fisheye(tmp_path):
    rig = lens_rig(("radtan", "radtan"))
    save(tmp_path, rig)
    back, _ = round_trip(tmp_path, rig, "urdf")
    assert back.same_as(rig, atol=1e-9)
    with pytest.raises(RigoptError, match="no Kannala-Brandt fisheye"):
        export_rig(lens_rig(), "urdf")


def test_nuscenes_carries_pinhole_lenses_and_the_rear_axle(tmp_path):
    rig = lens_rig(("none", "none"), origin=RigOrigin("rear_axle"))
    save(tmp_path, rig)
    back, result = round_trip(tmp_path, rig, "nuscenes")
    assert back.same_as(rig, atol=1e-9)
    assert "origin: rear axle (nuScenes ego frame)" in result.stderr


def test_lossy_exports_say_what_they_drop(tmp_path):
    rig = lens_rig(("radtan", "radtan"), origin=RigOrigin("rear_axle"))
    nuscenes = export_rig(rig, "nuscenes")
    assert any("carry no distortion" in w for w in nuscenes.warnings)
    carla = export_rig(rig, "carla")
    assert any("ideal centred pinholes" in w for w in carla.warnings)
    assert any("--origin rear_axle" in w for w in carla.warnings)
    wide = Camera("WIDE", [0, 0, 1], np.eye(3), Lens(1280, 960, 300.0, 300.0, 640.0, 480.0, "fisheye"))
    assert wide.fov > 180.0
    with pytest.raises(RigoptError, match="FOV under 180 deg"):
        export_rig(Rig("wide", "v", (wide,)), "carla")
    save(tmp_path, rig)
    result = run_rigopt("export", tmp_path / "rig_in.json", "--format", "nuscenes", "--out", tmp_path / "t")
    assert result.returncode == 0
    lines = result.stderr.splitlines()
    assert len(lines) == 2 and all(line.startswith("warning: ") for line in lines)  # distortion; name, vehicle


def test_carla_export_renders_like_the_original(tmp_path):
    from rigopt.validation.synthetic.render import render_rig
    from rigopt.validation.synthetic.scenes import split_scenes

    r1 = load_rig("R1")
    back, _ = round_trip(tmp_path, r1, "carla")
    scene = split_scenes("mini", 1, 1)[0]
    original, imported = render_rig(scene, 0, r1, None, (48, 27)), render_rig(scene, 0, back, None, (48, 27))
    for camera in r1.cameras:
        assert np.array_equal(original[camera.id].rgb, imported[camera.id].rgb), camera.id
        np.testing.assert_allclose(original[camera.id].depth, imported[camera.id].depth, rtol=1e-9)


def test_import_json_lists_origin_and_cameras(tmp_path):
    run_rigopt("export", "R1", "--format", "urdf", "--out", tmp_path / "r.urdf")
    result = run_rigopt("import", "urdf", tmp_path / "r.urdf", "--out", tmp_path / "r.json", "--json")
    report = json.loads(result.stdout)
    assert report["origin"] == "vehicle_centre" and report["vehicle"] == "urdf" and report["rig"] == "R1"
    assert [c["id"] for c in report["cameras"]] == [c.id for c in load_rig("R1").cameras]
    assert report["cameras"][0]["hfov"] == pytest.approx(65.0, abs=1e-9)


def test_existing_out_needs_force(tmp_path):
    run_rigopt("export", "R1", "--format", "carla", "--out", tmp_path / "c.json")
    again = run_rigopt("export", "R1", "--format", "carla", "--out", tmp_path / "c.json")
    assert again.returncode == 2 and "--force" in again.stderr
    assert run_rigopt("export", "R1", "--format", "carla", "--out", tmp_path / "c.json", "--force").returncode == 0


def test_nuscenes_list_prints_the_distinct_calibrations():
    from pathlib import Path

    folder = Path(__file__).resolve().parents[2] / "fixtures" / "formats" / "nuscenes_two_logs"
    rows = json.loads(run_rigopt("import", "nuscenes", folder, "--list", "--json").stdout)
    assert [r["vehicles"] for r in rows] == [["n015"], ["n008"]]


def test_a_design_with_near_field_fisheyes_goes_to_carla_with_its_perception_cameras(tmp_path):
    """CARLA's pinhole cannot carry a 190-degree fisheye: the error names --perception, which writes the
    perception cameras alone (with a note)."""
    import dataclasses

    from rigopt.design.near_field import fisheye_190
    from rigopt.rig.pccr_format import write_rig

    r1, fisheye = load_rig("R1"), fisheye_190()
    near = dataclasses.replace(r1.cameras[0], id="NEAR", role="near_field", lens=fisheye.lens)
    path = write_rig(dataclasses.replace(r1, name="two_roles", cameras=(*r1.cameras, near)), tmp_path / "rig.json")
    refused = run_rigopt("export", path, "--format", "carla", "--out", tmp_path / "carla.json")
    assert refused.returncode == 2 and "--perception" in refused.stderr and "NEAR" in refused.stderr
    done = run_rigopt("export", path, "--format", "carla", "--perception", "--out", tmp_path / "carla.json")
    assert done.returncode == 0, done.stderr
    assert "1 near_field camera(s) left out" in done.stderr
    sensors = json.loads((tmp_path / "carla.json").read_text())
    assert "NEAR" not in json.dumps(sensors) and r1.cameras[0].id in json.dumps(sensors)
