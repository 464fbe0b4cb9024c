"""rigopt.metrics.rigv: Rig Variance, checked against its definition and the slow reference."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from oracles.metrics import rigv_reference
from rigopt.errors import RigoptError
from rigopt.metrics.rigv import DMAX_EPSILON, rigv
from rigopt.rig.library import library_rig, rig_names
from rigopt.rig.model import Camera, Rig

S = np.diag([1.0, -1.0, 1.0])
HALF_TURN_Z = np.diag([-1.0, -1.0, 1.0])
ROTATION_ATOL = 1e-7  # arccos of a trace resolves angles near 0 only to ~sqrt(machine epsilon)
REFERENCE_KEYS = ("rigv", "tv", "rv", "fv", "dmax")

rigs = st.from_type(Rig)
lambda_values = st.tuples(*[st.floats(0.0, 10.0)] * 3)


def _rig(cameras, name="rig"):
    return Rig(name, "vehicle.test", tuple(Camera.pinhole(f"C{k}", p, r, f) for k, (p, r, f) in enumerate(cameras)))


def _reflected(rig):
    return Rig(rig.name, rig.vehicle, tuple(
        Camera.pinhole(c.id, S @ c.position, S @ c.rotation @ S, c.fov, c.image_size, c.zone) for c in rig.cameras))


def _assert_matches_reference(result, expected, scale=1.0):
    for key in REFERENCE_KEYS:
        atol = ROTATION_ATOL * scale if key in ("rigv", "rv") else 1e-12
        assert getattr(result, key) == pytest.approx(expected[key], rel=1e-9, abs=atol), key


@given(camera=st.from_type(Camera), lambdas=lambda_values)
def test_one_camera_gives_zero(camera, lambdas):
    result = rigv(_rig([(camera.position, camera.rotation, camera.fov)], "one"), lambdas)
    assert result.rig == "one"
    assert (result.rigv, result.tv, result.rv, result.fv, result.dmax) == (0.0, 0.0, 0.0, 0.0, 0.0)
    assert (result.tv_norm, result.rv_norm, result.fv_norm) == (0.0, 0.0, 0.0)


def test_hand_case_two_cameras_facing_opposite_ways():
    rig = _rig([([1.0, 0.0, 1.0], np.eye(3), 60.0), ([-1.0, 0.0, 1.0], HALF_TURN_Z, 120.0)], "pair")
    result = rigv(rig)
    assert result.tv == pytest.approx(2.0, rel=1e-12)
    assert result.dmax == pytest.approx(2.0, rel=1e-12)
    assert result.tv_norm == pytest.approx(2.0 / (2.0 + 1e-9), rel=1e-12)
    assert result.tv_norm == pytest.approx(1.0, abs=1e-9)
    assert result.rv == pytest.approx(math.pi, abs=ROTATION_ATOL)
    assert result.rv_norm == pytest.approx(1.0, abs=ROTATION_ATOL)
    assert result.fv == pytest.approx(60.0, rel=1e-12)
    assert result.fv_norm == pytest.approx(1.0 / 3.0, rel=1e-12)
    assert result.rigv == pytest.approx(1.0 + 1.0 + 1.0 / 3.0, abs=ROTATION_ATOL)
    assert result.lambdas == (1.0, 1.0, 1.0)


def test_hand_case_three_cameras_on_a_line():
    same = (np.eye(3), 90.0)
    rig = _rig([([0.0, 0.0, 0.0], *same), ([1.0, 0.0, 0.0], *same), ([3.0, 0.0, 0.0], *same)])
    result = rigv(rig)
    assert result.tv == pytest.approx((1.0 + 3.0 + 2.0) / 3.0, rel=1e-12)
    assert result.dmax == pytest.approx(3.0, rel=1e-12)
    assert result.tv_norm == pytest.approx(2.0 / (3.0 + DMAX_EPSILON), rel=1e-12)
    assert result.rv == pytest.approx(0.0, abs=ROTATION_ATOL) and result.fv == 0.0


def test_cameras_at_one_point_have_zero_translation_variance():
    rig = _rig([([1.0, 1.0, 1.0], np.eye(3), 60.0), ([1.0, 1.0, 1.0], HALF_TURN_Z, 90.0)])
    result = rigv(rig)
    assert result.tv == 0.0 and result.dmax == 0.0 and result.tv_norm == 0.0
    assert result.rigv == pytest.approx(1.0 + 30.0 / 180.0, abs=ROTATION_ATOL)


@given(rig=rigs, lambdas=lambda_values)
def test_lambdas_scale_the_normalised_parts(rig, lambdas):
    plain, weighted = rigv(rig), rigv(rig, lambdas)
    assert (weighted.tv_norm, weighted.rv_norm, weighted.fv_norm) == (plain.tv_norm, plain.rv_norm, plain.fv_norm)
    expected = lambdas[0] * plain.tv_norm + lambdas[1] * plain.rv_norm + lambdas[2] * plain.fv_norm
    assert weighted.rigv == pytest.approx(expected, rel=1e-12, abs=1e-12)
    assert weighted.lambdas == lambdas


@given(rig=rigs)
def test_components_are_the_pairwise_means(rig):
    result = rigv(rig)
    pairs = [(a, b) for k, a in enumerate(rig.cameras) for b in rig.cameras[k + 1:]]
    if not pairs:
        return
    distances = [np.linalg.norm(a.position - b.position) for a, b in pairs]
    assert result.tv == pytest.approx(np.mean(distances), rel=1e-9, abs=1e-12)
    assert result.dmax == pytest.approx(max(distances), rel=1e-12, abs=1e-12)
    assert result.fv == pytest.approx(np.mean([abs(a.fov - b.fov) for a, b in pairs]), rel=1e-9, abs=1e-12)
    assert result.tv <= result.dmax + 1e-12


@given(rig=rigs)
def test_normalised_parts_are_in_unit_interval(rig):
    result = rigv(rig)
    for value in (result.tv_norm, result.rv_norm, result.fv_norm):
        assert 0.0 <= value <= 1.0
    assert 0.0 <= result.rigv <= 3.0


@pytest.mark.parametrize("name", rig_names())
def test_library_rig_equals_reference(name):
    rig = library_rig(name)
    _assert_matches_reference(rigv(rig), rigv_reference(rig))


@pytest.mark.parametrize("name", ["R1", "R5", "R8"])
def test_library_rig_with_lambdas_equals_reference(name):
    rig, lambdas = library_rig(name), (0.3, 2.5, 7.0)
    _assert_matches_reference(rigv(rig, lambdas), rigv_reference(rig, lambdas), scale=3.0)


@given(rig=rigs, lambdas=lambda_values)
def test_random_rig_equals_reference(rig, lambdas):
    _assert_matches_reference(rigv(rig, lambdas), rigv_reference(rig, lambdas), scale=1.0 + sum(lambdas))


@given(rig=rigs, data=st.data())
def test_invariant_to_camera_order(rig, data):
    order = data.draw(st.permutations(range(len(rig))), label="order")
    shuffled = Rig(rig.name, rig.vehicle, tuple(rig.cameras[k] for k in order))
    before, after = rigv(rig), rigv(shuffled)
    for key in ("rigv", "tv", "rv", "fv", "dmax", "tv_norm", "rv_norm", "fv_norm"):
        atol = ROTATION_ATOL if key in ("rigv", "rv", "rv_norm") else 1e-12  # trace sums may round differently
        assert getattr(after, key) == pytest.approx(getattr(before, key), rel=1e-9, abs=atol), key


@given(rig=rigs, lambdas=lambda_values)
def test_invariant_to_a_frame_reflection(rig, lambdas):
    plain, mirrored = rigv(rig, lambdas), rigv(_reflected(rig), lambdas)
    for key in ("rigv", "tv", "rv", "fv", "dmax", "tv_norm", "rv_norm", "fv_norm"):
        assert getattr(mirrored, key) == pytest.approx(getattr(plain, key), rel=1e-12, abs=1e-12), key


@pytest.mark.parametrize("lambdas", [(1.0, -1.0, 1.0), (float("nan"), 1.0, 1.0), (1.0, 1.0, float("inf")),
                                     (1.0, 1.0)], ids=["negative", "NaN", "inf", "two values"])
def test_bad_lambdas_raise_rigopt_error(lambdas):
    with pytest.raises(RigoptError):
        rigv(library_rig("R1"), lambdas)
