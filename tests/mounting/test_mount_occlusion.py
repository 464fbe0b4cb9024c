"""The body and the keep-outs that block views are solids for the mount rules: a camera turned into the body from
just off its skin (its whole near frustum inside the body, where fcl's surface mesh meets nothing) is refused by
check_rig and has no clear direction, and a frustum wholly inside an occluding keep-out counts.

The box car (tests/box_car.py): the box [-2, 2] x [-0.9, 0.9] x [0.3, 1.5] m, a front and a mirrored side zone;
the trailer car adds an occluding keep-out box [-8, -2.5] x [-0.9, 0.9] x [0, 3] m behind it.
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from rigopt.camera import CameraModel, Lens
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.mounting.candidates import body_fraction, clear_directions
from rigopt.mounting.records import MountPractice, MountRules
from rigopt.mounting.rules import check_rig
from rigopt.mounting.shapes import collides, frustum_object, frustum_vertices
from rigopt.rig.library import load_rig
from rigopt.rig.model import Camera, Rig
from rigopt.rig.pccr_format import write_rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

from box_car import spec_text
from in_process import run_rigopt

BODY_IN_VIEW = "the body is in its view within 1 m"
TRAILER = """
[[keep_out]]
name = "trailer"
reason = "a coupled semi-trailer"
min = [-8.0, -0.9, 0.0]
max = [-2.5, 0.9, 3.0]
optional = true
occludes = true
"""


def camera(position, yaw_deg, fov=60.0) -> Camera:
    rotation = rotation_from_yaw_pitch_roll(np.deg2rad(yaw_deg), 0.0, 0.0)
    return Camera.pinhole("CAM", np.array(position, dtype=float), rotation, fov)


def problems(vehicle, cam, rules=MountRules()) -> tuple[str, ...]:
    return check_rig(Rig("test", vehicle.name, (cam,)), vehicle, rules).cameras[0].problems


@pytest.fixture(scope="module")
def trailer_car(tmp_path_factory) -> Vehicle:
    path = tmp_path_factory.mktemp("trailercar") / "vehicle.toml"
    path.write_text(spec_text("trailercar") + TRAILER)
    return Vehicle.from_spec(read_spec(path))


@pytest.mark.parametrize("off", [0.005, 0.0118])
def test_a_camera_facing_into_the_body_from_its_skin_is_refused(box_car, off):
    inward = camera([0.0, 0.9 + off, 1.0], -90.0)
    # the cause: its frustum (2 cm to 1 m) lies wholly inside the body, crossing no surface triangle
    assert box_car.ray_caster.inside(frustum_vertices(inward, MountRules())).all()
    assert not collides(frustum_object(inward, MountRules()), box_car.collision_object)
    assert problems(box_car, inward) == (BODY_IN_VIEW,)


def test_the_same_camera_facing_out_is_valid(box_car):
    assert problems(box_car, camera([0.0, 0.905, 1.0], 90.0)) == ()


def test_a_body_thinner_than_the_near_plane_in_front_of_the_lens_is_seen(box_car):
    """Below the box (z < 0.3) a lens 1 cm under it looking up has the body between the lens and the near plane
    (2 cm) only: the probe rays from the lens find it."""
    up = Camera.pinhole("CAM", np.array([0.0, 0.0, 0.29]), rotation_from_yaw_pitch_roll(0.0, np.pi / 2, 0.0), 60.0)
    assert BODY_IN_VIEW in problems(box_car, up)


def test_no_clear_direction_faces_into_the_body_from_its_skin(box_car):
    yaws = np.deg2rad([90.0, -90.0])
    for off in (0.005, 0.03):
        clear = clear_directions(box_car, [[0.0, 0.9 + off, 1.0]], yaws, np.array([0.0]), Lens.pinhole(65.0))
        assert clear[0, 0].tolist() == [True, False]


def test_a_camera_facing_into_the_body_sees_only_the_body(box_car):
    rotations = rotation_from_yaw_pitch_roll(np.deg2rad([-90.0, 90.0]), np.zeros(2), np.zeros(2))
    shares = body_fraction(box_car, [[0.0, 0.905, 1.0]] * 2, rotations, CameraModel.from_fov([65.0] * 2,
                                                                                             [[1280, 720]] * 2))
    assert shares.tolist() == [1.0, 0.0]


def test_a_frustum_wholly_inside_an_occluding_keep_out_is_refused(trailer_car):
    facing = camera([-2.49, 0.0, 1.0], 180.0)  # 1 cm before the trailer's front, looking into it
    assert "the keep-out trailer (a coupled semi-trailer) is in its view within 1 m" in problems(trailer_car, facing)
    lifted = MountRules(practice=MountPractice(lifted=("trailer",)))
    assert not any("trailer" in p for p in problems(trailer_car, facing, lifted))
    back = (trailer_car, [facing.position], np.array([np.pi]), np.array([0.0]), Lens.pinhole(60.0))
    assert not clear_directions(*back)[0, 0, 0]
    assert clear_directions(*back, lifted)[0, 0, 0]


def test_check_refuses_every_camera_of_r1_turned_into_the_etron(tmp_path):
    """R1 turned 180 deg: each camera faces into the body (CAM_SIDE_RIGHT 0.5 cm and CAM_FENDER_FRONT_LEFT 1.2 cm
    off the skin had their whole frustum inside it)."""
    r1 = load_rig("R1")
    turn = rotation_from_yaw_pitch_roll(np.pi, 0.0, 0.0)
    inward = Rig("R1_inward", r1.vehicle, tuple(replace(c, rotation=c.rotation @ turn) for c in r1.cameras))
    result = run_rigopt("check", write_rig(inward, tmp_path / "inward.json"), "--json")
    assert result.returncode == 1, result.stderr
    cameras = json.loads(result.stdout)["cameras"]
    assert len(cameras) == 8 and all(BODY_IN_VIEW in c["problems"] and not c["valid"] for c in cameras)
