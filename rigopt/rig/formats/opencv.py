"""OpenCV / Kalibr camera-chain YAML (``camchain.yaml``) read into and written from :class:`Rig`.

Layout (Kalibr's, one block per camera ``cam0``, ``cam1``, ...)::

    cam0:
      camera_model: pinhole
      intrinsics: [fu, fv, pu, pv]            # fx, fy, cx, cy in px
      distortion_model: radtan | equidistant | none
      distortion_coeffs: [k1, k2, p1, p2]     # radtan (a fifth, k3, is accepted: OpenCV's order);
                                              # equidistant: [k1, k2, k3, k4] (Kannala-Brandt)
      resolution: [width, height]
      T_cn_cnm1: 4x4                          # cam1 on: maps points of cam(n-1)'s frame into cam n's
      T_cam_imu: 4x4                          # optional: maps IMU-frame points into this camera's frame
      T_body_cam: 4x4                         # optional (rigopt's): maps this camera's points into the body frame
      camera_name: CAM_FRONT                  # optional (rigopt's): the camera id (default camN)

Camera frames are optical (z along the axis, x right, y down). The body frame is rigopt's vehicle frame
(x forward, y left, z up). A camera's pose comes from ``T_body_cam``, else from ``T_cam_imu`` (the IMU
frame taken as the body frame: give one with ISO axes), else from the previous camera through
``T_cn_cnm1``; a ``cam0`` with none of them sits at the body origin looking along +x. The files say
nothing about where the body origin is: the rig's origin is the vehicle centre unless ``--origin`` says
otherwise.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from rigopt.errors import RigFileError
from rigopt.geometry import R_CAM_OPTICAL, body_from_optical, optical_from_body
from rigopt.rig.formats.common import (Exported, Imported, make_camera, make_lens, make_rig, numbers,
                                       origin_note, read_text, rotation_matrix, warn_not_carried,
                                       warn_origin, whole_number)
from rigopt.rig.model import Rig, RigOrigin

DISTORTION_MODELS = {"none": "none", "radtan": "radtan", "equidistant": "fisheye"}
FIX = "write a Kalibr camchain (cam0: camera_model, intrinsics, distortion_model, distortion_coeffs, resolution)"
#: Largest disagreement (m, rotation entries) allowed between T_body_cam and the chain T_cn_cnm1 of one file.
CHAIN_TOLERANCE = 1e-6


def read_camchain(path, name: str | None = None, vehicle: str = "opencv", origin: RigOrigin | None = None) -> Imported:
    """Read a Kalibr camchain YAML file; returns the rig (name default: the file's stem) and stderr notes."""
    import yaml

    path = Path(path)
    text = read_text(path, "Kalibr camchain YAML", FIX)
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        at = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        raise RigFileError(f"{path}: not valid YAML{at}; {FIX}") from None
    if not isinstance(data, dict) or "cam0" not in data:
        raise RigFileError(f"{path}: a camchain is a YAML mapping with blocks cam0, cam1, ...; found none; {FIX}")
    cameras, notes, previous = [], [], None
    k = 0
    while f"cam{k}" in data:
        key = f"cam{k}"
        block = data[key]
        where = f"{path}: {key}"
        if not isinstance(block, dict):
            raise RigFileError(f"{where} must be a mapping of camera_model, intrinsics, ...; {FIX}")
        lens = _lens(block, where)
        t_body_optical, how = _pose(block, previous, where, k)
        if how:
            notes.append(how)
        camera_id = block.get("camera_name", key)
        if not isinstance(camera_id, str) or not camera_id:
            raise RigFileError(f"{where} camera_name must be a non-empty string, got {camera_id!r}")
        cameras.append(make_camera(where, camera_id, t_body_optical[:3, 3], body_from_optical(t_body_optical[:3, :3]), lens))
        previous = t_body_optical
        k += 1
    unread = [str(key) for key in data if key not in {f"cam{j}" for j in range(k)}]
    if unread:
        raise RigFileError(f"{path}: block(s) {', '.join(unread)} not read: a camchain numbers its cameras cam0, cam1, "
                           f"... without gaps (read cam0..cam{k - 1}); rename them or remove them")
    origin = origin or RigOrigin()
    why = "--origin" if origin.kind != "vehicle_centre" else "assumed: a camchain does not say; set it with --origin"
    rig = make_rig(str(path), name or path.stem, vehicle, cameras, origin)
    return Imported(rig, (origin_note(origin, why), *notes))


def _lens(block: dict, where: str):
    missing = [k for k in ("intrinsics", "resolution") if k not in block]
    if missing:
        raise RigFileError(f"{where} is missing {missing}; {FIX}")
    model = block.get("camera_model", "pinhole")
    if model != "pinhole":
        raise RigFileError(f"{where} camera_model {model!r} is not supported; rigopt reads pinhole cameras "
                           "(with radtan or equidistant distortion)")
    fx, fy, cx, cy = numbers(block["intrinsics"], (4,), f"{where} intrinsics [fu, fv, pu, pv]")
    resolution = block["resolution"]
    if not isinstance(resolution, list) or len(resolution) != 2:
        raise RigFileError(f"{where} resolution must be [width, height] in pixels, got {resolution!r}")
    width, height = (whole_number(v, f"{where} resolution") for v in resolution)
    distortion = block.get("distortion_model", "none")
    if distortion not in DISTORTION_MODELS:
        raise RigFileError(f"{where} distortion_model {distortion!r} is not supported; use one of "
                           f"{', '.join(DISTORTION_MODELS)}")
    model = DISTORTION_MODELS[distortion]
    raw = block.get("distortion_coeffs", [])
    counts = {"none": (0,), "radtan": (4, 5), "fisheye": (4,)}[model]
    if not isinstance(raw, list) or len(raw) not in counts:
        raise RigFileError(f"{where} distortion_coeffs of a {distortion} camera must be "
                           f"{' or '.join(str(c) for c in counts)} numbers, got {raw!r}")
    coefficients = list(numbers(raw, (len(raw),), f"{where} distortion_coeffs"))
    if model == "radtan" and len(coefficients) == 4:
        coefficients.append(0.0)
    return make_lens(where, width, height, fx, fy, cx, cy, model, coefficients)


def _transform(block: dict, key: str, where: str) -> np.ndarray:
    t = numbers(block[key], (4, 4), f"{where} {key} (4x4)")
    if not np.allclose(t[3], [0.0, 0.0, 0.0, 1.0], atol=1e-12):
        raise RigFileError(f"{where} {key}: the last row of a rigid transform must be [0, 0, 0, 1]")
    out = np.eye(4)
    out[:3, :3] = rotation_matrix(t[:3, :3], f"{where} {key} rotation part")
    out[:3, 3] = t[:3, 3]
    return out


def _pose(block: dict, previous, where: str, k: int) -> tuple[np.ndarray, str | None]:
    """(T_body_optical (4, 4), a note or None) of one camera block."""
    chained = None
    if "T_cn_cnm1" in block and previous is not None:
        chained = previous @ np.linalg.inv(_transform(block, "T_cn_cnm1", where))
    if "T_body_cam" in block:
        pose = _transform(block, "T_body_cam", where)
        if chained is not None and not np.allclose(pose, chained, rtol=0, atol=CHAIN_TOLERANCE):
            raise RigFileError(f"{where}: T_body_cam and T_cn_cnm1 disagree; fix one of them or drop T_cn_cnm1")
        return pose, None
    if "T_cam_imu" in block:
        return np.linalg.inv(_transform(block, "T_cam_imu", where)), None
    if chained is not None:
        return chained, None
    if k > 0:
        raise RigFileError(f"{where} has no T_cn_cnm1, T_cam_imu or T_body_cam; give each camera after cam0 its "
                           "pose (Kalibr's T_cn_cnm1 chain)")
    pose = np.eye(4)
    pose[:3, :3] = R_CAM_OPTICAL
    return pose, "cam0 has no T_cam_imu or T_body_cam: it is placed at the origin looking along +x"


# ------------------------------------------------------------------------------------------------ writing


def yaml_number(value: float) -> str:
    """A float as YAML 1.1 reads it back exactly (always with a dot: PyYAML reads '1e-05' as text)."""
    text = repr(float(value) + 0.0)
    mantissa, _, exponent = text.partition("e")
    if "." not in mantissa:
        mantissa += ".0"
    return mantissa + ("e" + exponent if exponent else "")


def _row(values) -> str:
    return "[" + ", ".join(yaml_number(v) for v in values) + "]"


def _matrix(name: str, t: np.ndarray) -> list[str]:
    return [f"  {name}:"] + [f"  - {_row(row)}" for row in t]


def export_camchain(rig: Rig) -> tuple[str, list[str]]:
    """The camchain YAML text of ``rig`` and warnings for what it does not carry."""
    lines, warnings, previous = [], [], None
    five = []
    for k, camera in enumerate(rig.cameras):
        lens = camera.lens
        t_body_optical = np.eye(4)
        t_body_optical[:3, :3] = optical_from_body(camera.rotation)
        t_body_optical[:3, 3] = camera.position
        model = {"none": "none", "radtan": "radtan", "fisheye": "equidistant"}[lens.distortion]
        coefficients = list(lens.coefficients)
        if lens.distortion == "radtan":
            if coefficients[4] == 0.0:
                coefficients = coefficients[:4]
            else:
                five.append(camera.id)
        lines += [f"cam{k}:", f"  camera_name: {json.dumps(camera.id)}", "  camera_model: pinhole",
                  f"  intrinsics: {_row([lens.fx, lens.fy, lens.cx, lens.cy])}",
                  f"  distortion_model: {model}", f"  distortion_coeffs: {_row(coefficients)}",
                  f"  resolution: [{lens.width}, {lens.height}]", f"  rostopic: {json.dumps('/' + camera.id + '/image_raw')}"]
        lines += _matrix("T_body_cam", t_body_optical)
        if previous is not None:
            lines += _matrix("T_cn_cnm1", np.linalg.inv(t_body_optical) @ previous)
        previous = t_body_optical
    if five:
        warnings.append(f"Kalibr's radtan takes 4 coefficients; the k3 of {', '.join(five)} is written as a fifth "
                        "(OpenCV's order), which Kalibr itself ignores")
    warnings += warn_origin(rig, "A camchain", "vehicle_centre")
    warnings += warn_not_carried(rig, "A camchain", carries_name=False, carries_vehicle=False)
    return "\n".join(lines) + "\n", warnings


def export_opencv(rig: Rig) -> Exported:
    text, warnings = export_camchain(rig)
    return Exported({"": text}, warnings)
