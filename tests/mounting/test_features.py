"""Mounting rules an engineer would sign (rigopt/mounting/features.py, the rig-level duplicate rule in
rigopt/mounting/practice.py): each rule on a hand-made vehicle, one lens that breaks it and one that does not.

The box truck: a 4 x 1.8 m body (x in [-2, 2], |y| <= 0.9, z in [0.3, 1.5]) with rectangular wheel arches
(x 0.8..1.6 and -1.6..-0.8, up to z 0.8) over wheels of radius 0.35 on axles at x +-1.2 (track 1.5), a rear
step, a hinged side door, a roof rail, a locker sticking out to |y| 1.25, a mirror head out to |y| 1.30, a
windscreen zone on the front face, a cab that tilts about its lower front edge over a bull bar, and a coupled
trailer. Lenses sit 3 cm off the surface as a housing puts them.
"""

from __future__ import annotations

import textwrap

import numpy as np
import pytest

from rigopt.errors import DataError
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.mounting import features
from rigopt.mounting.practice import duplicates, practical, practice_problems
from rigopt.mounting.records import MountPractice, MountRules
from rigopt.mounting.rules import check_rig
from rigopt.mounting.sampling import sample_zone_points
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import spec_from_dict, read_spec

BOX_TRUCK = """
name = "boxtruck"
blueprint = "vehicle.test.boxtruck"

[[solids]]
name = "body"
type = "prism"
side = [[-2, 0.3], [-1.6, 0.3], [-1.6, 0.8], [-0.8, 0.8], [-0.8, 0.3], [0.8, 0.3], [0.8, 0.8], [1.6, 0.8],
        [1.6, 0.3], [2, 0.3], [2, 1.5], [-2, 1.5]]
plan = [[2, 0], [2, 0.9], [-2, 0.9], [-2, 0]]

[[solids]]
type = "wheels"
axles = [1.2, -1.2]
radius = 0.35
width = 0.25
track = 1.5

[[solids]]
name = "rear_step"
type = "box"
center = [-2.15, 0.0, 0.65]
size = [0.3, 1.6, 0.2]

[[solids]]
name = "roof_rail"
type = "box"
center = [0.0, 0.7, 1.55]
size = [2.0, 0.04, 0.1]
mirrored = true

[[solids]]
name = "locker"
type = "box"
center = [-0.4, 0.0, 1.0]
size = [0.6, 2.5, 0.8]

[[solids]]
name = "mirror_head"
type = "box"
center = [1.7, 1.2, 1.3]
size = [0.1, 0.2, 0.2]
mirrored = true

[[solids]]
name = "bull_bar"
type = "box"
center = [2.15, 0.0, 1.1]
size = [0.1, 1.2, 0.4]

[[zones]]
name = "mirror"
min = [1.6, 1.05, 1.15]
max = [1.8, 1.4, 1.45]
normal = [0, 1, 0]
cone_deg = 90
mirrored = true

[[zones]]
name = "windshield_front"
min = [1.9, -1.0, 0.9]
max = [2.1, 1.0, 1.6]
normal = [1, 0, 0]
cone_deg = 45

[[zones]]
name = "side"
min = [-2.1, 0.8, 0.2]
max = [2.1, 1.4, 1.6]
normal = [0, 1, 0]
cone_deg = 45
mirrored = true

[[zones]]
name = "rear"
min = [-2.4, -1.0, 0.2]
max = [-1.9, 1.0, 1.6]
normal = [-1, 0, 0]
cone_deg = 45

[[zones]]
name = "roof"
min = [-2.0, -1.0, 1.4]
max = [2.0, 1.0, 1.7]
normal = [0, 0, 1]
cone_deg = 30

[[steps]]
name = "rear step"
min = [-2.3, -0.8, 0.55]
max = [-2.0, 0.8, 0.75]

[[door_frames]]
name = "side door"
min = [0.0, 0.85, 0.8]
max = [0.7, 0.95, 1.4]
frame = 0.05
hinge = "front"
mirrored = true

[[fixtures]]
name = "roof rail"
kind = "rail"
min = [-1.0, 0.68, 1.5]
max = [1.0, 0.72, 1.6]
mirrored = true

[wiped_area]
zone = "windshield_front"
outline = [[-0.5, 1.0], [0.5, 1.0], [0.5, 1.4], [-0.5, 1.4]]

[tilt_cab]
pivot = [2.0, 0.9]
angle_deg = 60
min = [1.0, -0.95, 0.9]
max = [2.0, 0.95, 1.5]

[[keep_out]]
name = "trailer"
reason = "a coupled semi-trailer"
min = [-8.0, -0.9, 0.0]
max = [-2.5, 0.9, 3.0]
optional = true
occludes = true
kingpin = [-3.5, 0.0, 1.0]
"""


def _truck(folder, text: str = BOX_TRUCK) -> Vehicle:
    path = folder / "vehicle.toml"
    path.write_text(textwrap.dedent(text))
    return Vehicle.from_spec(read_spec(path))


@pytest.fixture(scope="module")
def truck(tmp_path_factory) -> Vehicle:
    return _truck(tmp_path_factory.mktemp("boxtruck"))


def problems_at(vehicle, point, practice=MountPractice()) -> list[str]:
    return practice_problems(vehicle, [point], practice)[0]


def mentions(problems, *words) -> bool:
    return any(all(w in p for w in words) for p in problems)


def camera(camera_id, position, yaw_deg=0.0, pitch_deg=0.0, fov=60.0, module=None) -> Camera:
    rotation = rotation_from_yaw_pitch_roll(np.deg2rad(yaw_deg), np.deg2rad(pitch_deg), 0.0)
    return Camera.pinhole(camera_id, np.array(position, dtype=float), rotation, fov, module=module)


# --- steps and tailboards -------------------------------------------------------------------------------------


def test_a_lens_on_the_step_is_refused_with_its_height(truck):
    found = problems_at(truck, [-2.33, 0.0, 0.65])
    assert "on the rear step (walkable) at 0.65 m" in found


def test_a_lens_on_the_rear_face_above_the_step_is_not_on_it(truck):
    assert not mentions(problems_at(truck, [-2.03, 0.0, 1.2]), "walkable")


# --- door frames and hinge lines --------------------------------------------------------------------------------


def test_a_lens_on_the_door_s_shut_line_is_in_its_frame(truck):
    found = problems_at(truck, [0.03, 0.93, 1.1])
    assert "in the frame of the side door (0.03 m from its edge)" in found


def test_a_lens_beside_the_door_s_edge_is_in_its_frame_too(truck):
    assert mentions(problems_at(truck, [-0.03, -0.93, 1.1]), "in the frame of the side door")  # the mirrored door


def test_a_lens_by_the_hinged_edge_is_on_the_hinge_line(truck):
    found = problems_at(truck, [0.64, 0.93, 1.1])
    assert mentions(found, "on the hinge line of the side door (0.06 m from it)")
    assert not mentions(found, "in the frame")  # the hinge is said instead


def test_a_lens_in_the_middle_of_the_door_is_allowed(truck):
    assert problems_at(truck, [0.3, 0.93, 1.1]) == []


# --- rails, ladders, light bars, racks --------------------------------------------------------------------------


def test_a_lens_on_the_roof_rail_is_refused_and_one_on_the_roof_is_not(truck):
    rail = "on the roof rail (a rail: held and climbed on, no face for a housing)"
    assert rail in problems_at(truck, [0.0, 0.7, 1.63])
    assert problems_at(truck, [0.0, 0.0, 1.53]) == []


# --- wheel-arch lips and tyre spray -----------------------------------------------------------------------------


def test_the_arch_is_traced_where_the_body_leaves_it(truck):
    arch = next(a for a in truck.wheel_arches if a.name == "front-left wheel")
    up = arch.edge_at(np.array([0.0]))[0]
    assert up == pytest.approx(0.8 - 0.35, abs=1e-6)  # the arch's top at z 0.8 over the axle at 0.35
    forward = arch.edge_at(np.array([np.pi / 2]))[0]
    assert forward == pytest.approx(0.4, abs=1e-6)  # its front wall at x 1.6, 0.4 m ahead of the axle


def test_a_lens_just_above_the_arch_is_on_its_lip(truck):
    found = problems_at(truck, [1.2, 0.93, 0.83])
    assert "on the wheel-arch lip of the front-left wheel (0.03 m from the arch's edge, at least 0.05 m)" in found


def test_a_lens_well_above_the_arch_is_off_its_lip(truck):
    assert not mentions(problems_at(truck, [1.2, 0.93, 1.0]), "wheel-arch lip")


def test_a_low_lens_behind_a_tyre_is_in_its_spray_cone(truck):
    lens = [-0.3, 0.93, 0.55]
    offset = np.array(lens) - [1.2, 0.75, 0.0]  # from the front-left tyre's contact patch
    jet = [-np.cos(np.deg2rad(15.0)), 0.0, np.sin(np.deg2rad(15.0))]  # backwards, 15 deg up
    off_jet = np.rad2deg(np.arccos(offset @ jet / np.linalg.norm(offset)))
    assert 0 < off_jet < 15
    found = problems_at(truck, lens)
    assert (f"in the tyre-spray cone of the front-left wheel ({np.linalg.norm(offset):.2f} m behind its contact "
            f"patch, {off_jet:.0f} deg off the jet)") in found


def test_a_high_lens_behind_a_tyre_is_above_its_spray(truck):
    assert not mentions(problems_at(truck, [0.2, 0.93, 1.3]), "spray")


def test_the_spray_cone_is_as_long_and_wide_as_the_practice_says(truck):
    point = [-0.3, 0.93, 0.55]  # 1.61 m from the front-left contact patch, 8 deg off the jet
    assert not mentions(problems_at(truck, point, MountPractice(spray_length=1.5)), "spray")
    assert not mentions(problems_at(truck, point, MountPractice(spray_half_angle_deg=5.0)), "spray")
    wider = [0.2, 0.93, 0.55]  # 16 deg off the jet: in a cone of 20 deg, not in the default 15
    assert not mentions(problems_at(truck, wider), "spray")
    assert mentions(problems_at(truck, wider, MountPractice(spray_half_angle_deg=20.0)), "spray")


# --- the legal width --------------------------------------------------------------------------------------------


STRICT = MountPractice(width_allowance=0.0)


def test_a_housing_beyond_the_legal_width_protrudes(truck):
    # on the locker's side (|y| 1.25): the housing's outer face at 1.28 + 0.03, 0.035 m beyond 1.275
    found = problems_at(truck, [-0.4, 1.28, 1.0], STRICT)
    assert "protrudes 0.04 m beyond the legal width 2.55 m (side devices may add 0.00 m)" in found
    protrusion, limit = features.width_protrusion(truck, [[-0.4, 1.28, 1.0]], [[0.0, 1.0, 0.0]], ["side"],
                                                  (0.08, 0.06, 0.06))
    assert protrusion[0] == pytest.approx(0.035) and limit[0] == pytest.approx(1.275)


def test_side_devices_may_add_the_allowance_and_no_more(truck):
    assert not mentions(problems_at(truck, [-0.4, 1.28, 1.0]), "protrudes")  # 0.035 m: within the default 0.10
    deep = practice_problems(truck, [[-0.4, 1.33, 1.0]], MountPractice(), housing=(0.08, 0.06, 0.16))[0]
    assert "protrudes 0.14 m beyond the legal width 2.55 m (side devices may add 0.10 m)" in deep


def test_a_housing_on_the_narrow_body_stays_within_the_width(truck):
    assert not mentions(problems_at(truck, [-1.9, 0.93, 1.1], STRICT), "legal width")


def test_a_mirror_camera_does_not_count_in_the_width(truck):
    assert not mentions(problems_at(truck, [1.7, 1.33, 1.3], STRICT), "legal width")


def test_a_refrigerated_body_may_be_2_60_wide_and_a_spec_may_say_its_own(tmp_path):
    reefer = _truck(tmp_path, BOX_TRUCK.replace('blueprint = "vehicle.test.boxtruck"',
                                                'blueprint = "vehicle.test.boxtruck"\nrefrigerated = true'))
    assert reefer.legal_width == 2.60
    assert mentions(problems_at(reefer, [-0.4, 1.28, 1.0], STRICT), "protrudes 0.01 m beyond the legal width 2.60 m")
    wide = spec_from_dict({"name": "w", "legal_width": 2.7, "solids": [{"type": "box", "center": [0, 0, 1],
                                                                        "size": [4, 2, 1]}]})
    assert wide.legal_width == 2.7


def test_on_a_body_wider_than_the_law_the_body_s_side_is_the_limit(tmp_path):
    # the locker made 2.8 m wide: the body's own side (1.4 m) is the limit there, the mirror heads left out
    wide = _truck(tmp_path, BOX_TRUCK.replace("size = [0.6, 2.5, 0.8]", "size = [0.6, 2.8, 0.8]"))
    assert features.width_limits(wide) == pytest.approx((1.4, 1.4))
    found = problems_at(wide, [-0.4, 1.43, 1.0], STRICT)  # on the locker: 1.43 + 0.03 sticks out 0.06 beyond it
    assert ("protrudes 0.06 m beyond the body's side (1.40 m from the centreline: the body is wider than the legal "
            "2.55 m; side devices may add 0.00 m)") in found
    assert not mentions(problems_at(wide, [-0.4, 1.43, 1.0]), "protrudes")  # within the default allowance
    assert not mentions(problems_at(wide, [-0.4, 1.33, 1.0], STRICT), "protrudes")  # beyond 1.275, not the body


# --- the tilt-cab arc -------------------------------------------------------------------------------------------


def test_a_lens_on_the_bull_bar_is_in_the_tilt_cab_arc(truck):
    found = problems_at(truck, [2.15, 0.0, 1.33])
    assert "in the tilt-cab arc (the cab sweeps it tilting up to 60 deg about x 2.00 m, z 0.90 m)" in found


def test_a_lens_on_the_cab_tilts_with_it_and_one_below_the_pivot_is_not_swept(truck):
    assert not mentions(problems_at(truck, [2.03, 0.0, 1.2]), "tilt-cab")  # on the cab's front face
    assert not mentions(problems_at(truck, [2.23, 0.0, 0.95]), "tilt-cab")  # the bull bar's front, low


def test_the_arc_grows_with_the_tilt(truck, tmp_path):
    point = [[2.23, 0.0, 1.0]]  # 0.23 m ahead of the pivot, 0.1 m above it: the cab's front edge needs 66 deg
    assert not features.in_tilt_arc(truck, point, 0.05)[0]
    steeper = _truck(tmp_path, BOX_TRUCK.replace("angle_deg = 60", "angle_deg = 80"))
    assert features.in_tilt_arc(steeper, point, 0.05)[0]


# --- the trailer's swing ----------------------------------------------------------------------------------------


def test_the_swing_radius_reaches_the_trailer_s_front_corners(truck):
    (swing,) = features.trailer_swings(truck)
    assert swing.radius == pytest.approx(np.hypot(1.0, 0.9))
    assert features.trailer_swings(truck, lifted=("trailer",)) == []


def test_a_lens_beside_the_trailer_s_front_is_in_its_swing(truck):
    found = problems_at(truck, [-2.7, 1.0, 1.5])
    assert mentions(found, "in the trailer's swing (its front corners turn 1.35 m about the kingpin at x -3.50 m)")
    assert not mentions(problems_at(truck, [-2.7, 1.0, 1.5], MountPractice(lifted=("trailer",))), "swing")


def test_a_lens_below_the_trailer_s_underside_is_out_of_its_swing(truck):
    assert not mentions(problems_at(truck, [-2.7, 1.0, 0.8]), "swing")


def test_a_camera_facing_the_swing_has_it_in_its_near_view(truck):
    # on the body's left side near its rear, looking back past the trailer's side (its checked view spans yaw
    # 150-180 deg): the static box is out of it, the swinging front corner is not
    rig = Rig("swing", truck.blueprint, (camera("CAM_REAR_LEFT", [-1.9, 0.93, 1.3], yaw_deg=165.0),))
    (result,) = check_rig(rig, truck).cameras
    assert mentions(result.problems, "the trailer's swing", "is in its view within 1 m")
    assert not mentions(result.problems, "keep-out trailer")
    (solo,) = check_rig(rig, truck, MountRules(practice=MountPractice(lifted=("trailer",)))).cameras
    assert not mentions(solo.problems, "swing")


def test_segments_enter_the_swing_cylinder_exactly():
    swing = features.TrailerSwing("t", np.array([0.0, 0.0, 1.0]), 1.0, 3.0)
    starts = np.array([[2.0, 0.0, 2.0], [2.0, 0.0, 0.5], [2.0, 0.0, 2.0], [0.0, 0.0, 2.0], [2.0, 2.0, 2.0]])
    directions = np.array([[-1.0, 0, 0], [-1.0, 0, 0], [1.0, 0, 0], [1.0, 0, 0], [-1.0, 0, 0]])
    assert features.segments_hit_swings(starts, directions, 1.5, [swing]).tolist() == [True, False, False, True, False]
    assert features.segments_hit_swings(starts, directions, 0.9, [swing]).tolist() == [False, False, False, True, False]


# --- the windscreen's wiped area --------------------------------------------------------------------------------


def test_a_windscreen_lens_outside_the_wiped_area_is_refused(truck):
    found = problems_at(truck, [2.03, 0.8, 1.2])
    assert "on the windscreen outside the wiped area (0.30 m from it)" in found


def test_a_windscreen_lens_inside_the_wiped_area_is_allowed(truck):
    assert problems_at(truck, [2.03, 0.0, 1.2]) == []


# --- duplicates (rig level) -------------------------------------------------------------------------------------


def test_a_second_camera_with_the_same_lens_close_by_looking_the_same_way_duplicates_the_first():
    first, second = camera("CAM_A", [2.03, 0.0, 0.6]), camera("CAM_B", [2.03, 0.0, 0.91], yaw_deg=4.0)
    found = duplicates(Rig("r", "v", (first, second)))
    assert found == [None, "duplicates CAM_A: same lens, 0.31 m apart, 4 deg apart"]


@pytest.mark.parametrize("second", [
    camera("CAM_B", [2.03, 0.0, 0.91], yaw_deg=15.0),  # looking another way
    camera("CAM_B", [2.03, 0.0, 1.2]),  # 0.6 m apart
    camera("CAM_B", [2.03, 0.0, 0.91], fov=90.0),  # another lens
    camera("CAM_B", [2.03, 0.0, 0.91], module="stereo"),  # a stereo pair, in one module
])
def test_cameras_that_differ_or_share_a_module_are_no_duplicates(second):
    first = camera("CAM_A", [2.03, 0.0, 0.6], module="stereo" if second.module else None)
    assert duplicates(Rig("r", "v", (first, second))) == [None, None]


def test_check_names_the_duplicate_on_the_later_camera_only(truck):
    rig = Rig("dup", truck.blueprint, (camera("CAM_A", [-1.9, -0.93, 1.1], yaw_deg=-90.0),
                                       camera("CAM_B", [-1.7, -0.93, 1.1], yaw_deg=-90.0)))
    checks = check_rig(rig, truck).cameras
    assert checks[0].valid
    assert not checks[1].valid and mentions(checks[1].problems, "duplicates CAM_A: same lens, 0.20 m apart")


# --- the mount points and the switch ----------------------------------------------------------------------------


def test_the_mount_points_leave_out_every_place_the_features_forbid(truck):
    points, _, zones = sample_zone_points(truck, spacing=0.05)
    assert practical(truck, points).all()
    on_door = (points[:, 0] > 0.0) & (points[:, 0] < 0.7) & (points[:, 2] > 0.8) & (points[:, 2] < 1.4) & \
        (np.abs(points[:, 1]) < 1.0)
    assert on_door.any()  # the door itself stays mountable ...
    door_x = points[on_door, 0]
    assert door_x.min() > 0.05 - 1e-9 and door_x.max() < 0.6 + 1e-9  # ... but neither its frame nor its hinge line
    assert "windshield_front" in set(zones)
    front = points[zones == "windshield_front"]
    assert (np.abs(front[:, 1]) <= 0.5 + 1e-9).all()  # windscreen points only in the wiped area


def test_practice_switched_off_forbids_none_of_it(truck):
    off = MountPractice(enabled=False)
    lenses = [[-2.33, 0.0, 0.65], [0.03, 0.93, 1.1], [0.0, 0.7, 1.63], [1.2, 0.93, 0.83], [-0.3, 0.93, 0.55],
              [2.15, 0.0, 1.33], [-2.7, 1.0, 1.5], [2.03, 0.8, 1.2]]
    assert all(p for p in practice_problems(truck, lenses))
    assert practice_problems(truck, lenses, off) == [[]] * len(lenses)


# --- the spec's new keys ----------------------------------------------------------------------------------------

BASE = {"name": "v", "solids": [{"type": "box", "center": [0, 0, 1], "size": [4, 2, 1]}]}
BOX = {"min": [0, 0.8, 0.5], "max": [1, 1.0, 1.5]}


@pytest.mark.parametrize("extra, message", [
    ({"fixtures": [{"name": "f", "kind": "antenna", **BOX}]}, "'kind' must be one of rail, ladder, light_bar, rack"),
    ({"door_frames": [{"name": "d", "hinge": "side", **BOX}]}, "'hinge' must be one of front, rear"),
    ({"door_frames": [{"name": "d", "hinge": "left", **BOX}]}, "the hinge 'left' runs across the door"),
    ({"door_frames": [{"name": "d", "frame": -0.1, **BOX}]}, "'frame' must be a positive number"),
    ({"steps": [{"name": "s", "min": [0, 0, 1], "max": [1, 1, 0.5]}]}, "'min' must be below 'max'"),
    ({"legal_width": 25.5}, "'legal_width' is the vehicle's legal width in metres"),
    ({"refrigerated": "yes"}, "'refrigerated' must be true or false"),
    ({"wiped_area": {"outline": [[0, 1], [1, 1]]}}, "'outline' must be a list of at least 3"),
    ({"wiped_area": [1, 2]}, "'wiped_area' must be a table"),
    ({"tilt_cab": {"pivot": [3, 1], "angle_deg": 120, **BOX}}, "'angle_deg' is the cab's tilt in degrees"),
    ({"keep_out": [{"name": "trailer", "min": [-9, -1, 0], "max": [-1, 1, 4], "kingpin": [0, 0, 1]}]},
     "the trailer's 'kingpin' must lie behind its front"),
])
def test_a_bad_feature_in_a_spec_names_the_file_and_the_key(extra, message):
    with pytest.raises(DataError, match="v.toml") as caught:
        spec_from_dict({**BASE, **extra}, "v.toml")
    assert message in str(caught.value)
