"""Parts the example mesh makers share (``make_raw_bus.py``, ``make_raw_van.py``): wheels on their axles."""

from __future__ import annotations

import numpy as np
import trimesh


def wheels(axles_x, y: float, radius: float, width: float) -> list[trimesh.Trimesh]:
    """Two wheels on each axle at x (m) of ``axles_x``: cylinders along y of ``radius`` and ``width`` (m) standing on
    the ground, their centres at +-``y`` (m)."""
    turn = trimesh.transformations.rotation_matrix(np.pi / 2, [1.0, 0.0, 0.0])  # cylinder axis z -> y
    parts = []
    for x in axles_x:
        for side in (1.0, -1.0):
            wheel = trimesh.creation.cylinder(radius=radius, height=width, sections=24, transform=turn)
            wheel.apply_translation([x, side * y, radius])
            parts.append(wheel)
    return parts
