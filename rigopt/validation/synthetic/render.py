"""Rendering the benchmark's images: a CPU ray caster giving a camera's RGB, depth and object ids of a frame.

Every pixel casts one ray through its centre, through the camera's lens (:class:`rigopt.camera.CameraModel`:
the benchmark's centred square-pixel pinhole, or a real lens with its intrinsics and radtan or fisheye
distortion, resampled to the rendered size) and takes the nearest of: the ground plane z = 0, the scene's
oriented boxes (slab test in each box's frame, screen tile by screen tile so that a tile meets only the boxes
whose projection covers it; every box in every tile through a distorted lens), and the ego body mesh
(trimesh / embree, ego frame). Nothing within ``max_range`` metres is sky.

Frames and units: world x east, y north, z up; ego and camera body frames as in :mod:`rigopt.rig.model`;
optical frame z forward, x right, y down; metres. Pixel (row v, column u) has its centre at
(u + 0.5, v + 0.5) in the coordinates of the intrinsics ``K``. Depth is measured along the optical axis.

Shading is procedural and deterministic (hashed value noise on world or box coordinates; no random state):
asphalt, pavement, grass, kerbs and lane markings on the ground; per-class albedo, Lambertian light from a
fixed sun and class-specific patterns (windows, wheels, heads, lamps) on boxes; a fixed body colour for
the ego vehicle; a vertical sky gradient; mild distance fog.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import shapely
import trimesh

from rigopt.validation.synthetic.scene_model import Boxes, Road, Scene
from rigopt.benchmark import SYNTHETIC_IMAGE_SIZE
from rigopt.camera import CameraModel, pixel_centres
from rigopt.raycast import RayCaster
from rigopt.rig.model import Camera, Rig

#: Unit vector towards the sun, world frame.
SUN = np.array([0.45, -0.35, 0.82]) / np.linalg.norm([0.45, -0.35, 0.82])
AMBIENT, DIFFUSE = 0.45, 0.6
#: Distance (m) over which fog reaches 1 - 1/e of its colour.
FOG_DISTANCE = 400.0
#: Side (px) of the screen tiles in which rays meet boxes; pixels shaded (and ego rays cast) at a time.
TILE, CHUNK = 32, 1 << 17
#: Box-ray hits closer than this depth (m) are ignored; ego rays start this far (m) from the lens.
NEAR = 1e-4
EGO_RAY_OFFSET = 1e-3
#: Albedos (linear-ish RGB in [0, 1]) of the nine classes in CLASSES order, then other surfaces.
CLASS_ALBEDO = np.array([
    [0.78, 0.12, 0.10],  # car: red
    [0.95, 0.55, 0.10],  # truck: orange
    [0.95, 0.85, 0.15],  # bus: yellow
    [0.55, 0.15, 0.65],  # motorcycle: purple
    [0.10, 0.65, 0.70],  # bicycle: teal
    [0.15, 0.35, 0.85],  # adult: blue
    [0.30, 0.80, 0.25],  # child: green
    [0.92, 0.92, 0.92],  # traffic_sign: white plate
    [0.12, 0.12, 0.12],  # traffic_light: black housing
])
BUILDING, POLE, EGO = np.array([0.62, 0.56, 0.50]), np.array([0.42, 0.36, 0.30]), np.array([0.20, 0.24, 0.30])
ASPHALT, PAVEMENT, GRASS = np.array([0.27, 0.27, 0.29]), np.array([0.58, 0.56, 0.52]), np.array([0.30, 0.44, 0.20])
MARKING, KERB = np.array([0.92, 0.92, 0.88]), np.array([0.76, 0.76, 0.74])
GLASS, TYRE, SKIN = np.array([0.08, 0.10, 0.13]), np.array([0.05, 0.05, 0.05]), np.array([0.85, 0.65, 0.50])
SIGN_RED, WINDOW = np.array([0.80, 0.08, 0.08]), np.array([0.22, 0.27, 0.34])
LAMPS = np.array([[0.9, 0.1, 0.1], [0.95, 0.7, 0.1], [0.1, 0.85, 0.3]])
SKY_HORIZON, SKY_ZENITH = np.array([0.80, 0.85, 0.90]), np.array([0.30, 0.50, 0.85])


@dataclass(frozen=True, eq=False)
class Rendered:
    """One camera's image of one frame.

    rgb : (h, w, 3) uint8; depth : (h, w) float32 m along the optical axis (negative behind the lens's
    plane, which only a fisheye beyond 180 degrees sees), inf for sky; intrinsics : (3, 3) float K at this
    size; object_id : (h, w) int32 instance id of the box each pixel shows, -1 for ground, sky and the ego
    body; model : the camera model at this size (its distortion too).
    """

    rgb: np.ndarray
    depth: np.ndarray
    intrinsics: np.ndarray
    object_id: np.ndarray
    model: CameraModel | None = None


def render_rig(scene: Scene, frame_index: int, rig: Rig, ego: EgoBody | None,
               size: tuple[int, int] = SYNTHETIC_IMAGE_SIZE, max_range: float = 120.0) -> dict[str, Rendered]:
    """Render frame ``frame_index`` of ``scene`` with every camera of ``rig``: camera id -> Rendered."""
    return {camera.id: render_camera(scene, frame_index, camera, ego, size, max_range) for camera in rig.cameras}


def render_camera(scene: Scene, frame_index: int, camera: Camera, ego: EgoBody | None,
                  size: tuple[int, int] = SYNTHETIC_IMAGE_SIZE, max_range: float = 120.0) -> Rendered:
    """Render frame ``frame_index`` of ``scene`` through ``camera`` (mounted on the ego vehicle).

    Parameters
    ----------
    scene : Scene
        Road, static boxes and frames (world frame); the frame's ``T_world_ego`` (4, 4) places the ego.
    frame_index : int
        Which frame of ``scene.frames``.
    camera : Camera
        Pose in the ego frame and lens (a benchmark pinhole of its horizontal FOV, or its real lens); its own
        ``image_size`` is ignored in favour of ``size``: a real lens's intrinsics are scaled to it.
    ego : EgoBody or None
        The ego vehicle's body (its mesh in the ego frame, m), or None for no body.
    size : (int, int)
        ``(width, height)`` px of the rendered image.
    max_range : float
        Surfaces farther than this (m, Euclidean from the lens) are replaced by sky; may be inf.
    """
    w, h = (int(v) for v in size)
    if w <= 0 or h <= 0:
        raise ValueError(f"image size must be two positive integers (width, height), got {size!r}")
    model = CameraModel.rendered(camera, (w, h))
    distorted = bool(model.distorted)
    K = model.intrinsic_matrix()
    f = K[0, 0]
    T_world_ego = np.asarray(scene.frames[frame_index].T_world_ego, dtype=float)
    R_world_cam = T_world_ego[:3, :3] @ camera.rotation
    origin = T_world_ego[:3, :3] @ camera.position + T_world_ego[:3, 3]

    # Rays through pixel centres, body frame, scaled so that their optical-axis component is 1: then the
    # ray parameter t of a hit is its depth, and t * |d| its range. A distorted lens's are unit rays (a
    # fisheye sees beyond 90 degrees): t is the range and t * axial the depth.
    body = model.pixel_rays(pixel_centres(w, h), unit=distorted)
    axial = body[:, 0]
    dirs = body @ R_world_cam.T  # (h*w, 3) world
    norm = np.linalg.norm(dirs, axis=1)

    t_ground = np.full(h * w, np.inf)
    if origin[2] > 0:
        down = dirs[:, 2] < 0
        t_ground[down] = -origin[2] / dirs[down, 2]
    boxes = scene.boxes_at(frame_index)
    t_box, box_index = _box_hits(boxes, origin, dirs.reshape(h, w, 3), R_world_cam, model, max_range, distorted)
    t_box, box_index = t_box.ravel(), box_index.ravel()
    t_ego, normal_ego = np.full(h * w, np.inf), np.zeros((h * w, 3))
    if ego is not None and len(ego.mesh.faces):
        t_ego, normal_ego = ego.view(camera, model, body)
    candidates = np.stack([t_ground, t_box, t_ego])  # (3, h*w)
    kind = np.argmin(candidates, axis=0)
    t = candidates[kind, np.arange(h * w)]
    kind[~(np.isfinite(t) & (t * norm <= max_range))] = 3  # 0 ground, 1 box, 2 ego, 3 sky

    distance = t * norm  # m from the lens
    colour = np.empty((h * w, 3), dtype=np.float32)
    object_id = np.full(h * w, -1, dtype=np.int32)
    for surface, start in ((k, i) for k in range(4) for i in range(0, h * w, CHUNK)):
        sel = start + np.flatnonzero(kind[start:start + CHUNK] == surface)
        if not len(sel):
            continue
        if surface == 3:
            colour[sel] = _sky(dirs[sel, 2] / norm[sel])
            continue
        points = origin + dirs[sel] * t[sel, None]
        footprint = distance[sel] / f  # m per pixel on a surface facing the camera
        if surface == 0:
            grazing = np.maximum(-dirs[sel, 2] / norm[sel], 0.05)
            shade = _shade_ground(scene.road, points[:, :2], footprint / grazing) * (AMBIENT + DIFFUSE * SUN[2])
        elif surface == 1:
            shade = _shade_boxes(boxes, box_index[sel], points, footprint)
            object_id[sel] = boxes.instance[box_index[sel]]
        else:
            shade = EGO * _lambert(normal_ego[sel] @ T_world_ego[:3, :3].T)[:, None]
        fog = (1.0 - np.exp(-distance[sel] / FOG_DISTANCE))[:, None]
        colour[sel] = shade * (1 - fog) + SKY_HORIZON * fog
    depth = np.where(kind < 3, t * axial if distorted else t, np.inf).astype(np.float32)
    rgb = np.clip(np.round(colour * 255.0), 0, 255).astype(np.uint8).reshape(h, w, 3)
    return Rendered(rgb, depth.reshape(h, w), K, object_id.reshape(h, w), model)


# ---------------------------------------------------------------------------------------------------- geometry

_EDGES = np.array([[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4], [0, 4], [1, 5], [2, 6], [3, 7]])


def _to_box_frames(boxes: Boxes, vectors: np.ndarray) -> np.ndarray:
    """(..., n, 3) world vectors (broadcast against the n boxes) turned into each box's frame (yaw undone)."""
    c, s = np.cos(boxes.yaws), np.sin(boxes.yaws)
    x, y = vectors[..., 0], vectors[..., 1]
    along = c * x + s * y
    return np.stack([along, -s * x + c * y, np.broadcast_to(vectors[..., 2], along.shape)], axis=-1)


def _slab(origins, dirs, half) -> tuple[np.ndarray, np.ndarray]:
    """Entry and exit ray parameters of axis-aligned boxes [-half, half]. origins, dirs, half : three
    arrays each (the x, y, z components), all broadcast together; -> tnear, tfar. A ray misses where
    tnear > tfar."""
    near = far = None
    with np.errstate(divide="ignore", invalid="ignore"):
        for o, d, a in zip(origins, dirs, half):
            inv = 1.0 / d
            t1, t2 = (-a - o) * inv, (a - o) * inv
            lo, hi = np.fmin(t1, t2), np.fmax(t1, t2)
            near = lo if near is None else np.fmax(near, lo)
            far = hi if far is None else np.fmin(far, hi)
    return near, far


def _screen_rects(boxes: Boxes, origin, R_world_cam, model: CameraModel, w: int, h: int) -> np.ndarray:
    """(n, 4) int pixel bounds [col0, col1, row0, row1] (inclusive, 1 px margin) of each box's projection,
    clipped to the image; col0 > col1 where the box cannot be seen (behind the lens or off screen).

    The part of a box in front of the plane depth = NEAR is a convex polytope whose vertices are the
    corners in front and the crossings of the box's edges with that plane; its projection's bounds are
    those of the projected vertices."""
    cam = (boxes.corners() - origin) @ R_world_cam  # (n, 8, 3) body frame
    a, b = cam[:, _EDGES[:, 0]], cam[:, _EDGES[:, 1]]  # (n, 12, 3)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (NEAR - a[..., 0]) / (b[..., 0] - a[..., 0])
    crossing = a + np.clip(s, 0, 1)[..., None] * (b - a)
    crosses = (a[..., 0] < NEAR) != (b[..., 0] < NEAR)
    vertices = np.concatenate([cam, crossing], axis=1)
    valid = np.concatenate([cam[..., 0] >= NEAR, crosses], axis=1)
    in_front = np.concatenate([np.maximum(vertices[..., :1], NEAR), vertices[..., 1:]], axis=-1)
    pixels = model.project(in_front)
    bounds = []
    for coord, size in ((pixels[..., 0], w), (pixels[..., 1], h)):
        lo = np.where(valid, coord, np.inf).min(axis=1)
        hi = np.where(valid, coord, -np.inf).max(axis=1)
        # pixel k (centre k + 0.5) can meet the box when lo <= k + 0.5 <= hi
        bounds += [np.clip(np.ceil(lo - 0.5) - 1, 0, size), np.clip(np.floor(hi - 0.5) + 1, -1, size - 1)]
    rects = np.stack(bounds, axis=1)
    rects[~valid.any(axis=1)] = [1, 0, 1, 0]
    return rects.astype(int)


def _box_hits(boxes: Boxes, origin, dirs: np.ndarray, R_world_cam, model: CameraModel, max_range: float,
              distorted: bool = False):
    """Nearest box along each ray: dirs (h, w, 3) world rays from ``origin`` (3,) -> ray parameter (h, w) float
    (inf: no box) and index (h, w) int into ``boxes`` (-1: none). Boxes containing the lens are skipped.
    Through a distorted lens a box's projected corners do not bound its image, so every tile tests every box
    in range."""
    h, w = dirs.shape[:2]
    depth, index = np.full((h, w), np.inf), np.full((h, w), -1)
    if not len(boxes):
        return depth, index
    half = boxes.sizes / 2.0
    local_origin = _to_box_frames(boxes, origin - boxes.centers)  # (n, 3)
    gap = np.linalg.norm(np.maximum(np.abs(local_origin) - half, 0.0), axis=1)
    if distorted:
        rects = np.tile([0, w - 1, 0, h - 1], (len(boxes), 1))
    else:
        rects = _screen_rects(boxes, origin, R_world_cam, model, w, h)
    keep = (gap > 0) & (gap <= max_range) & (rects[:, 0] <= rects[:, 1]) & (rects[:, 2] <= rects[:, 3])
    if not keep.any():
        return depth, index
    ids = np.flatnonzero(keep)
    rects = rects[ids] // TILE  # tile bounds
    yaws = boxes.yaws[ids]
    turn_x = np.stack([np.cos(yaws), np.sin(yaws), np.zeros_like(yaws)])  # (3, k): world -> box x, y
    turn_y = np.stack([-np.sin(yaws), np.cos(yaws), np.zeros_like(yaws)])
    for ty in range(rects[:, 2].min(), rects[:, 3].max() + 1):
        in_row = (rects[:, 2] <= ty) & (ty <= rects[:, 3])
        for tx in range(rects[:, 0].min(), rects[:, 1].max() + 1):
            sel = np.flatnonzero(in_row & (rects[:, 0] <= tx) & (tx <= rects[:, 1]))
            if not len(sel):
                continue
            rows, cols = slice(ty * TILE, (ty + 1) * TILE), slice(tx * TILE, (tx + 1) * TILE)
            tile = dirs[rows, cols]  # (th, tw, 3)
            # ray directions in the frames of the k boxes: (th, tw, k) x and y, (th, tw, 1) z
            dx, dy = tile @ turn_x[:, sel], tile @ turn_y[:, sel]
            o, a = local_origin[ids[sel]].T, half[ids[sel]].T
            near, far = _slab(o, (dx, dy, tile[..., 2:]), a)
            t = np.where((near <= far) & (near >= NEAR), near, np.inf)
            best = np.argmin(t, axis=-1)
            t_best = np.take_along_axis(t, best[..., None], axis=-1)[..., 0]
            depth[rows, cols] = t_best
            index[rows, cols] = np.where(np.isfinite(t_best), ids[sel][best], -1)
    return depth, index


class EgoBody:
    """The ego vehicle's body as the renderer sees it: ``mesh`` (trimesh.Trimesh, ego frame, m).

    A body and the cameras on it are fixed in the ego frame, so every frame of a scene sees the body alike:
    :meth:`view` casts a camera's pixel rays at it once (per camera pose and camera model) and keeps the answer,
    with the body's ray caster. Pickled as its mesh alone: a worker process casts afresh.
    """

    def __init__(self, mesh: trimesh.Trimesh):
        self.mesh = mesh
        self._views: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}

    @cached_property
    def caster(self) -> RayCaster:
        """The body's ray caster, built on the first view cast."""
        return RayCaster(self.mesh)

    def __getstate__(self) -> dict:
        return {"mesh": self.mesh}

    def __setstate__(self, state: dict) -> None:
        self.__init__(state["mesh"])

    def view(self, camera: Camera, model: CameraModel, body: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Depth (h*w,) float (inf: none) and hit normals (h*w, 3), ego frame, of the body along the rays ``body``
        (h*w, 3), camera frame, of ``camera`` with ``model``. A body hit behind a nearer ground or box loses the
        nearest-surface choice, so casting without that limit changes no pixel."""
        key = (camera.position.tobytes(), camera.rotation.tobytes(), model.intrinsic_matrix().tobytes(),
               str(model.distortion), np.asarray(model.coefficients).tobytes(), float(model.width),
               float(model.height))
        if key not in self._views:
            self._views[key] = _ego_hits(self.caster, camera.position, body @ camera.rotation.T,
                                         np.full(len(body), np.inf))
        return self._views[key]


def _ego_hits(caster: RayCaster, position, dirs: np.ndarray, limit: np.ndarray):
    """First body triangle (the mesh of ``caster``) along each ray: dirs (m, 3) ego-frame rays from ``position``
    (3,) with unit optical-axis component -> depth (m,) float (inf: none) and the hit face normals (m, 3), ego
    frame. Only rays that meet the mesh's bounding box before depth ``limit`` (m,) are cast."""
    depth, normal = np.full(len(dirs), np.inf), np.zeros((len(dirs), 3))
    lo, hi = caster.mesh.bounds
    near, far = _slab(position - (lo + hi) / 2.0, dirs.T, (hi - lo) / 2.0 + 1e-6)
    cast = np.flatnonzero((near <= far) & (far > 0) & (near < limit))
    for start in range(0, len(cast), CHUNK):
        _cast_ego(caster, position, dirs, cast[start:start + CHUNK], depth, normal)
    return depth, normal


def _cast_ego(caster: RayCaster, position, dirs: np.ndarray, cast: np.ndarray, depth, normal):
    """Cast the rays ``dirs[cast]`` at the body (the mesh of ``caster``); write their depths and normals into
    depth, normal."""
    norm = np.linalg.norm(dirs[cast], axis=1)
    unit = dirs[cast] / norm[:, None]
    hits = caster.first_hits(position + EGO_RAY_OFFSET * unit, unit)
    rays = np.flatnonzero(hits.face >= 0)
    if len(rays):
        faces, distance = hits.face[rays], np.linalg.norm(hits.location[rays] - position, axis=1)
        depth[cast[rays]] = distance / norm[rays]
        n = caster.mesh.face_normals[faces]
        normal[cast[rays]] = np.where(np.sum(n * unit[rays], axis=1, keepdims=True) > 0, -n, n)


# ----------------------------------------------------------------------------------------------------- shading


def _lambert(normal: np.ndarray) -> np.ndarray:
    """(m,) light factor of unit world normals (m, 3): ambient plus diffuse sun."""
    return AMBIENT + DIFFUSE * np.maximum(normal @ SUN, 0.0)


def _sky(elevation: np.ndarray) -> np.ndarray:
    """(m, 3) sky colour for rays of sine of elevation ``elevation`` (m,): horizon haze to zenith blue."""
    a = np.clip(elevation, 0.0, 1.0)[:, None] ** 0.6
    return SKY_HORIZON * (1 - a) + SKY_ZENITH * a


def _hash01(ix: np.ndarray, iy: np.ndarray, seed: int) -> np.ndarray:
    """Deterministic pseudo-random values in [0, 1) of integer lattice points (int arrays, same shape)."""
    x = ix.astype(np.int64).astype(np.uint32) * np.uint32(0x8DA6B343)
    y = iy.astype(np.int64).astype(np.uint32) * np.uint32(0xD8163841)
    k = x ^ y ^ np.uint32((seed * 0x9E3779B1) & 0xFFFFFFFF)
    k ^= k >> np.uint32(15)
    k *= np.uint32(0x2C1B3C6D)
    k ^= k >> np.uint32(12)
    k *= np.uint32(0x297A2D39)
    k ^= k >> np.uint32(15)
    return k.astype(np.float64) / 2.0**32


def _noise(x: np.ndarray, y: np.ndarray, cell: float, footprint: np.ndarray, seed: int) -> np.ndarray:
    """Smooth value noise in [-0.5, 0.5) of lattice ``cell`` (m) at coordinates x, y (m, (m,) each), faded to
    0 where a pixel's ``footprint`` (m) exceeds half a cell (the pattern would alias)."""
    gx, gy = x / cell, y / cell
    ix, iy = np.floor(gx), np.floor(gy)
    fx, fy = gx - ix, gy - iy
    fx, fy = fx * fx * (3 - 2 * fx), fy * fy * (3 - 2 * fy)
    ix, iy = ix.astype(np.int64), iy.astype(np.int64)
    top = _hash01(ix, iy, seed) * (1 - fx) + _hash01(ix + 1, iy, seed) * fx
    bottom = _hash01(ix, iy + 1, seed) * (1 - fx) + _hash01(ix + 1, iy + 1, seed) * fx
    return (top * (1 - fy) + bottom * fy - 0.5) * np.clip(2.0 - 4.0 * footprint / cell, 0.0, 1.0)


def _shade_ground(road: Road, xy: np.ndarray, footprint: np.ndarray) -> np.ndarray:
    """(m, 3) unlit albedo of ground points xy (m, 2) world m seen with pixel footprint (m,) m."""
    x, y = xy[:, 0], xy[:, 1]
    colour = np.broadcast_to(GRASS, xy.shape[:1] + (3,)).copy()
    for region, albedo in zip(road.regions, (PAVEMENT, ASPHALT, KERB, MARKING)):
        if region is not None:
            colour[shapely.contains_xy(region, x, y)] = albedo
    grain = (0.5 * _noise(x, y, 0.15, footprint, 1) + 0.35 * _noise(x, y, 0.6, footprint, 2)
             + 0.3 * _noise(x, y, 3.0, footprint, 3))
    return colour * (1.0 + grain)[:, None]


def _shade_boxes(boxes: Boxes, j: np.ndarray, points: np.ndarray, footprint: np.ndarray) -> np.ndarray:
    """(m, 3) lit colour of the surface points (m, 3) world on boxes ``j`` (m,) seen with pixel footprint
    (m,) m: class albedo, per-instance tint, class pattern, Lambert shading of the face normal."""
    half = boxes.sizes[j] / 2.0
    sub = Boxes(boxes.centers[j], boxes.sizes[j], boxes.yaws[j], boxes.classes[j], boxes.instance[j])
    p = _to_box_frames(sub, points - sub.centers)  # (m, 3) box frame
    axis = np.argmax(np.abs(p) / half, axis=1)  # face hit: 0 front/back, 1 sides, 2 top/bottom
    normal_local = np.zeros_like(p)
    normal_local[np.arange(len(j)), axis] = np.sign(p[np.arange(len(j)), axis])
    c, s = np.cos(sub.yaws), np.sin(sub.yaws)
    normal = np.stack([c * normal_local[:, 0] - s * normal_local[:, 1],
                       s * normal_local[:, 0] + c * normal_local[:, 1], normal_local[:, 2]], axis=1)
    cls = sub.classes
    large = np.max(sub.sizes[:, :2], axis=1) > 1.5
    colour = np.where((cls < 0)[:, None], np.where(large[:, None], BUILDING, POLE), CLASS_ALBEDO[np.maximum(cls, 0)])
    tint = 0.8 + 0.35 * _hash01(sub.instance, np.zeros_like(sub.instance), 7)
    colour = colour * tint[:, None]
    side = axis < 2
    height = p[:, 2] + half[:, 2]  # m above the box's bottom
    frac = height / (2 * half[:, 2])
    along = np.where(axis == 0, p[:, 1], p[:, 0])  # horizontal coordinate on the face, m
    along_frac = np.abs(along) / np.where(axis == 0, half[:, 1], half[:, 0])

    def paint(mask, albedo):
        colour[mask] = albedo

    building = (cls < 0) & large
    floor = np.mod(height, 3.2) / 3.2
    paint(building & side & (height > 1.0) & (floor > 0.3) & (floor < 0.8) & (np.mod(along, 2.8) / 2.8 > 0.25)
          & (np.mod(along, 2.8) / 2.8 < 0.75), WINDOW)
    vehicle = (cls >= 0) & (cls <= 2)
    paint(vehicle & side & (frac > 0.55) & (frac < 0.85) & (along_frac < 0.85), GLASS)
    paint(vehicle & (axis == 1) & (height < 0.8) & (frac < 0.3) & (along_frac > 0.45) & (along_frac < 0.8), TYRE)
    paint(((cls == 3) | (cls == 4)) & (frac < 0.4) & (along_frac > 0.35), TYRE)
    person = (cls == 5) | (cls == 6)
    paint(person & (frac > 0.85), SKIN)
    paint(person & (frac < 0.45), GLASS)
    from_top = 2 * half[:, 2] - height
    sign = cls == 7
    plate = np.minimum(2 * half[:, 2], 0.8)
    paint(sign & (from_top > plate), POLE)
    paint(sign & (from_top <= plate) & ((from_top < 0.15 * plate) | (from_top > 0.85 * plate) | (along_frac > 0.7)),
          SIGN_RED)
    light = (cls == 8) & side
    scale = np.minimum(2 * half[:, 2], 1.0) / 3.0  # three lamps in the top metre (or the whole box)
    lamp = np.floor(from_top / scale).astype(int)
    centre = (lamp + 0.5) * scale
    lit = light & (lamp < 3) & (np.abs(from_top - centre) < 0.3 * scale) & (along_frac < 0.6)
    colour[lit] = LAMPS[lamp[lit]]
    grain = (0.25 * _noise(along + 31.0 * axis, height, 0.4, footprint, 4)
             + 0.2 * _noise(along, height, 2.0, footprint, 5))
    return colour * (1.0 + grain)[:, None] * _lambert(normal)[:, None]
