"""The near-field stage (rigopt/design/near_field.py): fisheye candidates, the set-cover MILP, and a small design."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.camera import CameraModel
from rigopt.coverage.regulations import parse_require, required_mask
from rigopt.coverage.visibility import resolved_by
from rigopt.design import near_field
from rigopt.design.selection import DesignInfeasible
from rigopt.rig.library import load_rig
from rigopt.rig.model import Rig
from rigopt.vehicle.library import load_vehicle


def test_the_default_fisheye_is_a_190_degree_equidistant_lens():
    camera = near_field.fisheye_190()
    assert camera.lens.distortion == "fisheye" and camera.lens.coefficients == (0.0, 0.0, 0.0, 0.0)
    assert camera.fov == pytest.approx(190.0) and camera.lens.image_size == (1280, 800)


def test_the_set_cover_takes_the_fewest_then_the_cheapest():
    # 4 candidates on 4 mount points far apart; points 0-2: {0, 1} see 0 and 1, {2} sees 2, {3} sees 0-2
    sees = np.array([[1, 1, 0], [1, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=bool)
    mount_points = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], dtype=float)
    chosen, status, gap = near_field.select_near_field(sees, np.arange(4), mount_points, np.ones(4))
    assert chosen.tolist() == [3] and status == "optimal" and gap == pytest.approx(0, abs=1e-9)
    sees[3, 2] = False  # now two cameras are needed: the cheaper of 0 and 1 with 2
    chosen, _, _ = near_field.select_near_field(sees, np.arange(4), mount_points, np.array([2.0, 1.0, 1.0, 1.0]))
    assert sorted(chosen.tolist()) in ([1, 2], [2, 3])
    assert 0 not in chosen


def test_a_point_no_candidate_sees_is_infeasible():
    with pytest.raises(DesignInfeasible, match="no near-field candidate sees"):
        near_field.select_near_field(np.array([[True, False]]), np.zeros(1, dtype=int), np.zeros((1, 3)), np.ones(1))


def test_clashing_mounts_hold_one_camera():
    sees = np.array([[1, 0], [0, 1], [1, 1]], dtype=bool)
    mount_points = np.array([[0, 0, 0], [0.05, 0, 0], [5, 0, 0]], dtype=float)  # 0 and 1 clash
    chosen, _, _ = near_field.select_near_field(sees, np.arange(3), mount_points, np.array([1.0, 1.0, 5.0]))
    assert chosen.tolist() == [2]


def test_of_two_duplicating_candidates_at_most_one_is_chosen():
    """0 and 1 (cheap) would duplicate each other; 2 and 3 (dearer) see what they see. Without the pair the MILP
    takes 0 and 1; with it, one of them and the other's stand-in."""
    sees = np.array([[1, 0], [0, 1], [1, 0], [0, 1]], dtype=bool)
    mount_points = np.array([[0, 0, 0], [0.3, 0, 0], [5, 0, 0], [9, 0, 0]], dtype=float)
    cost = np.array([0.0, 0.0, 1.0, 1.0])
    free, _, _ = near_field.select_near_field(sees, np.arange(4), mount_points, cost)
    assert free.tolist() == [0, 1]
    kept, _, _ = near_field.select_near_field(sees, np.arange(4), mount_points, cost, duplicates=np.array([[0, 1]]))
    assert kept.tolist() in ([0, 3], [1, 2])


def test_duplicate_pairs_are_the_same_lens_close_and_looking_the_same_way():
    """Mounting practice's duplicate rule on candidates: 0.5 m and 10 deg by default; a third lens or a turned
    axis is no duplicate, and none are with the feature rules off."""
    from rigopt.design.candidates import CandidateSet
    from rigopt.geometry import rotation_from_yaw_pitch_roll
    from rigopt.mounting.records import MountPractice

    yaws = np.deg2rad([0.0, 8.0, 30.0, 0.0])
    rotations = np.stack([rotation_from_yaw_pitch_roll(y, 0.0, 0.0) for y in yaws])
    positions = np.array([[0, 0, 1], [0.4, 0, 1], [0.2, 0, 1], [0.1, 0.1, 1]], dtype=float)
    catalogue = (near_field.fisheye_190(), near_field.fisheye_190())
    candidates = CandidateSet(positions, rotations, np.full(4, 190.0), yaws, np.zeros(4), np.arange(4), positions,
                              np.tile([1.0, 0.0, 0.0], (4, 1)), np.array(["bumper_front"] * 4), np.array([0, 0, 0, 1]),
                              catalogue)
    pairs = near_field.duplicate_pairs(candidates, np.arange(4), MountPractice())
    assert sorted(map(tuple, pairs.tolist())) == [(0, 1)]  # 2 is turned 30 deg, 3 has the other lens
    assert len(near_field.duplicate_pairs(candidates, np.arange(4), MountPractice(features=False))) == 0


def test_near_field_fisheyes_stay_off_glass_and_cost_more_off_the_production_spots():
    hgv = load_vehicle("hgv")
    zones = near_field.near_field_zones(hgv)
    assert "mirror" in zones and "bumper_front" in zones
    assert not set(zones) & set(near_field.GLASS_ZONES)
    with pytest.raises(Exception, match="glass"):
        near_field.near_field_zones(hgv, ("windshield_front",))
    points = np.array([[3.9, 0.0, 1.0], [3.5, 1.4, 2.0], [1.0, 1.3, 2.0]])
    costs = near_field.near_field_costs(hgv, ["bumper_front", "mirror", "b_pillar"], points)
    plain = near_field.mounting_costs(hgv, ["bumper_front", "mirror", "b_pillar"], points)
    assert (costs - plain).tolist() == [0.0, 0.0, near_field.OFF_SPOT_COST]


@pytest.mark.slow
def test_the_tt_sees_its_rear_field_and_near_ring_with_few_fisheyes():
    """On the tt (M1: R158), the design's fisheyes see every near ring and field point, at most two look back."""
    tt = load_vehicle("tt")
    presets = parse_require("default", tt)
    perception = Rig("none", tt.blueprint, (load_rig("R4").cameras[0],))
    design = near_field.design_near_field(tt, perception, presets, 0.25, tt.symmetry.symmetric)
    rig = Rig("nf", tt.blueprint, design.rig.cameras[1:])
    assert design.rig.cameras[0].role == "perception" and len(design.rig.perception()) == 1
    assert all(c.role == "near_field" for c in rig.cameras) and 3 <= len(rig) <= 8
    points = near_field.near_field_points(tt, presets)
    (r158,) = presets
    dense = r158.points(tt, 0.1)
    dense = dense[required_mask(tt, dense)]
    model = CameraModel.of_cameras(rig.cameras)
    for pts, demand in ((points.points, points.pixel_demand), (dense, r158.pixel_demands(len(dense)))):
        seen = resolved_by(tt.ray_caster, model, rig.positions, rig.rotations, pts, demand, near_field.NEAR_FIELD_RANGE)
        assert seen.any(axis=0).all()  # each at its field's pixels (the ring's points: in view)
    assert points.pixel_demand[:, 1].max() == r158.test_object.min_px > 0
    backwards = [c for c in rig.cameras if c.forward[0] < -0.7]
    assert 1 <= len(backwards) <= 2


@pytest.mark.slow
def test_a_two_role_design_leaves_the_fields_to_its_fisheyes():
    """design_rig(near_field=True) on the tt: R1's eight perception cameras, near-field fisheyes that alone see
    R158 densely; the predicted drop is the perception cameras'."""
    from rigopt.design.designer import design_rig
    from rigopt.design.problem import ReferenceRig
    from rigopt.design.settings import DesignSettings
    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.ranking import predict_transfer

    tt = load_vehicle("tt")
    result = design_rig(tt, ReferenceRig.on_own_vehicle(load_rig("R1")), load_weights("joint"),
                        DesignSettings(near_field=True, refine=False))
    rig = result.design.rig
    perception, fisheyes = rig.perception(), [c for c in rig.cameras if c.role == "near_field"]
    assert len(perception) == 8 and 1 <= len(fisheyes) <= 8
    assert all(c.lens.distortion == "fisheye" for c in fisheyes)
    assert [r.key for r in result.regions] == ["r158"] and result.regions[0].covered_frac == 1.0
    assert result.design.check.valid, [c.problems for c in result.design.check.cameras if not c.valid]
    nf = Rig("nf", tt.blueprint, tuple(fisheyes))
    (r158,) = parse_require("default", tt)
    dense = r158.points(tt, 0.1)
    dense = dense[required_mask(tt, dense)]
    seen = resolved_by(tt.ray_caster, CameraModel.of_cameras(nf.cameras), nf.positions, nf.rotations, dense,
                       r158.pixel_demands(len(dense)), near_field.NEAR_FIELD_RANGE)
    assert seen.any(axis=0).all()  # at R158's object's 25 px
    expected = predict_transfer(load_rig("R1"), [perception], load_weights("joint"))[0].predicted_drop
    assert result.design.prediction.predicted_drop == pytest.approx(expected)


@pytest.mark.slow
def test_free_perception_cameras_beside_mirrored_fisheyes():
    """perception_symmetric=False on the fire truck with the nearest-pose tolerance: the perception cameras take
    R1's layout (its rear camera low on a rear corner, the centre below 1.15 m being the tailboard's), the
    near-field fisheyes stay in mirrored pairs."""
    from rigopt.design.designer import design_rig
    from rigopt.design.problem import ReferenceRig
    from rigopt.design.settings import DesignSettings
    from rigopt.metrics.calibration import load_weights
    from rigopt.report.design_report import symmetry_dict
    from rigopt.vehicle.symmetry import rig_symmetry

    truck = load_vehicle("firetruck")
    settings = DesignSettings(perception_symmetric=False, match_height_m=0.05, match_pitch_deg=0.0,
                              match_yaw_deg=5.0, match_fov_deg=0.0, perception_range_m=20.0)
    result = design_rig(truck, ReferenceRig.on_own_vehicle(load_rig("R1")), load_weights("joint"), settings)
    rig = result.design.rig
    fisheyes = Rig("nf", truck.blueprint, tuple(c for c in rig.cameras if c.role == "near_field"))
    rearward = [c for c in rig.perception().cameras if c.forward[0] < -0.99]
    assert len(rearward) == 1 and abs(rearward[0].position[1]) > 1.0 and rearward[0].position[2] < 0.85
    assert result.near_field_mirrored and rig_symmetry(fisheyes).symmetric
    assert not rig_symmetry(rig.perception()).symmetric
    assert symmetry_dict(result)["describe"].startswith("perception cameras placed freely")


@pytest.mark.slow
@pytest.mark.parametrize("name", ["firetruck", "hgv"])
def test_a_trucks_default_design_puts_its_fisheyes_where_production_surround_view_does(name):
    """The default design from R1: every near-field fisheye at a production spot (a mirror among them), none on
    glass, and the whole rig passes the mount checks (duplicates included)."""
    from rigopt.design import design_rig
    from rigopt.mounting.rules import check_rig

    result = design_rig(name, "R1")
    fisheyes = [c for c in result.design.rig.cameras if c.role == "near_field"]
    assert fisheyes and all(c.zone in near_field.SURROUND_VIEW_ZONES for c in fisheyes)
    assert any(c.zone == "mirror" for c in fisheyes)
    assert check_rig(result.design.rig, result.vehicle, result.settings.rules).valid
    # the fields seen at their test objects' pixels, not only in view
    assert [(r.key, r.covered_frac) for r in result.regions] == [("r151", 1.0), ("r159", 1.0), ("r158", 1.0)]
    assert all(r.test_object.min_px == 25.0 for r in result.regions)
    if name == "hgv":  # the coupled trailer blocks part of some camera's view, and the report says so
        from rigopt.report.design_report import packaging_rows

        rows = packaging_rows(result.design.rig, result.vehicle, result.settings.rules.practice.lifted)
        assert any(share > 0 for row in rows for share in row["blocked_by_keep_outs"].values())
