"""The PCCR benchmark's rig JSON (CARLA frame), read into and written from :class:`Rig`.

File layout::

    {"vehicle_type": "vehicle.audi.etron",
     "cameras": [{"id": "CAM_BUMPER_FRONT", "location": [x, y, z], "rotation": [pitch, yaw, roll],
                  "fov": 65}, ...]}

``location`` in metres, CARLA frame (x forward, y right, z up); ``rotation`` in degrees, CARLA order,
any multiple of 360 apart; ``fov`` horizontal, degrees. Other keys (the benchmark's ``lidar``) are
ignored. rigopt adds optional keys, written only when they differ from the benchmark's defaults:

- per camera: ``image_size`` ``[width, height]`` (default 1280 x 720), ``zone``, ``module`` (the camera
  module, one housing, it shares with other cameras: a roof cluster, a stereo pair), ``role``
  (``"near_field"``; absent: ``"perception"``, so files written before roles are all perception), and for a real lens
  ``"intrinsics": {"fx": .., "fy": .., "cx": .., "cy": ..}`` (px) with
  ``"distortion": {"model": "radtan" | "fisheye", "coefficients": [...]}`` (OpenCV order: k1, k2, p1, p2,
  k3; fisheye k1..k4). With intrinsics, ``fov`` is the lens's derived horizontal FOV (checked on reading
  and kept as the lens's stated FOV, :attr:`rigopt.camera.Lens.stated_hfov`); a benchmark pinhole is written
  without them, as its ``fov`` alone.
- per rig: ``"origin": "rear_axle"`` or ``{"custom": [x, y, z]}`` (metres, CARLA frame) when the positions
  are not measured from the benchmark's vehicle centre; ``"frame"``, a sentence saying the file's frame (written
  into a design's rig.json, :func:`frame_note`; readers ignore it).
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from rigopt.benchmark import BENCHMARK_IMAGE_SIZE
from rigopt.camera import DISTORTION_COEFFICIENTS, FOV_TOLERANCE_DEG, Lens
from rigopt.errors import RigFileError, RigoptError, json_loads, not_utf8
from rigopt.geometry import carla_to_iso, iso_to_carla
from rigopt.output import existing_file
from rigopt.rig.model import ROLES, VEHICLE_CENTRE, Camera, Rig, RigOrigin

#: Decimals kept when writing angles (degrees) and locations (metres): far below any mounting tolerance,
#: and enough to give back the numbers of a file that was read.
WRITE_DECIMALS = 9


def rig_from_dict(data, name: str, source: str = "<rig>") -> Rig:
    """Build a Rig from the parsed JSON ``data`` of a benchmark rig file; ``source`` names it in errors."""
    if not isinstance(data, dict):
        raise RigFileError(f"{source}: a rig file must hold a JSON object with 'vehicle_type' and 'cameras'")
    for key in ("vehicle_type", "cameras"):
        if key not in data:
            raise RigFileError(f"{source}: missing key {key!r}; a rig file needs 'vehicle_type' and 'cameras'")
    vehicle = data["vehicle_type"]
    if not isinstance(vehicle, str) or not vehicle:
        raise RigFileError(f"{source}: 'vehicle_type' must be a non-empty string, got {vehicle!r}")
    cameras = data["cameras"]
    if not isinstance(cameras, list) or not cameras:
        raise RigFileError(f"{source}: 'cameras' must be a non-empty list of cameras")
    try:
        origin = _origin_from(data.get("origin"), source)
        return Rig(name, vehicle, tuple(_camera_from_dict(c, k, source) for k, c in enumerate(cameras)), origin)
    except RigoptError as error:
        message = str(error)
        raise RigFileError(message if message.startswith(source) else f"{source}: {message}") from None


def _camera_from_dict(entry, index: int, source: str) -> Camera:
    where = f"{source}: camera {index}"
    if not isinstance(entry, dict):
        raise RigFileError(f"{where} must be an object with 'id', 'location', 'rotation', 'fov'")
    missing = [k for k in ("id", "location", "rotation", "fov") if k not in entry]
    if missing:
        raise RigFileError(f"{where} ({entry.get('id', 'no id')}) is missing {missing}")
    if not isinstance(entry["id"], str) or not entry["id"]:
        raise RigFileError(f"{where} 'id' must be a non-empty string, got {entry['id']!r}")
    location = _numbers(entry["location"], 3, f"{where} ({entry['id']!r}) 'location' [x, y, z] metres")
    rotation = _numbers(entry["rotation"], 3, f"{where} ({entry['id']}) 'rotation' [pitch, yaw, roll] degrees")
    fov = _numbers([entry["fov"]], 1, f"{where} ({entry['id']}) 'fov' degrees")[0]
    size = entry.get("image_size", BENCHMARK_IMAGE_SIZE)
    if not (isinstance(size, (list, tuple)) and len(size) == 2 and all(isinstance(v, int) and v > 0 for v in size)):
        raise RigFileError(f"{where} ({entry['id']}) 'image_size' must be [width, height] in pixels, got {size!r}")
    position, rotation_matrix = carla_to_iso(location, rotation)
    lens = _lens_from(entry, size, fov, f"{where} ({entry['id']})")
    role = entry.get("role", "perception")
    if role not in ROLES:
        raise RigFileError(f"{where} ({entry['id']}) 'role' must be one of {', '.join(ROLES)} (absent: perception), "
                           f"got {role!r}")
    if lens is None:
        return Camera.pinhole(entry["id"], position, rotation_matrix, fov, tuple(size), entry.get("zone"),
                              entry.get("module"), role)
    return Camera(entry["id"], position, rotation_matrix, lens, entry.get("zone"), entry.get("module"), role)


def _lens_from(entry: dict, size, fov: float, where: str) -> Lens | None:
    """The camera's lens from 'intrinsics' and 'distortion', stated by the file's ``fov`` (deg, checked against
    the intrinsics); None without intrinsics: the benchmark's pinhole of ``fov`` and ``size``."""
    if "intrinsics" not in entry:
        if "distortion" in entry:
            raise RigFileError(f"{where} has 'distortion' without 'intrinsics'; give both (fx, fy, cx, cy in px)")
        return None
    intrinsics = entry["intrinsics"]
    if not isinstance(intrinsics, dict) or sorted(intrinsics) != ["cx", "cy", "fx", "fy"]:
        raise RigFileError(f"{where} 'intrinsics' must be an object with fx, fy, cx, cy in pixels, got {intrinsics!r}")
    fx, fy, cx, cy = _numbers([intrinsics[k] for k in ("fx", "fy", "cx", "cy")], 4, f"{where} 'intrinsics'")
    distortion = entry.get("distortion", {"model": "none", "coefficients": []})
    if not isinstance(distortion, dict) or distortion.get("model") not in DISTORTION_COEFFICIENTS:
        raise RigFileError(f"{where} 'distortion' must be {{\"model\": one of {', '.join(DISTORTION_COEFFICIENTS)}, "
                           f"\"coefficients\": [...]}}, got {distortion!r}")
    names = DISTORTION_COEFFICIENTS[distortion["model"]]
    coefficients = _numbers(distortion.get("coefficients", []), len(names),
                            f"{where} 'distortion' coefficients ({', '.join(names) or 'none'})")
    lens = Lens(size[0], size[1], fx, fy, cx, cy, distortion["model"], tuple(coefficients))
    if not abs(fov - lens.hfov) <= FOV_TOLERANCE_DEG:
        raise RigFileError(f"{where} fov {fov:g} deg disagrees with its lens's horizontal FOV {lens.hfov:.6f} deg "
                           "(from 'intrinsics' and 'distortion'); write the lens's FOV")
    if lens.is_ideal_pinhole:  # the benchmark's pinhole, of the file's fov
        return Lens.pinhole(fov, lens.image_size)
    return replace(lens, stated_hfov=fov)


def _origin_from(value, source: str) -> RigOrigin:
    if value is None or value == "vehicle_centre":
        return VEHICLE_CENTRE
    if value == "rear_axle":
        return RigOrigin("rear_axle")
    if isinstance(value, dict) and list(value) == ["custom"]:
        location = _numbers(value["custom"], 3, f"{source}: 'origin' custom point [x, y, z] metres")
        point, _ = carla_to_iso(location, [0.0, 0.0, 0.0])
        return RigOrigin("custom", tuple(point))
    raise RigFileError(f"{source}: 'origin' must be \"vehicle_centre\", \"rear_axle\" or {{\"custom\": [x, y, z]}} "
                       f"(metres, CARLA frame), got {value!r}")


def _numbers(values, count: int, what: str) -> list[float]:
    if not isinstance(values, (list, tuple)) or len(values) != count:
        raise RigFileError(f"{what}: expected {count} number(s), got {values!r}")
    out = []
    for v in values:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise RigFileError(f"{what}: expected numbers, got {values!r}")
        if not math.isfinite(v):
            raise RigFileError(f"{what}: NaN or inf is not allowed, got {values!r}")
        out.append(float(v))
    return out


def frame_note(rig: Rig) -> str:
    """The sentence a design's rig.json carries as ``"frame"``: CARLA's axes and angles, and where the positions
    are measured from (``rig.origin``)."""
    origin = {"vehicle_centre": "the vehicle's centre on the ground (the benchmark's origin)",
              "rear_axle": "the ground below the rear axle's centre",
              "custom": "the point 'origin' gives"}.get(rig.origin.kind, rig.origin.kind)
    return (f"CARLA's vehicle frame: location [x forward, y right, z up] in metres from {origin}; rotation [pitch, "
            "yaw, roll] in degrees; report.json and the pictures use ISO 8855 (y left) from the ground below the "
            "rear axle's centre")


def rig_to_dict(rig: Rig, say_frame: bool = False) -> dict:
    """The benchmark JSON object of ``rig`` (CARLA frame, degrees); ``say_frame`` adds ``"frame"``
    (:func:`frame_note`)."""
    location, rotation = iso_to_carla(rig.positions, rig.rotations)
    cameras = []
    for camera, loc, rot in zip(rig.cameras, location, rotation):
        entry = {
            "id": camera.id,
            "location": _rounded(loc),
            "rotation": _rounded(rot),
            "fov": _rounded([camera.fov])[0],
        }
        if camera.image_size != BENCHMARK_IMAGE_SIZE:
            entry["image_size"] = list(camera.image_size)
        if camera.zone is not None:
            entry["zone"] = camera.zone
        if camera.module is not None:
            entry["module"] = camera.module
        if camera.role != "perception":
            entry["role"] = camera.role
        if not camera.lens.is_ideal_pinhole:  # the benchmark's pinhole is its fov alone
            lens = camera.lens
            entry["intrinsics"] = dict(zip(("fx", "fy", "cx", "cy"), _rounded([lens.fx, lens.fy, lens.cx, lens.cy])))
            if lens.distortion != "none":
                entry["distortion"] = {"model": lens.distortion, "coefficients": [float(c) for c in lens.coefficients]}
        cameras.append(entry)
    data = {"vehicle_type": rig.vehicle}
    if say_frame:
        data["frame"] = frame_note(rig)
    if not rig.origin.is_benchmark:
        if rig.origin.kind == "custom":
            location, _ = iso_to_carla(np.array([rig.origin.point]), np.eye(3)[None])
            data["origin"] = {"custom": _rounded(location[0])}
        else:
            data["origin"] = rig.origin.kind
    data["cameras"] = cameras
    return data


def _rounded(values) -> list:
    """Round to WRITE_DECIMALS, drop -0.0, and write whole numbers as integers like the benchmark does."""
    out = []
    for v in np.round(np.asarray(values, dtype=float), WRITE_DECIMALS) + 0.0:
        out.append(int(v) if float(v).is_integer() else float(v))
    return out


def read_rig(path, name: str | None = None) -> Rig:
    """Read a benchmark rig file. ``name`` defaults to the file stem."""
    path = existing_file(path, "rig file", kind=RigFileError)
    try:
        text = path.read_text()
    except OSError as error:
        raise RigFileError(f"{path}: cannot read the rig file ({error.strerror})") from None
    except UnicodeDecodeError as error:
        raise not_utf8(path, "rig file", error, RigFileError) from None
    try:
        data = json_loads(text)
    except json.JSONDecodeError as error:
        raise RigFileError(f"{path}: not valid JSON (line {error.lineno}, column {error.colno}: {error.msg})") from None
    return rig_from_dict(data, name or path.stem, str(path))


def write_rig(rig: Rig, path, say_frame: bool = False) -> Path:
    """Write ``rig`` as a benchmark rig file (with ``"frame"`` when ``say_frame``); returns the path."""
    from rigopt.output import write_text_atomic

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(path, json.dumps(rig_to_dict(rig, say_frame), indent=2) + "\n")  # whole or not at all
    return path
