"""Narrow parts (no surface for a housing) told from sheets by the spread of their surface samples."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from rigopt.vehicle.supports import NARROW_WIDTH, narrow_keep_outs, narrow_points


def surface(mesh: trimesh.Trimesh, count: int = 20000) -> np.ndarray:
    return trimesh.sample.sample_surface(mesh, count, seed=0)[0]


@pytest.mark.parametrize("side, narrow", [(0.03, True), (0.05, True), (0.07, False), (0.3, False)])
def test_a_square_bar_is_narrow_below_about_5_7_cm(side, narrow):
    bar = trimesh.creation.box([2.0, side, side])
    points = surface(bar, 3000)
    middle = np.abs(points[:, 0]) < 0.8  # away from its ends
    assert narrow_points(points)[middle].mean() == pytest.approx(1.0 if narrow else 0.0, abs=0.05)


@pytest.mark.parametrize("width, narrow", [(0.05, True), (0.12, False)])
def test_an_open_strip_is_narrow_below_the_housing(width, narrow):
    strip = trimesh.Trimesh([[-1, -width / 2, 0], [1, -width / 2, 0], [1, width / 2, 0], [-1, width / 2, 0]],
                            [[0, 1, 2], [0, 2, 3]])
    points = surface(strip, 8000)
    middle = np.abs(points[:, 0]) < 0.8
    assert narrow_points(points)[middle].mean() == pytest.approx(1.0 if narrow else 0.0, abs=0.05)
    assert (width < NARROW_WIDTH) == narrow


def test_a_box_bodys_edges_and_corners_are_not_narrow():
    body = trimesh.creation.box([4.0, 1.8, 1.2])
    assert not narrow_points(surface(body, 40000)).any()


def test_a_rail_on_a_roof_is_one_keep_out_and_the_roof_none():
    roof = trimesh.creation.box([3.0, 1.8, 0.4])
    rail = trimesh.creation.box([2.0, 0.03, 0.03])
    rail.apply_translation([0.0, 0.5, 0.3])
    boxes = narrow_keep_outs(trimesh.util.concatenate([roof, rail]), margin=0.05)
    assert len(boxes) == 1
    np.testing.assert_allclose(boxes[0]["min"], [-1.05, 0.435, 0.235], atol=0.03)
    np.testing.assert_allclose(boxes[0]["max"], [1.05, 0.565, 0.365], atol=0.03)
    assert "no surface for a housing" in boxes[0]["reason"]
