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
    return [{"name": f"narrow_{k + 1}", "reason": KEEP_OUT_REASON,
             "min": np.round(group.min(axis=0) - margin, 4).tolist(),
             "max": np.round(group.max(axis=0) + margin, 4).tolist()}
            for k, group in enumerate(g for g in groups if len(g) >= MIN_GROUP)]
