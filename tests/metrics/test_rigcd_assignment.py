"""rigopt.metrics.rigcd's batched core: the costs of a group, the per-pair assignment and its bookkeeping.

The batched core must answer every pair exactly as one pair at a time would: the same costs to the bit
(the compiled ``pair_distances`` against ``column_costs``), a matching of minimum cost (against brute force over every
injective assignment), scipy's pairing even where matchings tie (tie-heavy rigs: two positions, two
headings, two FOVs) and whichever rig has more cameras, and values that do not depend on how the pairs are
grouped or chunked.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

import rigopt.metrics.rigcd as rigcd_module
from rigopt.metrics.pair_kernels import pair_distances
from rigopt.metrics.rigcd import RigBatch, camera_costs, column_costs, match_pairs, rigcd, rigcd_pairs
from rigopt.rig.library import library_rig, rig_names
from rigopt.rig.model import Camera, Rig, camera_columns

COMPONENTS = ("rigcd", "match", "count", "t", "r", "f")
HALF_TURNS = [np.eye(3), np.diag([-1.0, -1.0, 1.0])]  # about z: 0 and pi


def _random_rotations(rng, n):
    q = rng.normal(size=(n, 4))
    w, x, y, z = (q / np.linalg.norm(q, axis=1, keepdims=True)).T
    return np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
                     np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
                     np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


def _random_rig(rng, n, name):
    """n cameras: positions within +-3 m, uniform rotations, FOVs 60-120 deg (ties have probability 0)."""
    rotations = _random_rotations(rng, n)
    return Rig(name, "v", tuple(Camera.pinhole(f"C{k}", rng.uniform(-3, 3, 3), rotations[k], float(rng.uniform(60, 120)))
                                for k in range(n)))


def _tie_rig(rng, n, name):
    """n cameras at x = 0 or 1 m, turned by 0 or pi about z, FOV 60 or 61 deg: most costs tie exactly (a
    matching that breaks ties unlike scipy differs from scipy's pairing on about 2 rigs in 5)."""
    return Rig(name, "v", tuple(Camera.pinhole(f"C{k}", [float(rng.integers(0, 2)), 0.0, 0.0],
                                       HALF_TURNS[int(rng.integers(0, 2))], float(rng.integers(60, 62)))
                                for k in range(n)))


def _cost_matrix(a, b, lambdas=(1.0, 1.0, 1.0)):
    """(Na, Nb) float: the weighted cost, computed as the core computes it (column_costs, lt t + lr r + lf f)."""
    t, r, f = camera_costs(a.positions, a.rotations, a.fovs, b.positions, b.rotations, b.fovs)
    return lambdas[0] * t + lambdas[1] * r + lambdas[2] * f


def _brute_force_minimum(cost):
    """Least total cost over every injective assignment of the smaller side (all permutations)."""
    if cost.shape[0] > cost.shape[1]:
        cost = cost.T
    rows = np.arange(cost.shape[0])
    return min(cost[rows, list(cols)].sum() for cols in itertools.permutations(range(cost.shape[1]), len(rows)))


def test_pair_distances_are_column_costs_to_the_bit():
    rng = np.random.default_rng(3)
    rigs_a = [_random_rig(rng, 4, f"a{k}") for k in range(7)]
    rigs_b = [_random_rig(rng, 6, f"b{k}") for k in range(7)] + [_tie_rig(rng, 6, f"t{k}") for k in range(7)]
    rigs_a += rigs_a  # against random rigs and against tie-heavy ones
    pack_a, pack_b = RigBatch.from_rigs(rigs_a), RigBatch.from_rigs(rigs_b)
    t, r, f = pair_distances(pack_a.cameras, pack_a.offsets, 4, pack_b.cameras, pack_b.offsets, 6)
    assert t.shape == r.shape == f.shape == (14, 4, 6)
    for p, (a, b) in enumerate(zip(rigs_a, rigs_b)):
        expected = camera_costs(a.positions, a.rotations, a.fovs, b.positions, b.rotations, b.fovs)
        for got, want in zip((t[p], r[p], f[p]), expected):
            np.testing.assert_array_equal(got, want)


def test_pair_distances_of_a_rig_against_itself_are_exactly_zero_on_the_diagonal():
    rng = np.random.default_rng(4)
    pack = RigBatch.from_rigs([_random_rig(rng, 5, f"a{k}") for k in range(3)])
    t, r, f = pair_distances(pack.cameras, pack.offsets, 5, pack.cameras, pack.offsets, 5)
    for part in (t, r, f):
        assert np.all(np.diagonal(part, axis1=1, axis2=2) == 0.0)
        assert np.all(part[:, ~np.eye(5, dtype=bool)] > 0.0)


@pytest.mark.parametrize("seed", range(4))
def test_match_is_the_brute_force_minimum_with_ties_and_unequal_counts(seed):
    rng = np.random.default_rng(seed)
    sizes = [(na, nb) for na in range(1, 6) for nb in range(1, 6)]
    rigs_a = [_tie_rig(rng, na, f"a{k}") for k, (na, _) in enumerate(sizes)]
    rigs_b = [_tie_rig(rng, nb, f"b{k}") for k, (_, nb) in enumerate(sizes)]
    result = rigcd_pairs(rigs_a, rigs_b)
    for k, (a, b) in enumerate(zip(rigs_a, rigs_b)):
        m = min(len(a), len(b))
        assert result.match[k] * m == pytest.approx(_brute_force_minimum(_cost_matrix(a, b)), rel=1e-12, abs=1e-12)


def test_a_wrong_matching_is_caught_by_the_brute_force_minimum():
    # The check above can fail: the identity pairing of these rigs costs more than the optimum.
    same = (np.eye(3), 60.0)
    a = Rig("A", "v", (Camera.pinhole("C0", [0.0, 0.0, 0.0], *same), Camera.pinhole("C1", [10.0, 0.0, 0.0], *same)))
    b = Rig("B", "v", (Camera.pinhole("C0", [10.0, 0.0, 0.0], *same), Camera.pinhole("C1", [0.0, 0.0, 0.0], *same)))
    cost = _cost_matrix(a, b)
    assert np.trace(cost) > _brute_force_minimum(cost) + 1.0
    assert rigcd(a, b).match * 2 == pytest.approx(_brute_force_minimum(cost), abs=1e-12)


@pytest.mark.parametrize("seed", range(3))
def test_pairing_is_scipys_even_where_matchings_tie(seed):
    rng = np.random.default_rng(10 + seed)
    for na, nb in [(1, 4), (4, 1), (3, 5), (5, 3), (4, 4), (5, 5), (2, 2)]:
        for _ in range(6):
            a, b = _tie_rig(rng, na, "A"), _tie_rig(rng, nb, "B")
            rows, cols = linear_sum_assignment(_cost_matrix(a, b))
            expected = tuple((a.cameras[i].id, b.cameras[j].id) for i, j in zip(rows, cols))
            assert rigcd(a, b).pairs == expected, (na, nb)


def test_pairing_of_the_library_rigs_is_scipys():
    rigs = [library_rig(name) for name in rig_names()]
    for a in rigs:
        for b in rigs:
            rows, cols = linear_sum_assignment(_cost_matrix(a, b))
            assert rigcd(a, b).pairs == tuple((a.cameras[i].id, b.cameras[j].id) for i, j in zip(rows, cols))


@pytest.mark.parametrize("chunk", [1, 40, 32768])  # camera pairs: one rig pair a chunk, a few, every pair
def test_batched_values_equal_one_pair_at_a_time_exactly(chunk, monkeypatch):
    monkeypatch.setattr(rigcd_module, "CHUNK_CAMERA_PAIRS", chunk)
    rng = np.random.default_rng(5)
    rigs_a = [_random_rig(rng, int(rng.integers(1, 7)), f"a{k}") for k in range(40)]
    rigs_b = [_random_rig(rng, int(rng.integers(1, 7)), f"b{k}") for k in range(40)]
    rigs_a += [_tie_rig(rng, int(rng.integers(1, 6)), f"ta{k}") for k in range(40)]
    rigs_b += [_tie_rig(rng, int(rng.integers(1, 6)), f"tb{k}") for k in range(40)]
    lambdas = (0.5, 2.0, 0.1)
    batched = rigcd_pairs(rigs_a, rigs_b, 0.8, lambdas)
    for k, (a, b) in enumerate(zip(rigs_a, rigs_b)):
        one = rigcd(a, b, 0.8, lambdas)
        for key in COMPONENTS:
            assert getattr(batched, key)[k] == getattr(one, key), (k, key)


def test_batch_of_arrays_equals_batch_of_rigs_exactly():
    rng = np.random.default_rng(6)
    rigs_a = [_random_rig(rng, int(rng.integers(1, 6)), f"a{k}") for k in range(30)]
    rigs_b = [_random_rig(rng, int(rng.integers(1, 6)), f"b{k}") for k in range(30)]
    arrays = [RigBatch(np.concatenate([camera_columns(r.positions, r.rotations, r.fovs).T for r in rigs]),
                       [len(r) for r in rigs]) for rigs in (rigs_a, rigs_b)]
    np.testing.assert_array_equal(RigBatch.from_rigs(rigs_a).cameras, arrays[0].cameras)
    for batch in (RigBatch.from_rigs(rigs_a), arrays[0]):  # read-only, whichever way it was built
        with pytest.raises(ValueError, match="read-only"):
            batch.cameras[0, 0] = 1.0
    index = rng.permutation(30)
    from_rigs, _ = match_pairs(RigBatch.from_rigs(rigs_a), index, RigBatch.from_rigs(rigs_b), index[::-1],
                               0.9, (1.0, 1.0, 1.0))
    from_arrays, _ = match_pairs(arrays[0], index, arrays[1], index[::-1], 0.9, (1.0, 1.0, 1.0))
    for key in COMPONENTS:
        np.testing.assert_array_equal(from_rigs[key], from_arrays[key], err_msg=key)


def test_assignments_name_a_injective_matching_in_the_order_of_a():
    rng = np.random.default_rng(7)
    rigs_a = [_random_rig(rng, na, f"a{na}") for na in (2, 5, 3)]
    rigs_b = [_random_rig(rng, nb, f"b{nb}") for nb in (5, 2, 3)]
    index = np.arange(3)
    _, assignments = match_pairs(RigBatch.from_rigs(rigs_a), index, RigBatch.from_rigs(rigs_b), index, 0.9,
                                 (1.0, 1.0, 1.0), keep_assignment=True)
    for (rows, cols), a, b in zip(assignments, rigs_a, rigs_b):
        assert len(rows) == len(cols) == min(len(a), len(b))
        assert list(rows) == sorted(set(rows)) and len(set(cols)) == len(cols)
        assert max(rows) < len(a) and max(cols) < len(b)
