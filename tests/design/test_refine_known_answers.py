"""The continuous stage (casadi + IPOPT, ``rigopt.design.refine``) on problems whose optimum is known.

Every camera stands on a flat plate facing ahead (outward normal +x, at x = 2 m): its tangent frame is
(y, z), so a slide (u, v) moves it by u in y and v in z, and a mirrored pair at y = +a and y = -a has
mirrored frames (the mirror's move is (-u, v)). Known answers:

* one camera: slides back to its reference's place, stops at its radius, turns its pitch only within range;
* a mirrored pair (``mirror = [1, 0]``) whose references are mirror images reaches them both; one whose
  references are lopsided meets at the mean of the two targets as seen from one side (the smoothed cost
  ``sqrt(d^2 + SMOOTHING)`` of each is the same function of the distance to its target, so the sum is
  symmetric about their midpoint and strictly convex); one whose second camera has no reference moves as
  the mirror image of the first (slide, yaw, pitch and FOV);
* a centreline camera (``mirror = [0]``) keeps y = 0 and its yaw and turns only its pitch;
* a lens range: a pinhole's FOV goes to its reference's inside the range, stops at the bound outside it;
* a duty point: a camera turning towards its reference stops where the point reaches the inset frustum's
  edge, at bearing ``atan((1 - FRUSTUM_INSET) * tan_half)`` from its axis (``tan_half`` the pinhole's
  horizontal half-angle tangent for a yaw, times height / width for a pitch). The camera could slide to win a
  little turn, but 5 m away a slide buys under 0.2 rad per metre at a cost of 1 per metre: the smoothing
  lets it slide ~2e-4 m, ~3e-5 rad of turn.

Mutation run (refine.py broken one way at a time, in a copy of the checkout; this file's 11 tests run after
each; failed / 11 and which):

==============================================  ======  ========================================================
mutation of refine.py                           failed  tests that failed
==============================================  ======  ========================================================
drop the radius constraint                      1       radius
flip the sign of the mirrored yaw constraint    3       pair, lopsided pair, follower
drop the pitch bounds                           1       pitch range
drop the fov bounds                             2       fov bound, follower (its FOV runs off: no valid camera)
drop the duty constraints                       2       duty yaw, duty pitch
weight the offset term by 0                     8       slide, radius, pair, lopsided pair, follower, centreline,
                                                        duty yaw, duty pitch (a free slide wins turn)
drop the mirror u/v coupling                    2       lopsided pair, follower
drop only the mirror v coupling                 2       lopsided pair, follower
mirror move not reflected (F_j^T F_k)           3       pair, lopsided pair, follower
drop the mirrored pitch coupling                1       follower
drop the mirrored fov coupling                  1       follower
drop the centreline's lateral constraint        1       centreline
drop the centreline's yaw constraint            1       centreline
drop the frustum inset                          2       duty yaw, duty pitch
swap the half-angle tangents (h for v)          2       duty yaw, duty pitch
drop the horizontal duty bound                  1       duty yaw
drop the vertical duty bound                    1       duty pitch
weight the rotation term by 0                   11      all (in the lens tests yaw appears nowhere: casadi
                                                        refuses to read it)
weight the fov term by 0                        3       fov inside, fov bound, follower
every FOV fixed (hfov = camera.fov)             3       fov inside, fov bound, follower
==============================================  ======  ========================================================

Tests by short name, in file order: slide, radius, pitch range; pair (mirror-image references), lopsided pair,
follower (no reference), centreline; fov inside, fov bound; duty yaw, duty pitch.
"""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.benchmark import BENCHMARK_IMAGE_SIZE
from rigopt.design.refine import FRUSTUM_INSET, RefineProblem, refine
from rigopt.geometry import rotation_from_yaw_pitch_roll, yaw_pitch_roll_from_rotation
from rigopt.rig.model import Camera, Rig

#: The plate's outward normal: cameras on it slide in y and z.
NORMAL = np.array([1.0, 0.0, 0.0])


def camera(id: str, position, yaw_deg: float = 0.0, pitch_deg: float = 0.0, fov: float = 90.0) -> Camera:
    rotation = rotation_from_yaw_pitch_roll(np.radians(yaw_deg), np.radians(pitch_deg), 0.0)
    return Camera.pinhole(id, np.array(position, float), rotation, fov)


def rig(*cameras: Camera) -> Rig:
    return Rig("rig", "vehicle.audi.etron", cameras)


def one(position, pitch_deg: float = 0.0, fov: float = 90.0, yaw_deg: float = 0.0) -> Rig:
    return rig(camera("CAM", position, yaw_deg, pitch_deg, fov))


def solve(design: Rig, reference: Rig, radius: float = 1.0, pitch_range=(-0.5, 0.5), *, matched=None,
          mirror=None, fov_range=None, duties=None, points=None) -> Rig:
    """The refined rig; every camera matched to the reference camera of its index unless ``matched``."""
    n = len(design)
    problem = RefineProblem(design, reference, np.arange(n) if matched is None else np.array(matched),
                            np.tile(NORMAL, (n, 1)), np.zeros((n, 0), bool) if duties is None else np.array(duties),
                            np.zeros((0, 3)) if points is None else np.array(points, float),
                            alpha=1.0, lambdas=(1.0, 1.0, 0.01), pitch_range=pitch_range, fov_range=fov_range,
                            radius=radius, mirror=None if mirror is None else np.array(mirror))
    outcome = refine(problem)
    assert outcome.status == "Solve_Succeeded" and outcome.rig is not None
    return outcome.rig


def yaws_pitches_deg(refined: Rig) -> tuple[np.ndarray, np.ndarray]:
    yaw, pitch, _ = yaw_pitch_roll_from_rotation(refined.rotations)
    return np.degrees(yaw), np.degrees(pitch)


# --- one camera ------------------------------------------------------------------------------------------


def test_a_camera_off_its_reference_on_a_flat_plate_slides_back_to_it():
    refined = solve(one([2.0, 0.3, 1.2]), one([2.0, 0.0, 1.0]))
    assert refined.positions[0] == pytest.approx([2.0, 0.0, 1.0], abs=1e-3)
    assert np.degrees(yaw_pitch_roll_from_rotation(refined.rotations)[1][0]) == pytest.approx(0.0, abs=0.05)


def test_the_slide_stops_at_the_cameras_radius():
    refined = solve(one([2.0, 0.3, 1.0]), one([2.0, 0.0, 1.0]), radius=0.1)
    assert refined.positions[0] == pytest.approx([2.0, 0.2, 1.0], abs=1e-3)  # 0.1 m nearer, on the plate


def test_the_pitch_turns_to_the_reference_only_within_its_range():
    free = solve(one([2.0, 0.0, 1.0]), one([2.0, 0.0, 1.0], pitch_deg=-10.0))
    assert np.degrees(yaw_pitch_roll_from_rotation(free.rotations)[1][0]) == pytest.approx(-10.0, abs=0.05)
    bounded = solve(one([2.0, 0.0, 1.0]), one([2.0, 0.0, 1.0], pitch_deg=-10.0), pitch_range=np.radians([-5.0, 5.0]))
    assert np.degrees(yaw_pitch_roll_from_rotation(bounded.rotations)[1][0]) == pytest.approx(-5.0, abs=1e-3)


# --- mirrored pairs and the centreline -------------------------------------------------------------------

#: A pair on the plate at y = +-0.5 m, 1 m up, facing ahead.
PAIR = rig(camera("LEFT", [2.0, 0.5, 1.0]), camera("RIGHT", [2.0, -0.5, 1.0]))


def test_a_mirrored_pair_reaches_references_that_are_mirror_images():
    reference = rig(camera("L", [2.0, 0.62, 1.05], yaw_deg=10.0, pitch_deg=-4.0),
                    camera("R", [2.0, -0.62, 1.05], yaw_deg=-10.0, pitch_deg=-4.0))
    refined = solve(PAIR, reference, mirror=[1, 0])
    assert refined.positions == pytest.approx(reference.positions, abs=1e-3)
    yaws, pitches = yaws_pitches_deg(refined)
    assert yaws == pytest.approx([10.0, -10.0], abs=0.05)
    assert pitches == pytest.approx([-4.0, -4.0], abs=0.05)


def test_a_mirrored_pair_with_lopsided_references_meets_at_the_mean_of_its_mirrored_targets():
    # Seen from the left: targets (0.60, 1.02) and, mirrored, (0.56, 0.98) -> (0.58, 1.00); yaws 12 and 8 -> 10.
    reference = rig(camera("L", [2.0, 0.60, 1.02], yaw_deg=12.0, pitch_deg=-4.0),
                    camera("R", [2.0, -0.56, 0.98], yaw_deg=-8.0, pitch_deg=-4.0))
    refined = solve(PAIR, reference, mirror=[1, 0])
    assert refined.positions == pytest.approx(np.array([[2.0, 0.58, 1.0], [2.0, -0.58, 1.0]]), abs=1e-3)
    yaws, pitches = yaws_pitches_deg(refined)
    assert yaws == pytest.approx([10.0, -10.0], abs=0.05)
    assert pitches == pytest.approx([-4.0, -4.0], abs=0.05)


def test_a_mirrored_camera_without_a_reference_moves_as_the_mirror_image_of_its_pair():
    reference = rig(camera("L", [2.0, 0.6, 1.1], yaw_deg=10.0, pitch_deg=-4.0, fov=70.0))
    refined = solve(PAIR, reference, matched=[0, -1], mirror=[1, 0], fov_range=(60.0, 100.0))
    assert refined.positions == pytest.approx(np.array([[2.0, 0.6, 1.1], [2.0, -0.6, 1.1]]), abs=1e-3)
    yaws, pitches = yaws_pitches_deg(refined)
    assert yaws == pytest.approx([10.0, -10.0], abs=0.05)
    assert pitches == pytest.approx([-4.0, -4.0], abs=0.05)
    assert [c.fov for c in refined.cameras] == pytest.approx([70.0, 70.0], abs=1e-3)


def test_a_centreline_camera_stays_on_it_facing_ahead_and_turns_only_its_pitch():
    # Yaw held at 0, the rotation angle to Rz(15 deg) Ry(5 deg) is least at pitch -5 deg (trace of Rz Ry).
    refined = solve(one([2.0, 0.0, 1.0]), one([2.0, 0.2, 1.1], pitch_deg=-5.0, yaw_deg=15.0), mirror=[0])
    assert refined.positions[0] == pytest.approx([2.0, 0.0, 1.1], abs=1e-3)
    yaws, pitches = yaws_pitches_deg(refined)
    assert yaws[0] == pytest.approx(0.0, abs=1e-3)
    assert pitches[0] == pytest.approx(-5.0, abs=0.05)


# --- a lens range ----------------------------------------------------------------------------------------


def test_a_pinholes_fov_goes_to_its_references_inside_the_lens_range():
    refined = solve(one([2.0, 0.0, 1.0], fov=90.0), one([2.0, 0.0, 1.0], fov=70.0), fov_range=(60.0, 100.0))
    assert refined.cameras[0].fov == pytest.approx(70.0, abs=1e-3)


def test_a_pinholes_fov_stops_at_the_lens_ranges_bound():
    refined = solve(one([2.0, 0.0, 1.0], fov=90.0), one([2.0, 0.0, 1.0], fov=50.0), fov_range=(60.0, 100.0))
    assert refined.cameras[0].fov == pytest.approx(60.0, abs=1e-3)


# --- duty points -----------------------------------------------------------------------------------------

#: The duty tests' pinhole: tan of its half-angles, the vertical one scaled by the benchmark's aspect ratio.
DUTY_FOV = 60.0
TAN_H = np.tan(np.radians(DUTY_FOV / 2))
TAN_V = TAN_H * BENCHMARK_IMAGE_SIZE[1] / BENCHMARK_IMAGE_SIZE[0]


def test_a_duty_point_stops_the_yaw_where_it_reaches_the_inset_frustums_side():
    # The point 5 m away, 20 deg to the right, at the camera's height; the reference turns 40 deg left.
    bearing = np.radians(-20.0)
    point = [2.0 + 5.0 * np.cos(bearing), 5.0 * np.sin(bearing), 2.0]
    refined = solve(one([2.0, 0.0, 2.0], fov=DUTY_FOV), one([2.0, 0.0, 2.0], fov=DUTY_FOV, yaw_deg=40.0),
                    duties=[[True]], points=[point])
    yaw, pitch, _ = yaw_pitch_roll_from_rotation(refined.rotations)
    assert yaw[0] == pytest.approx(bearing + np.arctan((1 - FRUSTUM_INSET) * TAN_H), abs=1e-3)  # 9.25 deg
    assert pitch[0] == pytest.approx(0.0, abs=1e-3)


def test_a_duty_point_stops_the_pitch_where_it_reaches_the_inset_frustums_bottom():
    # The point 5 m away, 15 deg below straight ahead; the reference looks 20 deg up.
    elevation = np.radians(-15.0)
    point = [2.0 + 5.0 * np.cos(elevation), 0.0, 2.0 + 5.0 * np.sin(elevation)]
    refined = solve(one([2.0, 0.0, 2.0], fov=DUTY_FOV), one([2.0, 0.0, 2.0], fov=DUTY_FOV, pitch_deg=20.0),
                    duties=[[True]], points=[point])
    yaw, pitch, _ = yaw_pitch_roll_from_rotation(refined.rotations)
    assert pitch[0] == pytest.approx(elevation + np.arctan((1 - FRUSTUM_INSET) * TAN_V), abs=1e-3)  # 2.49 deg
    assert yaw[0] == pytest.approx(0.0, abs=1e-3)
