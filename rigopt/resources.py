"""Where rigopt's shipped data lives: the ``metrics/``, ``vehicles/`` and ``detectors/`` folders.

In a source checkout they are top-level folders beside the ``rigopt`` package; a built wheel carries
them inside the package as ``rigopt/_data/``. Both layouts are found here and nowhere else.
"""

from __future__ import annotations

from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent


def data_dir(name: str) -> Path:
    """The shipped data folder ``name`` ("metrics", "vehicles" or "detectors") of this installation."""
    for candidate in (_PACKAGE / "_data" / name, _PACKAGE.parent / name):
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError(
        f"rigopt's data folder {name!r} is missing from this installation; reinstall rigopt "
        "(pip install -e . from a checkout, or the wheel)"
    )
