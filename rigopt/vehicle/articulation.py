"""A tractor with its semi-trailer turned: the trailer's box swung about its kingpin, as a turn swings it.

A semi-trailer is a ``[[keep_out]]`` with a ``kingpin`` (:mod:`rigopt.vehicle.spec`). Turned by an articulation
angle a (deg) about the kingpin's vertical, its plan rotates by a counter-clockwise seen from above: a > 0 swings
its rear to the right (-y), as a right turn does (the trailer cuts the inside of the turn); a < 0 to the left.

The rules and coverage read keep-outs as axis-aligned boxes, so the turned trailer is given as slices: its length
cut into pieces at most SLICE_M m long, each piece turned and replaced by the box around it (the same name, reason,
height and flags; no kingpin). The slices cover the turned box and overshoot it by at most SLICE_M sin|a| m at
its sides (0.13 m at 30 deg). Frames: ISO 8855 vehicle frame, metres.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from rigopt.errors import RigoptError
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import KeepOutSpec

#: Longest slice (m) of a turned trailer.
SLICE_M = 0.25
#: Articulation angles (deg) accepted: a semi-trailer turns less than a right angle against its tractor.
MAX_ARTICULATION_DEG = 90.0


def turned_slices(box: KeepOutSpec, angle_deg: float) -> tuple[KeepOutSpec, ...]:
    """The slices (module docstring) of the semi-trailer ``box`` turned ``angle_deg`` about its kingpin."""
    angle = np.deg2rad(angle_deg)
    turn = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    pivot = box.kingpin[:2]
    cuts = np.linspace(box.min[0], box.max[0], int(np.ceil((box.max[0] - box.min[0]) / SLICE_M)) + 1)
    reason = f"{box.reason}, turned {angle_deg:+g} deg about its kingpin"
    out = []
    for x0, x1 in zip(cuts[:-1], cuts[1:]):
        corners = np.array([[x, y] for x in (x0, x1) for y in (box.min[1], box.max[1])])
        plan = (corners - pivot) @ turn.T + pivot
        low = np.array([*plan.min(axis=0), box.min[2]])
        high = np.array([*plan.max(axis=0), box.max[2]])
        out.append(replace(box, min=low, max=high, reason=reason, mirrored=False, kingpin=None))
    return tuple(out)


def articulated(vehicle: Vehicle, angle_deg: float) -> Vehicle:
    """``vehicle`` with every semi-trailer turned ``angle_deg`` (> 0: its rear to the right) about its kingpin, as
    slices (module docstring); the vehicle itself when it has no semi-trailer or the angle is 0. Its mesh is the
    same (the tractor does not move)."""
    if not (np.isfinite(angle_deg) and abs(angle_deg) <= MAX_ARTICULATION_DEG):
        raise RigoptError(f"an articulation angle is degrees within +-{MAX_ARTICULATION_DEG:g} (> 0: the trailer's rear "
                          f"swings right, as in a right turn), got {angle_deg!r}")
    trailers = [box for box in vehicle.spec.keep_outs if box.kingpin is not None]
    if not trailers or angle_deg == 0:
        return vehicle
    keep_outs = []
    for box in vehicle.spec.keep_outs:
        keep_outs += turned_slices(box, angle_deg) if box.kingpin is not None else [box]
    return Vehicle(replace(vehicle.spec, keep_outs=tuple(keep_outs)), vehicle.mesh)
