"""Waymo Open Dataset v1 ``Frame`` TFRecords: the camera calibrations of each frame's context, read from the
protobuf wire format (no TensorFlow, no waymo package; :mod:`rigopt.rig.formats.tfrecord` reads the framing).

The fields read, with their numbers in waymo-open-dataset's ``waymo_open_dataset/dataset.proto`` (proto2)::

    Frame              1 context (Context)
    Context            1 name (string: the segment), 2 camera_calibrations (repeated CameraCalibration)
    CameraCalibration  1 name (CameraName.Name: 1 FRONT, 2 FRONT_LEFT, 3 FRONT_RIGHT, 4 SIDE_LEFT, 5 SIDE_RIGHT),
                       2 intrinsic (repeated double: f_u, f_v, c_u, c_v, k1, k2, p1, p2, k3),
                       3 extrinsic (Transform), 4 width (int32), 5 height (int32),
                       6 rolling_shutter_direction (enum; not modelled)
    Transform          1 transform (repeated double: 4x4 row-major, camera frame -> vehicle frame)

proto2 writes a repeated double one value at a time (wire type 1) unless it is declared packed; both forms are
read. Every other field (images, lidar, labels) is skipped by its length. The values are checked where the
cameras are built (:mod:`rigopt.rig.formats.datasets`, shared with the v2 reader).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

from rigopt.errors import RigFileError
from rigopt.rig.formats.tfrecord import (LENGTH_DELIMITED, VARINT, message_fields, repeated_doubles, signed_int32,
                                         tfrecord_records)

FRAME_CONTEXT = 1
CONTEXT_NAME, CONTEXT_CAMERA_CALIBRATIONS = 1, 2
CALIBRATION_NAME, CALIBRATION_INTRINSIC, CALIBRATION_EXTRINSIC, CALIBRATION_WIDTH, CALIBRATION_HEIGHT = 1, 2, 3, 4, 5
TRANSFORM_VALUES = 1

WHAT = "a Waymo Open Dataset v1 Frame TFRecord (segment-*.tfrecord)"


@dataclass(frozen=True)
class CameraCalibrationRecord:
    """One ``CameraCalibration`` as the file gives it.

    camera : int or None, the CameraName number; intrinsic : tuple of float (9 expected); transform : tuple of
    float (16 expected, row-major camera -> vehicle); width, height : int or None, px; where : the file, record
    and entry, for messages.
    """

    camera: int | None
    intrinsic: tuple[float, ...]
    transform: tuple[float, ...]
    width: int | None
    height: int | None
    where: str


@dataclass(frozen=True)
class FrameContext:
    """The camera calibrations of one frame's context: ``record`` (0-based index in the file), ``segment`` (the
    context's name, else the file's stem) and ``calibrations`` in file order."""

    record: int
    segment: str
    calibrations: tuple[CameraCalibrationRecord, ...]


def frame_contexts(path: Path) -> Iterator[FrameContext]:
    """The distinct frame contexts of a v1 TFRecord file, in file order (the frames of a segment share one
    context, so a context whose bytes were seen before is skipped); a file without records is refused."""
    seen: set[bytes] = set()
    records = 0
    for record, data in tfrecord_records(path, WHAT):
        records += 1
        where = f"{path}: record {record}"
        context = _last_message(data, FRAME_CONTEXT, f"{where} (Frame)")
        digest = hashlib.sha256(context or b"").digest()
        if digest in seen:
            continue
        seen.add(digest)
        segment, calibrations = _read_context(context or b"", where)
        if not calibrations:
            raise RigFileError(f"{where}: the Frame has no camera calibrations (Frame.context.camera_calibrations is "
                               f"empty); pass {WHAT}")
        yield FrameContext(record, segment or Path(path).stem, calibrations)
    if not records:
        raise RigFileError(f"{path}: the TFRecord file holds no records (it is empty), so no Frame and no camera; "
                           f"pass {WHAT} with its frames, or remove this one from the folder")


def _last_message(data: bytes, number: int, where: str) -> bytes | None:
    """The bytes of sub-message field ``number`` (proto2 merges repeats; Frame.context is written once)."""
    found = None
    for field, wire_type, value in message_fields(data, where):
        if field == number:
            if wire_type != LENGTH_DELIMITED:
                raise RigFileError(f"{where}: field {number} must be a message (wire type 2), got wire type {wire_type}")
            found = value if found is None else found + value  # a repeated sub-message merges
    return found


def _read_context(context: bytes, where: str) -> tuple[str, tuple[CameraCalibrationRecord, ...]]:
    name, calibrations = "", []
    for field, wire_type, value in message_fields(context, f"{where} (Frame.context)"):
        if field == CONTEXT_NAME and wire_type == LENGTH_DELIMITED:
            try:
                name = value.decode("utf-8")
            except UnicodeDecodeError:
                raise RigFileError(f"{where}: Frame.context.name is not UTF-8 text") from None
        elif field == CONTEXT_CAMERA_CALIBRATIONS:
            entry = f"{where} camera_calibrations[{len(calibrations)}]"
            if wire_type != LENGTH_DELIMITED:
                raise RigFileError(f"{entry}: must be a message (wire type 2), got wire type {wire_type}")
            calibrations.append(_read_calibration(value, entry))
    return name, tuple(calibrations)


def _read_calibration(data: bytes, where: str) -> CameraCalibrationRecord:
    scalars: dict[int, int] = {}
    intrinsic: list[tuple[int, object]] = []
    extrinsic = b""
    for field, wire_type, value in message_fields(data, where):
        if field in (CALIBRATION_NAME, CALIBRATION_WIDTH, CALIBRATION_HEIGHT):
            if wire_type != VARINT:
                raise RigFileError(f"{where}: field {field} must be a varint, got wire type {wire_type}")
            scalars[field] = signed_int32(value)
        elif field == CALIBRATION_INTRINSIC:
            intrinsic.append((wire_type, value))
        elif field == CALIBRATION_EXTRINSIC:
            if wire_type != LENGTH_DELIMITED:
                raise RigFileError(f"{where}: extrinsic must be a Transform message, got wire type {wire_type}")
            extrinsic += value  # a repeated sub-message merges
    transform = [(wire_type, value) for field, wire_type, value in message_fields(extrinsic, f"{where} extrinsic")
                 if field == TRANSFORM_VALUES]
    return CameraCalibrationRecord(
        camera=scalars.get(CALIBRATION_NAME), intrinsic=repeated_doubles(intrinsic, f"{where} intrinsic"),
        transform=repeated_doubles(transform, f"{where} extrinsic.transform"),
        width=scalars.get(CALIBRATION_WIDTH), height=scalars.get(CALIBRATION_HEIGHT), where=where)
