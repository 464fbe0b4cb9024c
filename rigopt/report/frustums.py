"""A camera's frustum as the reports draw it: lines to its image's corners and its outline along the real
lens's rays (:func:`frustum_lines`), ended on a plane across the axis or on a sphere (:func:`_frustum_cap`)
and, as drawn, at the ground (:func:`ended_at_ground`), and where that solid meets the ground
(:func:`frustum_footprint`). Vehicle frame: ISO 8855 (x forward, y left,
z up), metres, the ground at z = 0; the camera as placed on its vehicle (the vehicle-centre frame)."""

from __future__ import annotations

import numpy as np

from rigopt.camera import CameraModel
from rigopt.rig.model import Camera

#: Default distance (m) from the lens at which frustums are drawn.
FRUSTUM_RANGE_M = 5.0
#: Points per image edge of a drawn frustum outline (rays through them: curved for a distorted lens).
EDGE_POINTS = 9
#: A frustum whose outline rays stay within this angle (deg) of the optical axis ends on a plane, else on a sphere.
PLANE_LIMIT_DEG = 75.0
#: Image cells (columns, rows) whose ground images make up a frustum's ground footprint.
FOOTPRINT_GRID = (64, 36)
#: A footprint cell's corner ray that meets the ground farther than this many frustum ranges (or not at all)
#: is taken there, along its azimuth (beyond the frustum's end, which cuts the footprint).
FOOTPRINT_FAR = 4.0


def _outline_rays(camera: Camera) -> np.ndarray:
    """(4 + 4 EDGE_POINTS + 1, 3) float: camera-body unit rays through the image's corners (top-left, top-right,
    bottom-right, bottom-left), then through its outline from the top-left corner clockwise, closed."""
    width, height = camera.image_size
    corners_px = np.array([[0.0, 0.0], [width, 0.0], [width, height], [0.0, height]])
    s = np.arange(EDGE_POINTS) / EDGE_POINTS
    outline_px = np.concatenate([a + s[:, None] * (b - a) for a, b in zip(corners_px, np.roll(corners_px, -1, 0))])
    outline_px = np.concatenate([outline_px, corners_px[:1]])
    return CameraModel.of_camera(camera).pixel_rays(np.concatenate([corners_px, outline_px]), frame="body")


def _frustum_cap(camera: Camera, frustum_range: float) -> tuple[str, float]:
    """Where a drawn frustum ends: ("plane", depth m) on the plane across the optical axis at that depth, where
    the image corner farthest off the axis is ``frustum_range`` m from the lens; or ("sphere", radius m) for
    a lens whose outline reaches more than PLANE_LIMIT_DEG off its axis."""
    rays = _outline_rays(camera)
    if rays[:, 0].min() >= np.cos(np.deg2rad(PLANE_LIMIT_DEG)):
        return "plane", float(frustum_range * rays[:4, 0].min())
    return "sphere", float(frustum_range)


def frustum_lines(camera: Camera, frustum_range: float = FRUSTUM_RANGE_M) -> tuple[np.ndarray, np.ndarray]:
    """A camera's drawn frustum in the vehicle frame (m): its image's corners (4, 3) (top-left, top-right,
    bottom-right, bottom-left pixel corners) and its outline (4 EDGE_POINTS + 1, 3), closed, from the
    top-left corner clockwise as seen from behind the camera, each on the ray of its pixel through the
    camera's lens model (distortion included, so a distorted lens draws its true, curved outline).

    Where the points lie on their rays (:func:`_frustum_cap`): on the plane across the optical axis at which
    the corner farthest off the axis is ``frustum_range`` m from the lens (a centred lens has all four corners
    there, and a pinhole's outline is a rectangle); for a lens whose outline reaches more than PLANE_LIMIT_DEG
    off its axis (a wide fisheye, whose corners may look backwards) on the sphere of radius ``frustum_range``
    instead."""
    rays = _outline_rays(camera)
    kind, reach = _frustum_cap(camera, frustum_range)
    distance = reach / rays[:, 0] if kind == "plane" else np.full(len(rays), reach)
    points = camera.position + (distance[:, None] * rays) @ camera.rotation.T
    return points[:4], points[4:]


def ended_at_ground(lens: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(k, 3) float m: ``points`` (k, 3) m, each on its ray from ``lens`` (3,) m (vehicle frame), with those below
    the ground moved back along their ray to where it meets the ground z = 0, so that a drawn frustum line
    ends there; points at or above the ground, and every point of a lens not above it, stay."""
    points = np.array(points, dtype=float)
    below = points[:, 2] < 0
    if lens[2] > 0 and below.any():
        share = lens[2] / (lens[2] - points[below, 2])  # of the way from the lens to the point: in (0, 1)
        points[below] = lens + share[:, None] * (points[below] - lens)
        points[below, 2] = 0.0
    return points


def frustum_footprint(camera: Camera, frustum_range: float = FRUSTUM_RANGE_M):
    """The drawn frustum's ground footprint: where the solid of :func:`frustum_lines` (the lens's view cone,
    ended where :func:`_frustum_cap` says) meets the ground z = 0, as a shapely (Multi)Polygon in the vehicle
    frame's x, y (m); empty when it does not reach the ground.

    The view cone's ground trace is the union of the ground images of FOOTPRINT_GRID image cells (each the
    quadrilateral through its corners' ground points: exact for a pinhole, whose cells' edges map to straight
    lines; cells whose corner rays all point up are left out, and a corner ray that does not reach the ground
    within the far limit is taken on the far circle, FOOTPRINT_FAR times the range, along its azimuth), cut by
    the frustum's end: the half-plane where the end plane crosses the ground, or the disc where the end sphere
    does."""
    import shapely

    height = float(camera.position[2])
    kind, reach = _frustum_cap(camera, frustum_range)
    if height <= 0 or (kind == "sphere" and reach <= height):
        return shapely.Polygon()
    model = CameraModel.of_camera(camera)
    columns, rows = FOOTPRINT_GRID
    u, v = np.meshgrid(np.linspace(0.0, float(model.width), columns + 1), np.linspace(0.0, float(model.height), rows + 1))
    rays = model.pixel_rays(np.stack([u.ravel(), v.ravel()], axis=1)) @ camera.rotation.T
    far = FOOTPRINT_FAR * frustum_range
    horizontal = np.linalg.norm(rays[:, :2], axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        reach_xy = np.where(rays[:, 2] < 0, height * horizontal / -rays[:, 2], np.inf)
        azimuth = rays[:, :2] / horizontal[:, None]
    ground = camera.position[:2] + np.minimum(reach_xy, far)[:, None] * azimuth
    ground, down = ground.reshape(rows + 1, columns + 1, 2), (rays[:, 2] < 0).reshape(rows + 1, columns + 1)
    quads = np.stack([ground[:-1, :-1], ground[:-1, 1:], ground[1:, 1:], ground[1:, :-1]], axis=2).reshape(-1, 4, 2)
    reaching = (down[:-1, :-1] | down[:-1, 1:] | down[1:, 1:] | down[1:, :-1]).ravel()
    quads = quads[reaching & np.all(np.isfinite(quads), axis=(1, 2))]  # cells that look at the ground
    axis = camera.forward
    if kind == "sphere":
        end = shapely.Point(camera.position[:2]).buffer(np.sqrt(reach**2 - height**2), quad_segs=32)
    else:  # ground points g with (g - lens) . axis <= depth: a half-plane of the ground
        across = np.linalg.norm(axis[:2])
        bound = reach + height * axis[2]
        if across < 1e-9:
            if bound < 0:
                return shapely.Polygon()
            end = shapely.box(*(camera.position[:2] - far), *(camera.position[:2] + far))
        else:
            normal, side = axis[:2] / across, np.array([-axis[1], axis[0]]) / across
            edge = camera.position[:2] + normal * bound / across
            big = 2 * far + abs(bound) / across
            end = shapely.Polygon([edge + side * big, edge - side * big, edge - side * big - normal * big,
                                   edge + side * big - normal * big])
    cells = shapely.make_valid(shapely.polygons(quads))
    cells = cells[shapely.intersects(cells, end)]
    if len(cells) == 0:
        return shapely.Polygon()
    return shapely.intersection(shapely.union_all(cells), end)
