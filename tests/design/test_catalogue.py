"""Camera catalogues of the designer: real cameras from TOML or JSON files, pinholes at any image size, and
a design that carries its cameras' lenses into the rig file and the report."""

from __future__ import annotations

import json

import numpy as np
import pytest

from in_process import run_rigopt
from rigopt.camera import Lens
from rigopt.cli.design_command import parse_image_size
from rigopt.design.settings import (CatalogueCamera, DesignSettings, parse_catalogue, pinhole_catalogue,
                                    read_catalogue)
from rigopt.errors import DataError, RigoptError
from rigopt.rig.library import load_rig

CAMERAS = [
    {"name": "front-radtan", "width": 2048, "height": 1550, "fx": 1773.0, "fy": 1773.0, "cx": 1024.0, "cy": 775.0,
     "distortion": "radtan", "coefficients": [-0.26, 0.07, 0.0, 0.0, 0.0]},
    {"name": "wide-pinhole", "width": 1920, "height": 1080, "fx": 960.0, "fy": 960.0, "cx": 960.0, "cy": 540.0},
]
TOML = "\n".join("[[cameras]]\n" + "".join(f"{k} = {json.dumps(v)}\n" for k, v in c.items()) for c in CAMERAS)


def test_toml_and_json_catalogues_give_the_same_cameras(tmp_path):
    (tmp_path / "c.toml").write_text(TOML)
    (tmp_path / "c.json").write_text(json.dumps({"cameras": CAMERAS}))
    cameras = read_catalogue(tmp_path / "c.toml")
    assert cameras == read_catalogue(tmp_path / "c.json")
    assert [c.name for c in cameras] == ["front-radtan", "wide-pinhole"]
    assert cameras[0].lens == Lens(2048, 1550, 1773.0, 1773.0, 1024.0, 775.0, "radtan", (-0.26, 0.07, 0, 0, 0))
    assert cameras[0].fov == pytest.approx(cameras[0].lens.hfov) and cameras[0].fov > 64.0
    assert cameras[1].fov == pytest.approx(90.0)  # 2 atan(960 / 960)


@pytest.mark.parametrize("entry, fragment", [
    ({**CAMERAS[1], "fx": -1.0}, "fx must be positive"),
    ({**CAMERAS[1], "k1": 0.1}, "unknown keys k1"),
    ({**CAMERAS[1], "distortion": "fisheye", "coefficients": [0.1, 0.2]}, "needs 4"),
    ({**CAMERAS[1], "width": 12.5}, "whole number"),
    ({**CAMERAS[1], "name": ""}, "'name'"),
])
def test_a_bad_camera_names_the_file_and_the_camera(entry, fragment):
    with pytest.raises(DataError, match=fragment) as error:
        parse_catalogue({"cameras": [CAMERAS[0], entry]}, "my.toml")
    assert str(error.value).startswith("my.toml: camera 2")


def test_pinhole_catalogues_take_an_image_size():
    cameras = pinhole_catalogue((60, 120), (1920, 1080))
    assert [c.fov for c in cameras] == [60.0, 120.0]
    assert all(c.lens.image_size == (1920, 1080) and c.lens.is_ideal_pinhole for c in cameras)
    assert cameras[1].lens.hfov == pytest.approx(120.0)
    assert parse_image_size("1920x1080") == (1920, 1080)
    for text in ("1920", "axb", "0x10", "-5x10"):
        with pytest.raises(RigoptError, match="--image-size"):
            parse_image_size(text)


def test_a_catalogue_camera_becomes_a_rig_camera_with_its_lens():
    radtan, pinhole = parse_catalogue({"cameras": CAMERAS}, "c")
    camera = radtan.camera("C", [1.0, 0.0, 1.0], np.eye(3), "front")
    assert camera.lens == radtan.lens and camera.image_size == (2048, 1550) and camera.fov == radtan.fov
    plain = CatalogueCamera.pinhole(65.0).camera("P", [1.0, 0.0, 1.0], np.eye(3))
    assert plain.lens == Lens.pinhole(65.0) and plain.fov == 65.0 and plain.image_size == (1280, 720)
    ideal = pinhole.camera("W", [1.0, 0.0, 1.0], np.eye(3)).lens  # an ideal pinhole: the benchmark's form
    assert ideal == Lens.pinhole(pinhole.fov, pinhole.lens.image_size) and ideal.stated_hfov == pinhole.fov
    assert DesignSettings(lenses=(radtan, 60.0)).fovs == (radtan.fov, 60.0)


@pytest.mark.slow
def test_a_design_from_a_catalogue_keeps_each_cameras_lens(tmp_path):
    (tmp_path / "cameras.toml").write_text(TOML)
    out = tmp_path / "design"
    result = run_rigopt("design", "--vehicle", "tt", "--ref", "R1", "--cameras-file", tmp_path / "cameras.toml",
                        "--pitch", "0", "--yaw-step", "30", "--spacing", "0.3", "--json",
                        "--out", out)
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)
    catalogue = {c.name: c.lens for c in read_catalogue(tmp_path / "cameras.toml")}
    design = load_rig(out / "rig.json")
    assert len(design.perception()) == 8  # the catalogue's lenses; the near-field cameras are fisheyes
    for camera, entry in zip(design.perception().cameras, summary["cameras"]):
        assert camera.lens in catalogue.values()  # refined or not, the lens is the catalogue's
        assert entry["lens"]["width"] == camera.image_size[0] and entry["lens"]["fx"] == camera.lens.fx
        assert entry["lens"]["hfov_deg"] == pytest.approx(camera.fov, abs=1e-6)
    assert any(c.lens.is_distorted for c in design.cameras)  # the radtan lens travels in the rig file
    assert summary["solver"]["milp_status"] == "optimal"  # (the refinement, accepted or not, kept the lenses)
    assert "radtan" in (out / "report.html").read_text()


def test_cameras_file_and_fov_do_not_mix(tmp_path):
    (tmp_path / "cameras.toml").write_text(TOML)
    result = run_rigopt("design", "--vehicle", "tt", "--ref", "R1", "--cameras-file", tmp_path / "cameras.toml",
                        "--fov", "90")
    assert result.returncode == 2 and "leave out --fov" in result.stderr
