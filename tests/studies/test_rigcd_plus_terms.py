"""studies/rigcd_plus/plus_terms.py: the candidate RigCD+ terms on cases with known answers.

The box car here is the coverage tests' box: x in [-2, 2], y in [-1, 1], z in [0.3, 1.5] m (ISO frame, x
forward, y left, z up); its footprint is the rectangle [-2, 2] x [-1, 1]. Coverage settings are coarse
(2 rings x 2 heights x 36 sectors, 16 x 10 pixel rays) to keep the file fast.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from rigopt.camera import focal_from_fov
from rigopt.vehicle.footprint import Footprint
from rigopt.coverage.matrix import sector_points
from rigopt.coverage.measures import CoverageSettings, camera_coverage
from rigopt.coverage.visibility import visible
from rigopt.errors import RigoptError
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.metrics.calibration import FEATURE_DECIMALS
from rigopt.metrics.rigcd import rigcd_matrix
from rigopt.rig.library import load_rig, rig_names
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

import plus_terms as plus  # studies/rigcd_plus, see conftest.py

BOX = "vehicle.test.plusbox"


def box_spec(name: str, half_length: float) -> str:
    """Spec of a box x in [-half_length, half_length], y in [-1, 1], z in [0.3, 1.5] m, blueprint
    ``vehicle.test.<name>``."""
    h = half_length
    return (f'name = "{name}"\nblueprint = "vehicle.test.{name}"\n\n[[solids]]\nname = "body"\ntype = "prism"\n'
            f"side = [[{-h}, 0.3], [{h}, 0.3], [{h}, 1.5], [{-h}, 1.5]]\n"
            f"plan = [[{h}, 0], [{h}, 1.0], [{-h}, 1.0], [{-h}, 0]]\n")

COARSE = CoverageSettings(ring_distances=(2.0, 10.0), ring_heights=(0.0, 0.8), sectors=36, image_grid=(16, 10))
SETTINGS = plus.PlusSettings(coverage=COARSE)
SYMMETRIC = [t for t in plus.TERMS if t not in plus.ASYMMETRIC_TERMS]


@pytest.fixture(scope="module")
def box(tmp_path_factory) -> Vehicle:
    path = tmp_path_factory.mktemp("plusbox") / "vehicle.toml"
    path.write_text(box_spec("plusbox", 2.0))
    vehicle = Vehicle.from_spec(read_spec(path))
    np.testing.assert_allclose(vehicle.mesh.bounds, [[-2, -1, 0.3], [2, 1, 1.5]], atol=1e-6)
    return vehicle


@pytest.fixture(scope="module")
def vehicles(box):
    return {BOX: box}


def cam(id, position, yaw=0.0, pitch=0.0, fov=90.0, image_size=(1280, 720)):
    """A camera; yaw, pitch in degrees (yaw > 0 turns left, pitch > 0 tilts up)."""
    rotation = rotation_from_yaw_pitch_roll(math.radians(yaw), math.radians(pitch), 0.0)
    return Camera.pinhole(id, np.asarray(position, dtype=float), rotation, fov, tuple(image_size))


def rig(*cameras, name="test", vehicle=BOX):
    return Rig(name, vehicle, tuple(cameras))


def corner_cameras():
    """Four 120-degree cameras at the box's corners looking diagonally out: neighbours overlap a little."""
    return [cam("FL", (2.05, 1.05, 1.0), 45, fov=120), cam("FR", (2.05, -1.05, 1.0), -45, fov=120),
            cam("RL", (-2.05, 1.05, 1.0), 135, fov=120), cam("RR", (-2.05, -1.05, 1.0), -135, fov=120)]


ROOF_DOWN = cam("DOWN", (0.0, 0.0, 1.6), pitch=-90.0)  # 0.1 m over the roof, looking at it
FRONT_OUT = cam("OUT", (2.05, 0.0, 1.0))  # on the bumper, looking forward, away from the body


# --- zero on itself, symmetry, batch = pair -----------------------------------------------------------------

def test_every_term_is_zero_on_itself_and_symmetric_where_stated(vehicles):
    rigs = [rig(*corner_cameras(), name="corners"),
            rig(*corner_cameras()[:3], ROOF_DOWN, name="three_and_down"),
            rig(FRONT_OUT, cam("BACK", (-2.05, 0, 1.2), 180, fov=60), name="two")]
    m = plus.term_matrices(rigs, rigs, settings=SETTINGS, vehicles=vehicles)
    assert set(m) == set(plus.TERMS)
    for term, values in m.items():
        assert values.shape == (3, 3)
        assert np.all(np.isfinite(values)) and np.all(values >= 0), term
        assert np.all(np.diag(values) == 0.0), term
        if term in SYMMETRIC:
            np.testing.assert_allclose(values, values.T, atol=1e-9, err_msg=term)
    # the rigs really differ, so the zero diagonal is not trivial
    for term in ("t", "cover", "overlap", "cw_t"):
        assert m[term][0, 1] > 0 and m[term][0, 2] > 0, term
    assert m["selfocc"][0, 1] > 0 and m["count"][0, 2] == 0.5  # the roof camera; 4 against 2 cameras
    one = plus.pair_terms(rigs[1], rigs[2], settings=SETTINGS, vehicles=vehicles)
    assert one == {term: m[term][1, 2] for term in plus.TERMS}


def test_library_rigs_on_their_vehicles_zero_diagonal():
    rigs = [load_rig(name) for name in ("R1", "R5", "R9")]  # etron, tt, hgv
    m = plus.term_matrices(rigs, rigs, settings=SETTINGS)
    for term in SYMMETRIC:
        assert np.all(np.diag(m[term]) == 0.0), term
        np.testing.assert_allclose(m[term], m[term].T, atol=1e-9, err_msg=term)
    assert np.all(m["cover"][~np.eye(3, dtype=bool)] > 0)


def test_unit_weight_features_are_the_published_ones():
    rigs = [load_rig(name) for name in rig_names()]
    m = plus.term_matrices(rigs, rigs, ("t", "r", "f", "count"))
    published = rigcd_matrix(rigs, rigs)
    for key in ("t", "r", "f", "count"):
        np.testing.assert_array_equal(m[key], np.round(getattr(published, key), FEATURE_DECIMALS) + 0.0)
    features = plus.features_under_matching(rigs[:3], rigs, (1.0, 1.0, 1.0))
    assert features.shape == (3, len(rigs), 3)
    np.testing.assert_array_equal(features[..., 0], m["t"][:3])


# --- 1. height and planar translation -----------------------------------------------------------------------

def test_raised_rig_height_term_is_exactly_the_lift():
    r1 = load_rig("R1")
    raised = Rig("R1-up", r1.vehicle, tuple(dataclasses.replace(c, position=c.position + [0, 0, 0.3])
                                            for c in r1.cameras))
    for a, b in ((r1, raised), (raised, r1)):
        terms = plus.pair_terms(a, b, ("dz", "dxy", "t", "r", "f"))
        assert terms["dz"] == 0.3
        assert terms["dxy"] == 0.0
        assert terms["t"] == 0.3 and terms["r"] == 0.0 and terms["f"] == 0.0


def test_planar_shift_goes_to_the_planar_term():
    a = rig(cam("A", (0, 0, 1)), cam("B", (1, 0, 1), yaw=90))
    b = rig(cam("A", (0.3, 0.4, 1)), cam("B", (1, 0, 1.2), yaw=90))
    terms = plus.pair_terms(a, b, ("dz", "dxy", "t"))
    assert terms["dz"] == pytest.approx(0.1, abs=1e-12)  # (0 + 0.2) / 2
    assert terms["dxy"] == pytest.approx(0.25, abs=1e-12)  # (0.5 + 0) / 2
    assert terms["t"] == pytest.approx(0.35, abs=1e-12)


# --- 2. focal length ----------------------------------------------------------------------------------------

def test_focal_term_60_vs_90_degrees():
    expected = abs(math.log(math.tan(math.radians(45)) / math.tan(math.radians(30))))
    assert expected == pytest.approx(0.5 * math.log(3), abs=1e-15)
    a, b = rig(cam("C", (0, 0, 1), fov=60)), rig(cam("C", (0, 0, 1), fov=90))
    assert plus.pair_terms(a, b, ("focal",))["focal"] == pytest.approx(expected, abs=1e-10)
    assert plus.pair_terms(b, a, ("focal",))["focal"] == pytest.approx(expected, abs=1e-10)
    # the same as the log ratio of focal lengths in pixels, whatever the (common) width
    assert expected == pytest.approx(abs(math.log(focal_from_fov(60, 1280) / focal_from_fov(90, 1280))), abs=1e-12)
    assert plus.pair_terms(a, b, ("f",))["f"] == 30.0


def test_focal_term_with_own_image_widths():
    a = rig(cam("C", (0, 0, 1), fov=90, image_size=(1280, 720)))
    b = rig(cam("C", (0, 0, 1), fov=90, image_size=(640, 360)))
    assert plus.pair_terms(a, b, ("focal",))["focal"] == 0.0  # common width: same FOV, same focal
    own = plus.PlusSettings(focal_width="own")
    assert plus.pair_terms(a, b, ("focal",), own)["focal"] == pytest.approx(math.log(2), abs=1e-10)


def test_pixels_per_metre():
    # 90 deg over 1280 px: f = 640 px, so 640 px per metre at 1 m and 64 at 10 m
    np.testing.assert_allclose(plus.pixels_per_metre(90.0, 1280, [1.0, 10.0]), [640.0, 64.0])
    with pytest.raises(RigoptError):
        plus.pixels_per_metre(90.0, 1280, 0.0)


# --- 3, 4. coverage and overlap structure ---------------------------------------------------------------------

def test_removing_a_camera_changes_exactly_the_points_only_it_saw(box, vehicles):
    cameras = corner_cameras()
    full, without = rig(*cameras, name="full"), rig(*cameras[1:], name="without_FL")

    # independently: per-camera visibility of the sector points from the coverage module
    points = sector_points(Footprint.of_mesh(box.mesh), COARSE)[0]
    sees = visible(box.caster(COARSE.backend), full.positions, full.rotations, full.fovs,
                   np.array([c.image_size for c in full.cameras]), points, COARSE.max_range)
    count = sees.sum(axis=0)
    only_fl = np.mean(sees[0] & (count == 1))
    fl_in_pair = np.mean(sees[0] & (count == 2))  # >= 2 before, < 2 after
    assert only_fl > 0.1 and fl_in_pair > 0  # non-trivial case

    terms = plus.pair_terms(full, without, ("cover", "overlap"), SETTINGS, vehicles)
    assert terms["cover"] == pytest.approx(only_fl, abs=1e-10)
    assert terms["overlap"] == pytest.approx(fl_in_pair, abs=1e-10)
    # the term is the mean of the per-ring fractions
    pa, pb = (plus.rig_profile(r, box, SETTINGS) for r in (full, without))
    per_ring = plus.coverage_difference(pa, pb)
    assert per_ring.shape == (4,)
    assert terms["cover"] == pytest.approx(per_ring.mean(), abs=1e-10)


def test_each_rig_is_measured_on_its_own_vehicle(tmp_path, box):
    path = tmp_path / "vehicle.toml"
    path.write_text(box_spec("longbox", 4.0))
    long_box = Vehicle.from_spec(read_spec(path))
    np.testing.assert_allclose(long_box.mesh.bounds, [[-4, -1, 0.3], [4, 1, 1.5]], atol=1e-6)
    # four 120 deg cameras on a mast off the centre: together they see all of the 10 m ring on both vehicles,
    # but which sectors two of them see depends on where that vehicle's ring points lie
    ring10 = plus.PlusSettings(coverage=CoverageSettings(ring_distances=(10.0,), ring_heights=(0.8,), sectors=72,
                                                         image_grid=(4, 4)))
    mast = [cam(f"M{k}", (1.5, 0, 3.0), yaw=90 * k, pitch=-10, fov=120) for k in range(4)]
    short, long = rig(*mast, name="short"), rig(*mast, name="long", vehicle="vehicle.test.longbox")
    states = []
    for vehicle, r in ((box, short), (long_box, long)):
        points = sector_points(vehicle.footprint, ring10.coverage)[0]
        sees = visible(vehicle.ray_caster, r.positions, r.rotations, r.fovs, np.array([c.image_size for c in r.cameras]),
                       points, ring10.coverage.max_range)
        assert sees.any(axis=0).all()
        states.append(sees.sum(axis=0) >= 2)
    expected = float(np.mean(states[0] != states[1]))
    assert expected > 0
    vehicles = {BOX: box, "vehicle.test.longbox": long_box}
    terms = plus.pair_terms(short, long, ("cover", "overlap", "t"), ring10, vehicles)
    assert terms["cover"] == 0.0 and terms["t"] == 0.0
    assert terms["overlap"] == pytest.approx(expected, abs=1e-10)


# --- 5. self-occlusion --------------------------------------------------------------------------------------

def test_self_occlusion_of_a_camera_looking_at_its_body(box, vehicles):
    down, out = rig(ROOF_DOWN, name="down"), rig(FRONT_OUT, name="out")
    assert plus.rig_profile(down, box, SETTINGS).self_occlusion[0] == 1.0
    assert plus.rig_profile(out, box, SETTINGS).self_occlusion[0] == 0.0
    assert plus.pair_terms(down, out, ("selfocc",), SETTINGS, vehicles)["selfocc"] == 1.0


def test_self_occlusion_matches_the_coverage_module(box):
    oblique = cam("ROOF_BACK", (1.5, 0.0, 1.6), yaw=180, pitch=-20)  # sees part of the roof
    r = rig(oblique, FRONT_OUT, name="oblique")
    mine = plus.rig_profile(r, box, SETTINGS).self_occlusion
    theirs = [c.self_occluded_frac for c in camera_coverage(box, r, COARSE, Footprint.of_mesh(box.mesh))]
    np.testing.assert_allclose(mine, theirs, atol=1e-12)
    assert 0.1 < mine[0] < 0.9 and mine[1] == 0.0


# --- 6. matching with calibrated weights --------------------------------------------------------------------

def test_weighted_matching_changes_the_matching():
    # same positions, rotations swapped: keeping positions costs 2 x 90 deg, swapping costs 2 x 1 m
    a = rig(cam("P", (0, 0, 1), 0), cam("Q", (1, 0, 1), 90))
    b = rig(cam("P", (0, 0, 1), 90), cam("Q", (1, 0, 1), 0))
    unit = plus.features_under_matching([a], [b], (1.0, 1.0, 1.0))[0, 0]
    np.testing.assert_allclose(unit, [1.0, 0.0, 0.0], atol=1e-12)  # pi > 2: swap
    heavy_t = plus.features_under_matching([a], [b], (10.0, 1.0, 1.0))[0, 0]
    np.testing.assert_allclose(heavy_t, [0.0, math.pi / 2, 0.0], atol=1e-10)  # 20 > pi: keep
    assert plus.matching(a, b)[1].tolist() == [1, 0]
    assert plus.matching(a, b, (10.0, 1.0, 1.0))[1].tolist() == [0, 1]
    # scaling the weights does not change the matching
    np.testing.assert_allclose(plus.features_under_matching([a], [b], (100.0, 10.0, 10.0))[0, 0], heavy_t)


def test_zero_weight_still_matches_a_rig_to_itself():
    # identical rotations and FOVs: with lt = 0 every matching costs 0; the tie-break keeps cameras paired
    cameras = [cam(f"C{k}", (k, 0, 1)) for k in range(4)]
    a, shuffled = rig(*cameras), rig(*(cameras[k] for k in (2, 0, 3, 1)))
    settings = plus.PlusSettings(match_lambdas=(0.0, 1.0, 1.0))
    for b in (a, shuffled):
        terms = plus.pair_terms(a, b, ("t", "dz", "dxy"), settings)
        assert terms == {"t": 0.0, "dz": 0.0, "dxy": 0.0}
    assert plus.matching(a, shuffled, (0.0, 0.0, 0.0))[1].tolist() == [1, 3, 0, 2]


# --- 7. coverage-weighted matching -------------------------------------------------------------------------

def test_coverage_shares_and_matched_weights_sum_to_one(box):
    profile = plus.rig_profile(rig(*corner_cameras(), ROOF_DOWN), box, SETTINGS)
    shares = profile.shares
    assert shares.shape == (5,)
    assert shares.sum() == pytest.approx(1.0, abs=1e-12)
    assert shares[4] == 0.0 and np.all(shares[:4] > 0.1)  # the roof camera sees no ring point
    for rows in ([0, 1, 2, 3, 4], [0, 2], [4, 1], [4]):
        w = plus.matched_weights(shares, rows)
        assert w.sum() == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(plus.matched_weights(shares, [4]), [1.0])  # no share: uniform
    np.testing.assert_allclose(plus.coverage_shares(np.zeros((2, 5), dtype=bool)), [0.5, 0.5])
    # a point seen by two cameras gives half to each
    np.testing.assert_allclose(plus.coverage_shares([[1, 1, 0], [0, 1, 0]]), [0.75, 0.25])


def test_coverage_weighted_terms_weigh_cameras_by_what_they_see(vehicles):
    a = rig(FRONT_OUT, ROOF_DOWN, name="a")  # the roof camera sees no sector point: weight 0
    moved_up = cam("DOWN", (1.0, 0.0, 1.6))  # moved 1 m and turned outward: it now sees
    b = rig(FRONT_OUT, moved_up, name="b")
    ab = plus.pair_terms(a, b, settings=SETTINGS, vehicles=vehicles)
    ba = plus.pair_terms(b, a, settings=SETTINGS, vehicles=vehicles)
    assert ab["t"] == 0.5 and ab["r"] == pytest.approx(math.pi / 4, abs=1e-10)
    assert ab["cw_t"] == 0.0 and ab["cw_r"] == 0.0  # only the front camera counts, and it is unchanged
    share = plus.rig_profile(b, vehicles[BOX], SETTINGS).shares[1]
    assert 0.05 < share < 0.95
    assert ba["cw_t"] == pytest.approx(share * 1.0, abs=1e-9)  # not symmetric
    assert ba["cw_r"] == pytest.approx(share * math.pi / 2, abs=1e-9)


# --- validation ---------------------------------------------------------------------------------------------

def test_bad_input_raises_clear_errors(box, vehicles):
    a = rig(FRONT_OUT)
    with pytest.raises(RigoptError, match="unknown RigCD\\+ terms"):
        plus.pair_terms(a, a, ("height",))
    with pytest.raises(RigoptError, match="empty"):
        plus.term_matrices([], [a], ("t",))
    with pytest.raises(RigoptError, match="sequence"):
        plus.term_matrices(a, [a], ("t",))
    with pytest.raises(RigoptError, match="Rig or RigProfile"):
        plus.term_matrices(["R1"], [a], ("t",))
    with pytest.raises(RigoptError, match="lambdas"):
        plus.PlusSettings(match_lambdas=(-1.0, 1.0, 1.0))
    with pytest.raises(RigoptError, match="lambdas"):
        plus.PlusSettings(match_lambdas=(float("nan"), 1.0, 1.0))
    with pytest.raises(RigoptError, match="focal_width"):
        plus.PlusSettings(focal_width="wide")
    with pytest.raises(RigoptError, match="sectors"):
        plus.PlusSettings(coverage=dataclasses.replace(COARSE, sectors=0))
    # a rig on an unknown vehicle: geometric terms work, vehicle terms name the rig and the vehicle
    stray = rig(FRONT_OUT, name="stray", vehicle="vehicle.nowhere")
    assert plus.pair_terms(stray, stray, ("t", "dz", "focal"))["t"] == 0.0
    with pytest.raises(RigoptError, match="stray.*vehicle.nowhere"):
        plus.pair_terms(stray, stray, ("cover",), SETTINGS)
    # profiles must match the settings and hold what the terms need
    other = plus.rig_profile(a, box, plus.PlusSettings(coverage=dataclasses.replace(COARSE, sectors=12)))
    with pytest.raises(RigoptError, match="coverage settings"):
        plus.pair_terms(other, a, ("cover",), SETTINGS, vehicles)
    bare = plus.rig_profile(a, box, SETTINGS, coverage=False)
    with pytest.raises(RigoptError, match="lacks"):
        plus.pair_terms(bare, a, ("cw_t",), SETTINGS, vehicles)
    with pytest.raises(RigoptError, match="without coverage"):
        _ = bare.shares
    with pytest.raises(RigoptError, match="FOV"):
        plus.focal_log_ratio(180.0, 90.0)
