"""Real lenses in rigopt.camera: the radtan and fisheye maths by hand, round trips, FOVs, what a distorted
lens sees (against brute-force projection), its checked frustum, and the batch model of mixed lenses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rigopt.camera import (MAX_FRUSTUM_HALF_ANGLE_DEG, CameraModel, Lens, distorted_coordinates, fisheye_distort,
                           radtan_distort, undistorted_directions, valid_angle)
from rigopt.errors import RigoptError
from rigopt.rig.model import Camera

#: An Argoverse-2-like front camera: 2048 x 1550, f about 1773 px, barrel radtan distortion (k1 < 0, k2 > 0).
ARGO = Lens(2048, 1550, 1773.0, 1773.0, 1024.0, 775.0, "radtan", (-0.26, 0.07, 0.0, 0.0, 0.0))
#: A surround-view fisheye (Kannala-Brandt) of about 200 degrees horizontally.
FISHEYE = Lens(1280, 960, 380.0, 380.0, 640.0, 480.0, "fisheye", (-0.02, 0.003, 0.0, 0.0))
#: Off-centre, non-square radtan with tangential terms.
SKEWED = Lens(1600, 1200, 1100.0, 1080.0, 790.0, 610.0, "radtan", (-0.12, 0.03, 0.001, -0.0005, -0.002))
LENSES = [ARGO, FISHEYE, SKEWED, Lens.pinhole(90.0)]


def random_pixels(lens: Lens, n=500, seed=0):
    return np.random.default_rng(seed).uniform([0, 0], [lens.width, lens.height], (n, 2))


# --- the formulas by hand ----------------------------------------------------------------------------------

def test_radtan_distortion_by_hand():
    k = np.array([-0.2, 0.05, 0.01, -0.02, 0.003])
    x, y = 0.3, -0.4
    r2 = 0.25
    radial = 1 - 0.2 * r2 + 0.05 * r2**2 + 0.003 * r2**3
    expected = (x * radial + 2 * 0.01 * x * y + -0.02 * (r2 + 2 * x * x),
                y * radial + 0.01 * (r2 + 2 * y * y) + 2 * -0.02 * x * y)
    np.testing.assert_allclose(radtan_distort(np.array(x), np.array(y), k), expected, rtol=1e-14)


def test_fisheye_distortion_by_hand():
    theta = 1.2
    expected = theta * (1 + 0.1 * theta**2 - 0.02 * theta**4 + 0.003 * theta**6 - 0.0004 * theta**8)
    assert float(fisheye_distort(theta, [0.1, -0.02, 0.003, -0.0004])) == pytest.approx(expected, rel=1e-14)


def test_an_equidistant_fisheye_puts_90_degrees_at_radius_pi_over_2():
    lens = Lens(1000, 1000, 300.0, 300.0, 500.0, 500.0, "fisheye", (0.0, 0.0, 0.0, 0.0))
    pixel = lens.project([[1.0, 0.0, 0.0]])[0]  # optical frame: 90 deg to the right
    np.testing.assert_allclose(pixel, [500.0 + 300.0 * math.pi / 2, 500.0], rtol=1e-12)
    # ... which is no pinhole: a fisheye is distorted even with zero coefficients.
    assert lens.is_distorted and not lens.is_ideal_pinhole


def test_shared_maths_invert_each_other_for_mixed_models():
    kinds = np.array(["none", "radtan", "fisheye"])[:, None]
    k = np.array([[0, 0, 0, 0, 0], [-0.2, 0.05, 0.001, 0.002, 0.0], [0.01, -0.002, 0, 0, 0]], float)[:, None, :]
    xd, yd = np.random.default_rng(1).uniform(-0.6, 0.6, (2, 3, 50))
    x, y, z = undistorted_directions(xd, yd, kinds, k)
    np.testing.assert_allclose(distorted_coordinates(x, y, z, kinds, k), (xd, yd), atol=1e-12)


# --- round trips and FOVs ----------------------------------------------------------------------------------

@pytest.mark.parametrize("lens", LENSES, ids=["argo", "fisheye", "skewed", "pinhole"])
def test_project_inverts_pixel_rays(lens):
    pixels = random_pixels(lens)
    np.testing.assert_allclose(lens.project(lens.pixel_rays(pixels)), pixels, atol=1e-7)
    model = CameraModel.of_lens(lens)
    np.testing.assert_allclose(model.project(model.pixel_rays(pixels)), pixels, atol=1e-7)
    np.testing.assert_allclose(model.pixel_rays(pixels, frame="optical"), lens.pixel_rays(pixels), atol=1e-14)


def test_barrel_distortion_widens_the_fov_beyond_the_pinholes():
    pinhole_hfov = math.degrees(2 * math.atan(1024 / 1773))
    assert pinhole_hfov == pytest.approx(60.02, abs=0.01)
    assert ARGO.hfov > pinhole_hfov + 4.0  # barrel distortion: the edge rays lie further out
    assert ARGO.hfov == pytest.approx(float(CameraModel.of_lens(ARGO).hfov), rel=1e-12)
    # The edge ray is the undistorted radius r with r (1 + k1 r^2 + k2 r^4) = 1024 / 1773.
    r = np.roots([0.07, 0, -0.26, 0, 1, -1024 / 1773])
    r = float(min(v.real for v in r if abs(v.imag) < 1e-12 and v.real > 0))
    assert ARGO.hfov == pytest.approx(2 * math.degrees(math.atan(r)), rel=1e-9)


def test_a_surround_view_fisheye_sees_about_200_degrees():
    assert 190.0 < FISHEYE.hfov < 205.0
    assert FISHEYE.vfov < FISHEYE.hfov
    camera = Camera("FISH", np.zeros(3), np.eye(3), FISHEYE)
    assert camera.fov == pytest.approx(FISHEYE.hfov) and camera.lens == FISHEYE
    assert float(CameraModel.of_camera(camera).hfov) == pytest.approx(FISHEYE.hfov, rel=1e-12)


def test_a_lens_whose_image_corners_fold_back_is_refused():
    with pytest.raises(RigoptError, match="folds back"):
        Lens(1280, 960, 330.0, 330.0, 640.0, 480.0, "fisheye", (0.05, -0.01, 0.0, 0.0))


def test_valid_angles_by_hand():
    assert valid_angle("none", [0] * 5) == pytest.approx(math.pi / 2)
    # k1 = -0.3 alone: d/dr r (1 - 0.3 r^2) = 1 - 0.9 r^2 = 0 at r = 1 / sqrt(0.9)
    assert valid_angle("radtan", [-0.3, 0, 0, 0, 0]) == pytest.approx(math.atan(1 / math.sqrt(0.9)), rel=1e-12)
    assert valid_angle("radtan", [-0.26, 0.07, 0, 0, 0]) == pytest.approx(math.pi / 2)  # never folds
    # theta (1 - 0.1 theta^2): folds at theta = 1 / sqrt(0.3); a plain equidistant lens at pi
    assert valid_angle("fisheye", [-0.1, 0, 0, 0]) == pytest.approx(1 / math.sqrt(0.3), rel=1e-12)
    assert valid_angle("fisheye", [0, 0, 0, 0]) == pytest.approx(math.pi)


# --- what a distorted lens sees ---------------------------------------------------------------------------

def brute_force_in_view(lens: Lens, points):
    """In view when the point projects into the image and the ray of that pixel is the point's direction
    (so images folding back do not count), body frame points."""
    optical = np.stack([-points[:, 1], -points[:, 2], points[:, 0]], axis=1)
    direction = optical / np.linalg.norm(optical, axis=1, keepdims=True)
    with np.errstate(all="ignore"):
        pixels = lens.project(optical)
        inside = ((pixels >= 0) & (pixels <= [lens.width, lens.height])).all(axis=1) & np.isfinite(pixels).all(1)
        if lens.distortion != "fisheye":
            inside &= optical[:, 2] > 0
        back = np.zeros_like(direction)
        back[inside] = lens.pixel_rays(pixels[inside])
    return inside & (np.einsum("ij,ij->i", back, direction) > 1 - 1e-9)


FOLDING = Lens(800, 600, 1000.0, 1000.0, 400.0, 300.0, "radtan", (-0.3, 0.0, 0.0, 0.0, 0.0))


@pytest.mark.parametrize("lens", [ARGO, FISHEYE, SKEWED, FOLDING], ids=["argo", "fisheye", "skewed", "folding"])
def test_in_view_of_distorted_lenses_is_brute_force_projection(lens):
    points = np.random.default_rng(3).normal(size=(20000, 3)) + [0.5, 0.0, 0.0]
    model = CameraModel.of_lens(lens)
    seen = model.in_view(points)
    expected = brute_force_in_view(lens, points)
    pixels = model.project(points)
    margin = np.minimum(np.abs(pixels - [0, 0]), np.abs(pixels - [lens.width, lens.height])).min(axis=-1)
    clear = ~np.isfinite(margin) | (margin > 1e-6)  # away from the image's edges
    np.testing.assert_array_equal(seen[clear], expected[clear])
    assert seen.sum() > 100


def test_a_folding_radtan_lens_does_not_see_what_folds_back_into_its_image():
    # k1 = -0.3: beyond r = 1.054 (46.5 deg) the image folds back; at r = 2 the point lands inside the image.
    model = CameraModel.of_lens(FOLDING)
    point = np.array([[1.0, -2.0 / math.sqrt(2), 2.0 / math.sqrt(2)]])  # body frame, r = 2 off the axis
    u, v = model.project(point)[0]
    assert 0 <= u <= 800 and 0 <= v <= 600  # projects inside ...
    assert not model.in_view(point)[0]  # ... but is not seen
    assert model.view_margin(point)[0] < 0


def test_a_fisheye_sees_behind_its_lens_plane_and_a_pinhole_does_not():
    behind = np.array([[-0.1, 1.0, 0.0], [-0.1, -1.0, 0.0]])  # 96 deg off the axis, left and right
    assert CameraModel.of_lens(FISHEYE).in_view(behind).all()
    assert not CameraModel.from_fov(170.0, (1280, 960)).in_view(behind).any()


def test_a_fisheye_sees_more_than_a_pinhole_of_the_same_focal_length():
    pinhole = Lens(1280, 960, 380.0, 380.0, 640.0, 480.0)
    points = np.random.default_rng(4).normal(size=(20000, 3))
    model = CameraModel.of_lenses([pinhole, FISHEYE])
    seen = model.in_view(points[None].repeat(2, axis=0))
    assert seen[1].sum() > 1.5 * seen[0].sum()
    assert np.all(seen[1] | ~seen[0])  # every direction the pinhole sees lands nearer the centre in the fisheye


def test_view_margin_of_a_distorted_lens_is_positive_exactly_in_view():
    points = np.random.default_rng(5).normal(size=(5000, 3)) + [0.8, 0.0, 0.0]
    for lens in (ARGO, FISHEYE, SKEWED, FOLDING):
        model = CameraModel.of_lens(lens)
        margin = model.view_margin(points)
        clear = np.abs(margin) > 1e-9
        np.testing.assert_array_equal((margin > 0)[clear], model.in_view(points)[clear])
    np.testing.assert_allclose(CameraModel.of_lens(ARGO).view_margin(np.array([[5.0, 0.0, 0.0]])), [1.0])


def test_a_mixed_batch_answers_each_camera_as_alone():
    lenses = [ARGO, Lens.pinhole(70.0, (640, 480)), FISHEYE]
    batch = CameraModel.of_lenses(lenses)
    points = np.random.default_rng(6).normal(size=(3, 400, 3)) + [1.0, 0.0, 0.0]
    for k, lens in enumerate(lenses):
        alone = CameraModel.of_lens(lens)
        np.testing.assert_array_equal(batch.in_view(points)[k], alone.in_view(points[k]))
        np.testing.assert_allclose(batch.view_margin(points)[k], alone.view_margin(points[k]), rtol=1e-12)
        np.testing.assert_allclose(batch.probe_rays(0.5)[k], alone.probe_rays(0.5), rtol=1e-12)
        assert batch.lens(k) == lens


def test_a_lens_maps_through_its_own_batch_model_and_a_camera_reads_it():
    """One lens API: a Lens is the batch model of one camera (Lens.model), its rays, projections and FOVs that
    model's, and a rig camera's model is its lens's."""
    for lens in LENSES:
        pixels = random_pixels(lens, 50, seed=8)
        optical = lens.model.pixel_rays(pixels, frame="optical")
        np.testing.assert_array_equal(lens.pixel_rays(pixels), optical)
        np.testing.assert_array_equal(lens.project(optical), lens.model.project(optical, frame="optical"))
        assert lens.derived_hfov == float(lens.model.hfov) and lens.vfov == float(lens.model.vfov)
        camera = Camera("C", np.zeros(3), np.eye(3), lens)
        assert CameraModel.of_camera(camera) is lens.model


def test_pinholes_given_as_lenses_are_the_from_fov_model_exactly():
    fovs, size = np.array([60.0, 90.0, 120.0]), (1280, 720)
    a = CameraModel.of_lenses([Lens.pinhole(f, size) for f in fovs])
    b = CameraModel.from_fov(fovs, size)
    points = np.random.default_rng(7).normal(size=(3, 100, 3))
    for name in ("fx", "fy", "cx", "cy"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    np.testing.assert_array_equal(a.in_view(points), b.in_view(points))
    np.testing.assert_array_equal(a.frustum_corners(0.02, 1.0, 0.5), b.frustum_corners(0.02, 1.0, 0.5))


# --- the checked frustum ----------------------------------------------------------------------------------

def test_a_barrel_lens_frustum_holds_its_whole_image():
    model = CameraModel.of_lens(ARGO)
    left, right, up, down = (math.tan(a) for a in model.side_angles())
    rays = model.pixel_rays(random_pixels(ARGO, 3000))
    a, b = rays[:, 1] / rays[:, 0], rays[:, 2] / rays[:, 0]
    assert np.all((-right - 1e-9 <= a) & (a <= left + 1e-9) & (-down - 1e-9 <= b) & (b <= up + 1e-9))
    edge = [math.tan(t) for t in model.edge_angles()]
    assert left > edge[0] and up > edge[2]  # the corners' rays lie outside the edge midpoints'


def test_a_wide_fisheyes_frustum_is_capped_and_convex():
    model = CameraModel.of_lens(FISHEYE)
    cap = math.radians(MAX_FRUSTUM_HALF_ANGLE_DEG)
    assert max(model.side_angles()) == pytest.approx(cap)
    corners = model.frustum_corners(0.02, 1.0, 1.0)
    assert np.all(np.isfinite(corners)) and np.all(corners[:, 0] > 0)
    np.testing.assert_allclose(corners[4:] / 50.0, corners[:4], rtol=1e-12)  # far plane = scaled near plane
    rays = model.probe_rays(0.5)
    np.testing.assert_allclose(np.linalg.norm(rays, axis=1), 1.0, rtol=1e-12)
    assert np.all(rays[:, 0] > 0)


def test_pixel_rays_at_unit_depth_refuse_fisheye_rays_behind_the_lens_plane():
    model = CameraModel.of_lens(FISHEYE)
    with pytest.raises(RigoptError, match="unit depth"):
        model.pixel_rays([[0.0, 480.0]], unit=False)
    ray = model.pixel_rays([[400.0, 300.0]], unit=False)
    assert ray[0, 0] == pytest.approx(1.0)


def test_resized_models_scale_the_intrinsics_and_keep_the_rays():
    model = CameraModel.of_lens(ARGO)
    half = model.resized((1024, 775))
    assert float(half.fx) == pytest.approx(886.5) and float(half.cx) == pytest.approx(512.0)
    np.testing.assert_allclose(half.pixel_rays([[100.0, 50.0]]), model.pixel_rays([[200.0, 100.0]]), atol=1e-12)
