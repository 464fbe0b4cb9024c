"""The four built-in vehicles fit the benchmark: size, zones, and every library rig mounted validly."""

import numpy as np
import pytest

from rigopt.mounting.rules import check_rig
from rigopt.rig.library import library_rig, rig_names
from rigopt.vehicle.library import find_spec, load_vehicle

BUILT_IN = {"etron": "vehicle.audi.etron", "tt": "vehicle.audi.tt", "firetruck": "vehicle.carlamotors.firetruck",
            "hgv": "vehicle.carlamotors.european_hgv"}
#: Rigs that deliberately move cameras away from the places their ids name.
ID_EXEMPT = {"R1-t"}


def expected_zone(camera_id: str) -> str:
    """The zone a benchmark camera id names (BUMPPER is R4's typo for BUMPER)."""
    words = camera_id.upper().replace("BUMPPER", "BUMPER").split("_")[1:]
    rear = "BACK" in words or "REAR" in words
    if "BUMPER" in words:
        return "bumper_rear" if rear else "bumper_front"
    if "FENDER" in words:
        return "fender_rear" if rear else "fender_front"
    if "SIDE" in words:
        return "b_pillar"
    if "MIRROR" in words:
        return "mirror"
    if "WINDSHIELD" in words:
        return "windshield_rear" if rear else "windshield_front"
    if "TOP" in words:
        return "roof_rear" if rear else "roof_front"
    return "bumper_rear" if rear else "bumper_front"


def test_expected_zone_reads_the_benchmark_ids():
    assert expected_zone("CAM_BUMPPER_FRONT_LEFT") == "bumper_front"
    assert expected_zone("CAM_BUMPER_REAR_RIGHT") == "bumper_rear"
    assert expected_zone("CAM_SIDE_LEFT") == "b_pillar"
    assert expected_zone("CAM_BACK_TOP") == "roof_rear"
    assert expected_zone("CAM_BACK") == "bumper_rear"
    assert expected_zone("CAM_WINDSHIELD_BACK") == "windshield_rear"


@pytest.mark.parametrize("name", sorted(BUILT_IN))
def test_names_blueprints_and_aliases_resolve(name):
    assert find_spec(name).name == name
    assert find_spec(BUILT_IN[name].upper()).name == name


@pytest.mark.parametrize("alias, name", [("suv", "etron"), ("sports", "tt")])
def test_obvious_aliases_resolve(alias, name):
    assert find_spec(alias).name == name


def required_size(name: str) -> np.ndarray:
    """The CARLA box, widened where the benchmark's own cameras lie outside it: every camera must be within
    5 cm of the surface, so the body reaches at least |y| - 0.05 m on each side (the trucks' mirror cameras
    sit 11 cm outside the box's half-width)."""
    vehicle = load_vehicle(name)
    box = np.array(vehicle.spec.box, dtype=float)
    for rig_name in rig_names():
        rig = library_rig(rig_name)
        if rig.vehicle.lower() == vehicle.blueprint.lower():
            y = rig.positions[:, 1]
            box[1] = max(box[1], (y.max() - 0.05) - (y.min() + 0.05))
    return box


@pytest.mark.parametrize("name", sorted(BUILT_IN))
def test_size_within_three_percent_of_the_carla_box(name):
    vehicle = load_vehicle(name)
    assert vehicle.mesh.is_watertight
    np.testing.assert_allclose(vehicle.size, required_size(name), rtol=0.03)


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(BUILT_IN))
def test_every_zone_selects_surface(name):
    vehicle = load_vehicle(name)
    fine = vehicle.fine_mesh
    for zone in vehicle.zones:
        assert zone.contains(fine.triangles_center, fine.face_normals).any(), zone.name


#: The benchmark drove its tractor unit solo: its rig is checked with the trailer keep-out lifted.
SOLO = {"R9"}


@pytest.mark.parametrize("rig_name", rig_names())
def test_library_rig_is_valid_on_its_vehicle(rig_name):
    from rigopt.mounting.records import MountPractice, MountRules

    rig = library_rig(rig_name)
    # the body-feature rules refuse some benchmark cameras: tests/mounting/test_practice.py lists which and why
    lifted = ("trailer",) if rig_name in SOLO else ()
    rules = MountRules(practice=MountPractice(lifted=lifted, features=False))
    result = check_rig(rig, load_vehicle(rig.vehicle), rules)
    problems = {c.id: c.problems for c in result.cameras if not c.valid}
    assert result.valid, problems


def test_r9_looks_into_a_coupled_trailer():
    """R9's cab-roof camera faces back over the fifth wheel: with a semi-trailer coupled it sees the trailer."""
    from rigopt.mounting.records import MountPractice, MountRules

    rig = library_rig("R9")
    rules = MountRules(practice=MountPractice(features=False))  # the fender cameras' width: test_practice.py
    flagged = {c.id: c.problems for c in check_rig(rig, load_vehicle(rig.vehicle), rules).cameras if not c.valid}
    assert list(flagged) == ["CAM_BACK_TOP"]
    assert "the keep-out trailer (a coupled semi-trailer) is in its view" in flagged["CAM_BACK_TOP"][0]


@pytest.mark.parametrize("rig_name", [n for n in rig_names() if n not in ID_EXEMPT])
def test_cameras_sit_in_the_zone_their_id_names(rig_name):
    rig = library_rig(rig_name)
    result = check_rig(rig, load_vehicle(rig.vehicle))
    wrong = {c.id: c.zone for c in result.cameras if c.zone != expected_zone(c.id)}
    assert not wrong, wrong
