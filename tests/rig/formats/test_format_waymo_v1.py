"""Waymo v1 Frame TFRecords: written here by a small protobuf encoder of the few fields dataset.proto gives
(Frame.context = 1; Context.name = 1, camera_calibrations = 2; CameraCalibration name 1, intrinsic 2, extrinsic
3, width 4, height 5, rolling_shutter_direction 6; Transform.transform = 1) and TFRecord framing with a bitwise
CRC32C written here; the same calibration as a v2 Parquet table gives the same rig; bad files each get one
clear error."""

from __future__ import annotations

import json
import struct

import numpy as np
import pyarrow as pa
import pyarrow.parquet as parquet
import pytest
from in_process import run_rigopt
from scipy.spatial.transform import Rotation

from rigopt.errors import RigFileError
from rigopt.rig.formats.datasets import read_waymo, waymo_calibrations
from rigopt.rig.formats.tfrecord import crc32c
from rigopt.rig.pccr_format import read_rig

SEGMENT = "10203656353524179475_7625_000_7645_000"
#: CameraName -> (yaw, pitch, roll) deg of camera -> vehicle (Waymo's camera frame: x forward, y left, z up),
#: position m, image size px.
POSES = {
    1: ((0.4, -1.2, 0.8), (1.54, -0.02, 2.12), (1920, 1280)),
    2: ((45.3, 0.9, -1.5), (1.50, 0.09, 2.11), (1920, 1280)),
    3: ((-44.8, -0.6, 1.1), (1.49, -0.10, 2.12), (1920, 1280)),
    4: ((90.5, 1.4, 0.3), (1.43, 0.11, 2.11), (1920, 886)),
    5: ((-89.7, -0.8, -0.9), (1.43, -0.11, 2.11), (1920, 886)),
}
INTRINSIC = (2059.6, 2058.9, 944.5, 638.9, 0.0436, -0.3373, 0.0011, -0.0008, 0.0123)


def calibration_values(dx: float = 0.0) -> dict[int, tuple[tuple, tuple, int, int]]:
    """CameraName -> (intrinsic 9, transform 16 row-major, width, height); ``dx`` m added to every x."""
    values = {}
    for number, (angles, position, (width, height)) in POSES.items():
        transform = np.eye(4)
        transform[:3, :3] = Rotation.from_euler("ZYX", angles, degrees=True).as_matrix()
        transform[:3, 3] = np.add(position, [dx, 0.0, 0.0])
        intrinsic = INTRINSIC if number <= 3 else INTRINSIC[:3] + (440.1,) + INTRINSIC[4:]
        values[number] = (intrinsic, tuple(transform.ravel()), width, height)
    return values


# ---------------------------------------------------------------------- protobuf and TFRecord, written here


def varint(value: int) -> bytes:
    value &= (1 << 64) - 1  # negative int32s are written as 64-bit two's complement
    out = bytearray()
    while True:
        byte, value = value & 0x7F, value >> 7
        out.append(byte | (0x80 if value else 0))
        if not value:
            return bytes(out)


def varint_field(number: int, value: int) -> bytes:
    return varint(number << 3) + varint(value)


def bytes_field(number: int, payload: bytes) -> bytes:
    return varint(number << 3 | 2) + varint(len(payload)) + payload


def double_field(number: int, values, packed: bool) -> bytes:
    if packed:
        return bytes_field(number, struct.pack(f"<{len(values)}d", *values))
    return b"".join(varint(number << 3 | 1) + struct.pack("<d", v) for v in values)


def camera_calibration(name: int, intrinsic, transform, width: int, height: int, packed: bool = False) -> bytes:
    return (varint_field(1, name) + double_field(2, intrinsic, packed)
            + bytes_field(3, double_field(1, transform, packed)) + varint_field(4, width) + varint_field(5, height)
            + varint_field(6, 2))


def frame(segment: str | None, calibrations: list[bytes], image: bytes = b"") -> bytes:
    """A Frame: timestamp (2), context (1: name, camera calibrations) and one CameraImage (4) holding ``image``."""
    context = (bytes_field(1, segment.encode()) if segment is not None else b"") + b"".join(
        bytes_field(2, c) for c in calibrations)
    return varint_field(2, 1_557_844_000_000_000) + bytes_field(1, context) + bytes_field(4, bytes_field(2, image))


def frame_of(segment: str | None, values: dict, packed: bool = False, image: bytes = b"") -> bytes:
    return frame(segment, [camera_calibration(n, *v, packed=packed) for n, v in values.items()], image)


def crc32c_bitwise(data: bytes) -> int:
    crc = 0xFFFFFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ (0x82F63B78 if crc & 1 else 0)
    return crc ^ 0xFFFFFFFF


def masked(data: bytes) -> int:
    crc = crc32c_bitwise(data)
    return ((((crc >> 15) | (crc << 17)) & 0xFFFFFFFF) + 0xA282EAD8) & 0xFFFFFFFF


def tfrecord(records: list[bytes]) -> bytes:
    out = b""
    for data in records:
        length = struct.pack("<Q", len(data))
        out += length + struct.pack("<I", masked(length)) + data + struct.pack("<I", masked(data))
    return out


def v2_table(segments: dict[str, dict]) -> pa.Table:
    """The v2 camera_calibration component of ``segments`` (name -> calibration_values)."""
    w = "[CameraCalibrationComponent]."
    keys = ("f_u", "f_v", "c_u", "c_v", "k1", "k2", "p1", "p2", "k3")
    rows: dict[str, list] = {c: [] for c in ("key.segment_context_name", "key.camera_name",
                                             *(f"{w}intrinsic.{k}" for k in keys), f"{w}extrinsic.transform",
                                             f"{w}width", f"{w}height", f"{w}rolling_shutter_direction")}
    for segment, values in segments.items():
        for number, (intrinsic, transform, width, height) in values.items():
            rows["key.segment_context_name"].append(segment)
            rows["key.camera_name"].append(number)
            for key, value in zip(keys, intrinsic):
                rows[f"{w}intrinsic.{key}"].append(value)
            rows[f"{w}extrinsic.transform"].append(list(transform))
            rows[f"{w}width"].append(width)
            rows[f"{w}height"].append(height)
            rows[f"{w}rolling_shutter_direction"].append(2)
    return pa.table({k: pa.array(v, type=pa.int8() if k == "key.camera_name" else None) for k, v in rows.items()})


IMAGE = np.random.default_rng(7).integers(0, 256, 9000, dtype=np.uint8).tobytes()  # past the blocked-CRC size


@pytest.fixture(scope="module")
def segment_file(tmp_path_factory):
    """Three frames of one segment (same context, a 9 kB image each) as a v1 TFRecord."""
    path = tmp_path_factory.mktemp("waymo_v1") / f"segment-{SEGMENT}_with_camera_labels.tfrecord"
    path.write_bytes(tfrecord([frame_of(SEGMENT, calibration_values(), image=IMAGE) for _ in range(3)]))
    return path


# --------------------------------------------------------------------------------------------------- tests


def test_crc32c_check_value_and_blocks_agree_with_the_bitwise_definition():
    assert crc32c(b"123456789") == 0xE3069283
    rng = np.random.default_rng(0)
    for length in (0, 1, 63, 4095, 4096, 4097, 9000, 70001):
        data = rng.integers(0, 256, length, dtype=np.uint8).tobytes()
        assert crc32c(data) == crc32c_bitwise(data), length


def test_v1_and_v2_of_the_same_calibration_are_the_same_rig(segment_file, tmp_path):
    table = tmp_path / "camera_calibration.parquet"
    parquet.write_table(v2_table({SEGMENT: calibration_values()}), table)
    v1, v2 = read_waymo(segment_file), read_waymo(table)
    assert v1.rig.same_as(v2.rig, atol=1e-12)
    assert v1.notes == v2.notes
    assert v1.rig.name == SEGMENT and [c.id for c in v1.rig.cameras] == ["FRONT", "FRONT_LEFT", "FRONT_RIGHT",
                                                                         "SIDE_LEFT", "SIDE_RIGHT"]
    # and both are what the numbers say: Waymo's camera frame is rigopt's body frame
    values = calibration_values()
    for camera, number in zip(v1.rig.cameras, POSES):
        transform = np.reshape(values[number][1], (4, 4))
        np.testing.assert_allclose(camera.rotation, transform[:3, :3], atol=1e-12)
        np.testing.assert_allclose(camera.position, transform[:3, 3], atol=1e-12)
        assert camera.lens.coefficients == values[number][0][4:]
        assert camera.image_size == values[number][2:]


def test_packed_doubles_read_as_the_unpacked(segment_file, tmp_path):
    packed = tmp_path / "packed.tfrecord"
    packed.write_bytes(tfrecord([frame_of(SEGMENT, calibration_values(), packed=True)]))
    assert read_waymo(packed).rig.same_as(read_waymo(segment_file).rig, atol=0.0)


def test_distinct_calibrations_across_segments_and_frames(tmp_path):
    folder = tmp_path / "segments"
    folder.mkdir()
    (folder / "a.tfrecord").write_bytes(tfrecord([frame_of("seg-a", calibration_values())] * 2))
    (folder / "b.tfrecord").write_bytes(tfrecord([frame_of("seg-b", calibration_values(0.05)),
                                                  frame_of("seg-b", calibration_values(0.07))]))
    (folder / "c.tfrecord").write_bytes(tfrecord([frame_of("seg-c", calibration_values())]))
    groups = waymo_calibrations(folder)
    assert [g["segments"] for g in groups] == [["seg-a", "seg-c"], ["seg-b"], ["seg-b (record 1)"]]
    np.testing.assert_allclose(read_waymo(folder, segment="seg-b (record 1)").rig.cameras[0].position[0], 1.61)
    assert read_waymo(folder, calibration=1).rig.name == "seg-b"
    with pytest.raises(RigFileError, match=r"holds 3 distinct calibrations; choose one with --calibration K or "
                                           r"--segment NAME"):
        read_waymo(folder)
    listing = run_rigopt("import", "waymo", folder, "--list", "--json")
    assert listing.returncode == 0, listing.stderr
    assert [row["segments"] for row in json.loads(listing.stdout)] == [g["segments"] for g in groups]


def test_a_tfrecord_without_the_suffix_and_a_segment_without_a_name(tmp_path):
    file = tmp_path / "frames.bin"
    file.write_bytes(tfrecord([frame_of(None, calibration_values())]))
    rig = read_waymo(file).rig
    assert rig.name == "frames" and len(rig) == 5  # Context.name missing: the file's stem


def test_import_command_reads_v1(segment_file, tmp_path):
    out = tmp_path / "waymo.json"
    result = run_rigopt("import", "waymo", segment_file, "--out", out)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(f"wrote {out}: 5 cameras (FRONT, FRONT_LEFT, FRONT_RIGHT, SIDE_LEFT, SIDE_RIGHT)")
    assert read_rig(out, name=SEGMENT).same_as(read_waymo(segment_file).rig, atol=1e-6)
    custom = run_rigopt("import", "waymo", segment_file, "--out", tmp_path / "c.json", "--origin", "custom",
                        "--origin-offset", "-1.2,0,0.1")
    assert custom.returncode == 0, custom.stderr
    assert read_rig(tmp_path / "c.json").origin.point == (-1.2, 0.0, 0.1)


def _write(tmp_path, data: bytes, name: str = "bad.tfrecord"):
    path = tmp_path / name
    path.write_bytes(data)
    return path


def test_damaged_files_name_the_record(tmp_path):
    good = tfrecord([frame_of(SEGMENT, calibration_values(), image=IMAGE)] * 2)
    first = len(good) // 2
    with pytest.raises(RigFileError, match=r"bad\.tfrecord: record 1: truncated \(the record needs"):
        read_waymo(_write(tmp_path, good[:-3]))
    with pytest.raises(RigFileError, match=r"record 1: truncated \(the file ends inside the record's 12-byte header"):
        read_waymo(_write(tmp_path, good[:first + 5]))
    flipped = bytearray(good)
    flipped[first - 100] ^= 0x01  # a byte of record 0's data
    with pytest.raises(RigFileError, match=r"record 0: the CRC of the record's data does not match; the file is damaged"):
        read_waymo(_write(tmp_path, bytes(flipped)))
    flipped = bytearray(good)
    flipped[first + 9] ^= 0x01  # record 1's length CRC
    with pytest.raises(RigFileError, match=r"record 1: the CRC of the record's length does not match"):
        read_waymo(_write(tmp_path, bytes(flipped)))
    with pytest.raises(RigFileError, match=r"bad\.tfrecord: not a TFRecord file"):
        read_waymo(_write(tmp_path, b"segment name, not a record: plain text\n"))


@pytest.mark.parametrize("record, message", [
    (frame(SEGMENT, []), r"record 0: the Frame has no camera calibrations"),
    (varint_field(2, 5), r"record 0: the Frame has no camera calibrations"),  # no context at all
    (frame(SEGMENT, [camera_calibration(7, INTRINSIC, np.eye(4).ravel(), 1920, 1280)]),
     r"camera_calibrations\[0\]: camera name 7 is not a Waymo camera \(1 FRONT, 2 FRONT_LEFT"),
    (frame(SEGMENT, [camera_calibration(0, INTRINSIC, np.eye(4).ravel(), 1920, 1280)]), r"camera name 0 is not"),
    (frame(SEGMENT, [camera_calibration(1, INTRINSIC[:8], np.eye(4).ravel(), 1920, 1280)]),
     r"\(FRONT\) intrinsic \(f_u, .*\): expected numbers of shape \(9,\)"),
    (frame(SEGMENT, [camera_calibration(1, INTRINSIC, np.eye(4).ravel(), -1920, 1280)]),
     r"\(FRONT\) width: expected a positive whole number of pixels, got -1920"),
    (frame(SEGMENT, [camera_calibration(1, INTRINSIC, np.eye(4).ravel(), 1920, 1280)] * 2),
     r"segment .* lists FRONT twice"),
    (bytes_field(1, bytes_field(2, bytes_field(2, b"\x00" * 12))), r"intrinsic: expected doubles"),
    (bytes_field(1, b"\x12\x05\x08"), r"field 2 runs past the end of the message"),
    (b"\x0a\x01\x80", r"a varint runs past the end"),
])
def test_bad_frames(tmp_path, record, message):
    with pytest.raises(RigFileError, match=message):
        read_waymo(_write(tmp_path, tfrecord([record])))


def test_bad_input_through_the_command(tmp_path):
    bad = _write(tmp_path, tfrecord([frame(SEGMENT, [])]))
    result = run_rigopt("import", "waymo", bad, "--out", tmp_path / "r.json")
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("rigopt: error: ")
    assert "no camera calibrations" in result.stderr and not (tmp_path / "r.json").exists()
    empty = tmp_path / "empty_folder"
    empty.mkdir()
    result = run_rigopt("import", "waymo", empty, "--out", tmp_path / "r.json")
    assert result.returncode == 2 and "holds no .parquet or .tfrecord file" in result.stderr
