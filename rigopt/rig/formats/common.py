"""Pieces every format reader and writer shares: checked numbers and files, frames, lenses, results.

Frames
------
rigopt's vehicle frame is ISO 8855 (x forward, y left, z up, metres); a camera's body frame has x along the
optical axis, y left, z up; the optical frame (OpenCV, ROS ``*_optical_frame``) has z along the axis, x right,
y down. ``R_CAM_OPTICAL`` maps optical directions into the body frame, so a file's ``R_ego_optical`` gives
rigopt's ``R_vehicle_cam = R_ego_optical @ R_CAM_OPTICAL.T`` (:func:`rigopt.geometry.body_from_optical`; the frames
and every rotation are rigopt.geometry's).

Pixels
------
Intrinsics (fx, fy, cx, cy) are taken as the files give them; rigopt's :class:`rigopt.camera.Lens` puts
the image's top-left corner at (0, 0). OpenCV's convention puts the top-left pixel's centre there, half a
pixel off: the principal point differs by 0.5 px, which moves a FOV by less than 0.02 deg on a 1000 px
image. Writers give the numbers back unchanged, so round trips are exact.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from rigopt.camera import Lens
from rigopt.errors import RigFileError, RigoptError, json_loads, not_utf8
from rigopt.geometry import body_from_optical, nearest_rotation, quaternion_to_matrix
from rigopt.output import existing_file
from rigopt.rig.model import Camera, Rig, RigOrigin

#: A quaternion whose norm is further than this from 1 is rejected; closer ones are normalised.
QUATERNION_NORM_TOLERANCE = 1e-3
#: A rotation matrix further than this (any entry of R R^T - I) from orthonormal is rejected.
ROTATION_TOLERANCE = 1e-6
#: Two calibrations are the same when positions agree within this (m), rotations (matrix entries) and
#: intrinsics (px, coefficients) within these.
SAME_POSITION_M, SAME_ROTATION, SAME_INTRINSIC = 1e-6, 1e-9, 1e-6


@dataclass(frozen=True)
class Imported:
    """What a reader gives: the rig and one-line notes for stderr (its origin first, then defaults used)."""

    rig: Rig
    notes: tuple[str, ...] = ()


@dataclass
class Exported:
    """What a writer gives: files (name relative to the output -> text) and one-line warnings for stderr
    (what the format could not carry)."""

    files: dict[str, str] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)


def origin_note(origin: RigOrigin, why: str) -> str:
    """'origin: rear axle (nuScenes ego frame)' and the like."""
    return f"origin: {origin.describe()} ({why})"


def read_text(path: Path, what: str, fix: str) -> str:
    """The UTF-8 text of ``path``; a RigFileError naming the file, what it should be (``what``, e.g. "URDF"),
    and ``fix``: "no such URDF file", "is a folder; give the URDF file itself", unreadable, not UTF-8."""
    path = Path(path)
    existing_file(path, f"{what} file", fix, kind=RigFileError)
    try:
        return path.read_text()
    except OSError as error:
        raise RigFileError(f"{path}: cannot read the {what} ({error.strerror}); {fix}") from None
    except UnicodeDecodeError as error:
        raise not_utf8(path, what, error, RigFileError) from None


def read_json(path: Path, what: str, fix: str):
    """The parsed JSON of ``path`` (see :func:`read_text`)."""
    path = Path(path)
    text = read_text(path, what, fix)
    try:
        return json_loads(text)
    except json.JSONDecodeError as error:
        raise RigFileError(f"{path}: not valid JSON (line {error.lineno}, column {error.colno}: {error.msg}); "
                           f"the {what} must be JSON") from None


def is_number(value) -> bool:
    """True for an int or float (numpy ones too), not a bool."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def numbers(values, shape: tuple[int, ...], where: str) -> np.ndarray:
    """``values`` as a finite float array of ``shape``; numbers only (no bools, no strings, no None)."""
    try:
        array = np.array(values, dtype=object)
    except ValueError:
        array = np.array(None)
    if array.shape != shape or not all(is_number(v) for v in array.flat):
        raise RigFileError(f"{where}: expected numbers of shape {shape}, got {_short(values)}")
    array = array.astype(float)
    if not np.all(np.isfinite(array)):
        raise RigFileError(f"{where}: NaN or inf is not allowed, got {_short(values)}")
    return array


def whole_number(value, where: str) -> int:
    """A positive whole number of pixels."""
    if not is_number(value) or not float(value).is_integer() or value <= 0:
        raise RigFileError(f"{where}: expected a positive whole number of pixels, got {_short(value)}")
    return int(value)


def _short(value) -> str:
    text = repr(value.tolist() if isinstance(value, np.ndarray) else value)
    return text if len(text) <= 80 else text[:77] + "..."


def unit_quaternion(values, where: str, order: str = "wxyz") -> np.ndarray:
    """A (w, x, y, z) unit quaternion from ``values`` given in ``order`` ("wxyz" or "xyzw")."""
    q = numbers(values, (4,), where)
    if order == "xyzw":
        q = q[[3, 0, 1, 2]]
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE:
        raise RigFileError(f"{where}: must be a unit quaternion, its norm is {norm:.6g}")
    return q / norm


def rotation_matrix(values, where: str) -> np.ndarray:
    """A proper 3x3 rotation matrix from ``values``; slightly off ones are re-orthonormalised (SVD)."""
    r = numbers(values, (3, 3), where)
    if np.max(np.abs(r @ r.T - np.eye(3))) > 1e-3 or np.linalg.det(r) < 0:
        raise RigFileError(f"{where}: not a rotation (orthonormal with determinant +1)")
    return nearest_rotation(r)


def optical_quaternion_rotation(q: np.ndarray) -> np.ndarray:
    """rigopt's ``R_vehicle_cam`` (3, 3) of a camera whose optical frame's orientation in the ego frame is the
    (w, x, y, z) unit quaternion ``q`` (nuScenes, Argoverse 1 and 2, DGP)."""
    return body_from_optical(quaternion_to_matrix(q))


def make_lens(where: str, width, height, fx, fy, cx, cy, distortion="none", coefficients=()) -> Lens:
    """A :class:`Lens`, its complaints (RigoptError) turned into a RigFileError that names ``where``. All-zero
    coefficients give a "none" lens (the same geometry, one way to say it)."""
    if all(c == 0 for c in coefficients):
        distortion, coefficients = "none", ()
    try:
        return Lens(width, height, fx, fy, cx, cy, distortion, tuple(coefficients))
    except RigoptError as error:
        raise RigFileError(f"{where}: {error}") from None


def make_camera(where: str, camera_id: str, position, rotation, lens: Lens) -> Camera:
    """A camera with a real lens (FOV and image size read from it)."""
    try:
        return Camera(camera_id, position, rotation, lens)
    except RigoptError as error:
        raise RigFileError(f"{where}: {error}") from None


def in_modules(cameras, within_m: float, name: str) -> tuple[tuple[Camera, ...], list[str]]:
    """``cameras`` with the groups whose lenses lie within ``within_m`` of each other (chained) put in one camera
    module each (``Camera.module``: one housing), named ``name`` (``name_1``, ``name_2``, ... for several), and
    a note per module for stderr. Cameras far from every other keep no module."""
    cameras = list(cameras)
    group = list(range(len(cameras)))

    def root(k):
        while group[k] != k:
            k = group[k]
        return k

    for a in range(len(cameras)):
        for b in range(a + 1, len(cameras)):
            if np.linalg.norm(cameras[a].position - cameras[b].position) <= within_m:
                group[root(b)] = root(a)
    members: dict[int, list[int]] = {}
    for k in range(len(cameras)):
        members.setdefault(root(k), []).append(k)
    modules = [m for m in members.values() if len(m) > 1]
    notes = []
    for number, module in enumerate(modules, 1):
        label = name if len(modules) == 1 else f"{name}_{number}"
        for k in module:
            cameras[k] = replace(cameras[k], module=label)
        notes.append(f"module {label}: {', '.join(cameras[k].id for k in module)} (lenses within {within_m:g} m of "
                     "each other share one housing)")
    return tuple(cameras), notes


def make_rig(where: str, name: str, vehicle: str, cameras, origin: RigOrigin) -> Rig:
    """A rig; its complaints (no camera, repeated ids) name ``where``."""
    try:
        return Rig(name, vehicle, tuple(cameras), origin)
    except RigoptError as error:
        raise RigFileError(f"{where}: {error}") from None


def same_pose_and_lens(a: Camera, b: Camera) -> bool:
    """True when two cameras hold the same calibration (id aside) within the SAME_* tolerances."""
    la, lb = a.lens, b.lens
    return (np.allclose(a.position, b.position, rtol=0, atol=SAME_POSITION_M)
            and np.allclose(a.rotation, b.rotation, rtol=0, atol=SAME_ROTATION)
            and la.image_size == lb.image_size and la.distortion == lb.distortion
            and np.allclose([la.fx, la.fy, la.cx, la.cy, *la.coefficients],
                            [lb.fx, lb.fy, lb.cx, lb.cy, *lb.coefficients], rtol=0, atol=SAME_INTRINSIC))


def same_cameras(a: tuple[Camera, ...], b: tuple[Camera, ...]) -> bool:
    """True when two camera sets have the same ids in the same order and the same calibrations."""
    return (len(a) == len(b) and all(x.id == y.id and same_pose_and_lens(x, y) for x, y in zip(a, b)))


def choose_calibration(calibrations: list, index: int | None, where: str, how: str):
    """The ``index``-th of the distinct ``calibrations`` (0-based), or the only one when ``index`` is None."""
    if not calibrations:
        raise RigFileError(f"{where}: holds no camera calibration; a rig needs at least one camera")
    if index is not None:
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < len(calibrations):
            raise RigFileError(f"{where}: --calibration {index} is out of range; there are {len(calibrations)} "
                               f"distinct calibration(s), numbered 0..{len(calibrations) - 1} (see --list)")
        return calibrations[index]
    if len(calibrations) > 1:
        raise RigFileError(f"{where}: holds {len(calibrations)} distinct calibrations; choose one with {how} "
                           "(--list shows them)")
    return calibrations[0]


def format_number(value: float) -> str:
    """Shortest text that reads back to the same float (repr), -0.0 written as 0.0."""
    return repr(float(value) + 0.0)


def warn_not_carried(rig: Rig, format_name: str, carries_name: bool, carries_vehicle: bool) -> list[str]:
    """Warnings for the rig-level things ``format_name`` does not carry (name, vehicle, zones, modules, roles)."""
    lost, options = [], []
    if not carries_name:
        lost.append(f"the rig's name {rig.name!r}")
        options.append("--name")
    if not carries_vehicle:
        lost.append(f"the vehicle {rig.vehicle!r}")
        options.append("--vehicle")
    zoned = [c.id for c in rig.cameras if c.zone is not None]
    if zoned:
        lost.append(f"the mounting zones of {len(zoned)} camera(s)")
    grouped = [c.id for c in rig.cameras if c.module is not None]
    if grouped:
        lost.append(f"the camera modules of {len(grouped)} camera(s)")
    if rig.near_field_count:
        lost.append(f"the near_field role of {rig.near_field_count} camera(s) (read back as perception)")
    if not lost:
        return []
    again = f"; give {' and '.join(options)} on import" if options else ""
    return [f"{format_name} does not carry {', '.join(lost)}{again}"]


def warn_origin(rig: Rig, format_name: str, native: str) -> list[str]:
    """A warning when the rig's origin is not the one ``format_name``'s readers assume (``native``)."""
    if rig.origin.kind == native:
        return []
    native_words = RigOrigin(native).describe() if native != "custom" else native
    return [f"{format_name} positions are read as measured from the {native_words}; {rig.name}'s are measured "
            f"from the {rig.origin.describe()} and are written unchanged (import them back with "
            f"--origin {rig.origin.kind})" if rig.origin.kind != "custom" else
            f"{format_name} positions are read as measured from the {native_words}; {rig.name}'s are measured "
            f"from a {rig.origin.describe()} and are written unchanged; the origin point is lost"]
