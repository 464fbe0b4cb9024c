"""Argoverse 1 import on a vehicle_calibration_info.json written from argoverse-api's documented example values
(its test data's log "1"): camera frames checked against scipy's reading of the quaternions, image sizes by
camera, pinhole and raw lenses (FOVs solved here from the formulas), the axle-height origin, bad files."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from console import run_console
from in_process import run_rigopt
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

from rigopt.errors import RigFileError, RigoptError
from rigopt.mounting.practice import as_modules
from rigopt.rig.formats.argoverse1 import AV1_AXLE_HEIGHT_M, read_argoverse1
from rigopt.rig.model import RigOrigin
from rigopt.rig.pccr_format import read_rig

LOG = Path(__file__).resolve().parents[2] / "fixtures" / "formats" / "argoverse1_log"
FILE = LOG / "vehicle_calibration_info.json"
RING = ["ring_front_center", "ring_front_left", "ring_front_right", "ring_rear_left", "ring_rear_right",
        "ring_side_left", "ring_side_right"]


def file_values() -> dict:
    """camera -> its camera_data_ value, straight from the fixture."""
    data = json.loads(FILE.read_text())
    return {entry["key"].removeprefix("image_raw_"): entry["value"] for entry in data["camera_data_"]}


def write_variant(tmp_path: Path, change) -> Path:
    """A copy of the fixture with ``change(data)`` applied; returns its log folder."""
    data = json.loads(FILE.read_text())
    change(data)
    folder = tmp_path / "log"
    folder.mkdir(exist_ok=True)
    (folder / "vehicle_calibration_info.json").write_text(json.dumps(data))
    return folder


def test_the_axle_height_is_the_tyre_radius_of_225_50r17():
    rim_radius_mm, sidewall_mm = 17 * 25.4 / 2, 0.50 * 225
    assert AV1_AXLE_HEIGHT_M == pytest.approx((rim_radius_mm + sidewall_mm) / 1000, abs=1e-12)
    assert 0.32 < AV1_AXLE_HEIGHT_M < 0.34  # argoverse-api issue #286: "around 33 cm above the ground"


def test_ring_cameras_frames_positions_and_notes():
    imported = read_argoverse1(LOG)
    rig = imported.rig
    assert [c.id for c in rig.cameras] == RING  # stereo left out, argoverse-api's camera order
    assert (rig.name, rig.vehicle, rig.origin) == ("argoverse1_log", "argoverse1", RigOrigin("rear_axle"))
    assert imported.notes[0].startswith("origin: rear axle (Argoverse 1 ego-vehicle frame); its origin is at the rear "
                                        "axle's height, so positions are raised by 0.328 m")
    assert "225/50R17" in imported.notes[0] and "--axle-height" in imported.notes[0]
    assert "undistorted" in imported.notes[1]
    assert imported.notes[2] == "stereo cameras left out: stereo_front_left, stereo_front_right (--cameras all keeps them)"
    assert "stereo_front_right_rect" in imported.notes[3]
    values = file_values()
    for camera in rig.cameras:
        value = values[camera.id]["vehicle_SE3_camera_"]
        r_ego_optical = Rotation.from_quat(value["rotation"]["coefficients"], scalar_first=True).as_matrix()
        # rigopt's body axes (x along the optical axis, y left, z up) are the optical frame's z, -x and -y
        np.testing.assert_allclose(camera.rotation[:, 0], r_ego_optical[:, 2], atol=1e-9, err_msg=camera.id)
        np.testing.assert_allclose(camera.rotation[:, 1], -r_ego_optical[:, 0], atol=1e-9, err_msg=camera.id)
        np.testing.assert_allclose(camera.rotation[:, 2], -r_ego_optical[:, 1], atol=1e-9, err_msg=camera.id)
        np.testing.assert_allclose(camera.position, np.add(value["translation"], [0, 0, AV1_AXLE_HEIGHT_M]),
                                   atol=1e-12)
        assert camera.image_size == (1920, 1200)
    cameras = {c.id: c for c in rig.cameras}
    assert cameras["ring_front_center"].forward[0] > 0.999
    assert cameras["ring_side_left"].forward[1] > 0.95 and cameras["ring_side_right"].forward[1] < -0.95
    assert cameras["ring_rear_left"].forward[0] < -0.4 and cameras["ring_rear_left"].forward[1] > 0.4
    assert 1.6 < cameras["ring_front_center"].position[2] < 1.75  # issue #286: the ring cameras ~1.68 m up


def test_pinhole_lenses_by_default():
    front = read_argoverse1(FILE).rig.cameras[0]
    value = file_values()["ring_front_center"]
    lens = front.lens
    assert lens.distortion == "none"
    assert (lens.fx, lens.fy, lens.cx, lens.cy) == (value["focal_length_x_px_"], value["focal_length_y_px_"],
                                                    value["focal_center_x_px_"], value["focal_center_y_px_"])
    expected = math.degrees(math.atan(lens.cx / lens.fx) + math.atan((1920 - lens.cx) / lens.fx))
    assert front.fov == pytest.approx(expected, abs=1e-9)


def test_all_cameras_keep_the_stereo_pair_but_never_rect():
    imported = read_argoverse1(LOG, cameras="all")
    ids = [c.id for c in imported.rig.cameras]
    assert ids == RING + ["stereo_front_left", "stereo_front_right"]
    assert all(c.image_size == (2464, 2056) for c in imported.rig.cameras[7:])
    assert not any("stereo cameras left out" in note for note in imported.notes)
    with pytest.raises(RigoptError, match=r"--cameras must be one of ring, all"):
        read_argoverse1(LOG, cameras="stereo")


def _radial_edge_angle(lens, u: float) -> float:
    """Angle (rad) off the axis of the ray through (u, cy) under x_d = x (1 + k1 x^2 + k2 x^4 + k3 x^6)."""
    k1, k2, _, _, k3 = lens.coefficients
    xd = abs(u - lens.cx) / lens.fx
    return math.atan(brentq(lambda x: x * (1 + k1 * x**2 + k2 * x**4 + k3 * x**6) - xd, 0.0, 2 * xd))


def test_raw_lenses_are_radtan_with_no_tangential_terms():
    imported = read_argoverse1(LOG, raw_lens=True, cameras="all")
    values = file_values()
    for camera in imported.rig.cameras:
        k1, k2, k3 = values[camera.id]["distortion_coefficients_"]
        lens = camera.lens
        assert lens.distortion == "radtan" and lens.coefficients == (k1, k2, 0.0, 0.0, k3)
        expected = math.degrees(_radial_edge_angle(lens, 0.0) + _radial_edge_angle(lens, lens.width))
        assert camera.fov == pytest.approx(expected, abs=1e-6), camera.id
    assert "radial distortion" in imported.notes[1]
    assert read_argoverse1(LOG).rig.cameras[0].fov < imported.rig.cameras[0].fov  # barrel distortion: wider


def test_axle_height_option_and_origin_override():
    given = file_values()["ring_front_center"]["vehicle_SE3_camera_"]["translation"]
    raised = read_argoverse1(LOG, axle_height=0.4)
    np.testing.assert_allclose(raised.rig.cameras[0].position, np.add(given, [0, 0, 0.4]), atol=1e-12)
    assert "raised by 0.4 m to the ground below it (--axle-height)" in raised.notes[0]
    as_given = read_argoverse1(LOG, origin=RigOrigin("rear_axle"))
    np.testing.assert_allclose(as_given.rig.cameras[0].position, given, atol=1e-12)
    assert as_given.notes[0] == "origin: rear axle (--origin)"
    with pytest.raises(RigoptError, match=r"--axle-height .* with --origin .* give one of the two"):
        read_argoverse1(LOG, origin=RigOrigin("rear_axle"), axle_height=0.3)
    for bad in (-0.1, 2.5, float("nan")):
        with pytest.raises(RigoptError, match=r"--axle-height must be the rear axle's height"):
            read_argoverse1(LOG, axle_height=bad)


@pytest.mark.parametrize("change, message", [
    (lambda d: d.pop("camera_data_"), r"a JSON object with a 'camera_data_' list"),
    (lambda d: d["camera_data_"][0].update(key="image_raw_roof_camera"), r"camera_data_\[0\] \(image_raw_roof_camera\): "
                                                                         r"not an Argoverse 1 camera"),
    (lambda d: d["camera_data_"][2]["value"].update(skew_=1.5), r"skew_ 1.5 is not supported"),
    (lambda d: d["camera_data_"][2]["value"].pop("focal_center_y_px_"), r"ring_rear_left\): lacks focal_center_y_px_"),
    (lambda d: d["camera_data_"][2]["value"]["vehicle_SE3_camera_"]["rotation"].update(coefficients=[1, 1, 0, 0]),
     r"must be a unit quaternion"),
    (lambda d: d["camera_data_"][2]["value"].update(distortion_coefficients_=[0.1, 0.2]),
     r"distortion_coefficients_ \(k1, k2, k3\): expected numbers of shape \(3,\)"),
    (lambda d: d["camera_data_"].append(d["camera_data_"][2]), r"ring_rear_left is listed twice"),
    (lambda d: d.update(camera_data_=d["camera_data_"][:2]), r"lists none of the ring cameras"),
])
def test_bad_files_name_the_entry(tmp_path, change, message):
    with pytest.raises(RigFileError, match=message):
        read_argoverse1(write_variant(tmp_path, change))


def test_missing_or_broken_file(tmp_path):
    with pytest.raises(RigFileError, match=r"vehicle_calibration_info\.json: no such Argoverse 1 calibration file; "
                                           r"pass an Argoverse 1 log"):
        read_argoverse1(tmp_path)
    (tmp_path / "vehicle_calibration_info.json").write_text("{")
    with pytest.raises(RigFileError, match=r"not valid JSON"):
        read_argoverse1(tmp_path)


def test_import_command_writes_the_rig(tmp_path):
    out = tmp_path / "av1.json"
    result = run_rigopt("import", "argoverse1", LOG, "--out", out, "--cameras", "all", "--axle-height", "0.33")
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(f"wrote {out}: 9 cameras")
    assert "raised by 0.33 m" in result.stderr
    written, expected = read_rig(out, name="argoverse1_log"), read_argoverse1(LOG, cameras="all", axle_height=0.33).rig
    assert written.same_as(as_modules(expected), atol=1e-6)  # the rig file rounds its numbers
    assert "cameras closer than 0.25 m share one housing" in result.stderr  # the roof ring's, 0.2 m apart
    bad = run_rigopt("import", "argoverse1", LOG, "--out", tmp_path / "x.json", "--origin", "rear_axle",
                     "--axle-height", "0.3")
    assert bad.returncode == 2 and bad.stderr.startswith("rigopt: error: --axle-height")
    assert not (tmp_path / "x.json").exists()


def test_console_script_prints_json(tmp_path):
    out = tmp_path / "av1.json"
    done = run_console("import", "argoverse1", LOG, "--out", out, "--json", timeout=120)
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["source"] == "argoverse1" and summary["origin"] == "rear_axle"
    assert [c["id"] for c in summary["cameras"]] == RING
    assert summary["cameras"][0]["image_size"] == [1920, 1200]
