"""The design pipeline (``design_rig``) end to end: the firetruck from R1 with the joint weights (one run,
module-scoped), and infeasible requirements on a box car written as a spec in tmp_path.

The result carries the MILP's rig (before the continuous refinement), so the MILP objective is checked
against the RigCD of the rig it chose.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import FrozenInstanceError, replace
from types import SimpleNamespace

import numpy as np
import pytest

from rigopt.coverage.measures import coverage_report
from rigopt.coverage.regulations import parse_require, region_coverage
from rigopt.mounting.practice import practice_problems
from rigopt.mounting.records import MountPractice
from rigopt.mounting.rules import check_rig
from rigopt.coverage.matrix import rig_coverage_matrix
from rigopt.design.designer import FIELD_EXTRA_CAMERAS, design_rig
from rigopt.design.requirements import reference_requirements as requirements
from rigopt.design.problem import ReferenceRig, benchmark_rigs
from rigopt.design.result import DesignResult
from rigopt.design.selection import DesignInfeasible
from rigopt.design.settings import DesignSettings
from rigopt.errors import RigoptError
from rigopt.metrics.calibration import load_weights
from rigopt.metrics.rigcd import rigcd
from rigopt.rig.library import load_rig
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.library import load_vehicle
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec
from rigopt.vehicle.symmetry import rig_symmetry

from box_car import BOX_ZONES, ROOF_ZONE, spec_text

BOX_CAR = spec_text("designbox", zones=BOX_ZONES + ROOF_ZONE)

UNCOVERED = re.compile(r"ring (?P<distance>[\d.]+) m at height (?P<height>[\d.]+) m, azimuth (?P<azimuth>[+-]\d+) deg")


@pytest.fixture(scope="module")
def firetruck():
    vehicle, reference, calibration = load_vehicle("firetruck"), load_rig("R1"), load_weights("joint")
    result = design_rig(vehicle, ReferenceRig.on_own_vehicle(reference), calibration, DesignSettings(),
                        compare_with=benchmark_rigs(vehicle))  # the bare designer (no pose preset)
    return SimpleNamespace(vehicle=vehicle, reference=reference, calibration=calibration, result=result,
                           design=result.design, milp_rig=result.milp.rig, settings=DesignSettings())


@pytest.fixture(scope="module")
def box_car(tmp_path_factory) -> Vehicle:
    path = tmp_path_factory.mktemp("designbox") / "vehicle.toml"
    path.write_text(BOX_CAR)
    return Vehicle.from_spec(read_spec(path))


def r1_on_its_vehicle() -> ReferenceRig:
    return ReferenceRig.on_own_vehicle(load_rig("R1"))


def front_reference(box_car: Vehicle) -> ReferenceRig:
    """One 100-degree camera on the box car's front, looking ahead: a reference that asks nothing behind."""
    rig = Rig("boxref", box_car.blueprint, (Camera.pinhole("F", np.array([2.04, 0.0, 1.0]), np.eye(3), 100.0),))
    return ReferenceRig(rig, box_car)


def weighted_rigcd(run, rig) -> float:
    return rigcd(run.reference, rig, run.calibration.alpha, run.calibration.lambdas).rigcd


# --- the firetruck design from R1 ---------------------------------------------------------------------


@pytest.mark.slow
def test_every_design_camera_passes_the_mount_checks(firetruck):
    check = check_rig(firetruck.design.rig, firetruck.vehicle)
    assert check.valid, [(c.id, c.problems) for c in check.cameras if not c.valid]


@pytest.mark.slow
def test_design_is_for_the_target_vehicle(firetruck):
    assert firetruck.design.rig.vehicle == "vehicle.carlamotors.firetruck"


@pytest.mark.slow
def test_design_meets_the_coverage_requirements(firetruck):
    assert firetruck.design.meets_requirements


@pytest.mark.slow
def test_recomputed_coverage_meets_the_requirements_at_every_sector_point(firetruck):
    needed = requirements(firetruck.reference, firetruck.result.references[0].vehicle, firetruck.settings)
    assert needed.sum() > 0  # R1 sees most of the rings: the requirement is not empty
    counts = rig_coverage_matrix(firetruck.design.rig, firetruck.vehicle, firetruck.settings.coverage).sees.sum(axis=0)
    assert counts.shape == needed.shape
    assert np.all(counts >= needed), np.flatnonzero(counts < needed)


@pytest.mark.slow
def test_design_predicts_a_smaller_drop_than_the_benchmark_rig_r6(firetruck):
    r6 = [s for s in firetruck.result.comparisons.rigs if s.rig.name == "R6"]
    assert len(r6) == 1
    assert firetruck.design.prediction.predicted_drop < r6[0].prediction.predicted_drop


@pytest.mark.slow
def test_design_rigcd_is_the_calibrated_rigcd_to_the_reference(firetruck):
    # the distance compares the perception cameras: the near-field ones are not fed to the detector
    rig = firetruck.design.rig
    assert rig.near_field_count >= 1
    assert abs(firetruck.design.prediction.rigcd - weighted_rigcd(firetruck, rig.perception())) <= 1e-9


@pytest.mark.slow
def test_milp_objective_is_the_rigcd_of_the_rig_it_chose(firetruck):
    """The MILP's matching is an optimal one: its objective equals RigCD (optimal assignment) of its rig."""
    assert abs(firetruck.result.milp.selection.objective - weighted_rigcd(firetruck, firetruck.milp_rig)) <= 1e-6


@pytest.mark.slow
def test_the_refinement_lowers_the_milps_rigcd_and_its_rig_is_the_design(firetruck):
    """The library's default settings on the fire truck: IPOPT moves all 8 perception cameras and lowers RigCD
    (1.892 -> 1.860), so the refined rig is the design."""
    objective, value = firetruck.result.milp.selection.objective, firetruck.design.prediction.rigcd
    refinement = firetruck.result.refinement
    assert refinement.accepted and refinement.status.startswith("accepted: IPOPT Solve_Succeeded")
    assert value < objective - 1e-3  # kept because it lowers the RigCD
    assert same_poses(firetruck.design.rig.perception(), refinement.refined.rig)
    assert refinement.cameras_moved == len(firetruck.design.rig.perception()) == 8
    assert not same_poses(firetruck.design.rig.perception(), firetruck.milp_rig)


def same_poses(a: Rig, b: Rig) -> bool:
    """The same cameras at the same poses (a near-field camera sharing a housing sets only ``module``)."""
    return [c.id for c in a.cameras] == [c.id for c in b.cameras] and np.array_equal(a.positions, b.positions) \
        and all(np.array_equal(p.rotation, q.rotation) for p, q in zip(a.cameras, b.cameras))


@pytest.mark.slow
def test_milp_solved_to_optimality(firetruck):
    milp = firetruck.result.milp
    assert milp.status == milp.selection.status == "optimal"
    assert 0.0 <= milp.gap <= DesignSettings().mip_gap
    assert 0 < milp.n_offered <= milp.n_candidates
    assert milp.check.valid and milp.repairs == 0  # no selected camera failed the mount checks


@pytest.mark.slow
def test_design_has_the_references_perception_camera_count_and_near_field_cameras_beside(firetruck):
    # two roles by default: R1's 8 perception cameras, the near-field fisheyes for the firetruck's fields
    rig = firetruck.design.rig
    assert len(rig.perception()) == len(firetruck.reference) == len(firetruck.milp_rig)
    assert rig.near_field_count >= 1
    assert all(c.lens.distortion == "fisheye" for c in rig.cameras if c.role == "near_field")


@pytest.mark.slow
def test_design_cameras_are_named_after_where_they_are_mounted_and_look(firetruck):
    from rigopt.design.naming import look_of

    rig = firetruck.milp_rig
    assert len({c.id for c in rig.cameras}) == len(rig)
    for camera in rig.cameras:
        assert camera.id.startswith(f"CAM_{camera.zone.upper()}")
        assert f"_TO_{look_of(camera.forward)}" in camera.id


@pytest.mark.slow
def test_naive_transfer_has_one_camera_per_reference_camera(firetruck):
    naive = firetruck.result.comparisons.naive_transfer
    assert naive is not None
    assert len(naive.rig) == len(firetruck.reference)
    assert [c.id for c in naive.rig.cameras] == [c.id for c in firetruck.reference.cameras]


@pytest.mark.slow
def test_naive_transfer_keeps_each_reference_lens_on_the_catalogue(firetruck):
    lenses = np.asarray(firetruck.settings.fovs)
    for moved, original in zip(firetruck.result.comparisons.naive_transfer.rig.cameras, firetruck.reference.cameras):
        assert moved.fov == lenses[np.argmin(np.abs(lenses - original.fov))]


@pytest.mark.slow
def test_height_matched_transfer_keeps_each_camera_nearest_its_height(firetruck):
    from rigopt.design.designer import HEIGHT_STEP, mount_candidates, naive_transfer

    settings = dataclasses.replace(firetruck.settings, symmetric=False)
    candidates = mount_candidates(firetruck.vehicle, settings)
    naive = naive_transfer(firetruck.vehicle, firetruck.reference, candidates, settings)
    matched = naive_transfer(firetruck.vehicle, firetruck.reference, candidates, settings, match="height")
    assert matched.name.startswith("height_matched_") and len(matched) == len(firetruck.reference)
    def gap(rig):
        return np.array([abs(c.position[2] - r.position[2]) for c, r in zip(rig.cameras, firetruck.reference.cameras)])

    def yaw(camera):
        return np.arctan2(camera.forward[1], camera.forward[0])

    assert (gap(matched) <= gap(naive) + HEIGHT_STEP).all() and gap(matched).sum() < gap(naive).sum()
    for moved, original in zip(matched.cameras, firetruck.reference.cameras):  # facing as the reference camera
        turn = abs(np.angle(np.exp(1j * (yaw(moved) - yaw(original)))))
        assert np.degrees(turn) <= settings.yaw_step_deg / 2 + 1e-6


@pytest.mark.slow
def test_design_cameras_come_in_mirrored_pairs_or_sit_on_the_centreline(firetruck):
    for rig in (firetruck.milp_rig, firetruck.design.rig):
        symmetry = rig_symmetry(rig)
        assert symmetry.symmetric, symmetry.describe()
        assert len(symmetry.pairs) >= 2
        # the firetruck's right side stands up to 6 cm further out than its left: pairs differ by that in |y|
        assert symmetry.largest_offset <= 0.07
        by_id = {c.id: c for c in rig.cameras}
        for left, right in symmetry.pairs:
            a, b = by_id[left], by_id[right]
            assert a.position[[0, 2]] == pytest.approx(b.position[[0, 2]], abs=0.01)  # each on its own side's body
            assert a.fov == b.fov
            assert np.arctan2(a.forward[1], a.forward[0]) == pytest.approx(-np.arctan2(b.forward[1], b.forward[0]),
                                                                           abs=1e-6)
        for name in symmetry.centreline:
            assert abs(by_id[name].position[1]) <= 1e-9


@pytest.mark.slow
def test_design_mounts_only_where_practice_allows(firetruck):
    rig = firetruck.design.rig
    assert np.all(rig.positions[:, 2] >= 0.5)
    assert not any(practice_problems(firetruck.vehicle, rig.positions, MountPractice()))


@pytest.mark.slow
def test_design_sees_the_near_field_at_least_as_well_as_r6(firetruck):
    r6 = next(s.rig for s in firetruck.result.comparisons.rigs if s.rig.name == "R6")
    ours, theirs = (coverage_report(rig, firetruck.vehicle) for rig in (firetruck.design.rig, r6))
    ring = [k for k, r in enumerate(ours.rings) if (r.distance_m, r.height_m) == (2.0, 0.0)][0]
    assert ours.rings[ring].covered_frac >= theirs.rings[ring].covered_frac
    assert ours.blind.area_m2 <= theirs.blind.area_m2


@pytest.mark.slow
def test_design_predicts_at_most_seven_tenths_of_r6s_linear_drop(firetruck):
    r6 = next(s for s in firetruck.result.comparisons.rigs if s.rig.name == "R6")
    assert firetruck.design.prediction.linear_drop <= 0.7 * r6.prediction.linear_drop


@pytest.mark.slow
def test_an_asymmetric_design_is_no_worse_in_rigcd_than_the_symmetric_one(firetruck):
    # the symmetric MILP's feasible set is a subset of the free one's (on the free candidate set's superset of
    # mount points); here only the MILP stage is compared
    free = design_rig(firetruck.vehicle, r1_on_its_vehicle(), firetruck.calibration,
                      DesignSettings(symmetric=False, refine=False))
    assert not rig_symmetry(free.design.rig).symmetric
    assert free.milp.selection.objective <= firetruck.result.milp.selection.objective + 1e-9


@pytest.mark.slow
def test_benchmark_rigs_are_the_library_rigs_of_the_target_vehicle(firetruck):
    names = [s.rig.name for s in firetruck.result.comparisons.rigs]
    assert "R6" in names
    assert all(s.rig.vehicle == "vehicle.carlamotors.firetruck" for s in firetruck.result.comparisons.rigs)
    assert firetruck.result.comparisons.best_rig.prediction.predicted_drop == min(
        s.prediction.predicted_drop for s in firetruck.result.comparisons.rigs)


@pytest.mark.slow
def test_the_result_carries_its_inputs(firetruck):
    result = firetruck.result
    assert isinstance(result, DesignResult)
    assert result.vehicle is firetruck.vehicle and result.calibration is firetruck.calibration
    assert [r.rig for r in result.references] == [firetruck.reference]
    assert result.references[0].vehicle.blueprint == firetruck.reference.vehicle
    assert replace(result.settings, symmetric=None) == DesignSettings()  # the symmetry it resolved to is kept
    assert result.settings.symmetric is True
    with pytest.raises(FrozenInstanceError):
        result.seconds = 0.0


def test_the_designer_compares_only_with_the_rigs_it_is_given(box_car):
    """No hidden lookups: without ``compare_with`` there is nothing to compare with but the naive transfer,
    and the reference's coverage is measured on the vehicle passed with it (here the box car itself)."""
    settings = DesignSettings(lenses=(100.0,), pitches_deg=(0.0,), yaw_step_deg=30.0, refine=False,
                              zones=("front",), near_field=False)
    result = design_rig(box_car, front_reference(box_car), load_weights("joint"), settings)
    assert result.comparisons.rigs == ()
    assert result.comparisons.best_rig is None
    assert result.references[0].vehicle is box_car
    assert result.refinement.status == "off" and not result.refinement.accepted
    assert len(result.design.rig) == 1 and result.design.meets_requirements


# --- infeasible requirements --------------------------------------------------------------------------


def uncovered_sectors(message: str) -> list[tuple[float, float, int]]:
    return [(float(m["distance"]), float(m["height"]), int(m["azimuth"])) for m in UNCOVERED.finditer(message)]


def test_roof_patch_only_cannot_see_the_rings(box_car):
    """From the middle of the roof (1.53 m, 0.6 m from its edges) the roof hides every ring point at
    heights 0 and 0.8 m that R1 requires: the designer says which ring sectors and what to change."""
    settings = DesignSettings(zones=("roof",), lenses=(60.0,), pitches_deg=(0.0, 10.0, 20.0), yaw_step_deg=30.0)
    with pytest.raises(DesignInfeasible) as error:
        design_rig(box_car, r1_on_its_vehicle(), load_weights("joint"), settings)
    message = str(error.value)
    assert "ring" in message and "azimuth" in message
    sectors = uncovered_sectors(message)
    assert sectors
    centres = {int(round(a)) for a in np.rad2deg(settings.coverage.azimuths(settings.coverage.sectors))}
    for distance, height, azimuth in sectors:
        assert distance in settings.coverage.ring_distances
        assert height in settings.coverage.ring_heights
        assert azimuth in centres
    assert "zones" in message  # what to change


def test_front_zone_only_leaves_the_rear_unseen(box_car):
    """Cameras on the front face cannot see through the body: the uncovered sectors are behind the car."""
    settings = DesignSettings(zones=("front",), lenses=(60.0,), yaw_step_deg=30.0)
    with pytest.raises(DesignInfeasible) as error:
        design_rig(box_car, r1_on_its_vehicle(), load_weights("joint"), settings)
    sectors = uncovered_sectors(str(error.value))
    assert sectors
    assert all(abs(azimuth) > 90 for _, _, azimuth in sectors), sectors


def test_triple_coverage_with_narrow_lenses_is_infeasible(box_car):
    """8 cameras of 30 deg cannot see every ring sector three times."""
    settings = DesignSettings(min_coverage=3, lenses=(30.0,), yaw_step_deg=30.0)
    with pytest.raises(DesignInfeasible) as error:
        design_rig(box_car, r1_on_its_vehicle(), load_weights("joint"), settings)
    message = str(error.value)
    assert "--cameras" in message or "--min-coverage" in message  # what to change


def test_design_infeasible_is_an_input_error_for_the_cli():
    assert issubclass(DesignInfeasible, RigoptError)


# --- regulation fields ------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def box_car_with_front_field(box_car):
    settings = DesignSettings(require="r159", lenses=(90.0, 120.0), yaw_step_deg=30.0, pitches_deg=(-20.0, 0.0),
                              refine=False, near_field=False)  # one camera set sees the field
    return design_rig(box_car, r1_on_its_vehicle(), load_weights("joint"), settings), settings


def test_a_required_field_is_seen_at_every_dense_point(box_car, box_car_with_front_field):
    result, settings = box_car_with_front_field
    assert [r.key for r in result.regions] == ["r159"]
    assert result.regions[0].covered and result.regions[0].covered_frac == 1.0
    again = region_coverage(result.design.rig, box_car, parse_require("r159", box_car), spacing=0.1)
    assert again[0].covered
    assert len(result.design.rig) <= len(load_rig("R1")) + FIELD_EXTRA_CAMERAS  # near-field cameras beyond the count


@pytest.mark.slow
def test_the_categorys_fields_are_required_and_seen_by_default(firetruck):
    assert [r.key for r in firetruck.result.regions] == ["r151", "r159", "r158"]  # N3 defaults
    assert firetruck.result.settings.require is None and firetruck.result.fields_fallback is None
    assert all(r.covered for r in firetruck.result.regions)
    # two roles by default: the near-field cameras alone see the fields, the perception cameras are R1's count
    rig = firetruck.design.rig
    assert firetruck.result.near_field.status == "optimal" and rig.near_field_count >= 1
    assert len(rig.perception()) == len(firetruck.reference)
    alone = region_coverage(Rig(rig.name, rig.vehicle, tuple(c for c in rig.cameras if c.role == "near_field"),
                                rig.origin),
                            firetruck.vehicle, parse_require("default", firetruck.vehicle), spacing=0.25)
    assert all(r.covered for r in alone)


@pytest.mark.parametrize("near_field", [False, True], ids=["one-set", "two-role"])
def test_fields_no_design_sees_are_dropped_with_a_note_and_reported(box_car, near_field):
    # cameras on the box car's front only: nothing sees the r158 field behind it; by default the design goes on
    settings = DesignSettings(lenses=(100.0, 120.0), yaw_step_deg=30.0, pitches_deg=(-20.0, 0.0), refine=False,
                              near_field=near_field, zones=("front",))
    result = design_rig(box_car, front_reference(box_car), load_weights("joint"), settings)
    assert "r158" in result.fields_fallback and "reported, not required" in result.fields_fallback
    assert result.settings.require == "none"
    assert [r.key for r in result.regions] == ["r158"] and not result.regions[0].covered
    with pytest.raises(DesignInfeasible, match="r158 field"):  # named, the field is strict
        design_rig(box_car, front_reference(box_car), load_weights("joint"), replace(settings, require="r158"))
    if near_field:  # the near ring behind the box is reported as unseeable, not asked
        assert result.near_field.ring_unseeable and result.near_field.status == "optimal"


@pytest.mark.slow
@pytest.mark.parametrize("near_field", [False, True], ids=["one-set", "two-role"])
def test_a_design_whose_fields_were_dropped_is_the_design_without_fields(box_car, near_field):
    settings = DesignSettings(lenses=(100.0, 120.0), yaw_step_deg=30.0, pitches_deg=(-20.0, 0.0), near_field=near_field,
                              zones=("front",))
    dropped = design_rig(box_car, front_reference(box_car), load_weights("joint"), settings)
    without = design_rig(box_car, front_reference(box_car), load_weights("joint"), replace(settings, require="none"))
    assert dropped.fields_fallback and without.fields_fallback is None
    assert dropped.refinement.status == without.refinement.status  # the dropped field does not veto the refinement
    assert dropped.design.prediction.rigcd == pytest.approx(without.design.prediction.rigcd, abs=1e-9)


def test_an_unseeable_field_point_is_named_with_the_field(box_car):
    settings = DesignSettings(zones=("front",), require="r158", lenses=(60.0,), yaw_step_deg=30.0, refine=False,
                              min_coverage=0, near_field=False)
    with pytest.raises(DesignInfeasible, match=r"r158 field at x .* height .*--require|ring"):
        design_rig(box_car, r1_on_its_vehicle(), load_weights("joint"), settings)


@pytest.mark.slow
def test_a_camera_may_slide_only_as_far_as_its_disc_stays_mountable(firetruck):
    from rigopt.design.refine import free_radii
    from rigopt.mounting.practice import on_wheels
    from rigopt.mounting.records import MountPractice, MountRules
    from rigopt.mounting.sampling import sample_zone_points

    vehicle, reach = firetruck.vehicle, 0.3
    # without the body-feature rules the samples reach the wheel arches' lips (the rules keep mounts off them)
    points, normals, zones = sample_zone_points(vehicle, 0.4, rules=MountRules(practice=MountPractice(features=False)))
    cameras = tuple(Camera.pinhole(f"c{k}", p, np.eye(3), 60.0, zone=z) for k, (p, z) in enumerate(zip(points, zones)))
    radii = free_radii(Rig("r", "x", cameras), normals, vehicle, reach)
    assert np.all((radii >= 0) & (radii <= reach))
    assert np.any(radii > 0) and np.any(radii < reach)
    # a lens less than the reach from a wheel's keep-out (its arch) cannot slide the whole reach
    near_wheel = np.array([bool(w) for w in on_wheels(vehicle, points, 0.05 + reach)])
    assert near_wheel.any() and np.all(radii[near_wheel] < reach)


@pytest.mark.slow
def test_the_naive_transfer_is_refined_as_the_design_is(firetruck):
    from rigopt.design.designer import mount_candidates, naive_transfer

    status = firetruck.result.comparisons.naive_refinement
    assert status.startswith("accepted: IPOPT Solve_Succeeded")  # the default fire truck's, deterministic
    settings = firetruck.result.settings
    unrefined = naive_transfer(firetruck.vehicle, firetruck.reference, mount_candidates(firetruck.vehicle, settings),
                               settings)
    refined = firetruck.result.comparisons.naive_transfer.rig
    assert [c.id for c in refined.cameras] == [c.id for c in unrefined.cameras]
    before, after = weighted_rigcd(firetruck, unrefined), weighted_rigcd(firetruck, refined)
    assert after < before  # accepted only when it lowers the calibrated RigCD


@pytest.mark.slow
def test_naive_transfer_past_a_trailer_takes_the_nearest_yaw_a_mount_allows():
    """No mount on the hgv may look straight back (the trailer): R1's rear camera takes the nearest yaw."""
    from rigopt.design.designer import mount_candidates, naive_transfer
    from rigopt.design.settings import DesignSettings
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.library import load_vehicle

    vehicle, reference = load_vehicle("hgv"), load_rig("R1")
    settings = DesignSettings(symmetric=False, require="none")
    candidates = mount_candidates(vehicle, settings)
    allowed = np.abs(np.angle(np.exp(1j * (candidates.yaws - np.pi))))
    assert allowed.min() > np.radians(settings.yaw_step_deg) / 2  # nothing faces straight back
    naive = naive_transfer(vehicle, reference, candidates, settings)
    assert naive is not None and len(naive) == len(reference)
    rear = naive.cameras[[c.id for c in reference.cameras].index("CAM_BUMPER_BACK")]
    assert abs(np.angle(np.exp(1j * (np.arctan2(rear.forward[1], rear.forward[0]) - np.pi)))) == pytest.approx(
        allowed[candidates.fovs == rear.fov].min(), abs=1e-6)


# --- the near-field stage in a background worker ------------------------------------------------------------------

def camera_values(rig: Rig) -> list:
    return [(c.id, c.role, c.module, c.zone, c.position.tolist(), c.rotation.tolist(), c.fov) for c in rig.cameras]


@pytest.mark.slow
@pytest.mark.parametrize("zones", [("front",), None], ids=["fields-dropped", "fields-seen"])
def test_a_design_with_a_background_worker_is_the_inline_design(box_car, zones):
    """The near-field stage and the naive transfer's refinement run in a worker process give the design they give
    inline: the same cameras to the bit, the same fallback note and the same progress messages in the same order."""
    from rigopt.background import Background

    settings = DesignSettings(lenses=(100.0, 120.0), yaw_step_deg=30.0, pitches_deg=(-20.0, 0.0), near_field=True,
                              zones=zones)
    said_inline, said_beside = [], []
    inline = design_rig(box_car, front_reference(box_car), load_weights("joint"), settings,
                        progress=said_inline.append)
    with Background(workers=True) as background:
        assert background.parallel
        beside = design_rig(box_car, front_reference(box_car), load_weights("joint"), settings,
                            progress=said_beside.append, background=background)
    assert camera_values(beside.design.rig) == camera_values(inline.design.rig)
    assert beside.design.rig.near_field_count == inline.design.rig.near_field_count >= 1
    assert beside.fields_fallback == inline.fields_fallback and said_beside == said_inline
    assert (beside.near_field.status, beside.near_field.n_points) == (inline.near_field.status,
                                                                       inline.near_field.n_points)
    naive, naive_beside = inline.comparisons.naive_transfer, beside.comparisons.naive_transfer
    assert camera_values(naive_beside.rig) == camera_values(naive.rig)
    assert beside.comparisons.naive_refinement == inline.comparisons.naive_refinement != "off"


def test_a_near_field_choice_for_another_symmetry_is_made_again(box_car):
    """A choice computed ahead for the first attempt's symmetry is not taken by a design that fell back to
    another: the stage is designed again for the symmetry it has."""
    from rigopt.design import designer
    from rigopt.design.near_field import NearFieldChoice

    settings = DesignSettings(lenses=(100.0,), yaw_step_deg=30.0, pitches_deg=(0.0,), refine=False, near_field=True,
                              zones=("front",), require="none", symmetric=False)
    stale = NearFieldChoice((), 0, 0, "stale", 0.0, 0.0, 1)
    job = SimpleNamespace(result=lambda: (stale, (), None, True, ("stale message",)))
    said = []
    stage, _, _ = designer._near_field_stage(box_car, front_reference(box_car).rig, (), None, settings, "none",
                                             said.append, job)
    assert stage.status != "stale" and "stale message" not in said
    fresh, _, _ = designer._near_field_stage(box_car, front_reference(box_car).rig, (), None, settings, "none",
                                             lambda message: None)
    assert camera_values(stage.rig) == camera_values(fresh.rig)


@pytest.mark.slow
def test_each_perception_camera_names_the_reference_camera_it_was_designed_for(firetruck):
    """The designer's own pairing reaches the result: every perception camera, in order, with one of R1's cameras
    each (eight for eight), whatever RigCD's matching of the final rig says."""
    result = firetruck.result
    perception = [c.id for c in result.design.rig.cameras if c.role == "perception"]
    assert [camera for camera, _ in result.stand_ins] == perception
    assert sorted(reference for _, reference in result.stand_ins) == sorted(c.id for c in firetruck.reference.cameras)
