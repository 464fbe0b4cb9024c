"""rigopt.camera: the ideal centred pinhole (focal lengths, FOVs, intrinsics) and the camera model (rays,
projection, in-view tests, frustum shapes), each checked by hand and against the others."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rigopt.camera import (CameraModel, Lens, camera_frame_points, focal_from_fov, fov_from_focal, in_frustum,
                           intrinsic_matrix, pinhole_half_tangents, pixel_centres, vertical_fov)
from rigopt.errors import RigoptError
from rigopt.geometry import R_CAM_OPTICAL, rotation_from_yaw_pitch_roll
from rigopt.rig.model import Camera

fov_deg = st.floats(1.0, 179.0)
#: The near-field stage's equidistant 190-degree fisheye, 1280 x 800 px.
FISHEYE_190 = Lens(1280, 800, 640 / math.radians(95.0), 640 / math.radians(95.0), 640.0, 400.0, "fisheye",
                   (0.0, 0.0, 0.0, 0.0))
width_px = st.integers(16, 8192)


def test_focal_of_fov_60_at_320_px():
    expected = 160.0 / math.tan(math.radians(30.0))  # half width over tan(half FOV)
    assert focal_from_fov(60.0, 320) == pytest.approx(expected, rel=1e-12)
    assert focal_from_fov(60.0, 320) == pytest.approx(277.128, abs=5e-4)


def test_fov_90_has_focal_half_the_width():
    assert focal_from_fov(90.0, 1280) == pytest.approx(640.0, rel=1e-12)


@given(fov=fov_deg, width=width_px)
def test_fov_from_focal_inverts_focal_from_fov(fov, width):
    assert fov_from_focal(focal_from_fov(fov, width), width) == pytest.approx(fov, rel=1e-9)


@given(focal=st.floats(1.0, 1e5), width=width_px)
def test_focal_from_fov_inverts_fov_from_focal(focal, width):
    assert focal_from_fov(fov_from_focal(focal, width), width) == pytest.approx(focal, rel=1e-9)


@given(a=fov_deg, b=fov_deg, width=width_px)
def test_wider_fov_has_shorter_focal(a, b, width):
    if a < b:
        assert focal_from_fov(a, width) > focal_from_fov(b, width)


def test_vertical_fov_of_90_at_1280_by_720():
    expected = math.degrees(2.0 * math.atan(math.tan(math.radians(45.0)) * 720.0 / 1280.0))
    assert vertical_fov(90.0, 1280, 720) == pytest.approx(expected, rel=1e-12)


@given(fov=fov_deg, width=width_px)
def test_vertical_fov_of_a_square_image_is_the_horizontal_fov(fov, width):
    assert vertical_fov(fov, width, width) == pytest.approx(fov, rel=1e-9)


@given(fov=fov_deg, width=width_px, height=width_px)
def test_vertical_fov_follows_the_aspect_ratio(fov, width, height):
    expected = 2.0 * math.degrees(math.atan(math.tan(math.radians(fov) / 2.0) * height / width))
    assert vertical_fov(fov, width, height) == pytest.approx(expected, rel=1e-9)


def test_functions_broadcast_over_arrays():
    fovs = np.array([[30.0, 60.0], [90.0, 120.0]])
    focal = focal_from_fov(fovs, 1280)
    assert focal.shape == (2, 2)
    assert focal[1, 0] == pytest.approx(640.0, rel=1e-12)
    np.testing.assert_allclose(fov_from_focal(focal, 1280), fovs, rtol=1e-12)
    assert vertical_fov(fovs, 1280, np.array([720, 1280])).shape == (2, 2)


def test_intrinsic_matrix_layout():
    k = intrinsic_matrix(90.0, 1280, 720)
    np.testing.assert_allclose(k, [[640.0, 0.0, 640.0], [0.0, 640.0, 360.0], [0.0, 0.0, 1.0]], rtol=1e-12)


@given(fov=fov_deg, width=width_px, height=width_px)
def test_intrinsic_matrix_maps_half_fov_ray_to_the_image_edge(fov, width, height):
    k = intrinsic_matrix(fov, width, height)
    centre = k @ np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(centre[:2] / centre[2], [width / 2, height / 2], rtol=1e-12)
    edge = k @ np.array([math.tan(math.radians(fov) / 2.0), 0.0, 1.0])  # optical frame: x right, z forward
    assert edge[0] / edge[2] == pytest.approx(width, rel=1e-9)
    assert edge[1] / edge[2] == pytest.approx(height / 2, rel=1e-12)


# --- the camera model: tangents, intrinsics, FOVs ---------------------------------------------------------

IDENTITY = np.eye(3)[None]
SIZE = np.array([[1280, 720]])
sizes = st.tuples(st.integers(16, 4096), st.integers(16, 4096))


def test_half_tangents_by_hand():
    tan_h, tan_v = CameraModel.from_fov([90.0, 60.0], [[1280, 720], [800, 800]]).half_tangents()
    np.testing.assert_allclose(tan_h, [1.0, math.tan(math.radians(30))], rtol=1e-12)
    np.testing.assert_allclose(tan_v, [0.5625, math.tan(math.radians(30))], rtol=1e-12)


@given(fov=fov_deg, size=sizes)
def test_edge_tangents_of_a_centred_pinhole_are_its_half_tangents(fov, size):
    model = CameraModel.from_fov(fov, size)
    left, right, up, down = model.edge_tangents()
    tan_h, tan_v = model.half_tangents()
    assert left == right == pytest.approx(float(tan_h), rel=1e-12)
    assert up == down == pytest.approx(float(tan_v), rel=1e-12)
    assert float(tan_h) == pytest.approx(math.tan(math.radians(fov) / 2), rel=1e-12)


@given(fov=fov_deg, size=sizes)
def test_model_fovs_are_the_given_and_the_vertical_fov(fov, size):
    model = CameraModel.from_fov(fov, size)
    assert float(model.hfov) == pytest.approx(fov, rel=1e-9)
    assert float(model.vfov) == pytest.approx(float(vertical_fov(fov, *size)), rel=1e-9)


@given(fov=fov_deg, size=sizes)
def test_symbolic_half_tangents_agree_with_the_model(fov, size):
    casadi = pytest.importorskip("casadi")
    symbol = casadi.MX.sym("fov")
    tan_h, tan_v = pinhole_half_tangents(symbol, *size, tan=casadi.tan)
    values = casadi.Function("tangents", [symbol], [tan_h, tan_v])(fov)
    np.testing.assert_allclose([float(v) for v in values], CameraModel.from_fov(fov, size).half_tangents(), rtol=1e-12)


def test_model_intrinsic_matrix_is_the_function():
    model = CameraModel.from_fov([90.0, 65.0], [[1280, 720], [640, 480]])
    k = model.intrinsic_matrix()
    assert k.shape == (2, 3, 3)
    np.testing.assert_array_equal(k[1], intrinsic_matrix(65.0, 640, 480))
    np.testing.assert_allclose(k[0], [[640.0, 0.0, 640.0], [0.0, 640.0, 360.0], [0.0, 0.0, 1.0]], rtol=1e-12)


def test_of_cameras_reads_each_cameras_lens():
    cameras = [Camera.pinhole("A", np.zeros(3), np.eye(3), 90.0, (1280, 720)),
               Camera.pinhole("B", np.zeros(3), np.eye(3), 60.0, (800, 600))]
    model = CameraModel.of_cameras(cameras)
    assert model.shape == (2,)
    np.testing.assert_allclose(model.hfov, [90.0, 60.0], rtol=1e-12)
    np.testing.assert_array_equal(model.width, [1280, 800])
    assert CameraModel.of_camera(cameras[1]).shape == ()
    np.testing.assert_array_equal(CameraModel.of_camera(cameras[1]).fx, model.fx[1])


@pytest.mark.parametrize("fov", [0.0, 180.0, float("nan"), -30.0, 200.0, float("inf")])
def test_bad_fov_raises(fov):
    with pytest.raises(RigoptError, match="FOV"):
        CameraModel.from_fov([fov], SIZE)


def test_one_bad_fov_among_good_ones_raises():
    with pytest.raises(RigoptError, match="nan"):
        CameraModel.from_fov([90.0, float("nan"), 60.0], np.tile(SIZE, (3, 1)))


@pytest.mark.parametrize("field", ["width", "height", "fx", "fy"])
def test_non_positive_intrinsics_raise(field):
    values = {**dict(width=1280.0, height=720.0, fx=640.0, fy=640.0, cx=640.0, cy=360.0), field: 0.0}
    with pytest.raises(RigoptError, match=field):
        CameraModel(**values)


def test_intrinsics_of_different_batch_shapes_raise():
    with pytest.raises(RigoptError, match="batch shape"):
        CameraModel([1280.0, 640.0], 720.0, [640.0, 320.0, 100.0], 640.0, 640.0, 360.0)


def test_model_arrays_are_read_only():
    model = CameraModel.from_fov([90.0], SIZE)
    with pytest.raises(ValueError):
        model.fx[0] = 1.0


# --- rays and projection ---------------------------------------------------------------------------------

@given(fov=fov_deg, size=sizes, u=st.floats(0.0, 1.0), v=st.floats(0.0, 1.0))
def test_project_inverts_pixel_rays(fov, size, u, v):
    model = CameraModel.from_fov(fov, size)
    pixel = np.array([[u * size[0], v * size[1]]])
    for unit in (True, False):
        ray = model.pixel_rays(pixel, unit=unit)
        np.testing.assert_allclose(model.project(3.7 * ray), pixel, rtol=1e-9, atol=1e-6 * max(size))


def test_pixel_rays_by_hand():
    model = CameraModel.from_fov(90.0, (1280, 720))  # f = 640, centre (640, 360)
    rays = model.pixel_rays([[640.0, 360.0], [1280.0, 360.0], [0.0, 0.0]], unit=False)
    # the centre is the optical axis; the right edge is 45 deg right (y < 0); the top-left corner is left and up
    np.testing.assert_allclose(rays, [[1.0, 0.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.5625]], rtol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(model.pixel_rays([[0.0, 0.0]]), axis=-1), 1.0, rtol=1e-12)


def test_optical_and_body_rays_differ_by_the_frame_change():
    model = CameraModel.from_fov(70.0, (800, 600))
    pixels = pixel_centres(8, 6) * 100
    body, optical = model.pixel_rays(pixels, unit=False), model.pixel_rays(pixels, unit=False, frame="optical")
    np.testing.assert_allclose(body, optical @ R_CAM_OPTICAL.T, atol=1e-15)
    np.testing.assert_array_equal(optical[:, 2], 1.0)
    with pytest.raises(RigoptError, match="frame"):
        model.pixel_rays(pixels, frame="vehicle")


def test_pixel_centres_run_row_by_row():
    np.testing.assert_array_equal(pixel_centres(3, 2), [[0.5, 0.5], [1.5, 0.5], [2.5, 0.5], [0.5, 1.5], [1.5, 1.5],
                                                        [2.5, 1.5]])


def test_grid_rays_through_cell_centres():
    model = CameraModel.from_fov(90.0, (1280, 720))
    rays = model.grid_rays((3, 3))
    assert rays.shape == (9, 3)
    np.testing.assert_allclose(np.linalg.norm(rays, axis=1), 1.0, rtol=1e-12)
    np.testing.assert_allclose(rays[4], [1.0, 0.0, 0.0], atol=1e-15)  # the middle cell is on the axis
    # the first cell is the top-left one: centre at (1280 / 6, 720 / 6) px, i.e. tangents (2/3, 2/3 * 0.5625)
    expected = np.array([1.0, 2 / 3, 2 / 3 * 0.5625])
    np.testing.assert_allclose(rays[0], expected / np.linalg.norm(expected), rtol=1e-12)
    assert model.in_view(rays).all()


def test_grid_rays_batch_over_cameras():
    model = CameraModel.from_fov([60.0, 120.0], [[1280, 720], [640, 640]])
    rays = model.grid_rays((4, 2))
    assert rays.shape == (2, 8, 3)
    np.testing.assert_allclose(rays[1], CameraModel.from_fov(120.0, (640, 640)).grid_rays((4, 2)), rtol=1e-15)
    with pytest.raises(RigoptError, match="grid"):
        model.grid_rays((0, 2))


@given(fov=fov_deg, size=sizes)
def test_in_view_is_projecting_inside_the_image(fov, size):
    model = CameraModel.from_fov(fov, size)
    rng = np.random.default_rng(int(fov * 1000) + size[0])
    points = rng.normal(size=(400, 3)) * [1.0, 3.0, 3.0] + [0.5, 0.0, 0.0]
    pixels = model.project(points)
    inside = (points[:, 0] > 0) & np.all((pixels >= 0) & (pixels <= size), axis=1)
    # away from the edges (where round-off decides) the two tests agree
    near_edge = np.any(np.abs(pixels - np.array(size) * np.round(pixels / size)) < 1e-6 * max(size), axis=1)
    np.testing.assert_array_equal(model.in_view(points)[~near_edge], inside[~near_edge])


def test_probe_rays_shrink_each_half_angle():
    model = CameraModel.from_fov(90.0, (1280, 720))
    rays = model.probe_rays(0.5)
    assert rays.shape == (9, 3)
    np.testing.assert_allclose(np.linalg.norm(rays, axis=1), 1.0, rtol=1e-12)
    np.testing.assert_allclose(rays[4], [1.0, 0.0, 0.0])
    half_v = math.atan(0.5625)
    # right-centre, left-centre, centre-up: angles of a quarter of the FOV and half the vertical half-angle
    assert math.atan2(rays[1, 1], rays[1, 0]) == pytest.approx(-math.pi / 8, rel=1e-12)
    assert math.atan2(rays[7, 1], rays[7, 0]) == pytest.approx(math.pi / 8, rel=1e-12)
    assert math.atan2(rays[5, 2], rays[5, 0]) == pytest.approx(half_v / 2, rel=1e-12)
    np.testing.assert_allclose(rays[8] / rays[8, 0], [1.0, math.tan(math.pi / 8), math.tan(half_v / 2)], rtol=1e-12)


def test_frustum_corners_span_near_to_far():
    corners = CameraModel.from_fov(90.0, (1280, 720)).frustum_corners(0.1, 2.0)
    assert corners.shape == (8, 3)
    np.testing.assert_allclose(corners[:4, 0], 0.1)
    np.testing.assert_allclose(corners[4:, 0], 2.0)
    expected = [[2, 2, 1.125], [2, 2, -1.125], [2, -2, 1.125], [2, -2, -1.125]]
    np.testing.assert_allclose(corners[4:], expected, rtol=1e-12)
    np.testing.assert_allclose(corners[:4] * 20, corners[4:], rtol=1e-12)


def test_view_margin_by_hand():
    model = CameraModel.from_fov(90.0, (1280, 720))
    points = np.array([[10.0, 0, 0], [10, 10, 0], [10, -5, 0], [10, 0, 5.625], [10, 0, -11.25], [10, 20, 0]])
    np.testing.assert_allclose(model.view_margin(points), [1.0, 0.0, 0.5, 0.0, -1.0, -1.0], atol=1e-12)


@given(fov=fov_deg, size=sizes)
def test_positive_view_margin_is_in_view(fov, size):
    model = CameraModel.from_fov(fov, size)
    points = np.random.default_rng(size[1]).normal(size=(300, 3)) + [1.0, 0.0, 0.0]
    margin = model.view_margin(points)
    clear = np.abs(margin) > 1e-9
    np.testing.assert_array_equal((margin > 0)[clear], model.in_view(points)[clear])


# --- in_frustum: a camera at the origin looking +x, FOV 90 deg, 1280 x 720 ---------------------------------

def frustum(points, rotation=IDENTITY, position=(0.0, 0.0, 0.0), fov=90.0, size=SIZE, **kwargs):
    return in_frustum(CameraModel.from_fov([fov], size), np.array([position], dtype=float), rotation,
                      np.array(points, dtype=float), **kwargs)[0]


def test_horizontal_limit_is_the_45_degree_line():
    # tan(90 / 2) = 1: at x = 10 the frustum reaches |y| = 10.
    assert frustum([[10, 9.99, 0], [10, -9.99, 0]]).tolist() == [True, True]
    assert frustum([[10, 10.01, 0], [10, -10.01, 0]]).tolist() == [False, False]


def test_vertical_limit_follows_the_aspect_ratio():
    # Square pixels: tan(vfov / 2) = tan(45 deg) * 720 / 1280 = 0.5625, so at x = 10 the limit is |z| = 5.625.
    tan_v = math.tan(math.radians(45.0)) * 720 / 1280
    limit = 10 * tan_v
    assert limit == pytest.approx(5.625)
    inside = [[10, 0, limit - 0.01], [10, 0, -(limit - 0.01)]]
    outside = [[10, 0, limit + 0.01], [10, 0, -(limit + 0.01)], [10, 0, 6.0]]  # 6 < 10: inside horizontally
    assert frustum(inside).tolist() == [True, True]
    assert frustum(outside).tolist() == [False, False, False]


def test_behind_the_camera_is_outside():
    # Mirror images of points well inside the frustum.
    assert not frustum([[-10, 0, 0], [-10, 1, 1], [-0.01, 0, 0], [0, 0, 0]]).any()
    assert frustum([[10, 0, 0], [10, 1, 1], [0.01, 0, 0]]).all()


def test_beyond_max_range_is_outside():
    assert frustum([[79.9, 0, 0], [80.1, 0, 0]], max_range=80.0).tolist() == [True, False]
    assert frustum([[1e6, 0, 0]]).tolist() == [True]  # no range limit by default
    # The range is the Euclidean distance, not the depth: (4, 3, 0) is 5 m away.
    assert frustum([[4, 2.9, 0], [4, 3.1, 0], [4.9, 0, 0]], max_range=5.0).tolist() == [True, False, True]


def test_yawed_camera_sees_left():
    rotation = rotation_from_yaw_pitch_roll(np.pi / 2, 0.0, 0.0)[None]
    seen = frustum([[0, 10, 0], [10, 0, 0], [0, -10, 0], [-9.99, 10, 0], [-10.01, 10, 0]], rotation)
    assert seen.tolist() == [True, False, False, True, False]


def test_translated_and_pitched_camera():
    # A camera at (1, 2, 3) pitched 90 deg down looks along -z; its image's horizontal axis is then
    # vehicle y, so the horizontal half-width at depth 3 is 3 m and the vertical one is 3 * 0.5625 m.
    rotation = rotation_from_yaw_pitch_roll(0.0, -np.pi / 2, 0.0)[None]
    points = [[1, 2, 0], [1, 2 + 2.99, 0], [1, 2 + 3.01, 0], [1 + 1.68, 2, 0], [1 + 1.70, 2, 0], [1, 2, 4]]
    assert frustum(points, rotation, position=(1, 2, 3)).tolist() == [True, True, False, True, False, False]


def test_camera_frame_points_by_hand():
    rotation = rotation_from_yaw_pitch_roll(np.pi / 2, 0.0, 0.0)  # looking left (+y)
    local = camera_frame_points([[1.0, 2.0, 3.0]], rotation[None], [[1.0, 7.0, 3.0], [0.0, 2.0, 4.0]])
    np.testing.assert_allclose(local, [[[5.0, 0.0, 0.0], [0.0, 1.0, 1.0]]], atol=1e-12)


def test_in_frustum_of_many_cameras_is_each_cameras():
    rng = np.random.default_rng(3)
    positions = rng.uniform(-2, 2, (5, 3))
    rotations = rotation_from_yaw_pitch_roll(rng.uniform(-3, 3, 5), rng.uniform(-1, 1, 5), np.zeros(5))
    fovs, image_sizes = rng.uniform(40, 170, 5), np.tile([1280, 720], (5, 1))
    points = rng.uniform(-20, 20, (500, 3))
    together = in_frustum(CameraModel.from_fov(fovs, image_sizes), positions, rotations, points, 15.0)
    alone = [in_frustum(CameraModel.from_fov(fovs[k:k + 1], image_sizes[k:k + 1]), positions[k:k + 1],
                        rotations[k:k + 1], points, 15.0)[0] for k in range(5)]
    np.testing.assert_array_equal(together, alone)
    assert 0 < together.sum() < together.size


# --- the fast paths give the plain computation's values to the bit ------------------------------------------------

def test_camera_frame_points_are_einsums_to_the_bit():
    rng = np.random.default_rng(8)
    yaws, pitches = np.meshgrid(np.deg2rad(np.arange(-180.0, 180.0, 45.0)), np.deg2rad([-90.0, -30.0, 0.0, 10.0]))
    rotations = rotation_from_yaw_pitch_roll(yaws.ravel(), pitches.ravel(), np.zeros(yaws.size))  # exact zeros too
    positions = rng.uniform(-3, 3, (len(rotations), 3))
    points = np.concatenate([rng.uniform(-30, 30, (400, 3)), positions[:3]])  # and points at a lens
    local = camera_frame_points(positions, rotations, points)
    expected = np.einsum("cji,cpj->cpi", rotations, points[None] - positions[:, None])
    np.testing.assert_array_equal(local, expected)
    assert np.array_equal(np.signbit(local), np.signbit(expected))  # the zeros' signs as well


@pytest.mark.parametrize("kind", ["pinhole", "fisheye", "mixed"])
def test_in_frustum_in_blocks_is_in_view_of_all(kind, monkeypatch):
    """Blocks of cameras, and a fisheye batch's own path, give the plain in_view of all cameras at once."""
    import rigopt.camera as camera

    rng = np.random.default_rng(9)
    n = 37
    fisheye = CameraModel.of_lens(FISHEYE_190)
    pinholes = CameraModel.from_fov(rng.uniform(40, 170, n), np.tile([1280, 720], (n, 1)))
    fisheyes = CameraModel(*(np.full(n, float(getattr(fisheye, a))) for a in ("width", "height", "fx", "fy", "cx",
                                                                                "cy")), "fisheye",
                           np.tile(fisheye.coefficients, (n, 1)) + rng.uniform(0, 0.01, (n, 5)) * [1, 0, 0, 0, 0])
    model = {"pinhole": pinholes, "fisheye": fisheyes,
             "mixed": CameraModel(*(np.where(np.arange(n) % 2 == 0, getattr(pinholes, a), getattr(fisheyes, a))
                                    for a in ("width", "height", "fx", "fy", "cx", "cy")),
                                  np.where(np.arange(n) % 2 == 0, "none", "fisheye"),
                                  np.where((np.arange(n) % 2 == 0)[:, None], 0.0, fisheyes.coefficients))}[kind]
    positions = rng.uniform(-2, 2, (n, 3))
    rotations = rotation_from_yaw_pitch_roll(rng.uniform(-3, 3, n), rng.uniform(-1.5, 0.5, n), np.zeros(n))
    points = rng.uniform(-20, 20, (300, 3))
    monkeypatch.setattr(camera, "FRUSTUM_BLOCK_ENTRIES", 5 * len(points))  # blocks of five cameras
    blocked = in_frustum(model, positions, rotations, points, 25.0)
    local = np.einsum("cji,cpj->cpi", rotations, points[None] - positions[:, None])
    # the general path, as in_view runs it for any batch that is not all fisheyes
    angle, u, v = model._distorted_view(local) if np.any(model.distorted) else (None, None, None)
    if kind == "pinhole":
        expected = model.in_view(local, 25.0)
    else:
        real = ((angle < model.valid_angles[:, None]) & (0 <= u) & (u <= model.width[:, None]) & (0 <= v)
                & (v <= model.height[:, None]))
        expected = np.where(model.distorted[:, None], real, model.in_view(local, 25.0)) if kind == "mixed" else real
        expected &= np.einsum("...i,...i->...", local, local) <= 25.0**2
    np.testing.assert_array_equal(blocked, expected)
    assert 0.05 < blocked.mean() < 0.95


def test_take_is_the_cameras_it_names():
    model = CameraModel.from_fov([60.0, 90.0, 120.0], [[1280, 720]] * 3)
    model.valid_angles  # derived before: carried over
    part = model.take(slice(1, 3))
    assert part.shape == (2,) and part.fx.tolist() == model.fx[1:].tolist()
    assert part.valid_angles.tolist() == model.valid_angles[1:].tolist()
    assert model.take(np.array([2, 0])).hfov.tolist() == pytest.approx([120.0, 60.0])
