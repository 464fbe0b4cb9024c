"""The designer's selection MILP (``select_cameras``) and its candidate pruning (``prune``).

Expected optima are derived by hand on 4-candidate instances (objective, chosen candidates, matching) and,
on random small instances, by enumerating every subset of candidates and its optimal matching
(scipy's ``linear_sum_assignment``). The objective of a selection of N cameras against R reference
cameras, M = min(N, R), is ``alpha / M * (sum of matched costs) + (1 - alpha) * |N - R| / max(N, R)``.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from rigopt.design.selection import (DesignInfeasible, Selection, count_term, essential_requirements, prune,
                                     select_cameras)
from rigopt.errors import RigoptError

ALPHA = 0.9

#: 4 candidates x 2 reference cameras. Candidate 0 is the cheapest for both references, so a greedy
#: choice (0 -> r0, then the best other for r1: 2 at cost 2) costs 1 + 2 = 3, but the optimal matching
#: is 1 -> r0 (1.1) and 0 -> r1 (1.2) = 2.3. Pairs by hand: {0,1} 2.3, {0,2} 3, {0,3} 5, {1,2} 3.1,
#: {1,3} 5.1, {2,3} 6.
COST = np.array([[1.0, 1.2],
                 [1.1, 5.0],
                 [5.0, 2.0],
                 [4.0, 4.0]])
DISTINCT_MOUNTS = np.arange(4)


def no_coverage(n: int):
    return np.zeros((n, 0), dtype=bool), np.zeros(0, dtype=int)


def solve(cost=COST, sees=None, required=None, mount=DISTINCT_MOUNTS, n_cameras=2, alpha=ALPHA, clash_pairs=()):
    if sees is None:
        sees, required = no_coverage(len(cost))
    return select_cameras(cost, sees, required, mount, n_cameras, alpha, clash_pairs)


def pairs_of(selection: Selection) -> set[tuple[int, int]]:
    """{(candidate, reference)} of the matched cameras."""
    return {(int(c), int(r)) for c, r in zip(selection.chosen, selection.matched) if r >= 0}


def objective_of(selection: Selection, cost: np.ndarray, alpha: float) -> float:
    """The objective recomputed from the returned solution (chosen cameras and their matching)."""
    n, n_ref = len(selection.chosen), cost.shape[1]
    matched = [(c, r) for c, r in zip(selection.chosen, selection.matched) if r >= 0]
    total = sum(cost[c, r] for c, r in matched)
    return alpha / min(n, n_ref) * total + (1 - alpha) * count_term(n, n_ref)


# --- count_term ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("n, r, expected", [(8, 8, 0.0), (6, 8, 0.25), (8, 6, 0.25), (1, 4, 0.75), (3, 2, 1 / 3)])
def test_count_term_is_the_relative_camera_count_difference(n, r, expected):
    assert count_term(n, r) == pytest.approx(expected, abs=1e-15)


# --- hand-derived optima ------------------------------------------------------------------------------


def test_equal_counts_objective_is_the_cheapest_perfect_matching():
    selection = solve()
    assert selection.objective == pytest.approx(ALPHA / 2 * 2.3 + (1 - ALPHA) * 0.0, abs=1e-7)


def test_equal_counts_chooses_the_optimal_matching_not_the_greedy_one():
    selection = solve()
    assert sorted(selection.chosen.tolist()) == [0, 1]
    assert pairs_of(selection) == {(1, 0), (0, 1)}


def test_solution_is_integral_and_consistent():
    selection = solve()
    chosen = selection.chosen
    assert chosen.dtype.kind == "i" and selection.matched.dtype.kind == "i"
    assert len(chosen) == 2 and len(set(chosen.tolist())) == 2  # x in {0, 1}, sum x = N
    assert set(selection.matched.tolist()) == {0, 1}  # each reference matched exactly once
    assert selection.objective == pytest.approx(objective_of(selection, COST, ALPHA), abs=1e-7)
    assert selection.status == "optimal"
    assert selection.n_candidates == 4


def test_alpha_zero_leaves_only_the_count_term():
    assert solve(alpha=0.0, n_cameras=3).objective == pytest.approx(1 / 3, abs=1e-7)


def test_more_cameras_than_reference_leaves_one_unmatched():
    selection = solve(n_cameras=3)
    assert len(selection.chosen) == 3
    assert sorted(selection.matched.tolist()) == [-1, 0, 1]
    assert {(1, 0), (0, 1)} <= pairs_of(selection)
    assert selection.objective == pytest.approx(ALPHA / 2 * 2.3 + (1 - ALPHA) * 1 / 3, abs=1e-7)


def test_fewer_cameras_than_reference_matches_each_chosen_camera_once():
    # 4 candidates x 3 references, N = 2, M = 2: by hand {0->r0, 2->r2} = 1.5 beats {1->r1, 2->r2} = 1.7
    # and {0->r0, 1->r1} = 2.2.
    cost = np.array([[1.0, 2.0, 8.0],
                     [2.0, 1.2, 8.0],
                     [3.0, 3.0, 0.5],
                     [9.0, 9.0, 9.0]])
    selection = solve(cost=cost, n_cameras=2)
    assert pairs_of(selection) == {(0, 0), (2, 2)}
    assert np.all(selection.matched >= 0)
    assert len(set(selection.matched.tolist())) == 2
    assert selection.objective == pytest.approx(ALPHA / 2 * 1.5 + (1 - ALPHA) * 1 / 3, abs=1e-7)


def test_coverage_forces_the_costlier_candidate():
    # One required sector that only candidate 3 sees: the best pair containing 3 is {0->r0, 3->r1} = 5.
    sees = np.zeros((4, 2), dtype=bool)
    sees[3, 0] = True
    sees[:, 1] = True  # a second sector everybody sees: it must not change anything
    required = np.array([1, 1])
    free = solve()
    forced = solve(sees=sees, required=required)
    assert 3 in forced.chosen.tolist()
    assert pairs_of(forced) == {(0, 0), (3, 1)}
    assert forced.objective - free.objective == pytest.approx(ALPHA / 2 * (5.0 - 2.3), abs=1e-7)


def test_unrequired_sector_does_not_constrain():
    sees = np.zeros((4, 1), dtype=bool)
    sees[3, 0] = True
    selection = solve(sees=sees, required=np.array([0]))
    assert sorted(selection.chosen.tolist()) == [0, 1]


def test_double_coverage_requirement_is_met():
    # A sector only 2 and 3 see, needed twice: both must be chosen; {2->r1, 3->r0} = 6 < {2->r0, 3->r1} = 9.
    sees = np.zeros((4, 1), dtype=bool)
    sees[[2, 3], 0] = True
    selection = solve(sees=sees, required=np.array([2]))
    assert pairs_of(selection) == {(2, 1), (3, 0)}
    assert selection.objective == pytest.approx(ALPHA / 2 * 6.0, abs=1e-7)


def test_two_candidates_on_one_mount_point_cannot_both_be_chosen():
    # 0 and 1 share mount point 7: the best allowed pair is {0->r0, 2->r1} = 3.
    selection = solve(mount=np.array([7, 7, 8, 9]))
    assert sorted(selection.chosen.tolist()) == [0, 2]
    assert selection.objective == pytest.approx(ALPHA / 2 * 3.0, abs=1e-7)


def test_clashing_mount_points_cannot_both_be_used():
    selection = solve(clash_pairs=np.array([[0, 1]]))
    assert sorted(selection.chosen.tolist()) == [0, 2]
    assert selection.objective == pytest.approx(ALPHA / 2 * 3.0, abs=1e-7)


def test_clash_between_unused_mount_points_changes_nothing():
    selection = solve(clash_pairs=np.array([[2, 3], [5, 6]]))  # 5, 6: mount points no candidate uses
    assert sorted(selection.chosen.tolist()) == [0, 1]
    assert selection.objective == pytest.approx(ALPHA / 2 * 2.3, abs=1e-7)


def test_fleet_minimises_the_worst_reference():
    # A second reference of one camera that candidates 0 and 1 match badly (3) and 2 and 3 perfectly (0).
    # By hand, max over the two references: {0,1}: max(0.45*2.3, 0.9*3 + 0.1/2) = 2.75; {0,2}: max(1.35,
    # 0.05) = 1.35; {1,2}: 1.395; {0,3}: 2.25; {1,3}: 2.295; {2,3}: 2.7.
    second = np.array([[3.0], [3.0], [0.0], [0.0]])
    sees, required = no_coverage(4)
    selection = select_cameras([COST, second], sees, required, DISTINCT_MOUNTS, 2, ALPHA)
    assert sorted(selection.chosen.tolist()) == [0, 2]
    assert selection.objective == pytest.approx(1.35, abs=1e-7)
    assert len(selection.matchings) == 2
    by_candidate = dict(zip(selection.chosen.tolist(), selection.matchings[1].tolist()))
    assert by_candidate == {0: -1, 2: 0}


# --- infeasible ---------------------------------------------------------------------------------------


def test_required_sector_seen_by_no_candidate_is_infeasible():
    sees = np.zeros((4, 2), dtype=bool)
    sees[:, 0] = True
    with pytest.raises(DesignInfeasible) as error:
        solve(sees=sees, required=np.array([1, 1]))
    message = str(error.value)
    assert "coverage" in message
    assert "--cameras" in message and "wider lenses" in message  # says what to change


def test_more_cameras_than_mount_points_is_infeasible():
    with pytest.raises(DesignInfeasible) as error:
        solve(mount=np.array([0, 0, 1, 1]), n_cameras=3)
    message = str(error.value)
    assert "only 2 mount points" in message and "3 cameras" in message
    assert "lower the camera count" in message


def test_clashes_leaving_too_few_usable_mount_points_is_infeasible():
    with pytest.raises(DesignInfeasible, match="housing"):
        solve(clash_pairs=np.array([[0, 1], [2, 3]]), n_cameras=3)


def test_zero_cameras_is_an_input_error():
    with pytest.raises(RigoptError, match="at least 1"):
        solve(n_cameras=0)


# --- brute force --------------------------------------------------------------------------------------


def random_instance(seed: int):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(6, 9))
    n_ref = int(rng.integers(2, 4))
    n_sectors = int(rng.integers(1, 5))
    cost = rng.uniform(0.0, 5.0, size=(n, n_ref))
    sees = rng.random((n, n_sectors)) < 0.45
    required = rng.choice([0, 1, 1, 2], size=n_sectors)
    mount = rng.integers(0, n - 1, size=n)  # n - 1 mount points: at least one is shared
    points = np.unique(mount)
    clash = rng.choice(points, size=2, replace=False).reshape(1, 2) if rng.random() < 0.5 else np.zeros((0, 2), int)
    n_cameras = int(rng.integers(2, 5))
    alpha = float(rng.uniform(0.3, 1.0))
    return cost, sees, required, mount, clash, n_cameras, alpha


def brute_force(cost, sees, required, mount, clash, n_cameras, alpha) -> float | None:
    """The minimum objective over every feasible subset and matching; None if none is feasible."""
    n, n_ref = cost.shape
    best = None
    for subset in itertools.combinations(range(n), n_cameras):
        subset = list(subset)
        used = mount[subset]
        if len(set(used.tolist())) < n_cameras:
            continue
        if any(a in used and b in used for a, b in clash):
            continue
        if np.any(sees[subset].sum(axis=0) < required):
            continue
        rows, cols = linear_sum_assignment(cost[subset])
        value = alpha / min(n_cameras, n_ref) * cost[subset][rows, cols].sum() + (1 - alpha) * count_term(n_cameras, n_ref)
        best = value if best is None else min(best, value)
    return best


@pytest.mark.parametrize("seed", range(40))
def test_milp_optimum_equals_brute_force_enumeration(seed):
    cost, sees, required, mount, clash, n_cameras, alpha = random_instance(seed)
    expected = brute_force(cost, sees, required, mount, clash, n_cameras, alpha)
    if expected is None:
        with pytest.raises(DesignInfeasible):
            select_cameras(cost, sees, required, mount, n_cameras, alpha, clash)
        return
    selection = select_cameras(cost, sees, required, mount, n_cameras, alpha, clash, mip_gap=1e-9)
    assert selection.objective == pytest.approx(expected, rel=1e-7, abs=1e-7)
    # the returned solution is feasible and its matching gives the reported objective
    chosen = selection.chosen
    assert len(chosen) == n_cameras == len(set(chosen.tolist()))
    assert np.all(sees[chosen].sum(axis=0) >= required)
    assert len(set(mount[chosen].tolist())) == n_cameras
    assert not any(a in mount[chosen] and b in mount[chosen] for a, b in clash)
    matched = selection.matched[selection.matched >= 0]
    assert len(matched) == min(n_cameras, cost.shape[1]) == len(set(matched.tolist()))
    assert objective_of(selection, cost, alpha) == pytest.approx(selection.objective, abs=1e-7)


def test_brute_force_instances_are_not_degenerate():
    """Guards the cross-check above: some instances are infeasible, and on some feasible ones the coverage
    and housing constraints change the optimum (so the MILP's constraints are really exercised)."""
    infeasible = binding = 0
    for seed in range(40):
        cost, sees, required, mount, clash, n_cameras, alpha = random_instance(seed)
        best = brute_force(cost, sees, required, mount, clash, n_cameras, alpha)
        if best is None:
            infeasible += 1
            continue
        free = brute_force(cost, sees[:, :0], required[:0], np.arange(len(cost)), clash[:0], n_cameras, alpha)
        binding += best > free + 1e-9
    assert 3 <= infeasible <= 30
    assert binding >= 3


# --- prune --------------------------------------------------------------------------------------------


PRUNE_COST = np.array([[5.0, 0.1],
                       [1.0, 9.0],
                       [2.0, 8.0],
                       [3.0, 0.2],
                       [9.0, 9.5],
                       [8.0, 7.0]])


def test_prune_keeps_each_references_k_cheapest():
    # r0's two cheapest: 1, 2; r1's: 0, 3.
    sees, required = no_coverage(6)
    assert prune(PRUNE_COST, sees, required, keep_per_reference=2, keep_per_sector=6).tolist() == [0, 1, 2, 3]


def test_prune_keeps_the_cheapest_seers_of_each_required_sector():
    # Sector 0 (required): seen by 4 (cheapest cost 9), 5 (7) and 2 (2): its two cheapest are 2 and 5.
    # Sector 1 (not required): seen by 4 only: 4 is not kept.
    sees = np.zeros((6, 2), dtype=bool)
    sees[[2, 4, 5], 0] = True
    sees[4, 1] = True
    kept = prune(PRUNE_COST, sees, np.array([1, 0]), keep_per_reference=1, keep_per_sector=2)
    assert kept.tolist() == [0, 1, 2, 5]


def test_prune_never_drops_the_only_seer_of_a_required_sector():
    sees = np.zeros((6, 1), dtype=bool)
    sees[4, 0] = True  # the most expensive candidate for both references
    kept = prune(PRUNE_COST, sees, np.array([1]), keep_per_reference=1, keep_per_sector=1)
    assert 4 in kept.tolist()


@pytest.mark.parametrize("seed", range(10))
def test_prune_keeps_a_seer_of_every_coverable_required_sector(seed):
    rng = np.random.default_rng(100 + seed)
    n, n_ref, q = 40, 3, 12
    cost = rng.uniform(0, 10, size=(n, n_ref))
    sees = rng.random((n, q)) < 0.1
    required = rng.integers(0, 3, size=q)
    kept = prune(cost, sees, required, keep_per_reference=2, keep_per_sector=2)
    assert np.all(np.diff(kept) > 0)  # sorted, no duplicates
    for s in np.flatnonzero(required > 0):
        seers = np.flatnonzero(sees[:, s])
        # as many seers as keep_per_sector allows (or all of them) survive
        assert np.isin(seers, kept).sum() >= min(2, len(seers))


def test_pruning_to_two_per_reference_keeps_the_optimum():
    # r0's two cheapest are 0 and 1, r1's are 0 and 2: the optimum {0, 1} survives and is found again.
    sees, required = no_coverage(4)
    kept = prune(COST, sees, required, keep_per_reference=2, keep_per_sector=0)
    assert kept.tolist() == [0, 1, 2]
    pruned = select_cameras(COST[kept], sees[kept], required, DISTINCT_MOUNTS[kept], 2, ALPHA)
    assert pruned.objective == pytest.approx(solve().objective, abs=1e-9)


# --- symmetric selection --------------------------------------------------------------------------------


def test_a_mirror_constraint_chooses_whole_pairs():
    # 4 candidates: 0 <-> 1 and 2 <-> 3 mirror images. Free, the cheapest two are 0 (r0) and 2 (r1): 1 + 1;
    # in pairs, {0, 1} costs 1 + 1.5 and {2, 3} costs 1 + 3 (best matchings), so {0, 1} wins.
    cost = np.array([[1.0, 4.0], [4.0, 1.5], [4.0, 1.0], [3.0, 5.0]])
    free = select_cameras(cost, *no_coverage(4), np.arange(4), 2, ALPHA)
    assert set(free.chosen.tolist()) == {0, 2}
    paired = select_cameras(cost, *no_coverage(4), np.arange(4), 2, ALPHA, mirror=np.array([1, 0, 3, 2]))
    assert set(paired.chosen.tolist()) == {0, 1}
    assert paired.objective == pytest.approx(ALPHA / 2 * 2.5)


def test_an_odd_count_in_pairs_needs_a_centreline_camera():
    cost = np.array([[1.0], [1.0], [2.0]])
    mirror = np.array([1, 0, 2])  # 2 is its own mirror: on the centreline
    assert select_cameras(cost, *no_coverage(3), np.arange(3), 1, ALPHA, mirror=mirror).chosen.tolist() == [2]
    with pytest.raises(DesignInfeasible, match="mirrored pairs"):
        select_cameras(cost[:2], *no_coverage(2), np.arange(2), 1, ALPHA, mirror=np.array([1, 0]))


def test_a_weighted_mounting_cost_trades_rigcd_for_cheaper_mounts():
    # one reference camera; candidate 0 matches it best (cost 1) but is expensive to mount (3), candidate 1
    # matches worse (1.5) on an ordinary panel (1). The objective adds w / N * m_c: w = 0.1 keeps 0 (0.9 + 0.3 <
    # 1.35 + 0.1), w = 1 moves to 1 (0.9 + 3 > 1.35 + 1); the reported objective stays the RigCD.
    cost, mount_cost = np.array([[1.0], [1.5]]), np.array([3.0, 1.0])
    light = select_cameras(cost, *no_coverage(2), np.arange(2), 1, ALPHA, mount_cost=mount_cost, cost_weight=0.1)
    heavy = select_cameras(cost, *no_coverage(2), np.arange(2), 1, ALPHA, mount_cost=mount_cost, cost_weight=1.0)
    assert light.chosen.tolist() == [0] and light.cost_term == pytest.approx(0.3)
    assert heavy.chosen.tolist() == [1] and heavy.cost_term == pytest.approx(1.0)
    assert heavy.objective == pytest.approx(ALPHA * 1.5)


# --- implied requirements and count ranges ------------------------------------------------------------


def test_implied_requirement_points_are_dropped_and_the_binding_ones_kept():
    sees = np.array([[1, 1, 0, 1, 1],
                     [0, 1, 1, 0, 1],
                     [0, 1, 0, 0, 1]], dtype=bool)
    # point 0 (seen by {0}) implies 1 ({0,1,2}) and 3 ({0}, equal: the first kept); 2 ({1}) is needed;
    # 4 equals 1 but needs 2 cameras: 1 implies nothing about it, and 4 implies 1
    required = np.array([1, 1, 1, 1, 2])
    assert essential_requirements(sees, required).tolist() == [0, 2, 4]
    assert essential_requirements(sees, np.array([0, 1, 1, 0, 0])).tolist() == [2]


@pytest.mark.parametrize("seed", range(6))
def test_implied_points_do_not_change_the_optimum(seed):
    rng = np.random.default_rng(seed)
    cost = rng.uniform(0.5, 3.0, (9, 3))
    sees = rng.random((9, 12)) < 0.35
    sees[np.arange(9), rng.integers(0, 12, 9)] = True
    required = (sees.sum(axis=0) > 0).astype(int)
    full = select_cameras(cost, sees, required, np.arange(9), 4, ALPHA)
    # the same MILP with every requirement written out: brute force over subsets gives the same optimum
    best = min(objective_by_enumeration(cost, c) for c in itertools.combinations(range(9), 4)
               if np.all(sees[list(c)].sum(axis=0) >= required))
    assert full.objective == pytest.approx(best, abs=1e-9)


def objective_by_enumeration(cost, chosen) -> float:
    rows, cols = linear_sum_assignment(cost[list(chosen)])
    return ALPHA / min(len(chosen), cost.shape[1]) * cost[list(chosen)][rows, cols].sum() + (1 - ALPHA) * count_term(
        len(chosen), cost.shape[1])


@pytest.mark.parametrize("seed", range(4))
def test_a_count_range_solved_at_once_equals_the_best_single_count(seed):
    rng = np.random.default_rng(100 + seed)
    cost = rng.uniform(0.2, 2.0, (10, 3))
    sees = rng.random((10, 8)) < 0.3
    required = (sees.sum(axis=0) > 0).astype(int)
    at_once = select_cameras(cost, sees, required, np.arange(10), (3, 6), ALPHA)
    singles = [select_cameras(cost, sees, required, np.arange(10), n, ALPHA) for n in range(3, 7)]
    assert at_once.objective == pytest.approx(min(s.objective for s in singles), abs=1e-9)
    assert 3 <= len(at_once.chosen) <= 6
    with pytest.raises(RigoptError, match="at or above"):
        select_cameras(cost, sees, required, np.arange(10), (2, 4), ALPHA)
