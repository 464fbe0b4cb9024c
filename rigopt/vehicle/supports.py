"""Where a camera housing has no surface to stand on: rails, ladders, racks' bars, light bars.

A zone needs a surface flat and large enough for a housing (8 x 6 cm, ``rigopt.mounting.rules``). The mesh's
own surface (as the user gave it, before closing) is sampled about ``SPACING`` m apart; around each sample,
the samples within ``RADIUS`` m spread over a sheet (a panel, a roof, a wheel: wide in two directions) or
along a line (a bar, a rail, a rung: wide in one only). The second principal spread of that neighbourhood, as
the width of a uniform strip (sqrt(12) standard deviations), under ``NARROW_WIDTH`` makes the sample *narrow*:
an open strip narrower than 8 cm, a closed bar thinner than about 5.7 cm (a square bar's perimeter spreads
sqrt(2) times its side). Narrow samples are grouped (``GROUP_REACH`` m) and each group of at least
``MIN_GROUP`` becomes a keep-out box (``[[keep_out]]``, grown by ``margin`` m: the closing's thickening of thin
parts and one grid pitch, the lens's 3 cm and 3 cm more), so no lens is placed on it. Edges and corners of a
body spread over two faces and stay mountable.

A narrow part that is a mirror's arm (:func:`mirror_zone`: high on the front of the body, reaching out beyond the
body's side) holds a mirror head at its end: the body outboard of the side around it becomes a ``mirror`` zone,
where production surround view mounts its side cameras; the arm itself stays a keep-out.

:func:`box_around` and :func:`connected_pieces` are the box and the grouping every part found on a mesh uses
(treads, glass, lamps, mud flaps).

ISO vehicle frame, metres.
"""

from __future__ import annotations

import numpy as np
import trimesh

#: Samples about this far apart (m), at most MAX_SAMPLES; the neighbourhood of a sample (m).
SPACING, MAX_SAMPLES, RADIUS = 0.035, 250_000, 0.1
#: A neighbourhood narrower than this (m, sqrt(12) standard deviations across it) is no mount.
NARROW_WIDTH = 0.08
#: Narrow samples closer than this join one group (m); a group needs this many samples to be a keep-out.
GROUP_REACH, MIN_GROUP = 0.25, 5
KEEP_OUT_REASON = "no surface for a housing: rail, ladder or bar"


def narrow_points(points: np.ndarray) -> np.ndarray:
    """(n,) bool: surface samples ``points`` (n, 3) m whose neighbourhood (RADIUS) is a strip narrower than
    NARROW_WIDTH (module doc)."""
    from scipy import sparse
    from scipy.spatial import cKDTree

    pairs = cKDTree(points).query_pairs(RADIUS, output_type="ndarray")
    n = len(points)
    rows = np.concatenate([pairs[:, 0], pairs[:, 1], np.arange(n)])
    cols = np.concatenate([pairs[:, 1], pairs[:, 0], np.arange(n)])
    near = sparse.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    count = np.asarray(near.sum(axis=1)).ravel()
    centred = points - points.mean(axis=0)  # second moments about a common centre, for precision
    mean = near @ centred / count[:, None]
    products = np.stack([centred[:, i] * centred[:, j] for i in range(3) for j in range(3)], axis=1)
    second = (near @ products / count[:, None]).reshape(n, 3, 3)
    covariance = second - mean[:, :, None] * mean[:, None, :]
    spread = np.sqrt(np.maximum(np.linalg.eigvalsh(covariance), 0.0))  # ascending
    return (count >= 6) & (np.sqrt(12.0) * spread[:, 1] < NARROW_WIDTH)


def box_around(points, margin: float, digits: int = 3) -> dict:
    """{"min": [x, y, z], "max": [x, y, z]} of a found part's points (..., 3) m grown by ``margin`` m on every side,
    rounded to ``digits``: the box of a ``vehicle.toml`` entry."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    return {"min": np.round(points.min(axis=0) - margin, digits).tolist(),
            "max": np.round(points.max(axis=0) + margin, digits).tolist()}


def connected_pieces(triangles: np.ndarray) -> list[np.ndarray]:
    """The connected pieces of triangles (k, 3, 3) (sharing an edge once coincident corners are merged): each
    piece's indices into ``triangles``, in order."""
    mesh = trimesh.Trimesh(triangles.reshape(-1, 3), np.arange(3 * len(triangles)).reshape(-1, 3), process=False)
    mesh.merge_vertices()
    groups = trimesh.graph.connected_components(mesh.face_adjacency, nodes=np.arange(len(triangles)), min_len=1)
    return sorted((np.sort(np.asarray(group)) for group in groups), key=lambda group: group[0])


def narrow_keep_outs(mesh: trimesh.Trimesh, margin: float) -> list[dict]:
    """``[[keep_out]]`` tables (name, reason, min, max) over the narrow parts of ``mesh``'s surface (ISO, m),
    each box grown by ``margin`` m; largest first."""
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    count = int(min(MAX_SAMPLES, max(2000, mesh.area / SPACING**2)))
    points, _ = trimesh.sample.sample_surface(mesh, count, seed=3)
    narrow = points[narrow_points(points)]
    if len(narrow) < MIN_GROUP:
        return []
    tree = cKDTree(narrow)
    _, label = connected_components(tree.sparse_distance_matrix(tree, GROUP_REACH, output_type="coo_matrix"),
                                    directed=False)
    groups = sorted((narrow[label == k] for k in np.unique(label)), key=len, reverse=True)
    return [{"name": f"narrow_{k + 1}", "reason": KEEP_OUT_REASON, **box_around(group, margin, 4)}
            for k, group in enumerate(g for g in groups if len(g) >= MIN_GROUP)]


#: A narrow part is a mirror's arm when its lowest point is above this share of the body's height, it reaches
#: into the front MIRROR_FRONT_SHARE of the length and out beyond the body's side.
MIRROR_LOW_SHARE, MIRROR_FRONT_SHARE = 0.4, 0.3
#: How far (m) around a mirror arm's box, in x and z, the mirror zone reaches (the head hangs from its end).
MIRROR_HEAD_REACH = 0.5


def mirror_zone(keep_outs: list[dict], bounds: np.ndarray, half_width: float) -> dict | None:
    """A ``[[zones]]`` table named ``mirror`` over the mirror heads of ``keep_outs`` (narrow_keep_outs' tables)
    that are mirror arms (module doc) of a body of ``bounds`` (2, 3) m and ``half_width`` m without its mirrors:
    outboard of the side (|y| > half_width), MIRROR_HEAD_REACH m around the arms in x and z, both sides
    (mirrored), faces looking out, forward or back (normal +y within 90 deg); None when no arm is found."""
    (x0, _, z0), (x1, _, z1) = bounds
    arms = [(np.asarray(k["min"]), np.asarray(k["max"])) for k in keep_outs
            if k["min"][2] > z0 + MIRROR_LOW_SHARE * (z1 - z0) and k["max"][0] > x1 - MIRROR_FRONT_SHARE * (x1 - x0)
            and max(abs(k["min"][1]), abs(k["max"][1])) > half_width]
    if not arms:
        return None
    low, high = np.min([a[0] for a in arms], axis=0), np.max([a[1] for a in arms], axis=0)
    reach = max(abs(low[1]), abs(high[1]))
    return {"name": "mirror", "min": [round(float(low[0] - MIRROR_HEAD_REACH), 4), round(float(half_width), 4),
                                      round(float(low[2] - MIRROR_HEAD_REACH), 4)],
            "max": [round(float(high[0] + MIRROR_HEAD_REACH), 4), round(float(reach + MIRROR_HEAD_REACH), 4),
                    round(float(high[2] + MIRROR_HEAD_REACH), 4)],
            "normal": [0, 1, 0], "cone_deg": 90, "mirrored": True}
