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

A point is *resolved* (:func:`resolved_by`) when it is seen and a regulation's test object standing there (its
height, the pixels its image must span) is as tall in the camera's image as asked (:func:`object_pixel_heights`).

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


#: Points along a test object's axis, foot to top, whose projections give the object's image height.
OBJECT_SAMPLES = 9


def object_pixel_heights(model: CameraModel, positions, rotations, points, object_heights, cameras, which
                         ) -> np.ndarray:
    """(n,) float px: how tall a test object standing below point ``which[i]`` is in camera ``cameras[i]``'s image:
    the length of the image of the part of its axis in the camera's view (:meth:`CameraModel.in_view`, the object
    not hidden by anything: the point's own visibility is :func:`visible_by`'s), the axis from the ground below the
    point up to ``object_heights[which[i]]`` m sampled at OBJECT_SAMPLES points (their images joined by straight
    lines: a distorted lens's curved image is a little longer).

    model : CameraModel of batch shape (c,); positions : (c, 3) m; rotations : (c, 3, 3) R_vehicle_cam;
    points : (p, 3) m, vehicle frame; object_heights : (p,) m; cameras, which : (n,) int pairs of indices.
    """
    positions, rotations = np.asarray(positions, dtype=float), np.asarray(rotations, dtype=float)
    points, heights = np.asarray(points, dtype=float), np.asarray(object_heights, dtype=float)
    cameras, which = np.asarray(cameras, dtype=int), np.asarray(which, dtype=int)
    if not len(cameras):
        return np.zeros(0)
    up = np.linspace(0.0, 1.0, OBJECT_SAMPLES)
    axis = np.repeat(points[which, None, :], OBJECT_SAMPLES, axis=1)  # (n, k, 3): foot to top
    axis[:, :, 2] = up[None, :] * heights[which, None]
    local = np.einsum("nji,nkj->nki", rotations[cameras], axis - positions[cameras, None, :])
    model.valid_angles  # derived once for the batch: take() hands it to the pairs instead of one lens at a time
    pair_model = model.take(cameras)
    inside = pair_model.in_view(local)
    with np.errstate(divide="ignore", invalid="ignore"):
        pixels = pair_model.project(local)
        steps = np.linalg.norm(np.diff(pixels, axis=1), axis=-1)
    return np.where(inside[:, 1:] & inside[:, :-1], steps, 0.0).sum(axis=1)


def fine_enough(seen, model: CameraModel, positions, rotations, points, pixel_demand) -> np.ndarray:
    """(c, p) bool: the pairs of ``seen`` (c, p) bool (camera c sees point p) where the test object at point p is
    as tall in camera c's image as it asks: ``pixel_demand`` (p, 2) float, each point's (object height m, pixels
    its image must span; 0 asks nothing), :func:`object_pixel_heights`."""
    fine = np.array(seen, dtype=bool)
    demand = np.asarray(pixel_demand, dtype=float).reshape(-1, 2)
    points = np.asarray(points, dtype=float)
    cam, point = np.nonzero(fine & (demand[:, 1] > 0)[None, :])
    if len(cam):
        # the points of one ground position (a test object's heights) stand on one object: measured once
        stands, stand_of = np.unique(np.column_stack([points[:, :2], demand[:, 0]]), axis=0, return_inverse=True)
        stand_of = stand_of.reshape(-1)
        pairs, pair_of = np.unique(cam * len(stands) + stand_of[point], return_inverse=True)
        feet = np.column_stack([stands[:, :2], np.zeros(len(stands))])
        heights = object_pixel_heights(model, positions, rotations, feet, stands[:, 2], pairs // len(stands),
                                       pairs % len(stands))
        small = heights[pair_of.reshape(-1)] < demand[point, 1]
        fine[cam[small], point[small]] = False
    return fine


def resolved_by(caster: RayCaster, model: CameraModel, positions, rotations, points, pixel_demand,
                max_range: float = DEFAULT_MAX_RANGE, boxes=()) -> np.ndarray:
    """(c, p) bool: point p seen by camera c (:func:`visible_by`) with its test object as many pixels tall as
    ``pixel_demand`` (p, 2) asks (:func:`fine_enough`)."""
    seen = visible_by(caster, model, positions, rotations, points, max_range, boxes)
    return fine_enough(seen, model, positions, rotations, points, pixel_demand)


def no_pixel_demand(n: int) -> np.ndarray:
    """(n, 2) float: a pixel demand that asks nothing (in view is enough) of ``n`` points."""
    return np.tile([1.0, 0.0], (n, 1))
