"""Requirement presets modelled on regulations' close-proximity fields, and a rig's coverage of them.

Each preset is a ground region around the vehicle (rectangles and polygons placed against the body's outline,
joined) with the heights at which a test object there must be seen: UN R158 behind the vehicle, R151 along the
nearside, R159 in front, R46 classes II, IV, V and VI, and TfL's Direct Vision Standard. Their figures, sources
and simplifications are in docs/regulations.md.

Frames: ISO 8855 vehicle frame (x forward, y left, z up; metres; the vehicle's origin on the ground). A preset's
lines come from its reference outline (:class:`BodyReference`): for most presets the footprint of the whole body
(the convex hull of the mesh on the ground, mirrors included); for R151 the body below 2.0 m without its mirrors,
and a coupled trailer. ``front`` and ``rear`` are the outline's largest and smallest x, the ``nearside`` and
``offside`` its extreme y on the kerb side and on the other side. In right-hand traffic (the default) the
nearside is the right, -y; in left-hand traffic it is the left, +y. The driver's ocular points (the R46 fields)
are taken at ``driver_eye_x``.

A field never asks for ground the body stands on or overhangs: the region is the field less the reference
outline grown by ``clearance`` (0.3 m, R158's own near edge; a test object has a body of its own, and the ground
right under a bumper is hidden from every camera above it).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import shapely

from rigopt.camera import CameraModel
from rigopt.coverage.visibility import DEFAULT_MAX_RANGE, fine_enough, occluders, visible_by
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
#: R151's reference lines leave out every part of the vehicle higher than this (m) above the ground.
R151_MAX_HEIGHT = 2.0
#: The zones that hold devices for indirect vision (mirror heads, camera arms): R151's lines leave out the mesh
#: inside them, their boxes grown by MIRROR_ZONE_MARGIN m on every side (a mirror's arm reaches past the zone a
#: camera may be mounted in: the hgv's lower arms end 0.14 m ahead of its mirror zones).
MIRROR_ZONES = ("mirror",)
MIRROR_ZONE_MARGIN = 0.2
#: Where rigopt ends R46 class II's field, which runs "to the horizon" (m behind the driver's ocular points).
R46_HORIZON_CUT = 50.0
#: Length (m) of the criticality weights' fall-off with distance from the body and from the nearside front corner.
CRITICALITY_LENGTH = 1.0


@dataclass(frozen=True)
class FieldObject:
    """What a field asks to see at each of its points: ``name`` (a child, a cyclist, R46's critical object), a
    cylinder ``height`` m tall and ``width`` m across, whose image must be at least ``min_px`` pixels tall for a
    point to count as seen; ``source`` says where the figures come from (docs/regulations.md).

    A field point counts as *resolved* by a camera when the camera sees it and the object standing on the ground
    below it is at least ``min_px`` pixels tall in the camera's image
    (:func:`rigopt.coverage.visibility.object_pixel_heights`)."""

    name: str
    height: float
    width: float
    min_px: float
    source: str = ""

    def __post_init__(self):
        if not (self.height > 0 and self.width > 0 and self.min_px >= 0 and np.isfinite(self.min_px)):
            raise RigoptError(f"test object {self.name!r}: height and width must be > 0 m and min_px a number of "
                              f"pixels >= 0, got {self.height!r} m, {self.width!r} m, {self.min_px!r} px")

    def with_min_px(self, min_px: float) -> "FieldObject":
        """This object asked to be ``min_px`` pixels tall."""
        return replace(self, min_px=float(min_px))

    def describe(self) -> str:
        """E.g. 'a cyclist 1.6 m tall at >= 25 px'."""
        return f"{self.name} {self.height:g} m tall at >= {self.min_px:g} px"

    def as_dict(self) -> dict:
        return {"name": self.name, "height_m": self.height, "width_m": self.width, "min_px": self.min_px,
                "source": self.source}


def _check_edge(name: str, edge, lines: tuple[str, ...]) -> None:
    line, offset = edge
    if line not in lines or not np.isfinite(offset):
        raise RigoptError(f"a field's {name} edge is (line, offset m) with line one of {', '.join(lines)} and a "
                          f"finite offset, got {edge!r}")


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
            _check_edge(name, getattr(self, name), lines)

    def shape(self, lines: BodyLines) -> shapely.Polygon:
        """The rectangle in the vehicle frame (m), placed against ``lines``."""
        x0, x1 = sorted((lines.x(self.back), lines.x(self.ahead)))
        y0, y1 = sorted((lines.y(self.offside), lines.y(self.nearside)))
        return shapely.box(x0, y0, x1, y1)


@dataclass(frozen=True)
class FieldPolygon:
    """One polygon of a field: ``corners`` in order, each (x edge, side edge) as in :class:`FieldBox` (an x line
    and offset forward, a side line and offset outward). E.g. R46 class IV's outer edge running straight from
    4.5 m out at 1.5 m behind the eyes to 15 m out at 10 m behind them."""

    corners: tuple[tuple[tuple[str, float], tuple[str, float]], ...]

    def __post_init__(self):
        if len(self.corners) < 3:
            raise RigoptError(f"a field polygon needs at least 3 corners, got {len(self.corners)}")
        for x_edge, side_edge in self.corners:
            _check_edge("corner's x", x_edge, X_LINES)
            _check_edge("corner's side", side_edge, SIDE_LINES)

    def shape(self, lines: BodyLines) -> shapely.Polygon:
        """The polygon in the vehicle frame (m), placed against ``lines``; an invalid (self-crossing) one is
        refused."""
        polygon = shapely.Polygon([(lines.x(x_edge), lines.y(side_edge)) for x_edge, side_edge in self.corners])
        if not polygon.is_valid:
            raise RigoptError(f"a field polygon's corners cross each other: {self.corners!r}")
        return polygon


@dataclass(frozen=True)
class BodyReference:
    """What of the vehicle a preset's lines and near-body clearance are measured from.

    ``max_height``: parts of the mesh higher than this (m) are left out (None: none); ``left_out_zones``: the
    mesh inside the boxes of these zones (mirrored copies included), grown by MIRROR_ZONE_MARGIN, is left out (a
    vehicle without such a zone keeps everything); ``trailer``: a coupled trailer (every keep-out in force that
    occludes, ``lifted`` ones left out) joins the outline, so that its sides and its rear are the vehicle's.
    """

    max_height: float | None = None
    left_out_zones: tuple[str, ...] = ()
    trailer: bool = False

    @property
    def whole_body(self) -> bool:
        return self.max_height is None and not self.left_out_zones and not self.trailer

    def outline(self, vehicle: Vehicle, lifted=()) -> shapely.Polygon:
        """The reference on the ground, vehicle frame (m): the convex hull of the kept mesh in plan, joined
        with the plan rectangle of each coupled trailer."""
        if self.whole_body:
            return vehicle.footprint.polygon
        points = _mesh_points_below(vehicle.mesh, self.max_height)
        keep = np.ones(len(points), dtype=bool)
        for zone in vehicle.zones:
            if zone.name in self.left_out_zones:
                low, high = zone.min - MIRROR_ZONE_MARGIN, zone.max + MIRROR_ZONE_MARGIN
                keep &= ~np.all((points >= low) & (points <= high), axis=1)
        if not keep.any():
            raise RigoptError(f"{vehicle.name}: no part of the body is left for the reference lines (below "
                              f"{self.max_height} m, outside the zones {', '.join(self.left_out_zones)})")
        outline = shapely.MultiPoint(points[keep, :2]).convex_hull
        if self.trailer:
            boxes = [shapely.box(low[0], low[1], high[0], high[1])
                     for low, high, _ in keep_out_boxes(vehicle, lifted, occluding_only=True)]
            outline = shapely.union_all([outline, *boxes])
        return outline


#: The whole body, mirrors included (every preset but R151).
WHOLE_BODY = BodyReference()
#: R151's reference: the body up to 2.0 m without its devices for indirect vision, and a coupled trailer.
R151_REFERENCE = BodyReference(R151_MAX_HEIGHT, MIRROR_ZONES, trailer=True)


def _mesh_points_below(mesh, height: float | None) -> np.ndarray:
    """(n, 3) float m: the vertices of ``mesh`` at most ``height`` high and the points where its edges cross that
    height (the corners of the mesh cut there); every vertex when ``height`` is None."""
    vertices = np.asarray(mesh.vertices, dtype=float)
    if height is None:
        return vertices
    edges = np.asarray(mesh.edges_unique)
    a, b = vertices[edges[:, 0]], vertices[edges[:, 1]]
    crossing = (a[:, 2] - height) * (b[:, 2] - height) < 0
    t = (height - a[crossing, 2]) / (b[crossing, 2] - a[crossing, 2])
    cut = a[crossing] + t[:, None] * (b[crossing] - a[crossing])
    return np.concatenate([vertices[vertices[:, 2] <= height], cut])


@dataclass(frozen=True)
class BodyLines:
    """The lines fields are placed against, from the reference outline: ``front``, ``rear``, ``eye`` x (m);
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

    @property
    def nearside_front_corner(self) -> np.ndarray:
        """(2,) float m: where the front line meets the nearside line."""
        return np.array([self.front, self.nearside])


def driver_eye_x(vehicle: Vehicle) -> float:
    """x (m) of the driver's ocular points: EYE_SETBACK behind the body's front, by category."""
    kind = "heavy" if vehicle.category in HEAVY_CATEGORIES else "light"
    return float(vehicle.mesh.bounds[1][0]) - EYE_SETBACK[kind]


def body_lines(vehicle: Vehicle, traffic: str = "right", reference: BodyReference = WHOLE_BODY,
               lifted=()) -> BodyLines:
    """The extreme lines of ``vehicle``'s ``reference`` outline for ``traffic`` ('right': nearside -y; 'left':
    +y); ``lifted`` names keep-outs lifted (a trailer not coupled)."""
    if traffic not in TRAFFIC:
        raise RigoptError(f"unknown traffic side {traffic!r}; use right (nearside on the right, -y) or left")
    x_min, y_min, x_max, y_max = reference.outline(vehicle, lifted).bounds
    near, off, outward = (y_min, y_max, -1.0) if traffic == "right" else (y_max, y_min, 1.0)
    return BodyLines(float(x_max), float(x_min), driver_eye_x(vehicle), float(near), float(off), outward)


@dataclass(frozen=True)
class RegionPreset:
    """A requirement: the ground ``boxes`` (FieldBox or FieldPolygon) around the vehicle, joined, less the
    ``reference`` outline grown by ``clearance`` m, where a test object must be seen at every one of ``heights``
    (m above the ground), as large in the image as its ``test_object`` asks (None: in view is enough).

    ``key`` names it on the command line (``r151``, ``r151:lht`` in left-hand traffic), ``title`` says what it
    is, ``source`` cites the regulation; ``traffic`` ('right' or 'left') puts the nearside at -y or +y;
    ``reference`` (:class:`BodyReference`) is what the lines are measured from.
    """

    key: str
    title: str
    source: str
    heights: tuple[float, ...]
    boxes: tuple[FieldBox | FieldPolygon, ...]
    traffic: str = "right"
    clearance: float = NEAR_BODY_CLEARANCE
    reference: BodyReference = WHOLE_BODY
    test_object: FieldObject | None = None

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

    @property
    def pixel_demand(self) -> np.ndarray:
        """(2,) float: (test object height m, pixels its image must span) at each field point; (1, 0) without a
        test object (in view is enough)."""
        thing = self.test_object
        return np.array([thing.height, thing.min_px] if thing else [1.0, 0.0])

    def pixel_demands(self, n: int) -> np.ndarray:
        """(n, 2) float: :attr:`pixel_demand` for each of ``n`` field points."""
        return np.tile(self.pixel_demand, (n, 1))

    def with_min_px(self, min_px: float) -> "RegionPreset":
        """This preset with its test object asked to be ``min_px`` pixels tall (a preset without one unchanged)."""
        return replace(self, test_object=self.test_object.with_min_px(min_px)) if self.test_object else self

    def lines(self, vehicle: Vehicle, lifted=()) -> BodyLines:
        """The lines this preset's fields are placed against on ``vehicle`` (``lifted``: keep-outs lifted)."""
        return body_lines(vehicle, self.traffic, self.reference, lifted)

    def polygon(self, vehicle: Vehicle, lifted=()) -> shapely.Polygon | shapely.MultiPolygon:
        """The ground region in the vehicle frame (m): the boxes' union less the grown reference outline (a
        Polygon for every one-sided preset on a convex footprint; a MultiPolygon for fields on both sides, r46-ii,
        or where a body splits a field). ``lifted`` names keep-outs lifted (a trailer not coupled)."""
        lines = self.lines(vehicle, lifted)
        field = shapely.union_all([box.shape(lines) for box in self.boxes])
        return field.difference(self.reference.outline(vehicle, lifted).buffer(self.clearance))

    def ground_samples(self, vehicle: Vehicle, spacing: float = 0.5, lifted=()) -> tuple[np.ndarray, np.ndarray]:
        """((g, 2), (b, 2)) float m: the grid points (on multiples of ``spacing``) strictly inside the polygon,
        and its boundary sampled at most ``spacing`` apart (every corner included)."""
        polygon = self.polygon(vehicle, lifted)
        return grid_inside(polygon, spacing), boundary_samples(polygon, spacing)

    def points(self, vehicle: Vehicle, spacing: float = 0.5, lifted=()) -> np.ndarray:
        """(n, 3) float m, vehicle frame: the grid over the polygon and its boundary samples
        (:meth:`ground_samples`) at every height; heights vary slowest, the grid before the boundary."""
        grid, boundary = self.ground_samples(vehicle, spacing, lifted)
        return at_heights(np.concatenate([grid, boundary]), self.heights)

    def criticality(self, vehicle: Vehicle, xy, lifted=()) -> np.ndarray:
        """(n,) float in (0, 2]: the criticality weight of each ground position ``xy`` (n, 2) m (see
        :func:`criticality_weights`), against this preset's reference outline and nearside front corner."""
        return criticality_weights(xy, self.reference.outline(vehicle, lifted),
                                   self.lines(vehicle, lifted).nearside_front_corner)


def criticality_weights(xy, outline, corner) -> np.ndarray:
    """(n,) float in (0, 2]: how critical a test object at each ground position ``xy`` (n, 2) m is.

    w = 1 / (1 + d_body / L) + 1 / (1 + d_corner / L), with d_body the distance (m) from ``outline`` (a shapely
    polygon, the body on the ground), d_corner the distance from ``corner`` (2,) m (the nearside front corner, where
    a turning truck's front meets a cyclist or pedestrian beside it) and L = CRITICALITY_LENGTH (1 m). Each term
    is 1 at the body (at the corner) and halves L away: at the corner w = 2, 1 m ahead of it 1, 3 m from both 0.5,
    far from both it tends to 0. rigopt's choice, not a regulation's.
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    d_body = shapely.distance(outline, shapely.points(xy)) if len(xy) else np.zeros(0)
    d_corner = np.linalg.norm(xy - np.asarray(corner, dtype=float), axis=1)
    return 1.0 / (1.0 + np.asarray(d_body) / CRITICALITY_LENGTH) + 1.0 / (1.0 + d_corner / CRITICALITY_LENGTH)


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


def _r46_wedge(side: str, near_back: float, near_width: float, wide_back: float, wide_width: float,
               far_back: float) -> FieldPolygon:
    """An R46 wide field on ``side`` ('nearside' or 'offside'): ``near_width`` m wide from ``near_back`` m behind
    the ocular points, its outer edge running straight to ``wide_width`` m at ``wide_back`` m behind them, that wide
    to ``far_back`` m behind them; every width measured outward from ``side``'s line."""
    return FieldPolygon(((("eye", -near_back), (side, 0.0)), (("eye", -near_back), (side, near_width)),
                         (("eye", -wide_back), (side, wide_width)), (("eye", -far_back), (side, wide_width)),
                         (("eye", -far_back), (side, 0.0))))


_R46_II = tuple(_r46_wedge(side, 4.0, 1.0, 30.0, 5.0, R46_HORIZON_CUT) for side in ("offside", "nearside"))
_R46_IV = (_r46_wedge("nearside", 1.5, 4.5, 10.0, 15.0, 25.0),)
_R46_V = (_box(("eye", -1.75), ("eye", 1.0), ("nearside", 0.0), ("nearside", 2.0)),)
_R46_VI = (_box(("front", 0.0), ("front", 2.0), ("offside", 0.0), ("nearside", 2.0)),)
#: R151's band: 4.5 m out from the nearside, from the front back 30 m and at least to the rear of the vehicle or
#: of its coupled trailer (the collision line's end).
_R151 = (_box(("front", -30.0), ("front", 0.0), ("nearside", 0.0), ("nearside", 4.5)),
         _box(("rear", 0.0), ("front", 0.0), ("nearside", 0.0), ("nearside", 4.5)))

#: The pixels a field's test object must be tall in a camera's image for its point to count as seen: KITTI's
#: smallest evaluated box height (its Moderate and Hard levels), rigopt's choice for every field; the regulations
#: judge what a driver sees on a monitor (arc-minutes at the eye) or what a system detects, neither a camera's
#: pixels (docs/regulations.md).
MIN_OBJECT_PX = 25.0
R158_OBJECT = FieldObject("R158's test object", 0.8, 0.3, MIN_OBJECT_PX,
                         "UN R158: a cylinder at least 0.8 m tall and 0.3 m wide")
R46_OBJECT = FieldObject("R46's critical object", 0.8, 0.8, MIN_OBJECT_PX,
                        "UN R46 / Directive 2003/97/EC: a circular object 0.8 m across (taken as 0.8 m tall)")
CYCLIST = FieldObject("a cyclist", 1.6, 0.6, MIN_OBJECT_PX, "rigopt's: the field's top height (R151's target "
                     "not found)")
CHILD = FieldObject("a child", 1.15, 0.3, MIN_OBJECT_PX, "rigopt's: a child's height (R159's targets not found)")

PRESETS: dict[str, RegionPreset] = {p.key: p for p in (
    RegionPreset("r158", "rear close-proximity field (reversing)",
                 "UN R158 (devices for reversing motion), rear-view camera field 0.3-3.5 m behind the vehicle; its "
                 "test object 0.8 m tall, 0.3 m across",
                 (0.0, 0.4, 0.8), (_box(("rear", -3.5), ("rear", -0.3), *_FULL_WIDTH),), test_object=R158_OBJECT),
    RegionPreset("r151", "nearside blind-spot field (BSIS)",
                 "UN R151 (blind spot information system), nearside area from the front corner rearwards, lines "
                 "without mirrors and parts above 2.0 m, to the rear of a coupled trailer",
                 (0.0, 0.8, 1.2, 1.6), _R151, reference=R151_REFERENCE, test_object=CYCLIST),
    RegionPreset("r159", "front close-proximity field (MOIS)",
                 "UN R159 (moving off information system), area directly in front of the vehicle",
                 (0.0, 0.8, 1.2, 1.6), (_box(("front", 0.0), ("front", 3.7), ("offside", 0.5), ("nearside", 0.5)),),
                 test_object=CHILD),
    RegionPreset("r46-ii", "main rear-view fields, both sides (class II)",
                 "UN R46 class II field of vision (main exterior mirror / camera-monitor), driver and passenger "
                 f"side, cut {R46_HORIZON_CUT:g} m behind the ocular points",
                 (0.0, 0.8, 1.2), _R46_II, test_object=R46_OBJECT),
    RegionPreset("r46-iv", "wide-angle field, nearside (class IV)",
                 "UN R46 class IV field of vision (wide-angle exterior mirror / camera-monitor), passenger side",
                 (0.0, 0.8, 1.2), _R46_IV, test_object=R46_OBJECT),
    RegionPreset("r46-v", "close-proximity side field, nearside (class V)",
                 "UN R46 class V field of vision (close-proximity exterior mirror / camera-monitor), passenger side",
                 (0.0, 0.8, 1.2), _R46_V, test_object=R46_OBJECT),
    RegionPreset("r46-vi", "front field (class VI)",
                 "UN R46 class VI field of vision (front mirror / camera-monitor)",
                 (0.0, 0.8, 1.2), _R46_VI, test_object=R46_OBJECT),
    RegionPreset("dvs", "HGV cab zone and safe-system fields seen by cameras (a proxy of London DVS's camera part, "
                 "not DVS compliance: DVS rates the driver's direct vision)",
                 "TfL Direct Vision Standard: the assessment zone around the cab (2 m front, 4.5 m nearside) and "
                 "the Progressive Safe System's fields (R46 classes V and VI, nearside sensors 9 m x 2.2 m)",
                 (0.0, 0.8, 1.2, 1.6),
                 (_box(("eye", -1.75), ("front", 2.0), ("offside", 0.6), ("nearside", 4.5)),
                  _box(("front", -9.0), ("front", 0.0), ("nearside", 0.0), ("nearside", 2.2)),
                  *_R46_V, *_R46_VI), test_object=CHILD),
)}

#: The presets each UN category asks for when none are named (``default``).
#: The fields each category asks for by default. The EU General Safety Regulation ((EU) 2019/2144, Annex II) requires
#: a blind-spot information system (UN R151) and a moving-off information system (UN R159) on M2, M3, N2 and N3,
#: and a reversing detection (UN R158) on every M and N vehicle.
CATEGORY_DEFAULTS = {"M1": ("r158",), "N1": ("r158",), "M2": ("r151", "r159", "r158"), "M3": ("r151", "r159", "r158"),
                     "N2": ("r151", "r159", "r158"), "N3": ("r151", "r159", "r158")}


#: Regulations that apply to a category and that rigopt does not model: category -> ((regulation, why), ...).
NOT_MODELLED = {category: (("UN R166", "the driver's awareness of vulnerable road users close to the front and sides "
                                       "(M1 and N1: the front's full width, both sides ahead of the mirrors); its "
                                       "field distances and test object were not found (docs/regulations.md)"),)
                for category in ("M1", "N1")}


def category_dict(vehicle: Vehicle) -> dict:
    """The vehicle's category in a report: ``category``, ``reason`` (stated in its spec, or the shape's suggestion
    and why), ``default_fields`` (the presets it asks for, CATEGORY_DEFAULTS) and ``not_modelled`` (the
    regulations that apply to it and are not modelled, NOT_MODELLED: [{regulation, why}])."""
    reason = ("stated in its vehicle.toml" if vehicle.spec.category
              else f"suggested by its shape: {vehicle.category_guess.reason}")
    return {"category": vehicle.category, "reason": reason, "default_fields": list(CATEGORY_DEFAULTS[vehicle.category]),
            "not_modelled": [{"regulation": name, "why": why} for name, why in NOT_MODELLED.get(vehicle.category, ())]}


def category_text(category: dict) -> str:
    """One line of a report: the category, why, the fields it asks for by default and what applies unmodelled."""
    text = (f"category {category['category']} ({category['reason']}): fields asked for by default "
            f"{', '.join(category['default_fields'])}")
    return text + "".join(f"; {m['regulation']} also applies and is not modelled: {m['why']}"
                          for m in category["not_modelled"])


def default_presets(vehicle: Vehicle, traffic: str = "right") -> tuple[RegionPreset, ...]:
    """The presets ``vehicle``'s category asks for (CATEGORY_DEFAULTS): trucks and buses (N2, N3, M2, M3) r151,
    r159, r158; cars and light vans (M1, N1) r158."""
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


@dataclass(frozen=True)
class CameraShare:
    """One camera's part in a field: ``seen_frac`` the share of the field's required points it sees, ``only_frac``
    the share it alone sees (no other camera of the rig does)."""

    camera: str
    seen_frac: float
    only_frac: float


@dataclass(frozen=True, eq=False)
class RegionCoverage:
    """How much of one preset's region a rig sees.

    ``covered_frac``: the fraction of the required points (``n_points``: grid and boundary, every height, at
    ``spacing`` m) seen by at least one camera, each at its ``test_object``'s pixels (resolved; every share below
    counts resolved points); ``in_view_frac`` the fraction in some camera's view with nothing in between, however
    small; ``height_covered_frac`` (h,) the same per height of
    ``heights``; ``weighted_covered_frac`` the same with each point weighted by its criticality
    (:func:`criticality_weights` of its ground position); ``unseen`` (k, 3) float m the required points no camera
    sees; ``area_m2`` the region's ground area; ``unseen_area_m2`` that area times the fraction of its grid
    positions where some required height is unseen; ``cameras`` (CameraShare, in the rig's order) each camera's
    share, ``overlap_frac`` the share seen by two cameras or more, so that the cameras' ``only_frac`` and
    ``overlap_frac`` add up to ``covered_frac`` (all 0 for a field with no required point, which counts as
    covered); ``polygon`` the region (vehicle frame, m); ``n_excluded`` the region's points not asked for, inside
    the body's footprint or a keep-out in force (on a tractor with its trailer coupled, most of R158's field).
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
    polygon: shapely.Polygon | shapely.MultiPolygon
    weighted_covered_frac: float = 1.0
    cameras: tuple[CameraShare, ...] = ()
    overlap_frac: float = 0.0
    n_excluded: int = 0
    in_view_frac: float = 1.0
    test_object: FieldObject | None = None

    @property
    def covered(self) -> bool:
        """True when every required point is seen."""
        return len(self.unseen) == 0


def required_mask(vehicle: Vehicle, points, lifted=()) -> np.ndarray:
    """(n,) bool: which ``points`` (n, 3) m a field asks to be seen: not inside the body's footprint and not
    inside a keep-out box in force (a coupled trailer fills the space behind a tractor; ``lifted`` names the
    optional keep-outs lifted, as in MountPractice)."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    needed = vehicle.footprint.distance_to(points[:, :2]) > 0
    for low, high, _ in keep_out_boxes(vehicle, lifted):
        needed &= ~np.all((points >= low) & (points <= high), axis=1)
    return needed


def _share(values: np.ndarray, weights: np.ndarray | None = None) -> float:
    """The (weighted) mean of the bool ``values``, 1.0 when there are none."""
    if not len(values):
        return 1.0
    return float(np.average(values, weights=weights))


def region_coverage(rig: Rig, vehicle: Vehicle, presets, spacing: float = 0.1, backend: str = "auto",
                    max_range: float = DEFAULT_MAX_RANGE, lifted=()) -> tuple[RegionCoverage, ...]:
    """Coverage of each of ``presets`` by ``rig`` (positions in ``vehicle``'s frame) on ``vehicle``: every
    required point (:func:`required_mask`) of the region's grid and boundary at ``spacing`` m, at every height,
    tested for occlusion-aware visibility (:func:`rigopt.coverage.visibility.visible_by`: the body and the keep-outs
    in force that block views, a coupled trailer) by each camera, and for the pixels its test object asks
    (:func:`rigopt.coverage.visibility.fine_enough`). ``lifted`` names keep-outs lifted (a trailer not coupled):
    they neither hide points, nor block views, nor place R151's lines."""
    model, boxes = CameraModel.of_cameras(rig.cameras), occluders(vehicle, lifted)
    out = []
    for preset in presets:
        polygon = preset.polygon(vehicle, lifted)
        grid, boundary = grid_inside(polygon, spacing), boundary_samples(polygon, spacing)
        ground = np.concatenate([grid, boundary])
        points = at_heights(ground, preset.heights)
        needed = required_mask(vehicle, points, lifted)
        by_camera = np.zeros((len(rig.cameras), len(points)), dtype=bool)
        in_view = np.zeros(len(points), dtype=bool)
        if needed.any():
            view = visible_by(vehicle.caster(backend), model, rig.positions, rig.rotations, points[needed],
                              max_range, boxes)
            in_view[needed] = view.any(axis=0)
            by_camera[:, needed] = fine_enough(view, model, rig.positions, rig.rotations, points[needed],
                                               preset.pixel_demands(int(needed.sum())))
        count = by_camera.sum(axis=0)
        seen = (count > 0) | ~needed
        per_height = len(ground)
        by_height = [(seen[k * per_height:(k + 1) * per_height], needed[k * per_height:(k + 1) * per_height])
                     for k in range(len(preset.heights))]
        grid_unseen = np.zeros(len(grid), dtype=bool)
        for s, n in by_height:
            grid_unseen |= (~s & n)[:len(grid)]
        unseen_share = float(grid_unseen.mean()) if len(grid) else float(np.any(needed & ~seen))
        weights = np.tile(preset.criticality(vehicle, ground, lifted), len(preset.heights))[needed]
        alone = by_camera[:, needed] & (count[needed] == 1)
        shares = tuple(CameraShare(camera.id, float(by_camera[k, needed].mean()) if needed.any() else 0.0,
                                   float(alone[k].mean()) if needed.any() else 0.0)
                       for k, camera in enumerate(rig.cameras))
        out.append(RegionCoverage(
            preset.key, preset.title, preset.source, tuple(preset.heights), _share(seen[needed]),
            tuple(_share(s[n]) for s, n in by_height), points[needed & ~seen], int(needed.sum()),
            float(polygon.area), float(polygon.area * unseen_share), float(spacing), polygon,
            _share(seen[needed], weights), shares, float(np.mean(count[needed] >= 2)) if needed.any() else 0.0,
            int((~needed).sum()), _share(in_view[needed]), preset.test_object))
    return tuple(out)
