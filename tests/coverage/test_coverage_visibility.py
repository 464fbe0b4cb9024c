"""Exact visibility cases: a camera facing the box car, points just behind a corner (the frustum alone is tested
in tests/test_camera.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rigopt.camera import CameraModel, in_frustum
from rigopt.coverage.visibility import visible
from rigopt.raycast import RayCaster
from rigopt.geometry import rotation_from_yaw_pitch_roll

SIZE = np.array([[1280, 720]])


# --- one camera facing the box car ---------------------------------------------------------------------------

CAMERA = np.array([5.0, 0.0, 0.9])  # 3 m in front of the front face x = 2, at mid-height, looking -x
LOOK_BACK = rotation_from_yaw_pitch_roll(np.pi, 0.0, 0.0)[None]


def face_points(x):
    return np.array([[x, y, z] for y in np.linspace(-0.95, 0.95, 7) for z in np.linspace(0.35, 1.45, 5)])


@pytest.mark.parametrize("backend", ["auto", "triangle"])
def test_camera_facing_the_box(box_vehicle, backend):
    near, far = face_points(2.0), face_points(-2.0)
    # Both faces are inside the frustum (|y| <= 0.95 < depth, |z - 0.9| <= 0.55 < 0.5625 * depth) ...
    assert in_frustum(CameraModel.from_fov([90.0], SIZE), CAMERA[None], LOOK_BACK, np.concatenate([near, far])).all()
    # ... the near face (the points lie on the surface) is seen, the far face is behind the body.
    assert visible(box_vehicle.caster(backend), CAMERA[None], LOOK_BACK, [90.0], SIZE, near).all()
    assert not visible(box_vehicle.caster(backend), CAMERA[None], LOOK_BACK, [90.0], SIZE, far).any()
    # Points behind the box, and points between the camera and the box.
    behind = face_points(-3.0)
    between = face_points(3.0)
    assert not visible(box_vehicle.caster(backend), CAMERA[None], LOOK_BACK, [90.0], SIZE, behind).any()
    assert visible(box_vehicle.caster(backend), CAMERA[None], LOOK_BACK, [90.0], SIZE, between).all()


@pytest.mark.parametrize("backend", ["auto", "triangle"])
def test_points_a_centimetre_off_the_surface(box_vehicle, backend):
    # 1 cm inside the front face: hidden by it; 1 cm in front of it: seen.
    inside, outside = face_points(2.0 - 0.01), face_points(2.0 + 0.01)
    seen = visible(box_vehicle.caster(backend), CAMERA[None], LOOK_BACK, [90.0], SIZE,
                   np.concatenate([inside, outside]))[0]
    assert seen.tolist() == [False] * len(inside) + [True] * len(outside)


# --- a point just hidden behind a body edge ------------------------------------------------------------------

def offset_targets(camera, edge, target_on_tangent, normal, gap=0.01):
    """Two targets on either side of the tangent line camera -> edge -> target, moved along ``normal`` (unit,
    away from the body) so that the segment from the camera passes ``gap`` m from the edge. Moving the
    target by s (target at L from the camera, edge at e) puts the edge at s e / sqrt(L^2 + s^2) from the new
    line, so s = gap L / sqrt(e^2 - gap^2)."""
    length, edge_distance = np.linalg.norm(target_on_tangent - camera), np.linalg.norm(edge - camera)
    shift = gap * length / math.sqrt(edge_distance**2 - gap**2)
    return target_on_tangent - shift * normal, target_on_tangent + shift * normal


def distance_point_to_line(point, a, b):
    direction = (b - a) / np.linalg.norm(b - a)
    offset = point - a
    return np.linalg.norm(offset - (offset @ direction) * direction)


# Vertical edge (2, 1, z): in plan view the line through the camera (4, 0) and the corner (2, 1) is
# x + 2 y = 4; it stays at y = (4 - x) / 2 >= 1 for x <= 2, so it only touches the box at that corner, and
# reaches (-4, 4) at x = -4. The body is on the side x + 2 y < 4 (the origin), so outwards is (1, 2) / sqrt 5.
VERTICAL_EDGE = (np.array([4.0, 0.0, 0.9]), np.array([2.0, 1.0, 0.9]), np.array([-4.0, 4.0, 0.9]),
                 np.array([1.0, 2.0, 0.0]) / math.sqrt(5.0), 180.0, 0.0)
# Rear top edge (-2, y, 1.5): in the x-z plane the line through the camera (4, 3) and (-2, 1.5) has slope
# 1 / 4, so it runs above the roof (z = 1.5 + (x + 2) / 4 > 1.5 for x > -2) and meets the ground at x = -8.
# The body lies below it; outwards is (-1, 4) / sqrt 17 (perpendicular to (4, 1), upwards).
TOP_EDGE = (np.array([4.0, 0.0, 3.0]), np.array([-2.0, 0.0, 1.5]), np.array([-8.0, 0.0, 0.0]),
            np.array([-1.0, 0.0, 4.0]) / math.sqrt(17.0), 180.0, -14.0)


@pytest.mark.parametrize("case", [VERTICAL_EDGE, TOP_EDGE], ids=["vertical-edge", "top-edge"])
@pytest.mark.parametrize("backend", ["auto", "triangle"])
def test_point_just_behind_an_edge(box_vehicle, case, backend):
    camera, edge, target, normal, yaw, pitch = case
    # The hand-made tangent really goes through the edge, and the normal is perpendicular to it.
    assert distance_point_to_line(edge, camera, target) == pytest.approx(0.0, abs=1e-12)
    assert normal @ (target - camera) == pytest.approx(0.0, abs=1e-12)
    hidden, seen = offset_targets(camera, edge, target, normal)
    for point in (hidden, seen):
        assert distance_point_to_line(edge, camera, point) == pytest.approx(0.01, rel=1e-9)
    caster = RayCaster(box_vehicle.mesh, backend)
    assert caster.segments_clear([camera, camera], [hidden, seen]).tolist() == [False, True]
    rotation = rotation_from_yaw_pitch_roll(np.deg2rad(yaw), np.deg2rad(pitch), 0.0)[None]
    points = np.array([hidden, seen])
    assert in_frustum(CameraModel.from_fov([90.0], SIZE), camera[None], rotation, points).all()
    assert visible(caster, camera[None], rotation, [90.0], SIZE, points)[0].tolist() == [False, True]


# --- cameras sharing a position share their segments --------------------------------------------------------------

class CountingCaster:
    """A RayCaster that records how many segments it was asked about."""

    def __init__(self, caster):
        self.caster, self.segments = caster, 0

    def segments_clear(self, starts, ends):
        self.segments += len(np.atleast_2d(starts))
        return self.caster.segments_clear(starts, ends)


def test_cameras_at_one_position_cast_each_segment_once(box_vehicle):
    # Two mount positions, four yaws each (90 deg pinholes): each camera's row equals the row it gets alone, and
    # a (position, point) segment is cast once however many cameras there see the point.
    positions = np.repeat([[3.0, 0.0, 0.9], [0.0, 2.0, 0.9]], 4, axis=0)
    yaws = np.tile(np.deg2rad([0.0, 90.0, 180.0, -90.0]) + 0.3, 2)
    rotations = rotation_from_yaw_pitch_roll(yaws, np.zeros(8), np.zeros(8))
    rng = np.random.default_rng(4)
    points = rng.uniform([-6.0, -5.0, 0.0], [6.0, 5.0, 2.0], (300, 3))
    fovs, sizes = np.full(8, 120.0), np.tile(SIZE, (8, 1))
    counting = CountingCaster(box_vehicle.ray_caster)
    seen = visible(counting, positions, rotations, fovs, sizes, points)
    for k in range(8):
        alone = visible(box_vehicle.ray_caster, positions[k:k + 1], rotations[k:k + 1], fovs[k:k + 1], sizes[k:k + 1],
                        points)[0]
        np.testing.assert_array_equal(seen[k], alone)
    in_view = in_frustum(CameraModel.from_fov(fovs, sizes), positions, rotations, points, 80.0)
    assert counting.segments == in_view[:4].any(axis=0).sum() + in_view[4:].any(axis=0).sum()
    assert counting.segments < in_view.sum()  # the frustums overlap: fewer casts than (camera, point) pairs
    assert (in_view & ~seen).any()  # and the body hides some
