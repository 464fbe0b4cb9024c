"""TFRecord files of protobuf messages, read without TensorFlow or protobuf: the record framing with its CRC32C
checks, and the protobuf wire format.

TFRecord (what TensorFlow's ``tf.io.TFRecordWriter`` writes), record after record::

    uint64 length (little-endian) | uint32 masked CRC32C of those 8 bytes | data | uint32 masked CRC32C of data

  masked(crc) = ((crc >> 15) | (crc << 17)) + 0xA282EAD8, modulo 2^32. CRC32C is the Castagnoli CRC: reflected
  polynomial 0x82F63B78, initial value and final XOR 0xFFFFFFFF (the check value of b"123456789" is 0xE3069283).

Protobuf wire format: a message is a run of fields, each a varint key (field number << 3 | wire type) and a
value: wire type 0 a varint, 1 eight bytes (fixed64, double), 2 a varint length and that many bytes (string,
bytes, sub-message or packed repeated field), 5 four bytes (fixed32, float). Groups (wire types 3 and 4,
deprecated) are not read.
"""

from __future__ import annotations

import struct
from functools import lru_cache
from pathlib import Path
from typing import Iterator

import numpy as np

from rigopt.errors import RigFileError
from rigopt.output import existing_file

#: CRC32C's polynomial, bit-reflected.
CASTAGNOLI = 0x82F63B78
#: TFRecord's mask constant.
MASK_DELTA = 0xA282EAD8
#: Below this many bytes the CRC runs byte by byte; above, in blocks computed side by side (numpy).
BLOCKED_CRC_MIN_BYTES = 4096
#: Wire types.
VARINT, FIXED64, LENGTH_DELIMITED, FIXED32 = 0, 1, 2, 5


def _byte_table() -> np.ndarray:
    """(256,) uint32: the CRC register after one byte, for each value of the register's low byte xor the byte."""
    table = np.arange(256, dtype=np.uint32)
    for _ in range(8):
        table = np.where(table & 1, (table >> 1) ^ np.uint32(CASTAGNOLI), table >> 1).astype(np.uint32)
    return table


_TABLE = _byte_table()
_TABLE_LIST = [int(v) for v in _TABLE]


def _register_bytewise(register: int, data) -> int:
    """The CRC register (no initial or final XOR) after ``data``, one byte at a time."""
    table = _TABLE_LIST
    for byte in bytes(data):
        register = table[(register ^ byte) & 0xFF] ^ (register >> 8)
    return register


@lru_cache(maxsize=8)
def _zeros_operator(length: int) -> tuple[list[int], list[int], list[int], list[int]]:
    """The register after ``length`` zero bytes as a function of the register before, which is linear over GF(2):
    four 256-entry tables, one per byte of the register before, whose entries are XORed together."""
    basis = (np.uint32(1) << np.arange(32, dtype=np.uint32)).astype(np.uint32)
    for _ in range(length):
        basis = _TABLE[basis & 0xFF] ^ (basis >> 8)
    bits = ((np.arange(256)[:, None] >> np.arange(8)[None, :]) & 1).astype(bool)  # (256, 8)
    tables = []
    for byte in range(4):
        images = basis[8 * byte:8 * byte + 8]
        tables.append([int(v) for v in np.bitwise_xor.reduce(np.where(bits, images[None, :], 0), axis=1)])
    return tuple(tables)


def _register_blocked(register: int, data) -> int:
    """As :func:`_register_bytewise`, fast on long data: the data is cut into blocks of about sqrt(n) / 8 bytes whose
    registers (from zero) are computed side by side, then chained: register(r, A + B) = Z_|B|(register(r, A)) xor
    register(0, B), Z_|B| being the register after |B| zero bytes (linear in r)."""
    view = memoryview(data).cast("B")
    if len(view) < BLOCKED_CRC_MIN_BYTES:
        return _register_bytewise(register, view)
    block = 1 << max(6, len(view).bit_length() // 2 - 3)  # about sqrt(n) / 8: 256 bytes for 5 MB (fastest measured)
    head = len(view) % block
    register = _register_bytewise(register, view[:head])
    columns = np.frombuffer(view, dtype=np.uint8, offset=head).reshape(-1, block).T.copy()  # (block, count)
    registers = np.zeros(columns.shape[1], dtype=np.uint32)
    for row in columns:
        registers = _TABLE[(registers ^ row) & 0xFF] ^ (registers >> 8)
    t0, t1, t2, t3 = _zeros_operator(block)
    for value in registers.tolist():
        register = t0[register & 0xFF] ^ t1[(register >> 8) & 0xFF] ^ t2[(register >> 16) & 0xFF] ^ t3[register >> 24]
        register ^= value
    return register


def crc32c(data) -> int:
    """CRC32C (Castagnoli) of ``data`` (bytes-like) as an unsigned 32-bit int."""
    return _register_blocked(0xFFFFFFFF, data) ^ 0xFFFFFFFF


def masked_crc32c(data) -> int:
    """TFRecord's masked CRC32C of ``data``."""
    crc = crc32c(data)
    return ((((crc >> 15) | (crc << 17)) & 0xFFFFFFFF) + MASK_DELTA) & 0xFFFFFFFF


def tfrecord_record(data: bytes) -> bytes:
    """``data`` framed as one TFRecord record (length, its masked CRC, data, its masked CRC)."""
    length = struct.pack("<Q", len(data))
    return length + struct.pack("<I", masked_crc32c(length)) + data + struct.pack("<I", masked_crc32c(data))


def looks_like_tfrecord(path: Path) -> bool:
    """True when ``path`` starts with a TFRecord length whose masked CRC matches (False when unreadable)."""
    try:
        with open(path, "rb") as file:
            header = file.read(12)
    except OSError:
        return False
    return len(header) == 12 and struct.unpack("<I", header[8:])[0] == masked_crc32c(header[:8])


def tfrecord_records(path: Path, what: str) -> Iterator[tuple[int, bytes]]:
    """(index, data) of every record of the TFRecord file ``path``, both CRCs checked; a RigFileError names the
    file and record for a file that is not a TFRecord, a truncated record or a CRC that does not match."""
    path = existing_file(path, "TFRecord file", f"pass {what}", kind=RigFileError)
    try:
        file = open(path, "rb")
    except OSError as error:
        raise RigFileError(f"{path}: cannot read it ({error.strerror}); pass {what}") from None
    with file:
        size = path.stat().st_size
        index = 0
        while True:
            header = file.read(12)
            if not header:
                return
            where = f"{path}: record {index}"
            if len(header) < 12:
                raise RigFileError(f"{where}: truncated (the file ends inside the record's 12-byte header); the file "
                                   "is incomplete, download or copy it again")
            (length,), (length_crc,) = struct.unpack("<Q", header[:8]), struct.unpack("<I", header[8:])
            if length_crc != masked_crc32c(header[:8]):
                if index == 0:
                    raise RigFileError(f"{path}: not a TFRecord file (its first 8 bytes are not a record length with "
                                       f"a matching CRC); pass {what}")
                raise RigFileError(f"{where}: the CRC of the record's length does not match; the file is damaged, "
                                   "download or copy it again")
            left = size - file.tell()
            if length + 4 > left:
                raise RigFileError(f"{where}: truncated (the record needs {length} bytes of data and a 4-byte CRC, "
                                   f"{left} are left); the file is incomplete, download or copy it again")
            data = file.read(length)
            footer = file.read(4)
            if len(data) < length or len(footer) < 4:
                raise RigFileError(f"{where}: truncated (the file ends inside the record); the file is incomplete, "
                                   "download or copy it again")
            if struct.unpack("<I", footer)[0] != masked_crc32c(data):
                raise RigFileError(f"{where}: the CRC of the record's data does not match; the file is damaged, "
                                   "download or copy it again")
            yield index, data
            index += 1


def _varint(data, position: int, where: str) -> tuple[int, int]:
    """(value, next position) of the varint at ``position`` (at most 10 bytes, 64 bits)."""
    value, shift = 0, 0
    for offset in range(10):
        if position + offset >= len(data):
            break
        byte = data[position + offset]
        value |= (byte & 0x7F) << shift
        if byte < 0x80:
            return value & 0xFFFFFFFFFFFFFFFF, position + offset + 1
        shift += 7
    raise RigFileError(f"{where}: a varint runs past the end of the message or over 10 bytes; not a valid "
                       "protobuf message")


def message_fields(data, where: str) -> Iterator[tuple[int, int, object]]:
    """(field number, wire type, value) of each field of the protobuf message ``data``: an int for a varint,
    bytes for fixed64 (8), fixed32 (4) and length-delimited values."""
    data = memoryview(data).cast("B")
    position = 0
    while position < len(data):
        key, position = _varint(data, position, where)
        number, wire_type = key >> 3, key & 7
        if number == 0:
            raise RigFileError(f"{where}: field number 0 is not allowed; not a valid protobuf message")
        if wire_type == VARINT:
            value, position = _varint(data, position, where)
        elif wire_type in (FIXED64, FIXED32, LENGTH_DELIMITED):
            if wire_type == LENGTH_DELIMITED:
                size, position = _varint(data, position, where)
            else:
                size = 8 if wire_type == FIXED64 else 4
            if position + size > len(data):
                raise RigFileError(f"{where}: field {number} runs past the end of the message; not a valid "
                                   "protobuf message")
            value, position = bytes(data[position:position + size]), position + size
        else:
            raise RigFileError(f"{where}: field {number} has wire type {wire_type}, which is not read (groups) or "
                               "not valid; not a protobuf message rigopt can read")
        yield number, wire_type, value


def repeated_doubles(entries: list[tuple[int, object]], where: str) -> tuple[float, ...]:
    """The values of a ``repeated double`` field from its (wire type, value) entries: one by one (fixed64) or
    packed (length-delimited, 8 bytes each), in file order."""
    values: list[float] = []
    for wire_type, value in entries:
        if wire_type == FIXED64:
            values.append(struct.unpack("<d", value)[0])
        elif wire_type == LENGTH_DELIMITED and len(value) % 8 == 0:
            values.extend(struct.unpack(f"<{len(value) // 8}d", value))
        else:
            raise RigFileError(f"{where}: expected doubles (wire type 1, or packed: 2 with a multiple of 8 bytes), got "
                               f"wire type {wire_type}")
    return tuple(values)


def signed_int32(value: int) -> int:
    """An int32/enum varint (negative ones are written as 64-bit two's complement) as a Python int."""
    return value - (1 << 64) if value >= 1 << 63 else value
