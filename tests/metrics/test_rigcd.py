"""rigopt.metrics.rigcd: Rig Contrastive Distance, checked against its definition and the slow reference.

Tolerances: the geodesic angle is an arccos of a trace, which near the identity only resolves angles to
about sqrt(machine epsilon) ~ 1e-8 rad (a one-ulp change in the trace, e.g. from another summation order
or array layout, moves it by ~2e-8), so anything containing the rotation term (r, match, rigcd) is
compared to 1e-7 and the rest (t, f, count) to 1e-9; rigopt's own geodesic distance is exact near 0,
so RigCD(A, A) is exactly 0.
Where two matchings tie, the per-component means (t, r, f) depend on which one the solver returns, so
the components are compared only where the optimal matching is unique.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.optimize import linear_sum_assignment

from oracles.metrics import rigcd_reference, rotation_distance_reference
from rigopt.errors import RigoptError
from rigopt.metrics.rigcd import camera_costs, rigcd, rigcd_matrix, rigcd_pairs
from rigopt.rig.library import library_rig, rig_names
from rigopt.rig.model import Camera, Rig

COMPONENTS = ("rigcd", "match", "count", "t", "r", "f")
TOTALS = ("rigcd", "match", "count")  # well defined even when matchings tie
PARTS = ("t", "r", "f")
S = np.diag([1.0, -1.0, 1.0])
ROTATION_ATOL = 1e-7

rigs = st.from_type(Rig)
alphas = st.floats(0.0, 1.0)
lambda_values = st.tuples(*[st.floats(0.0, 10.0)] * 3)


def _rig(cameras, name="rig"):
    """A rig of (position, rotation, fov) triples with ids C0, C1, ..."""
    return Rig(name, "vehicle.test", tuple(Camera.pinhole(f"C{k}", p, r, f) for k, (p, r, f) in enumerate(cameras)))


def _small_rigs(max_cameras=5):
    return st.lists(st.from_type(Camera), min_size=1, max_size=max_cameras).map(
        lambda cams: _rig([(c.position, c.rotation, c.fov) for c in cams], name="small")
    )


def _reflected(rig):
    """The same rig described in a mirrored frame (y flipped), as CARLA vs ISO 8855."""
    return Rig(rig.name, rig.vehicle, tuple(
        Camera.pinhole(c.id, S @ c.position, S @ c.rotation @ S, c.fov, c.image_size, c.zone) for c in rig.cameras))


def _permuted(rig, order):
    return Rig(rig.name, rig.vehicle, tuple(rig.cameras[k] for k in order))


def _hand_costs(a, b, lambdas):
    """Weighted cost matrix straight from the definition (independent of camera_costs)."""
    lt, lr, lf = lambdas
    return np.array([[lt * np.linalg.norm(ca.position - cb.position)
                      + lr * rotation_distance_reference(ca.rotation.tolist(), cb.rotation.tolist())
                      + lf * abs(ca.fov - cb.fov) for cb in b.cameras] for ca in a.cameras])


def _unique_optimum(a, b, lambdas=(1.0, 1.0, 1.0), margin=1e-6):
    """True when every other matching costs at least ``margin`` more than the optimal one.

    Any other matching of the same size leaves out at least one optimal pair, so forbidding each optimal
    pair in turn and re-solving finds the second best.
    """
    cost = _hand_costs(a, b, lambdas)
    rows, cols = linear_sum_assignment(cost)
    best = cost[rows, cols].sum()
    big = 10.0 * (np.abs(cost).sum() + 1.0)
    for i, j in zip(rows, cols):
        forbidden = cost.copy()
        forbidden[i, j] = big
        r2, c2 = linear_sum_assignment(forbidden)
        if forbidden[r2, c2].sum() <= best + margin:
            return False
    return True


def _atol(key, scale=1.0):
    """Absolute tolerance of a component: 1e-9 without the rotation term, ROTATION_ATOL (scaled) with it."""
    return 1e-9 if key in ("count", "t", "f") else ROTATION_ATOL * scale


def _assert_close(x, y, key, scale=1.0):
    assert x == pytest.approx(y, rel=1e-9, abs=_atol(key, scale)), key


#: A rotation rigopt accepts (orthonormal to 1e-9, within is_rotation's 1e-6) whose trace(R^T R) is
#: 3 - 2e-9: the arccos formula gives it a distance of ~4.5e-5 rad from itself on any platform.
NEARLY_ORTHONORMAL = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0 - 1e-9]])


# --- definition-level properties ------------------------------------------------------------------------


@given(a=rigs)
def test_rigcd_of_a_rig_with_itself_is_zero(a):
    result = rigcd(a, a)
    assert result.count == 0.0
    assert result.t == pytest.approx(0.0, abs=1e-9)
    assert result.f == pytest.approx(0.0, abs=1e-9)
    assert result.rigcd == pytest.approx(0.0, abs=1e-6)


@given(a=rigs)
@example(a=_rig([([0.0, 0.0, 0.0], NEARLY_ORTHONORMAL, 60.0)], "nearly"))
def test_rigcd_of_a_rig_with_itself_is_exactly_zero(a):
    assert rigcd(a, a).rigcd == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("name", ["R1", "R1-c10", "R6", "R9"])
def test_rigcd_of_a_library_rig_with_itself_is_zero(name):
    rig = library_rig(name)
    result = rigcd(rig, rig)
    assert result.rigcd == pytest.approx(0.0, abs=1e-6)
    assert sorted(result.pairs) == sorted((c.id, c.id) for c in rig.cameras)


@given(a=rigs, b=rigs)
def test_rigcd_is_symmetric(a, b):
    ab, ba = rigcd(a, b), rigcd(b, a)
    keys = COMPONENTS if _unique_optimum(a, b) else TOTALS
    for key in keys:
        assert getattr(ab, key) == pytest.approx(getattr(ba, key), rel=1e-9, abs=_atol(key)), key


@given(a=rigs, b=rigs, data=st.data())
def test_rigcd_is_invariant_to_camera_order(a, b, data):
    order_a = data.draw(st.permutations(range(len(a))), label="order_a")
    order_b = data.draw(st.permutations(range(len(b))), label="order_b")
    before, after = rigcd(a, b), rigcd(_permuted(a, order_a), _permuted(b, order_b))
    keys = COMPONENTS if _unique_optimum(a, b) else TOTALS
    for key in keys:
        assert getattr(after, key) == pytest.approx(getattr(before, key), rel=1e-9, abs=_atol(key)), key
    if _unique_optimum(a, b):
        assert sorted(after.pairs) == sorted(before.pairs)


@given(a=rigs, b=rigs, alpha=alphas, lambdas=lambda_values)
def test_rigcd_is_invariant_to_a_frame_reflection(a, b, alpha, lambdas):
    plain = rigcd(a, b, alpha, lambdas)
    mirrored = rigcd(_reflected(a), _reflected(b), alpha, lambdas)
    for key in COMPONENTS:
        assert getattr(mirrored, key) == pytest.approx(getattr(plain, key), rel=1e-12, abs=1e-12), key


@given(a=_small_rigs(), b=_small_rigs(), lambdas=lambda_values)
def test_match_is_the_minimum_over_all_matchings(a, b, lambdas):
    cost = _hand_costs(a, b, lambdas)
    if len(a) <= len(b):
        best = min(sum(cost[i, j] for i, j in enumerate(cols)) for cols in itertools.permutations(range(len(b)), len(a)))
    else:
        best = min(sum(cost[i, j] for j, i in enumerate(rows)) for rows in itertools.permutations(range(len(a)), len(b)))
    expected = best / min(len(a), len(b))
    assert rigcd(a, b, lambdas=lambdas).match == pytest.approx(expected, rel=1e-9, abs=ROTATION_ATOL * (1 + sum(lambdas)))


@given(a=rigs, b=rigs)
def test_count_term_is_count_difference_over_the_larger_count(a, b):
    expected = abs(len(a) - len(b)) / max(len(a), len(b))
    assert rigcd(a, b).count == expected


@given(a=rigs, b=rigs, alpha=alphas, lambdas=lambda_values)
def test_rigcd_combines_match_and_count_with_alpha(a, b, alpha, lambdas):
    result = rigcd(a, b, alpha, lambdas)
    assert result.alpha == alpha and result.lambdas == lambdas
    assert result.match == pytest.approx(lambdas[0] * result.t + lambdas[1] * result.r + lambdas[2] * result.f,
                                         rel=1e-12, abs=1e-12)
    assert result.rigcd == pytest.approx(alpha * result.match + (1 - alpha) * result.count, rel=1e-12, abs=1e-12)


@given(a=rigs, b=rigs)
def test_alpha_one_drops_the_count_and_alpha_zero_keeps_only_it(a, b):
    assert rigcd(a, b, alpha=1.0).rigcd == pytest.approx(rigcd(a, b, alpha=1.0).match, rel=1e-15, abs=0)
    assert rigcd(a, b, alpha=0.0).rigcd == abs(len(a) - len(b)) / max(len(a), len(b))


@given(a=rigs, b=rigs)
def test_breakdown_pairs_name_a_matching(a, b):
    result = rigcd(a, b)
    assert len(result.pairs) == min(len(a), len(b))
    ids_a, ids_b = [p[0] for p in result.pairs], [p[1] for p in result.pairs]
    assert len(set(ids_a)) == len(ids_a) and set(ids_a) <= {c.id for c in a.cameras}
    assert len(set(ids_b)) == len(ids_b) and set(ids_b) <= {c.id for c in b.cameras}
    # the components are the means over exactly these pairs
    cams_a, cams_b = {c.id: c for c in a.cameras}, {c.id: c for c in b.cameras}
    t = np.mean([np.linalg.norm(cams_a[i].position - cams_b[j].position) for i, j in result.pairs])
    f = np.mean([abs(cams_a[i].fov - cams_b[j].fov) for i, j in result.pairs])
    assert result.t == pytest.approx(t, rel=1e-12, abs=1e-12)
    assert result.f == pytest.approx(f, rel=1e-12, abs=1e-12)
    assert (result.a, result.b) == (a.name, b.name)


def test_breakdown_pairs_follow_the_cameras_not_the_order():
    same = (np.eye(3), 60.0)
    a = _rig([([0.0, 0.0, 0.0], *same), ([10.0, 0.0, 0.0], *same)], "A")
    b = _rig([([10.1, 0.0, 0.0], *same), ([0.2, 0.0, 0.0], *same)], "B")
    result = rigcd(a, b)
    assert sorted(result.pairs) == [("C0", "C1"), ("C1", "C0")]
    assert result.t == pytest.approx((0.2 + 0.1) / 2, rel=1e-12)


# --- hand-computed cases --------------------------------------------------------------------------------

QUARTER_TURN_Z = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def _hand_pair():
    a = _rig([([1.0, 2.0, 0.5], np.eye(3), 60.0)], "A")
    b = _rig([([1.0, 2.0 + 3.0, 0.5], QUARTER_TURN_Z, 90.0)], "B")  # 3 m apart, 90 deg about z, fov +30
    return a, b


def test_hand_case_one_camera_each():
    a, b = _hand_pair()
    result = rigcd(a, b)
    assert result.t == pytest.approx(3.0, rel=1e-12)
    assert result.r == pytest.approx(math.pi / 2, rel=1e-12)
    assert result.f == pytest.approx(30.0, rel=1e-12)
    assert result.count == 0.0
    assert result.match == pytest.approx(3.0 + math.pi / 2 + 30.0, rel=1e-12)
    assert result.rigcd == pytest.approx(0.9 * (3.0 + math.pi / 2 + 30.0), rel=1e-12)
    assert result.pairs == (("C0", "C0"),)


def test_hand_case_lambdas_weight_the_components():
    a, b = _hand_pair()
    result = rigcd(a, b, alpha=0.5, lambdas=(2.0, 0.5, 0.1))
    assert (result.t, result.f) == pytest.approx((3.0, 30.0), rel=1e-12)  # unweighted means
    assert result.match == pytest.approx(2.0 * 3.0 + 0.5 * math.pi / 2 + 0.1 * 30.0, rel=1e-12)
    assert result.rigcd == pytest.approx(0.5 * result.match, rel=1e-12)


def test_hand_case_zero_lambdas_give_zero_match():
    a, b = _hand_pair()
    result = rigcd(a, b, lambdas=(0.0, 0.0, 0.0))
    assert result.match == 0.0 and result.rigcd == 0.0


def test_hand_case_count_two_against_five():
    same = (np.eye(3), 60.0)
    a = _rig([([float(k), 0.0, 0.0], *same) for k in range(2)], "A")
    b = _rig([([float(k), 0.0, 0.0], *same) for k in range(5)], "B")
    result = rigcd(a, b)
    assert result.count == pytest.approx(3 / 5, rel=1e-15)
    assert result.match == pytest.approx(0.0, abs=1e-7)
    assert result.rigcd == pytest.approx(0.1 * 3 / 5, abs=1e-7)
    assert rigcd(a, b, alpha=1.0).rigcd == pytest.approx(0.0, abs=1e-7)


# --- single-camera rigs ---------------------------------------------------------------------------------


@given(camera=st.from_type(Camera), b=rigs, lambdas=lambda_values)
def test_single_camera_rig_matches_its_cheapest_camera(camera, b, lambdas):
    a = _rig([(camera.position, camera.rotation, camera.fov)], "one")
    result = rigcd(a, b, lambdas=lambdas)
    costs = _hand_costs(a, b, lambdas)[0]
    assert result.match == pytest.approx(costs.min(), rel=1e-9, abs=ROTATION_ATOL * (1 + sum(lambdas)))
    assert result.count == (len(b) - 1) / len(b)
    assert len(result.pairs) == 1 and result.pairs[0][0] == "C0"


# --- batched forms against the reference ----------------------------------------------------------------


@pytest.fixture(scope="module")
def library():
    return [library_rig(n) for n in rig_names()]


@pytest.fixture(scope="module")
def library_matrix(library):
    return rigcd_matrix(library, library)


def test_library_matrix_equals_reference_for_every_pair(library, library_matrix):
    assert library_matrix.rigcd.shape == (14, 14)
    for i, a in enumerate(library):
        for j, b in enumerate(library):
            expected = rigcd_reference(a, b)
            for key in COMPONENTS:
                _assert_close(getattr(library_matrix, key)[i, j], expected[key], key)


def test_library_matrix_is_symmetric(library_matrix):
    for key in COMPONENTS:
        np.testing.assert_allclose(getattr(library_matrix, key), getattr(library_matrix, key).T,
                                   rtol=1e-9, atol=1e-9, err_msg=key)


def test_library_matrix_diagonal_is_zero(library_matrix):
    np.testing.assert_allclose(np.diag(library_matrix.rigcd), 0.0, atol=1e-6)


def test_library_matrix_with_weights_equals_reference(library):
    alpha, lambdas = 0.7, (0.5, 2.0, 0.05)
    matrix = rigcd_matrix(library[:7], library[7:], alpha, lambdas)
    assert matrix.rigcd.shape == (7, 7) and matrix.alpha == alpha and matrix.lambdas == lambdas
    for i, a in enumerate(library[:7]):
        for j, b in enumerate(library[7:]):
            expected = rigcd_reference(a, b, alpha, lambdas)
            for key in COMPONENTS:
                _assert_close(getattr(matrix, key)[i, j], expected[key], key, scale=3.0)


@settings(max_examples=50)
@given(
    rigs_a=st.lists(rigs, min_size=1, max_size=3),
    rigs_b=st.lists(rigs, min_size=1, max_size=3),
    alpha=alphas,
    lambdas=lambda_values,
)
def test_random_matrix_equals_reference(rigs_a, rigs_b, alpha, lambdas):
    matrix = rigcd_matrix(rigs_a, rigs_b, alpha, lambdas)
    assert matrix.rigcd.shape == (len(rigs_a), len(rigs_b))
    scale = 1.0 + sum(lambdas)
    for i, a in enumerate(rigs_a):
        for j, b in enumerate(rigs_b):
            expected = rigcd_reference(a, b, alpha, lambdas)
            unique = _unique_optimum(a, b, lambdas, margin=1e-6 * scale)
            for key in COMPONENTS if unique else TOTALS:
                _assert_close(getattr(matrix, key)[i, j], expected[key], key, scale=scale)


@given(pairs=st.lists(st.tuples(rigs, rigs), min_size=1, max_size=5), alpha=alphas, lambdas=lambda_values)
def test_pairs_equal_the_matrix_diagonal(pairs, alpha, lambdas):
    rigs_a, rigs_b = [p[0] for p in pairs], [p[1] for p in pairs]
    diagonal = rigcd_pairs(rigs_a, rigs_b, alpha, lambdas)
    matrix = rigcd_matrix(rigs_a, rigs_b, alpha, lambdas)
    # the two group the pairs differently, so the trace sums may round differently (see module docstring)
    unique = all(_unique_optimum(a, b) for a, b in pairs)
    for key in COMPONENTS if unique else TOTALS:
        np.testing.assert_allclose(getattr(diagonal, key), np.diag(getattr(matrix, key)), rtol=1e-9,
                                   atol=_atol(key, 1.0 + sum(lambdas)), err_msg=key)


@given(a=rigs, b=rigs, alpha=alphas, lambdas=lambda_values)
def test_single_pair_equals_its_matrix_entry(a, b, alpha, lambdas):
    one, matrix = rigcd(a, b, alpha, lambdas), rigcd_matrix([a], [b], alpha, lambdas)
    for key in COMPONENTS:
        assert getattr(one, key) == pytest.approx(getattr(matrix, key)[0, 0], rel=1e-9, abs=_atol(key)), key


@given(a=rigs, b=rigs)
def test_camera_costs_are_the_definition(a, b):
    t, r, f = camera_costs(a.positions, a.rotations, a.fovs, b.positions, b.rotations, b.fovs)
    assert t.shape == r.shape == f.shape == (len(a), len(b))
    np.testing.assert_allclose(t + r + f, _hand_costs(a, b, (1.0, 1.0, 1.0)), rtol=1e-9, atol=ROTATION_ATOL)
    np.testing.assert_allclose(f, np.abs(a.fovs[:, None] - b.fovs[None, :]), rtol=0, atol=0)


# --- bad input ------------------------------------------------------------------------------------------

BAD_WEIGHTS = {
    "alpha 1.5": dict(alpha=1.5),
    "alpha -0.1": dict(alpha=-0.1),
    "alpha NaN": dict(alpha=float("nan")),
    "alpha inf": dict(alpha=float("inf")),
    "negative lambda": dict(lambdas=(1.0, -1.0, 1.0)),
    "NaN lambda": dict(lambdas=(float("nan"), 1.0, 1.0)),
    "inf lambda": dict(lambdas=(1.0, 1.0, float("inf"))),
    "two lambdas": dict(lambdas=(1.0, 1.0)),
    "four lambdas": dict(lambdas=(1.0, 1.0, 1.0, 1.0)),
}


@pytest.mark.parametrize("weights", list(BAD_WEIGHTS.values()), ids=list(BAD_WEIGHTS))
@pytest.mark.parametrize("function", ["rigcd", "rigcd_matrix", "rigcd_pairs"])
def test_bad_weights_raise_rigopt_error(function, weights):
    a, b = _hand_pair()
    with pytest.raises(RigoptError):
        if function == "rigcd":
            rigcd(a, b, **weights)
        elif function == "rigcd_matrix":
            rigcd_matrix([a], [b], **weights)
        else:
            rigcd_pairs([a], [b], **weights)


def test_empty_rig_lists_raise_rigopt_error():
    a, _ = _hand_pair()
    with pytest.raises(RigoptError):
        rigcd_matrix([], [a])
    with pytest.raises(RigoptError):
        rigcd_matrix([a], [])


def test_pairs_of_unequal_lengths_raise_rigopt_error():
    a, b = _hand_pair()
    with pytest.raises(RigoptError):
        rigcd_pairs([a, b], [a])
