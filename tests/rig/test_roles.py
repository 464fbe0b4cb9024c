"""Camera roles: perception (fed to the detector) and near_field; in rig files, CARLA lists and other exports."""

from __future__ import annotations

import dataclasses
import json

import pytest

from rigopt.camera import Lens
from rigopt.errors import RigFileError
from rigopt.rig.formats.carla import export_carla, read_carla
from rigopt.rig.formats.nuscenes import export_nuscenes
from rigopt.rig.library import load_rig
from rigopt.rig.pccr_format import read_rig, rig_to_dict, write_rig


def _with_near_field(rig, ids):
    return dataclasses.replace(rig, cameras=tuple(dataclasses.replace(c, role="near_field") if c.id in ids else c
                                                  for c in rig.cameras))


def test_a_rig_file_keeps_roles_and_an_older_file_is_all_perception(tmp_path):
    r1 = load_rig("R1")
    assert all(c.role == "perception" for c in r1.cameras) and r1.perception() is r1
    mixed = _with_near_field(r1, {"CAM_BUMPER_FRONT", "CAM_BUMPER_BACK"})
    data = rig_to_dict(mixed)
    assert [c.get("role") for c in data["cameras"]].count("near_field") == 2
    assert all("role" not in c for c in rig_to_dict(r1)["cameras"])  # the benchmark's files are unchanged
    back = read_rig(write_rig(mixed, tmp_path / "mixed.json"))
    assert back.same_as(dataclasses.replace(mixed, name="mixed")) and back.near_field_count == 2
    assert [c.id for c in back.perception().cameras] == [c.id for c in r1.cameras if c.id not in
                                                         {"CAM_BUMPER_FRONT", "CAM_BUMPER_BACK"}]


def test_roles_are_checked():
    r1 = load_rig("R1")
    with pytest.raises(RigFileError, match="role must be one of perception, near_field"):
        dataclasses.replace(r1.cameras[0], role="driver")
    with pytest.raises(RigFileError, match="no perception cameras"):
        _with_near_field(r1, {c.id for c in r1.cameras}).perception()


def test_bad_role_in_a_file_is_one_clear_error(tmp_path):
    data = rig_to_dict(load_rig("R1"))
    data["cameras"][0]["role"] = "fisheye"
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    with pytest.raises(RigFileError, match=r"'role' must be one of perception, near_field \(absent: perception\)"):
        read_rig(path)


def test_carla_carries_the_role_as_role_name_and_nuscenes_says_it_does_not(tmp_path):
    mixed = _with_near_field(load_rig("R1"), {"CAM_BUMPER_BACK"})
    exported = export_carla(mixed)
    sensors = json.loads(exported.files[""])["sensors"]
    assert {s["id"]: s["attributes"]["role_name"] for s in sensors}["CAM_BUMPER_BACK"] == "near_field"
    path = tmp_path / "carla.json"
    path.write_text(exported.files[""])
    assert read_carla(path).rig.near_field_count == 1
    warnings = export_nuscenes(mixed).warnings
    assert any("near_field role of 1 camera(s)" in w for w in warnings)


def test_rigcd_and_rank_compare_the_perception_cameras_and_say_so(tmp_path, capsys):
    from rigopt.cli import run
    from rigopt.rig.pccr_format import write_rig

    r1 = load_rig("R1")
    extra = dataclasses.replace(r1.cameras[0], id="CAM_FISHEYE_FRONT", role="near_field", lens=Lens.pinhole(120.0))
    with_near_field = write_rig(dataclasses.replace(r1, name="r1nf", cameras=(*r1.cameras, extra)),
                                tmp_path / "r1nf.json")
    capsys.readouterr()
    assert run(["rigcd", "R1", str(with_near_field), "--json"]) == 0
    captured = capsys.readouterr()
    data = json.loads(captured.out)
    assert data["rigcd"] == 0 and data["count"] == 0  # the near-field camera is not compared
    assert data["near_field_left_out"] == {"r1nf": 1}  # and the JSON says so, as the note does
    assert "1 near_field camera(s) are not fed to the detector" in captured.err
    assert run(["rank", "--ref", "R1", str(with_near_field), "R1-c6", "--json"]) == 0
    ranked = json.loads(capsys.readouterr().out)
    assert ranked[0]["rig"] == "r1nf" and ranked[0]["rigcd"] == 0
    assert [p["near_field_left_out"] for p in ranked] == [1, 0]
