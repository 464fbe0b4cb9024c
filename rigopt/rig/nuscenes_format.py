"""nuScenes calibration tables (``sensor.json``, ``calibrated_sensor.json``) read into and written from :class:`Rig`.

Conventions
-----------
Tables as in a nuScenes release folder (e.g. ``v1.0-mini/``)::

    sensor.json:            [{"token", "channel": "CAM_FRONT", "modality": "camera"}, ...]
    calibrated_sensor.json: [{"token", "sensor_token", "translation": [x, y, z],
                              "rotation": [w, x, y, z], "camera_intrinsic": [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]}, ...]

The ego frame is ISO 8855 (x forward, y left, z up), the same as rigopt's vehicle frame; ``translation``
is the lens centre in metres. ``rotation`` is a scalar-first unit quaternion for ``R_ego_optical``, which
maps the camera's optical frame (z forward, x right, y down) into the ego frame; rigopt's camera body
rotation is ``R_vehicle_cam = R_ego_optical @ R_CAM_OPTICAL.T``. Only ``modality == "camera"`` channels
become cameras; lidar and radar records are skipped unchecked. The horizontal FOV comes from ``fx`` and
the image width: rigopt assumes the ideal centred square-pixel pinhole, so ``cx``, ``cy`` and ``fy`` are
ignored (nuScenes principal points sit a few pixels off the centre). Camera ids are the channel names.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np

from rigopt.camera import fov_from_focal, intrinsic_matrix
from rigopt.errors import RigFileError, not_utf8
from rigopt.geometry import R_CAM_OPTICAL, matrix_to_quaternion, quaternion_to_matrix
from rigopt.rig.model import Camera, Rig

SENSOR_FILE = "sensor.json"
CALIBRATION_FILE = "calibrated_sensor.json"
#: nuScenes camera images, (width, height) in pixels.
NUSCENES_IMAGE_SIZE = (1600, 900)
#: A quaternion whose norm is further than this from 1 is rejected; closer ones are normalised.
QUATERNION_NORM_TOLERANCE = 1e-3
#: Two records of one channel are the same calibration when they agree within these tolerances
#: (translation metres, rotation-matrix entries, focal pixels).
SAME_TRANSLATION_M, SAME_ROTATION, SAME_FOCAL_PX = 1e-6, 1e-9, 1e-6


def read_nuscenes_rig(directory, image_size=NUSCENES_IMAGE_SIZE, index=None, name=None, vehicle="nuscenes") -> Rig:
    """Read the camera rig of a nuScenes table folder.

    Parameters
    ----------
    directory : path
        Folder holding ``sensor.json`` and ``calibrated_sensor.json`` (e.g. ``v1.0-mini/``).
    image_size : (int, int)
        ``(width, height)`` in pixels of every camera; the width turns ``fx`` into the horizontal FOV.
    index : int or None
        None: each camera channel's records must all hold the same calibration. K >= 0: take each
        channel's K-th record (0-based, in file order), for datasets whose logs were calibrated differently.
    name, vehicle : str
        The rig's name (default: the folder's name) and vehicle.

    Returns
    -------
    Rig
        One camera per camera channel, in the order the channels first appear in ``sensor.json``.
    """
    directory = Path(directory)
    if not directory.is_dir():
        raise RigFileError(f"{directory}: no such directory; pass the nuScenes table folder holding {SENSOR_FILE} "
                           f"and {CALIBRATION_FILE} (e.g. v1.0-mini/)")
    size = _image_size(image_size, directory)
    calibration_path = directory / CALIBRATION_FILE
    if index is not None and (isinstance(index, bool) or not isinstance(index, int) or index < 0):
        raise RigFileError(f"{calibration_path}: --index must be a non-negative integer, got {index!r}")
    sensor_path = directory / SENSOR_FILE
    sensors = _read_table(sensor_path, ("token", "channel", "modality"))
    records = _read_table(calibration_path, ("token", "sensor_token"))

    camera_channel = {s["token"]: s["channel"] for s in sensors if s["modality"] == "camera"}
    channels = list(dict.fromkeys(s["channel"] for s in sensors if s["modality"] == "camera"))
    if not channels:
        raise RigFileError(f"{sensor_path}: no sensor has modality 'camera'; a rig needs at least one camera channel")
    known = {s["token"] for s in sensors}
    poses = {channel: [] for channel in channels}
    for k, record in enumerate(records):
        if record["sensor_token"] not in known:
            raise RigFileError(f"{calibration_path}: record {k} refers to sensor_token {record['sensor_token']!r}, "
                               f"which {SENSOR_FILE} does not list; use the two tables of one release")
        channel = camera_channel.get(record["sensor_token"])
        if channel is not None:
            poses[channel].append(_camera_pose(record, f"{calibration_path}: record {k} ({channel})"))

    cameras = []
    for channel in channels:
        position, rotation, focal = _choose(channel, poses[channel], index, calibration_path)
        cameras.append(Camera(channel, position, rotation, float(fov_from_focal(focal, size[0])), size))
    return Rig(name or directory.resolve().name, vehicle, tuple(cameras))


def _image_size(image_size, directory: Path) -> tuple[int, int]:
    """``image_size`` checked as two positive integers ``(width, height)`` in pixels."""
    size = tuple(image_size) if isinstance(image_size, (list, tuple)) else ()
    if len(size) != 2 or not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v > 0
                                 for v in size):
        raise RigFileError(f"{directory}: image_size must be two positive integers (width, height) in pixels, "
                           f"got {image_size!r}")
    return int(size[0]), int(size[1])


def _read_table(path: Path, keys: tuple[str, ...]) -> list[dict]:
    """A nuScenes table: a JSON list of objects, each with the string-valued ``keys``."""
    try:
        text = path.read_text()
    except OSError as error:
        raise RigFileError(f"{path}: cannot read the nuScenes table ({error.strerror}); "
                           f"the folder needs {SENSOR_FILE} and {CALIBRATION_FILE}") from None
    except UnicodeDecodeError as error:
        raise not_utf8(path, "nuScenes table", error, RigFileError) from None
    try:
        table = json.loads(text)
    except json.JSONDecodeError as error:
        raise RigFileError(f"{path}: not valid JSON (line {error.lineno}, column {error.colno}: {error.msg})") from None
    if not isinstance(table, list):
        raise RigFileError(f"{path}: a nuScenes table must be a JSON list of records")
    for k, record in enumerate(table):
        if not isinstance(record, dict):
            raise RigFileError(f"{path}: record {k} must be a JSON object with keys {list(keys)}")
        missing = [key for key in keys if key not in record]
        if missing:
            raise RigFileError(f"{path}: record {k} is missing {missing}; each record needs {list(keys)}")
        bad = [key for key in keys if not isinstance(record[key], str) or not record[key]]
        if bad:
            raise RigFileError(f"{path}: record {k} keys {bad} must be non-empty strings")
    return table


def _camera_pose(record: dict, where: str) -> tuple[np.ndarray, np.ndarray, float]:
    """(position (3,) metres ego, R_vehicle_cam (3, 3), fx pixels) of one camera calibration record."""
    missing = [key for key in ("translation", "rotation", "camera_intrinsic") if key not in record]
    if missing:
        raise RigFileError(f"{where} is missing {missing}; a camera record needs "
                           "translation, rotation and camera_intrinsic")
    translation = _numbers(record["translation"], (3,), f"{where} 'translation' [x, y, z] metres")
    quaternion = _numbers(record["rotation"], (4,), f"{where} 'rotation' quaternion [w, x, y, z]")
    intrinsic = _numbers(record["camera_intrinsic"], (3, 3), f"{where} 'camera_intrinsic' 3x3 matrix")
    norm = float(np.linalg.norm(quaternion))
    if abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE:
        raise RigFileError(f"{where} 'rotation' must be a unit quaternion [w, x, y, z], its norm is {norm:.6g}")
    if not (intrinsic[0, 0] > 0 and intrinsic[1, 1] > 0):
        raise RigFileError(f"{where} 'camera_intrinsic' focal lengths K[0][0], K[1][1] must be positive pixels, "
                           f"got {intrinsic[0, 0]:g} and {intrinsic[1, 1]:g}")
    rotation = quaternion_to_matrix(quaternion / norm) @ R_CAM_OPTICAL.T
    return translation, rotation, float(intrinsic[0, 0])


def _numbers(values, shape: tuple[int, ...], what: str) -> np.ndarray:
    """``values`` as a finite float array of ``shape``; JSON numbers only (no bools, no strings)."""
    array = np.array(values, dtype=object)
    if array.shape != shape or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in array.flat):
        raise RigFileError(f"{what}: expected numbers of shape {shape}, got {values!r}")
    array = array.astype(float)
    if not np.all(np.isfinite(array)):
        raise RigFileError(f"{what}: NaN or inf is not allowed, got {values!r}")
    return array


def _choose(channel: str, poses: list, index: int | None, path: Path):
    """The one calibration of ``channel``: its ``index``-th record, or the record all of them agree on."""
    if not poses:
        raise RigFileError(f"{path}: camera channel {channel} has no record; "
                           f"add its calibration or drop the channel from {SENSOR_FILE}")
    if index is not None:
        if index >= len(poses):
            raise RigFileError(f"{path}: --index {index} is out of range for {channel}, which has {len(poses)} "
                               f"record(s); valid indices are 0..{len(poses) - 1}")
        return poses[index]
    distinct = []
    for pose in poses:
        if not any(_same(pose, other) for other in distinct):
            distinct.append(pose)
    if len(distinct) > 1:
        raise RigFileError(f"{path}: {channel} has {len(distinct)} different calibrations in {len(poses)} records; "
                           f"choose one with --index K (0-based, in file order)")
    return poses[0]


def _same(a, b) -> bool:
    return (np.allclose(a[0], b[0], rtol=0, atol=SAME_TRANSLATION_M)
            and np.allclose(a[1], b[1], rtol=0, atol=SAME_ROTATION)
            and abs(a[2] - b[2]) <= SAME_FOCAL_PX)


def write_nuscenes_calibration(rig: Rig, directory, image_size=None) -> Path:
    """Write ``rig`` as nuScenes ``sensor.json`` and ``calibrated_sensor.json`` in ``directory``.

    One camera channel per camera, named by its id; tokens are hashes of the channel names, so the
    same rig always gives the same files. ``image_size`` ``(width, height)`` pixels overrides each
    camera's own for the centred intrinsic matrix. The rig's name, vehicle and zones are not written.
    Returns the directory.
    """
    directory = Path(directory)
    override = None if image_size is None else _image_size(image_size, directory)
    directory.mkdir(parents=True, exist_ok=True)
    sensors, records = [], []
    for camera in rig.cameras:
        width, height = override or camera.image_size
        sensor_token = nuscenes_token("sensor", camera.id)
        sensors.append({"token": sensor_token, "channel": camera.id, "modality": "camera"})
        records.append({
            "token": nuscenes_token("calibrated_sensor", camera.id),
            "sensor_token": sensor_token,
            "translation": [float(v) + 0.0 for v in camera.position],  # + 0.0 drops -0.0
            "rotation": [float(v) for v in matrix_to_quaternion(camera.rotation @ R_CAM_OPTICAL)],
            "camera_intrinsic": intrinsic_matrix(camera.fov, width, height).tolist(),
        })
    (directory / SENSOR_FILE).write_text(json.dumps(sensors, indent=2) + "\n")
    (directory / CALIBRATION_FILE).write_text(json.dumps(records, indent=2) + "\n")
    return directory


def nuscenes_token(table: str, channel: str) -> str:
    """A 32-hex-digit nuScenes-style token, fixed by the table and channel names."""
    return hashlib.sha256(f"rigopt/{table}/{channel}".encode()).hexdigest()[:32]
