"""The perception cameras' pose tolerance (``--match-height``, ``--match-pitch``, ``--match-yaw``, ``--match-fov``):
each camera of a design is matched only to a reference camera within the tolerance of its height above the
ground, its pitch, its yaw and its lens; and the perception range (``--perception-range``)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from box_car import BOX_ZONES, ROOF_ZONE, spec_text
from in_process import run_rigopt

from rigopt.design.designer import design_rig, pose_violations
from rigopt.design.tolerance import (
    EXCESS_COST,
    OUT_OF_TOLERANCE_COST,
    matched_widening,
    pose_gaps,
    tolerance_penalty,
    within_pose_tolerance,
)
from rigopt.design.problem import ReferenceRig
from rigopt.design.settings import DesignSettings
from rigopt.errors import RigoptError
from rigopt.metrics.calibration import load_weights
from rigopt.rig.library import load_rig
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec


@pytest.fixture(scope="module")
def box_car(tmp_path_factory) -> Vehicle:
    path = tmp_path_factory.mktemp("posebox") / "vehicle.toml"
    path.write_text(spec_text("posebox", zones=BOX_ZONES + ROOF_ZONE))
    return Vehicle.from_spec(read_spec(path))


def pitched(pitch_deg: float) -> np.ndarray:
    """A camera rotation facing +x, pitched ``pitch_deg`` up (forward's z = sin(pitch))."""
    p = np.deg2rad(pitch_deg)
    forward = np.array([np.cos(p), 0.0, np.sin(p)])
    left = np.array([0.0, 1.0, 0.0])
    return np.column_stack([forward, left, np.cross(forward, left)])


def test_the_tolerance_compares_height_above_ground_and_pitch():
    reference = Rig("ref", "x", (Camera.pinhole("A", np.array([0.0, 0.0, 1.0]), pitched(0.0), 90.0),
                                 Camera.pinhole("B", np.array([0.0, 0.0, 2.0]), pitched(-10.0), 90.0)))
    heights = np.array([1.05, 1.2, 1.95, 2.0])
    pitches = np.deg2rad([0.0, 0.0, -10.0, -5.0])
    free = within_pose_tolerance(heights, pitches, reference, DesignSettings())
    assert free.all()
    ok = within_pose_tolerance(heights, pitches, reference, DesignSettings(match_height_m=0.1, match_pitch_deg=2.0))
    assert ok.tolist() == [[True, False], [False, False], [False, True], [False, False]]
    height_only = within_pose_tolerance(heights, pitches, reference, DesignSettings(match_height_m=0.1))
    assert height_only.tolist() == [[True, False], [False, False], [False, True], [False, True]]


def test_the_yaw_tolerance_wraps_around_and_the_fov_tolerance_compares_lenses():
    reference = Rig("ref", "x", (Camera.pinhole("back", np.zeros(3), pitched(0.0) @ _turn(180.0), 65.0),
                                 Camera.pinhole("front", np.zeros(3), pitched(0.0), 90.0)))
    yaws = np.deg2rad([-176.0, 170.0, 4.0, 30.0])
    fovs = np.array([65.0, 65.0, 90.0, 70.0])
    level, heights = np.zeros(4), np.ones(4)
    by_yaw = within_pose_tolerance(heights, level, reference, DesignSettings(match_yaw_deg=5.0), yaws, fovs)
    assert by_yaw.tolist() == [[True, False], [False, False], [False, True], [False, False]]
    by_lens = within_pose_tolerance(heights, level, reference, DesignSettings(match_fov_deg=0.0), yaws, fovs)
    assert by_lens.tolist() == [[True, False], [True, False], [False, True], [False, False]]
    both = within_pose_tolerance(heights, level, reference, DesignSettings(match_yaw_deg=5.0, match_fov_deg=5.0),
                                 yaws, fovs)
    assert both.tolist() == [[True, False], [False, False], [False, True], [False, False]]


def _turn(yaw_deg: float) -> np.ndarray:
    """A rotation about the vertical axis by ``yaw_deg`` (for a camera frame whose first column looks forward)."""
    c, s = np.cos(np.deg2rad(yaw_deg)), np.sin(np.deg2rad(yaw_deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_the_perception_range_frees_the_near_rings_only_with_near_field_cameras(box_car):
    from rigopt.design.requirements import design_requirements

    reference = [ReferenceRig.on_own_vehicle(load_rig("R1"))]
    base = DesignSettings(require="none")
    every = design_requirements(reference, box_car, base)
    far = design_requirements(reference, box_car, DesignSettings(require="none", perception_range_m=10.0))
    single = design_requirements(reference, box_car, DesignSettings(require="none", perception_range_m=10.0,
                                                                   near_field=False))
    near = np.array([label.startswith(("ring 2 m", "ring 5 m")) for label in every.labels])
    assert near.any() and every.needed[near].sum() > 0
    assert far.needed[near].sum() == 0 and np.array_equal(far.needed[~near], every.needed[~near])
    assert np.array_equal(single.needed, every.needed)
    with pytest.raises(RigoptError, match="perception range"):
        DesignSettings(perception_range_m=-1.0)


def test_a_negative_or_infinite_tolerance_is_refused():
    with pytest.raises(RigoptError, match="height tolerance"):
        DesignSettings(match_height_m=-0.1)
    with pytest.raises(RigoptError, match="pitch tolerance"):
        DesignSettings(match_pitch_deg=float("inf"))
    with pytest.raises(RigoptError, match="yaw tolerance"):
        DesignSettings(match_yaw_deg=-5.0)
    with pytest.raises(RigoptError, match="FOV tolerance"):
        DesignSettings(match_fov_deg=float("nan"))


@pytest.mark.slow
def test_a_design_within_the_tolerance_keeps_every_matched_camera_inside_it(box_car):
    reference = ReferenceRig.on_own_vehicle(load_rig("R1"))
    settings = DesignSettings(lenses=(90.0, 120.0), yaw_step_deg=30.0, pitches_deg=(-10.0, 0.0), near_field=False,
                              require="none", match_height_m=0.3, match_pitch_deg=0.0)
    result = design_rig(box_car, reference, load_weights("joint"), settings)
    rig = result.design.rig
    assert pose_violations(rig, reference.rig, load_weights("joint"), settings) == []
    # every camera has a reference camera within 0.3 m of its height (the matching's partner)
    gaps = np.abs(rig.positions[:, 2, None] - reference.rig.positions[None, :, 2])
    assert np.all(gaps.min(axis=1) <= 0.3 + 1e-9)
    assert np.allclose(rig.rotations[:, 2, 0], 0.0, atol=1e-9)  # R1 looks level: so does every design camera
    # without the tolerance the same problem is free to pitch cameras down
    free = design_rig(box_car, reference, load_weights("joint"), DesignSettings(
        lenses=(90.0, 120.0), yaw_step_deg=30.0, pitches_deg=(-10.0, 0.0), near_field=False, require="none"))
    assert free.milp.selection.objective <= result.milp.selection.objective + 1e-9


def test_gaps_are_in_units_of_the_tolerance():
    reference = Rig("ref", "vehicle.test", (Camera.pinhole("a", np.array([0.0, 0.0, 1.0]), pitched(0.0), 65.0),))
    settings = DesignSettings(match_height_m=0.2, match_pitch_deg=5.0, match_fov_deg=0.0)
    heights, pitches = np.array([1.0, 1.3, 1.1, 1.0]), np.deg2rad([0.0, 0.0, -15.0, 0.0])
    gaps = pose_gaps(heights, pitches, reference, settings, fovs=np.array([65.0, 65.0, 65.0, 70.0]))
    # 0.3 m is 1.5 tolerances; 15 deg of pitch is 3 (the larger of 0.5 and 3); any FOV gap against 0 is infinite
    assert gaps[:, 0] == pytest.approx([0.0, 1.5, 3.0, np.inf], rel=1e-6)
    assert within_pose_tolerance(heights, pitches, reference, settings,
                                 fovs=np.array([65.0, 65.0, 65.0, 70.0]))[:, 0].tolist() == [True, False, False, False]


def test_beyond_the_tolerance_a_camera_pays_per_tolerance():
    gaps = np.array([[0.5, 2.0, np.inf], [3.0, 1.5, np.inf]])
    penalty = tolerance_penalty(gaps)
    # within: free; 2 and 1.5 tolerances away: 1 and 0.5 tolerances beyond; a column no candidate can meet: lifted
    assert penalty.tolist() == [[0.0, EXCESS_COST, 0.0], [2 * EXCESS_COST, 0.5 * EXCESS_COST, 0.0]]
    broken = tolerance_penalty(np.array([[np.inf], [0.0]]))  # a zero tolerance one candidate meets
    assert broken[:, 0].tolist() == [OUT_OF_TOLERANCE_COST, 0.0]
    widen = matched_widening(np.array([[0.5, 2.0, 0.0], [3.0, 1.5, 0.0]]), np.array([1, 0]))
    assert widen.tolist() == pytest.approx([3.0, 2.0, 1.0])


@pytest.mark.slow
def test_a_reference_camera_no_mount_allows_keeps_the_nearest_pose(box_car):
    # R1 looks level and only -10 deg is offered: no camera can keep 2 deg of pitch, so each camera keeps the
    # nearest pitch there is, 5 tolerances away, as every candidate does: the design is the one without it
    settings = DesignSettings(lenses=(90.0, 120.0), yaw_step_deg=30.0, pitches_deg=(-10.0,), near_field=False,
                              require="none", match_pitch_deg=2.0)
    reference = ReferenceRig.on_own_vehicle(load_rig("R1"))
    widened = design_rig(box_car, reference, load_weights("joint"), settings)
    free = design_rig(box_car, reference, load_weights("joint"), replace(settings, match_pitch_deg=None))
    assert sorted(k for k, _ in widened.tolerance_widened) == sorted(c.id for c in reference.rig.cameras)
    assert [f for _, f in widened.tolerance_widened] == pytest.approx([(10.0 - 1e-6) / 2.0] * len(reference.rig))
    assert np.array_equal(widened.milp.rig.positions, free.milp.rig.positions)
    assert free.tolerance_widened == ()
    # a zero tolerance no candidate meets is lifted: the cameras are matched without it
    lifted = design_rig(box_car, reference, load_weights("joint"), replace(settings, match_pitch_deg=0.0))
    assert all(not np.isfinite(f) for _, f in lifted.tolerance_widened)
    assert lifted.milp.selection.objective == pytest.approx(free.milp.selection.objective, abs=1e-9)


@pytest.mark.slow
def test_the_command_takes_the_tolerance_and_reports_it(tmp_path):
    result = run_rigopt("design", "--vehicle", "tt", "--ref", "R1", "--match-height", "0.2", "--match-pitch", "0",
                        "--match-fov", "30", "--single-set", "--require", "none", "--yaw-step", "30", "--out", tmp_path / "d", "--json")
    assert result.returncode == 0, result.stderr
    import json

    summary = json.loads(result.stdout)
    assert summary["pose_tolerance"] == {"height_m": 0.2, "pitch_deg": 0.0, "yaw_deg": None, "fov_deg": 30.0,
                                          "lifted_for": [], "widened_by": {}, "height_search_m": 0.0,
                                          "height_moves": []}
    assert summary["perception_range_m"] == 0.0
    assert all(abs(c["fov"] - 65.0) <= 30.0 for c in summary["cameras"])  # R1's lenses are all 65 deg
    bad = run_rigopt("design", "--vehicle", "tt", "--ref", "R1", "--match-height", "-1")
    assert bad.returncode == 2 and "--match-height" in bad.stderr
    bad = run_rigopt("design", "--vehicle", "tt", "--ref", "R1", "--perception-range", "-3")
    assert bad.returncode == 2 and "--perception-range" in bad.stderr


@pytest.mark.slow
def test_the_command_defaults_to_the_nearest_pose_and_pose_free_restores_the_earlier_default(tmp_path):
    common = ("design", "--vehicle", "tt", "--ref", "R1", "--yaw-step", "30", "--require", "none", "--json")
    import json

    nearest = run_rigopt(*common, "--out", tmp_path / "n")
    assert nearest.returncode == 0, nearest.stderr
    summary = json.loads(nearest.stdout)
    tolerance = {k: summary["pose_tolerance"][k] for k in ("height_m", "pitch_deg", "yaw_deg", "fov_deg")}
    assert tolerance == {"height_m": 0.05, "pitch_deg": 0.0, "yaw_deg": 5.0, "fov_deg": 0.0}
    assert summary["perception_range_m"] == 20.0
    free = json.loads(run_rigopt(*common, "--pose", "free", "--out", tmp_path / "f").stdout)
    assert free["pose_tolerance"]["height_m"] is None and free["perception_range_m"] == 0.0
    given = json.loads(run_rigopt(*common, "--match-height", "0.2", "--perception-range", "10",
                                  "--out", tmp_path / "g").stdout)
    assert given["pose_tolerance"]["height_m"] == 0.2 and given["pose_tolerance"]["yaw_deg"] == 5.0
    assert given["perception_range_m"] == 10.0
    single = json.loads(run_rigopt(*common, "--single-set", "--out", tmp_path / "s").stdout)
    assert single["pose_tolerance"]["height_m"] is None  # one camera set is always free
    bad = run_rigopt(*common, "--pose", "wide", "--out", tmp_path / "b")
    assert bad.returncode == 2 and "--pose" in bad.stderr
