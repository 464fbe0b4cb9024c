"""The benchmark's data format: nuScenes tables plus ``samples/<CAM>/`` images, written and read back.

Layout of one rig's split (the root a nuScenes reader expects)::

    <root>/v1.0-<split>/{log,scene,sample,sample_data,sensor,calibrated_sensor,ego_pose,
                         sample_annotation,instance,category,visibility,attribute}.json
    <root>/samples/<CAM>/<sample_data token>.png
    <root>/depth/<CAM>/<sample_data token>.png      16-bit depth maps (rigopt's data made since they exist)

Conventions are nuScenes': ``ego_pose`` and ``sample_annotation`` are in the global (world) frame,
quaternions are (w, x, y, z), annotation sizes are (width, length, height) metres, and a camera's
``calibrated_sensor`` maps its optical frame (z forward, x right, y down) into the ego frame. The reader
serves rigopt's own data and the real benchmark's folders alike.

Three fields are rigopt's own. Each ``calibrated_sensor`` record of a distorted lens carries ``distortion``
(``"radtan"`` or ``"fisheye"``, :class:`rigopt.camera.Lens`) and ``distortion_coefficients``: its
``camera_intrinsic`` is then the ``K`` of the distorted normalised coordinates, not a pinhole's (a record
without them is a pinhole). Each ``sample_data`` record of rigopt's data names its depth map in
``depth_filename`` (depth along the optical axis in cm, 0 where no surface; ``generate.DEPTH_SCALE``). Each
``sample_annotation`` record of rigopt's data carries ``visible_fraction``,
the float in [0, 1] its ``visibility_token`` is binned from; 0 marks an object that no camera of the rig
sees (nuScenes' lowest level, v0-40, cannot tell it from a barely visible one). nuScenes loaders ignore the
extra keys. An annotation without ``visible_fraction`` (the real benchmark's data, or rigopt's data made
before the field, when only seen objects were annotated) reads as visible.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rigopt.validation.synthetic.scene_model import CLASSES
from rigopt.errors import DataError, not_utf8
from rigopt.geometry import matrix_to_quaternion, quaternion_to_matrix, rot_z, yaw_pitch_roll_from_rotation
from rigopt.rig.formats.nuscenes import nuscenes_token

TABLES = ("log", "scene", "sample", "sample_data", "sensor", "calibrated_sensor", "ego_pose", "sample_annotation",
          "instance", "category", "visibility", "attribute")
#: nuScenes visibility levels: token, name, and the visible fraction range [low, high).
VISIBILITY = (("1", "v0-40", 0.0, 0.4), ("2", "v40-60", 0.4, 0.6), ("3", "v60-80", 0.6, 0.8),
              ("4", "v80-100", 0.8, 1.01))


def visibility_token(fraction: float) -> str:
    """The nuScenes visibility token of a visible fraction in [0, 1]."""
    return next(token for token, _, low, high in VISIBILITY if low <= fraction < high)


def pose_record(token: str, T: np.ndarray, **extra) -> dict:
    """A nuScenes pose record of the rigid transform T (4, 4): translation and (w, x, y, z) rotation."""
    return {"token": token, "translation": T[:3, 3].tolist(), "rotation": matrix_to_quaternion(T[:3, :3]).tolist(),
            **extra}


def static_tables() -> dict[str, list[dict]]:
    """The tables that do not depend on the data: category, visibility, attribute."""
    return {
        "category": [{"token": nuscenes_token("category", name), "name": name, "description": ""} for name in CLASSES],
        "visibility": [{"token": token, "level": level, "description": f"visible fraction {low:g} to {min(high, 1):g}"}
                       for token, level, low, high in VISIBILITY],
        "attribute": [],
    }


def save_tables(root, version: str, tables: dict[str, list[dict]]) -> Path:
    """Write every table of ``tables`` (missing ones empty) as ``<root>/<version>/<table>.json``."""
    folder = Path(root) / version
    folder.mkdir(parents=True, exist_ok=True)
    for name in TABLES:
        (folder / f"{name}.json").write_text(json.dumps(tables.get(name, []), indent=1) + "\n")
    return folder


@dataclass(frozen=True)
class TrainingSample:
    """One sample for a detector.

    images : {channel: path}; intrinsics : {channel: (3, 3)}; T_ego_cam : {channel: (4, 4)} optical frame
    -> ego; T_world_ego (4, 4); boxes in the ego frame: centers (n, 3) m, sizes (n, 3) (length, width,
    height) m, yaws (n,) rad, classes (n,) int into CLASSES, visibility (n,) str tokens, instances (n,) str
    instance tokens (the same object across samples and, for rigopt's data, across rigs);
    visible_fractions (n,) float in [0, 1] (NaN where the dataset does not record it), None when not read;
    depths : {channel: path} of the renderer's depth maps (``generate.DEPTH_SCALE``), None when the dataset
    has none; distortions : {channel: (model, coefficients)} of the channels whose calibration records a lens
    distortion (the others are pinholes of their intrinsics).
    """

    token: str
    scene: str
    timestamp_us: int
    images: dict
    intrinsics: dict
    T_ego_cam: dict
    T_world_ego: np.ndarray
    centers: np.ndarray
    sizes: np.ndarray
    yaws: np.ndarray
    classes: np.ndarray
    visibility: np.ndarray
    instances: np.ndarray
    visible_fractions: np.ndarray | None = None
    depths: dict | None = None
    distortions: dict = field(default_factory=dict)

    @property
    def visible(self) -> np.ndarray:
        """(n,) bool: the boxes some camera of the rig sees (fraction > 0; unrecorded fractions count as seen)."""
        if self.visible_fractions is None:
            return np.ones(len(self.classes), dtype=bool)
        return ~(np.asarray(self.visible_fractions, dtype=float) <= 0)


def _transform(record: dict) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = quaternion_to_matrix(record["rotation"])
    T[:3, 3] = record["translation"]
    return T


def _load(folder: Path, name: str) -> list[dict]:
    path = folder / f"{name}.json"
    try:
        return json.loads(path.read_text())
    except OSError:
        raise DataError(f"{path}: missing table; a dataset folder needs {', '.join(TABLES[:8])}") from None
    except UnicodeDecodeError as error:
        raise not_utf8(path, "dataset table", error) from None
    except json.JSONDecodeError as error:
        raise DataError(f"{path}: not valid JSON (line {error.lineno}: {error.msg})") from None


def read_dataset(root, version: str | None = None) -> list[TrainingSample]:
    """All samples of a nuScenes-layout folder ``root`` (``version`` defaults to its only v1.0-* folder),
    camera channels only, in scene and time order."""
    root = Path(root)
    if version is None:
        versions = sorted(p.name for p in root.glob("v1.0-*") if p.is_dir())
        if len(versions) != 1:
            raise DataError(f"{root}: expected one v1.0-* table folder, found {versions or 'none'}; pass the version")
        version = versions[0]
    folder = root / version
    tables = {name: _load(folder, name) for name in ("scene", "sample", "sample_data", "sensor", "calibrated_sensor",
                                                     "ego_pose", "sample_annotation", "instance", "category")}
    by_token = {name: {r["token"]: r for r in records} for name, records in tables.items()}
    channel_of = {s["token"]: s["channel"] for s in tables["sensor"] if s.get("modality") == "camera"}
    class_of = {c["token"]: CLASSES.index(c["name"]) if c["name"] in CLASSES else -1 for c in tables["category"]}
    scene_name = {s["token"]: s["name"] for s in tables["scene"]}
    data_by_sample: dict[str, list[dict]] = {}
    for record in tables["sample_data"]:
        data_by_sample.setdefault(record["sample_token"], []).append(record)
    annotations: dict[str, list[dict]] = {}
    for record in tables["sample_annotation"]:
        annotations.setdefault(record["sample_token"], []).append(record)

    samples = []
    for sample in sorted(tables["sample"], key=lambda s: (scene_name.get(s["scene_token"], ""), s["timestamp"])):
        images, depths, intrinsics, extrinsics, distortions, T_world_ego = {}, {}, {}, {}, {}, None
        for record in data_by_sample.get(sample["token"], []):
            calibration = by_token["calibrated_sensor"][record["calibrated_sensor_token"]]
            channel = channel_of.get(calibration["sensor_token"])
            if channel is None:
                continue
            images[channel] = root / record["filename"]
            if record.get("depth_filename"):
                depths[channel] = root / record["depth_filename"]
            intrinsics[channel] = np.asarray(calibration["camera_intrinsic"], dtype=float)
            if "distortion" in calibration:
                distortions[channel] = (calibration["distortion"],
                                        tuple(calibration.get("distortion_coefficients", ())))
            extrinsics[channel] = _transform(calibration)
            T_world_ego = _transform(by_token["ego_pose"][record["ego_pose_token"]])
        if T_world_ego is None:
            continue
        T_ego_world = np.linalg.inv(T_world_ego)
        boxes = annotations.get(sample["token"], [])
        centers = np.array([T_ego_world[:3, :3] @ b["translation"] + T_ego_world[:3, 3] for b in boxes]).reshape(-1, 3)
        sizes = np.array([[b["size"][1], b["size"][0], b["size"][2]] for b in boxes]).reshape(-1, 3)
        world_yaw = np.array([_yaw(quaternion_to_matrix(b["rotation"])) for b in boxes])
        ego_yaw = _yaw(T_world_ego[:3, :3])
        classes = np.array([class_of[by_token["instance"][b["instance_token"]]["category_token"]] for b in boxes],
                           dtype=int)
        samples.append(TrainingSample(
            sample["token"], scene_name.get(sample["scene_token"], ""), int(sample["timestamp"]), images, intrinsics,
            extrinsics, T_world_ego, centers, sizes, np.angle(np.exp(1j * (world_yaw - ego_yaw))), classes,
            np.array([b.get("visibility_token", "") for b in boxes]), np.array([b["instance_token"] for b in boxes]),
            np.array([_fraction(b) for b in boxes], dtype=float), depths if len(depths) == len(images) else None,
            distortions))
    return samples


def _fraction(record: dict) -> float:
    """An annotation's ``visible_fraction`` (NaN when the record has none)."""
    value = record.get("visible_fraction")
    if value is None:
        return float("nan")
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 <= value <= 1:
        raise DataError(f"sample_annotation {record.get('token', '?')}: visible_fraction must be a number in [0, 1], "
                        f"got {value!r}")
    return float(value)


def _yaw(rotation: np.ndarray) -> float:
    """Heading (yaw about z, radians in (-pi, pi]) of a box's or the ego's rotation (3, 3)."""
    return float(yaw_pitch_roll_from_rotation(rotation)[0])


def box_rotation(yaw: float) -> list[float]:
    """(w, x, y, z) quaternion of a box turned by ``yaw`` rad about z."""
    return matrix_to_quaternion(rot_z(yaw)).tolist()
