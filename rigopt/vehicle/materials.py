"""What a mesh file's materials say its parts are: glass, lamps, number plates.

A part's material is read by its name (any case) and, for glass, its transparency:

- **glass**: a name holding ``glass``, ``window``, ``windscreen``, ``windshield`` or ``screen``, or a see-through
  material (an OBJ material's dissolve ``d`` below 0.9 or its transparency ``Tr`` above 0.1; a glTF material
  blended with a base colour alpha below 0.9);
- **lamp**: ``lamp``, ``light``, ``indicator``, ``blinker`` or ``reflector`` (a lamp's lens must stay uncovered);
- **number_plate**: ``plate`` or ``licen`` (licence, license).

A lamp's or plate's word wins over glass (a "headlight glass" is a lamp's lens). A mesh without materials (STL, PLY, most raw exports) has no such parts. Triangles are in the file's frame and
units, with the transforms of a scene's nodes applied, as the whole mesh is read.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from rigopt.vehicle.supports import box_around, connected_pieces

GLASS_WORDS = ("glass", "window", "windscreen", "windshield", "screen")
LAMP_WORDS = ("lamp", "light", "indicator", "blinker", "reflector")
PLATE_WORDS = ("plate", "licen")
KINDS = ("glass", "lamp", "number_plate")
#: A lamp's or number plate's fixture box reaches this far (m) beyond the part.
FIXTURE_MARGIN = 0.01
OPAQUE = 0.9


def _see_through(material) -> bool:
    extra = {k.lower(): v for k, v in (getattr(material, "kwargs", None) or {}).items()}
    for key, see_through in (("d", lambda v: v < OPAQUE), ("tr", lambda v: v > 1 - OPAQUE)):
        try:
            value = float(np.ravel(extra[key])[0]) if key in extra else None
        except (TypeError, ValueError):
            value = None
        if value is not None and see_through(value):
            return True
    color = getattr(material, "baseColorFactor", None)
    if color is not None and str(getattr(material, "alphaMode", "")).upper() == "BLEND":
        alpha = np.asarray(color, dtype=float).ravel()[-1]
        return bool((alpha / 255.0 if alpha > 1.0 else alpha) < OPAQUE)
    return False


def material_kind(material) -> str | None:
    """'glass', 'lamp', 'number_plate' or None for a trimesh material (SimpleMaterial from an OBJ's MTL,
    PBRMaterial from glTF, or None)."""
    if material is None:
        return None
    name = str(getattr(material, "name", "") or "").lower()
    if any(word in name for word in LAMP_WORDS):
        return "lamp"
    if any(word in name for word in PLATE_WORDS):
        return "number_plate"
    if any(word in name for word in GLASS_WORDS) or _see_through(material):
        return "glass"
    return None


def material_parts(path) -> dict[str, list[tuple[str, np.ndarray]]]:
    """{kind: [(material name, (k, 3, 3) triangles) of each part of that kind]} of the mesh file ``path`` (module
    doc); every kind of KINDS is a key, its list empty when the file has none."""
    parts: dict[str, list[tuple[str, np.ndarray]]] = {kind: [] for kind in KINDS}
    try:
        loaded = trimesh.load(Path(path), process=False)
    except Exception:  # the whole mesh was read already; a file trimesh reads only as one mesh has no parts
        return parts
    if isinstance(loaded, trimesh.Scene):
        for node in loaded.graph.nodes_geometry:
            transform, name = loaded.graph[node]
            geometry = loaded.geometry[name]
            material = getattr(geometry.visual, "material", None) if isinstance(geometry, trimesh.Trimesh) else None
            kind = material_kind(material)
            if kind:
                corners = trimesh.transform_points(geometry.triangles.reshape(-1, 3), transform)
                parts[kind].append((str(material.name), corners.reshape(-1, 3, 3)))
    elif isinstance(loaded, trimesh.Trimesh):
        material = getattr(loaded.visual, "material", None)
        kind = material_kind(material)
        if kind:
            parts[kind].append((str(material.name), loaded.triangles))
    return parts


def part_fixtures(parts: dict[str, list[tuple[str, np.ndarray]]]) -> list[dict]:
    """``[[fixtures]]`` entries (name, kind, min, max) over each connected lamp and number plate of ``parts`` (as
    :func:`material_parts` returns them, in the vehicle frame), each box grown by FIXTURE_MARGIN m."""
    fixtures = []
    for kind, label in (("lamp", "lamp"), ("number_plate", "number plate")):
        pieces = [(name, triangles[piece]) for name, triangles in parts[kind] for piece in connected_pieces(triangles)]
        for k, (name, piece) in enumerate(sorted(pieces, key=lambda item: (-item[1][..., 0].max(), -item[1][..., 1].max()))):
            fixtures.append({"name": f"{label} {k + 1} (material {name})", "kind": kind,
                             **box_around(piece, FIXTURE_MARGIN)})
    return fixtures
