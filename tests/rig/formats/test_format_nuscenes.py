"""nuScenes calibration tables: frames, lenses, record selection, round trip and input errors."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rigopt.errors import RigFileError
from rigopt.rig.library import load_rig
from rigopt.rig.formats.nuscenes import read_nuscenes, write_nuscenes_calibration


def read_nuscenes_rig(directory, **options):
    return read_nuscenes(directory, **options).rig

H = math.sqrt(0.5)
#: R_ego_optical = [[0, 0, 1], [-1, 0, 0], [0, -1, 0]]: optical z along ego +x (a front camera).
Q_FRONT = [0.5, -0.5, 0.5, -0.5]
#: R_ego_optical = [[1, 0, 0], [0, 0, 1], [0, -1, 0]] = Rx(-90 deg): optical z along ego +y, x along ego +x.
Q_LEFT = [H, -H, 0.0, 0.0]
FOCAL = 1266.417


def intrinsic(focal=FOCAL, cx=800.0, cy=450.0):
    return [[focal, 0.0, cx], [0.0, focal, cy], [0.0, 0.0, 1.0]]


def sensor(channel, modality="camera"):
    return {"token": f"s-{channel}", "channel": channel, "modality": modality}


def record(channel, translation=(1.7, 0.0, 1.5), rotation=Q_FRONT, camera_intrinsic=None, token=None):
    return {
        "token": token or f"c-{channel}",
        "sensor_token": f"s-{channel}",
        "translation": list(translation),
        "rotation": list(rotation),
        "camera_intrinsic": intrinsic() if camera_intrinsic is None else camera_intrinsic,
    }


def write_tables(directory, sensors, records):
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "sensor.json").write_text(json.dumps(sensors))
    (directory / "calibrated_sensor.json").write_text(json.dumps(records))
    return directory


def front_tables(tmp_path, **fields):
    return write_tables(tmp_path / "v1.0-mini", [sensor("CAM_FRONT")], [record("CAM_FRONT", **fields)])


def test_front_optical_frame_gives_identity_body_rotation(tmp_path):
    camera = read_nuscenes_rig(front_tables(tmp_path, translation=(1.7, 0.02, 1.5))).cameras[0]
    np.testing.assert_allclose(camera.rotation, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(camera.forward, [1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(camera.position, [1.7, 0.02, 1.5], atol=0)


def test_optical_axis_along_ego_y_is_a_camera_looking_left(tmp_path):
    camera = read_nuscenes_rig(front_tables(tmp_path, rotation=Q_LEFT)).cameras[0]
    yaw_90 = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]  # Rz(+90 deg): x -> +y, y -> -x, z up
    np.testing.assert_allclose(camera.rotation, yaw_90, atol=1e-12)
    np.testing.assert_allclose(camera.forward, [0.0, 1.0, 0.0], atol=1e-12)


def test_near_unit_quaternion_is_normalised(tmp_path):
    camera = read_nuscenes_rig(front_tables(tmp_path, rotation=[1.0005 * q for q in Q_FRONT])).cameras[0]
    np.testing.assert_allclose(camera.rotation, np.eye(3), atol=1e-12)


def test_fov_comes_from_the_intrinsics_and_the_image_width(tmp_path):
    directory = front_tables(tmp_path, camera_intrinsic=intrinsic(cx=816.27, cy=491.5))
    camera = read_nuscenes_rig(directory).cameras[0]
    expected = math.degrees(math.atan(816.27 / 1266.417) + math.atan((1600 - 816.27) / 1266.417))
    assert camera.fov == pytest.approx(expected, abs=1e-9)
    assert camera.image_size == (1600, 900) and camera.lens.cx == 816.27
    narrow = read_nuscenes_rig(front_tables(tmp_path), image_size=(1280, 720)).cameras[0]
    expected = math.degrees(math.atan(800.0 / 1266.417) + math.atan(480.0 / 1266.417))  # cx 800 of 1280
    assert narrow.fov == pytest.approx(expected, abs=1e-9)
    assert narrow.image_size == (1280, 720)


def test_names_default_to_the_folder_and_can_be_given(tmp_path):
    directory = front_tables(tmp_path)
    rig = read_nuscenes_rig(directory)
    assert (rig.name, rig.vehicle, [c.id for c in rig.cameras]) == ("v1.0-mini", "nuscenes", ["CAM_FRONT"])
    rig = read_nuscenes_rig(directory, name="mini", vehicle="renault.zoe")
    assert (rig.name, rig.vehicle) == ("mini", "renault.zoe")


def test_library_rig_round_trips(tmp_path):
    rig = load_rig("R1")
    back = read_nuscenes_rig(write_nuscenes_calibration(rig, tmp_path / "r1"), image_size=rig.cameras[0].image_size)
    assert back.origin.kind == "rear_axle"
    assert [c.id for c in back.cameras] == [c.id for c in rig.cameras]
    np.testing.assert_allclose(back.positions, rig.positions, atol=1e-9, rtol=0)
    np.testing.assert_allclose(back.rotations, rig.rotations, atol=1e-9, rtol=0)
    np.testing.assert_allclose(back.fovs, rig.fovs, atol=1e-9, rtol=0)


def test_writer_is_deterministic_and_uses_a_centred_intrinsic(tmp_path):
    rig = load_rig("R1")
    a = write_nuscenes_calibration(rig, tmp_path / "a", image_size=(1600, 900))
    b = write_nuscenes_calibration(rig, tmp_path / "b", image_size=(1600, 900))
    for table in ("sensor.json", "calibrated_sensor.json"):
        assert (a / table).read_text() == (b / table).read_text()
    records = json.loads((a / "calibrated_sensor.json").read_text())
    assert len({r["token"] for r in records}) == len(rig)
    assert all(r["camera_intrinsic"][0][2] == 800.0 and r["camera_intrinsic"][1][2] == 450.0 for r in records)


def test_lidar_and_radar_channels_are_ignored(tmp_path):
    sensors = [sensor("LIDAR_TOP", "lidar"), sensor("CAM_FRONT"), sensor("RADAR_FRONT", "radar")]
    records = [record("LIDAR_TOP", camera_intrinsic=[]), record("CAM_FRONT"), record("RADAR_FRONT", rotation=[0] * 4)]
    rig = read_nuscenes_rig(write_tables(tmp_path / "t", sensors, records))
    assert [c.id for c in rig.cameras] == ["CAM_FRONT"]


def test_cameras_follow_the_sensor_table_order(tmp_path):
    channels = ["CAM_FRONT", "CAM_BACK", "CAM_FRONT_LEFT"]
    records = [record(c) for c in reversed(channels)]
    rig = read_nuscenes_rig(write_tables(tmp_path / "t", [sensor(c) for c in channels], records))
    assert [c.id for c in rig.cameras] == channels


def two_logs(tmp_path, **second):
    records = [record("CAM_FRONT", token="c1"), record("CAM_FRONT", token="c2", **second)]
    return write_tables(tmp_path / "t", [sensor("CAM_FRONT")], records)


def test_identical_records_of_a_channel_are_accepted(tmp_path):
    rig = read_nuscenes_rig(two_logs(tmp_path, translation=(1.7, 0.0, 1.5 + 1e-9)))
    np.testing.assert_allclose(rig.cameras[0].position, [1.7, 0.0, 1.5], atol=1e-8)


@pytest.mark.parametrize(
    "second",
    [{"translation": (1.7, 0.0, 1.5 + 1e-5)}, {"rotation": Q_LEFT}, {"camera_intrinsic": intrinsic(FOCAL + 1e-4)}],
    ids=["translation", "rotation", "focal"],
)
def test_records_differing_in_any_field_are_different_calibrations(tmp_path, second):
    with pytest.raises(RigFileError, match=r"holds 2 distinct calibrations"):
        read_nuscenes_rig(two_logs(tmp_path, **second))


def test_differing_records_need_a_calibration_choice(tmp_path):
    directory = two_logs(tmp_path, translation=(1.6, 0.0, 1.5))
    with pytest.raises(RigFileError, match=r"holds 2 distinct calibrations.*--calibration K"):
        read_nuscenes_rig(directory)
    np.testing.assert_allclose(read_nuscenes_rig(directory, calibration=0).cameras[0].position, [1.7, 0.0, 1.5])
    np.testing.assert_allclose(read_nuscenes_rig(directory, calibration=1).cameras[0].position, [1.6, 0.0, 1.5])
    with pytest.raises(RigFileError, match=r"--calibration 2 is out of range.*0\.\.1"):
        read_nuscenes_rig(directory, calibration=2)
    with pytest.raises(RigFileError, match=r"--calibration -1 is out of range"):
        read_nuscenes_rig(directory, calibration=-1)


def test_repeated_identical_records_pair_with_a_channel_of_two(tmp_path):
    records = [record("CAM_FRONT", token="c1"), record("CAM_FRONT", token="c2", translation=(1.6, 0.0, 1.5)),
               record("CAM_BACK", token="b1")]
    directory = write_tables(tmp_path / "t", [sensor("CAM_FRONT"), sensor("CAM_BACK")], records)
    rig = read_nuscenes_rig(directory, calibration=1)
    np.testing.assert_allclose(rig.cameras[0].position, [1.6, 0.0, 1.5])
    assert rig.cameras[1].id == "CAM_BACK"


BAD_RECORDS = [
    ({"translation": [1.0, float("nan"), 1.5]}, r"calibrated_sensor\.json: record 0 \(CAM_FRONT\) 'translation'.*NaN"),
    ({"translation": [1.0, 1.5]}, r"'translation'.*shape \(3,\)"),
    ({"translation": [1.0, "0", 1.5]}, r"'translation'.*expected numbers"),
    ({"rotation": [0.0, 0.0, 0.0, 0.0]}, r"'rotation'.*must be a unit quaternion.*norm is 0"),
    ({"rotation": [1.1, 0.0, 0.0, 0.0]}, r"'rotation'.*must be a unit quaternion.*norm is 1\.1"),
    ({"rotation": [1.0, 0.0, float("inf"), 0.0]}, r"'rotation'.*NaN or inf"),
    ({"camera_intrinsic": []}, r"'camera_intrinsic' 3x3 matrix.*shape \(3, 3\)"),
    ({"camera_intrinsic": [[1266.4, 0.0, 800.0], [0.0, 1266.4, 450.0]]}, r"'camera_intrinsic'.*shape \(3, 3\)"),
    ({"camera_intrinsic": intrinsic(focal=0.0)}, r"'camera_intrinsic' focal lengths.*must be positive"),
    ({"camera_intrinsic": intrinsic(focal=-1266.4)}, r"'camera_intrinsic' focal lengths.*must be positive"),
]


@pytest.mark.parametrize(("fields", "message"), BAD_RECORDS)
def test_bad_camera_records_are_rejected(tmp_path, fields, message):
    with pytest.raises(RigFileError, match=message):
        read_nuscenes_rig(front_tables(tmp_path, **fields))


@pytest.mark.parametrize("key", ["translation", "rotation", "camera_intrinsic", "sensor_token"])
def test_missing_record_keys_are_rejected(tmp_path, key):
    bad = record("CAM_FRONT")
    del bad[key]
    directory = write_tables(tmp_path / "t", [sensor("CAM_FRONT")], [bad])
    with pytest.raises(RigFileError, match=rf"calibrated_sensor\.json: record 0.*missing \['{key}'\]"):
        read_nuscenes_rig(directory)


def test_missing_sensor_keys_are_rejected(tmp_path):
    directory = write_tables(tmp_path / "t", [{"token": "s-CAM_FRONT", "channel": "CAM_FRONT"}], [record("CAM_FRONT")])
    with pytest.raises(RigFileError, match=r"sensor\.json: record 0 is missing \['modality'\]"):
        read_nuscenes_rig(directory)


@pytest.mark.parametrize("table", ["sensor.json", "calibrated_sensor.json"])
def test_missing_and_invalid_tables_are_rejected(tmp_path, table):
    directory = front_tables(tmp_path)
    (directory / table).write_text("[{")
    with pytest.raises(RigFileError, match=rf"{table}: not valid JSON"):
        read_nuscenes_rig(directory)
    (directory / table).write_text('{"token": "x"}')
    with pytest.raises(RigFileError, match=rf"{table}: a nuScenes table must be a JSON list"):
        read_nuscenes_rig(directory)
    (directory / table).unlink()
    with pytest.raises(RigFileError, match=rf"{table}: no such nuScenes table file"):
        read_nuscenes_rig(directory)
    (directory / table).mkdir()
    with pytest.raises(RigFileError, match=rf"{table} is a folder; give the nuScenes table file itself"):
        read_nuscenes_rig(directory)


def test_missing_directory_is_rejected(tmp_path):
    with pytest.raises(RigFileError, match=r"nowhere: no such folder; give the folder holding the nuScenes tables"):
        read_nuscenes_rig(tmp_path / "nowhere")
    (tmp_path / "sensor.json").write_text("[]")
    with pytest.raises(RigFileError, match=r"sensor\.json is a file; give the folder holding the nuScenes tables"):
        read_nuscenes_rig(tmp_path / "sensor.json")


def test_tables_without_cameras_are_rejected(tmp_path):
    directory = write_tables(tmp_path / "t", [sensor("LIDAR_TOP", "lidar")], [record("LIDAR_TOP")])
    with pytest.raises(RigFileError, match=r"sensor\.json: no sensor has modality 'camera'"):
        read_nuscenes_rig(directory)


def test_camera_channel_without_record_is_rejected(tmp_path):
    directory = write_tables(tmp_path / "t", [sensor("CAM_FRONT"), sensor("CAM_BACK")], [record("CAM_FRONT")])
    with pytest.raises(RigFileError, match=r"camera channel CAM_BACK has no record"):
        read_nuscenes_rig(directory)


def test_record_of_an_unknown_sensor_is_rejected(tmp_path):
    directory = write_tables(tmp_path / "t", [sensor("CAM_FRONT")], [record("CAM_FRONT"), record("CAM_BACK")])
    with pytest.raises(RigFileError, match=r"record 1 refers to sensor_token 's-CAM_BACK'"):
        read_nuscenes_rig(directory)


@pytest.mark.parametrize("size", [(1600,), (0, 900), (1600.0, 900), "1600x900", (True, 900), (1600, 900, 3)])
def test_bad_image_sizes_are_rejected(tmp_path, size):
    with pytest.raises(RigFileError, match=r"image_size must be two positive integers"):
        read_nuscenes_rig(front_tables(tmp_path), image_size=size)
