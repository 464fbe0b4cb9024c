"""The glass of a user mesh, where its file says which parts are glass: the windscreen and rear window as zones, the
side and roof glass as keep-outs.

A mesh file's part is glass when its material says so: a name holding ``glass``, ``window``, ``windscreen``,
``windshield`` or ``screen`` (any case), or see-through (an OBJ material's dissolve ``d`` below 0.9 or its
transparency ``Tr`` above 0.1; a glTF material blended with a base colour alpha below 0.9). A mesh without
materials (STL, PLY, most raw exports) has no glass to find: its windscreen zone stays the box's (``user.default_zones``).

Of the glass, only the outside skin is read: faces whose normal points away from the body's centre (a glass
panel's inner faces look in). A face whose normal leans forward by at least ``LEAN`` (its x component; more than
sideways) is the windscreen's (a car's, raked 25-30 deg above the horizontal, leans about 0.45), back the rear
window's, sideways (y, more than along x) a side window's; the rest, facing up, a glass roof's. The windscreen and rear window replace the box-derived ``windshield_front`` and
``windshield_rear`` zones (their glass's box grown by ``ZONE_MARGIN`` m, the normal the glass's mean, within
``ZONE_CONE_DEG``): a camera there sits behind the glass (:mod:`rigopt.mounting.features`). Side windows wind down
and glass roofs cannot be drilled: each connected pane becomes a keep-out box (grown by ``KEEP_OUT_MARGIN`` m).

ISO vehicle frame, metres.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

GLASS_WORDS = ("glass", "window", "windscreen", "windshield", "screen")
OPAQUE = 0.9
LEAN = 0.3
ZONE_MARGIN, ZONE_CONE_DEG = 0.05, 50.0
KEEP_OUT_MARGIN = 0.03
SIDE_REASON, ROOF_REASON = "side window glass: it winds down", "glass roof: no housing is bonded to it"


def is_glass(material) -> bool:
    """Whether a trimesh material (SimpleMaterial from an OBJ's MTL, PBRMaterial from glTF, or None) is glass."""
    if material is None:
        return False
    name = str(getattr(material, "name", "") or "").lower()
    if any(word in name for word in GLASS_WORDS):
        return True
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


def glass_triangles(path) -> np.ndarray:
    """(k, 3, 3) the triangles of ``path``'s glass parts, in the file's frame and units (transforms of a scene's
    nodes applied, as the whole mesh is read); (0, 3, 3) when it has none or no materials."""
    try:
        loaded = trimesh.load(Path(path), process=False)
    except Exception:  # the whole mesh was read already; a file trimesh reads only as one mesh has no parts
        return np.zeros((0, 3, 3))
    parts = []
    if isinstance(loaded, trimesh.Scene):
        for node in loaded.graph.nodes_geometry:
            transform, name = loaded.graph[node]
            geometry = loaded.geometry[name]
            if isinstance(geometry, trimesh.Trimesh) and is_glass(getattr(geometry.visual, "material", None)):
                parts.append(trimesh.transform_points(geometry.triangles.reshape(-1, 3), transform).reshape(-1, 3, 3))
    elif isinstance(loaded, trimesh.Trimesh) and is_glass(getattr(loaded.visual, "material", None)):
        parts.append(loaded.triangles)
    return np.concatenate(parts) if parts else np.zeros((0, 3, 3))


def _outer_faces(triangles: np.ndarray, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The triangles (k, 3, 3) of the glass's outside skin (normals pointing away from ``centre`` (3,) m), their
    unit normals (k, 3) and areas (k,)."""
    cross = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    keep = area > 1e-9
    normals = cross[keep] / (2 * area[keep, None])
    centres = triangles[keep].mean(axis=1)
    outward = np.einsum("ij,ij->i", normals, centres - centre) > 0
    return triangles[keep][outward], normals[outward], area[keep][outward]


def _panes(index: np.ndarray, triangles: np.ndarray) -> list[np.ndarray]:
    """Connected panes of glass triangles (k, 3, 3) (sharing an edge, once coincident corners are merged): each
    pane's indices into ``index`` (k,), in order."""
    mesh = trimesh.Trimesh(triangles.reshape(-1, 3), np.arange(3 * len(triangles)).reshape(-1, 3), process=False)
    mesh.merge_vertices()
    groups = trimesh.graph.connected_components(mesh.face_adjacency, nodes=np.arange(len(triangles)), min_len=1)
    return [index[np.sort(np.asarray(group))] for group in groups]


def glass_features(triangles: np.ndarray, centre) -> tuple[list[dict], list[dict]]:
    """From the glass triangles (k, 3, 3), vehicle frame, of a body centred on ``centre`` (3,) m: the
    ``windshield_front`` and ``windshield_rear`` zones over the windscreen and rear window (those there are) and
    the keep-outs over the side and roof panes. Each pane (a connected piece of glass) is one kind, by the mean
    normal of its outside skin (a pane's edges face every way)."""
    if not len(triangles):
        return [], []
    triangles, normals, areas = _outer_faces(np.asarray(triangles, dtype=float), np.asarray(centre, dtype=float))
    kinds: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {"front": [], "rear": [], "side": [], "roof": []}
    for pane in _panes(np.arange(len(triangles)), triangles):
        normal = (normals[pane] * areas[pane, None]).sum(axis=0)
        normal /= np.linalg.norm(normal)
        along, across = normal[0], abs(normal[1])
        kind = ("front" if along >= LEAN and along > across else "rear" if -along >= LEAN and -along > across
                else "side" if across >= LEAN else "roof" if normal[2] >= LEAN else None)
        if kind:
            kinds[kind].append((triangles[pane].reshape(-1, 3), normal * areas[pane].sum()))
    zones = []
    for name, kind in (("windshield_front", "front"), ("windshield_rear", "rear")):
        if kinds[kind]:
            corners = np.concatenate([c for c, _ in kinds[kind]])
            normal = np.sum([n for _, n in kinds[kind]], axis=0)
            zones.append({"name": name, "min": _rounded(corners.min(axis=0) - ZONE_MARGIN),
                          "max": _rounded(corners.max(axis=0) + ZONE_MARGIN),
                          "normal": _rounded(normal / np.linalg.norm(normal)), "cone_deg": ZONE_CONE_DEG,
                          "mirrored": False})
    keep_outs = [{"name": f"{label} {k + 1}", "reason": reason, "min": _rounded(corners.min(axis=0) - KEEP_OUT_MARGIN),
                  "max": _rounded(corners.max(axis=0) + KEEP_OUT_MARGIN)}
                 for label, reason, kind in (("side window", SIDE_REASON, "side"), ("glass roof", ROOF_REASON, "roof"))
                 for k, (corners, _) in enumerate(sorted(kinds[kind], key=lambda pane: (-pane[0][:, 0].max(),
                                                                                        -pane[0][:, 1].max())))]
    return zones, keep_outs


def _rounded(values) -> list[float]:
    return [round(float(v), 3) for v in values]
