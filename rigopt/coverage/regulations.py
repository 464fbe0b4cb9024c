"""Requirement presets modelled on regulations' close-proximity fields, and a rig's coverage of them.

Each preset is a ground region around the vehicle (rectangles placed against the body's outline, joined)
with the heights at which a test object there must be seen: UN R158 behind the vehicle, R151 along the
nearside, R159 in front, R46 classes IV, V and VI, and TfL's Direct Vision Standard. Their figures, sources
and simplifications are in docs/regulations.md.

Frames: ISO 8855 vehicle frame (x forward, y left, z up; metres; the vehicle's origin on the ground). The
body's outline is its footprint (the convex hull of the mesh on the ground, mirrors included): ``front``
and ``rear`` are its largest and smallest x, the ``nearside`` and ``offside`` its extreme y on the kerb side
and on the other side. In right-hand traffic (the default) the nearside is the right, -y; in left-hand
traffic it is the left, +y. The driver's ocular points (the R46 fields) are taken at ``driver_eye_x``.

A field never asks for ground the body stands on or overhangs: the region is the field less the footprint
grown by ``clearance`` (0.3 m, R158's own near edge; a test object has a body of its own, and the ground
right under a bumper is hidden from every camera above it).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import shapely

from rigopt.camera import CameraModel
from rigopt.coverage.footprint import Footprint
from rigopt.coverage.visibility import DEFAULT_MAX_RANGE, visible_by
from rigopt.errors import RigoptError
from rigopt.mounting.practice import keep_out_boxes
from rigopt.rig.model import Rig
from rigopt.vehicle.model import Vehicle

TRAFFIC = ("right", "left")
#: The suffix of a preset key for left-hand traffic (``r151:lht``); ``:rht`` names the default.
TRAFFIC_SUFFIX = {"right": "rht", "left": "lht"}
#: Ground (m) next to the body's footprint that no field asks for (R158's near edge, used for every field).
NEAR_BODY_CLEARANCE = 0.3
#: Distance (m) from the body's front to the driver's ocular points: cab-over trucks and buses (M2, M3, N2, N3)
#: and bonneted vehicles (M1, N1). rigopt's assumptions: the vehicle spec holds no seat.
EYE_SETBACK = {"heavy": 1.2, "light": 2.2}
HEAVY_CATEGORIES = ("M2", "M3", "N2", "N3")
#: The lines a field's edges are measured from: x lines (offsets forward, m) and side lines (offsets outward,
#: away from the body, m).
X_LINES = ("front", "rear", "eye")
SIDE_LINES = ("nearside", "offside")


@dataclass(frozen=True)
class FieldBox:
    """One rectangle of a field: x from ``back`` to ``ahead``, y from its ``offside`` to its ``nearside`` edge.

    Each edge is (line, offset m): ``back``/``ahead`` lie ``offset`` m forward (negative: behind) of the
    ``front``, ``rear`` or ``eye`` line; ``offside``/``nearside`` lie ``offset`` m outward (away from the body)
    of the ``nearside`` or ``offside`` line. E.g. R46 class V: back ('eye', -1.75), ahead ('eye', 1.0),
    offside ('nearside', 0.0), nearside ('nearside', 2.0).
    """

    back: tuple[str, float]
    ahead: tuple[str, float]
    offside: tuple[str, float]
    nearside: tuple[str, float]

    def __post_init__(self):
        for name, lines in (("back", X_LINES), ("ahead", X_LINES), ("offside", SIDE_LINES), ("nearside", SIDE_LINES)):
            line, offset = getattr(self, name)
            if line not in lines or not np.isfinite(offset):
                raise RigoptError(f"a field box's {name} edge is (line, offset m) with line one of "
                                  f"{', '.join(lines)} and a finite offset, got {getattr(self, name)!r}")


@dataclass(frozen=True)
class BodyLines:
    """The lines fields are placed against, from the footprint: ``front``, ``rear``, ``eye`` x (m);
    ``nearside``, ``offside`` y (m); ``outward`` the y direction (+1 or -1) from the body to the nearside."""

    front: float
    rear: float
    eye: float
    nearside: float
    offside: float
    outward: float

    def x(self, edge: tuple[str, float]) -> float:
        line, offset = edge
        return getattr(self, line) + offset

    def y(self, edge: tuple[str, float]) -> float:
        line, offset = edge
        direction = self.outward if line == "nearside" else -self.outward
        return getattr(self, line) + direction * offset


def driver_eye_x(vehicle: Vehicle) -> float:
    """x (m) of the driver's ocular points: EYE_SETBACK behind the body's front, by category."""
    kind = "heavy" if vehicle.category in HEAVY_CATEGORIES else "light"
    return float(vehicle.mesh.bounds[1][0]) - EYE_SETBACK[kind]


def body_lines(vehicle: Vehicle, traffic: str = "right") -> BodyLines:
    """The footprint's extreme lines of ``vehicle`` for ``traffic`` ('right': nearside -y; 'left': +y)."""
    if traffic not in TRAFFIC:
        raise RigoptError(f"unknown traffic side {traffic!r}; use right (nearside on the right, -y) or left")
    (x_min, y_min, _), (x_max, y_max, _) = np.asarray(vehicle.mesh.bounds, dtype=float)
    near, off, outward = (y_min, y_max, -1.0) if traffic == "right" else (y_max, y_min, 1.0)
    return BodyLines(float(x_max), float(x_min), driver_eye_x(vehicle), float(near), float(off), outward)


@dataclass(frozen=True)
class RegionPreset:
    """A requirement: the ground ``boxes`` (FieldBox) around the vehicle, joined, less the footprint grown by
    ``clearance`` m, where a test object must be seen at every one of ``heights`` (m above the ground).

    ``key`` names it on the command line (``r151``, ``r151:lht`` in left-hand traffic), ``title`` says what it
    is, ``source`` cites the regulation; ``traffic`` ('right' or 'left') puts the nearside at -y or +y.
    """

    key: str
    title: str
    source: str
    heights: tuple[float, ...]
    boxes: tuple[FieldBox, ...]
    traffic: str = "right"
    clearance: float = NEAR_BODY_CLEARANCE

    def __post_init__(self):
        if not self.heights or not all(np.isfinite(h) and h >= 0 for h in self.heights):
            raise RigoptError(f"preset {self.key}: heights must be metres above the ground, >= 0, got {self.heights!r}")
        if self.traffic not in TRAFFIC or not self.boxes or not self.clearance >= 0:
            raise RigoptError(f"preset {self.key}: needs boxes, traffic right or left and a clearance >= 0")

    @property
    def base_key(self) -> str:
        """The key without its traffic suffix."""
        return self.key.split(":")[0]

    def with_traffic(self, traffic: str) -> "RegionPreset":
        """This preset in ``traffic`` ('right' or 'left'); the key gets ``:lht`` for left-hand traffic."""
        if traffic not in TRAFFIC:
            raise RigoptError(f"unknown traffic side {traffic!r}; use right or left")
        key = self.base_key + (f":{TRAFFIC_SUFFIX['left']}" if traffic == "left" else "")
        return replace(self, key=key, traffic=traffic)

    def polygon(self, vehicle: Vehicle) -> shapely.Polygon:
        """The ground region in the vehicle frame (m): the boxes' union less the grown footprint (a Polygon for
        every preset on a convex footprint; a MultiPolygon only where a body splits a field)."""
        lines = body_lines(vehicle, self.traffic)
        rectangles = []
        for box in self.boxes:
            x0, x1 = sorted((lines.x(box.back), lines.x(box.ahead)))
            y0, y1 = sorted((lines.y(box.offside), lines.y(box.nearside)))
            rectangles.append(shapely.box(x0, y0, x1, y1))
        field = shapely.union_all(rectangles)
        return field.difference(Footprint.of_mesh(vehicle.mesh).polygon.buffer(self.clearance))

    def ground_samples(self, vehicle: Vehicle, spacing: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
        """((g, 2), (b, 2)) float m: the grid points (on multiples of ``spacing``) strictly inside the polygon,
        and its boundary sampled at most ``spacing`` apart (every corner included)."""
        polygon = self.polygon(vehicle)
        return grid_inside(polygon, spacing), boundary_samples(polygon, spacing)

    def points(self, vehicle: Vehicle, spacing: float = 0.5) -> np.ndarray:
        """(n, 3) float m, vehicle frame: the grid over the polygon and its boundary samples
        (:meth:`ground_samples`) at every height; heights vary slowest, the grid before the boundary."""
        grid, boundary = self.ground_samples(vehicle, spacing)
        return at_heights(np.concatenate([grid, boundary]), self.heights)


def _check_spacing(spacing: float) -> float:
    spacing = float(spacing)
    if not np.isfinite(spacing) or spacing <= 0:
        raise RigoptError(f"the sampling spacing must be a positive number of metres, got {spacing}")
    return spacing


def grid_inside(geometry, spacing: float) -> np.ndarray:
    """(g, 2) float m: the points k * ``spacing`` (k integer, both axes) strictly inside ``geometry``."""
    spacing = _check_spacing(spacing)
    if geometry.is_empty:
        return np.zeros((0, 2))
    x0, y0, x1, y1 = geometry.bounds
    xs = np.arange(np.ceil(x0 / spacing), np.floor(x1 / spacing) + 1) * spacing
    ys = np.arange(np.ceil(y0 / spacing), np.floor(y1 / spacing) + 1) * spacing
    xx, yy = (a.ravel() for a in np.meshgrid(xs, ys))
    inside = shapely.contains_xy(geometry, xx, yy)
    return np.column_stack([xx[inside], yy[inside]])


def boundary_samples(geometry, spacing: float) -> np.ndarray:
    """(b, 2) float m: every ring of ``geometry`` (a Polygon or MultiPolygon) with points at most ``spacing``
    apart along it, its vertices included, each ring's closing point once."""
    spacing = _check_spacing(spacing)
    rings = shapely.get_rings(shapely.get_parts(geometry))
    parts = [shapely.get_coordinates(shapely.segmentize(ring, spacing))[:-1] for ring in rings]
    return np.concatenate(parts) if parts else np.zeros((0, 2))


def at_heights(xy: np.ndarray, heights) -> np.ndarray:
    """(len(heights) * n, 3): the ground points ``xy`` (n, 2) at each height in turn."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    return np.concatenate([np.column_stack([xy, np.full(len(xy), float(h))]) for h in heights]) \
        if len(heights) else np.zeros((0, 3))


# ----------------------------------------------------------------------------------------------- presets
# Boxes: (back, ahead, offside, nearside) edges; see FieldBox. Figures and sources: docs/regulations.md.

_FULL_WIDTH = (("offside", 0.0), ("nearside", 0.0))


def _box(back, ahead, offside, nearside) -> FieldBox:
    return FieldBox(back, ahead, offside, nearside)


_R46_IV = (_box(("eye", -25.0), ("eye", -1.5), ("nearside", 0.0), ("nearside", 4.5)),
           _box(("eye", -25.0), ("eye", -10.0), ("nearside", 0.0), ("nearside", 15.0)))
_R46_V = (_box(("eye", -1.75), ("eye", 1.0), ("nearside", 0.0), ("nearside", 2.0)),)
_R46_VI = (_box(("front", 0.0), ("front", 2.0), ("offside", 0.0), ("nearside", 2.0)),)

PRESETS: dict[str, RegionPreset] = {p.key: p for p in (
    RegionPreset("r158", "rear close-proximity field (reversing)",
                 "UN R158 (devices for reversing motion), rear-view camera field 0.3-3.5 m behind the vehicle",
                 (0.0, 0.4, 0.8, 1.2), (_box(("rear", -3.5), ("rear", -0.3), *_FULL_WIDTH),)),
    RegionPreset("r151", "nearside blind-spot field (BSIS)",
                 "UN R151 (blind spot information system), nearside area from the front corner rearwards",
                 (0.0, 0.8, 1.2, 1.6), (_box(("front", -30.0), ("front", 0.0), ("nearside", 0.0), ("nearside", 4.5)),)),
    RegionPreset("r159", "front close-proximity field (MOIS)",
                 "UN R159 (moving off information system), area directly in front of the vehicle",
                 (0.0, 0.8, 1.2, 1.6), (_box(("front", 0.0), ("front", 3.7), ("offside", 0.5), ("nearside", 0.5)),)),
    RegionPreset("r46-iv", "wide-angle field, nearside (class IV)",
                 "UN R46 class IV field of vision (wide-angle exterior mirror / camera-monitor), passenger side",
                 (0.0, 0.8, 1.2), _R46_IV),
    RegionPreset("r46-v", "close-proximity side field, nearside (class V)",
                 "UN R46 class V field of vision (close-proximity exterior mirror / camera-monitor), passenger side",
                 (0.0, 0.8, 1.2), _R46_V),
    RegionPreset("r46-vi", "front field (class VI)",
                 "UN R46 class VI field of vision (front mirror / camera-monitor)",
                 (0.0, 0.8, 1.2), _R46_VI),
    RegionPreset("dvs", "HGV cab zone and safe-system fields (London DVS)",
                 "TfL Direct Vision Standard: the assessment zone around the cab (2 m front, 4.5 m nearside) and "
                 "the Progressive Safe System's fields (R46 classes V and VI, nearside sensors 9 m x 2.2 m)",
                 (0.0, 0.8, 1.2, 1.6),
                 (_box(("eye", -1.75), ("front", 2.0), ("offside", 0.6), ("nearside", 4.5)),
                  _box(("front", -9.0), ("front", 0.0), ("nearside", 0.0), ("nearside", 2.2)),
                  *_R46_V, *_R46_VI)),
)}

#: The presets each UN category asks for when none are named (``default``).
CATEGORY_DEFAULTS = {"M1": ("r158",), "N1": ("r158",), "M2": ("r159", "r158"), "M3": ("r159", "r158"),
                     "N2": ("r151", "r159", "r158"), "N3": ("r151", "r159", "r158")}


def default_presets(vehicle: Vehicle, traffic: str = "right") -> tuple[RegionPreset, ...]:
    """The presets ``vehicle``'s category asks for (CATEGORY_DEFAULTS): trucks (N2, N3) r151, r159, r158; buses
    (M2, M3) r159, r158; cars and vans (M1, N1) r158."""
    return tuple(PRESETS[key].with_traffic(traffic) for key in CATEGORY_DEFAULTS[vehicle.category])


def parse_require(text: str, vehicle: Vehicle, traffic: str = "right") -> tuple[RegionPreset, ...]:
    """The presets named by ``text``: comma-separated keys of PRESETS, ``default`` (``vehicle``'s category
    defaults) or ``none`` (no preset); a key may end in ``:lht`` (left-hand traffic: nearside +y) or ``:rht``,
    else it is in ``traffic``. Case and spaces are ignored; a preset named twice counts once."""
    known = ", ".join([*PRESETS, "default", "none"])
    names = [part.strip().lower() for part in str(text).split(",") if part.strip()]
    if not names:
        raise RigoptError(f"--require needs preset names (comma-separated): {known}")
    out: list[RegionPreset] = []
    for name in names:
        key, _, suffix = name.partition(":")
        sides = {v: k for k, v in TRAFFIC_SUFFIX.items()}
        if suffix and suffix not in sides:
            raise RigoptError(f"--require {name!r}: unknown traffic suffix {suffix!r}; use :lht (left-hand "
                              "traffic, nearside left) or :rht (right-hand traffic, the default)")
        side = sides.get(suffix, traffic)
        if key == "none" and not suffix:
            if len(names) == 1:
                return ()
            raise RigoptError(f"--require {text!r}: 'none' stands alone (no field is checked); drop it or the other "
                              "names")
        if key == "default":
            chosen = default_presets(vehicle, side)
        elif key in PRESETS:
            chosen = (PRESETS[key].with_traffic(side),)
        else:
            raise RigoptError(f"--require: unknown preset {name!r}; use comma-separated names from: {known} "
                              "(a name may end in :lht for left-hand traffic); see docs/regulations.md")
        out += [p for p in chosen if p.key not in {q.key for q in out}]
    return tuple(out)


# ----------------------------------------------------------------------------------------------- coverage


@dataclass(frozen=True, eq=False)
class RegionCoverage:
    """How much of one preset's region a rig sees.

    ``covered_frac``: the fraction of the required points (``n_points``: grid and boundary, every height, at
    ``spacing`` m) seen by at least one camera; ``height_covered_frac`` (h,) the same per height of
    ``heights``; ``unseen`` (k, 3) float m the required points no camera sees; ``area_m2`` the region's ground
    area; ``unseen_area_m2`` that area times the fraction of its grid positions where some required height is
    unseen; ``polygon`` the region (vehicle frame, m).
    """

    key: str
    title: str
    source: str
    heights: tuple[float, ...]
    covered_frac: float
    height_covered_frac: tuple[float, ...]
    unseen: np.ndarray
    n_points: int
    area_m2: float
    unseen_area_m2: float
    spacing: float
    polygon: shapely.Polygon

    @property
    def covered(self) -> bool:
        """True when every required point is seen."""
        return len(self.unseen) == 0


def required_mask(vehicle: Vehicle, points, lifted=()) -> np.ndarray:
    """(n,) bool: which ``points`` (n, 3) m a field asks to be seen: not inside the body's footprint and not
    inside a keep-out box in force (a coupled trailer fills the space behind a tractor; ``lifted`` names the
    optional keep-outs lifted, as in MountPractice)."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    needed = Footprint.of_mesh(vehicle.mesh).distance_to(points[:, :2]) > 0
    for low, high, _ in keep_out_boxes(vehicle, lifted):
        needed &= ~np.all((points >= low) & (points <= high), axis=1)
    return needed


def region_coverage(rig: Rig, vehicle: Vehicle, presets, spacing: float = 0.1, backend: str = "auto",
                    max_range: float = DEFAULT_MAX_RANGE, lifted=()) -> tuple[RegionCoverage, ...]:
    """Coverage of each of ``presets`` by ``rig`` (positions in ``vehicle``'s frame) on ``vehicle``: every
    required point (:func:`required_mask`) of the region's grid and boundary at ``spacing`` m, at every height,
    tested for occlusion-aware visibility (:func:`rigopt.coverage.visibility.visible_by`)."""
    model = CameraModel.of_cameras(rig.cameras)
    out = []
    for preset in presets:
        polygon = preset.polygon(vehicle)
        grid, boundary = grid_inside(polygon, spacing), boundary_samples(polygon, spacing)
        per_height = len(grid) + len(boundary)
        points = at_heights(np.concatenate([grid, boundary]), preset.heights)
        needed = required_mask(vehicle, points, lifted)
        seen = np.ones(len(points), dtype=bool)
        if needed.any():
            seen[needed] = visible_by(vehicle.mesh, model, rig.positions, rig.rotations, points[needed], max_range,
                                      backend).any(axis=0)
        by_height = [(seen[k * per_height:(k + 1) * per_height], needed[k * per_height:(k + 1) * per_height])
                     for k in range(len(preset.heights))]
        fractions = tuple(float(s[n].mean()) if n.any() else 1.0 for s, n in by_height)
        grid_unseen = np.zeros(len(grid), dtype=bool)
        for s, n in by_height:
            grid_unseen |= (~s & n)[:len(grid)]
        unseen_share = float(grid_unseen.mean()) if len(grid) else float(np.any(needed & ~seen))
        out.append(RegionCoverage(
            preset.key, preset.title, preset.source, tuple(preset.heights),
            float(seen[needed].mean()) if needed.any() else 1.0, fractions, points[needed & ~seen],
            int(needed.sum()), float(polygon.area), float(polygon.area * unseen_share), float(spacing), polygon))
    return tuple(out)
