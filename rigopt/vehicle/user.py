"""User vehicles: check a mesh file, bring it into the ISO frame, give it zones, and store it by name.

A stored vehicle is ``$RIGOPT_HOME/vehicles/<name>/`` holding ``body.ply`` (ISO frame, metres) and a
``vehicle.toml`` whose one solid is that mesh; from then on ``--vehicle <name>`` works everywhere. Names are
unique without regard to case; replacing a stored vehicle needs ``force``, and the folder is written whole
(rigopt.output.atomic_folder) or not at all.
"""

from __future__ import annotations

import re
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from rigopt.errors import DataError, RigoptError
from rigopt.output import atomic_folder
from rigopt.vehicle.library import SPEC_FILE, broken_user_vehicles, find_spec, user_vehicles_dir
from rigopt.vehicle.model import ZONE_QUERY_EDGE, expand_zones
from rigopt.vehicle.closing import ClosingReport, close_mesh
from rigopt.vehicle.orientation import check_pose, frame_rotation
from rigopt.vehicle.spec import read_toml, spec_from_dict
from rigopt.vehicle.wheels import FoundWheels, find_wheels

FRAMES = ("carla", "iso")
#: Mesh formats read (trimesh; COLLADA through pycollada); scenes of several parts are merged.
MESH_FORMATS = (".obj", ".stl", ".ply", ".glb", ".gltf", ".dae", ".off")
#: The lowest point of the body must lie within this distance of the ground plane z = 0 (m).
GROUND_TOLERANCE = 0.5


@dataclass(frozen=True)
class PreparedMesh:
    """A user's mesh ready to store: ``mesh`` closed, ISO frame, metres; ``raw`` the input in the ISO frame
    before closing; ``closing`` how it was closed; ``wheels`` found (front first); ``warnings``."""

    mesh: trimesh.Trimesh
    raw: trimesh.Trimesh
    closing: ClosingReport
    wheels: tuple[FoundWheels, ...]
    warnings: tuple[str, ...]


@dataclass(frozen=True)
class AddedVehicle:
    """What ``add_user_vehicle`` stored: the spec ``path``, the ``axles`` (x m, front first), the
    ``wheels`` found, the ``closing`` report and ``warnings``."""

    path: Path
    axles: tuple[float, ...]
    wheels: tuple[FoundWheels, ...]
    closing: ClosingReport
    warnings: tuple[str, ...]


def carla_mesh_to_iso(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Reflect y (CARLA y right -> ISO y left); face winding is reversed so normals stay outward."""
    return trimesh.Trimesh(mesh.vertices * np.array([1.0, -1.0, 1.0]), mesh.faces[:, ::-1], process=False)


def read_mesh_file(path) -> trimesh.Trimesh:
    """Every triangle of a mesh file as one mesh, as stored (the parts of a scene merged with their
    transforms applied); no repair."""
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


def prepare_user_mesh(path, frame: str = "iso", *, scale: float = 1.0, forward: str | None = None,
                      up: str | None = None, allow_size: bool = False, axles=None) -> PreparedMesh:
    """Read a mesh file, bring it into the ISO frame (frame reflection, then ``--forward``/``--up``
    rotation, then ``scale``), check units, orientation and size (fast, before closing; see
    :mod:`rigopt.vehicle.orientation`), find its wheels, and close it (:mod:`rigopt.vehicle.closing`)."""
    path = Path(path)
    if frame not in FRAMES:
        raise RigoptError(f"--frame must be one of {', '.join(FRAMES)}, got {frame!r}")
    if not (np.isfinite(scale) and scale > 0):
        raise RigoptError(f"--scale must be a positive number, got {scale}")
    rotation = frame_rotation(forward or "+x", up or "+z")
    loaded = read_mesh_file(path)
    if frame == "carla":
        loaded = carla_mesh_to_iso(loaded)
    raw = trimesh.Trimesh(loaded.vertices @ rotation.T * scale, loaded.faces, process=False)
    raw.remove_unreferenced_vertices()
    wheels_guess = find_wheels(raw) if np.ptp(raw.bounds, axis=0).max() > 0 else ()
    warnings = check_pose(raw, str(path), scale=scale, forward=forward, up=up, allow_size=allow_size,
                          axles=[w.x for w in wheels_guess])
    if abs(raw.bounds[0, 2]) > GROUND_TOLERANCE:
        raise DataError(f"{path}: the lowest point is at z = {raw.bounds[0, 2]:.2f} m; move the mesh so that "
                        "its wheels stand on z = 0")
    wheels = find_wheels(raw, axles) if axles is not None else wheels_guess
    closed, report = close_mesh(raw, str(path))
    return PreparedMesh(closed, raw, report, wheels, tuple(warnings))


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
                     scale: float = 1.0, forward: str | None = None, up: str | None = None,
                     allow_size: bool = False, axles=None, roof_rack: float | None = None) -> AddedVehicle:
    """Check ``mesh_path``, store it as vehicle ``name`` with the zones of ``zones_path`` (a TOML file of
    ``[[zones]]``) or defaults from its box (plus a ``roof_rack`` raised zone of height ``roof_rack`` m),
    its axles and wheels (found, or at ``axles`` x m), and return what was stored.

    ``scale``, ``forward``, ``up`` and ``allow_size`` are the mesh flags of :func:`prepare_user_mesh`. A
    user vehicle of the same name (any case) is replaced only with ``force``; built-in names and aliases
    are never taken.
    """
    if not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.-]*", name):
        raise RigoptError(f"vehicle name {name!r} must be letters, digits, '_', '.' or '-'")
    if roof_rack is not None and not (np.isfinite(roof_rack) and 0 < roof_rack <= 3.0):
        raise RigoptError(f"--roof-rack is the rack's height above the roof in metres, in (0, 3], got {roof_rack}")
    if axles is not None:
        axles = sorted((float(x) for x in axles), reverse=True)
        if not axles or not all(np.isfinite(axles)):
            raise RigoptError("--axles needs the x (m, ISO frame) of each axle, e.g. --axles 1.5,-1.4")
    folder = _store_folder(name, force)
    prepared = prepare_user_mesh(mesh_path, frame, scale=scale, forward=forward, up=up, allow_size=allow_size,
                                 axles=axles)
    mesh = prepared.mesh
    if axles is not None:
        low, high = mesh.bounds[:, 0]
        outside = [x for x in axles if not low <= x <= high]
        if outside:
            raise RigoptError(f"--axles {outside} lie outside the mesh's length (x from {low:.2f} to {high:.2f} m)")
    zones = _read_zones(zones_path) if zones_path else default_zones(mesh.bounds)
    if roof_rack is not None:
        zones = [z for z in zones if z.get("name") != "roof_rack"] + [roof_rack_zone(mesh.bounds, roof_rack)]
    found_axles = tuple(axles) if axles is not None else tuple(w.x for w in prepared.wheels)
    data = {"name": name, "blueprint": name, "aliases": [], "box": np.ptp(mesh.bounds, axis=0).tolist(),
            "axles": [round(x, 4) for x in found_axles],
            "solids": [{"name": "body", "type": "mesh", "file": "body.ply"}],
            "wheels": [{"axles": [round(w.x, 4)], "radius": round(w.radius, 4), "width": round(w.width, 4),
                        "track": round(w.track, 4)} for w in prepared.wheels],
            "zones": zones}
    if not data["wheels"]:
        del data["wheels"]
    # validated before anything is written; problems name the user's zones file (or the mesh for default zones)
    spec = spec_from_dict(data, str(zones_path or mesh_path))
    _check_zones_select_surface(spec, mesh)
    with atomic_folder(folder, force=True, option="vehicle store") as work:
        mesh.export(work / "body.ply")
        (work / SPEC_FILE).write_text(_to_toml(data))
    for old in [p for p in folder.parent.iterdir() if p.name.lower() == name.lower() and p.name != name]:
        shutil.rmtree(old, ignore_errors=True)  # the same name in another case, replaced (force was given)
    return AddedVehicle(folder / SPEC_FILE, found_axles, prepared.wheels, prepared.closing, prepared.warnings)


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
