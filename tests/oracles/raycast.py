"""A brute-force ray-triangle intersection (Moller-Trumbore against every triangle): the oracle of the ray
backends (rigopt.raycast) in tests and benchmarks, never used by the tool itself. Import as
``from oracles.raycast import first_hit_distance_bruteforce``."""

from __future__ import annotations

import numpy as np


def first_hit_distance_bruteforce(triangles, origins, directions, chunk: int = 256) -> np.ndarray:
    """(n,) float: distance along each unit ray to the nearest triangle it crosses, inf if none.

    triangles : (t, 3, 3) float vertices; origins, directions : (n, 3) float. Rays are processed ``chunk``
    at a time against all triangles at once.
    """
    triangles = np.asarray(triangles, dtype=float)
    v0, edge1, edge2 = triangles[:, 0], triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]
    origins, directions = np.atleast_2d(origins), np.atleast_2d(directions)
    out = np.full(len(origins), np.inf)
    for start in range(0, len(origins), chunk):
        o, d = origins[start:start + chunk, None, :], directions[start:start + chunk, None, :]  # (c, 1, 3)
        p = np.cross(d, edge2)  # (c, t, 3)
        det = np.einsum("ctk,tk->ct", p, edge1)
        usable = np.abs(det) > 1e-12
        inv = np.where(usable, 1.0 / np.where(usable, det, 1.0), 0.0)
        s = o - v0
        u = np.einsum("ctk,ctk->ct", s, p) * inv
        q = np.cross(s, edge1)
        v = np.einsum("ctk,ctk->ct", np.broadcast_to(d, q.shape), q) * inv
        t = np.einsum("ctk,tk->ct", q, edge2) * inv
        hit = usable & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-9)
        out[start:start + chunk] = np.where(hit, t, np.inf).min(axis=1)
    return out
