"""The discrete stage: choose cameras among candidates and match them to the reference (cvxpy + HiGHS MILP).

For a camera count N and a reference of R cameras, with M = min(N, R):

    minimise   alpha / M * sum_e cost_e y_e  +  (1 - alpha) |N - R| / max(N, R)  +  w / R * sum_c m_c x_c
    subject to sum_c x_c = N
               N >= R: every reference camera matched once (sum_c y_cr = 1), sum_r y_cr <= x_c
               N <  R: every chosen camera matched once (sum_r y_cr = x_c), sum_c y_cr <= 1
               coverage: sum_c sees_cq x_c >= required_q for every sector point q
               housings: at most one camera per mount point and per pair of clashing mount points
               symmetry (optional): x_c = x_mirror(c), cameras in mirrored pairs or on the centreline
               x, y binary

``cost[c, r]`` is the raw-unit matching cost ``lt ||t_c - t_r|| + lr dR + lf |f_c - f_r|`` (the weighted
matching of RigCD), so the objective is exactly the calibrated RigCD of the chosen rig to the reference
when the matching is optimal, which the MILP guarantees on the candidate set. The last term, off by default
(w = 0), adds the relative mounting cost m_c of the chosen cameras per reference camera (their zones' costs and tyre spray,
:func:`rigopt.mounting.practice.mounting_costs`) weighted by w.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sparse

from rigopt.design.defaults import DEFAULT_MAX_NODES
from rigopt.errors import RigoptError
from rigopt.quiet import HIGHS_OPTIONS, quiet_highs


class DesignInfeasible(RigoptError):
    """The requirements cannot be met by any choice of candidates; the message says which and why."""


@dataclass(frozen=True)
class Selection:
    """The MILP's answer: ``chosen`` (k,) candidate indices, ``matched`` (k,) index into the (first)
    reference or -1, ``objective`` (calibrated RigCD; in fleet mode the largest over the references), solver
    ``status``, relative ``gap``, ``seconds``, ``n_candidates``, ``matchings``: one ``matched`` per
    reference, and ``cost_term``: the weighted mounting cost the MILP added to the objective (0 unweighted)."""

    chosen: np.ndarray
    matched: np.ndarray
    objective: float
    status: str
    gap: float
    seconds: float
    n_candidates: int
    matchings: tuple[np.ndarray, ...] = ()
    cost_term: float = 0.0


def count_term(n_cameras: int, n_reference: int) -> float:
    return abs(n_cameras - n_reference) / max(n_cameras, n_reference)


def prune(cost: np.ndarray, sees: np.ndarray, required: np.ndarray, keep_per_reference: int = 150,
          keep_per_sector: int = 6) -> np.ndarray:
    """Candidates worth offering the MILP: each reference camera's ``keep_per_reference`` cheapest, plus for
    every required sector point the ``keep_per_sector`` cheapest candidates that see it. Returns (k,) int."""
    keep = set()
    for r in range(cost.shape[1]):
        keep.update(np.argsort(cost[:, r], kind="stable")[:keep_per_reference].tolist())
    cheapest = cost.min(axis=1)
    for q in np.flatnonzero(required > 0):
        seeing = np.flatnonzero(sees[:, q])
        keep.update(seeing[np.argsort(cheapest[seeing], kind="stable")[:keep_per_sector]].tolist())
    return np.array(sorted(keep), dtype=int)


def essential_requirements(sees: np.ndarray, required: np.ndarray) -> np.ndarray:
    """(k,) int: the requirement points whose constraints the MILP needs. A point b is implied by a point a
    when every candidate that sees a also sees b and a needs at least as many cameras: meeting a meets b (of
    points seen by the same candidates, the one needing most, then the first, is kept). Dropping implied
    points leaves the feasible set as it is; a regulation field's hundreds of points shrink to those that
    bind.

    sees : (n, q) bool; required : (q,) int. Returns the indices of the points kept, sorted."""
    q = np.flatnonzero(required > 0)
    if len(q) < 2:
        return q
    # points seen by exactly the same candidates: the one needing most (the first of those) stands for all
    packed = np.packbits(sees[:, q], axis=0).T
    order = np.lexsort((q, -required[q]))  # most needed first, then by index
    _, first = np.unique(packed[order], axis=0, return_index=True)
    q = np.sort(q[order[first]])
    columns = sees[:, q].astype(np.float32)  # counts stay exact in float32 (below 2^24 candidates)
    size = columns.sum(axis=0)
    common = columns.T @ columns  # (k, k): candidates that see both points (one BLAS product)
    implies = (common == size[:, None]) & (required[q][:, None] >= required[q][None, :])  # [a, b]: a implies b
    np.fill_diagonal(implies, False)
    return q[~implies.any(axis=0)]


def _matching(cp, x, cost: np.ndarray, n_cameras: int, alpha: float, count_choice=None):
    """Matching variables of one reference and the calibrated RigCD they give; returns (y, constraints, rigcd).
    ``count_choice``: (z, counts) for a count range at or above the reference's count, z binary over counts."""
    n, n_ref = cost.shape
    y = cp.Variable(n * n_ref, boolean=True)  # y[c * n_ref + r]
    edges = np.arange(n * n_ref)
    per_candidate = sparse.csr_matrix((np.ones(n * n_ref), (np.repeat(np.arange(n), n_ref), edges)), shape=(n, n * n_ref))
    per_reference = sparse.csr_matrix((np.ones(n * n_ref), (np.tile(np.arange(n_ref), n), edges)),
                                      shape=(n_ref, n * n_ref))
    if n_cameras >= n_ref:
        constraints = [per_reference @ y == 1, per_candidate @ y <= x]
    else:
        constraints = [per_candidate @ y == x, per_reference @ y <= 1]
    if count_choice is not None:  # N >= R for every N of the range: the matching term is linear, the count term
        z, counts = count_choice    # one of the range's constants
        terms = np.array([count_term(k, n_ref) for k in counts])
        return y, constraints, alpha / n_ref * (cost.ravel() @ y) + (1.0 - alpha) * (terms @ z)
    rigcd = alpha / min(n_cameras, n_ref) * (cost.ravel() @ y) + (1.0 - alpha) * count_term(n_cameras, n_ref)
    return y, constraints, rigcd


def select_cameras(cost, sees: np.ndarray, required: np.ndarray, mount: np.ndarray, n_cameras: int | tuple[int, int],
                   alpha: float, clash_pairs=(), max_nodes: int = DEFAULT_MAX_NODES, mip_gap: float = 1e-4,
                   mirror: np.ndarray | None = None, mount_cost: np.ndarray | None = None,
                   cost_weight: float = 0.0) -> Selection:
    """Solve the selection MILP above.

    cost : (n, R) float raw-unit matching costs, or a list of them (one per reference rig: the fleet mode,
    which minimises the largest calibrated RigCD over the references); sees : (n, q) bool; required : (q,)
    int cameras needed per sector point; mount : (n,) int mount point of each candidate; n_cameras : a count,
    or a (low, high) range at or above every reference's camera count, solved at once (the count a variable
    of the MILP: with N >= R the objective stays linear); max_nodes : the branch-and-bound nodes HiGHS may
    explore, a work limit (one thread, a fixed seed), so the same input gives the same selection on any machine
    at any load (status ``node_limit`` when it stops there before proving ``mip_gap``); clash_pairs :
    (p, 2) int mount points whose housings collide; mirror : (n,) int each candidate's mirror image among
    the n (itself on the centreline), or None for no symmetry; mount_cost : (n,) float relative mounting cost
    of each candidate, weighted by ``cost_weight`` per reference camera in the objective (w / R sum m_c x_c,
    R the largest reference count). Raises DesignInfeasible when the MILP has no solution; ``objective`` is
    the calibrated RigCD (the mounting cost term left out).
    """
    import cvxpy as cp

    costs = [np.asarray(c, dtype=float) for c in (cost if isinstance(cost, (list, tuple)) else [cost])]
    low, high = count_range(n_cameras, max(c.shape[1] for c in costs), mount)
    model = _selection_model(costs, sees, required, mount, low, high, alpha, clash_pairs, mirror, mount_cost,
                             cost_weight)
    seconds = _solve(model.problem, max_nodes, mip_gap)
    if model.problem.status in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE):
        pairs = " in mirrored pairs" if mirror is not None else ""
        raise DesignInfeasible(f"no choice of {low if low == high else f'{low}-{high}'} candidate cameras{pairs} meets "
                               "the coverage and housing requirements; allow more cameras (--cameras), more zones, "
                               "wider lenses or lower the coverage requirement"
                               f"{' (or design without symmetry: --asymmetric)' if pairs else ''}")
    return _selection_of(model, costs, low, high, max_nodes, seconds)


def count_range(n_cameras: int | tuple[int, int], n_ref: int, mount: np.ndarray) -> tuple[int, int]:
    """(low, high) of a camera count or range, checked: at least 1; a range only at or above the largest
    reference's ``n_ref`` cameras; no more cameras than mount points."""
    low, high = (n_cameras, n_cameras) if np.isscalar(n_cameras) else (int(n_cameras[0]), int(n_cameras[1]))
    if low < 1 or high < low:
        raise RigoptError(f"the camera count must be at least 1 (a range low <= high), got {n_cameras}")
    if low < high and low < n_ref:
        raise RigoptError(f"a camera count range is solved at once only at or above the reference's {n_ref} "
                          f"cameras, got {low}-{high}; solve each count instead")
    if len(np.unique(mount)) < low:
        raise DesignInfeasible(f"only {len(np.unique(mount))} mount points are available for {low} cameras; "
                               "lower the camera count, allow more zones or a finer --spacing")
    return low, high


@dataclass(frozen=True)
class _SelectionModel:
    """The selection MILP as cvxpy holds it: ``x`` (n,) the chosen candidates, ``matchings`` one (y, constraints,
    calibrated RigCD expression) per reference, ``objective`` the RigCD (the largest over a fleet), ``penalty``
    the mounting cost term (0.0 without)."""

    problem: object
    x: object
    matchings: list
    objective: object
    penalty: object


def _selection_model(costs, sees, required, mount, low, high, alpha, clash_pairs, mirror, mount_cost,
                     cost_weight) -> _SelectionModel:
    """The MILP of :func:`select_cameras` (its docstring and the module's), built in one fixed order."""
    import cvxpy as cp

    n, n_ref = costs[0].shape[0], max(c.shape[1] for c in costs)
    x = cp.Variable(n, boolean=True)
    if low == high:
        constraints, choice = [cp.sum(x) == low], None
    else:
        z = cp.Variable(high - low + 1, boolean=True)
        counts = np.arange(low, high + 1)
        constraints, choice = [cp.sum(z) == 1, cp.sum(x) == counts @ z], (z, counts)
    matchings = [_matching(cp, x, c, high if choice else low, alpha, choice) for c in costs]
    for _, matching_constraints, _ in matchings:
        constraints += matching_constraints
    needed = essential_requirements(sees, required)
    if len(needed):
        constraints.append(sparse.csr_matrix(sees[:, needed].T.astype(float)) @ x >= required[needed])
    groups = _mount_groups(mount, clash_pairs)
    if groups.shape[0]:
        constraints.append(groups @ x <= 1)
    if mirror is not None:
        first = np.flatnonzero(np.arange(n) < mirror)
        if len(first):
            constraints.append(x[first] == x[mirror[first]])
    if len(matchings) == 1:
        objective = matchings[0][2]
    else:
        worst = cp.Variable()
        constraints += [worst >= rigcd for _, _, rigcd in matchings]
        objective = worst
    penalty = 0.0
    if cost_weight and mount_cost is not None:
        penalty = cost_weight / n_ref * (np.asarray(mount_cost, dtype=float) @ x)
    return _SelectionModel(cp.Problem(cp.Minimize(objective + penalty), constraints), x, matchings, objective, penalty)


def _solve(problem, max_nodes: int, mip_gap: float) -> float:
    """Solve with HiGHS under its work limit (one thread, fixed seed); the seconds it took."""
    import cvxpy as cp

    options = {**HIGHS_OPTIONS, "mip_rel_gap": float(mip_gap), "mip_max_nodes": int(max_nodes)}
    quiet_highs()
    start = time.perf_counter()
    try:
        with warnings.catch_warnings():  # a limited solve warns "may be inaccurate": its status says so
            warnings.simplefilter("ignore", UserWarning)
            problem.solve(solver=cp.HIGHS, **options)
    except cp.error.SolverError as error:
        raise RigoptError(f"the MIP solver failed ({error}); is highspy installed? pip install highspy") from None
    return time.perf_counter() - start


def _selection_of(model: _SelectionModel, costs, low: int, high: int, max_nodes: int, seconds: float) -> Selection:
    """The Selection a solved model holds; a node limit reached before any feasible selection is an error."""
    import cvxpy as cp

    problem, x = model.problem, model.x
    chosen = np.flatnonzero(x.value > 0.5) if x.value is not None else np.zeros(0, dtype=int)
    if not low <= len(chosen) <= high:  # stopped at the node limit before finding any feasible selection
        raise RigoptError(f"the MIP solver found no feasible design within {max_nodes} branch-and-bound nodes "
                          f"(status {problem.status}); raise --max-nodes")
    n = costs[0].shape[0]
    matched = []
    for (y, _, _), c in zip(model.matchings, costs):
        pairs = y.value.reshape(n, c.shape[1]) > 0.5
        matched.append(np.array([int(np.argmax(pairs[k])) if pairs[k].any() else -1 for k in chosen]))
    status = "optimal" if problem.status == cp.OPTIMAL else "node_limit" if _stopped(problem) else problem.status
    rigcd_value = (float(model.objective.value) if len(model.matchings) > 1
                   else float(model.matchings[0][2].value))
    cost_term = float(model.penalty.value) if hasattr(model.penalty, "value") else 0.0
    return Selection(chosen, matched[0], rigcd_value, status, _gap(problem), seconds, n, tuple(matched), cost_term)


def _stopped(problem) -> bool:
    """True when HiGHS stopped at its node limit before proving the gap (its only limit)."""
    import cvxpy as cp

    return problem.status == cp.USER_LIMIT


def _gap(problem) -> float:
    info = (problem.solver_stats.extra_stats if problem.solver_stats else None)
    gap = getattr(info, "mip_gap", None)
    return float(gap) if gap is not None and np.isfinite(gap) else 0.0


def _mount_groups(mount: np.ndarray, clash_pairs) -> sparse.csr_matrix:
    """Rows of candidates that may hold at most one camera: each mount point, and each clashing pair."""
    points = np.unique(mount)
    index = {p: k for k, p in enumerate(points)}
    rows, cols = [], []
    for c, p in enumerate(mount):
        rows.append(index[p])
        cols.append(c)
    row = len(points)
    members = {p: np.flatnonzero(mount == p) for p in points}
    for a, b in np.asarray(clash_pairs, dtype=int).reshape(-1, 2):
        if a in members and b in members:
            for c in np.concatenate([members[a], members[b]]):
                rows.append(row)
                cols.append(c)
            row += 1
    return sparse.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(row, len(mount)))
