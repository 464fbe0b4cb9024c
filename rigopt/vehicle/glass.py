"""The glass of a user mesh, where its file says which parts are glass (:mod:`rigopt.vehicle.materials`): the
windscreen and rear window as zones, the side and roof glass as keep-outs. A mesh without materials has no glass to
find: its windscreen zone stays the box's (``user.default_zones``).

Of the glass, only the outside skin is read: faces whose normal points away from the body's centre (a glass
panel's inner faces look in). Each connected pane is sorted by the area-weighted mean normal of its skin (its edges
face every way): leaning forward by at least ``LEAN`` (its x component, and more than sideways) it is the
windscreen (a car's, raked 25-30 deg above the horizontal, leans about 0.45), back the rear window, sideways (y,
more than along x) a side window, up a glass roof. The windscreen and rear window replace the box-derived
``windshield_front`` and
``windshield_rear`` zones (their glass's box grown by ``ZONE_MARGIN`` m, the normal the glass's mean, within
``ZONE_CONE_DEG``): a camera there sits behind the glass (:mod:`rigopt.mounting.features`). Side windows wind down
and glass roofs cannot be drilled: each connected pane becomes a keep-out box (grown by ``KEEP_OUT_MARGIN`` m).

ISO vehicle frame, metres.
"""

from __future__ import annotations

import numpy as np
import trimesh

from rigopt.vehicle.supports import box_around, connected_pieces

LEAN = 0.3
ZONE_MARGIN, ZONE_CONE_DEG = 0.05, 50.0
KEEP_OUT_MARGIN = 0.03
SIDE_REASON, ROOF_REASON = "side window glass: it winds down", "glass roof: no housing is bonded to it"


def _outer_faces(triangles: np.ndarray, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The triangles (k, 3, 3) of the glass's outside skin (normals pointing away from ``centre`` (3,) m), their
    unit normals (k, 3) and areas (k,)."""
    normals, valid = trimesh.triangles.normals(triangles)  # unit normals of the faces with an area
    triangles = triangles[valid]
    outward = np.einsum("ij,ij->i", normals, triangles.mean(axis=1) - centre) > 0
    return triangles[outward], normals[outward], trimesh.triangles.area(triangles[outward])


def glass_features(triangles: np.ndarray, centre) -> tuple[list[dict], list[dict]]:
    """From the glass triangles (k, 3, 3), vehicle frame, of a body centred on ``centre`` (3,) m: the
    ``windshield_front`` and ``windshield_rear`` zones over the windscreen and rear window (those there are) and
    the keep-outs over the side and roof panes. Each pane (a connected piece of glass) is one kind, by the mean
    normal of its outside skin (a pane's edges face every way)."""
    if not len(triangles):
        return [], []
    triangles, normals, areas = _outer_faces(np.asarray(triangles, dtype=float), np.asarray(centre, dtype=float))
    kinds: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {"front": [], "rear": [], "side": [], "roof": []}
    for pane in connected_pieces(triangles):
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
            normal = np.sum([n for _, n in kinds[kind]], axis=0)
            zones.append({"name": name, **box_around(np.concatenate([c for c, _ in kinds[kind]]), ZONE_MARGIN),
                          "normal": np.round(normal / np.linalg.norm(normal), 3).tolist(), "cone_deg": ZONE_CONE_DEG,
                          "mirrored": False})
    keep_outs = [{"name": f"{label} {k + 1}", "reason": reason, **box_around(corners, KEEP_OUT_MARGIN)}
                 for label, reason, kind in (("side window", SIDE_REASON, "side"), ("glass roof", ROOF_REASON, "roof"))
                 for k, (corners, _) in enumerate(sorted(kinds[kind], key=lambda pane: (-pane[0][:, 0].max(),
                                                                                        -pane[0][:, 1].max())))]
    return zones, keep_outs

