"""Designing a rig: ``design_rig(vehicle, references, ...)`` and its ``DesignSettings`` (the command's preset by
default), loaded when first used so that importing the package stays light.

    from rigopt.design import design_rig, DesignSettings
    result = design_rig("firetruck", "R1")  # what `rigopt design --vehicle firetruck --ref R1` designs
"""

from __future__ import annotations

import importlib

_LAZY = {"design_rig": "rigopt.design.designer", "DesignSettings": "rigopt.design.settings",
         "ReferenceRig": "rigopt.design.problem", "benchmark_rigs": "rigopt.design.problem",
         "DesignResult": "rigopt.design.result"}

__all__ = sorted(_LAZY)


def __getattr__(name: str):
    if name not in _LAZY:
        raise AttributeError(f"module 'rigopt.design' has no attribute {name!r}")
    value = getattr(importlib.import_module(_LAZY[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})
