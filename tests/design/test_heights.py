"""The height search (``--height-search``, :mod:`rigopt.design.heights`): after the MILP each perception camera
moves to the valid mount nearest its reference camera's height, within a radius, keeping its direction and lens,
and only where the rig still passes the mount checks and meets its coverage requirements."""

from __future__ import annotations

import json

import numpy as np
import pytest

from box_car import BOX_ZONES, front_and_left_rig, spec_text
from in_process import run_rigopt

from rigopt.design.heights import HEIGHT_SEARCH_SPACING, HEIGHT_STEP_M, search_heights
from rigopt.design.settings import DesignSettings
from rigopt.errors import RigoptError
from rigopt.mounting.rules import check_rig
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec


@pytest.fixture(scope="module")
def box_car(tmp_path_factory) -> Vehicle:
    path = tmp_path_factory.mktemp("heightbox") / "vehicle.toml"
    path.write_text(spec_text("heightbox", zones=BOX_ZONES))
    return Vehicle.from_spec(read_spec(path))


@pytest.fixture(scope="module")
def low_rig(box_car) -> Rig:
    """The box car's two-camera rig with both lenses lowered to 0.6 m (the box's skin spans 0.3-1.5 m)."""
    rig = front_and_left_rig(box_car.blueprint)
    cameras = tuple(Camera(c.id, c.position * [1, 1, 0] + [0, 0, 0.6], c.rotation, c.lens, zone=z)
                    for c, z in zip(rig.cameras, ("front", "side")))
    return Rig(rig.name, rig.vehicle, cameras)


def reference_at(heights) -> Rig:
    """A reference rig of level cameras at ``heights`` (m), one per entry, on the centreline."""
    return Rig("ref", "x", tuple(Camera.pinhole(f"R{k}", np.array([0.0, 0.0, h]), np.eye(3), 90.0)
                                 for k, h in enumerate(heights)))


def always(_rig) -> bool:
    return True


def test_each_camera_moves_to_its_reference_cameras_height_within_the_radius(box_car, low_rig):
    assert check_rig(low_rig, box_car).valid
    reference = reference_at([1.0, 0.9])
    moved, moves = search_heights(low_rig, np.array([0, 1]), reference, box_car, 0.75, DesignSettings(), always)
    heights = moved.positions[:, 2]
    # within half the fine grid of the target, never farther than the radius, same direction and lens
    assert np.abs(heights - [1.0, 0.9]).max() <= HEIGHT_SEARCH_SPACING / 2 + HEIGHT_STEP_M
    assert np.all(np.linalg.norm(moved.positions - low_rig.positions, axis=1) <= 0.75)
    assert np.array_equal(moved.rotations, low_rig.rotations) and moved.fovs.tolist() == low_rig.fovs.tolist()
    assert check_rig(moved, box_car).valid
    assert [(m.reference, m.from_m) for m in moves] == [("R0", 0.6), ("R1", 0.6)]
    assert [m.to_m for m in moves] == pytest.approx(heights.tolist())
    assert [m.camera for m in moves] == [c.id for c in moved.cameras]
    assert [c.id for c in moved.cameras] == ["CAM_FRONT_TO_FRONT", "CAM_SIDE_LEFT_TO_LEFT"]
    again = search_heights(low_rig, np.array([0, 1]), reference, box_car, 0.75, DesignSettings(), always)
    assert np.array_equal(again[0].positions, moved.positions)  # same input, same answer


def test_a_target_out_of_reach_takes_the_nearest_height_the_radius_allows(box_car, low_rig):
    moved, moves = search_heights(low_rig, np.array([0, 0]), reference_at([1.4]), box_car, 0.3, DesignSettings(),
                                  always)
    assert len(moves) == 2
    assert np.all(np.linalg.norm(moved.positions - low_rig.positions, axis=1) <= 0.3)
    assert np.all(moved.positions[:, 2] > 0.8)  # 0.3 m up, give or take the grid


def test_nothing_moves_where_the_requirements_or_the_radius_forbid_it(box_car, low_rig):
    reference = reference_at([1.0, 0.9])
    for radius, keeps in ((0.75, lambda rig: False), (0.0, always)):
        same, moves = search_heights(low_rig, np.array([0, 1]), reference, box_car, radius, DesignSettings(), keeps)
        assert moves == () and same is low_rig
    # a camera already at its reference camera's height stays
    level, moves = search_heights(low_rig, np.array([0, 1]), reference_at([0.6, 0.605]), box_car, 0.75,
                                  DesignSettings(), always)
    assert moves == () and level is low_rig


def test_the_requirement_check_sees_every_trial_and_a_refused_point_is_skipped(box_car, low_rig):
    seen = []

    def refuse_first(rig):
        seen.append(rig.positions[0].copy())
        return len(seen) > 1

    moved, moves = search_heights(low_rig, np.array([0]), reference_at([1.0]), box_car, 0.75, DesignSettings(),
                                  refuse_first)
    assert len(seen) == 2 and not np.array_equal(seen[0], seen[1])
    assert np.array_equal(moved.positions[0], seen[1]) and len(moves) == 1


def test_the_setting_is_checked():
    with pytest.raises(RigoptError, match="height search"):
        DesignSettings(height_search_m=-0.1)
    with pytest.raises(RigoptError, match="height search"):
        DesignSettings(height_search_m=float("nan"))


@pytest.mark.slow
def test_the_default_design_moves_its_cameras_to_the_reference_heights_and_height_search_0_keeps_the_grid(tmp_path):
    common = ("design", "--vehicle", "firetruck", "--ref", "R1")
    searched = run_rigopt(*common, "--out", tmp_path / "s")  # printed summary; the figures from report.json
    assert searched.returncode == 0, searched.stderr
    summary = json.loads((tmp_path / "s" / "report.json").read_text())
    assert summary["pose_tolerance"]["height_search_m"] == 0.75
    moved_line = f"height search: {len(summary['pose_tolerance']['height_moves'])} perception camera(s) moved"
    assert moved_line in searched.stderr
    assert "weighted by criticality" in searched.stderr and "not asked for" not in searched.stderr
    moves = summary["pose_tolerance"]["height_moves"]
    assert moves and all(abs(m["to_m"] - m["reference_m"]) < abs(m["from_m"] - m["reference_m"]) for m in moves)
    assert all(m["moved_m"] <= 0.75 for m in moves)
    grid = json.loads(run_rigopt(*common, "--json", "--height-search", "0", "--out", tmp_path / "g").stdout)
    assert grid["pose_tolerance"]["height_moves"] == [] and grid["pose_tolerance"]["widened_by"]
    assert not summary["pose_tolerance"]["widened_by"]  # every fire-truck camera within 0.05 m of R1's height
    checked = run_rigopt("check", tmp_path / "s" / "rig.json", "--vehicle", "firetruck")
    assert checked.returncode == 0, checked.stdout + checked.stderr
    bad = run_rigopt(*common, "--height-search", "-1")
    assert bad.returncode == 2 and "--height-search" in bad.stderr
