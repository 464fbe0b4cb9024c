"""User vehicles: check a mesh file, bring it into the ISO frame, give it zones, and store it by name.

A stored vehicle is ``$RIGOPT_HOME/vehicles/<name>/`` holding ``body.ply`` (ISO frame, metres) and a
``vehicle.toml`` whose one solid is that mesh; from then on ``--vehicle <name>`` works everywhere. Names are
unique without regard to case; replacing a stored vehicle needs ``force``, and the folder is written whole
(rigopt.output.atomic_folder) or not at all.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import trimesh

from rigopt.errors import DataError, RigoptError
from rigopt.output import atomic_folder
from rigopt.vehicle.library import SPEC_FILE, broken_user_vehicles, find_spec, user_vehicles_dir
from rigopt.vehicle.model import ZONE_QUERY_EDGE, expand_zones
from rigopt.vehicle.spec import read_toml, spec_from_dict

FRAMES = ("carla", "iso")
#: Plausible road-vehicle extents in metres: (length, width, height) lower and upper bounds.
SIZE_LOW = np.array([2.0, 1.0, 0.8])
SIZE_HIGH = np.array([25.0, 3.5, 5.0])
#: The lowest point of the body must lie within this distance of the ground plane z = 0 (m).
GROUND_TOLERANCE = 0.5


def carla_mesh_to_iso(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Reflect y (CARLA y right -> ISO y left); face winding is reversed so normals stay outward."""
    return trimesh.Trimesh(mesh.vertices * np.array([1.0, -1.0, 1.0]), mesh.faces[:, ::-1], process=False)


def load_user_mesh(path, frame: str = "iso") -> trimesh.Trimesh:
    """Load a mesh file (OBJ, STL, PLY, GLB, ...) as one watertight mesh in the ISO frame, checked."""
    path = Path(path)
    if frame not in FRAMES:
        raise RigoptError(f"--frame must be one of {', '.join(FRAMES)}, got {frame!r}")
    if not path.is_file():
        raise DataError(f"{path}: no such mesh file")
    try:
        loaded = trimesh.load(path, force="mesh", process=False)
    except Exception as error:  # trimesh raises many kinds for unreadable files
        raise DataError(f"{path}: trimesh cannot read this mesh ({type(error).__name__}: {error})") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise DataError(f"{path}: the file holds no triangles")
    mesh = _as_solid(loaded, path)
    if frame == "carla":
        mesh = carla_mesh_to_iso(mesh)
    _check_scale_and_pose(mesh, path)
    return mesh


def _as_solid(mesh: trimesh.Trimesh, path: Path) -> trimesh.Trimesh:
    """The mesh as a closed 2-manifold: manifold3d merges coincident open edges (STL files keep no shared
    vertices); failing that, trimesh fills holes and fixes normals first."""
    import manifold3d

    def solid(candidate: trimesh.Trimesh):
        raw = manifold3d.Mesh(np.asarray(candidate.vertices, dtype=np.float32),
                              np.asarray(candidate.faces, dtype=np.uint32))
        raw.merge()
        result = manifold3d.Manifold(raw)
        return result if result.status() == manifold3d.Error.NoError and not result.is_empty() else None

    result = solid(mesh)
    if result is None:
        repaired = mesh.copy()
        repaired.merge_vertices()
        trimesh.repair.fill_holes(repaired)
        trimesh.repair.fix_normals(repaired)
        result = solid(repaired)
    if result is None:
        raise DataError(f"{path}: the mesh is not watertight and could not be repaired (open edges, holes or "
                        "self-touching parts); export a closed surface")
    out = result.to_mesh()
    closed = trimesh.Trimesh(np.asarray(out.vert_properties[:, :3], dtype=float), np.asarray(out.tri_verts),
                             process=False)
    if closed.volume <= 0:
        raise DataError(f"{path}: the mesh encloses no volume (are its faces turned inside out?)")
    return closed


def _check_scale_and_pose(mesh: trimesh.Trimesh, path: Path) -> None:
    size = np.ptp(mesh.bounds, axis=0)
    described = f"{size[0]:.3g} x {size[1]:.3g} x {size[2]:.3g}"
    if np.all(size / 1000.0 >= SIZE_LOW * 0.5) and np.all(size / 1000.0 <= SIZE_HIGH):
        raise DataError(f"{path}: the mesh is {described} units, which looks like millimetres; "
                        "scale it to metres (x 0.001) before adding it")
    if np.all(size / 100.0 >= SIZE_LOW * 0.5) and np.all(size / 100.0 <= SIZE_HIGH) and size.max() > 40:
        raise DataError(f"{path}: the mesh is {described} units, which looks like centimetres; scale it to metres")
    if size[2] > size[0] or size[1] > size[0]:
        axis = "z (up)" if size[2] >= size[1] else "y (sideways)"
        raise DataError(f"{path}: the mesh is longest along {axis} ({described} m for x, y, z): it is lying on its "
                        "side or turned; rotate it so that x is forward and z up (or use --frame carla for "
                        "CARLA's y-right frame)")
    if np.any(size < SIZE_LOW) or np.any(size > SIZE_HIGH):
        raise DataError(f"{path}: {described} m (length x width x height) is not a road vehicle's size "
                        f"(expected between {SIZE_LOW.tolist()} and {SIZE_HIGH.tolist()} m); check its units")
    if abs(mesh.bounds[0, 2]) > GROUND_TOLERANCE:
        raise DataError(f"{path}: the lowest point is at z = {mesh.bounds[0, 2]:.2f} m; move the mesh so that "
                        "its wheels stand on z = 0")


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


def add_user_vehicle(name: str, mesh_path, zones_path=None, frame: str = "iso", *, force: bool = False) -> Path:
    """Check ``mesh_path``, store it as vehicle ``name`` with the zones of ``zones_path`` (a TOML file of
    ``[[zones]]``) or defaults from its box, and return the stored spec's path.

    A user vehicle of the same name (any case) is replaced only with ``force``; built-in names and aliases
    are never taken.
    """
    if not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.-]*", name):
        raise RigoptError(f"vehicle name {name!r} must be letters, digits, '_', '.' or '-'")
    folder = _store_folder(name, force)
    mesh = load_user_mesh(mesh_path, frame)
    zones = _read_zones(zones_path) if zones_path else default_zones(mesh.bounds)
    data = {"name": name, "blueprint": name, "aliases": [], "box": np.ptp(mesh.bounds, axis=0).tolist(),
            "solids": [{"name": "body", "type": "mesh", "file": "body.ply"}], "zones": zones}
    # validated before anything is written; problems name the user's zones file (or the mesh for default zones)
    spec = spec_from_dict(data, str(zones_path or mesh_path))
    _check_zones_select_surface(spec, mesh)
    with atomic_folder(folder, force=True, option="vehicle store") as work:
        mesh.export(work / "body.ply")
        (work / SPEC_FILE).write_text(_to_toml(data))
    for old in [p for p in folder.parent.iterdir() if p.name.lower() == name.lower() and p.name != name]:
        shutil.rmtree(old, ignore_errors=True)  # the same name in another case, replaced (force was given)
    return folder / SPEC_FILE


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
