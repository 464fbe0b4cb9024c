"""Rig Contrastive Distance (RigCD): batched over many rig pairs, one implementation used everywhere.

Definition (docs/metrics.md): pair camera i of rig A with camera j of rig B at the raw-unit cost
``C_ij = lt ||t_i - t_j|| + lr dR(R_i, R_j) + lf |f_i - f_j|`` (m + rad + deg), take the minimum-cost
matching of ``M = min(N_A, N_B)`` pairs, and over the matched pairs

    t = mean ||t_i - t_j|| (m),  r = mean dR (rad),  f = mean |f_i - f_j| (deg)
    match = lt t + lr r + lf f,  count = |N_A - N_B| / max(N_A, N_B)
    rigcd = alpha match + (1 - alpha) count

The cost of every candidate camera against every reference camera (:func:`camera_costs`) is the same
function the designer's MILP uses. Rotations are compared through unit quaternions
(:func:`rigopt.geometry.quaternion_angle`): the same geodesic angle as the definition's arccos of a trace,
but exact near 0 and pi, so RigCD(A, A) is exactly 0.

Speed (``benchmarks/rigcd_speed.py``): pairs are grouped by camera counts, and each group (in chunks of at
most CHUNK_CAMERA_PAIRS camera pairs) gets its distances and exact matchings from compiled loops over the pairs
(:mod:`rigopt.metrics.pair_kernels`): the same operations as :func:`column_costs`, so the same bits, and
scipy's ``linear_sum_assignment`` pairing, ties included. scipy's assignment called once per pair took about
as long as all the rest; a lockstep shortest-augmenting-path solver over all pairs at once in numpy
reproduced its pairings but took about 5x longer (docs/benchmarks.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from operator import attrgetter
from typing import Sequence

import numpy as np

from rigopt.errors import RigoptError
from rigopt.geometry import quaternion_angle, sum_of_squares
from rigopt.rig.model import FOV, POSITION, QUATERNION, Rig, camera_columns

DEFAULT_ALPHA = 0.9
DEFAULT_LAMBDAS = (1.0, 1.0, 1.0)


def camera_costs(positions_a, rotations_a, fovs_a, positions_b, rotations_b, fovs_b):
    """Component distances between every camera of set A and every camera of set B.

    positions_* : (..., Na|Nb, 3) float metres; rotations_* : (..., Na|Nb, 3, 3) float;
    fovs_* : (..., Na|Nb) float degrees. Leading axes broadcast.
    Returns (t, r, f), each (..., Na, Nb) float: metres, radians, degrees.
    """
    a = camera_columns(positions_a, rotations_a, fovs_a)[..., :, None]  # (8, ..., Na, 1)
    b = camera_columns(positions_b, rotations_b, fovs_b)[..., None, :]  # (8, ..., 1, Nb)
    return column_costs(a, b)


def column_costs(a, b):
    """(t m, r rad, f deg) between cameras given as broadcastable columns a, b : (8, ...) float
    (:func:`camera_columns`); each result has the broadcast shape without the first axis."""
    t = np.sqrt(sum_of_squares(a[POSITION] - b[POSITION]))
    r = quaternion_angle(a[QUATERNION], b[QUATERNION], axis=0)
    f = np.abs(a[FOV] - b[FOV])
    return t, r, f


def check_weights(alpha: float, lambdas: Sequence[float]) -> tuple[float, tuple[float, float, float]]:
    """Validate ``alpha`` in [0, 1] and three finite, non-negative lambdas; returns them as floats."""
    lambdas = tuple(float(v) for v in lambdas)
    if len(lambdas) != 3 or not all(np.isfinite(v) and v >= 0 for v in lambdas):
        raise RigoptError(f"lambdas must be three finite, non-negative numbers (t, r, f), got {lambdas}")
    alpha = float(alpha)
    if not (np.isfinite(alpha) and 0.0 <= alpha <= 1.0):
        raise RigoptError(f"alpha must be in [0, 1], got {alpha}")
    return alpha, lambdas


#: Added (times the largest lambda, at least 1) to every lambda when one is 0; see tie_broken_lambdas.
TIE_BREAK = 1e-9


def tie_broken_lambdas(lambdas: Sequence[float]) -> tuple[float, float, float]:
    """Matching lambdas with ties of a zero-weighted term broken by the unit-weight cost: unchanged when all
    three are positive, else each raised by TIE_BREAK x max(largest, 1), so that a rig against itself is
    always matched camera to itself whatever the weights."""
    values = np.asarray(check_weights(DEFAULT_ALPHA, lambdas)[1])
    if np.all(values > 0):
        return tuple(float(v) for v in values)
    return tuple(float(v) for v in values + TIE_BREAK * max(float(values.max()), 1.0))


@dataclass(frozen=True)
class RigCDMatrix:
    """RigCD and its components for every pair (a, b); each array is (len(rigs_a), len(rigs_b)) float.

    Attributes: ``rigcd``, ``match`` (weighted matching term), ``count`` (camera-count term),
    ``t`` (m), ``r`` (rad), ``f`` (deg) as unweighted means over the matched pairs, and the
    ``alpha`` and ``lambdas`` used.
    """

    rigcd: np.ndarray
    match: np.ndarray
    count: np.ndarray
    t: np.ndarray
    r: np.ndarray
    f: np.ndarray
    alpha: float
    lambdas: tuple[float, float, float]


@dataclass(frozen=True)
class RigCDBreakdown:
    """RigCD of one pair of rigs with its matching: ``pairs`` lists (camera id in A, camera id in B)."""

    a: str
    b: str
    rigcd: float
    match: float
    count: float
    t: float
    r: float
    f: float
    alpha: float
    lambdas: tuple[float, float, float]
    pairs: tuple[tuple[str, str], ...]


class RigBatch:
    """Many rigs as one array of cameras, the input of the batched metric core.

    cameras : (C, 8) float, the C cameras of all rigs, rig after rig, each row the camera's
    :func:`rigopt.rig.model.camera_columns` (position m, unit quaternion, FOV deg); counts : (n,) int cameras
    per rig, each >= 1; rig k owns rows ``offsets[k] : offsets[k] + counts[k]``.
    """

    def __init__(self, cameras, counts):
        self.counts = np.asarray(counts, dtype=int)
        if self.counts.ndim != 1 or len(self.counts) == 0 or np.any(self.counts < 1):
            raise RigoptError("a rig batch needs at least one rig and at least one camera per rig")
        self.offsets = np.cumsum(self.counts) - self.counts
        self.cameras = np.array(cameras, dtype=float, order="C")  # a read-only copy, as a batch of rigs holds
        if self.cameras.shape != (int(self.counts.sum()), 8):
            raise RigoptError(f"rig batch cameras must be ({int(self.counts.sum())}, 8), got {self.cameras.shape}")
        self.cameras.flags.writeable = False

    @classmethod
    def from_rigs(cls, rigs: Sequence[Rig]) -> "RigBatch":
        """The batch of ``rigs``, in order: their cached :attr:`Rig.column_bytes` joined in one copy."""
        if len(rigs) == 0:
            raise RigoptError("no rigs given; pass at least one rig")
        blocks = list(map(attrgetter("column_bytes"), rigs))
        batch = cls.__new__(cls)  # the blocks are the rigs' own checked columns: nothing to validate
        batch.cameras = np.frombuffer(b"".join(blocks), dtype=float).reshape(-1, 8)
        batch.counts = np.fromiter(map(len, blocks), dtype=int, count=len(blocks)) // _CAMERA_BYTES
        batch.offsets = np.cumsum(batch.counts) - batch.counts
        return batch

    def __len__(self) -> int:
        return len(self.counts)


_CAMERA_BYTES = 8 * np.dtype(float).itemsize  # one camera's row of a RigBatch


def _as_batch(rigs) -> RigBatch:
    return rigs if isinstance(rigs, RigBatch) else RigBatch.from_rigs(rigs)


def check_same_origin(*groups) -> None:
    """Refuse to compare rigs whose positions are measured from different reference points.

    groups : sequences of Rig (a prebuilt RigBatch carries no origins and is skipped). Convert first with
    :func:`rigopt.vehicle.placement.common_frame`, which knows the vehicles.
    """
    rigs = [group for group in groups if not isinstance(group, RigBatch)]
    # Rigs mostly share one origin object: compare values only when there are several objects.
    if len(set().union(*(map(id, map(attrgetter("origin"), group)) for group in rigs))) < 2:
        return
    origins = {rig.origin for group in rigs for rig in group}
    if len(origins) > 1:
        named = sorted(o.describe() for o in origins)
        raise RigoptError(f"the rigs measure camera positions from different origins ({', '.join(named)}); RigCD "
                          "would mix reference points: convert them to one frame first "
                          "(rigopt.vehicle.placement.common_frame, or --vehicle on the command line)")


#: Most camera pairs whose distances are computed in one step: a chunk's four (G, N_A, N_B) arrays stay in cache
#: (1 MiB) and memory stays bounded whatever the rigs' sizes.
CHUNK_CAMERA_PAIRS = 32768


def _chunk_bounds(start: int, end: int, camera_pairs: int):
    """(start, end) of consecutive runs covering start:end, near-equal in size, each of at most
    CHUNK_CAMERA_PAIRS // camera_pairs items (at least one)."""
    most = max(1, CHUNK_CAMERA_PAIRS // camera_pairs)
    pieces = -(-(end - start) // most)
    cuts = start + (np.arange(pieces + 1) * (end - start)) // pieces
    return zip(cuts[:-1].tolist(), cuts[1:].tolist())


def match_pairs(pack_a: RigBatch, index_a, pack_b: RigBatch, index_b, alpha: float, lambdas,
                keep_assignment: bool = False):
    """RigCD of the pairs (pack_a[index_a[p]], pack_b[index_b[p]]); index_* : (P,) int; alpha and lambdas
    as checked by :func:`check_weights` (the matching minimises the cost with these lambdas).

    Pairs are grouped by camera counts, and each group (in chunks of at most CHUNK_CAMERA_PAIRS camera pairs)
    gets its distances and matchings from the compiled loops of :mod:`rigopt.metrics.pair_kernels`. Returns (values,
    assignments): values a dict of (P,) float arrays keyed rigcd, match, count, t, r, f; assignments, with
    ``keep_assignment``, a list of (rows (M,), cols (M,)) int camera indices per pair, else None.
    """
    from rigopt.metrics.pair_kernels import assign_pairs, pair_distances  # numba, loaded when pairs are matched

    lt, lr, lf = lambdas
    index_a, index_b = np.asarray(index_a), np.asarray(index_b)
    n_pairs = len(index_a)
    out = {key: np.zeros(n_pairs) for key in ("t", "r", "f")}
    na_all, nb_all = pack_a.counts[index_a], pack_b.counts[index_b]
    assignments = [None] * n_pairs if keep_assignment else None
    key = na_all * (int(nb_all.max()) + 1) + nb_all  # one int per (N_A, N_B)
    order = np.argsort(key, kind="stable")
    starts = np.flatnonzero(np.r_[True, np.diff(key[order]) != 0])
    ends = np.r_[starts[1:], len(order)]
    # Groups of one (N_A, N_B), cut into chunks whose arrays stay in cache (and memory bounded).
    chunks = []  # (pairs, N_A, N_B)
    for start, end in zip(starts, ends):
        na, nb = int(na_all[order[start]]), int(nb_all[order[start]])
        chunks += [(order[s:e], na, nb) for s, e in _chunk_bounds(start, end, na * nb)]
    buffer = np.empty((4, max(len(group) * na * nb for group, na, nb in chunks)))  # each chunk's distances, in turn
    for group, na, nb in chunks:
        t, r, f = pair_distances(pack_a.cameras, pack_a.offsets[index_a[group]], na,
                                 pack_b.cameras, pack_b.offsets[index_b[group]], nb, buffer)  # each (G, Na, Nb)
        rows, cols = assign_pairs(t, r, f, lambdas)  # each (G, M)
        flat = (np.arange(len(group))[:, None] * na + rows) * nb + cols
        for key, values in (("t", t), ("r", r), ("f", f)):
            out[key][group] = values.ravel().take(flat).mean(axis=1)
        if keep_assignment:
            for g, p in enumerate(group):
                assignments[p] = (rows[g], cols[g])
    out["count"] = np.abs(na_all - nb_all) / np.maximum(na_all, nb_all)
    out["match"] = lt * out["t"] + lr * out["r"] + lf * out["f"]
    out["rigcd"] = alpha * out["match"] + (1.0 - alpha) * out["count"]
    return out, assignments


def rigcd_matrix(rigs_a: Sequence[Rig] | RigBatch, rigs_b: Sequence[Rig] | RigBatch, alpha: float = DEFAULT_ALPHA,
                 lambdas: Sequence[float] = DEFAULT_LAMBDAS) -> RigCDMatrix:
    """RigCD of every rig in ``rigs_a`` against every rig in ``rigs_b``; arrays (len(a), len(b)).

    Either side is a sequence of Rig or a prebuilt RigBatch.
    """
    alpha, lambdas = check_weights(alpha, lambdas)
    check_same_origin(rigs_a, rigs_b)
    pack_a, pack_b = _as_batch(rigs_a), _as_batch(rigs_b)
    ia, ib = np.meshgrid(np.arange(len(rigs_a)), np.arange(len(rigs_b)), indexing="ij")
    out, _ = match_pairs(pack_a, ia.ravel(), pack_b, ib.ravel(), alpha, lambdas)
    shape = (len(rigs_a), len(rigs_b))
    return RigCDMatrix(**{k: v.reshape(shape) for k, v in out.items()}, alpha=alpha, lambdas=lambdas)


def rigcd_pairs(rigs_a: Sequence[Rig] | RigBatch, rigs_b: Sequence[Rig] | RigBatch, alpha: float = DEFAULT_ALPHA,
                lambdas: Sequence[float] = DEFAULT_LAMBDAS) -> RigCDMatrix:
    """RigCD of the pairs ``(rigs_a[p], rigs_b[p])``; arrays (P,) instead of a matrix. Sides as rigcd_matrix."""
    if len(rigs_a) != len(rigs_b):
        raise RigoptError(f"rigcd_pairs needs two lists of equal length, got {len(rigs_a)} and {len(rigs_b)}")
    alpha, lambdas = check_weights(alpha, lambdas)
    check_same_origin(rigs_a, rigs_b)
    index = np.arange(len(rigs_a))
    out, _ = match_pairs(_as_batch(rigs_a), index, _as_batch(rigs_b), index, alpha, lambdas)
    return RigCDMatrix(**out, alpha=alpha, lambdas=lambdas)


def rigcd(rig_a: Rig, rig_b: Rig, alpha: float = DEFAULT_ALPHA,
          lambdas: Sequence[float] = DEFAULT_LAMBDAS) -> RigCDBreakdown:
    """RigCD of one pair with every component and the matched camera pairs."""
    alpha, lambdas = check_weights(alpha, lambdas)
    check_same_origin([rig_a], [rig_b])
    zero = np.zeros(1, dtype=int)
    out, assignments = match_pairs(RigBatch.from_rigs([rig_a]), zero, RigBatch.from_rigs([rig_b]), zero, alpha, lambdas,
                                   keep_assignment=True)
    rows, cols = assignments[0]
    pairs = tuple((rig_a.cameras[i].id, rig_b.cameras[j].id) for i, j in zip(rows, cols))
    values = {k: float(v[0]) for k, v in out.items()}
    return RigCDBreakdown(a=rig_a.name, b=rig_b.name, **values, alpha=alpha, lambdas=lambdas, pairs=pairs)
