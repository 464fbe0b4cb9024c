"""Mount candidates on the box car: the directions a mount point can face with its near view clear."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.camera import Lens
from rigopt.mounting.candidates import clear_directions, mount_candidates
from rigopt.mounting.records import MountRules


def test_front_point_can_look_forward_not_backward(box_car):
    clear = clear_directions(box_car, [[2.03, 0.0, 1.0]], np.deg2rad([0.0, 180.0]), np.array([0.0]), Lens.pinhole(65.0))
    assert clear.shape == (1, 1, 2)
    assert clear[0, 0].tolist() == [True, False]


def test_side_point_can_look_outward_not_across_the_body(box_car):
    clear = clear_directions(box_car, [[0.0, 0.93, 1.0]], np.deg2rad([90.0, -90.0]), np.array([0.0]), Lens.pinhole(65.0))
    assert clear[0, 0].tolist() == [True, False]


def test_clear_directions_use_the_frustum_margin(box_car):
    # on the left side looking 40 deg outward with a 120 deg lens: the outer half of the view grazes the body
    args = (box_car, [[0.0, 0.93, 1.0]], np.deg2rad([40.0]), np.array([0.0]), Lens.pinhole(120.0))
    assert clear_directions(*args)[0, 0, 0]
    assert not clear_directions(*args, rules=MountRules(frustum_margin=0.0))[0, 0, 0]


@pytest.fixture(scope="module")
def front_candidates(box_car):
    return mount_candidates(box_car, 0.3, lens=Lens.pinhole(65.0), zones=["front"], yaws_deg=range(-180, 180, 10),
                            pitches_deg=(-10, 0, 10))


def test_candidate_shapes(front_candidates):
    c = front_candidates
    n = len(c.points)
    assert n > 0
    assert c.normals.shape == (n, 3) and c.zones.shape == (n,)
    assert c.yaws.shape == (36,) and c.pitches.shape == (3,)
    assert c.clear.shape == (n, 3, 36) and c.clear.dtype == bool


def test_candidate_angles_are_radians(front_candidates):
    np.testing.assert_allclose(front_candidates.yaws[[0, 18]], [-np.pi, 0.0], atol=1e-12)
    np.testing.assert_allclose(front_candidates.pitches, np.deg2rad([-10, 0, 10]), atol=1e-12)
    assert front_candidates.fov == 65.0


def test_front_clear_yaws_form_one_band_around_zero(front_candidates):
    c = front_candidates
    zero = int(np.argmin(np.abs(c.yaws)))
    level = int(np.argmin(np.abs(c.pitches)))
    for clear in c.clear[:, level]:
        indices = np.flatnonzero(clear)
        assert clear[zero], "a front-face point must see straight ahead"
        assert indices.max() - indices.min() + 1 == len(indices), f"clear yaws not contiguous: {clear.astype(int)}"
        assert not clear[0], "a front-face point cannot look backward"


def test_front_clear_band_is_symmetric_on_the_centre_line(box_car):
    c = mount_candidates(box_car, 0.3, lens=Lens.pinhole(65.0), zones=["front"], yaws_deg=range(-180, 180, 10), pitches_deg=(0,))
    central = np.flatnonzero(np.abs(c.points[:, 1]) < 0.5)
    assert len(central) > 0
    yaws = np.rad2deg(c.yaws)
    for k in central:
        clear = yaws[c.clear[k, 0]]
        assert clear.min() == pytest.approx(-clear.max(), abs=1e-9)
