"""The dataset rigs of measurements/rigs/real: each committed rig file is what ``rigopt import`` makes of its source
folder (the commands of measurements/rigs/real/README.md), so neither can drift from the other; and the rigs
hold the datasets' documented camera sets and image sizes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from carla_convention import carla_rotate_vector
from in_process import run_rigopt

from rigopt.rig.pccr_format import read_rig

REAL = Path(__file__).resolve().parents[3] / "measurements" / "rigs" / "real"

#: dataset: (the import command's arguments after ``rigopt import``, {camera: (width, height)} as documented)
IMPORTS = {
    "nuscenes": (["nuscenes", "nuscenes", "--name", "nuscenes", "--vehicle", "tt"],
                 {c: (1600, 900) for c in ("CAM_FRONT", "CAM_FRONT_LEFT", "CAM_FRONT_RIGHT", "CAM_BACK",
                                           "CAM_BACK_LEFT", "CAM_BACK_RIGHT")}),
    "argoverse2": (["argoverse2", "argoverse2", "--name", "argoverse2", "--vehicle", "etron"],
                   {"ring_front_center": (1550, 2048),
                    **{f"ring_{c}": (2048, 1550) for c in ("front_left", "front_right", "rear_left", "rear_right",
                                                           "side_left", "side_right")}}),
    "waymo": (["waymo", "waymo", "--name", "waymo", "--vehicle", "etron"],
              {"FRONT": (1920, 1280), "FRONT_LEFT": (1920, 1280), "FRONT_RIGHT": (1920, 1280),
               "SIDE_LEFT": (1920, 886), "SIDE_RIGHT": (1920, 886)}),
    "ddad": (["dgp", "ddad", "--name", "ddad", "--vehicle", "etron"],
             {f"CAMERA_0{k}": (1936, 1216) for k in (1, 5, 6, 7, 8, 9)}),
}


@pytest.mark.parametrize("dataset", list(IMPORTS))
def test_committed_rig_is_the_import_of_its_source(dataset, tmp_path):
    args, sizes = IMPORTS[dataset]
    out = tmp_path / f"{dataset}.json"
    result = run_rigopt("import", *args, "--out", out, cwd=REAL)
    assert result.returncode == 0, result.stderr
    fresh, committed = read_rig(out), read_rig(REAL / f"{dataset}.json")
    assert [c.id for c in committed.cameras] == [c.id for c in fresh.cameras] == list(sizes)
    assert (committed.name, committed.vehicle, committed.origin.kind) == (fresh.name, fresh.vehicle, "rear_axle")
    for old, new in zip(committed.cameras, fresh.cameras):
        np.testing.assert_allclose(old.position, new.position, atol=1e-3, err_msg=old.id)
        np.testing.assert_allclose(old.rotation, new.rotation, atol=1e-6, err_msg=old.id)
        assert old.fov == pytest.approx(new.fov, abs=1e-6), old.id
        assert old.image_size == new.image_size == sizes[old.id]


def test_real_rigs_sit_on_the_roof_and_look_level():
    """Every camera of the four rigs is a roof camera (1.45-2.2 m up) looking within 5 deg of level."""
    for dataset in IMPORTS:
        for camera in read_rig(REAL / f"{dataset}.json").cameras:
            assert 1.45 < camera.position[2] < 2.2, (dataset, camera.id)
            assert abs(camera.forward[2]) < np.sin(np.radians(5.0)), (dataset, camera.id)


def quaternion(w, x, y, z) -> np.ndarray:
    """Scalar-first quaternion -> (3, 3) rotation, written out independently of rigopt."""
    n = np.linalg.norm([w, x, y, z])
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _raw_extrinsics() -> dict:
    """{dataset: {camera: R_ego_camera (3, 3)}} as the datasets' files give them (write_sources.py's values),
    the camera frame being x forward along the optical axis, y left, z up (Waymo's own; the optical frames of
    nuScenes and Argoverse 2 turned into it with the fixed optical-to-body matrix)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("write_sources", REAL / "write_sources.py")
    sources = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(sources)

    body_from_optical = sources.OPTICAL_IN_BODY
    return {
        "nuscenes": {c: quaternion(*q) @ body_from_optical.T for c, (_, q, _) in sources.NUSCENES.items()},
        "argoverse2": {c: quaternion(*pose[:4]) @ body_from_optical.T for c, pose in sources.AV2_POSES.items()},
        "waymo": {name: sources.yaw_matrix(yaw) for name, yaw, _, _ in sources.WAYMO_CAMERAS.values()},
        "ddad": {c: sources.yaw_matrix(yaw) for c, yaw in sources.DDAD_CAMERAS.items()},
    }


def _carla_export_matches(import_args, raw: dict, tmp_path, cwd=None) -> dict:
    """Run ``rigopt`` ``import_args`` into a rig file, export it as a CARLA spawn list, and check that CARLA's
    RotateVector of each camera's angles is its raw camera-to-ego rotation ``raw[id]`` (3, 3), taken to CARLA's
    y-right axes, to 1e-9. Returns the spawn list's rotations by camera."""
    import json

    rig_file, spawn_list = tmp_path / "rig.json", tmp_path / "spawn.json"
    result = run_rigopt(*import_args, "--out", rig_file, cwd=cwd)
    assert result.returncode == 0, result.stderr
    result = run_rigopt("export", rig_file, "--format", "carla", "--out", spawn_list)
    assert result.returncode == 0, result.stderr
    sensors = {s["id"]: s["transform"]["rotation"] for s in json.loads(spawn_list.read_text())["sensors"]}
    assert sorted(sensors) == sorted(raw)
    flip = np.diag([1.0, -1.0, 1.0])  # ISO (y left) <-> CARLA (y right), on the vehicle and on the camera
    for camera, r_ego_camera in raw.items():
        angles = sensors[camera]
        carla = carla_rotate_vector(angles["pitch"], angles["yaw"], angles["roll"])
        np.testing.assert_allclose(carla, flip @ r_ego_camera @ flip, rtol=0, atol=1e-9, err_msg=camera)
    return sensors


@pytest.mark.parametrize("dataset", list(IMPORTS))
def test_carla_export_of_an_imported_real_rig_reproduces_its_raw_extrinsics(dataset, tmp_path):
    """Import the raw calibration, export it as a CARLA spawn list, and rotate the camera's axes with CARLA's own
    formula: the result is the raw camera-to-ego rotation (taken to CARLA's y-right axes) to 1e-9."""

    args, _ = IMPORTS[dataset]
    sensors = _carla_export_matches(["import", *args], _raw_extrinsics()[dataset], tmp_path, cwd=REAL)
    if dataset in ("nuscenes", "argoverse2"):  # real calibrations: every camera has some roll
        assert max(abs(a["roll"]) for a in sensors.values()) > 0.1


def test_waymo_roof_cluster_is_one_camera_module():
    """Waymo's five cameras share one roof housing: imported as one module, they do not clash with each other."""
    rig = read_rig(REAL / "waymo.json")
    assert {c.module for c in rig.cameras} == {"roof_cluster"}
    assert all(c.module is None for c in read_rig(REAL / "nuscenes.json").cameras)  # 0.5-1.7 m apart


def test_carla_export_of_an_argoverse1_import_reproduces_its_raw_extrinsics(tmp_path):
    """The same check on the Argoverse 1 fixture (every camera, stereo included): vehicle_SE3_camera_'s
    scalar-first quaternion is the optical frame's rotation in the ego frame."""
    import json

    fixture = Path(__file__).resolve().parents[2] / "fixtures" / "formats" / "argoverse1_log"
    entries = json.loads((fixture / "vehicle_calibration_info.json").read_text())["camera_data_"]
    body_from_optical = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    raw = {}
    for entry in entries:
        name = entry["key"].removeprefix("image_raw_")
        if not name.endswith("_rect"):
            coefficients = entry["value"]["vehicle_SE3_camera_"]["rotation"]["coefficients"]
            raw[name] = quaternion(*coefficients) @ body_from_optical.T
    _carla_export_matches(["import", "argoverse1", fixture, "--cameras", "all"], raw, tmp_path)
