"""Procedural benchmark scenes from a seed: the road, static boxes, moving agents and the ego's path.

Layout (world frame, see :mod:`rigopt.validation.synthetic.scene_model`): a straight street along x through the origin
(2-4 lanes of ~3.5 m, right-hand traffic), or a four-way junction of that street with a second one along y.
Outside each carriageway's solid edge lines lies a strip (parked cars or a cycle lane), then the kerb,
the sidewalk (pedestrians, street-light poles, signs, lights) and, set back, the buildings. At a junction
the x street has green: its traffic drives through, the y street's inbound traffic queues at its stop
lines and pedestrians cross the y street. The ego drives a lane of the x street at a constant speed,
its path centred on the street's middle, which extends 150 m beyond the path at both ends.

Agents move at constant velocity and are present in the frames where they are on their street; the
bird's-eye footprints of all boxes stay apart at every frame and clear of :data:`EGO_CLEARANCE` around
the ego. Where they would not, the lower-priority box goes (in this order of priority: buildings and poles,
the ego's clearance, signs and lights, parked cars, vehicles, cyclists, pedestrians, crossing pedestrians).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import shapely

from rigopt.validation.synthetic.scene_model import CLASSES, SAMPLE_INTERVAL_US, SPLITS, Boxes, Frame, Road, Scene
from rigopt.errors import RigoptError
from rigopt.geometry import rot_z

#: Box sizes per class: mean, standard deviation, lower and upper clip, each (length, width, height) m.
SIZES = {
    "car": ((4.6, 1.9, 1.7), (0.45, 0.12, 0.2), (3.6, 1.6, 1.35), (5.6, 2.2, 2.3)),
    "truck": ((7.0, 2.5, 3.0), (1.6, 0.2, 0.45), (4.8, 2.0, 2.1), (11.0, 2.9, 4.0)),
    "bus": ((11.0, 2.9, 3.4), (1.2, 0.08, 0.3), (8.5, 2.5, 2.8), (13.5, 3.0, 4.2)),
    "motorcycle": ((2.1, 0.8, 1.5), (0.2, 0.1, 0.15), (1.6, 0.55, 1.1), (2.6, 1.1, 1.9)),
    "bicycle": ((1.7, 0.6, 1.3), (0.15, 0.08, 0.12), (1.3, 0.4, 1.0), (2.1, 0.9, 1.7)),
    "adult": ((0.7, 0.7, 1.75), (0.12, 0.12, 0.1), (0.45, 0.45, 1.45), (1.0, 1.0, 2.05)),
    "child": ((0.5, 0.5, 1.2), (0.08, 0.08, 0.15), (0.3, 0.3, 0.9), (0.7, 0.7, 1.5)),
    "traffic_sign": ((0.08, 0.75, 0.75), (0.02, 0.12, 0.15), (0.04, 0.45, 0.4), (0.15, 1.1, 1.2)),
    "traffic_light": ((0.35, 0.35, 1.0), (0.04, 0.04, 0.1), (0.25, 0.25, 0.7), (0.5, 0.5, 1.3)),
}
#: First seed of each split; a split holds at most SEEDS_PER_SPLIT seeds, so splits never share scenes.
SPLIT_OFFSETS = {"train": 0, "val": 100_000, "test": 200_000, "mini": 300_000}
SEEDS_PER_SPLIT = 100_000
#: A seed offset k (``rigopt bench generate --seed k``) moves every split's seeds by k times this, past the
#: ranges of all four splits, so that different offsets never share a scene.
SEED_OFFSET_STEP = 10_000_000
#: Footprint (length, width) m centred on the ego origin that every box keeps out of: the largest
#: benchmark vehicles (8.5 x 3.0 m) fit, with >= 2.5 m ahead/behind and 0.6 m beside a 5 x 2.2 m car.
EGO_CLEARANCE = (10.0, 3.4)
MAX_EGO_SPEED = 48.0 / 3.6
JUNCTION_PROBABILITY = 0.4
MARKING_WIDTH = 0.15
_GAP = 0.05  # every agent keeps this far (m) from any other box
_DASH, _DASH_GAP, _PIECE = 3.0, 6.0, 20.0  # dashed lines; longest piece of a solid line or kerb (m)
_VEHICLES, _VEHICLE_MIX = ("car", "truck", "bus", "motorcycle"), (0.72, 0.10, 0.06, 0.12)
_ID = {name: k for k, name in enumerate(CLASSES)}


def split_seeds(split: str, count: int) -> list[int]:
    """The seeds of the first ``count`` scenes of ``split``; ranges of different splits are disjoint."""
    if split not in SPLIT_OFFSETS:
        raise RigoptError(f"unknown split {split!r}; valid splits: {', '.join(SPLITS)}")
    if not 1 <= count <= SEEDS_PER_SPLIT:
        raise RigoptError(f"scene count must be in [1, {SEEDS_PER_SPLIT}], got {count}")
    return list(range(SPLIT_OFFSETS[split], SPLIT_OFFSETS[split] + count))


def scene_name(split: str, index: int, seed: int) -> str:
    """``scene-<split>-<index:04d>-s<seed>``: the name of a generated split's ``index``-th scene; the seed at
    its end is what ``generate.split_layout`` regenerates the scene from."""
    return f"scene-{split}-{index:04d}-s{seed}"


def split_scenes(split: str, count: int, n_frames: int = 40, seed_offset: int = 0) -> list[Scene]:
    """The first ``count`` scenes of ``split``, ``n_frames`` samples each, under seed offset ``seed_offset``
    (0 or more; see SEED_OFFSET_STEP), named by ``scene_name``: what ``rigopt bench generate`` renders."""
    if isinstance(seed_offset, bool) or not isinstance(seed_offset, (int, np.integer)) or seed_offset < 0:
        raise RigoptError(f"the seed offset must be a whole number >= 0, got {seed_offset!r}")
    seeds = [seed + int(seed_offset) * SEED_OFFSET_STEP for seed in split_seeds(split, count)]
    return [generate_scene(seed, split, n_frames, name=scene_name(split, k, seed)) for k, seed in enumerate(seeds)]


@dataclass(frozen=True)
class _Street:
    """A straight street through the origin; s runs along ``axis``, t to its left (``normal``), metres.

    directions : (k,) +1 (along the axis) or -1 per lane, from the right (t < 0) to the left;
    parking : (2,) bool per side (right, left): parked cars in the shoulder strip, else a cycle lane;
    cross, cross_walk : the crossing street's asphalt half-width and sidewalk width (0: no crossing).
    """

    axis: np.ndarray
    half_length: float
    lane_width: float
    directions: np.ndarray
    shoulder: float
    parking: np.ndarray
    sidewalk: float
    setback: float
    cross: float = 0.0
    cross_walk: float = 0.0

    @property
    def normal(self):
        return np.array([-self.axis[1], self.axis[0]])

    @property
    def carriage(self):
        return len(self.directions) * self.lane_width / 2

    @property
    def edge(self):
        return self.carriage + self.shoulder

    @property
    def stop(self):
        """|s| of the stop lines before the crossing."""
        return self.cross + self.cross_walk + 1.0

    def at(self, s, t):
        """World (..., 2) of street coordinates s, t (broadcast)."""
        s, t = np.broadcast_arrays(np.asarray(s, float), np.asarray(t, float))
        return s[..., None] * self.axis + t[..., None] * self.normal

    def lane_t(self, i):
        return -self.carriage + (i + 0.5) * self.lane_width

    def heading(self, d):
        """Yaw (rad) of travel in direction d = +-1."""
        return float(np.arctan2(d * self.axis[1], d * self.axis[0]))

    def spans(self, cut):
        """(s0, s1) pieces of the street outside |s| < cut (the whole street when cut <= 0)."""
        h = self.half_length
        return [(-h, h)] if cut <= 0 else [(-h, -cut), (cut, h)]

    def rectangle(self, half_width, s0=None, s1=None):
        """(4, 2) corners of the band |t| <= half_width from s0 to s1 (default: the whole street)."""
        s0, s1 = -self.half_length if s0 is None else s0, self.half_length if s1 is None else s1
        return self.at([s0, s1, s1, s0], [-half_width, -half_width, half_width, half_width])


def _street(rng, axis, half_length) -> _Street:
    k = int(rng.integers(2, 5))
    along = {2: 1, 3: int(rng.integers(1, 3)), 4: 2}[k]
    parking = rng.random(2) < 0.55
    return _Street(np.asarray(axis, float), half_length, rng.uniform(3.3, 3.7), np.where(np.arange(k) < along, 1, -1),
                   rng.uniform(2.3, 2.6) if parking.any() else rng.uniform(1.5, 2.2), parking,
                   rng.uniform(2.8, 5.0), rng.uniform(0.0, 6.0))


def _size(rng, name):
    mean, std, low, high = SIZES[name]
    return np.clip(rng.normal(mean, std), low, high)


def _rectangles(xy, size, yaw):
    """(n, 5, 2) closed bird's-eye rectangles of centres xy (n, 2), (length, width) size (n, 2), yaws (n,)."""
    local = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1], [1, 1]]) * size[:, None] / 2
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    return np.stack([local[..., 0] * c - local[..., 1] * s, local[..., 0] * s + local[..., 1] * c], -1) + xy[:, None]


def _lines(st, s0, s1, t, dashed, phase=0.0):
    """(m, 2, 2) segments of a line at offset t from s0 to s1: dashes, or pieces of at most _PIECE m."""
    if dashed:
        starts = np.arange(s0 + phase, s1 - _DASH, _DASH + _DASH_GAP)
        ends = starts + _DASH
    else:
        edges = np.linspace(s0, s1, int(np.ceil((s1 - s0) / _PIECE)) + 1)
        starts, ends = edges[:-1], edges[1:]
    return np.stack([st.at(starts, t), st.at(ends, t)], axis=1)


def _across(st, s, t0, t1):
    """(1, 2, 2): one segment across the street at s from t0 to t1."""
    return np.array([[st.at(s, t0), st.at(s, t1)]])


def _road(rng, kind, streets, walks) -> Road:
    surface, markings, kerbs = [], [], []
    for n, st in enumerate(streets):
        surface += [st.rectangle(st.edge, s0, s1) for s0, s1 in st.spans(st.cross if n else 0.0)]
        kerbs += [_lines(st, s0, s1, side * st.edge, False) for s0, s1 in st.spans(st.cross) for side in (-1, 1)]
        k, w = len(st.directions), st.lane_width
        for s0, s1 in st.spans(st.stop if st.cross else 0.0):
            markings += [_lines(st, s0, s1, side * st.carriage, False) for side in (-1, 1)]
            for i in range(1, k):
                centre = st.directions[i] != st.directions[i - 1]
                markings.append(_lines(st, s0, s1, -st.carriage + i * w, not (centre and k == 4), rng.uniform(0, 9)))
        divider = -st.carriage + w * int(np.sum(st.directions > 0))
        for c, h, approaches in walks[n]:  # crosswalk edges, then stop lines of the approaching lanes
            markings += [_across(st, c + e, -st.edge + 0.3, st.edge - 0.3) for e in (-h + 0.3, h - 0.3)]
            markings += [_across(st, c - d * (h + 1), *((-st.carriage, divider) if d > 0 else (divider, st.carriage)))
                         for d in approaches]
    return Road(kind, tuple(surface), np.concatenate(markings), MARKING_WIDTH, np.concatenate(kerbs))


def _statics(rng, streets, walks):
    """Rows (x, y, z_bottom, length, width, height, yaw, class, rank, kind) of static candidates; kind 0:
    building, 1: street furniture (off the asphalt), 2: parked car (away from crossings)."""
    rows = []

    def add(xy, bottom, size, yaw, cls, rank, kind):
        rows.append((*xy, bottom, *size, yaw, cls, rank, kind))

    def head(st, s, t, d, name):
        """A pole at (s, t) carrying a sign or light head that faces traffic travelling in direction d."""
        size, bottom = _size(rng, name), rng.uniform(1.9, 2.5) if name == "traffic_sign" else rng.uniform(2.4, 3.2)
        pole = 0.12 if name == "traffic_sign" else 0.2
        add(st.at(s, t), 0.0, (pole, pole, bottom + size[2]), st.heading(1), -1, 0, 1)
        add(st.at(s - d * (pole / 2 + size[0] / 2 + 0.02), t), bottom, size, st.heading(-d), _ID[name], 2, 1)

    for n, st in enumerate(streets):
        h = st.half_length
        for side in (-1, 1):
            s = -h - rng.uniform(0, 20)
            while s < h:  # buildings, frontage along the street
                length, depth = rng.uniform(10, 35), rng.uniform(8, 20)
                t = side * (st.edge + st.sidewalk + st.setback + rng.uniform(0.2, 2.0) + depth / 2)
                add(st.at(s + length / 2, t), 0.0, (length, depth, rng.uniform(4, 25)), st.heading(1), -1, 0, 0)
                s += length + rng.uniform(1, 12)
            for s in np.arange(-h + rng.uniform(0, 30), h, rng.uniform(25, 40)):  # street lights
                add(st.at(s, side * (st.edge + 0.5)), 0.0, (0.25, 0.25, rng.uniform(7, 9)), st.heading(1), -1, 0, 1)
            for s in rng.uniform(-h, h, rng.poisson(h / 60)):
                head(st, s, side * (st.edge + 0.65), -side, "traffic_sign")
            if st.parking[(side + 1) // 2]:
                s, d = -h + rng.uniform(0, 10), -side
                while s < h:
                    size = _size(rng, "car")
                    if all(abs(s + size[0] / 2 - c) > h_walk + 6 for c, h_walk, _ in walks[n]):
                        add(st.at(s + size[0] / 2, side * (st.carriage + st.shoulder / 2)), 0.0, size,
                            st.heading(d), _ID["car"], 3, 2)
                    s += size[0] + rng.uniform(0.8, 3.0) + rng.exponential(rng.uniform(1, 15))
        for c, h_walk, approaches in walks[n]:
            for d in approaches:
                head(st, c - d * (h_walk - 0.5), -d * (st.edge + 0.65), d, "traffic_light")
    rows = np.array(rows)
    corridors = shapely.polygons([st.rectangle(st.edge + st.sidewalk + st.setback) for st in streets])
    asphalt = shapely.polygons([st.rectangle(st.edge) for st in streets])
    forbidden = [shapely.union_all(corridors), shapely.union_all(asphalt),  # per kind; then the junction's area:
                 shapely.intersection_all(corridors).buffer(6.0) if len(streets) > 1 else shapely.Polygon()]
    polys = shapely.polygons(_rectangles(rows[:, :2], rows[:, 3:5], rows[:, 6]))
    ok = np.ones(len(rows), bool)
    for kind, area in enumerate(forbidden):
        shapely.prepare(area)
        ok[rows[:, 9] == kind] = ~shapely.intersects(area, polys[rows[:, 9] == kind])
    return rows[ok]


def _agents(rng, streets, walks, duration, ego_speed, ego_lane, ego_q):
    """Rows (x, y at t_ref, t_ref, vx, vy, length, width, height, yaw, class, rank, presence axis x, y,
    presence half-length) of the agent candidates: present while |position . axis| <= half-length."""
    rows, traffic = [], rng.uniform(5, 40)

    def lane(n, st, t, d, speed, q_start, q_end, t_ref, rank, ego=False, names=_VEHICLES, mix=_VEHICLE_MIX,
             spacing=None):
        """Vehicles nose to tail at offset t from q_start towards q_end (q = d s: along travel) at time t_ref."""
        step = np.sign(q_end - q_start)
        q = q_start + step * rng.exponential(3.0)
        while (q_end - q) * step > 0:
            name = names[rng.choice(len(mix), p=mix)]
            size = _size(rng, name)
            centre = q + step * size[0] / 2
            ego_gap = abs(centre - ego_q) - size[0] / 2 - EGO_CLEARANCE[0] / 2
            clear = any(abs(d * centre - c) < h_walk + 1 + size[0] / 2 for c, h_walk, _ in walks[n]) or (
                st.cross and abs(centre) < st.stop + size[0] / 2)  # stopped traffic keeps these clear
            if (q_end - centre) * step > 0 and not (ego and ego_gap < 2.0) and not (speed == 0 and clear):
                rows.append((*st.at(d * centre, t), t_ref, *(speed * d * st.axis), *size, st.heading(d), _ID[name],
                             rank, *st.axis, st.half_length))
            gap = spacing() if spacing else 2.0 + speed * rng.uniform(0.8, 2.0) + rng.exponential(traffic)
            q += step * (size[0] + gap)

    for n, st in enumerate(streets):
        h = st.half_length
        for i, d in enumerate(st.directions):
            speed, t = rng.uniform(6, 14), st.lane_t(i)
            if n == 0:
                if i == ego_lane or (ego_speed == 0 and d == st.directions[ego_lane]):  # a jam or a red light
                    speed = ego_speed
                elif rng.random() < 0.05:
                    speed = 0.0
                reach = h + speed * duration / 2 + 10
                lane(n, st, t, d, speed, -reach, reach, duration / 2, 4, ego=i == ego_lane)
            else:  # red light: a queue at the stop line, and the traffic that has already left the junction
                lane(n, st, t, d, 0.0, -st.stop, -h - 5, 0.0, 4)
                lane(n, st, t, d, speed, st.stop + 1, h + 5, 0.0, 4)
        for side in (-1, 1):
            if not st.parking[(side + 1) // 2]:  # cyclists in the cycle lane (at a red light: those leaving it)
                speed, d = rng.uniform(3, 7), -side
                reach = h + speed * duration / 2 + 10
                q0, q1, t_ref = (st.stop + 1, h + 5, 0.0) if n else (-reach, reach, duration / 2)
                lane(n, st, side * (st.carriage + st.shoulder / 2), d, speed, q0, q1, t_ref, 5, names=("bicycle",),
                     mix=(1.0,), spacing=lambda: 5 + rng.exponential(60))
            s, spacing = -h - 5 + rng.exponential(5), rng.uniform(5, 25)
            while s < h + 5:  # pedestrians on the sidewalk, some standing
                name = "child" if rng.random() < 0.15 else "adult"
                size, d = _size(rng, name), rng.choice((-1, 1))
                speed = 0.0 if rng.random() < 0.2 else np.clip(rng.normal(1.35, 0.2), 0.7, 2.0) * (
                    0.85 if name == "child" else 1.0)
                t = side * (st.edge + rng.uniform(1.6, max(1.7, st.sidewalk - 0.5)))
                yaw = st.heading(d) if speed else rng.uniform(-np.pi, np.pi)
                rows.append((*st.at(s, t), duration / 2, *(speed * d * st.axis), *size, yaw, _ID[name], 6, *st.axis, h))
                s += 1.0 + rng.exponential(spacing)
    main = streets[0]
    for _ in range(int(rng.integers(10, 30))):  # pedestrians crossing the main street, at its crosswalk or not
        c, h_walk, _ = walks[0][0] if walks[0] and rng.random() < 0.6 else (ego_q + rng.uniform(-60, 60), 1.0, ())
        name, d, speed = "child" if rng.random() < 0.15 else "adult", rng.choice((-1, 1)), rng.uniform(1.0, 1.7)
        size = _size(rng, name)
        xy = main.at(c + rng.uniform(-h_walk + 0.5, h_walk - 0.5), rng.uniform(-main.edge, main.edge))
        rows.append((*xy, duration / 2, *(speed * d * main.normal), *size, float(np.arctan2(*(d * main.normal)[::-1])),
                     _ID[name], 7, *main.normal, main.edge + main.sidewalk + main.setback - 0.6))
    return np.array(rows)


def _keep(static_rect, static_rank, agent_rect, present, agent_rank):
    """Greedy removal of overlaps in priority order (rank, then index): (static keep (S,), agent keep (A,)).

    static_rect : (S, 5, 2); agent_rect : (A, F, 5, 2) bird's-eye rectangles; present : (A, F) bool.
    """
    n_static = len(static_rect)
    statics = shapely.polygons(static_rect)
    tree = shapely.STRtree(statics)
    i, j = tree.query(statics, predicate="intersects")
    edges = [np.stack([i, j], 1)]
    a, f = np.nonzero(present)
    rects = agent_rect[a, f]
    i, j = tree.query(shapely.polygons(rects), predicate="intersects")
    edges.append(np.stack([n_static + a[i], j], 1))
    shifted = shapely.polygons(rects + np.stack([f * 1e5, 0 * f], 1)[:, None])  # one frame per 100 km of x
    i, j = shapely.STRtree(shifted).query(shifted, predicate="intersects")
    edges.append(np.stack([n_static + a[i], n_static + a[j]], 1))
    edges = np.unique(np.sort(np.concatenate(edges), axis=1), axis=0)
    edges = edges[edges[:, 0] != edges[:, 1]]
    rank = np.concatenate([static_rank, agent_rank])
    neighbours = [[] for _ in rank]
    for u, v in edges:
        neighbours[u].append(v)
        neighbours[v].append(u)
    keep = np.zeros(len(rank), bool)
    for u in np.lexsort((np.arange(len(rank)), rank)):
        keep[u] = not any(keep[v] for v in neighbours[u])
    return keep[:n_static], keep[n_static:]


def generate_scene(seed: int, split: str = "train", n_frames: int = 40, name: str | None = None) -> Scene:
    """The scene of ``seed``: the same seed always gives identical arrays. ``n_frames`` samples at 2 Hz;
    ``name`` defaults to ``scene-{split}-s{seed}``."""
    if split not in SPLITS:
        raise RigoptError(f"unknown split {split!r}; valid splits: {', '.join(SPLITS)}")
    if n_frames < 1 or seed < 0:
        raise RigoptError(f"n_frames must be >= 1 and seed >= 0, got {n_frames} and {seed}")
    rng, dt = np.random.default_rng(seed), SAMPLE_INTERVAL_US * 1e-6
    duration = (n_frames - 1) * dt
    ego_speed = 0.0 if rng.random() < 0.1 else rng.uniform(0.0, MAX_EGO_SPEED)
    main = _street(rng, (1.0, 0.0), 150.0 + ego_speed * duration / 2)
    streets, walks = [main], [[]]
    if rng.random() < JUNCTION_PROBABILITY:
        cross = _street(rng, (0.0, 1.0), 150.0)
        streets = [dataclasses.replace(main, cross=cross.edge, cross_walk=cross.sidewalk),
                   dataclasses.replace(cross, cross=main.edge, cross_walk=main.sidewalk)]
        walks = [[(-st.cross - st.cross_walk / 2, st.cross_walk / 2, (1,)),
                  (st.cross + st.cross_walk / 2, st.cross_walk / 2, (-1,))] for st in streets]
    elif rng.random() < 0.5:  # a signalised crosswalk near the ego's path
        walks = [[(rng.uniform(-1, 1) * (ego_speed * duration / 2 + 40), 2.0, (1, -1))]]
    main, kind = streets[0], "junction" if len(streets) > 1 else "straight"
    i_ego = int(rng.integers(len(main.directions)))
    d_ego, ego_q = int(main.directions[i_ego]), rng.uniform(-10, 10)  # ego_q: position along travel at mid-time
    red = [c - d_ego * (h + 1) for c, h, approaches in walks[0] if d_ego in approaches]
    if ego_speed == 0 and red:  # stopped at the stop line
        ego_q = d_ego * red[0] - EGO_CLEARANCE[0] / 2 - rng.uniform(0.5, 3.0)

    road, statics = _road(rng, kind, streets, walks), _statics(rng, streets, walks)
    agents, times = _agents(rng, streets, walks, duration, ego_speed, i_ego, ego_q), np.arange(n_frames) * dt
    ego_xy = main.at(d_ego * (ego_q + ego_speed * (times - duration / 2)), main.lane_t(i_ego))
    ego_yaw = main.heading(d_ego)

    xy = agents[:, None, :2] + (times - agents[:, 2:3])[..., None] * agents[:, None, 3:5]  # (A, F, 2)
    present = np.abs(np.einsum("afk,ak->af", xy, agents[:, 11:13])) <= agents[:, 13:14]
    agents, xy, present = (v[present.any(1)] for v in (agents, xy, present))
    rects = _rectangles(xy.reshape(-1, 2), np.repeat(agents[:, 5:7] + 2 * _GAP, n_frames, 0),
                        np.repeat(agents[:, 8], n_frames)).reshape(len(agents), n_frames, 5, 2)
    ego_rect = _rectangles(ego_xy, np.tile(EGO_CLEARANCE, (n_frames, 1)), np.full(n_frames, ego_yaw))
    keep_static, keep_agent = _keep(
        _rectangles(statics[:, :2], statics[:, 3:5], statics[:, 6]), statics[:, 8],
        np.concatenate([ego_rect[None], rects]), np.vstack([np.ones(n_frames, bool), present]),
        np.concatenate([[1], agents[:, 10]]))
    assert keep_agent[0], f"seed {seed}: the ego's clearance meets a building or pole"  # a layout bug
    statics, (agents, xy, present) = statics[keep_static], (v[keep_agent[1:]] for v in (agents, xy, present))

    static = Boxes(np.column_stack([statics[:, :2], statics[:, 2] + statics[:, 5] / 2]), statics[:, 3:6].copy(),
                   statics[:, 6].copy(), statics[:, 7].astype(int), np.arange(1, len(statics) + 1))
    instance = np.arange(len(agents)) + len(statics) + 1
    base = int(rng.integers(1_530_000_000, 1_700_000_000)) * 1_000_000
    frames = []
    for k in range(n_frames):
        m = present[:, k]
        T = np.eye(4)
        T[:3, :3], T[:2, 3] = rot_z(ego_yaw), ego_xy[k]
        frames.append(Frame(base + k * SAMPLE_INTERVAL_US, T, Boxes(
            np.column_stack([xy[m, k], agents[m, 7] / 2]), agents[m, 5:8], agents[m, 8], agents[m, 9].astype(int),
            instance[m])))
    return Scene(name or f"scene-{split}-s{seed}", seed, split, road, static, tuple(frames))
