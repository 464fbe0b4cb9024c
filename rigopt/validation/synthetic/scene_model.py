"""The synthetic benchmark's scene data: roads, oriented 3D boxes and ego poses, independent of any rig.

Frames
------
World frame: right-handed, x east, y north, z up, metres, ground at z = 0. Ego frame: ISO 8855 (x
forward, y left, z up) with its origin on the ground at the vehicle's reference point; ``T_world_ego``
(4, 4) maps ego points into the world. Yaws are radians about +z, counter-clockwise from +x.
Timestamps are microseconds, samples at 2 Hz as in the benchmark.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import shapely

#: The benchmark's nine detection classes, in its order.
CLASSES = ("car", "truck", "bus", "motorcycle", "bicycle", "adult", "child", "traffic_sign", "traffic_light")
#: Time between samples (microseconds): 2 Hz.
SAMPLE_INTERVAL_US = 500_000
SPLITS = ("train", "val", "test", "mini")


@dataclass(frozen=True)
class Boxes:
    """n oriented boxes in the world frame.

    centers : (n, 3) float m (box centre, not its bottom); sizes : (n, 3) float m (length along the box's
    heading, width, height); yaws : (n,) float rad; classes : (n,) int index into CLASSES, or -1 for
    unannotated occluders (buildings, poles); instance : (n,) int id stable across a scene's frames.
    """

    centers: np.ndarray
    sizes: np.ndarray
    yaws: np.ndarray
    classes: np.ndarray
    instance: np.ndarray

    def __len__(self) -> int:
        return len(self.yaws)

    @staticmethod
    def empty() -> "Boxes":
        return Boxes(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros(0, dtype=int), np.zeros(0, dtype=int))

    @staticmethod
    def concatenate(parts) -> "Boxes":
        parts = [p for p in parts if len(p)]
        if not parts:
            return Boxes.empty()
        return Boxes(*(np.concatenate([getattr(p, f) for p in parts]) for f in
                       ("centers", "sizes", "yaws", "classes", "instance")))

    def corners(self) -> np.ndarray:
        """(n, 8, 3) float: box corners in the world frame (bottom four, then top four)."""
        signs = np.array([[sx, sy, sz] for sz in (-1, 1) for sx, sy in ((1, 1), (1, -1), (-1, -1), (-1, 1))])
        local = signs[None] * self.sizes[:, None] / 2.0
        c, s = np.cos(self.yaws)[:, None], np.sin(self.yaws)[:, None]
        x = local[..., 0] * c - local[..., 1] * s
        y = local[..., 0] * s + local[..., 1] * c
        return np.stack([x, y, local[..., 2]], axis=-1) + self.centers[:, None]


#: Width (m) of the pavement strip around the road surface, and half-width (m) of a kerb strip.
PAVEMENT_WIDTH, KERB_HALF_WIDTH = 4.0, 0.15


@dataclass(frozen=True)
class Road:
    """The road network of a scene, on the ground (z = 0), world frame.

    surface : list of (k, 2) float polygons of asphalt; markings : (m, 2, 2) float painted line segments
    (start, end) m with ``marking_width`` m; kerbs : (p, 2, 2) float kerb segments; kind : "straight" or
    "junction".
    """

    kind: str
    surface: tuple[np.ndarray, ...]
    markings: np.ndarray
    marking_width: float
    kerbs: np.ndarray

    @cached_property
    def regions(self) -> list:
        """Prepared shapely regions on the ground, world frame: [pavement (the surface widened by
        PAVEMENT_WIDTH), asphalt (the surface), kerbs, markings], None where there is none; built once per road."""
        surface = shapely.union_all([shapely.Polygon(p) for p in self.surface]) if self.surface else None
        segments = {name: np.asarray(getattr(self, name), dtype=float).reshape(-1, 2, 2) for name in ("kerbs", "markings")}
        kerbs = (shapely.union_all(shapely.buffer(shapely.linestrings(segments["kerbs"]), KERB_HALF_WIDTH))
                 if len(segments["kerbs"]) else None)
        markings = (shapely.union_all(shapely.buffer(shapely.linestrings(segments["markings"]), self.marking_width / 2))
                    if len(segments["markings"]) and self.marking_width > 0 else None)
        regions = [surface.buffer(PAVEMENT_WIDTH) if surface is not None else None, surface, kerbs, markings]
        for region in regions:
            if region is not None:
                shapely.prepare(region)
        return regions

    def __getstate__(self) -> dict:
        """The road's fields alone: its regions are rebuilt where they are needed."""
        return {key: value for key, value in self.__dict__.items() if key != "regions"}


@dataclass(frozen=True)
class Frame:
    """One sample: ``timestamp_us``, ``T_world_ego`` (4, 4), and the dynamic agents at that time."""

    timestamp_us: int
    T_world_ego: np.ndarray
    agents: Boxes


@dataclass(frozen=True)
class Scene:
    """A deterministic scene: ``name``, ``seed``, ``split``, its road, static boxes (buildings, poles:
    class -1; parked cars: annotated) and its frames. Nothing in it depends on a rig."""

    name: str
    seed: int
    split: str
    road: Road
    static: Boxes
    frames: tuple[Frame, ...]

    def boxes_at(self, k: int) -> Boxes:
        """Every box present in frame k: static ones and that frame's agents."""
        return Boxes.concatenate([self.static, self.frames[k].agents])
