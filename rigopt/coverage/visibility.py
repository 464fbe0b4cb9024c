"""Occlusion-aware visibility: is a point inside a camera's pinhole frustum, with no body in between?

A point p is *seen* by a camera (t, R, fov, image size) when, in the camera body frame
``d = R^T (p - t)`` (x along the optical axis): ``d_x > 0``, ``|d_y| <= d_x tan(hfov / 2)``,
``|d_z| <= d_x tan(vfov / 2)``, ``|d| <= max_range``, and the segment from the lens to p meets no body
triangle. Segments are tested by :func:`rigopt.raycast.segments_clear` (embree or trimesh's triangle
intersector, ``backend``).
"""

from __future__ import annotations

import numpy as np
import trimesh

from rigopt.camera import CameraModel, in_frustum
from rigopt.raycast import segments_clear

#: Metres beyond which a camera sees nothing, unless the settings say otherwise.
DEFAULT_MAX_RANGE = 80.0


def visible(mesh: trimesh.Trimesh, positions, rotations, fovs, image_sizes, points,
            max_range: float = DEFAULT_MAX_RANGE, backend: str = "auto") -> np.ndarray:
    """(c, p) bool: point p seen by camera c: in its frustum and not hidden by the body ``mesh``.

    positions : (c, 3) m; rotations : (c, 3, 3) R_vehicle_cam; fovs : (c,) deg; image_sizes : (c, 2) px;
    points : (p, 3) m, vehicle frame; max_range : m.
    """
    seen = in_frustum(CameraModel.from_fov(fovs, image_sizes), positions, rotations, points, max_range)
    cam, point = np.nonzero(seen)
    if len(cam):
        clear = segments_clear(mesh, np.asarray(positions, dtype=float)[cam], np.asarray(points, dtype=float)[point],
                               backend)
        seen[cam[~clear], point[~clear]] = False
    return seen
