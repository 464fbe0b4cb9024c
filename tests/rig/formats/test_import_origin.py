"""``--origin custom --origin-offset X,Y,Z`` on every import command: the positions stay as the file gives them,
the rig records the custom origin, and moving the rig to its vehicle's centre adds the offset (what
``RigOrigin("custom", point)`` means); the option's mistakes each get one error line; ``--origin``'s help names
every kind."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.feather as feather
import pytest
from in_process import run_rigopt

from rigopt.rig.model import RigOrigin
from rigopt.rig.pccr_format import read_rig
from rigopt.vehicle.library import load_vehicle
from rigopt.vehicle.placement import to_vehicle_centre

FIXTURES = Path(__file__).resolve().parents[2] / "fixtures" / "formats"
OFFSET = (-1.42, 0.05, 0.31)
OFFSET_TEXT = ",".join(str(v) for v in OFFSET)
IMPORT_COMMANDS = ("nuscenes", "argoverse1", "argoverse2", "dgp", "waymo", "opencv", "urdf", "carla")


@pytest.fixture(scope="module")
def sources(tmp_path_factory) -> dict[str, list]:
    """format -> the import arguments (format, path, extra options) of a small source of that format."""
    tmp = tmp_path_factory.mktemp("origin_sources")
    for fmt, suffix in (("urdf", ".urdf"), ("carla", ".json")):
        result = run_rigopt("export", "R1", "--format", fmt, "--out", tmp / f"r1{suffix}")
        assert result.returncode == 0, result.stderr
    av2 = tmp / "av2_log" / "calibration"
    av2.mkdir(parents=True)
    feather.write_feather(pa.table({"sensor_name": ["ring_front_center"], "qw": [0.5], "qx": [-0.5], "qy": [0.5],
                                    "qz": [-0.5], "tx_m": [1.63], "ty_m": [0.0], "tz_m": [1.43]}),
                          av2 / "egovehicle_SE3_sensor.feather")
    feather.write_feather(pa.table({"sensor_name": ["ring_front_center"], "fx_px": [1773.5], "fy_px": [1773.5],
                                    "cx_px": [775.8], "cy_px": [1023.6], "k1": [0.0], "k2": [0.0], "k3": [0.0],
                                    "height_px": [2048], "width_px": [1550]}), av2 / "intrinsics.feather")
    return {
        "nuscenes": ["nuscenes", FIXTURES / "nuscenes_two_logs", "--calibration", "0"],
        "argoverse1": ["argoverse1", FIXTURES / "argoverse1_log"],
        "argoverse2": ["argoverse2", av2.parent],
        "dgp": ["dgp", FIXTURES / "dgp_scene"],
        "waymo": None,  # tests/rig/formats/test_format_waymo_v1.py checks it on a v1 TFRecord
        "opencv": ["opencv", FIXTURES / "kalibr_camchain.yaml"],
        "urdf": ["urdf", tmp / "r1.urdf"],
        "carla": ["carla", tmp / "r1.json"],
    }


@pytest.fixture(scope="module")
def vehicle():
    return load_vehicle("tt")


@pytest.mark.parametrize("fmt", [f for f in IMPORT_COMMANDS if f != "waymo"])
def test_custom_origin_keeps_positions_and_means_the_offset_from_the_centre(fmt, sources, vehicle, tmp_path):
    args = sources[fmt]
    custom, as_given = tmp_path / "custom.json", tmp_path / "as_given.json"
    result = run_rigopt("import", *args, "--out", custom, "--origin", "custom", "--origin-offset", OFFSET_TEXT)
    assert result.returncode == 0, result.stderr
    assert result.stderr.startswith("origin: custom point (-1.420, 0.050, 0.310) m (--origin)")
    reference = run_rigopt("import", *args, "--out", as_given, "--origin", "vehicle_centre")
    assert reference.returncode == 0, reference.stderr
    rig, given = read_rig(custom), read_rig(as_given)
    assert rig.origin == RigOrigin("custom", OFFSET)
    for camera, plain in zip(rig.cameras, given.cameras):
        np.testing.assert_allclose(camera.position, plain.position, atol=1e-9)  # nothing raised or moved
    centred, change = to_vehicle_centre(rig, vehicle)
    assert change is not None and centred.origin == RigOrigin("vehicle_centre")
    for camera, plain in zip(centred.cameras, given.cameras):
        np.testing.assert_allclose(camera.position, plain.position + np.array(OFFSET), atol=1e-9)


@pytest.mark.parametrize("options, message", [
    (["--origin-offset", "1,2,3"], "--origin-offset needs --origin custom"),
    (["--origin", "custom"], "--origin custom needs --origin-offset X,Y,Z"),
    (["--origin", "rear_axle", "--origin-offset", "1,2,3"], "--origin-offset goes with --origin custom, not --origin "
                                                            "rear_axle"),
    (["--origin", "custom", "--origin-offset", "1,2"], "--origin-offset must be three numbers X,Y,Z"),
    (["--origin", "custom", "--origin-offset", "a,b,c"], "--origin-offset must be three numbers X,Y,Z"),
    (["--origin", "custom", "--origin-offset", "1,inf,0"], "--origin-offset must be three numbers X,Y,Z"),
    (["--origin", "roof"], "--origin must be one of vehicle_centre, rear_axle, custom, got 'roof'"),
])
def test_origin_mistakes_are_one_error_line(options, message, tmp_path):
    out = tmp_path / "r.json"
    result = run_rigopt("import", "argoverse1", FIXTURES / "argoverse1_log", "--out", out, *options)
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and result.stderr.startswith(f"rigopt: error: {message}")
    assert result.stdout == "" and not out.exists()


@pytest.mark.parametrize("fmt", IMPORT_COMMANDS)
def test_origin_help_lists_every_kind(fmt):
    result = run_rigopt("import", fmt, "--help")
    assert result.returncode == 0
    text = re.sub(r"[\s│]+", " ", result.stdout)
    assert re.search(r"--origin .*vehicle_centre, rear_axle, or custom", text)
    assert "--origin-offset" in text
