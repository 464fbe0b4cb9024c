"""The five mount rules of :func:`rigopt.mounting.rules.check_rig`, each with a passing and a failing case.

The vehicles are written here (not the built-in ones): a box car, the box [-2, 2] x [-0.9, 0.9] x
[0.3, 1.5] m with a front zone and a mirrored side zone, and a step car, the box car plus a cabin
[-2, 0] x [-0.9, 0.9] x [1.4, 2.3] that makes a concave edge along x = 0, z = 1.5. The default housing
is 8 x 6 x 6 cm, so a well-mounted lens is 3 cm off the surface.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rigopt.mounting.records import CameraCheck, MountRules, RigCheck
from rigopt.mounting.rules import check_rig
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

from box_car import spec_text

BOX_CAR = spec_text("boxcar")

STEP = """
[[solids]]
name = "cabin"
type = "prism"
side = [[-2, 1.4], [0, 1.4], [0, 2.3], [-2, 2.3]]
plan = [[0, 0], [0, 0.9], [-2, 0.9], [-2, 0]]

[[zones]]
name = "step"
min = [-0.2, -1.0, 1.3]
max = [0.2, 1.0, 1.7]
normal = [1, 0, 1]
cone_deg = 50

[[zones]]
name = "nose"
min = [1.9, -1.0, 1.4]
max = [2.2, 1.0, 1.6]
normal = [1, 0, 1]
cone_deg = 50
"""


def _vehicle(folder, text: str) -> Vehicle:
    path = folder / "vehicle.toml"
    path.write_text(text)
    return Vehicle.from_spec(read_spec(path))


@pytest.fixture(scope="module")
def box_car(tmp_path_factory):
    return _vehicle(tmp_path_factory.mktemp("boxcar"), BOX_CAR)


@pytest.fixture(scope="module")
def step_car(tmp_path_factory):
    return _vehicle(tmp_path_factory.mktemp("stepcar"), BOX_CAR.replace('"boxcar"', '"stepcar"') + STEP)


def camera(camera_id, position, yaw_deg=0.0, pitch_deg=0.0, fov=60.0) -> Camera:
    rotation = rotation_from_yaw_pitch_roll(np.deg2rad(yaw_deg), np.deg2rad(pitch_deg), 0.0)
    return Camera.pinhole(camera_id, np.array(position, dtype=float), rotation, fov)


def check(vehicle, *cameras, rules=MountRules()) -> RigCheck:
    return check_rig(Rig("test", vehicle.name, cameras), vehicle, rules)


def only(result: RigCheck) -> CameraCheck:
    assert len(result.cameras) == 1
    return result.cameras[0]


def mentions(result: CameraCheck, word: str) -> bool:
    return any(word in problem for problem in result.problems)


FRONT = [2.03, 0.0, 1.0]  # 3 cm in front of the front face


# --- a good mount ------------------------------------------------------------------------------------------


def test_front_camera_looking_forward_is_valid(box_car):
    result = check(box_car, camera("F", FRONT))
    assert result.valid
    assert only(result).problems == ()


def test_check_reports_distance_and_zone(box_car):
    result = only(check(box_car, camera("F", FRONT)))
    assert result.id == "F"
    assert result.distance_to_surface == pytest.approx(0.03, abs=1e-6)
    assert result.zone == "front"


def test_rig_check_names_rig_and_vehicle(box_car):
    result = check(box_car, camera("F", FRONT))
    assert (result.rig, result.vehicle) == ("test", "boxcar")


def test_rig_is_invalid_when_one_camera_is(box_car):
    result = check(box_car, camera("F", FRONT), camera("IN", [1.9, 0.5, 1.0]))
    assert [c.valid for c in result.cameras] == [True, False]
    assert not result.valid


# --- rule 1: outside the body, close to it --------------------------------------------------------------


def test_camera_inside_the_body_is_invalid(box_car):
    result = only(check(box_car, camera("IN", [1.9, 0.0, 1.0])))
    assert not result.valid
    assert result.distance_to_surface == pytest.approx(-0.1, abs=1e-6)
    assert mentions(result, "inside")


def test_camera_floating_off_the_surface_is_invalid(box_car):
    result = only(check(box_car, camera("FAR", [2.2, 0.0, 1.0])))
    assert not result.valid
    assert mentions(result, "off the surface")
    assert result.problems == (result.problems[0],)  # nothing else is wrong with it


def test_camera_at_max_distance_is_valid(box_car):
    rules = MountRules()
    result = only(check(box_car, camera("F", [2.0 + rules.max_distance - 1e-4, 0.0, 1.0])))
    assert result.valid


def test_max_distance_is_a_rule_parameter(box_car):
    result = only(check(box_car, camera("F", FRONT), rules=MountRules(max_distance=0.02)))
    assert mentions(result, "off the surface")


# --- rule 2: housing penetration -------------------------------------------------------------------------


def test_camera_on_an_outer_edge_is_valid(step_car):
    d = 0.015 / np.sqrt(2)  # 1.5 cm off the front-top edge, diagonally
    result = only(check(step_car, camera("EDGE", [2.0 + d, 0.0, 1.5 + d])))
    assert not mentions(result, "penetrates")
    assert result.valid


def test_camera_in_an_inside_corner_penetrates(step_car):
    # 1.5 cm off both the roof and the cabin's front face: a 6 cm high housing cannot fit there
    result = only(check(step_car, camera("CORNER", [0.015, 0.0, 1.515], pitch_deg=20)))
    assert not result.valid
    assert result.zone == "step"
    assert mentions(result, "penetrates")


def test_camera_clear_of_the_inside_corner_is_valid(step_car):
    result = only(check(step_car, camera("ROOF", [0.2, 0.0, 1.53], pitch_deg=20)))
    assert result.valid, result.problems


def badge_car(folder, thickness: float) -> Vehicle:
    """The box car with a 2 x 2 cm badge standing ``thickness`` m proud of the front face, y in [0.03, 0.05], z in [0.99, 1.01]."""
    badge = f"""
[[solids]]
name = "badge"
type = "box"
center = [{2.0 + thickness / 2 - 0.05}, 0.04, 1.0]
size = [{thickness + 0.1}, 0.02, 0.02]
"""
    return _vehicle(folder, BOX_CAR + badge)


@pytest.fixture(scope="module")
def badge_5mm(tmp_path_factory):
    return badge_car(tmp_path_factory.mktemp("badge"), 0.005)


def test_housing_over_a_small_badge_is_within_tolerance(badge_5mm):
    # the housing's back face lies on the front face and overlaps the 5 mm badge: less than the 1 cm tolerance
    result = only(check(badge_5mm, camera("F", FRONT)))
    assert result.zone == "front"
    assert result.valid, result.problems


def test_housing_over_a_small_badge_penetrates_with_a_tight_tolerance(badge_5mm):
    result = only(check(badge_5mm, camera("F", FRONT), rules=MountRules(penetration_tolerance=0.002)))
    assert mentions(result, "penetrates")
    assert result.problems == (result.problems[0],)


def test_housing_over_a_thick_badge_penetrates(tmp_path):
    result = only(check(badge_car(tmp_path, 0.015), camera("F", FRONT)))
    assert result.distance_to_surface == pytest.approx(0.03, abs=1e-6)  # the badge is not the nearest surface
    assert mentions(result, "penetrates")


# --- rule 3: the near view frustum ---------------------------------------------------------------------


def test_camera_facing_into_the_body_is_invalid(box_car):
    result = only(check(box_car, camera("BACK", FRONT, yaw_deg=180)))
    assert not result.valid
    assert mentions(result, "view")


GRAZING = dict(position=[0.0, 0.93, 1.0], yaw_deg=40.0, fov=120.0)


def test_frustum_margin_keeps_a_grazing_view_valid(box_car):
    g = GRAZING
    result = only(check(box_car, camera("SIDE", g["position"], g["yaw_deg"], fov=g["fov"])))
    assert result.valid, result.problems


def test_frustum_margin_zero_checks_the_whole_view(box_car):
    g = GRAZING
    result = only(check(box_car, camera("SIDE", g["position"], g["yaw_deg"], fov=g["fov"]),
                        rules=MountRules(frustum_margin=0.0)))
    assert not result.valid
    assert mentions(result, "view")


def test_frustum_range_limits_the_view_check(box_car):
    # facing the body from 3 cm: a frustum that ends 2.5 cm ahead of the lens stays clear of it
    result = only(check(box_car, camera("BACK", FRONT, yaw_deg=180), rules=MountRules(frustum_range=0.025)))
    assert not mentions(result, "view")


# --- rule 4: zones -----------------------------------------------------------------------------------------


def test_camera_outside_every_zone_is_invalid(box_car):
    # 3 cm above the roof, which has no zone; looking up so that the view is clear
    result = only(check(box_car, camera("ROOF", [0.0, 0.0, 1.53], pitch_deg=30)))
    assert not result.valid
    assert result.zone is None
    assert result.problems == ("outside every mounting zone",)


def test_zone_needs_the_normal_cone_not_just_the_box(box_car):
    # the left side near the front, inside the front zone's box but with a sideways normal: the side zone
    result = only(check(box_car, camera("SIDE", [1.95, 0.93, 1.0], yaw_deg=60)))
    assert result.zone == "side"


def test_mirrored_zone_holds_the_right_side(box_car):
    result = only(check(box_car, camera("RIGHT", [0.0, -0.93, 1.0], yaw_deg=-90)))
    assert result.valid
    assert result.zone == "side"


# --- rule 5: housings of two cameras ------------------------------------------------------------------------


def test_two_cameras_2cm_apart_collide(box_car):
    result = check(box_car, camera("A", FRONT), camera("B", [2.03, 0.02, 1.0]))
    assert not result.valid
    a, b = result.cameras
    assert not a.valid and not b.valid
    assert mentions(a, "collides") and "B" in a.problems[-1]
    assert mentions(b, "collides") and "A" in b.problems[-1]


def test_two_cameras_of_one_module_share_a_housing(box_car):
    """A stereo pair or a roof cluster: cameras of one module do not clash with each other, but still do with a
    camera outside the module."""
    a, b = (replace(camera(k, p), module="stereo") for k, p in (("A", FRONT), ("B", [2.03, 0.02, 1.0])))
    assert check(box_car, a, b).valid
    c = camera("C", [2.03, -0.02, 1.0])
    result = check(box_car, a, b, c)
    assert not result.valid and mentions(result.cameras[2], "collides")
    clash = next(problem for problem in result.cameras[2].problems if "collides" in problem)
    assert [n for n in ("A", "B") if n in clash] == ["A", "B"]


def test_two_cameras_20cm_apart_are_one_module_or_refused(box_car):
    """Lenses closer than a module's size (0.25 m) share one housing: in housings of their own the later is refused,
    as one module both are valid; 0.3 m apart they may stand alone. (Different lenses: the same lens looking the
    same way this close would duplicate A, test_features.py.)"""
    a, b = camera("A", FRONT), camera("B", [2.03, 0.2, 1.0], fov=90.0)
    alone = check(box_car, a, b)
    assert alone.cameras[0].valid and not alone.cameras[1].valid
    assert alone.cameras[1].problems == ("0.200 m from A in a housing of its own: housings closer than 0.25 m are one "
                                         "module (give both the same module) or stand farther apart",)
    assert check(box_car, replace(a, module="pod"), replace(b, module="pod")).valid
    assert check(box_car, a, camera("B", [2.03, 0.3, 1.0], fov=90.0)).valid


def test_a_foot_on_a_degenerate_face_has_no_surface_and_no_housing_fits(badge_5mm):
    """A zero normal (a zero-area face of the mesh) gives no housing frame: the foot does not fit, it is not
    checked with a NaN box."""
    import warnings

    from rigopt.mounting.rules import housing_fits

    foot = np.array([[2.0, 0.0, 1.0], [2.0, 0.0, 1.0]])
    normals = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fits = housing_fits(badge_5mm, foot, normals)
    assert fits.tolist() == [True, False]
