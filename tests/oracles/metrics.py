"""Slow, obvious implementations of the metrics (rigopt.metrics), written straight from the definitions.

They are the oracles of the tests and the baselines of ``benchmarks/`` (which put this checkout's ``tests``
folder on sys.path); the tool itself never uses them. Import as ``from oracles.metrics import ...``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import linear_sum_assignment

from rigopt.rig.model import Rig


def rotation_distance_reference(ra, rb) -> float:
    """Geodesic angle in radians between two (3, 3) rotations, one trace at a time."""
    trace = sum(ra[k][i] * rb[k][i] for i in range(3) for k in range(3))  # trace(Ra^T Rb)
    return math.acos(min(1.0, max(-1.0, (trace - 1.0) / 2.0)))


def rigcd_reference(a: Rig, b: Rig, alpha: float = 0.9, lambdas=(1.0, 1.0, 1.0)) -> dict:
    """RigCD of one pair by plain Python loops over camera pairs and a Hungarian solve.

    Returns a dict with keys rigcd, match, count, t, r, f (floats).
    """
    lt, lr, lf = lambdas
    parts = [[None] * len(b) for _ in range(len(a))]
    cost = np.zeros((len(a), len(b)))
    for i, ca in enumerate(a.cameras):
        for j, cb in enumerate(b.cameras):
            dt = math.dist(ca.position.tolist(), cb.position.tolist())
            dr = rotation_distance_reference(ca.rotation.tolist(), cb.rotation.tolist())
            df = abs(ca.fov - cb.fov)
            parts[i][j] = (dt, dr, df)
            cost[i, j] = lt * dt + lr * dr + lf * df
    rows, cols = linear_sum_assignment(cost)
    matched = [parts[i][j] for i, j in zip(rows, cols)]
    t = sum(p[0] for p in matched) / len(matched)
    r = sum(p[1] for p in matched) / len(matched)
    f = sum(p[2] for p in matched) / len(matched)
    count = abs(len(a) - len(b)) / max(len(a), len(b))
    match = lt * t + lr * r + lf * f
    return {"rigcd": alpha * match + (1 - alpha) * count, "match": match, "count": count, "t": t, "r": r, "f": f}


def rigv_reference(rig: Rig, lambdas=(1.0, 1.0, 1.0)) -> dict:
    """RigV of one rig by a loop over camera pairs; dict with rigv, tv, rv, fv, dmax."""
    cams = rig.cameras
    pairs = [(cams[i], cams[j]) for i in range(len(cams)) for j in range(i + 1, len(cams))]
    if not pairs:
        return {"rigv": 0.0, "tv": 0.0, "rv": 0.0, "fv": 0.0, "dmax": 0.0}
    dists = [math.dist(a.position.tolist(), b.position.tolist()) for a, b in pairs]
    tv = sum(dists) / len(pairs)
    rv = sum(rotation_distance_reference(a.rotation.tolist(), b.rotation.tolist()) for a, b in pairs) / len(pairs)
    fv = sum(abs(a.fov - b.fov) for a, b in pairs) / len(pairs)
    dmax = max(dists)
    lt, lr, lf = lambdas
    value = (lt * min(1.0, max(0.0, tv / (dmax + 1e-9))) + lr * min(1.0, max(0.0, rv / math.pi))
             + lf * min(1.0, max(0.0, fv / 180.0)))
    return {"rigv": value, "tv": tv, "rv": rv, "fv": fv, "dmax": dmax}
