"""The rig JSON's optional real-lens and origin fields: written only when needed, read back exactly."""

import json
from dataclasses import replace

import numpy as np
import pytest

from rigopt.camera import Lens
from rigopt.errors import RigFileError
from rigopt.rig.library import load_rig
from rigopt.rig.model import Camera, Rig, RigOrigin
from rigopt.rig.pccr_format import rig_from_dict, rig_to_dict

RADTAN = Lens(1550, 2048, 1773.5, 1772.9, 775.2, 1024.6, "radtan", (-0.26, 0.09, 0.0004, -0.0002, -0.015))
FISHEYE = Lens(1920, 1080, 330.0, 331.0, 960.5, 540.0, "fisheye", (0.05, -0.01, 0.002, 0.0))


def real_rig(origin=RigOrigin("rear_axle")) -> Rig:
    return Rig("real", "nuscenes", (Camera("FRONT", [1.6, 0.0, 1.5], np.eye(3), RADTAN, "roof"),
                                    Camera("LEFT", [1.0, 0.9, 1.0], np.eye(3)[[1, 0, 2]] * [[1], [-1], [1]],
                                                     FISHEYE),
                                    Camera.pinhole("PIN", [0.0, 0.0, 1.8], np.eye(3), 70.0)), origin)


@pytest.mark.parametrize("origin", [RigOrigin("rear_axle"), RigOrigin("custom", (0.5, -0.2, 0.3)), RigOrigin()])
def test_real_lenses_and_origins_round_trip_exactly(origin):
    rig = real_rig(origin)
    back = rig_from_dict(json.loads(json.dumps(rig_to_dict(rig))), "real")
    assert back.same_as(rig)
    assert back.cameras[1].fov == pytest.approx(FISHEYE.hfov, abs=1e-8) and back.cameras[1].fov > 180


def test_the_benchmark_rigs_write_no_new_keys():
    data = rig_to_dict(load_rig("R1"))
    assert set(data) == {"vehicle_type", "cameras"}
    assert all(set(c) <= {"id", "location", "rotation", "fov", "zone"} for c in data["cameras"])


def test_a_lens_written_as_an_ideal_pinhole_is_the_benchmark_camera():
    derived = Lens.pinhole(65.0, (1280, 720))
    derived = Lens(1280, 720, derived.fx, derived.fy, derived.cx, derived.cy)  # the same lens, no stated FOV
    camera = Camera("C", [0, 0, 1], np.eye(3), derived)
    assert camera.lens == Lens.pinhole(derived.hfov, (1280, 720)) and camera.lens.stated_hfov == derived.hfov
    assert camera.fov == pytest.approx(65.0, abs=1e-9) and camera.lens.is_ideal_pinhole


def test_a_fov_that_disagrees_with_the_lens_is_refused():
    data = rig_to_dict(real_rig())
    data["cameras"][0]["fov"] = 60
    with pytest.raises(RigFileError, match="disagrees with its lens"):
        rig_from_dict(data, "bad", "bad.json")


@pytest.mark.parametrize("change, message", [
    (lambda c: c.update(distortion={"model": "radtan", "coefficients": [0.1]}), "coefficients"),
    (lambda c: c.update(distortion={"model": "division"}), "'distortion' must be"),
    (lambda c: c.pop("intrinsics"), "without 'intrinsics'"),
    (lambda c: c.update(intrinsics={"fx": 1000}), "fx, fy, cx, cy"),
])
def test_malformed_lens_fields_name_the_file_and_the_camera(change, message):
    data = rig_to_dict(real_rig())
    change(data["cameras"][0])
    with pytest.raises(RigFileError, match=message) as error:
        rig_from_dict(data, "bad", "bad.json")
    assert str(error.value).startswith("bad.json: camera 0 (FRONT)")


def test_an_unknown_origin_is_refused_with_the_accepted_forms():
    data = rig_to_dict(real_rig())
    data["origin"] = "front_axle"
    with pytest.raises(RigFileError, match="rear_axle"):
        rig_from_dict(data, "bad", "bad.json")


def test_camera_modules_round_trip_and_only_when_present():
    r1 = load_rig("R1")
    paired = Rig("paired", r1.vehicle, tuple(c if k > 1 else Camera(c.id, c.position, c.rotation, c.lens, c.zone,
                                                                     "front_pair")
                                             for k, c in enumerate(r1.cameras)))
    data = rig_to_dict(paired)
    assert [c.get("module") for c in data["cameras"]][:3] == ["front_pair", "front_pair", None]
    assert rig_from_dict(json.loads(json.dumps(data)), "paired").same_as(paired)
    assert not paired.same_as(r1)  # the module is part of a camera


@pytest.mark.parametrize("change, message", [
    ({"id": None}, "'id' must be a non-empty string"),
    ({"id": 7}, "'id' must be a non-empty string"),
    ({"id": "CAM\u001b[2J"}, "control characters"),
    ({"module": 4}, "module must be a non-empty string"),
    ({"location": [1.0e6, 0.0, 1.0]}, "more than 1000 m"),
])
def test_bad_camera_names_and_far_cameras_are_refused(change, message):
    data = rig_to_dict(load_rig("R1"))
    data["cameras"][0].update(change)
    with pytest.raises(RigFileError, match=message.replace("[", r"\[")):
        rig_from_dict(data, "bad", "bad.json")


def test_a_design_rig_file_says_its_frame_and_reads_back_the_same():
    """A design's rig.json keeps the benchmark's format and adds one sentence naming its frame; readers ignore it."""
    from rigopt.rig.pccr_format import frame_note

    rig = load_rig("R1")
    data = rig_to_dict(rig, say_frame=True)
    assert list(data) == ["vehicle_type", "frame", "cameras"]
    assert data["frame"] == frame_note(rig) and data["frame"].startswith("CARLA's vehicle frame: location [x forward, y right")
    assert "the vehicle's centre on the ground" in data["frame"]
    again = rig_from_dict(data, "R1", "R1.json")
    assert rig_to_dict(again) == rig_to_dict(rig)
    axle = replace(rig, origin=RigOrigin("rear_axle"))
    assert "below the rear axle's centre" in frame_note(axle).split(";")[0]
