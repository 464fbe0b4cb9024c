"""Vehicle specs: the TOML description of a body as parametric solids plus its named mounting zones.

Everything is in the ISO 8855 vehicle frame (x forward, y left, z up; metres, origin at the benchmark's
vehicle origin on the ground). A spec file::

    name = "etron"
    title = "Audi e-tron"                  # optional: the vehicle in words, for messages
    blueprint = "vehicle.audi.etron"       # the CARLA blueprint the benchmark's rigs name
    aliases = ["suv"]
    box = [4.8557, 2.0328, 1.6494]         # CARLA bounding box length, width, height (m), for checks
    axles = [1.45, -1.48]                  # optional: x of each axle (m); default: the wheels solids' axles
    category = "M1"                        # optional: UN vehicle category (M1, M2, M3, N1, N2, N3); default:
                                           # suggested by the shape (rigopt.vehicle.category)

    [[solids]]                              # intersection of a side profile extruded across y and a
    name = "body"                           # plan outline extruded along z
    type = "prism"
    side = [[x, z], ...]                    # closed polygon in the x-z plane
    plan = [[x, y], ...]                    # half outline, y >= 0, from the front centre to the rear
    taper = [1.0, 0.8]                      # optional: plan scaled by (sx, sy) at the top (tumblehome)

    [[solids]]
    type = "wheels"                         # one wheel per axle and side
    axles = [1.45, -1.48]                   # x of each axle
    radius = 0.37
    width = 0.26
    track = 1.66                            # distance between the wheels' centre planes

    [[solids]]
    type = "box"                            # a box; mirrored = true adds its copy at -y
    center = [x, y, z]
    size = [dx, dy, dz]
    mirrored = true

    [[solids]]
    type = "mesh"                           # a mesh file in the ISO frame (user vehicles)
    file = "body.ply"

    [[zones]]                               # a mounting zone: surface inside the box whose outward
    name = "bumper_front"                   # normal lies within cone_deg of normal
    min = [x, y, z]
    max = [x, y, z]
    normal = [1, 0, 0]
    cone_deg = 80
    mirrored = false                        # true adds the zone reflected to -y under the same name
    cost = 1.0                              # optional: relative mounting cost (1 an ordinary body panel)
    raised_max = 0.0                        # optional: a raised zone (roof rack, pod, mast): a camera may
                                            # sit up to this far (m) above the surface, on a post along
                                            # `normal` (see rigopt.mounting.rules)

    [[wheels]]                              # optional, user vehicles: wheels the mesh already holds,
    axles = [1.45]                          # described for the checks (same keys as a wheels solid);
    radius = 0.37                           # one table per axle
    width = 0.24
    track = 1.66

Features mounting practice refuses lenses on (:mod:`rigopt.mounting.features`), all optional::

    legal_width = 2.55                      # m, the width no camera may stick out beyond (default 2.55,
    refrigerated = false                    # or 2.60 with refrigerated = true: a refrigerated body)

    [[steps]]                               # a walkable surface: a step, a tailboard, a catwalk; the box
    name = "tailboard"                      # holds the step itself (tread and riser)
    min = [x, y, z]
    max = [x, y, z]
    mirrored = false

    [[door_frames]]                         # a door or locker door: the box is its opening (thinnest across
    name = "locker door"                    # the door); no lens within `frame` m of its edges (the frame,
    min = [x, y, z]                         # the seals, the shut line)
    max = [x, y, z]
    frame = 0.10
    hinge = "front"                         # optional: the hinged edge (front, rear, left, right, top,
    mirrored = true                         # bottom); no lens within the rules' hinge band of it

    [[fixtures]]                            # a part that carries no camera: kind = rail, ladder,
    name = "aerial ladder"                  # light_bar, rack, mud_flap, lamp or number_plate
    kind = "ladder"
    min = [x, y, z]
    max = [x, y, z]

    [wiped_area]                            # the windscreen: a lens in `zone` must look through the area
    zone = "windshield_front"               # the wipers sweep, `outline` [[y, z], ...] m seen from the
    outline = [[y, z], ...]                 # front (projected along x)

    [tilt_cab]                              # a cab that tilts forward about the axis along y through
    pivot = [x, z]                          # `pivot` by up to `angle_deg`; the box is the cab that tilts
    angle_deg = 65
    min = [x, y, z]
    max = [x, y, z]

A ``[[keep_out]]`` with ``kingpin = [x, y, z]`` is a semi-trailer: its front corners swing about the kingpin
when the combination turns (the swing envelope, :func:`rigopt.mounting.features.trailer_swing`).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rigopt.errors import DataError, not_utf8

SOLID_TYPES = ("prism", "wheels", "box", "mesh")
#: Kinds of ``[[fixtures]]``: parts that carry no camera.
FIXTURE_KINDS = ("rail", "ladder", "light_bar", "rack", "mud_flap", "lamp", "number_plate")
#: The edges a door's hinge may run along, as (axis, side): front = +x, left = +y, top = +z.
HINGE_EDGES = {"front": (0, 1), "rear": (0, -1), "left": (1, 1), "right": (1, -1), "top": (2, 1), "bottom": (2, -1)}
#: The width (m) a vehicle may not exceed (EU: Directive 96/53/EC), and that of a refrigerated body.
LEGAL_WIDTH_M, REFRIGERATED_WIDTH_M = 2.55, 2.60
#: UN vehicle categories a spec may name: M (passengers; M1 cars, M2/M3 buses), N (goods; N1 vans up to 3.5 t,
#: N2 trucks up to 12 t, N3 heavier).
CATEGORIES = ("M1", "M2", "M3", "N1", "N2", "N3")


@dataclass(frozen=True)
class Prism:
    """Side profile (n, 2) float (x, z) extruded across y, intersected with a plan outline (m, 2) float
    (x, y >= 0 half, mirrored) extruded along z; ``taper`` (sx, sy) scales the plan at the top."""

    name: str
    side: np.ndarray
    plan: np.ndarray
    taper: tuple[float, float] = (1.0, 1.0)


@dataclass(frozen=True)
class Wheels:
    """Cylinders of ``radius`` and ``width`` (m) on each axle x in ``axles``, centre planes at +-track/2."""

    name: str
    axles: tuple[float, ...]
    radius: float
    width: float
    track: float


@dataclass(frozen=True)
class Box:
    """Axis-aligned box: ``center`` (3,) and ``size`` (3,) in metres; ``mirrored`` adds the -y copy."""

    name: str
    center: np.ndarray
    size: np.ndarray
    mirrored: bool = False


@dataclass(frozen=True)
class MeshSolid:
    """A triangle mesh file (any format trimesh reads), already in the ISO vehicle frame, metres;
    ``path`` is resolved against the spec file's folder."""

    name: str
    path: Path


@dataclass(frozen=True)
class ZoneSpec:
    """A mounting zone: surface points in the box [``min``, ``max``] (3,) m whose outward normal lies
    within ``cone_deg`` degrees of ``normal`` (3,) unit; ``mirrored`` adds the -y reflection."""

    name: str
    min: np.ndarray
    max: np.ndarray
    normal: np.ndarray
    cone_deg: float
    mirrored: bool = False
    raised_max: float = 0.0
    cost: float = 1.0


@dataclass(frozen=True)
class KeepOutSpec:
    """A box [``min``, ``max``] (3,) m no lens may be in, and why (``reason``); ``mirrored`` adds its -y
    reflection; ``optional`` keep-outs may be lifted by name (a trailer that is not always coupled);
    ``occludes``: a solid that blocks views too (a trailer), checked like the body in the near-view rule."""

    name: str
    min: np.ndarray
    max: np.ndarray
    reason: str
    mirrored: bool = False
    optional: bool = False
    occludes: bool = False
    kingpin: np.ndarray | None = None


@dataclass(frozen=True)
class FeatureBox:
    """A part of the body a lens may not sit on: ``kind`` "step" (a walkable surface) or a fixture kind
    (FIXTURE_KINDS), the box [``min``, ``max``] (3,) m that holds the part; ``mirrored`` adds its -y copy."""

    name: str
    kind: str
    min: np.ndarray
    max: np.ndarray
    mirrored: bool = False


@dataclass(frozen=True)
class DoorFrameSpec:
    """A door's opening, the box [``min``, ``max``] (3,) m (thinnest across the door); ``frame`` m the band
    around its edges where no lens goes; ``hinge`` the hinged edge (a HINGE_EDGES key) or None; ``mirrored``
    adds the -y copy (its hinge on the same edge)."""

    name: str
    min: np.ndarray
    max: np.ndarray
    frame: float = 0.10
    hinge: str | None = None
    mirrored: bool = False


@dataclass(frozen=True)
class WipedAreaSpec:
    """The area of the windscreen the wipers sweep: ``outline`` (k, 2) float (y, z) m seen from the front;
    lenses whose surface foot lies in ``zone`` must lie inside it."""

    zone: str
    outline: np.ndarray


@dataclass(frozen=True)
class TiltCabSpec:
    """A cab that tilts forward by up to ``angle_deg`` about the axis along y through ``pivot`` (x, z) m;
    the cab is the box [``min``, ``max``] (3,) m."""

    pivot: np.ndarray
    angle_deg: float
    min: np.ndarray
    max: np.ndarray


@dataclass(frozen=True)
class VehicleSpec:
    """A vehicle: ``name``, CARLA ``blueprint``, ``aliases``, ``box`` (length, width, height) m, solids,
    zones, the file it came from, ``axles`` (x m) and ``wheels``: wheel descriptions that are not solids
    (the ``[[wheels]]`` tables of a user vehicle, whose mesh holds the wheels already); ``category`` the UN
    vehicle category it names (None: not given); ``title`` the vehicle in words for messages (None: not given)."""

    name: str
    blueprint: str
    aliases: tuple[str, ...]
    box: tuple[float, float, float]
    solids: tuple[Prism | Wheels | Box | MeshSolid, ...]
    zones: tuple[ZoneSpec, ...]
    source: str = field(default="<spec>", compare=False)
    axles: tuple[float, ...] = ()
    wheels: tuple[Wheels, ...] = ()
    keep_outs: tuple[KeepOutSpec, ...] = ()
    min_lens_height: float | None = None
    category: str | None = None
    title: str | None = None
    steps: tuple[FeatureBox, ...] = ()
    fixtures: tuple[FeatureBox, ...] = ()
    door_frames: tuple[DoorFrameSpec, ...] = ()
    wiped_area: WipedAreaSpec | None = None
    tilt_cab: TiltCabSpec | None = None
    legal_width: float = LEGAL_WIDTH_M


def read_toml(path, what: str) -> dict:
    """Parse the TOML file ``path``; errors name the file and ``what`` it should be."""
    path = Path(path)
    try:
        return tomllib.loads(path.read_text())
    except OSError as error:
        raise DataError(f"{path}: cannot read the {what} ({error.strerror})") from None
    except UnicodeDecodeError as error:
        raise not_utf8(path, what, error) from None
    except tomllib.TOMLDecodeError as error:
        raise DataError(f"{path}: not valid TOML ({error})") from None


def read_spec(path) -> VehicleSpec:
    """Read and validate a vehicle spec TOML file."""
    return spec_from_dict(read_toml(path, "vehicle spec"), str(path))


def spec_from_dict(data: dict, source: str = "<spec>") -> VehicleSpec:
    """Validate the parsed TOML ``data`` of a vehicle spec; errors name ``source``."""
    reader = _Reader(source)
    name = reader.text(data, "name")
    solids = tuple(reader.solid(s, k) for k, s in enumerate(reader.table_list(data, "solids")))
    if not solids:
        raise DataError(f"{source}: a vehicle needs at least one [[solids]] entry")
    zones = tuple(reader.zone(z, k) for k, z in enumerate(reader.table_list(data, "zones")))
    box = tuple(reader.numbers(data, "box", 3, positive=True)) if "box" in data else (0.0, 0.0, 0.0)
    aliases = data.get("aliases", [])
    if not isinstance(aliases, list) or not all(isinstance(a, str) for a in aliases):
        raise DataError(f"{source}: 'aliases' must be a list of strings")
    blueprint = reader.text(data, "blueprint") if "blueprint" in data else name
    axles = data.get("axles", [])
    if not isinstance(axles, list) or not all(_is_number(a) for a in axles):
        raise DataError(f"{source}: 'axles' must be a list of numbers, the x (m) of each axle")
    wheels = tuple(reader.wheels(w, f"wheels {k}", f"wheels{k}") for k, w in enumerate(reader.table_list(data, "wheels")))
    keep_outs = tuple(reader.keep_out(t, k) for k, t in enumerate(reader.table_list(data, "keep_out")))
    min_height = reader.number(data, "min_lens_height", "top level", positive=False) if "min_lens_height" in data else None
    if min_height is not None and min_height < 0:
        raise DataError(f"{source}: 'min_lens_height' is a height above the ground in metres, >= 0, got {min_height}")
    category = reader.category(data) if "category" in data else None
    title = reader.text(data, "title") if "title" in data else None
    steps = tuple(reader.feature(t, f"steps {k}", "step") for k, t in enumerate(reader.table_list(data, "steps")))
    fixtures = tuple(reader.feature(t, f"fixtures {k}", None)
                     for k, t in enumerate(reader.table_list(data, "fixtures")))
    door_frames = tuple(reader.door_frame(t, k) for k, t in enumerate(reader.table_list(data, "door_frames")))
    wiped = reader.wiped_area(data) if "wiped_area" in data else None
    tilt_cab = reader.tilt_cab(data) if "tilt_cab" in data else None
    return VehicleSpec(name, blueprint, tuple(aliases), box, solids, zones, source, tuple(float(a) for a in axles),
                       wheels, keep_outs, min_height, category, title, steps, fixtures, door_frames, wiped, tilt_cab,
                       reader.legal_width(data))


class _Reader:
    """Typed access to TOML tables with errors that name the file and the entry."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, where: str, message: str) -> DataError:
        return DataError(f"{self.source}: {where}: {message}")

    def text(self, table: dict, key: str, where: str = "top level") -> str:
        value = table.get(key)
        if not isinstance(value, str) or not value:
            raise self.fail(where, f"'{key}' must be a non-empty string")
        return value

    def category(self, table: dict) -> str:
        value = table.get("category")
        if not isinstance(value, str) or value.strip().upper() not in CATEGORIES:
            raise self.fail("top level", f"'category' must be a UN vehicle category, one of {', '.join(CATEGORIES)} "
                                         f"(M1 a car, N3 a heavy truck), got {value!r}")
        return value.strip().upper()

    def table_list(self, table: dict, key: str) -> list:
        value = table.get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self.fail("top level", f"'{key}' must be an array of tables ([[{key}]])")
        return value

    def numbers(self, table: dict, key: str, count: int, where: str = "top level", positive: bool = False):
        value = table.get(key)
        if not isinstance(value, list) or len(value) != count or not all(_is_number(v) for v in value):
            raise self.fail(where, f"'{key}' must be {count} finite numbers, got {value!r}")
        if positive and not all(v > 0 for v in value):
            raise self.fail(where, f"'{key}' must be positive, got {value!r}")
        return [float(v) for v in value]

    def flag(self, table: dict, key: str, where: str) -> bool:
        value = table.get(key, False)
        if not isinstance(value, bool):
            raise self.fail(where, f"'{key}' must be true or false, got {value!r}")
        return value

    def number(self, table: dict, key: str, where: str, positive: bool = True) -> float:
        value = table.get(key)
        if not _is_number(value) or (positive and value <= 0):
            raise self.fail(where, f"'{key}' must be a {'positive ' if positive else ''}number, got {value!r}")
        return float(value)

    def polygon(self, table: dict, key: str, where: str) -> np.ndarray:
        value = table.get(key)
        valid = (isinstance(value, list) and len(value) >= 3
                 and all(isinstance(p, list) and len(p) == 2 and all(_is_number(v) for v in p) for p in value))
        if not valid:
            raise self.fail(where, f"'{key}' must be a list of at least 3 [a, b] points (finite numbers)")
        return np.array(value, dtype=float)

    def solid(self, table: dict, index: int):
        kind = table.get("type")
        where = f"solid {index} ({table.get('name', kind)})"
        name = str(table.get("name", f"{kind}{index}"))
        if kind == "prism":
            plan = self.polygon(table, "plan", where)
            if np.any(plan[:, 1] < -1e-9):
                raise self.fail(where, "'plan' is the half outline with y >= 0 (it is mirrored to -y)")
            taper = tuple(self.numbers(table, "taper", 2, where, positive=True)) if "taper" in table else (1.0, 1.0)
            return Prism(name, self.polygon(table, "side", where), plan, taper)
        if kind == "wheels":
            return self.wheels(table, where, name)
        if kind == "box":
            return Box(name, np.array(self.numbers(table, "center", 3, where)),
                       np.array(self.numbers(table, "size", 3, where, positive=True)), self.flag(table, "mirrored", where))
        if kind == "mesh":
            file = Path(self.text(table, "file", where))
            return MeshSolid(name, file if file.is_absolute() else Path(self.source).parent / file)
        raise self.fail(where, f"unknown solid type {kind!r}; use one of {', '.join(SOLID_TYPES)}")

    def wheels(self, table: dict, where: str, name: str) -> Wheels:
        axles = table.get("axles")
        if not isinstance(axles, list) or not axles or not all(_is_number(a) for a in axles):
            raise self.fail(where, "'axles' must be a list of axle x positions (m)")
        return Wheels(name, tuple(float(a) for a in axles), self.number(table, "radius", where),
                      self.number(table, "width", where), self.number(table, "track", where))

    def named_box(self, table: dict, where: str) -> tuple[str, np.ndarray, np.ndarray]:
        """A table's ``name`` and its box ``min`` < ``max`` (3,) m."""
        return (self.text(table, "name", where), *self.box(table, where))

    def box(self, table: dict, where: str) -> tuple[np.ndarray, np.ndarray]:
        """A table's box ``min`` < ``max`` (3,) m."""
        low, high = np.array(self.numbers(table, "min", 3, where)), np.array(self.numbers(table, "max", 3, where))
        if np.any(low >= high):
            raise self.fail(where, f"'min' must be below 'max' on every axis, got {low.tolist()} and {high.tolist()}")
        return low, high

    def zone(self, table: dict, index: int) -> ZoneSpec:
        where = f"zone {index} ({table.get('name', '?')})"
        name, low, high = self.named_box(table, where)
        normal = np.array(self.numbers(table, "normal", 3, where))
        if np.linalg.norm(normal) < 1e-9:
            raise self.fail(where, "'normal' must be a non-zero vector")
        cone = self.number(table, "cone_deg", where)
        if cone > 180:
            raise self.fail(where, f"'cone_deg' must be in (0, 180], got {cone}")
        raised = self.number(table, "raised_max", where, positive=False) if "raised_max" in table else 0.0
        if raised < 0:
            raise self.fail(where, f"'raised_max' is a height above the surface in metres, >= 0, got {raised}")
        cost = self.number(table, "cost", where, positive=False) if "cost" in table else 1.0
        if cost < 0:
            raise self.fail(where, f"'cost' is a relative mounting cost, >= 0 (1 an ordinary body panel), got {cost}")
        return ZoneSpec(name, low, high, normal / np.linalg.norm(normal), cone, self.flag(table, "mirrored", where),
                        raised, cost)


    def keep_out(self, table: dict, index: int) -> KeepOutSpec:
        where = f"keep_out {index} ({table.get('name', '?')})"
        name, low, high = self.named_box(table, where)
        reason = self.text(table, "reason", where) if "reason" in table else name
        kingpin = np.array(self.numbers(table, "kingpin", 3, where)) if "kingpin" in table else None
        if kingpin is not None and not kingpin[0] < high[0]:
            raise self.fail(where, f"the trailer's 'kingpin' must lie behind its front (x < {high[0]:g}), got "
                                   f"x {kingpin[0]:g}")
        return KeepOutSpec(name, low, high, reason, self.flag(table, "mirrored", where),
                           self.flag(table, "optional", where), self.flag(table, "occludes", where), kingpin)

    def table(self, data: dict, key: str) -> dict:
        value = data.get(key)
        if not isinstance(value, dict):
            raise self.fail("top level", f"'{key}' must be a table ([{key}])")
        return value

    def feature(self, table: dict, where: str, kind: str | None) -> FeatureBox:
        """A ``[[steps]]`` (``kind`` "step") or ``[[fixtures]]`` (``kind`` None: read from the table) entry."""
        where = f"{where} ({table.get('name', '?')})"
        name, low, high = self.named_box(table, where)
        if kind is None:
            kind = table.get("kind")
            if kind not in FIXTURE_KINDS:
                raise self.fail(where, f"'kind' must be one of {', '.join(FIXTURE_KINDS)}, got {kind!r}")
        return FeatureBox(name, kind, low, high, self.flag(table, "mirrored", where))

    def door_frame(self, table: dict, index: int) -> DoorFrameSpec:
        where = f"door_frames {index} ({table.get('name', '?')})"
        name, low, high = self.named_box(table, where)
        frame = self.number(table, "frame", where) if "frame" in table else 0.10
        hinge = table.get("hinge")
        if hinge is not None and hinge not in HINGE_EDGES:
            raise self.fail(where, f"'hinge' must be one of {', '.join(HINGE_EDGES)} (the hinged edge), got {hinge!r}")
        if hinge is not None and HINGE_EDGES[hinge][0] == int(np.argmin(high - low)):
            raise self.fail(where, f"the hinge '{hinge}' runs across the door: the box's thinnest side is across "
                                   "the door, its hinge along one of its other edges")
        return DoorFrameSpec(name, low, high, frame, hinge, self.flag(table, "mirrored", where))

    def wiped_area(self, data: dict) -> WipedAreaSpec:
        table = self.table(data, "wiped_area")
        zone = self.text(table, "zone", "wiped_area") if "zone" in table else "windshield_front"
        return WipedAreaSpec(zone, self.polygon(table, "outline", "wiped_area"))

    def tilt_cab(self, data: dict) -> TiltCabSpec:
        table = self.table(data, "tilt_cab")
        pivot = np.array(self.numbers(table, "pivot", 2, "tilt_cab"))
        angle = self.number(table, "angle_deg", "tilt_cab")
        if angle > 90:
            raise self.fail("tilt_cab", f"'angle_deg' is the cab's tilt in degrees, in (0, 90], got {angle:g}")
        return TiltCabSpec(pivot, angle, *self.box(table, "tilt_cab"))

    def legal_width(self, data: dict) -> float:
        """The spec's ``legal_width`` m, else REFRIGERATED_WIDTH_M with ``refrigerated = true``, else LEGAL_WIDTH_M."""
        refrigerated = self.flag(data, "refrigerated", "top level")
        if "legal_width" not in data:
            return REFRIGERATED_WIDTH_M if refrigerated else LEGAL_WIDTH_M
        width = self.number(data, "legal_width", "top level")
        if not 1.0 <= width <= 4.0:
            raise self.fail("top level", f"'legal_width' is the vehicle's legal width in metres (2.55 in the EU, "
                                         f"2.60 for refrigerated bodies), got {width:g}")
        return width


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
