"""nuScenes calibration tables read into and written from :class:`Rig`.

Tables as in a nuScenes release folder (e.g. ``v1.0-mini/``)::

    sensor.json:            [{"token", "channel": "CAM_FRONT", "modality": "camera"}, ...]
    calibrated_sensor.json: [{"token", "sensor_token", "translation": [x, y, z],
                              "rotation": [w, x, y, z], "camera_intrinsic": [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]}, ...]
    sample_data.json (optional): [{"calibrated_sensor_token", "sample_token", "width", "height", ...}, ...]
    sample.json, scene.json, log.json (optional): sample -> scene -> log, to tell which log used which records

The ego frame is ISO 8855 (x forward, y left, z up) with its origin on the ground below the middle of the
rear axle; ``translation`` is the lens centre in metres. ``rotation`` is a scalar-first unit quaternion for
``R_ego_optical`` (optical frame: z forward, x right, y down). nuScenes images are rectified: the cameras
have no distortion. Only ``modality == "camera"`` channels become cameras (ids: the channel names).

A release holds one calibration per log. With sample_data, sample, scene and log tables, each log's camera
records form one rig; logs whose rigs agree in every value are one *distinct calibration*. Without them,
the K-th distinct record of every channel (in file order) forms the K-th calibration. Image sizes come
from sample_data's width and height, else from a default (1600 x 900, nuScenes' cameras).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rigopt.camera import CameraModel, intrinsic_matrix
from rigopt.errors import RigFileError
from rigopt.geometry import matrix_to_quaternion, optical_from_body
from rigopt.output import existing_folder
from rigopt.rig.formats.common import (Exported, Imported, choose_calibration, make_camera, make_lens, make_rig,
                                       numbers, optical_quaternion_rotation, origin_note, read_json,
                                       same_cameras, unit_quaternion, warn_not_carried, warn_origin)
from rigopt.rig.model import Camera, Rig, RigOrigin

SENSOR_FILE = "sensor.json"
CALIBRATION_FILE = "calibrated_sensor.json"
SAMPLE_DATA_FILE = "sample_data.json"
LINK_FILES = ("sample.json", "scene.json", "log.json")
#: nuScenes camera images, (width, height) in pixels.
NUSCENES_IMAGE_SIZE = (1600, 900)
ORIGIN = RigOrigin("rear_axle")
FIX = f"pass the nuScenes table folder holding {SENSOR_FILE} and {CALIBRATION_FILE} (e.g. v1.0-mini/)"


@dataclass(frozen=True)
class Calibration:
    """One distinct calibration of a release: its cameras and the logs (logfile names), vehicles and scenes
    that used it (empty when the release has no sample_data/sample/scene/log tables)."""

    cameras: tuple[Camera, ...]
    logs: tuple[str, ...] = ()
    vehicles: tuple[str, ...] = ()
    scenes: tuple[str, ...] = ()
    log_tokens: tuple[str, ...] = ()
    scene_tokens: tuple[str, ...] = ()


def read_nuscenes(directory, image_size=NUSCENES_IMAGE_SIZE, calibration: int | None = None, log: str | None = None,
                  scene: str | None = None, name: str | None = None, vehicle: str = "nuscenes",
                  origin: RigOrigin | None = None) -> Imported:
    """Read the camera rig of a nuScenes table folder.

    image_size : (w, h) or {channel: (w, h)} with an optional None key for the rest; used where
        sample_data gives no size. calibration : the K-th (0-based) distinct calibration; log, scene : the
        calibration that log (logfile name or token) or scene (name or token) used. None of them: the
        release must hold one distinct calibration. name : default the chosen log's name, else the
        folder's. origin : default the rear axle. Returns the rig and notes for stderr.
    """
    directory = Path(directory)
    calibrations, linked, defaulted_sizes = _calibrations(directory, image_size)
    where = str(directory)
    if log is not None or scene is not None:
        if not linked:
            raise RigFileError(f"{directory}: --log and --scene need {SAMPLE_DATA_FILE} and "
                               f"{', '.join(LINK_FILES)} in the folder; choose with --calibration K instead")
        chosen = _by_log_or_scene(directory, calibrations, log, scene)
    else:
        chosen = choose_calibration(calibrations, calibration, where, "--calibration K, --log NAME or --scene NAME")
    origin = origin or ORIGIN
    default_name = chosen.logs[0] if (log is not None or scene is not None) and chosen.logs else directory.resolve().name
    rig = make_rig(where, name or default_name, vehicle, chosen.cameras, origin)
    notes = [origin_note(origin, "nuScenes ego frame" if origin == ORIGIN else "--origin")]
    defaulted = [c.id for c in rig.cameras if c.id in defaulted_sizes]
    if defaulted:
        w, h = rig.cameras[[c.id for c in rig.cameras].index(defaulted[0])].image_size
        notes.append(f"image size {w}x{h} assumed for {', '.join(defaulted)} ({SAMPLE_DATA_FILE} gives none; "
                     "set it with --image-size)")
    return Imported(rig, tuple(notes))


def _by_log_or_scene(directory: Path, calibrations: list[Calibration], log, scene) -> Calibration:
    for calibration in calibrations:
        if ((log is not None and log in calibration.logs + calibration.log_tokens)
                or (scene is not None and scene in calibration.scenes + calibration.scene_tokens)):
            return calibration
    what, value = ("--log", log) if log is not None else ("--scene", scene)
    known = sorted({x for c in calibrations for x in (c.logs if log is not None else c.scenes)})
    shown = ", ".join(known[:8]) + (", ..." if len(known) > 8 else "")
    raise RigFileError(f"{directory}: {what} {value!r} names no {what[2:]} with camera data; known: {shown}")


def nuscenes_calibrations(directory, image_size=NUSCENES_IMAGE_SIZE) -> list[Calibration]:
    """The distinct calibrations of a table folder, in the order their first log (or record) appears."""
    return _calibrations(Path(directory), image_size)[0]


def _calibrations(directory: Path, image_size) -> tuple[list[Calibration], bool, set[str]]:
    """(distinct calibrations, whether the tables linked records to logs, channels given the default size)."""
    existing_folder(directory, f"the nuScenes tables {SENSOR_FILE} and {CALIBRATION_FILE} (e.g. v1.0-mini/)",
                    kind=RigFileError)
    sizes = _image_sizes(image_size, directory)
    defaulted: set[str] = set()
    sensor_path, calibration_path = directory / SENSOR_FILE, directory / CALIBRATION_FILE
    sensors = _read_table(sensor_path, ("token", "channel", "modality"))
    records = _read_table(calibration_path, ("token", "sensor_token"))
    camera_channel = {s["token"]: s["channel"] for s in sensors if s["modality"] == "camera"}
    channels = list(dict.fromkeys(s["channel"] for s in sensors if s["modality"] == "camera"))
    if not channels:
        raise RigFileError(f"{sensor_path}: no sensor has modality 'camera'; a rig needs at least one camera channel")
    known = {s["token"] for s in sensors}
    camera_records = []
    for k, record in enumerate(records):
        if record["sensor_token"] not in known:
            raise RigFileError(f"{calibration_path}: record {k} refers to sensor_token {record['sensor_token']!r}, "
                               f"which {SENSOR_FILE} does not list; use the tables of one release")
        if record["sensor_token"] in camera_channel:
            camera_records.append((k, record, camera_channel[record["sensor_token"]]))

    sample_data = _optional_table(directory / SAMPLE_DATA_FILE, ("calibrated_sensor_token",))
    measured = _sizes_from_sample_data(sample_data, {r["token"] for _, r, _ in camera_records}, directory)
    cameras = {}
    for k, record, channel in camera_records:
        size = measured.get(record["token"])
        if size is None:
            size = sizes.get(channel, sizes[None])
            defaulted.add(channel)
        cameras[record["token"]] = _camera(record, channel, size, f"{calibration_path}: record {k} ({channel})")
    for channel in channels:
        if not any(c == channel for _, _, c in camera_records):
            raise RigFileError(f"{calibration_path}: camera channel {channel} has no record; "
                               f"add its calibration or drop the channel from {SENSOR_FILE}")

    links = [_optional_table(directory / f, ("token",)) for f in LINK_FILES]
    if sample_data is not None and all(t is not None for t in links):
        by_log = _records_by_log(directory, sample_data, *links, set(cameras))
        if by_log:
            return _distinct_logs(by_log, cameras, channels), True, defaulted
    return _distinct_records(camera_records, cameras, channels, calibration_path), False, defaulted


def _camera(record: dict, channel: str, size: tuple[int, int], where: str) -> Camera:
    """The rigopt camera of one calibrated_sensor record."""
    missing = [key for key in ("translation", "rotation", "camera_intrinsic") if key not in record]
    if missing:
        raise RigFileError(f"{where} is missing {missing}; a camera record needs "
                           "translation, rotation and camera_intrinsic")
    translation = numbers(record["translation"], (3,), f"{where} 'translation' [x, y, z] metres")
    quaternion = unit_quaternion(record["rotation"], f"{where} 'rotation' quaternion [w, x, y, z]")
    k = numbers(record["camera_intrinsic"], (3, 3), f"{where} 'camera_intrinsic' 3x3 matrix")
    if not (k[0, 0] > 0 and k[1, 1] > 0):
        raise RigFileError(f"{where} 'camera_intrinsic' focal lengths K[0][0], K[1][1] must be positive pixels, "
                           f"got {k[0, 0]:g} and {k[1, 1]:g}")
    if k[0, 1] != 0 or k[1, 0] != 0 or k[2, 0] != 0 or k[2, 1] != 0 or k[2, 2] != 1:
        raise RigFileError(f"{where} 'camera_intrinsic' must be [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] "
                           f"(no skew); got {record['camera_intrinsic']!r}")
    lens = make_lens(where, size[0], size[1], k[0, 0], k[1, 1], k[0, 2], k[1, 2])
    return make_camera(where, channel, translation, optical_quaternion_rotation(quaternion), lens)


def _sizes_from_sample_data(sample_data, tokens: set[str], directory: Path) -> dict[str, tuple[int, int]]:
    """calibrated_sensor token -> (width, height) of its first sample_data record with a size.

    A camera's record without ``width`` and ``height`` (both absent or null) gives none; any other value but
    positive whole pixels (0, negative, fractional, text) is refused, naming the record: a camera image has a
    size, so a 0 is a broken table, not a missing value.
    """
    sizes = {}
    for k, record in enumerate(sample_data or ()):
        token = record["calibrated_sensor_token"]
        if token not in tokens or token in sizes:
            continue
        width, height = record.get("width"), record.get("height")
        if width is None and height is None:
            continue
        if not all(isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in (width, height)):
            raise RigFileError(f"{directory / SAMPLE_DATA_FILE}: record {k} (token {record.get('token', '?')!r}) is "
                               f"an image of a camera's calibrated_sensor {token!r}, so its width and height must be "
                               f"positive whole pixels, got {width!r} x {height!r}; fix the record, or drop both keys "
                               "to use --image-size")
        sizes[token] = (width, height)
    return sizes


def _records_by_log(directory, sample_data, samples, scenes, logs, camera_tokens) -> dict[str, dict]:
    """logfile -> {"tokens": calibrated_sensor tokens of its cameras, "vehicle", "scenes", "scene_tokens",
    "log_token"}, in the order the logs first appear in sample_data."""
    scene_of_sample = {s["token"]: s.get("scene_token") for s in samples}
    scene_by_token = {s["token"]: s for s in scenes}
    log_by_token = {entry["token"]: entry for entry in logs}
    by_log: dict[str, dict] = {}
    for record in sample_data:
        token = record["calibrated_sensor_token"]
        if token not in camera_tokens:
            continue
        scene = scene_by_token.get(scene_of_sample.get(record.get("sample_token")))
        log = log_by_token.get(scene.get("log_token")) if scene else None
        if log is None:
            raise RigFileError(f"{directory / SAMPLE_DATA_FILE}: record {record.get('token', '?')!r} leads to no log "
                               f"through sample.json, scene.json and log.json; use the tables of one release")
        key = log.get("logfile") or log["token"]
        entry = by_log.setdefault(key, {"tokens": [], "vehicle": str(log.get("vehicle", "")), "scenes": [],
                                        "scene_tokens": [], "log_token": log["token"]})
        if token not in entry["tokens"]:
            entry["tokens"].append(token)
        if scene["token"] not in entry["scene_tokens"]:
            entry["scene_tokens"].append(scene["token"])
            entry["scenes"].append(str(scene.get("name") or scene["token"]))
    return by_log


def _distinct_logs(by_log: dict, cameras: dict, channels: list[str]) -> list[Calibration]:
    groups: list[dict] = []
    for logfile, entry in by_log.items():
        own = {cameras[t].id: cameras[t] for t in entry["tokens"]}
        rig_cameras = tuple(own[c] for c in channels if c in own)
        for group in groups:
            if same_cameras(group["cameras"], rig_cameras):
                break
        else:
            group = {"cameras": rig_cameras, "logs": [], "vehicles": [], "scenes": [], "log_tokens": [],
                     "scene_tokens": []}
            groups.append(group)
        group["logs"].append(logfile)
        group["log_tokens"].append(entry["log_token"])
        group["scene_tokens"] += entry["scene_tokens"]
        if entry["vehicle"] and entry["vehicle"] not in group["vehicles"]:
            group["vehicles"].append(entry["vehicle"])
        group["scenes"] += entry["scenes"]
    return [Calibration(g["cameras"], tuple(g["logs"]), tuple(g["vehicles"]), tuple(g["scenes"]),
                        tuple(g["log_tokens"]), tuple(g["scene_tokens"])) for g in groups]


def _distinct_records(camera_records, cameras: dict, channels: list[str], path: Path) -> list[Calibration]:
    per_channel: dict[str, list[Camera]] = {c: [] for c in channels}
    for _, record, channel in camera_records:
        camera = cameras[record["token"]]
        if not any(same_cameras((camera,), (other,)) for other in per_channel[channel]):
            per_channel[channel].append(camera)
    counts = {c: len(v) for c, v in per_channel.items()}
    n = max(counts.values())
    uneven = {c: k for c, k in counts.items() if k not in (1, n)}
    if uneven:
        raise RigFileError(f"{path}: camera channels have different numbers of distinct calibrations {counts}, so "
                           f"they cannot be paired into rigs; add {SAMPLE_DATA_FILE}, {', '.join(LINK_FILES)} to "
                           "tell which log used which records")
    return [Calibration(tuple(per_channel[c][k if counts[c] > 1 else 0] for c in channels)) for k in range(n)]


def _image_sizes(image_size, directory: Path) -> dict:
    """``image_size`` as {channel or None (the rest): (w, h)} (positive whole pixels)."""
    table = dict(image_size) if isinstance(image_size, dict) else {None: image_size}
    table.setdefault(None, NUSCENES_IMAGE_SIZE)
    for key, size in table.items():
        size = tuple(size) if isinstance(size, (list, tuple)) else ()
        if len(size) != 2 or not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v > 0
                                     for v in size):
            raise RigFileError(f"{directory}: image_size must be two positive integers (width, height) in pixels, "
                               f"got {table[key]!r}")
        table[key] = (int(size[0]), int(size[1]))
    return table


def _read_table(path: Path, keys: tuple[str, ...]) -> list[dict]:
    """A nuScenes table: a JSON list of objects, each with the string-valued ``keys``."""
    table = read_json(path, "nuScenes table", FIX)
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


def _optional_table(path: Path, keys: tuple[str, ...]) -> list[dict] | None:
    return _read_table(path, keys) if path.exists() else None


def describe_calibrations(calibrations: list[Calibration]) -> list[dict]:
    """Rows for ``--list``: index, cameras, logs (logfile names), vehicles, scenes."""
    rows = []
    for k, calibration in enumerate(calibrations):
        rows.append({"calibration": k, "cameras": [c.id for c in calibration.cameras], "logs": list(calibration.logs),
                     "vehicles": list(calibration.vehicles), "scenes": list(calibration.scenes)})
    return rows


# ------------------------------------------------------------------------------------------------ writing


def export_nuscenes(rig: Rig) -> Exported:
    """``sensor.json``, ``calibrated_sensor.json`` and ``sample_data.json`` (one record per camera, for
    its image size) of ``rig``, with warnings for what nuScenes does not carry (distortion, name, vehicle,
    zones; a non-rear-axle origin)."""
    sensors, records, sample_data = _tables(rig, None)
    for camera in rig.cameras:
        width, height = camera.image_size
        sample_data.append({
            "token": nuscenes_token("sample_data", camera.id), "sample_token": "", "ego_pose_token": "",
            "calibrated_sensor_token": nuscenes_token("calibrated_sensor", camera.id), "timestamp": 0,
            "fileformat": "jpg", "is_key_frame": False, "height": height, "width": width, "filename": "",
            "prev": "", "next": ""})
    exported = Exported({SENSOR_FILE: _dump(sensors), CALIBRATION_FILE: _dump(records),
                         SAMPLE_DATA_FILE: _dump(sample_data)})
    distorted = [c.id for c in rig.cameras if c.lens.is_distorted]
    if distorted:
        exported.warnings.append(f"nuScenes cameras are rectified and carry no distortion; the distortion of "
                                 f"{', '.join(distorted)} is dropped (intrinsics kept)")
    exported.warnings += warn_origin(rig, "nuScenes", "rear_axle")
    exported.warnings += warn_not_carried(rig, "nuScenes", carries_name=False, carries_vehicle=False)
    return exported


def _tables(rig: Rig, image_size, lenses: bool = False) -> tuple[list, list, list]:
    """sensor and calibrated_sensor records of ``rig`` (``image_size`` (w, h) px or None: each camera's own);
    with ``lenses``, a distorted lens's record carries its distortion model and coefficients."""
    sensors, records = [], []
    for camera in rig.cameras:
        sensor_token = nuscenes_token("sensor", camera.id)
        sensors.append({"token": sensor_token, "channel": camera.id, "modality": "camera"})
        if image_size is not None:
            k = CameraModel.rendered(camera, image_size).intrinsic_matrix().tolist()
        elif camera.lens.is_ideal_pinhole:
            k = intrinsic_matrix(camera.fov, *camera.image_size).tolist()
        else:
            lens = camera.lens
            k = [[lens.fx, 0.0, lens.cx], [0.0, lens.fy, lens.cy], [0.0, 0.0, 1.0]]
        records.append({
            "token": nuscenes_token("calibrated_sensor", camera.id),
            "sensor_token": sensor_token,
            "translation": [float(v) + 0.0 for v in camera.position],  # + 0.0 drops -0.0
            "rotation": [float(v) for v in matrix_to_quaternion(optical_from_body(camera.rotation))],
            "camera_intrinsic": k,
        })
        if lenses and camera.lens.is_distorted:
            records[-1].update({"distortion": camera.lens.distortion,
                                "distortion_coefficients": [float(c) for c in camera.lens.coefficients]})
    return sensors, records, []


def _dump(table) -> str:
    return json.dumps(table, indent=2) + "\n"


def write_nuscenes_calibration(rig: Rig, directory, image_size=None) -> Path:
    """Write ``rig`` as nuScenes ``sensor.json`` and ``calibrated_sensor.json`` in ``directory`` (the
    benchmark generator's tables).

    One camera channel per camera, named by its id; tokens are hashes of the channel names, so the
    same rig always gives the same files. ``image_size`` ``(width, height)`` pixels overrides each
    camera's own: the intrinsic matrix is then that of the camera as the benchmark renders it at that size
    (:meth:`CameraModel.rendered`: a benchmark pinhole's centred matrix of its FOV, a real lens's scaled).
    A distorted lens's record also carries ``"distortion"`` (its model) and ``"distortion_coefficients"``
    (rigopt's additions to the nuScenes fields, read by the benchmark's detectors). Returns the directory.
    """
    directory = Path(directory)
    if image_size is not None:
        image_size = _image_sizes(image_size, directory)[None]
    directory.mkdir(parents=True, exist_ok=True)
    sensors, records, _ = _tables(rig, image_size, lenses=True)
    (directory / SENSOR_FILE).write_text(_dump(sensors))
    (directory / CALIBRATION_FILE).write_text(_dump(records))
    return directory


def nuscenes_token(table: str, channel: str) -> str:
    """A 32-hex-digit nuScenes-style token, fixed by the table and channel names."""
    return hashlib.sha256(f"rigopt/{table}/{channel}".encode()).hexdigest()[:32]
