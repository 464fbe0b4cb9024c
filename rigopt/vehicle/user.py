"""User vehicles: check a mesh file, bring it into the ISO frame, give it zones, and store it by name.

A stored vehicle is ``$RIGOPT_HOME/vehicles/<name>/`` holding ``body.ply`` (ISO frame, metres, from the
vehicle centre: the centre of the body's footprint box, on the ground under its tyres, whatever the file's
origin) and a ``vehicle.toml`` whose one solid is that mesh, with its axles, wheels, zones and keep-outs; from then on ``--vehicle <name>`` works everywhere. Names are
unique without regard to case; replacing a stored vehicle needs ``force``, and the folder is written whole
(rigopt.output.atomic_folder) or not at all.
"""

from __future__ import annotations

import re
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import trimesh

from rigopt.errors import DataError, RigoptError
from rigopt.output import atomic_folder
from rigopt.vehicle.library import SPEC_FILE, broken_user_vehicles, find_spec, user_vehicles_dir
from rigopt.vehicle.model import ZONE_QUERY_EDGE, Vehicle, expand_zones
from rigopt.vehicle.category import body_width, width_warning
from rigopt.vehicle.closing import SHELL_PITCHES, ClosingReport, close_mesh
from rigopt.vehicle.glass import glass_features
from rigopt.vehicle.materials import KINDS, material_parts, part_fixtures
from rigopt.vehicle.mud_flaps import mud_flaps
from rigopt.vehicle.orientation import PoseError, check_pose, frame_rotation
from rigopt.vehicle.spec import CATEGORIES, read_toml, spec_from_dict
from rigopt.vehicle.supports import mirror_zone, narrow_keep_outs
from rigopt.vehicle.treads import step_treads
from rigopt.vehicle.wheels import FoundWheels, contact_height, find_wheels

FRAMES = ("carla", "iso")
#: Mesh formats read (trimesh; COLLADA through pycollada); scenes of several parts are merged.
MESH_FORMATS = (".obj", ".stl", ".ply", ".glb", ".gltf", ".dae", ".off")
#: Without wheels to stand on, the lowest point of the body must lie within this distance of z = 0 (m).
GROUND_TOLERANCE = 0.5
#: A lowering onto the wheels smaller than this (m) is made without a note.
GROUND_NOTE = 0.005
#: Two axles closer than this (m) are one: the smallest road wheel's diameter.
MIN_AXLE_GAP = 0.4
#: A narrow part's keep-out reaches this far (m) beyond its thickened surface: the lens's 3 cm and 3 cm more.
KEEP_OUT_CLEARANCE = 0.06


@dataclass(frozen=True)
class PreparedMesh:
    """A user's mesh ready to store: ``mesh`` closed, ISO frame, metres, from the vehicle centre; ``raw`` the
    input in that frame before closing; ``closing`` how it was closed; ``wheels`` found (front first);
    ``scale`` applied (file unit -> m); ``offset`` (3,) m added to every point after the flags (the file's
    origin moved to the vehicle centre: the centre of the footprint box, on the ground); ``warnings`` and
    ``notes`` (what was inferred); ``parts``: the parts its materials name (glass, lamps, number plates:
    :func:`rigopt.vehicle.materials.material_parts`) in the same frame."""

    mesh: trimesh.Trimesh
    raw: trimesh.Trimesh
    closing: ClosingReport
    wheels: tuple[FoundWheels, ...]
    warnings: tuple[str, ...]
    notes: tuple[str, ...] = ()
    scale: float = 1.0
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    parts: dict = field(default_factory=lambda: {kind: [] for kind in KINDS})


@dataclass(frozen=True)
class AddedVehicle:
    """What ``add_user_vehicle`` stored: the spec ``path``, the ``axles`` (x m, front first), the
    ``wheels`` found, the ``closing`` report, the ``keep_outs`` made for narrow parts, ``warnings`` and
    ``notes``; its UN ``category`` and why (``category_reason``: the shape's suggestion, or that it was given);
    ``mirror``: the ``mirror`` zone inferred over its mirror heads (:func:`rigopt.vehicle.supports.mirror_zone`),
    or None; ``treads``: the step treads found on it (``[[steps]]`` entries, :func:`rigopt.vehicle.treads.step_treads`);
    ``glass``: the zones its glass became (``windshield_front``, ``windshield_rear``), its side and roof panes
    being among ``keep_outs`` (:mod:`rigopt.vehicle.glass`); ``fixtures``: its lamps and number plates
    (:func:`rigopt.vehicle.materials.part_fixtures`) and mud flaps (:mod:`rigopt.vehicle.mud_flaps`), ``[[fixtures]]``
    entries."""

    path: Path
    axles: tuple[float, ...]
    wheels: tuple[FoundWheels, ...]
    closing: ClosingReport
    warnings: tuple[str, ...]
    notes: tuple[str, ...] = ()
    keep_outs: tuple[dict, ...] = ()
    category: str = "M1"
    category_reason: str = ""
    mirror: dict | None = None
    treads: tuple[dict, ...] = ()
    glass: tuple[dict, ...] = ()
    fixtures: tuple[dict, ...] = ()


@dataclass(frozen=True)
class FoundFeatures:
    """What a user's mesh shows beyond its box: ``glass_zones`` (the windscreen and rear window as zones),
    ``keep_outs`` (side and roof glass), ``steps`` (treads) and ``fixtures`` (lamps, number plates, mud flaps), as
    ``vehicle.toml`` entries."""

    glass_zones: list[dict]
    keep_outs: list[dict]
    steps: list[dict]
    fixtures: list[dict]


def found_features(prepared: PreparedMesh) -> FoundFeatures:
    """The body features :mod:`rigopt.vehicle.glass`, :mod:`~rigopt.vehicle.treads`, :mod:`~rigopt.vehicle.materials`
    and :mod:`~rigopt.vehicle.mud_flaps` find on ``prepared`` (vehicle frame)."""
    glass = np.concatenate([triangles for _, triangles in prepared.parts["glass"]] + [np.zeros((0, 3, 3))])
    glass_zones, keep_outs = glass_features(glass, [0.0, 0.0, float(prepared.mesh.bounds[:, 2].mean())])
    return FoundFeatures(glass_zones, keep_outs, step_treads(prepared.raw, [(w.x, w.radius) for w in prepared.wheels]),
                         part_fixtures(prepared.parts) + mud_flaps(prepared.raw, prepared.wheels))


def carla_mesh_to_iso(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Reflect y (CARLA y right -> ISO y left); face winding is reversed so normals stay outward."""
    return trimesh.Trimesh(mesh.vertices * np.array([1.0, -1.0, 1.0]), mesh.faces[:, ::-1], process=False)


def read_mesh_file(path) -> trimesh.Trimesh:
    """Every triangle of a mesh file as one mesh, as stored (the parts of a scene merged with their
    transforms applied; a COLLADA file's declared unit not applied, see :func:`declared_unit`); no repair."""
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: no such mesh file")
    if path.suffix.lower() not in MESH_FORMATS:
        raise DataError(f"{path}: cannot read {path.suffix or 'extension-less'} files: not a mesh format rigopt "
                        f"reads; use one of {', '.join(MESH_FORMATS)}")
    if path.suffix.lower() == ".dae":
        try:
            import collada  # noqa: F401  (trimesh reads COLLADA through it)
        except ImportError:
            raise DataError(f"{path}: reading COLLADA needs the pycollada package: pip install pycollada") from None
    try:
        loaded = trimesh.load(path, force="mesh", process=False)
    except Exception as error:  # trimesh raises many kinds for unreadable files
        raise DataError(f"{path}: trimesh cannot read this mesh ({type(error).__name__}: {error})") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise DataError(f"{path}: the file holds no triangles")
    if not np.all(np.isfinite(loaded.vertices)):
        raise DataError(f"{path}: the mesh has vertices that are not finite numbers")
    return trimesh.Trimesh(np.asarray(loaded.vertices, float), np.asarray(loaded.faces), process=False)


def declared_unit(path) -> float | None:
    """Metres per unit that a COLLADA file declares (``<asset><unit meter="0.01"/>``, the document's own
    asset), or None (other formats, no declaration, or 1)."""
    path = Path(path)
    if path.suffix.lower() != ".dae":
        return None
    try:
        for _, element in ElementTree.iterparse(path, events=("end",)):
            tag = element.tag.rsplit("}", 1)[-1]
            if tag == "unit" and "meter" in element.attrib:
                value = float(element.attrib["meter"])
                return value if np.isfinite(value) and value > 0 and value != 1.0 else None
            if tag == "asset":  # the first asset to close is the document's (COLLADA puts it first)
                return None
    except (ElementTree.ParseError, ValueError):
        return None
    return None


def prepare_user_mesh(path, frame: str = "iso", *, scale: float | None = None, length: float | None = None,
                      forward: str | None = None, up: str | None = None, allow_size: bool = False, axles=None,
                      ground: bool = False, pitch: float | None = None) -> PreparedMesh:
    """Read a mesh file and bring it into rigopt's vehicle frame: frame reflection, ``--forward``/``--up``
    rotation, scale (``scale``; or ``length``: the longest extent becomes that many metres; else a COLLADA
    file's declared unit, else 1), then moved so that the centre of its footprint box is at x = y = 0 and its
    tyres' lowest contacts on z = 0 (without tyres: ``ground`` puts its lowest point there, else the file's
    z is kept when its lowest point is within GROUND_TOLERANCE of 0). Checks units, orientation and size (fast,
    before closing; :mod:`rigopt.vehicle.orientation`), measures the wheels (at ``axles`` x m, vehicle frame,
    when given) and closes the mesh (:mod:`rigopt.vehicle.closing`, grid ``pitch`` m)."""
    path = Path(path)
    if frame not in FRAMES:
        raise RigoptError(f"--frame must be one of {', '.join(FRAMES)}, got {frame!r}")
    for flag, value in (("--scale", scale), ("--length", length)):
        if value is not None and not (np.isfinite(value) and value > 0):
            raise RigoptError(f"{flag} must be a positive number, got {value}")
    if scale is not None and length is not None:
        raise RigoptError("give --scale or --length, not both (--length sets the scale from the real length)")
    rotation = frame_rotation(forward or "+x", up or "+z")
    loaded = read_mesh_file(path)
    if frame == "carla":
        loaded = carla_mesh_to_iso(loaded)
    posed = trimesh.Trimesh(loaded.vertices @ rotation.T, loaded.faces, process=False)
    posed.remove_unreferenced_vertices()
    notes = []
    if length is not None:
        scale = length / float(np.ptp(posed.bounds, axis=0).max())
        notes.append(f"scaled by {scale:.6g} to a length of {length:g} m")
    elif scale is None:
        scale = declared_unit(path) or 1.0
        if scale != 1.0:
            notes.append(f"the file declares its unit as {scale:g} m (COLLADA <unit meter>): scaled by {scale:g}")
    raw = trimesh.Trimesh(posed.vertices * scale, posed.faces, process=False)
    centre = 0.5 * (raw.bounds[0] + raw.bounds[1])
    offset = np.array([-centre[0], -centre[1], 0.0])
    raw.apply_translation(offset)
    wheels_guess = find_wheels(raw) if np.ptp(raw.bounds, axis=0).max() > 0 else ()
    warnings = check_pose(raw, str(path), scale=scale, forward=forward, up=up, allow_size=allow_size,
                          axles=[w.x for w in wheels_guess])
    lift = _ground_lift(raw, wheels_guess, ground, str(path), notes)
    raw.apply_translation([0.0, 0.0, lift])
    offset[2] = lift
    if np.abs(offset).max() > GROUND_NOTE:
        origin = np.round(offset, 3) + 0.0  # no negative zeros
        notes.append("measured from the centre of its footprint box on the ground: the file's origin is at "
                     f"({origin[0]:+.3f}, {origin[1]:+.3f}, {origin[2]:+.3f}) m (ISO x, y, z)")
    if axles is not None:
        _check_axles(axles, raw.bounds[:, 0])
    wheels = find_wheels(raw, axles) if axles is not None else wheels_guess
    closed, report = close_mesh(raw, str(path), pitch=pitch)
    reflect = np.array([1.0, -1.0, 1.0]) if frame == "carla" else np.ones(3)
    parts = {kind: [(name, ((triangles * reflect) @ rotation.T * scale + offset).reshape(-1, 3, 3))
                    for name, triangles in found] for kind, found in material_parts(path).items()}
    return PreparedMesh(closed, raw, report, wheels, tuple(warnings), tuple(notes), float(scale),
                        tuple(float(v) for v in offset), parts)


def _ground_lift(raw: trimesh.Trimesh, wheels, ground: bool, source: str, notes: list) -> float:
    """The z shift (m) that stands ``raw`` on the ground: its tyres' lowest contacts, else (``ground``) its lowest
    point, else none when its lowest point is near z = 0; a PoseError naming --ground otherwise."""
    lowest = float(raw.bounds[0, 2])
    contact = contact_height(raw, wheels)
    if contact is not None:
        if abs(contact) > GROUND_NOTE:
            notes.append(f"stood on its tyres: moved {'down' if contact > 0 else 'up'} by {abs(contact):.3f} m")
        return -contact
    if ground:
        if abs(lowest) > GROUND_NOTE:
            notes.append(f"--ground: moved {'down' if lowest > 0 else 'up'} by {abs(lowest):.3f} m")
        return -lowest
    if abs(lowest) > GROUND_TOLERANCE:
        raise PoseError(f"{source}: the lowest point is at z = {lowest:.2f} m and no tyres were found to stand it on: "
                        "add --ground (to put its lowest point on z = 0)", {"--ground": ""})
    return 0.0


def _check_axles(axles, x_range) -> None:
    """Refuse ``axles`` (x m, vehicle frame, front first) closer than MIN_AXLE_GAP or outside ``x_range``."""
    low, high = (float(v) for v in x_range)
    outside = [x for x in axles if not low < x < high]
    if outside:
        raise RigoptError(f"--axles {', '.join(f'{x:g}' for x in outside)} lie outside the mesh's length (x from "
                          f"{low:.2f} to {high:.2f} m, measured from the centre of its footprint box)")
    close = [(a, b) for a, b in zip(axles, axles[1:]) if a - b < MIN_AXLE_GAP]
    if close:
        a, b = close[0]
        raise RigoptError(f"--axles {a:g} and {b:g} are {a - b:.2f} m apart; axles are distinct and at least "
                          f"{MIN_AXLE_GAP:g} m apart (a wheel's diameter): give each axle's x once")


def load_user_mesh(path, frame: str = "iso", **flags) -> trimesh.Trimesh:
    """Load a mesh file as one closed mesh in the ISO frame, checked (see :func:`prepare_user_mesh`)."""
    return prepare_user_mesh(path, frame, **flags).mesh


def default_zones(bounds: np.ndarray) -> list[dict]:
    """Zones derived from the body's box (2, 3): bumpers, fenders, B-pillars, windshields, roof halves."""
    (x0, y0, z0), (x1, y1, z1) = bounds
    length, height = x1 - x0, z1 - z0
    xm, top = (x0 + x1) / 2, z1 + 0.1

    def zone(name, low, high, normal, cone, mirrored=False):
        return {"name": name, "min": list(map(float, low)), "max": list(map(float, high)),
                "normal": normal, "cone_deg": cone, "mirrored": mirrored}

    side_y = (0.0, y1 + 0.1)
    return [
        zone("bumper_front", (x1 - 0.15 * length, y0 - 0.1, z0), (x1 + 0.1, y1 + 0.1, z0 + 0.6 * height), [1, 0, 0], 70),
        zone("bumper_rear", (x0 - 0.1, y0 - 0.1, z0), (x0 + 0.15 * length, y1 + 0.1, z0 + 0.6 * height), [-1, 0, 0], 70),
        zone("fender_front", (x1 - 0.35 * length, side_y[0], z0 + 0.15 * height),
             (x1 - 0.1 * length, side_y[1], z0 + 0.65 * height), [0, 1, 0], 60, True),
        zone("fender_rear", (x0 + 0.1 * length, side_y[0], z0 + 0.15 * height),
             (x0 + 0.35 * length, side_y[1], z0 + 0.65 * height), [0, 1, 0], 60, True),
        zone("b_pillar", (x0 + 0.35 * length, side_y[0], z0 + 0.5 * height),
             (x1 - 0.35 * length, side_y[1], z0 + 0.95 * height), [0, 1, 0], 60, True),
        zone("roof_front", (xm, y0 - 0.1, z0 + 0.8 * height), (x1 + 0.1, y1 + 0.1, top), [0, 0, 1], 30),
        zone("roof_rear", (x0 - 0.1, y0 - 0.1, z0 + 0.8 * height), (xm, y1 + 0.1, top), [0, 0, 1], 30),
        zone("windshield_front", (xm - 0.1 * length, y0 - 0.1, z0 + 0.55 * height), (x1 + 0.1, y1 + 0.1, top),
             [1, 0, 1], 50),
        zone("windshield_rear", (x0 - 0.1, y0 - 0.1, z0 + 0.55 * height), (xm + 0.1 * length, y1 + 0.1, top),
             [-1, 0, 1], 50),
    ]


def roof_rack_zone(bounds: np.ndarray, height: float) -> dict:
    """A raised zone over the top 20 % of the body's box (2, 3), upward normals within 30 degrees: a roof
    rack whose cameras may sit up to ``height`` m above the roof."""
    (x0, y0, z0), (x1, y1, z1) = bounds
    return {"name": "roof_rack", "min": [float(x0 - 0.1), float(y0 - 0.1), float(z0 + 0.8 * (z1 - z0))],
            "max": [float(x1 + 0.1), float(y1 + 0.1), float(z1 + 0.1)], "normal": [0, 0, 1], "cone_deg": 30,
            "mirrored": False, "raised_max": float(height)}


def add_user_vehicle(name: str, mesh_path, zones_path=None, frame: str = "iso", *, force: bool = False,
                     scale: float | None = None, length: float | None = None, forward: str | None = None,
                     up: str | None = None, allow_size: bool = False, axles=None, roof_rack: float | None = None,
                     ground: bool = False, pitch: float | None = None, category: str | None = None) -> AddedVehicle:
    """Check ``mesh_path``, store it as vehicle ``name`` with the zones of ``zones_path`` (a TOML file of
    ``[[zones]]``) or defaults from its box (plus a ``roof_rack`` raised zone of height ``roof_rack`` m, and
    keep-outs over its narrow parts: :mod:`rigopt.vehicle.supports`), its axles and wheels (found, or at
    ``axles`` x m from the vehicle centre), its UN ``category`` (None: the one its shape suggests,
    :mod:`rigopt.vehicle.category`), and return what was stored.

    ``scale``, ``length``, ``forward``, ``up``, ``allow_size``, ``ground`` and ``pitch`` are the mesh flags of
    :func:`prepare_user_mesh`. A user vehicle of the same name (any case) is replaced only with ``force``;
    built-in names and aliases are never taken.
    """
    if not re.fullmatch(r"[^\W_][\w.-]*", name):  # letters of any script, digits, '_', '.', '-'
        raise RigoptError(f"vehicle name {name!r} must start with a letter or digit and hold only letters, digits, "
                          "'_', '.' or '-' (no spaces, slashes or other marks)")
    if roof_rack is not None and not (np.isfinite(roof_rack) and 0 < roof_rack <= 3.0):
        raise RigoptError(f"--roof-rack is the rack's height above the roof in metres, in (0, 3], got {roof_rack}")
    if axles is not None:
        axles = sorted((float(x) for x in axles), reverse=True)
        if not axles or not all(np.isfinite(axles)):
            raise RigoptError("--axles needs the x (m, from the vehicle centre) of each axle, e.g. --axles 1.5,-1.4")
    if category is not None and str(category).strip().upper() not in CATEGORIES:
        raise RigoptError(f"--category {category!r} is not a UN vehicle category: give one of {', '.join(CATEGORIES)} "
                          "(M: carrying people, N: goods; 1 light, 2 medium, 3 heavy)")
    folder = _store_folder(name, force)
    prepared = prepare_user_mesh(mesh_path, frame, scale=scale, length=length, forward=forward, up=up,
                                 allow_size=allow_size, axles=axles, ground=ground, pitch=pitch)
    mesh = prepared.mesh
    zones = _read_zones(zones_path) if zones_path else default_zones(mesh.bounds)
    found = found_features(prepared)
    if not zones_path:
        # the glass first: a zone is the first holding a camera's foot and normal, and the roof's cone reaches a
        # raked windscreen
        zones = found.glass_zones + [z for z in zones if z["name"] not in {g["name"] for g in found.glass_zones}]
    if roof_rack is not None:
        zones = [z for z in zones if z.get("name") != "roof_rack"] + [roof_rack_zone(mesh.bounds, roof_rack)]
    found_axles = tuple(axles) if axles is not None else tuple(w.x for w in prepared.wheels)
    data = {"name": name, "blueprint": name, "aliases": [], "box": np.ptp(mesh.bounds, axis=0).tolist(),
            "axles": [round(x, 4) for x in found_axles],
            "solids": [{"name": "body", "type": "mesh", "file": "body.ply"}],
            "wheels": [{"axles": [round(w.x, 4)], "radius": round(w.radius, 4), "width": round(w.width, 4),
                        "track": round(w.track, 4)} for w in prepared.wheels],
            "zones": zones, "keep_out": found.keep_outs, "steps": found.steps, "fixtures": found.fixtures}
    # validated before anything is written; problems name the user's zones file (or the mesh for default zones)
    spec = spec_from_dict({k: v for k, v in data.items() if v != []}, str(zones_path or mesh_path))
    _check_zones_select_surface(spec, mesh)
    body = Vehicle(spec, mesh)
    if category is None:
        data["category"], reason = body.category_guess.category, body.category_guess.reason
    else:
        data["category"], reason = str(category).strip().upper(), "given (--category)"
    too_wide = width_warning(body)
    if not zones_path:
        # beyond the narrow part: its thickening and one grid pitch (an enclosed ladder is filled up to it)
        reach = (SHELL_PITCHES + 1) * prepared.closing.pitch + KEEP_OUT_CLEARANCE
        narrow = narrow_keep_outs(prepared.raw, reach)
        data["keep_out"] = narrow + found.keep_outs
        mirror = mirror_zone(narrow, mesh.bounds, body_width(body) / 2)
        if mirror is not None:
            data["zones"] = [*zones, mirror]
    data = {k: v for k, v in data.items() if v != [] or k in ("axles", "aliases")}
    with atomic_folder(folder, force=True, option="vehicle store") as work:
        mesh.export(work / "body.ply")
        (work / SPEC_FILE).write_text(_to_toml(data))
    for old in [p for p in folder.parent.iterdir() if p.name.lower() == name.lower() and p.name != name]:
        shutil.rmtree(old, ignore_errors=True)  # the same name in another case, replaced (force was given)
    return AddedVehicle(folder / SPEC_FILE, found_axles, prepared.wheels, prepared.closing,
                        prepared.warnings + ((too_wide,) if too_wide else ()), prepared.notes,
                        tuple(data.get("keep_out", ())), data["category"], reason,
                        next((z for z in data["zones"] if z["name"] == "mirror"), None), tuple(data.get("steps", ())),
                        tuple(found.glass_zones) if not zones_path else (), tuple(data.get("fixtures", ())))


def _store_folder(name: str, force: bool) -> Path:
    """The store folder of ``name``, refused for a built-in name or alias, or a stored name (any case)
    without ``force``."""
    try:
        existing = find_spec(name)
    except RigoptError:
        existing = None
    if existing is not None and not Path(existing.source).is_relative_to(user_vehicles_dir()):
        raise RigoptError(f"{name!r} is a built-in vehicle ({existing.name}); choose another name")
    folder = user_vehicles_dir() / name
    stored = [p.name for p in folder.parent.glob("*") if p.is_dir() and p.name.lower() == name.lower()] \
        if folder.parent.is_dir() else []
    stored += [n for n in broken_user_vehicles() if n.lower() == name.lower() and n not in stored]
    if existing is not None:
        stored.append(existing.name)
    if stored and not force:
        raise RigoptError(f"a user vehicle {stored[0]!r} exists (names ignore case); add --force to replace it, or "
                          "choose another name")
    return folder


def _read_zones(path) -> list[dict]:
    zones = read_toml(path, "zones file").get("zones")
    if not isinstance(zones, list) or not zones:
        raise DataError(f"{path}: expected one or more [[zones]] tables (name, min, max, normal, cone_deg)")
    return zones


def _check_zones_select_surface(spec, mesh: trimesh.Trimesh) -> None:
    vertices, faces = trimesh.remesh.subdivide_to_size(mesh.vertices, mesh.faces, ZONE_QUERY_EDGE)
    fine = trimesh.Trimesh(vertices, faces, process=False)
    centres, normals = fine.triangles_center, fine.face_normals
    for zone in expand_zones(spec.zones):
        if not zone.contains(centres, normals).any():
            raise DataError(f"{spec.source}: zone {zone.name!r} selects no surface of the mesh; widen its box "
                            f"{zone.min.round(2).tolist()}..{zone.max.round(2).tolist()} or its normal cone")


def _to_toml(data: dict) -> str:
    """The few TOML shapes a user vehicle spec needs: top-level scalars and lists, arrays of tables."""
    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return repr(float(v)) if isinstance(v, float) else str(v)

    lines = [f"{k} = {value(v)}" for k, v in data.items() if not isinstance(v, list) or not v or not isinstance(v[0], dict)]
    for key, tables in data.items():
        if isinstance(tables, list) and tables and isinstance(tables[0], dict):
            for table in tables:
                lines += ["", f"[[{key}]]"] + [f"{k} = {value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"
