"""Dataset calibration importers on small fixtures written from each format's documented layout and values:
frames (where each camera looks), lenses, image sizes, distinct calibrations, FOVs checked against values
computed here independently (scipy root finding on the distortion formulas), and origins."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.feather as feather
import pyarrow.parquet as parquet
import pytest
from scipy.optimize import brentq, fsolve

from rigopt.errors import RigFileError
from rigopt.rig.formats.datasets import read_argoverse2, read_dgp, read_waymo, waymo_calibrations
from rigopt.rig.formats.nuscenes import describe_calibrations, nuscenes_calibrations, read_nuscenes
from rigopt.rig.formats.opencv import read_camchain
from rigopt.rig.model import RigOrigin

FIXTURES = Path(__file__).resolve().parents[2] / "fixtures" / "formats"


# ------------------------------------------------------------------------- independent FOV of a lens


def edge_angle(lens, u: float, v: float) -> float:
    """Angle (rad) from the optical axis of the ray through pixel (u, v), solved here from the formulas."""
    xd, yd = (u - lens.cx) / lens.fx, (v - lens.cy) / lens.fy
    k = lens.coefficients
    if lens.distortion == "fisheye":
        r = math.hypot(xd, yd)
        def f(t):
            return t * (1 + k[0] * t**2 + k[1] * t**4 + k[2] * t**6 + k[3] * t**8) - r

        top = 0.01
        while f(top) < 0:  # the first bracket from the axis out
            top += 0.01
        return brentq(f, 0.0, top)
    if lens.distortion == "radtan":
        k1, k2, p1, p2, k3 = k

        def residual(p):
            x, y = p
            r2 = x * x + y * y
            radial = 1 + k1 * r2 + k2 * r2**2 + k3 * r2**3
            return [x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x) - xd,
                    y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y - yd]

        x, y = fsolve(residual, [xd, yd], xtol=1e-12)
        return math.atan(math.hypot(x, y))
    return math.atan(math.hypot(xd, yd))


def independent_hfov(lens) -> float:
    return math.degrees(edge_angle(lens, 0.0, lens.cy) + edge_angle(lens, lens.width, lens.cy))


def assert_fovs_derive_from_lenses(rig):
    for camera in rig.cameras:
        lens = camera.lens
        assert camera.fov == pytest.approx(independent_hfov(lens), abs=0.5), camera.id
        assert camera.image_size == lens.image_size


# ------------------------------------------------------------------------------------------- nuScenes


NUSCENES = FIXTURES / "nuscenes_two_logs"


def test_nuscenes_two_logs_are_two_distinct_calibrations():
    calibrations = nuscenes_calibrations(NUSCENES)
    rows = describe_calibrations(calibrations)
    assert [r["calibration"] for r in rows] == [0, 1]
    assert rows[0]["logs"] == ["n015-2018-07-24-11-22-45+0800", "n015-2018-10-08-15-36-50+0800"]  # same values
    assert rows[1]["logs"] == ["n008-2018-08-01-15-16-36-0400"]
    assert rows[0]["vehicles"] == ["n015"] and rows[1]["vehicles"] == ["n008"]
    assert rows[0]["cameras"] == ["CAM_FRONT", "CAM_BACK", "CAM_FRONT_LEFT"]


def test_nuscenes_choice_by_log_scene_or_calibration_agree():
    by_log = read_nuscenes(NUSCENES, log="n008-2018-08-01-15-16-36-0400").rig
    by_scene = read_nuscenes(NUSCENES, scene="scene-0103").rig
    by_index = read_nuscenes(NUSCENES, calibration=1).rig
    assert by_log.same_as(by_scene)
    assert all(a.same_as(b) for a, b in zip(by_log.cameras, by_index.cameras))
    assert by_log.name == "n008-2018-08-01-15-16-36-0400"
    np.testing.assert_allclose(by_log.cameras[0].position, [1.72200568478, 0.00475453292289, 1.49491291905])


def test_nuscenes_without_a_choice_lists_the_ways_to_choose():
    with pytest.raises(RigFileError, match=r"2 distinct calibrations; choose one with --calibration K, --log"):
        read_nuscenes(NUSCENES)
    with pytest.raises(RigFileError, match=r"--calibration 2 is out of range.*0\.\.1"):
        read_nuscenes(NUSCENES, calibration=2)
    with pytest.raises(RigFileError, match=r"--log 'nowhere' names no log"):
        read_nuscenes(NUSCENES, log="nowhere")


def test_nuscenes_lenses_frames_and_origin():
    imported = read_nuscenes(NUSCENES, calibration=0)
    rig = imported.rig
    assert imported.notes[0] == "origin: rear axle (nuScenes ego frame)"
    assert rig.origin.kind == "rear_axle" and rig.vehicle == "nuscenes"
    front, back, left = rig.cameras
    assert front.forward[0] > 0.99 and back.forward[0] < -0.99 and left.forward[1] > 0.5
    assert front.image_size == (1600, 900)  # from sample_data
    lens = front.lens
    assert (lens.fx, lens.cx, lens.cy, lens.distortion) == (1266.417203046554, 816.2670197447984,
                                                            491.50706579294757, "none")
    expected = math.degrees(math.atan(816.2670197447984 / 1266.417203046554)
                            + math.atan((1600 - 816.2670197447984) / 1266.417203046554))
    assert front.fov == pytest.approx(expected, abs=1e-9)
    assert_fovs_derive_from_lenses(rig)


# ---------------------------------------------------------------------------------------- Argoverse 2


AV2_POSES = {  # the documented example (sensor.md of the av2 API): qw, qx, qy, qz, tx_m, ty_m, tz_m
    "ring_front_center": (0.502809, -0.499689, 0.500147, -0.497340, 1.631216, -0.000779, 1.432780),
    "ring_front_left": (0.635526, -0.671957, 0.275463, -0.262107, 1.550015, 0.197539, 1.431329),
    "ring_front_right": (0.264354, -0.278344, 0.671740, -0.633567, 1.554057, -0.194171, 1.430575),
    "ring_rear_left": (0.600598, -0.603227, -0.371096, 0.371061, 1.104117, 0.124369, 1.446070),
    "ring_rear_right": (-0.368149, 0.369885, 0.603626, -0.602733, 1.103432, -0.128317, 1.428135),
    "ring_side_left": (0.684152, -0.724938, -0.058345, 0.054735, 1.310427, 0.267904, 1.433233),
    "ring_side_right": (-0.053810, 0.056105, 0.727113, -0.682103, 1.310236, -0.273345, 1.435529),
    "stereo_front_left": (0.500421, -0.499934, 0.501241, -0.498399, 1.625085, 0.248148, 1.222831),
    "stereo_front_right": (0.500885, -0.503584, 0.498793, -0.496713, 1.633076, -0.250872, 1.222173),
    "up_lidar": (0.999996, 0.000000, 0.000000, -0.002848, 1.350180, 0.000000, 1.640420),
}
AV2_FOCAL = {"ring_front_center": 1773.504272, "ring_front_left": 1682.010713, "ring_front_right": 1684.834479,
             "ring_rear_left": 1686.494558, "ring_rear_right": 1683.375120, "ring_side_left": 1684.902403,
             "ring_side_right": 1682.936559, "stereo_front_left": 1685.825885, "stereo_front_right": 1683.137591}


@pytest.fixture(scope="module")
def av2_log(tmp_path_factory):
    log = tmp_path_factory.mktemp("av2") / "54bc6dbc-ebfb-3fba-b5b3-57f88b4b79ca"
    (log / "calibration").mkdir(parents=True)
    names = list(AV2_POSES)
    columns = list(zip(*AV2_POSES.values()))
    feather.write_feather(pa.table({"sensor_name": names, **{c: list(v) for c, v in zip(
        ("qw", "qx", "qy", "qz", "tx_m", "ty_m", "tz_m"), columns)}}), log / "calibration" / "egovehicle_SE3_sensor.feather")
    cams = list(AV2_FOCAL)
    portrait = [c == "ring_front_center" for c in cams]
    feather.write_feather(pa.table({
        "sensor_name": cams, "fx_px": [AV2_FOCAL[c] for c in cams], "fy_px": [AV2_FOCAL[c] for c in cams],
        "cx_px": [775.826693 if p else 1024.5 for p in portrait], "cy_px": [1023.6 if p else 775.2 for p in portrait],
        "k1": [-0.245 if p else -0.262 for p in portrait], "k2": [-0.212167 if p else -0.136984 for p in portrait],
        "k3": [0.328694 if p else 0.209330 for p in portrait],
        "height_px": [2048 if p else 1550 for p in portrait], "width_px": [1550 if p else 2048 for p in portrait],
    }), log / "calibration" / "intrinsics.feather")
    return log


def test_argoverse2_ring_and_stereo_cameras(av2_log):
    imported = read_argoverse2(av2_log)
    rig = imported.rig
    assert [c.id for c in rig.cameras] == list(AV2_FOCAL)  # the lidar is skipped
    assert imported.notes[0].startswith("origin: rear axle (Argoverse 2 ego-vehicle frame); its origin is at the "
                                        "rear axle's height, so positions are raised by 0.35 m")
    assert "undistorted" in imported.notes[1]
    assert rig.name == av2_log.name and rig.vehicle == "argoverse2"
    cameras = {c.id: c for c in rig.cameras}
    assert cameras["ring_front_center"].image_size == (1550, 2048)  # portrait
    assert cameras["ring_front_left"].image_size == (2048, 1550)
    assert cameras["ring_front_center"].forward[0] > 0.999
    assert cameras["ring_side_left"].forward[1] > 0.95 and cameras["ring_side_right"].forward[1] < -0.95
    assert cameras["ring_rear_left"].forward[0] < -0.4 and cameras["ring_rear_left"].forward[1] > 0.4
    # the ego origin is at the rear axle's height; rigopt's rear-axle origin is on the ground below it
    np.testing.assert_allclose(cameras["stereo_front_left"].position, [1.625085, 0.248148, 1.222831 + 0.35])
    lens = cameras["ring_front_center"].lens
    assert lens.distortion == "none" and (lens.fx, lens.cx) == (1773.504272, 775.826693)  # undistorted imagery
    assert_fovs_derive_from_lenses(rig)
    assert cameras["ring_front_center"].fov < cameras["ring_front_left"].fov  # portrait: narrower horizontally
    assert read_argoverse2(av2_log / "calibration").rig.same_as(rig)
    as_given = read_argoverse2(av2_log, origin=RigOrigin("rear_axle")).rig  # --origin: positions taken as they are
    np.testing.assert_allclose(as_given.cameras[7].position, [1.625085, 0.248148, 1.222831])


def test_argoverse2_missing_column_names_the_file(av2_log, tmp_path):
    bad = tmp_path / "log" / "calibration"
    bad.mkdir(parents=True)
    (bad / "egovehicle_SE3_sensor.feather").write_bytes((av2_log / "calibration" / "egovehicle_SE3_sensor.feather")
                                                       .read_bytes())
    feather.write_feather(pa.table({"sensor_name": ["a"], "fx_px": [1.0]}), bad / "intrinsics.feather")
    with pytest.raises(RigFileError, match=r"intrinsics\.feather: the Argoverse 2 intrinsics table lacks columns"):
        read_argoverse2(bad.parent)
    (bad / "intrinsics.feather").write_text("not feather")
    with pytest.raises(RigFileError, match=r"intrinsics\.feather: not a readable"):
        read_argoverse2(bad.parent)


# ------------------------------------------------------------------------------------------------ DGP


DGP = FIXTURES / "dgp_scene"


def test_dgp_six_cameras_with_sizes_from_the_scene():
    imported = read_dgp(DGP)
    rig = imported.rig
    assert [c.id for c in rig.cameras] == ["CAMERA_01", "CAMERA_05", "CAMERA_06", "CAMERA_07", "CAMERA_08", "CAMERA_09"]
    assert imported.notes == ("origin: rear axle (DDAD ego frame)",  # the lidar datum is said to be left out
                              "LIDAR left out: no camera model (fx 0: a lidar or another sensor); give a camera its "
                              "intrinsics to import it")
    assert all(c.image_size == (1936, 1216) for c in rig.cameras)
    yaws = [math.degrees(math.atan2(c.forward[1], c.forward[0])) for c in rig.cameras]
    np.testing.assert_allclose(yaws, [0, 60, -60, 120, -120, 180], atol=1e-9)
    front, back = rig.cameras[0].lens, rig.cameras[5].lens
    assert front.distortion == "radtan" and front.coefficients == (-0.18, 0.094, 0.0002, -0.0001, 0.0)
    assert back.distortion == "fisheye" and back.coefficients == (0.05, -0.01, 0.002, -0.0003)
    assert_fovs_derive_from_lenses(rig)


def test_dgp_calibration_file_alone_takes_the_default_size(tmp_path):
    file = tmp_path / "alone" / "calibration" / "c.json"
    file.parent.mkdir(parents=True)
    file.write_text(next((DGP / "calibration").glob("*.json")).read_text())
    imported = read_dgp(file, image_size=(1920, 1200))
    assert all(c.image_size == (1920, 1200) for c in imported.rig.cameras)
    assert "image size 1920x1200 assumed" in imported.notes[1]


def test_dgp_rational_terms_are_refused(tmp_path):
    import json

    data = json.loads(next((DGP / "calibration").glob("*.json")).read_text())
    data["intrinsics"][0]["k4"] = 0.1
    bad = tmp_path / "calibration.json"
    bad.write_text(json.dumps(data))
    with pytest.raises(RigFileError, match=r"calibration\.json: datum 0 \(CAMERA_01\): the rational terms \['k4'\]"):
        read_dgp(bad)


# ---------------------------------------------------------------------------------------------- Waymo


W = "[CameraCalibrationComponent]."
WAYMO_POSES = {  # camera -> vehicle, camera frame x forward, y left, z up: yaw (deg) and position
    1: (0.0, (1.54, -0.02, 2.12)), 2: (45.0, (1.50, 0.09, 2.11)), 3: (-45.0, (1.49, -0.10, 2.12)),
    4: (90.0, (1.43, 0.11, 2.11)), 5: (-90.0, (1.43, -0.11, 2.11)),
}


def waymo_table(segments: dict[str, float]) -> pa.Table:
    """Rows for each segment: the five cameras, front 1920x1280, sides 1920x886; ``segments`` maps a segment
    name to an offset (m) added to x, so different offsets are different calibrations."""
    rows = {c: [] for c in ("key.segment_context_name", "key.camera_name", *(f"{W}intrinsic.{k}" for k in
            ("f_u", "f_v", "c_u", "c_v", "k1", "k2", "p1", "p2", "k3")), f"{W}extrinsic.transform", f"{W}width",
            f"{W}height", f"{W}rolling_shutter_direction")}
    for segment, dx in segments.items():
        for number, (yaw, (x, y, z)) in WAYMO_POSES.items():
            c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
            transform = [c, -s, 0.0, x + dx, s, c, 0.0, y, 0.0, 0.0, 1.0, z, 0.0, 0.0, 0.0, 1.0]
            side = number > 3
            values = {"f_u": 2059.6, "f_v": 2059.6, "c_u": 944.5, "c_v": 638.9 if not side else 440.1, "k1": 0.0436,
                      "k2": -0.3373, "p1": 0.0011, "p2": -0.0008, "k3": 0.0}
            rows["key.segment_context_name"].append(segment)
            rows["key.camera_name"].append(number)
            for key, value in values.items():
                rows[f"{W}intrinsic.{key}"].append(value)
            rows[f"{W}extrinsic.transform"].append(transform)
            rows[f"{W}width"].append(1920)
            rows[f"{W}height"].append(886 if side else 1280)
            rows[f"{W}rolling_shutter_direction"].append(2)
    return pa.table({k: pa.array(v, type=pa.int8() if k == "key.camera_name" else None) for k, v in rows.items()})


@pytest.fixture(scope="module")
def waymo_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("waymo") / "camera_calibration.parquet"
    parquet.write_table(waymo_table({"10023947602400723454_1120_000_1140_000": 0.0, "segment-b": 0.0,
                                     "segment-c": 0.05}), path)
    return path


def test_waymo_five_cameras_in_its_own_camera_frame(waymo_file):
    groups = waymo_calibrations(waymo_file)
    assert [g["segments"] for g in groups] == [["10023947602400723454_1120_000_1140_000", "segment-b"], ["segment-c"]]
    imported = read_waymo(waymo_file, segment="segment-c")
    rig = imported.rig
    assert imported.notes[0] == "origin: rear axle (Waymo vehicle frame)"
    assert [c.id for c in rig.cameras] == ["FRONT", "FRONT_LEFT", "FRONT_RIGHT", "SIDE_LEFT", "SIDE_RIGHT"]
    assert rig.cameras[0].image_size == (1920, 1280) and rig.cameras[3].image_size == (1920, 886)
    np.testing.assert_allclose(rig.cameras[0].rotation, np.eye(3), atol=1e-12)  # x forward: rigopt's body frame
    np.testing.assert_allclose(rig.cameras[3].forward, [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(rig.cameras[0].position, [1.59, -0.02, 2.12], atol=1e-12)
    assert rig.cameras[0].lens.coefficients == (0.0436, -0.3373, 0.0011, -0.0008, 0.0)
    assert_fovs_derive_from_lenses(rig)
    with pytest.raises(RigFileError, match=r"2 distinct calibrations"):
        read_waymo(waymo_file)
    assert read_waymo(waymo_file, calibration=0).rig.name == "10023947602400723454_1120_000_1140_000"


# --------------------------------------------------------------------------------------------- Kalibr


def test_kalibr_camchain_with_imu_frame_and_chain():
    imported = read_camchain(FIXTURES / "kalibr_camchain.yaml")
    cam0, cam1 = imported.rig.cameras
    assert (cam0.id, cam1.id) == ("cam0", "cam1")
    np.testing.assert_allclose(cam0.position, [1.9, 0.05, 1.45], atol=1e-12)
    np.testing.assert_allclose(cam0.rotation, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(cam1.position, [1.9, -0.25, 1.45], atol=1e-12)
    np.testing.assert_allclose(cam1.forward, [0, -1, 0], atol=1e-12)
    assert cam0.lens.distortion == "radtan" and cam0.lens.coefficients[4] == 0.0
    assert cam1.lens.distortion == "fisheye" and cam1.image_size == (512, 512)
    assert cam1.fov > 150.0  # a wide equidistant lens
    assert_fovs_derive_from_lenses(imported.rig)
    assert imported.rig.origin.kind == "vehicle_centre" and "assumed" in imported.notes[0]
