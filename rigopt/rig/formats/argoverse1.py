"""Argoverse 1 (argoverse-api) ``vehicle_calibration_info.json`` read into :class:`Rig` (import only).

Layout (argoverse-api's ``argoverse/utils/calibration.py`` reads it; its issues #81 and #286 explain it)::

    {"camera_data_": [{"key": "image_raw_ring_front_center",
                       "value": {"focal_length_x_px_", "focal_length_y_px_", "focal_center_x_px_",
                                 "focal_center_y_px_", "skew_", "distortion_coefficients_": [k1, k2, k3],
                                 "vehicle_SE3_camera_": {"rotation": {"coefficients": [qw, qx, qy, qz]},
                                                         "translation": [x, y, z]}}}, ...],
     "vehicle_SE3_up_lidar_": {...}, "vehicle_SE3_down_lidar_": {...}}

- ``vehicle_SE3_camera_`` maps points of the camera's optical frame (z forward, x right, y down) into the
  ego-vehicle frame (x forward, y left, z up, metres): ``R_ego_optical`` and the camera's position.
- Image sizes are not in the file; argoverse-api's ``camera_stats.py`` gives them by camera: the seven ring
  cameras 1920 x 1200, the two stereo cameras 2464 x 2056. The stereo cameras are left out unless asked for;
  the ``*_rect`` entries (rectified copies of the stereo images) are always left out.
- ``distortion_coefficients_`` are OpenCV's radial k1, k2, k3 with p1 = p2 = 0 (issue #81), i.e. rigopt's radtan
  (k1, k2, 0, 0, k3) exactly; but the dataset's imagery is distributed undistorted (same issue), so the cameras
  are pinholes unless the raw lenses are asked for.
- The ego frame's origin is the centre of the rear axle at the axle's height ("around 33 cm above the ground",
  issue #286): positions are raised by the axle height (:data:`AV1_AXLE_HEIGHT_M` unless given) to rigopt's
  rear-axle origin on the ground.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

from rigopt.errors import RigFileError, RigoptError
from rigopt.output import existing_file
from rigopt.rig.formats.common import (Imported, make_camera, make_lens, make_rig, numbers,
                                       optical_quaternion_rotation, read_json, unit_quaternion)
from rigopt.rig.formats.datasets import axle_height_origin
from rigopt.rig.model import RigOrigin

CALIBRATION_FILE = "vehicle_calibration_info.json"
KEY_PREFIX = "image_raw_"

#: Cameras and image sizes (width, height) px, as argoverse-api's camera_stats.py lists them.
RING_CAMERAS = ("ring_front_center", "ring_front_left", "ring_front_right", "ring_rear_left", "ring_rear_right",
                "ring_side_left", "ring_side_right")
STEREO_CAMERAS = ("stereo_front_left", "stereo_front_right")
#: Every key's camera part argoverse-api knows: the cameras and the rectified stereo entries.
KNOWN_CAMERAS = RING_CAMERAS + STEREO_CAMERAS + tuple(f"{c}_rect" for c in STEREO_CAMERAS)
RING_IMAGE_SIZE, STEREO_IMAGE_SIZE = (1920, 1200), (2464, 2056)

#: Height (m) of Argoverse 1's ego origin (the rear axle's centre) above the ground: the loaded tyre radius of its
#: Ford Fusion Hybrid, taken as the nominal radius of the Fusion Hybrid's stock tyre 225/50R17 (the 2013-2020
#: Fusion Hybrid SE and Titanium; tyre-size listings): rim 17 in / 2 = 215.9 mm plus a sidewall of 50 % of
#: 225 mm = 112.5 mm, 328.4 mm. argoverse-api's maintainers put the origin "around 33 cm above the ground"
#: (issue #286).
AV1_AXLE_HEIGHT_M = (17 * 25.4 / 2 + 0.50 * 225) / 1000
#: An --axle-height outside this range (m) is refused as a typo.
AXLE_HEIGHT_RANGE_M = (0.0, 2.0)
#: Camera sets of ``--cameras``.
CAMERA_SETS = ("ring", "all")

FIX = f"pass an Argoverse 1 log folder (holding {CALIBRATION_FILE}) or the file itself"


def read_argoverse1(path, name: str | None = None, vehicle: str = "argoverse1", origin: RigOrigin | None = None,
                    axle_height: float | None = None, cameras: str = "ring", raw_lens: bool = False) -> Imported:
    """Read the cameras of an Argoverse 1 log (its folder or its vehicle_calibration_info.json).

    name : default the log folder's name. origin : None for the file's own (the rear axle's centre at axle height,
    raised by ``axle_height`` m, default :data:`AV1_AXLE_HEIGHT_M`, to the ground); with one, the positions are
    taken as they are. cameras : "ring" (the seven ring cameras) or "all" (and the two stereo cameras).
    raw_lens : keep the lenses' radial distortion (radtan k1, k2, 0, 0, k3) instead of the pinholes of the
    distributed, undistorted images.
    """
    if cameras not in CAMERA_SETS:
        raise RigoptError(f"--cameras must be one of {', '.join(CAMERA_SETS)}, got {cameras!r}")
    if axle_height is not None:
        if origin is not None:
            raise RigoptError("--axle-height raises the file's positions to rigopt's rear-axle origin; with --origin "
                              "they are taken as they are: give one of the two")
        low, high = AXLE_HEIGHT_RANGE_M
        if not (math.isfinite(axle_height) and low <= axle_height <= high):
            raise RigoptError(f"--axle-height must be the rear axle's height above the ground in metres, "
                              f"{low:g} to {high:g}, got {axle_height!r}")
    path = Path(path)
    file = path / CALIBRATION_FILE if path.is_dir() else path
    existing_file(file, "Argoverse 1 calibration file", FIX, kind=RigFileError)
    data = read_json(file, "Argoverse 1 calibration JSON", FIX)
    if not isinstance(data, dict) or not isinstance(data.get("camera_data_"), list):
        raise RigFileError(f"{file}: an Argoverse 1 calibration is a JSON object with a 'camera_data_' list; {FIX}")
    wanted = RING_CAMERAS + (STEREO_CAMERAS if cameras == "all" else ())
    found, left_out = {}, []
    for k, entry in enumerate(data["camera_data_"]):
        where = f"{file}: camera_data_[{k}]"
        if not isinstance(entry, dict) or not isinstance(entry.get("key"), str) or not isinstance(entry.get("value"),
                                                                                                    dict):
            raise RigFileError(f"{where}: each entry is an object with 'key' (text) and 'value' (an object)")
        camera = entry["key"].removeprefix(KEY_PREFIX)
        where = f"{where} ({entry['key']})"
        if not entry["key"].startswith(KEY_PREFIX) or camera not in KNOWN_CAMERAS:
            raise RigFileError(f"{where}: not an Argoverse 1 camera; keys are {KEY_PREFIX}<camera> with <camera> one "
                               f"of {', '.join(KNOWN_CAMERAS)}")
        if camera not in wanted:
            left_out.append(camera)
            continue
        if camera in found:
            raise RigFileError(f"{where}: {camera} is listed twice; use one log's {CALIBRATION_FILE}")
        found[camera] = _camera_values(entry["value"], where)
    if not found:
        raise RigFileError(f"{file}: lists none of the ring cameras ({', '.join(RING_CAMERAS)}); {FIX}")
    height = AV1_AXLE_HEIGHT_M if axle_height is None else axle_height
    source = (" (--axle-height)" if axle_height is not None else
              " (the tyre radius of Argoverse 1's Ford Fusion Hybrid, 225/50R17; set it with --axle-height)")
    origin, origin_text, raise_by = axle_height_origin(origin, "Argoverse 1 ego-vehicle frame", height, source)
    rig_cameras = []
    for camera in (c for c in wanted if c in found):
        (fx, fy, cx, cy), radial, q, t, where = found[camera]
        size = RING_IMAGE_SIZE if camera in RING_CAMERAS else STEREO_IMAGE_SIZE
        if raw_lens:
            lens = make_lens(where, *size, fx, fy, cx, cy, "radtan", (radial[0], radial[1], 0.0, 0.0, radial[2]))
        else:
            lens = make_lens(where, *size, fx, fy, cx, cy)
        position = t + [0.0, 0.0, raise_by]
        rig_cameras.append(make_camera(where, camera, position, optical_quaternion_rotation(q), lens))
    notes = [origin_text, "lenses keep their radial distortion (OpenCV radtan k1, k2, 0, 0, k3): the raw sensors, not "
             "the distributed images, which are undistorted" if raw_lens else
             "Argoverse 1 imagery is distributed undistorted: k1, k2, k3 are not applied (pinhole cameras; --raw-lens "
             "keeps them)"]
    stereo = [c for c in STEREO_CAMERAS if c in left_out]
    if stereo:
        notes.append(f"stereo cameras left out: {', '.join(stereo)} (--cameras all keeps them)")
    rectified = [c for c in left_out if c.endswith("_rect")]
    if rectified:
        notes.append(f"left out {', '.join(rectified)}: rectified copies of the stereo cameras' images")
    default_name = file.parent.resolve().name
    stereo_pair = [k for k, c in enumerate(rig_cameras) if c.id in STEREO_CAMERAS]
    if len(stereo_pair) == 2:  # the stereo pair is one module: a 0.30 m bar behind the windscreen
        for k in stereo_pair:
            rig_cameras[k] = replace(rig_cameras[k], module="stereo_front")
        notes.append("module stereo_front: stereo_front_left, stereo_front_right (one stereo bar)")
    rig = make_rig(str(file), name or default_name, vehicle, rig_cameras, origin)
    return Imported(rig, tuple(notes))


def _camera_values(value: dict, where: str):
    """((fx, fy, cx, cy), (k1, k2, k3), q (w, x, y, z), t (3,), where) of one camera_data_ value, checked."""
    keys = ("focal_length_x_px_", "focal_length_y_px_", "focal_center_x_px_", "focal_center_y_px_", "skew_",
            "distortion_coefficients_", "vehicle_SE3_camera_")
    missing = [key for key in keys if key not in value]
    if missing:
        raise RigFileError(f"{where}: lacks {', '.join(missing)}")
    intrinsics = numbers([value[key] for key in keys[:5]], (5,), f"{where} focal lengths, centre and skew_")
    if intrinsics[4] != 0.0:
        raise RigFileError(f"{where}: skew_ {intrinsics[4]:g} is not supported; rigopt's lenses have no skew")
    radial = numbers(value["distortion_coefficients_"], (3,), f"{where} distortion_coefficients_ (k1, k2, k3)")
    pose = value["vehicle_SE3_camera_"]
    rotation = pose.get("rotation") if isinstance(pose, dict) else None
    if not isinstance(rotation, dict) or "coefficients" not in rotation or "translation" not in pose:
        raise RigFileError(f"{where}: vehicle_SE3_camera_ needs 'rotation': {{'coefficients': [qw, qx, qy, qz]}} and "
                           "'translation': [x, y, z]")
    q = unit_quaternion(rotation["coefficients"], f"{where} vehicle_SE3_camera_ rotation coefficients (qw, qx, qy, qz)")
    t = numbers(pose["translation"], (3,), f"{where} vehicle_SE3_camera_ translation")
    return tuple(intrinsics[:4]), tuple(radial), q, t, where
