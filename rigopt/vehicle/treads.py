"""Step treads found on a user mesh: the walkable ledges no lens may sit on (``[[steps]]`` in ``vehicle.toml``).

A tread is a patch of the mesh's own surface (as the user gave it, before closing) that faces up (its normal
within ``UP_CONE_DEG`` of +z), lies at step height (its top between ``TREAD_Z`` m), is large enough to stand on
(at least ``MIN_AREA`` m²) and is shallow (its narrower horizontal side at most ``MAX_DEPTH`` m: a rear step, a
cab or door step, a bumper-top sill). Only on bodies at least ``MIN_BODY_HEIGHT`` m tall (vans, buses, trucks,
ambulances): a car's bonnet and boot lid also face up at 0.6-0.9 m, and a car has no step to tell them from.
The tyres' tops, which face up at a wheel's diameter, are no treads: faces within ``WHEEL_MARGIN`` m of a
wheel's circle (side view) are left out. Each tread becomes a step box over it, down to ``RISER`` m below it (the
riser under the tread is kicked too).

ISO vehicle frame, metres.
"""

from __future__ import annotations

import numpy as np
import trimesh

from rigopt.vehicle.supports import connected_pieces

UP_CONE_DEG = 15.0
TREAD_Z = (0.2, 1.0)
MIN_AREA, MAX_DEPTH = 0.02, 0.6
MIN_BODY_HEIGHT = 2.0
RISER, ABOVE = 0.3, 0.05
WHEEL_MARGIN = 0.05


def step_treads(mesh: trimesh.Trimesh, wheels=()) -> list[dict]:
    """``[[steps]]`` entries (name, min, max, mirrored false) over the treads of ``mesh`` (module doc), in the
    order of their x from the front; none on a body lower than MIN_BODY_HEIGHT. ``wheels``: (x, radius) m of
    each wheel standing on the ground, whose tyre tops are left out."""
    low_z, high_z = mesh.bounds[:, 2]
    if high_z - low_z < MIN_BODY_HEIGHT:
        return []
    centres = mesh.triangles_center
    up = ((mesh.face_normals[:, 2] >= np.cos(np.radians(UP_CONE_DEG)))
          & (centres[:, 2] >= TREAD_Z[0]) & (centres[:, 2] <= TREAD_Z[1]))
    for x, radius in wheels:
        up &= np.hypot(centres[:, 0] - x, centres[:, 2] - radius) > radius + WHEEL_MARGIN
    triangles = mesh.triangles[up]
    treads = []
    for piece in connected_pieces(triangles):  # a triangle soup's (STL's) corners are merged there
        corners = triangles[piece].reshape(-1, 3)
        low, high = corners.min(axis=0), corners.max(axis=0)
        if trimesh.triangles.area(triangles[piece]).sum() >= MIN_AREA and min(high[:2] - low[:2]) <= MAX_DEPTH:
            treads.append((low, high))
    treads.sort(key=lambda box: -box[1][0])
    return [{"name": f"tread {k + 1} (found: faces up at {high[2]:.2f} m)",
             "min": [round(float(v), 3) for v in (low[0], low[1], high[2] - RISER)],
             "max": [round(float(v), 3) for v in (high[0], high[1], high[2] + ABOVE)], "mirrored": False}
            for k, (low, high) in enumerate(treads)]
