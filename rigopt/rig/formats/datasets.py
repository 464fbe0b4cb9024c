"""Calibration files of Argoverse 2, DGP (DDAD) and Waymo Open Dataset (v2 and v1) read into :class:`Rig` (import
only).

Argoverse 2 (a log folder, or its ``calibration/`` folder; Apache Feather tables)::

    egovehicle_SE3_sensor.feather: sensor_name, qw, qx, qy, qz, tx_m, ty_m, tz_m   (R_ego_sensor, sensor in ego)
    intrinsics.feather:            sensor_name, fx_px, fy_px, cx_px, cy_px, k1, k2, k3, height_px, width_px

  Camera (sensor) frames are optical (z forward, x right, y down). The imagery is provided undistorted (the
  av2 sensor guide; the av2 API's PinholeCamera uses fx, fy, cx, cy only), so the cameras are pinholes: the
  k1, k2, k3 columns are checked but not applied. Only sensors listed in intrinsics.feather are cameras
  (lidars skipped). The ego-vehicle frame's origin is the centre of the rear axle at the axle's height (the
  guide's example annotations, whose tz_m is the box centre, put the ground 0.33-0.38 m below it): positions
  are raised by ``AV2_ORIGIN_HEIGHT_M`` to rigopt's rear-axle origin on the ground.

DGP / DDAD (a scene folder holding ``calibration/<key>.json`` and ``scene*.json``, or one calibration JSON)::

    {"names": ["CAMERA_01", ..., "LIDAR"],
     "intrinsics": [{"fx", "fy", "cx", "cy", "skew", "fov", "fisheye", "k1".."k6", "p1", "p2"}, ...],
     "extrinsics": [{"translation": {"x", "y", "z"}, "rotation": {"qx", "qy", "qz", "qw"}}, ...]}

  Protobuf JSON leaves out zero values (a missing number is 0). Datums with fx = 0 (lidars) are skipped.
  Extrinsics are sensor poses in the ego frame; camera frames are optical. ``fisheye`` 0 is OpenCV's
  radtan (k4..k6, the rational terms, must be 0); 1 is OpenCV's fisheye (k1..k4). Image sizes come from
  the scene JSON's ``data[].datum.image.{width, height}`` of each camera, else a default (1936 x 1216).

Waymo Open Dataset v2 (a ``camera_calibration`` Parquet file or a folder of them)::

    key.segment_context_name, key.camera_name (1 FRONT, 2 FRONT_LEFT, 3 FRONT_RIGHT, 4 SIDE_LEFT, 5 SIDE_RIGHT),
    [CameraCalibrationComponent].intrinsic.{f_u, f_v, c_u, c_v, k1, k2, p1, p2, k3},
    [CameraCalibrationComponent].extrinsic.transform (16 numbers, row-major camera -> vehicle),
    [CameraCalibrationComponent].{width, height, rolling_shutter_direction}

  Waymo's camera frame is x forward along the optical axis, y left, z up: rigopt's body frame, so the
  extrinsic's rotation is ``R_vehicle_cam`` as it stands. Rolling shutter is not modelled.

Waymo Open Dataset v1 (``Frame`` TFRecord files, ``*.tfrecord``, or a folder of them): each frame's
``context.camera_calibrations`` hold the same numbers as v2's table (:mod:`rigopt.rig.formats.waymo_v1` reads
them) and ``context.name`` is the segment; both versions build their cameras with one function, so the same
calibration gives the same rig.

All three ego frames are ISO 8855 axes with their origin below or at the centre of the rear axle: DDAD's and
Waymo's on the ground, Argoverse 2's at the axle's height (see above).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rigopt.errors import RigFileError
from rigopt.output import existing_file, existing_folder
from rigopt.rig.formats.common import (Imported, choose_calibration, in_modules, make_camera, make_lens, make_rig,
                                       numbers, optical_quaternion_rotation, origin_note, read_json, rotation_matrix,
                                       same_cameras, unit_quaternion, whole_number)
from rigopt.rig.formats.tfrecord import looks_like_tfrecord
from rigopt.rig.formats.waymo_v1 import frame_contexts
from rigopt.rig.model import RigOrigin

REAR_AXLE = RigOrigin("rear_axle")

AV2_POSES = "egovehicle_SE3_sensor.feather"
AV2_INTRINSICS = "intrinsics.feather"
AV2_POSE_COLUMNS = ("sensor_name", "qw", "qx", "qy", "qz", "tx_m", "ty_m", "tz_m")
AV2_INTRINSIC_COLUMNS = ("sensor_name", "fx_px", "fy_px", "cx_px", "cy_px", "k1", "k2", "k3", "height_px", "width_px")

#: Height (m) of the Argoverse 2 ego-vehicle origin (the rear axle's centre) above the ground: the ground lies
#: 0.33-0.38 m below it (median 0.36) in the av2 sensor guide's example annotations, about the wheel radius
#: (0.33 m) of its Ford Fusion Hybrid.
AV2_ORIGIN_HEIGHT_M = 0.35

DGP_IMAGE_SIZE = (1936, 1216)

#: Waymo's cameras sit in one roof cluster: lenses this close (m, chained) are imported as one camera module.
WAYMO_CLUSTER_M = 0.3
WAYMO_CAMERAS = {1: "FRONT", 2: "FRONT_LEFT", 3: "FRONT_RIGHT", 4: "SIDE_LEFT", 5: "SIDE_RIGHT"}
WAYMO = "[CameraCalibrationComponent]."
WAYMO_INTRINSIC = ("f_u", "f_v", "c_u", "c_v", "k1", "k2", "p1", "p2", "k3")
WAYMO_COLUMNS = ("key.segment_context_name", "key.camera_name", *(f"{WAYMO}intrinsic.{k}" for k in WAYMO_INTRINSIC),
                 f"{WAYMO}extrinsic.transform", f"{WAYMO}width", f"{WAYMO}height")


def _origin(origin: RigOrigin | None, frame: str) -> tuple[RigOrigin, str]:
    origin = origin or REAR_AXLE
    return origin, origin_note(origin, frame if origin == REAR_AXLE else "--origin")


def axle_height_origin(origin: RigOrigin | None, frame: str, height_m: float, source: str = ""
                       ) -> tuple[RigOrigin, str, float]:
    """The origin, its stderr note and the height (m) to add to every z for an ego frame whose origin is the rear
    axle's centre at the axle's height (Argoverse 1 and 2): rigopt's rear-axle origin is on the ground below it.

    origin : the user's ``--origin`` (None: the format's own); with one, the file's positions are taken as they are
    (raised by 0). height_m : the axle's height above the ground; source : words after the note saying where it
    comes from, e.g. " (--axle-height)".
    """
    if origin is not None:
        return origin, origin_note(origin, "--origin"), 0.0
    note = (f"{origin_note(REAR_AXLE, frame)}; its origin is at the rear axle's height, so positions are raised by "
            f"{height_m:.3g} m to the ground below it{source}")
    return REAR_AXLE, note, float(height_m)


def _read_arrow(path: Path, columns: tuple[str, ...], what: str, fix: str, parquet: bool = False) -> dict:
    """Columns of a Feather or Parquet table as Python lists; errors name the file and the missing columns."""
    try:
        if parquet:
            import pyarrow.parquet as reader
        else:
            import pyarrow.feather as reader
    except ImportError:  # pragma: no cover - pyarrow is a core dependency
        raise RigFileError(f"{path}: reading {what} needs pyarrow; pip install pyarrow") from None
    existing_file(path, what, fix, kind=RigFileError)
    try:
        table = reader.read_table(path)
    except Exception:  # pyarrow raises several kinds for a file that is not its format
        kind = "Parquet" if parquet else "Feather"
        raise RigFileError(f"{path}: not a readable {what} (pyarrow cannot read it as {kind}); {fix}") from None
    missing = [c for c in columns if c not in table.column_names]
    if missing:
        raise RigFileError(f"{path}: the {what} lacks columns {missing}; {fix}")
    return {c: table.column(c).to_pylist() for c in columns}


# --------------------------------------------------------------------------------------------- Argoverse 2


def read_argoverse2(path, name: str | None = None, vehicle: str = "argoverse2",
                    origin: RigOrigin | None = None) -> Imported:
    """Read the cameras of an Argoverse 2 log (its folder or its calibration/ folder)."""
    path = existing_folder(path, f"{AV2_POSES} and {AV2_INTRINSICS} (an Argoverse 2 log's calibration/ folder, "
                                 "or the log folder holding it)", kind=RigFileError)
    folder = path / "calibration" if (path / "calibration").is_dir() else path
    fix = f"an Argoverse 2 calibration folder holds {AV2_POSES} and {AV2_INTRINSICS}"
    poses = _read_arrow(folder / AV2_POSES, AV2_POSE_COLUMNS, "Argoverse 2 sensor pose table", fix)
    intrinsics = _read_arrow(folder / AV2_INTRINSICS, AV2_INTRINSIC_COLUMNS, "Argoverse 2 intrinsics table", fix)
    pose_rows = {n: k for k, n in enumerate(poses["sensor_name"])}
    origin, note, raise_by = axle_height_origin(origin, "Argoverse 2 ego-vehicle frame", AV2_ORIGIN_HEIGHT_M)
    cameras = []
    for k, sensor in enumerate(intrinsics["sensor_name"]):
        where = f"{folder / AV2_INTRINSICS}: row {k} ({sensor})"
        if not isinstance(sensor, str) or not sensor:
            raise RigFileError(f"{where}: sensor_name must be a non-empty string")
        if sensor not in pose_rows:
            raise RigFileError(f"{where}: {AV2_POSES} has no pose for {sensor}; use the two tables of one log")
        row = pose_rows[sensor]
        pose_where = f"{folder / AV2_POSES}: row {row} ({sensor})"
        q = unit_quaternion([poses[c][row] for c in ("qw", "qx", "qy", "qz")], f"{pose_where} qw, qx, qy, qz")
        t = numbers([poses[c][row] for c in ("tx_m", "ty_m", "tz_m")], (3,), f"{pose_where} tx_m, ty_m, tz_m")
        fx, fy, cx, cy = numbers([intrinsics[c][k] for c in AV2_INTRINSIC_COLUMNS[1:5]], (4,), where)
        numbers([intrinsics[c][k] for c in ("k1", "k2", "k3")], (3,), f"{where} k1, k2, k3")  # checked, not applied
        width = whole_number(intrinsics["width_px"][k], f"{where} width_px")
        height = whole_number(intrinsics["height_px"][k], f"{where} height_px")
        lens = make_lens(where, width, height, fx, fy, cx, cy)
        position = t + np.array([0.0, 0.0, raise_by])
        cameras.append(make_camera(where, sensor, position, optical_quaternion_rotation(q), lens))
    notes = (note, "Argoverse 2 imagery is undistorted: k1, k2, k3 are not applied (pinhole cameras)")
    default_name = path.name if folder != path else path.resolve().parent.name
    rig = make_rig(str(folder / AV2_INTRINSICS), name or default_name, vehicle, cameras, origin)
    return Imported(rig, notes)


# ----------------------------------------------------------------------------------------------------- DGP


def dgp_calibration_files(path: Path) -> list[Path]:
    """The calibration JSON files of a DGP scene folder (sorted), or [path] for a file."""
    if path.is_file():
        return [path]
    if not path.is_dir():
        raise RigFileError(f"{path}: no such file or directory; pass a DGP scene folder (holding calibration/) "
                           "or a calibration JSON file")
    folder = path / "calibration" if (path / "calibration").is_dir() else path
    files = sorted(folder.glob("*.json"))
    if not files:
        raise RigFileError(f"{folder}: holds no calibration JSON; pass a DGP scene folder (holding calibration/) "
                           "or a calibration JSON file")
    return files


def read_dgp(path, image_size=DGP_IMAGE_SIZE, calibration: int | None = None, name: str | None = None,
             vehicle: str = "dgp", origin: RigOrigin | None = None) -> Imported:
    """Read the cameras of a DGP (DDAD) scene: its one distinct calibration, or the ``calibration``-th."""
    path = Path(path)
    files = dgp_calibration_files(path)
    scene_folder = path if path.is_dir() else path.parent.parent
    sizes = _dgp_image_sizes(scene_folder)
    rigs = []
    for file in files:
        cameras, defaulted, skipped = _dgp_cameras(file, sizes, image_size)
        if not any(same_cameras(cameras, other[0]) for other in rigs):
            rigs.append((cameras, defaulted, skipped, file))
    cameras, defaulted, skipped, file = choose_calibration(rigs, calibration, str(path), "--calibration K")
    origin, note = _origin(origin, "DDAD ego frame")
    default_name = scene_folder.resolve().name
    rig = make_rig(str(file), name or default_name, vehicle, cameras, origin)
    notes = [note]
    if defaulted:
        notes.append(f"image size {image_size[0]}x{image_size[1]} assumed for {', '.join(defaulted)} (no scene JSON "
                     "gives it; set it with --image-size)")
    if skipped:
        notes.append(f"{', '.join(skipped)} left out: no camera model (fx 0: a lidar or another sensor); give a "
                     "camera its intrinsics to import it")
    return Imported(rig, tuple(notes))


def dgp_calibrations(path, image_size=DGP_IMAGE_SIZE) -> list[dict]:
    """Rows for ``--list``: each distinct calibration with its files."""
    path = Path(path)
    files = dgp_calibration_files(path)
    sizes = _dgp_image_sizes(path if path.is_dir() else path.parent.parent)
    rows: list[dict] = []
    for file in files:
        cameras, _, _ = _dgp_cameras(file, sizes, image_size)
        for row in rows:
            if same_cameras(cameras, row["_cameras"]):
                row["files"].append(file.name)
                break
        else:
            rows.append({"_cameras": cameras, "files": [file.name]})
    return [{"calibration": k, "cameras": [c.id for c in r["_cameras"]], "files": r["files"]}
            for k, r in enumerate(rows)]


def _dgp_image_sizes(folder: Path) -> dict[str, tuple[int, int]]:
    """Camera name -> (width, height) from the scene JSON files of ``folder`` (first found wins)."""
    sizes: dict[str, tuple[int, int]] = {}
    for scene in sorted(folder.glob("scene*.json")) if folder.is_dir() else ():
        data = read_json(scene, "DGP scene JSON", "use the scene JSON of a DGP dataset")
        for k, datum in enumerate(data.get("data", []) if isinstance(data, dict) else []):
            image = (datum.get("datum") or {}).get("image") if isinstance(datum, dict) else None
            camera = (datum.get("id") or {}).get("name") if isinstance(datum, dict) else None
            if not isinstance(image, dict) or not isinstance(camera, str) or camera in sizes:
                continue
            where = f"{scene}: data {k} ({camera}) image"
            sizes[camera] = (whole_number(image.get("width"), f"{where} width"),
                             whole_number(image.get("height"), f"{where} height"))
    return sizes


def _dgp_number(entry: dict, key: str, where: str) -> float:
    value = entry.get(key, 0.0)
    return float(numbers([value], (1,), f"{where} {key}")[0])


def _dgp_cameras(file: Path, sizes: dict, image_size) -> tuple[tuple, list[str], list[str]]:
    """(cameras, the camera names whose image size was assumed, the datums skipped as no camera: fx 0)."""
    data = read_json(file, "DGP calibration JSON", "use a calibration/<key>.json of a DGP scene")
    if not isinstance(data, dict) or not all(isinstance(data.get(k), list) for k in ("names", "intrinsics", "extrinsics")):
        raise RigFileError(f"{file}: a DGP calibration is a JSON object with lists 'names', 'intrinsics' and "
                           "'extrinsics'")
    names, intrinsics, extrinsics = data["names"], data["intrinsics"], data["extrinsics"]
    if not len(names) == len(intrinsics) == len(extrinsics):
        raise RigFileError(f"{file}: 'names', 'intrinsics' and 'extrinsics' must be as long as each other, got "
                           f"{len(names)}, {len(intrinsics)} and {len(extrinsics)}")
    cameras, defaulted, skipped = [], [], []
    for k, (sensor, intrinsic, extrinsic) in enumerate(zip(names, intrinsics, extrinsics)):
        where = f"{file}: datum {k} ({sensor})"
        if not isinstance(sensor, str) or not isinstance(intrinsic, dict) or not isinstance(extrinsic, dict):
            raise RigFileError(f"{where}: names are strings, intrinsics and extrinsics objects")
        if _dgp_number(intrinsic, "fx", where) == 0.0:
            skipped.append(sensor)  # a lidar or other datum without a camera model: said in a note
            continue
        fx, fy, cx, cy, skew = (_dgp_number(intrinsic, key, where) for key in ("fx", "fy", "cx", "cy", "skew"))
        if skew != 0.0:
            raise RigFileError(f"{where}: skew {skew:g} is not supported; rigopt's lenses have no skew")
        coefficient = {key: _dgp_number(intrinsic, key, where) for key in
                       ("k1", "k2", "k3", "k4", "k5", "k6", "p1", "p2")}
        fisheye = intrinsic.get("fisheye", 0)
        if fisheye == 0:
            rational = [key for key in ("k4", "k5", "k6") if coefficient[key] != 0.0]
            if rational:
                raise RigFileError(f"{where}: the rational terms {rational} are not supported (rigopt's radtan has "
                                   "k1, k2, p1, p2, k3)")
            model, values = "radtan", [coefficient[key] for key in ("k1", "k2", "p1", "p2", "k3")]
        elif fisheye == 1:
            model, values = "fisheye", [coefficient[key] for key in ("k1", "k2", "k3", "k4")]
        else:
            raise RigFileError(f"{where}: fisheye {fisheye!r} is not supported; 0 (radtan) and 1 (OpenCV fisheye) are")
        translation, rotation = extrinsic.get("translation", {}), extrinsic.get("rotation", {})
        if not isinstance(translation, dict) or not isinstance(rotation, dict):
            raise RigFileError(f"{where}: extrinsics need 'translation' {{x, y, z}} and 'rotation' {{qx, qy, qz, qw}}")
        position = [_dgp_number(translation, key, f"{where} translation") for key in "xyz"]
        q = unit_quaternion([_dgp_number(rotation, key, f"{where} rotation") for key in ("qw", "qx", "qy", "qz")],
                            f"{where} rotation quaternion")
        size = sizes.get(sensor)
        if size is None:
            size = tuple(image_size)
            defaulted.append(sensor)
        lens = make_lens(where, size[0], size[1], fx, fy, cx, cy, model, values)
        cameras.append(make_camera(where, sensor, position, optical_quaternion_rotation(q), lens))
    return tuple(cameras), defaulted, skipped


# --------------------------------------------------------------------------------------------------- Waymo


WAYMO_FILES = "a Waymo v2 camera_calibration Parquet file or folder, or Waymo v1 Frame .tfrecord files (or their folder)"


def _waymo_files(path: Path) -> list[Path]:
    """The Parquet (v2) and TFRecord (v1) files of ``path``: itself, or a folder's (its camera_calibration/)."""
    if path.is_file():
        return [path]
    if path.is_dir():
        folder = path / "camera_calibration" if (path / "camera_calibration").is_dir() else path
        files = sorted(folder.glob("*.parquet")) + sorted(folder.glob("*.tfrecord"))
        if files:
            return files
        raise RigFileError(f"{folder}: holds no .parquet or .tfrecord file; pass {WAYMO_FILES}")
    raise RigFileError(f"{path}: no such file or directory; pass {WAYMO_FILES}")


def _is_v1(file: Path) -> bool:
    """A v1 Frame TFRecord: by its suffix, or (any other name) a first record whose length CRC matches."""
    return file.suffix in (".tfrecord", ".tfrecords") or (file.suffix != ".parquet" and looks_like_tfrecord(file))


def _waymo_camera(where: str, number: int, intrinsic, transform, width, height):
    """One Waymo camera (v1 and v2 alike): CameraName ``number``, intrinsic (9: f_u, f_v, c_u, c_v, k1, k2, p1,
    p2, k3), transform (16, row-major camera -> vehicle; Waymo's camera frame is rigopt's body frame), image size."""
    values = numbers(intrinsic, (9,), f"{where} intrinsic (f_u, f_v, c_u, c_v, k1, k2, p1, p2, k3)")
    t = numbers(transform, (16,), f"{where} extrinsic.transform (16 numbers, row-major)").reshape(4, 4)
    if not np.allclose(t[3], [0.0, 0.0, 0.0, 1.0], atol=1e-9):
        raise RigFileError(f"{where}: extrinsic.transform's last row must be [0, 0, 0, 1]")
    rotation = rotation_matrix(t[:3, :3], f"{where} extrinsic.transform rotation")
    lens = make_lens(where, whole_number(width, f"{where} width"), whole_number(height, f"{where} height"),
                     *values[:4], "radtan", values[4:])
    return make_camera(where, WAYMO_CAMERAS[number], t[:3, 3], rotation, lens)


def _add_camera(cameras: list, camera, segment: str, where: str) -> None:
    if any(c.id == camera.id for c in cameras):
        raise RigFileError(f"{where}: segment {segment} lists {camera.id} twice")
    cameras.append(camera)


def _waymo_v2_segments(file: Path, segments: dict[str, list]) -> None:
    """Add the cameras of a v2 camera_calibration table to ``segments`` (segment name -> cameras)."""
    fix = "use the camera_calibration component of the Waymo Open Dataset v2"
    table = _read_arrow(file, WAYMO_COLUMNS, "Waymo v2 camera_calibration table", fix, parquet=True)
    if not table["key.camera_name"]:
        raise RigFileError(f"{file}: the Waymo v2 camera_calibration table has its columns but no rows, so no camera; "
                           "pass the camera_calibration file of a segment (one row per camera), or remove this one "
                           "from the folder")
    for k in range(len(table["key.camera_name"])):
        segment = table["key.segment_context_name"][k]
        number = table["key.camera_name"][k]
        where = f"{file}: row {k}"
        if not isinstance(segment, str) or number not in WAYMO_CAMERAS:
            raise RigFileError(f"{where}: key.segment_context_name must be text and key.camera_name one of "
                               f"{sorted(WAYMO_CAMERAS)}, got {segment!r}, {number!r}")
        where = f"{where} ({WAYMO_CAMERAS[number]})"
        camera = _waymo_camera(where, number, [table[f"{WAYMO}intrinsic.{key}"][k] for key in WAYMO_INTRINSIC],
                               table[f"{WAYMO}extrinsic.transform"][k], table[f"{WAYMO}width"][k],
                               table[f"{WAYMO}height"][k])
        _add_camera(segments.setdefault(segment, []), camera, segment, where)


def _waymo_v1_segments(file: Path, segments: dict[str, list]) -> None:
    """Add the cameras of each distinct frame context of a v1 TFRecord to ``segments``; a segment whose frames
    disagree gets one entry per calibration, the later ones named "SEGMENT (record K)"."""
    for context in frame_contexts(file):
        cameras: list = []
        for entry in context.calibrations:
            if entry.camera not in WAYMO_CAMERAS:
                known = ", ".join(f"{k} {name}" for k, name in WAYMO_CAMERAS.items())
                raise RigFileError(f"{entry.where}: camera name {entry.camera!r} is not a Waymo camera ({known})")
            where = f"{entry.where} ({WAYMO_CAMERAS[entry.camera]})"
            camera = _waymo_camera(where, entry.camera, entry.intrinsic, entry.transform, entry.width, entry.height)
            _add_camera(cameras, camera, context.segment, where)
        name = context.segment
        if name in segments and not same_cameras(_in_waymo_order(segments[name]), _in_waymo_order(cameras)):
            name = f"{context.segment} (record {context.record})"
        segments.setdefault(name, cameras)


def _in_waymo_order(cameras) -> tuple:
    order = {name: k for k, name in WAYMO_CAMERAS.items()}
    return tuple(sorted(cameras, key=lambda c: order[c.id]))


def waymo_segments(path) -> list[tuple[str, tuple]]:
    """(segment name, cameras) of every segment in Waymo v2 camera_calibration Parquet or v1 Frame TFRecord files
    (a file or a folder), in file order."""
    segments: dict[str, list] = {}
    for file in _waymo_files(Path(path)):
        if _is_v1(file):
            _waymo_v1_segments(file, segments)
        else:
            _waymo_v2_segments(file, segments)
    return [(segment, _in_waymo_order(cameras)) for segment, cameras in segments.items()]


def waymo_calibrations(path) -> list[dict]:
    """The distinct calibrations of the segments, each with its segments (for ``--list`` and choosing)."""
    groups: list[dict] = []
    for segment, cameras in waymo_segments(path):
        for group in groups:
            if same_cameras(group["cameras"], cameras):
                group["segments"].append(segment)
                break
        else:
            groups.append({"cameras": cameras, "segments": [segment]})
    return groups


def read_waymo(path, calibration: int | None = None, segment: str | None = None, name: str | None = None,
               vehicle: str = "waymo", origin: RigOrigin | None = None) -> Imported:
    """Read the cameras of Waymo v2 camera_calibration or v1 Frame TFRecords: one segment's, or the K-th distinct
    calibration."""
    groups = waymo_calibrations(path)
    if segment is not None:
        chosen = next((g for g in groups if segment in g["segments"]), None)
        if chosen is None:
            known = [s for g in groups for s in g["segments"]]
            raise RigFileError(f"{path}: --segment {segment!r} is not in the table; segments: "
                               f"{', '.join(known[:6])}{', ...' if len(known) > 6 else ''}")
    else:
        chosen = choose_calibration(groups, calibration, str(path), "--calibration K or --segment NAME")
    origin, note = _origin(origin, "Waymo vehicle frame")
    cameras, module_notes = in_modules(chosen["cameras"], WAYMO_CLUSTER_M, "roof_cluster")
    rig = make_rig(str(path), name or (segment or chosen["segments"][0]), vehicle, cameras, origin)
    return Imported(rig, (note, *module_notes, "rolling shutter is not modelled: cameras are taken as global shutter"))
