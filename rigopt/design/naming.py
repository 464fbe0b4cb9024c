"""Camera names that say where a camera is mounted and where it looks, e.g. ``CAM_FENDER_REAR_LEFT_TO_BACK_LEFT``.

A designed camera used to take the name of the reference camera it matches, which on another vehicle can
contradict where it sits (a "windshield front" camera on a cab's rear wall). Now the name is built from its
mounting zone, the side of the vehicle it is on (omitted on the centreline or when the zone says it), and
the direction it faces (eight 45-degree sectors of yaw in the vehicle frame: FRONT, FRONT_LEFT, LEFT,
BACK_LEFT, BACK, BACK_RIGHT, RIGHT, FRONT_RIGHT). The reference camera each matches is reported beside it.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

#: Yaw sectors (deg, ISO: > 0 to the left of forward), their centres every 45 degrees from 0.
LOOKS = ("FRONT", "FRONT_LEFT", "LEFT", "BACK_LEFT", "BACK", "BACK_RIGHT", "RIGHT", "FRONT_RIGHT")

#: |y| (m) below which a camera counts as on the centreline.
CENTRELINE_M = 0.15


def look_of(forward) -> str:
    """The facing sector of an optical axis ``forward`` (3,) in the vehicle frame."""
    yaw = np.degrees(np.arctan2(forward[1], forward[0]))
    return LOOKS[int(np.round(yaw / 45.0)) % 8]


def mount_name(zone: str | None, position, forward) -> str:
    """``CAM_<ZONE>[_<SIDE>]_TO_<LOOK>`` for a lens at ``position`` (3,) m facing ``forward`` (3,)."""
    base = (zone or "body").upper().replace("-", "_").replace(" ", "_")
    side = "" if abs(position[1]) < CENTRELINE_M else ("LEFT" if position[1] > 0 else "RIGHT")
    if side and side in base.split("_"):
        side = ""
    return "_".join(part for part in ("CAM", base, side, "TO", look_of(forward)) if part)


def unique(names: Sequence[str]) -> list[str]:
    """``names`` with repeats numbered in order (``X``, ``X_2``, ``X_3``)."""
    seen: dict[str, int] = {}
    out = []
    for name in names:
        seen[name] = seen.get(name, 0) + 1
        out.append(name if seen[name] == 1 else f"{name}_{seen[name]}")
    return out
