"""rigopt.rig.pccr_format: the benchmark's rig JSON (CARLA frame) <-> Rig (ISO 8855)."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from rigopt.errors import RigFileError
from rigopt.geometry import quaternion_to_matrix
from rigopt.rig.library import library_rig
from rigopt.rig.model import Camera, Rig
from rigopt.rig.pccr_format import read_rig, rig_from_dict, rig_to_dict, write_rig

#: The benchmark's original rig files (CARLA frame, y right); the library holds rigopt's copies.
BENCHMARK_RIGS = Path(os.environ.get("RIGOPT_PCCR_RIGS", Path(__file__).resolve().parents[3] / "shared" / "pccr" / "rigs"))
LIBRARY_NAMES = ["R1", "R1-c10", "R1-c6", "R1-f", "R1-r", "R1-t", "R2", "R3", "R4", "R5", "R6", "R7", "R8", "R9"]

needs_benchmark = pytest.mark.skipif(
    not BENCHMARK_RIGS.is_dir(), reason=f"benchmark rig files not found at {BENCHMARK_RIGS} (set RIGOPT_PCCR_RIGS)"
)


def _benchmark_file(name: str) -> Path:
    return BENCHMARK_RIGS / f"{name}.json"


def _library_file(name: str) -> Path:
    [path] = Path(__file__).resolve().parents[2].glob(f"vehicles/*/rigs/{name}.json")
    return path


def _minimal_camera(**overrides):
    entry = {"id": "CAM_FRONT", "location": [2.0, 0.0, 0.7], "rotation": [0.0, 0.0, 0.0], "fov": 65}
    entry.update(overrides)
    return entry


def _write_text(tmp_path, text: str) -> Path:
    path = tmp_path / "bad_rig.json"
    path.write_text(text)
    return path


# --- the benchmark's files ------------------------------------------------------------------------------


@needs_benchmark
@pytest.mark.parametrize("name", LIBRARY_NAMES)
def test_benchmark_file_reads_like_the_library_copy(name):
    assert read_rig(_benchmark_file(name)).same_as(library_rig(name))


@pytest.mark.parametrize("source", ["library", pytest.param("benchmark", marks=needs_benchmark)])
@pytest.mark.parametrize("name", LIBRARY_NAMES)
def test_read_write_read_round_trip_is_exact(tmp_path, name, source):
    original = read_rig(_library_file(name) if source == "library" else _benchmark_file(name))
    written = write_rig(original, tmp_path / f"{name}.json")
    assert read_rig(written).same_as(original, atol=1e-12)


@pytest.mark.parametrize("source", ["library", pytest.param("benchmark", marks=needs_benchmark)])
@pytest.mark.parametrize("name", LIBRARY_NAMES)
def test_written_numbers_are_the_files_numbers(tmp_path, name, source):
    path = _library_file(name) if source == "library" else _benchmark_file(name)
    original = json.loads(path.read_text())
    written = json.loads(write_rig(read_rig(path), tmp_path / "out.json").read_text())
    assert written["vehicle_type"] == original["vehicle_type"]
    assert [c["id"] for c in written["cameras"]] == [c["id"] for c in original["cameras"]]
    for new, old in zip(written["cameras"], original["cameras"]):
        assert new["location"] == old["location"]
        assert new["fov"] == old["fov"]
        assert [(a - b) % 360.0 for a, b in zip(new["rotation"], old["rotation"])] == [0.0, 0.0, 0.0]
        assert all(-180.0 < a <= 180.0 for a in new["rotation"][1:])


@needs_benchmark
def test_benchmark_angles_beyond_180_are_written_wrapped():
    # R8's camera with yaw 214 in the benchmark file is written as the same direction, -146; 180 stays 180.
    original = json.loads(_benchmark_file("R8").read_text())
    assert any(c["rotation"][1] == 214.0 for c in original["cameras"])
    written = rig_to_dict(read_rig(_benchmark_file("R8")))
    assert [c["rotation"][1] for c in written["cameras"]] == [
        180.0 - (180.0 - c["rotation"][1]) % 360.0 for c in original["cameras"]
    ]


@needs_benchmark
@pytest.mark.parametrize("name", LIBRARY_NAMES)
def test_benchmark_files_read_without_error_and_in_order(name):
    data = json.loads(_benchmark_file(name).read_text())
    rig = read_rig(_benchmark_file(name))
    assert rig.name == name and rig.vehicle == data["vehicle_type"]
    assert [c.id for c in rig.cameras] == [c["id"] for c in data["cameras"]]
    np.testing.assert_array_equal(rig.fovs, [c["fov"] for c in data["cameras"]])


# --- frame conversion -----------------------------------------------------------------------------------


def test_file_location_y_right_becomes_iso_y_left():
    rig = rig_from_dict({"vehicle_type": "v", "cameras": [_minimal_camera(location=[1.09, 0.99, 0.72])]}, "r")
    np.testing.assert_array_equal(rig.cameras[0].position, [1.09, -0.99, 0.72])


def test_file_yaw_plus_90_looks_right_which_is_iso_minus_y():
    rig = rig_from_dict({"vehicle_type": "v", "cameras": [_minimal_camera(rotation=[0.0, 90.0, 0.0])]}, "r")
    np.testing.assert_allclose(rig.cameras[0].forward, [0.0, -1.0, 0.0], atol=1e-15)


def test_file_pitch_plus_looks_up():
    rig = rig_from_dict({"vehicle_type": "v", "cameras": [_minimal_camera(rotation=[18.0, 0.0, 0.0])]}, "r")
    forward = rig.cameras[0].forward
    np.testing.assert_allclose(forward, [math.cos(math.radians(18)), 0.0, math.sin(math.radians(18))], atol=1e-15)


def test_name_defaults_to_the_file_stem_and_can_be_given(tmp_path):
    path = tmp_path / "my_rig.json"
    path.write_text(json.dumps({"vehicle_type": "v", "cameras": [_minimal_camera()]}))
    assert read_rig(path).name == "my_rig"
    assert read_rig(path, name="other").name == "other"
    assert read_rig(str(path)).name == "my_rig"


def test_lidar_key_is_ignored():
    with_lidar = {"vehicle_type": "v", "cameras": [_minimal_camera()],
                  "lidar": {"location": [0.0, 0.0, 2.0], "channels": 64, "whatever": [1, 2]}}
    without = {"vehicle_type": "v", "cameras": [_minimal_camera()]}
    assert rig_from_dict(with_lidar, "r").same_as(rig_from_dict(without, "r"))
    assert "lidar" not in rig_to_dict(rig_from_dict(with_lidar, "r"))


def test_image_size_and_zone_written_only_when_not_default(tmp_path):
    default = rig_from_dict({"vehicle_type": "v", "cameras": [_minimal_camera()]}, "r")
    assert set(rig_to_dict(default)["cameras"][0]) == {"id", "location", "rotation", "fov"}
    custom = rig_from_dict(
        {"vehicle_type": "v", "cameras": [_minimal_camera(image_size=[1920, 1080], zone="roof")]}, "r"
    )
    assert custom.cameras[0].image_size == (1920, 1080) and custom.cameras[0].zone == "roof"
    entry = rig_to_dict(custom)["cameras"][0]
    assert entry["image_size"] == [1920, 1080] and entry["zone"] == "roof"
    assert read_rig(write_rig(custom, tmp_path / "r.json")).same_as(custom, atol=1e-12)


def test_write_creates_parent_folders(tmp_path):
    rig = rig_from_dict({"vehicle_type": "v", "cameras": [_minimal_camera()]}, "deep")
    path = write_rig(rig, tmp_path / "a" / "b" / "deep.json")
    assert path.is_file() and read_rig(path).same_as(rig, atol=1e-12)


_unit = st.floats(0.0, 1.0)


@st.composite
def _random_rigs(draw):
    """Rigs of random cameras, positions rounded like a file would hold them (9 decimals)."""
    cameras = []
    for k in range(draw(st.integers(1, 6))):
        u1, u2, u3 = draw(st.tuples(_unit, _unit, _unit))
        q = [math.sqrt(1 - u1) * math.sin(2 * math.pi * u2), math.sqrt(1 - u1) * math.cos(2 * math.pi * u2),
             math.sqrt(u1) * math.sin(2 * math.pi * u3), math.sqrt(u1) * math.cos(2 * math.pi * u3)]
        rotation = quaternion_to_matrix(q)
        position = np.round(draw(st.tuples(*[st.floats(-5.0, 5.0)] * 3)), 9)
        cameras.append(Camera.pinhole(f"CAM_{k}", position, rotation, draw(st.floats(30.0, 150.0))))
    return Rig("random", "vehicle.test", tuple(cameras))


@settings(max_examples=50, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rig=_random_rigs())
def test_random_rig_write_read_round_trip(tmp_path, rig):
    # away from gimbal lock, where yaw and roll are ill-conditioned
    assume(all(math.hypot(r[0, 0], r[1, 0]) > 1e-6 for r in rig.rotations))
    back = read_rig(write_rig(rig, tmp_path / "random.json"))
    assert back.same_as(rig, atol=1e-9)


# --- bad input ------------------------------------------------------------------------------------------

_CAMERA = json.dumps(_minimal_camera())

BAD_FILES = {
    "malformed JSON": '{"vehicle_type": "v", "cameras": [' + _CAMERA,
    "empty file": "",
    "top level is a list": "[" + _CAMERA + "]",
    "missing cameras": '{"vehicle_type": "v"}',
    "missing vehicle_type": '{"cameras": [' + _CAMERA + "]}",
    "vehicle_type not a string": '{"vehicle_type": 3, "cameras": [' + _CAMERA + "]}",
    "empty vehicle_type": '{"vehicle_type": "", "cameras": [' + _CAMERA + "]}",
    "empty cameras": '{"vehicle_type": "v", "cameras": []}',
    "cameras not a list": '{"vehicle_type": "v", "cameras": ' + _CAMERA + "}",
    "camera not an object": '{"vehicle_type": "v", "cameras": [[1, 2, 3]]}',
    "camera missing fov": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, 0, 0]}]}',
    "camera missing id": '{"vehicle_type": "v", "cameras": [{"location": [0, 0, 1], "rotation": [0, 0, 0], "fov": 60}]}',
    "camera missing location": '{"vehicle_type": "v", "cameras": [{"id": "C", "rotation": [0, 0, 0], "fov": 60}]}',
    "camera missing rotation": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "fov": 60}]}',
    "NaN location": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [NaN, 0, 1], "rotation": [0, 0, 0], "fov": 60}]}',
    "NaN rotation": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, NaN, 0], "fov": 60}]}',
    "NaN fov": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, 0, 0], "fov": NaN}]}',
    "Infinity location": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, Infinity, 1], "rotation": [0, 0, 0], "fov": 60}]}',
    "-Infinity rotation": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [-Infinity, 0, 0], "fov": 60}]}',
    "Infinity fov": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, 0, 0], "fov": Infinity}]}',
    "overflowing number": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [1e999, 0, 1], "rotation": [0, 0, 0], "fov": 60}]}',
    "string in location": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": ["1.0", 0, 1], "rotation": [0, 0, 0], "fov": 60}]}',
    "string in rotation": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, "90", 0], "fov": 60}]}',
    "string fov": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, 0, 0], "fov": "60"}]}',
    "null fov": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, 0, 0], "fov": null}]}',
    "location of length 2": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 1], "rotation": [0, 0, 0], "fov": 60}]}',
    "rotation of length 4": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, 0, 0, 0], "fov": 60}]}',
    "location a number": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": 1, "rotation": [0, 0, 0], "fov": 60}]}',
    "nested location": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [[0], [0], [1]], "rotation": [0, 0, 0], "fov": 60}]}',
    "boolean in location": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [true, 0, 1], "rotation": [0, 0, 0], "fov": 60}]}',
    "boolean in rotation": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, false, 0], "fov": 60}]}',
    "boolean fov": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, 0, 0], "fov": true}]}',
    "fov 0": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, 0, 0], "fov": 0}]}',
    "fov 180": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, 0, 0], "fov": 180}]}',
    "empty id": '{"vehicle_type": "v", "cameras": [{"id": "", "location": [0, 0, 1], "rotation": [0, 0, 0], "fov": 60}]}',
    "duplicate ids": '{"vehicle_type": "v", "cameras": [' + _CAMERA + ", " + _CAMERA + "]}",
    "image_size of one value": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, 0, 0], "fov": 60, "image_size": [1280]}]}',
    "image_size zero": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, 0, 0], "fov": 60, "image_size": [0, 720]}]}',
    "image_size floats": '{"vehicle_type": "v", "cameras": [{"id": "C", "location": [0, 0, 1], "rotation": [0, 0, 0], "fov": 60, "image_size": [1280.5, 720]}]}',
}


@pytest.mark.parametrize("text", list(BAD_FILES.values()), ids=list(BAD_FILES))
def test_bad_file_raises_rig_file_error_naming_the_path(tmp_path, text):
    path = _write_text(tmp_path, text)
    with pytest.raises(RigFileError) as caught:
        read_rig(path)
    assert str(path) in str(caught.value)


def test_missing_file_raises_rig_file_error_naming_the_path(tmp_path):
    path = tmp_path / "absent.json"
    with pytest.raises(RigFileError) as caught:
        read_rig(path)
    assert str(path) in str(caught.value)


def test_bad_camera_error_names_the_camera(tmp_path):
    text = ('{"vehicle_type": "v", "cameras": [' + _CAMERA + ', {"id": "CAM_REAR", "location": [0, 0], '
            '"rotation": [0, 0, 0], "fov": 60}]}')
    with pytest.raises(RigFileError, match="CAM_REAR"):
        read_rig(_write_text(tmp_path, text))


def test_rig_from_dict_names_its_source():
    with pytest.raises(RigFileError, match="^somewhere.json: "):
        rig_from_dict({"vehicle_type": "v", "cameras": []}, "r", source="somewhere.json")
    with pytest.raises(RigFileError, match="^somewhere.json: "):
        rig_from_dict({"vehicle_type": "v", "cameras": [_minimal_camera(fov=0)]}, "r", source="somewhere.json")
