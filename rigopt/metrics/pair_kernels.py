"""Compiled loops of the batched RigCD core: camera-pair distances and the exact assignment of many pairs.

Each pair of rigs is small (1-12 cameras a side), so the work is many tiny problems; numpy spends most of
its time on temporaries and scipy's ``linear_sum_assignment`` on one call per pair. These loops (numba,
compiled once and cached beside this file) do the same arithmetic in place:

- :func:`pair_distances` gives every camera of each rig of a group against every camera of its partner:
  the same IEEE operations, in the same order, as :func:`rigopt.metrics.rigcd.column_costs` and
  :func:`rigopt.geometry.quaternion_angle` (no fused multiply-adds, no reassociation), with the
  arctangent taken by numpy itself, so every value is column_costs' to the bit;
- :func:`assign_pairs` solves each pair's minimum-cost matching by the shortest augmenting path method
  (Crouse 2016, "On implementing 2D rectangular assignment algorithms") with the choices scipy's
  ``linear_sum_assignment`` makes: rows in order, among columns of equal reduced cost the first found that
  is unassigned, the search order of the remaining columns; a tall matrix solved as its transpose. The
  pairing therefore equals scipy's, ties included (tests/metrics/test_pair_kernels.py).
"""

from __future__ import annotations

import importlib.util
import math
import sys

import numpy as np

from rigopt.errors import RigoptError


def _import_njit():
    """numba's ``njit``. numba takes any importable ``coverage`` for coverage.py and fails on a plain folder of
    that name on the path (a namespace package: a coverage report folder in the working directory, the tests'
    tests/coverage), so such a folder is hidden from numba's import, and only from it."""
    loaded = sys.modules.get("coverage")
    spec = loaded.__spec__ if loaded is not None else importlib.util.find_spec("coverage")
    if spec is None or spec.origin is not None:  # no coverage, or coverage.py itself
        from numba import njit
        return njit
    sys.modules["coverage"] = None  # `import coverage` now raises ImportError: numba runs without coverage.py
    try:
        from numba import njit
    finally:
        if loaded is None:
            del sys.modules["coverage"]
        else:
            sys.modules["coverage"] = loaded
    return njit


njit = _import_njit()


@njit(cache=True, nogil=True)
def _distance_parts(cameras_a, starts_a, na, cameras_b, starts_b, nb, t, f, low, high):
    """Fill t (m), f (deg) and the two square roots of the quaternion angle, each (G, na, nb) float.

    cameras_* : (C, 8) float camera rows; starts_* : (G,) int, the first row of each rig of the group.
    low, high = sqrt(min(d2, s2)), sqrt(max(d2, s2)) with d2 = |qa - qb|^2, s2 = |qa + qb|^2, each sum of
    squares added in index order as rigopt.geometry.sum_of_squares adds them.
    """
    for p in range(len(starts_a)):
        for i in range(na):
            a = cameras_a[starts_a[p] + i]
            for j in range(nb):
                b = cameras_b[starts_b[p] + j]
                d = a[0] - b[0]
                square = d * d
                for k in range(1, 3):
                    d = a[k] - b[k]
                    square = square + d * d
                t[p, i, j] = math.sqrt(square)
                d = a[3] - b[3]
                s = a[3] + b[3]
                d2 = d * d
                s2 = s * s
                for k in range(4, 7):
                    d = a[k] - b[k]
                    s = a[k] + b[k]
                    d2 = d2 + d * d
                    s2 = s2 + s * s
                low[p, i, j] = math.sqrt(min(d2, s2))
                high[p, i, j] = math.sqrt(max(d2, s2))
                f[p, i, j] = abs(a[7] - b[7])


def pair_distances(cameras_a, starts_a, na: int, cameras_b, starts_b, nb: int, buffer=None):
    """Distances of every camera of rig A_p (rows ``starts_a[p]`` on, na cameras) to every camera of rig B_p.

    cameras_* : (C, 8) float camera rows (:class:`rigopt.metrics.rigcd.RigBatch`); starts_* : (G,) int;
    buffer : optional (4, K >= G na nb) float scratch that the results then view (reused across calls).
    Returns (t m, r rad, f deg), each (G, na, nb) float, equal to column_costs' values to the bit.
    """
    size = len(starts_a) * na * nb
    if buffer is None:
        buffer = np.empty((4, size))
    t, r, f, high = (part[:size].reshape(len(starts_a), na, nb) for part in buffer)
    _distance_parts(cameras_a, starts_a, na, cameras_b, starts_b, nb, t, f, r, high)
    np.multiply(np.arctan2(r, high, out=r), 4.0, out=r)  # numpy's arctangent: quaternion_angle's bits
    return t, r, f


@njit(cache=True, nogil=True)
def _augment(cost, row, u, v, shortest, path, row_of_col, col_of_row, seen_rows, seen_cols, remaining):
    """One shortest augmenting path from ``row`` on cost (R, C), R <= C; updates the duals u (R,), v (C,)
    and the matching (col_of_row (R,), row_of_col (C,), -1 when free). Returns False when no finite path."""
    n_cols = cost.shape[1]
    for k in range(n_cols):
        remaining[k] = n_cols - k - 1
        shortest[k] = np.inf
        seen_cols[k] = False
    for k in range(cost.shape[0]):
        seen_rows[k] = False
    n_remaining = n_cols
    reached = 0.0
    i = row
    sink = -1
    while sink == -1:
        nearest = -1
        lowest = np.inf
        seen_rows[i] = True
        for k in range(n_remaining):
            j = remaining[k]
            reduced = reached + cost[i, j] - u[i] - v[j]
            if reduced < shortest[j]:
                path[j] = i
                shortest[j] = reduced
            if shortest[j] < lowest or (shortest[j] == lowest and row_of_col[j] == -1):
                lowest = shortest[j]
                nearest = k
        reached = lowest
        if reached == np.inf:
            return False
        j = remaining[nearest]
        if row_of_col[j] == -1:
            sink = j
        else:
            i = row_of_col[j]
        seen_cols[j] = True
        n_remaining -= 1
        remaining[nearest] = remaining[n_remaining]
    u[row] += reached
    for k in range(cost.shape[0]):
        if seen_rows[k] and k != row:
            u[k] += reached - shortest[col_of_row[k]]
    for j in range(n_cols):
        if seen_cols[j]:
            v[j] -= reached - shortest[j]
    j = sink
    while True:
        i = path[j]
        row_of_col[j] = i
        j, col_of_row[i] = col_of_row[i], j
        if i == row:
            return True


@njit(cache=True, nogil=True)
def _assign(t, r, f, lt, lr, lf, rows, cols):
    """Matchings of minimum cost ``(lt t + lr r) + lf f`` for each pair p of t, r, f : (G, Na, Nb) float;
    writes rows, cols : (G, M) int (M = min(Na, Nb)) sorted by the A index. Returns the first pair without a
    finite matching, or -1."""
    n_pairs, na, nb = t.shape
    tall = na > nb
    n_rows, n_cols = (nb, na) if tall else (na, nb)
    cost = np.empty((n_rows, n_cols))
    u, v, shortest = np.empty(n_rows), np.empty(n_cols), np.empty(n_cols)
    path, row_of_col = np.empty(n_cols, np.int64), np.empty(n_cols, np.int64)
    col_of_row = np.empty(n_rows, np.int64)
    seen_rows, seen_cols = np.empty(n_rows, np.bool_), np.empty(n_cols, np.bool_)
    remaining = np.empty(n_cols, np.int64)
    for p in range(n_pairs):
        for i in range(na):
            for j in range(nb):
                value = (lt * t[p, i, j] + lr * r[p, i, j]) + lf * f[p, i, j]
                if tall:
                    cost[j, i] = value
                else:
                    cost[i, j] = value
        u[:] = 0.0
        v[:] = 0.0
        path[:] = -1
        row_of_col[:] = -1
        col_of_row[:] = -1
        for row in range(n_rows):
            if not _augment(cost, row, u, v, shortest, path, row_of_col, col_of_row, seen_rows, seen_cols,
                            remaining):
                return p
        if tall:  # B's cameras were the rows: list the matched A cameras in order
            m = 0
            for i in range(na):
                if row_of_col[i] != -1:
                    rows[p, m] = i
                    cols[p, m] = row_of_col[i]
                    m += 1
        else:
            for i in range(na):
                rows[p, i] = i
                cols[p, i] = col_of_row[i]
    return -1


def assign_pairs(t, r, f, lambdas):
    """Minimum-cost matching of each pair: scipy's ``linear_sum_assignment`` pairing of the weighted cost.

    t, r, f : (G, Na, Nb) float (m, rad, deg); lambdas (lt, lr, lf). The cost ``(lt t + lr r) + lf f`` is
    formed in that order. Returns (rows, cols), each (G, M) int with M = min(Na, Nb): camera indices in A
    and in B of the matched pairs, sorted by the A index.
    """
    n_pairs, na, nb = t.shape
    rows, cols = np.empty((n_pairs, min(na, nb)), dtype=np.int64), np.empty((n_pairs, min(na, nb)), dtype=np.int64)
    failed = _assign(t, r, f, *(float(v) for v in lambdas), rows, cols)
    if failed != -1:
        raise RigoptError(f"the camera costs of pair {failed} admit no finite matching; lambdas too large for "
                          "float64: use weights of order 1")
    return rows, cols
