"""Occlusion-aware visibility: is a point in a camera's view, with nothing of the vehicle in between?

A point p is *seen* by a camera (t, R, lens) when, in the camera body frame ``d = R^T (p - t)`` (x along
the optical axis), the camera model has it in view (:meth:`rigopt.camera.CameraModel.in_view`: for the
benchmark's pinhole ``d_x > 0``, ``|d_y| <= d_x tan(hfov / 2)``, ``|d_z| <= d_x tan(vfov / 2)``; for a
distorted lens, its projection inside the image within the lens's valid angle), ``|d| <= max_range``, and
nothing blocks the segment from the lens to p:

- the body, a solid (:meth:`rigopt.raycast.RayCaster.segments_clear`; a vehicle's caster is
  ``vehicle.caster(backend)``): a lens inside it, or on its skin facing into it, sees nothing that way;
- the ``boxes`` given, solids too: the keep-outs that block views (:func:`occluders`: a coupled trailer, unless
  lifted), which the coverage measures, the coverage matrix and the regulation fields pass by default. A point
  inside one is hidden by it.

Each (lens position, point) segment is cast once however many cameras at that position see the point.
"""

from __future__ import annotations

import numpy as np

from rigopt.camera import CameraModel, in_frustum
from rigopt.mounting.practice import keep_out_boxes, segments_hit_boxes
from rigopt.raycast import RayCaster
from rigopt.vehicle.model import Vehicle

#: Metres beyond which a camera sees nothing, unless the settings say otherwise.
DEFAULT_MAX_RANGE = 80.0


def occluders(vehicle: Vehicle, lifted=()) -> list[tuple[np.ndarray, np.ndarray, str]]:
    """The solids besides the body that block views on ``vehicle``: its keep-out boxes in force that occlude
    (a coupled trailer), as (low (3,) m, high (3,) m, label); ``lifted`` names optional ones switched off (a
    tractor driven without its trailer: ``("trailer",)``, as ``MountPractice.lifted``)."""
    return keep_out_boxes(vehicle, tuple(lifted), occluding_only=True)


def visible(caster: RayCaster, positions, rotations, fovs, image_sizes, points,
            max_range: float = DEFAULT_MAX_RANGE, boxes=()) -> np.ndarray:
    """(c, p) bool: point p seen by pinhole camera c: in its frustum and not hidden by the body (the mesh of
    ``caster``) nor by ``boxes``.

    positions : (c, 3) m; rotations : (c, 3, 3) R_vehicle_cam; fovs : (c,) deg; image_sizes : (c, 2) px;
    points : (p, 3) m, vehicle frame; max_range : m; boxes : [(low (3,), high (3,), label), ...] m.
    """
    return visible_by(caster, CameraModel.from_fov(fovs, image_sizes), positions, rotations, points, max_range,
                      boxes)


def visible_by(caster: RayCaster, model: CameraModel, positions, rotations, points,
               max_range: float = DEFAULT_MAX_RANGE, boxes=()) -> np.ndarray:
    """(c, p) bool: as :func:`visible`, for cameras of any lens: ``model`` a CameraModel of batch shape (c,)
    (e.g. ``CameraModel.of_cameras(rig.cameras)``). Cameras at one position (a mount's orientations and lenses)
    share their segments: each (position, point) pair in some frustum is cast once. ``boxes``: solid boxes
    [(low (3,), high (3,), label), ...] m that block too (:func:`occluders`)."""
    seen = in_frustum(model, positions, rotations, points, max_range)
    cam, point = np.nonzero(seen)
    if len(cam):
        positions, points = np.asarray(positions, dtype=float), np.asarray(points, dtype=float)
        origins, origin_of = np.unique(positions, axis=0, return_inverse=True)
        pairs, pair_of = np.unique(origin_of.reshape(-1)[cam] * len(points) + point, return_inverse=True)
        starts, ends = origins[pairs // len(points)], points[pairs % len(points)]
        clear = caster.segments_clear(starts, ends)
        if len(boxes):  # segments start + s (end - start), s in [0, 1]
            clear &= ~segments_hit_boxes(starts, ends - starts, 1.0, boxes)
        clear = clear[pair_of]
        seen[cam[~clear], point[~clear]] = False
    return seen
