"""A semi-trailer turned about its kingpin (rigopt.vehicle.articulation): slices of its box, and what it hides."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.errors import RigoptError
from rigopt.mounting.practice import in_keep_outs
from rigopt.vehicle.articulation import SLICE_M, articulated, turned_slices
from rigopt.vehicle.library import load_vehicle
from rigopt.vehicle.spec import KeepOutSpec

TRAILER = KeepOutSpec("trailer", np.array([-10.0, -1.25, 0.0]), np.array([1.0, 1.25, 4.0]), "a trailer",
                      optional=True, occludes=True, kingpin=np.array([0.0, 0.0, 1.2]))


def _inside(slices, point) -> bool:
    return any(np.all((point >= s.min) & (point <= s.max)) for s in slices)


@pytest.mark.parametrize("angle, rear", [(90.0, [0.0, -9.9, 1.0]), (-90.0, [0.0, 9.9, 1.0]),
                                         (30.0, [-9.9 * np.cos(np.pi / 6), -9.9 * np.sin(np.pi / 6), 1.0])])
def test_a_positive_angle_swings_the_trailers_rear_to_the_right(angle, rear):
    slices = turned_slices(TRAILER, angle)
    assert len(slices) == int(np.ceil(11.0 / SLICE_M)) and all(s.kingpin is None and s.name == "trailer" for s in slices)
    assert _inside(slices, np.array(rear)) and not _inside(slices, np.array([-9.9, 0.0, 1.0]))
    assert all(s.min[2] == 0.0 and s.max[2] == 4.0 and s.optional and s.occludes for s in slices)


def test_the_slices_cover_the_turned_box_and_overshoot_it_by_at_most_a_slice_times_the_sine():
    angle = np.deg2rad(30.0)
    slices = turned_slices(TRAILER, 30.0)
    rng = np.random.default_rng(0)
    local = np.column_stack([rng.uniform(-10, 1, 2000), rng.uniform(-1.25, 1.25, 2000)])  # in the trailer's frame
    turn = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    plan = local @ turn.T
    assert all(_inside(slices, np.array([x, y, 2.0])) for x, y in plan)
    # beyond the turned box's side by more than SLICE_M sin(30 deg) nothing is covered
    side = np.array([[x, 1.25 + SLICE_M * np.sin(angle) + 0.01] for x in np.linspace(-9.5, 0.5, 50)]) @ turn.T
    assert not any(_inside(slices, np.array([x, y, 2.0])) for x, y in side)


def test_the_hgv_turned_hides_other_ground_and_a_vehicle_without_a_trailer_is_itself():
    hgv, car = load_vehicle("hgv"), load_vehicle("etron")
    assert articulated(car, 30.0) is car and articulated(hgv, 0.0) is hgv
    turned = articulated(hgv, 30.0)
    assert turned.mesh is hgv.mesh and len(turned.spec.keep_outs) > len(hgv.spec.keep_outs)
    behind, beside = np.array([[-12.0, 0.0, 1.0]]), np.array([[-12.0, -5.0, 1.0]])  # behind the tractor, to its right
    assert in_keep_outs(hgv, behind)[0] and not in_keep_outs(hgv, beside)[0]
    assert not in_keep_outs(turned, behind)[0] and in_keep_outs(turned, beside)[0]
    for bad in (91.0, float("nan")):
        with pytest.raises(RigoptError, match="articulation angle"):
            articulated(hgv, bad)
