"""The built-in rig library (the PCCR benchmark's 14 rigs) and the one lookup of a rig by name or path.

Library rigs are benchmark-format files under ``vehicles/<vehicle>/rigs/<NAME>.json``; names are
matched case-insensitively.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from rigopt.errors import RigFileError, unknown_name
from rigopt.output import existing_file
from rigopt.resources import data_dir
from rigopt.rig.model import Rig
from rigopt.rig.pccr_format import read_rig


@lru_cache(maxsize=1)
def _library_files() -> dict[str, Path]:
    files = sorted(data_dir("vehicles").glob("*/rigs/*.json"))
    return {path.stem: path for path in files}


def rig_names() -> list[str]:
    """Names of the library rigs in the benchmark's order (R1 family first, then R2 ... R9)."""
    return sorted(_library_files(), key=_benchmark_order)


def _benchmark_order(name: str):
    head, _, tail = name.partition("-")
    return (int(head[1:]) if head[1:].isdigit() else 99, tail != "", tail.lower())


def library_rig(name: str) -> Rig:
    """The library rig ``name`` (case-insensitive); raises UnknownNameError listing the valid names."""
    files = _library_files()
    by_lower = {k.lower(): k for k in files}
    key = by_lower.get(name.lower())
    if key is None:
        raise unknown_name("rig", name, rig_names())
    return read_rig(files[key], key)


def load_rig(name_or_path) -> Rig:
    """A rig from a library name (case-insensitive) or a path to a benchmark rig file.

    A string that names a library rig wins over a file of the same name in the working directory
    only when no such file exists; paths ending in ``.json`` are always read as files. A folder is never a
    rig file: a library name stays that rig where a folder of that name lies in the working directory
    (``rigopt bench generate`` makes one per rig).
    """
    if isinstance(name_or_path, Rig):
        return name_or_path
    text = str(name_or_path)
    path = Path(text)
    if path.suffix.lower() == ".json" or path.is_file():
        existing_file(path, "rig file", f"library rigs: {', '.join(rig_names())}", kind=RigFileError)
        return read_rig(path)
    if path.is_dir() and text.lower() not in {name.lower() for name in rig_names()}:
        raise RigFileError(f"{path} is a folder; give the rig file itself (a rig JSON file) or a library rig "
                           f"({', '.join(rig_names())})")
    return library_rig(text)
