"""rigopt: design automotive camera rigs that a camera-only 3D detector transfers to.

The Python API in one place; see docs/index.md. The names load on first use (module ``__getattr__``),
so that ``import rigopt`` (and ``rigopt --help``) does not pay for numpy, scipy and cvxpy.
"""

from __future__ import annotations

import importlib

from rigopt.errors import DataError, RigFileError, RigoptError, UnknownNameError

__version__ = "0.1.0"

#: Public name -> the module that defines it.
_LAZY = {
    "Calibration": "rigopt.metrics.calibration", "load_weights": "rigopt.metrics.calibration",
    "predict_transfer": "rigopt.metrics.ranking", "rank_candidates": "rigopt.metrics.ranking",
    "RigBatch": "rigopt.metrics.rigcd", "RigCDBreakdown": "rigopt.metrics.rigcd", "RigCDMatrix": "rigopt.metrics.rigcd",
    "rigcd": "rigopt.metrics.rigcd", "rigcd_matrix": "rigopt.metrics.rigcd", "rigcd_pairs": "rigopt.metrics.rigcd",
    "RigVBreakdown": "rigopt.metrics.rigv", "rigv": "rigopt.metrics.rigv",
    "load_rig": "rigopt.rig.library", "rig_names": "rigopt.rig.library",
    "Camera": "rigopt.rig.model", "Rig": "rigopt.rig.model",
    "read_rig": "rigopt.rig.pccr_format", "write_rig": "rigopt.rig.pccr_format",
}

__all__ = sorted(["DataError", "RigFileError", "RigoptError", "UnknownNameError", *_LAZY])


def __getattr__(name: str):
    if name not in _LAZY:
        raise AttributeError(f"module 'rigopt' has no attribute {name!r}")
    value = getattr(importlib.import_module(_LAZY[name]), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})
