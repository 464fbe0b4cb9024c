"""The benchmark renderer: closed-form geometry of ground, boxes and ego body, road shading, determinism."""

import numpy as np
import pytest
import trimesh

from rigopt.validation.synthetic import render as render_module
from rigopt.validation.synthetic.render import EgoBody, Rendered, render_camera, render_rig
from rigopt.validation.synthetic.scene_model import Boxes, Frame, Road, Scene
from rigopt.geometry import rot_y, rot_z
from rigopt.rig.model import Camera, Rig

W, H = 160, 90
F = 80.0  # focal (px) of a 90 degree horizontal FOV at width 160: 0.5 * 160 / tan(45 deg)
CX, CY = 80.0, 45.0
NO_ROAD = Road("straight", (), np.zeros((0, 2, 2)), 0.15, np.zeros((0, 2, 2)))


def pose(x=0.0, y=0.0, yaw=0.0):
    T = np.eye(4)
    T[:3, :3] = rot_z(yaw)
    T[:3, 3] = [x, y, 0.0]
    return T


def boxes(centers, sizes, yaws=None, classes=None, instance=None):
    centers, sizes = np.atleast_2d(np.asarray(centers, float)), np.atleast_2d(np.asarray(sizes, float))
    n = len(centers)
    return Boxes(centers, sizes, np.zeros(n) if yaws is None else np.asarray(yaws, float),
                 np.zeros(n, int) if classes is None else np.asarray(classes),
                 np.arange(n) if instance is None else np.asarray(instance))


def scene(static=None, road=NO_ROAD, T=None, agents=None):
    frame = Frame(0, pose() if T is None else T, Boxes.empty() if agents is None else agents)
    return Scene("scene-render", 0, "mini", road, Boxes.empty() if static is None else static, (frame,))


def camera(position=(0.0, 0.0, 1.5), rotation=None, fov=90.0, cam_id="CAM"):
    return Camera.pinhole(cam_id, np.array(position, float), np.eye(3) if rotation is None else rotation, fov)


def rectangle(cols, rows, shape=(H, W)):
    """(h, w) bool: True on columns cols[0]..cols[1] and rows rows[0]..rows[1] (inclusive)."""
    mask = np.zeros(shape, bool)
    mask[rows[0]:rows[1] + 1, cols[0]:cols[1] + 1] = True
    return mask


def test_level_camera_over_empty_ground_sees_sky_above_and_ground_below_the_principal_row():
    h = 1.5
    # The ego pose must not matter for a flat world: drive somewhere and turn.
    out = render_camera(scene(T=pose(30.0, -12.0, 2.0)), 0, camera((0.0, 0.0, h)), None, (W, H), max_range=np.inf)
    sky = np.isinf(out.depth)
    # Pixel row v has its centre at v + 0.5: rows 0..44 look above the horizon (cy = 45), rows 45.. below.
    assert sky[:45].all() and not sky[45:].any()
    v = np.arange(45, H) + 0.5
    expected = h * F / (v - CY)  # depth along the optical axis, the same in every column
    np.testing.assert_allclose(out.depth[45:], np.broadcast_to(expected[:, None], (H - 45, W)), rtol=1e-6)
    assert (out.object_id == -1).all()


def test_ground_beyond_max_range_is_sky():
    h, max_range = 1.5, 40.0
    out = render_camera(scene(), 0, camera((0.0, 0.0, h)), None, (W, H), max_range=max_range)
    u, v = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    with np.errstate(divide="ignore"):
        depth = np.where(v > CY, h * F / (v - CY), np.inf)
    distance = depth * np.sqrt(1 + ((u - CX) / F) ** 2 + ((v - CY) / F) ** 2)
    np.testing.assert_array_equal(np.isinf(out.depth), distance > max_range)


def test_box_straight_ahead_covers_its_projected_near_face_at_its_distance():
    # Near face at x = 10 m, y in [-1.5, 2.5], z in [0.5, 2.5]; the lens is at height 1.5 m.
    box = boxes([11.0, 0.5, 1.5], [2.0, 4.0, 2.0], instance=[42])
    out = render_camera(scene(box), 0, camera(), None, (W, H))
    # u = cx - f y / x, v = cy - f (z - 1.5) / x: u in [60, 92], v in [37, 53]; pixel centres inside
    # that rectangle are columns 60..91 and rows 37..52.
    expected = rectangle((60, 91), (37, 52))
    np.testing.assert_array_equal(out.object_id == 42, expected)
    assert set(np.unique(out.object_id)) == {-1, 42}
    np.testing.assert_allclose(out.depth[expected], 10.0, rtol=1e-6)


def test_box_yaw_and_ego_pose_are_applied():
    # The same box as above relative to an ego parked at (100, 50) heading north (the camera looks along
    # world +y, its left is world -x), the box turned with it: its 2 m length runs along world y.
    box = boxes([100.0 - 0.5, 50.0 + 11.0, 1.5], [2.0, 4.0, 2.0], yaws=[np.pi / 2], instance=[7])
    out = render_camera(scene(box, T=pose(100.0, 50.0, np.pi / 2)), 0, camera(), None, (W, H))
    np.testing.assert_array_equal(out.object_id == 7, rectangle((60, 91), (37, 52)))
    np.testing.assert_allclose(out.depth[out.object_id == 7], 10.0, rtol=1e-6)


def test_a_box_behind_the_camera_is_not_visible():
    empty = render_camera(scene(), 0, camera(), None, (W, H))
    out = render_camera(scene(boxes([-11.0, 0.5, 1.5], [2.0, 4.0, 2.0])), 0, camera(), None, (W, H))
    assert (out.object_id == -1).all()
    np.testing.assert_array_equal(out.depth, empty.depth)
    np.testing.assert_array_equal(out.rgb, empty.rgb)


def test_the_nearest_of_two_boxes_wins_and_a_box_around_the_lens_is_ignored():
    near = boxes([11.0, 0.5, 1.5], [2.0, 4.0, 2.0], instance=[1])
    far = boxes([21.0, 0.0, 1.5], [2.0, 40.0, 20.0], instance=[2])
    around = boxes([0.0, 0.0, 1.5], [1.0, 1.0, 1.0], instance=[3])
    out = render_camera(scene(Boxes.concatenate([far, near, around])), 0, camera(), None, (W, H))
    front = rectangle((60, 91), (37, 52))
    assert (out.object_id[front] == 1).all()
    # The far face spans v = cy -+ f * 10 / 20 (rows 5..84); above row 51 the ground lies beyond 20 m
    # (1.5 * f / (v + 0.5 - cy) > 20): the far box shows on rows 5..50 outside the near one.
    behind = ~front & ((np.arange(H) >= 5) & (np.arange(H) <= 50))[:, None]
    assert (out.object_id[behind] == 2).all()
    np.testing.assert_allclose(out.depth[behind], 20.0, rtol=1e-6)



def test_a_wall_beside_and_behind_the_lens_shows_only_ahead():
    # Wall: y in [3, 4], x in [-20, 20], z in [0, 3]; the lens at the origin, height 1.5, looking along +x.
    # The ray (1, a, b) (a = -(u + 0.5 - cx) / f, b = -(v + 0.5 - cy) / f) meets its face y = 3 at depth
    # 3 / a when a > 0, x = 3 / a <= 20 and |1.5 + 3 b / a - 1.5| <= 1.5. Rays turned away from it (a < 0)
    # meet its line only behind the lens.
    wall = boxes([0.0, 3.5, 1.5], [40.0, 1.0, 3.0], instance=[9])
    out = render_camera(scene(wall), 0, camera(), None, (W, H))
    u, v = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    a, b = -(u - CX) / F, -(v - CY) / F
    expected = (a >= 0.15) & (np.abs(b) <= a / 2)
    np.testing.assert_array_equal(out.object_id == 9, expected)
    np.testing.assert_allclose(out.depth[expected], 3.0 / a[expected], rtol=1e-6)


@pytest.mark.parametrize("yaw", [0.0, 1.3, np.pi, -2.0])
def test_screen_tiles_do_not_change_the_image(monkeypatch, yaw):
    s, cam = city(), camera((1.5, 0.3, 1.6), rot_z(yaw), fov=120.0)
    monkeypatch.setattr(render_module, "TILE", 10**6)  # one tile: every box on screen meets every ray
    whole = render_camera(s, 0, cam, None, (W, H))
    monkeypatch.setattr(render_module, "TILE", 4)  # small tiles: each meets only the boxes projected on it
    tiled = render_camera(s, 0, cam, None, (W, H))
    np.testing.assert_array_equal(whole.object_id, tiled.object_id)
    np.testing.assert_array_equal(whole.depth, tiled.depth)
    assert (whole.object_id >= 0).any()

def box_mesh():
    """A 2 x 2 x 2 m box: x, y in [-1, 1], z in [0, 2], ego frame."""
    mesh = trimesh.creation.box((2.0, 2.0, 2.0))
    mesh.apply_translation((0.0, 0.0, 1.0))
    return mesh


def ego_box():
    """The box as the ego body."""
    return EgoBody(box_mesh())


def test_a_camera_looking_back_at_the_ego_body_sees_it_and_nothing_behind_it():
    # The camera 4 m ahead of the body's front face (x = 1), looking back (-x) at height 1; a large box
    # (instance 7) stands 10 m behind the lens. Ego face: |y|, |z - 1| <= 1 at depth 4: +-20 px around
    # the centre, columns and rows 60..99 and 25..64. Box face: |y| <= 3, z - 1 in [-1, 3] at depth 10:
    # u in [56, 104], v in [21, 53]; below it the ground is nearer.
    behind = boxes([-6.0, 0.0, 2.0], [2.0, 6.0, 4.0], instance=[7])
    cam = camera((5.0, 0.0, 1.0), rot_z(np.pi))
    out = render_camera(scene(behind), 0, cam, ego_box(), (W, H))
    body = rectangle((60, 99), (25, 64))
    box = rectangle((56, 103), (21, 52))
    assert (out.object_id[body] == -1).all()
    np.testing.assert_allclose(out.depth[body], 4.0, atol=1e-3)
    assert (out.object_id[box & ~body] == 7).all() and (out.object_id[~box] == -1).all()
    # The body colour: the face's normal is +x; fixed colour, Lambert light, a little fog.
    light = render_module.AMBIENT + render_module.DIFFUSE * max(render_module.SUN[0], 0.0)
    u, v = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    distance = 4.0 * np.sqrt(1 + ((u - CX) / F) ** 2 + ((v - CY) / F) ** 2)
    fog = (1 - np.exp(-distance / render_module.FOG_DISTANCE))[..., None]
    expected = 255 * (render_module.EGO * light * (1 - fog) + render_module.SKY_HORIZON * fog)
    np.testing.assert_allclose(out.rgb[body], expected[body], atol=1.0)
    # Without the body the box shows through.
    bare = render_camera(scene(behind), 0, cam, None, (W, H))
    assert (bare.object_id[body & box] == 7).all()
    np.testing.assert_allclose(bare.depth[body & box], 10.0, rtol=1e-6)


def test_a_camera_a_centimetre_from_the_body_sees_only_the_body():
    out = render_camera(scene(), 0, camera((1.01, 0.0, 1.0), rot_z(np.pi)), ego_box(), (W, H))
    np.testing.assert_allclose(out.depth, 0.01, atol=1e-3)
    assert (out.object_id == -1).all()


def test_road_surface_markings_and_grass_are_shaded_apart():
    # Looking straight down from 10 m: the ground point of pixel (u, v) is x = -(v + 0.5 - cy) / f * 10,
    # y = -(u + 0.5 - cx) / f * 10, so 1 px = 0.125 m. The road is |y| <= 3 (columns 56..103), the
    # pavement strip reaches |y| <= 7 (columns 24..135), a 0.5 m marking along y = 0 covers columns 78..81.
    road = Road("straight", (np.array([[-50, -3.0], [50, -3.0], [50, 3.0], [-50, 3.0]]),),
                np.array([[[-50.0, 0.0], [50.0, 0.0]]]), 0.5, np.zeros((0, 2, 2)))
    down = camera((0.0, 0.0, 10.0), rot_y(np.pi / 2))
    out = render_camera(scene(road=road), 0, down, None, (W, H))
    np.testing.assert_allclose(out.depth, 10.0, rtol=1e-6)
    rgb = out.rgb.astype(int)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    marking = (r > 140) & (g > 140) & (b > 140)
    asphalt = np.r_[56:77, 83:104]
    assert marking[:, 78:82].all() and not marking[:, asphalt].any() and not marking[:, [77, 82]].any()
    assert (rgb[:, asphalt].max(axis=-1) < 110).all() and (np.ptp(rgb[:, asphalt], axis=-1) < 12).all()
    grass = np.r_[0:23, 137:160]
    assert (g[:, grass] > r[:, grass] + 10).all() and (g[:, grass] > b[:, grass] + 10).all()
    pavement = np.r_[25:55, 105:135]
    assert rgb[:, pavement].mean() > rgb[:, asphalt].mean() + 40
    # the ground has texture: not one flat colour on the asphalt
    assert rgb[:, asphalt].std() > 2.0


def city():
    """About 200 boxes of every class and occluder along a straight road."""
    rng = np.random.default_rng(3)
    rows = []
    for side in (-1, 1):
        rows += [([x, side * 16, 6.0], [12, 8, 12.0], 0.0, -1) for x in np.arange(-60, 140, 14)]
        rows += [([x, side * 8.5, 3.0], [0.25, 0.25, 6.0], 0.0, -1) for x in np.arange(-40, 120, 20)]
        rows += [([x, side * 8.3, 1.4], [0.08, 0.7, 2.8], 0.0, 7) for x in np.arange(-30, 120, 25)]
        rows += [([x, side * 7.5, 4.5], [0.3, 0.3, 0.9], 0.0, 8) for x in (40.0, 90.0)]
    sizes = {0: (4.5, 1.9, 1.5), 1: (8, 2.5, 3.2), 2: (12, 2.6, 3.2), 3: (2.1, 0.8, 1.5), 4: (1.8, 0.6, 1.7),
             5: (0.5, 0.6, 1.75), 6: (0.4, 0.4, 1.2)}
    for _ in range(110):
        k = int(rng.integers(0, 7))
        size = sizes[k]
        y = rng.choice([-5.25, -1.75, 1.75, 5.25]) if k < 3 else rng.choice([-1, 1]) * rng.uniform(7.5, 10.5)
        rows.append(([rng.uniform(-40, 130), y, size[2] / 2], size, rng.uniform(-np.pi, np.pi), k))
    static = Boxes(np.array([r[0] for r in rows], float), np.array([r[1] for r in rows], float),
                   np.array([r[2] for r in rows]), np.array([r[3] for r in rows]), np.arange(len(rows)) + 1000)
    road = Road("straight", (np.array([[-200, -7.0], [300, -7.0], [300, 7.0], [-200, 7.0]]),),
                np.array([[[x, y], [x + 3, y]] for y in (-3.5, 0.0, 3.5) for x in np.arange(-200, 300, 9)], float),
                0.15, np.array([[[-200, -7.0], [300, -7.0]], [[-200, 7.0], [300, 7.0]]]))
    return scene(static, road, pose(0.0, -1.75, 0.05))


def test_rendering_is_deterministic_and_typed():
    s = city()
    assert len(s.boxes_at(0)) >= 150
    cam = camera((1.5, 0.3, 1.6), rot_z(0.4), fov=100.0)
    first = render_camera(s, 0, cam, ego_box(), (W, H))
    render_camera(scene(), 0, cam, None, (W, H))  # something else in between
    second = render_camera(city(), 0, cam, ego_box(), (W, H))
    for name in ("rgb", "depth", "object_id", "intrinsics"):
        np.testing.assert_array_equal(getattr(first, name), getattr(second, name))
    assert first.rgb.shape == (H, W, 3) and first.rgb.dtype == np.uint8
    assert first.depth.shape == (H, W) and first.depth.dtype == np.float32
    assert first.object_id.shape == (H, W) and first.object_id.dtype == np.int32
    assert first.intrinsics.shape == (3, 3)
    assert (first.object_id >= 0).mean() > 0.2  # the street is full of boxes
    assert set(np.unique(first.object_id)) <= {-1} | set(s.boxes_at(0).instance.tolist())
    assert np.isfinite(first.depth[first.object_id >= 0]).all() and (first.depth > 0).all()


@pytest.mark.parametrize("fov, size", [(90.0, (160, 90)), (60.0, (320, 240)), (150.0, (64, 48))])
def test_intrinsics_follow_the_horizontal_fov_and_the_render_size(fov, size):
    out = render_camera(scene(), 0, camera(fov=fov), None, size)
    w, h = size
    f = 0.5 * w / np.tan(np.deg2rad(fov) / 2)
    np.testing.assert_allclose(out.intrinsics, [[f, 0, w / 2], [0, f, h / 2], [0, 0, 1]], rtol=1e-12)
    assert out.rgb.shape == (h, w, 3) and out.depth.shape == (h, w)


def test_render_rig_renders_every_camera():
    s = scene(boxes([11.0, 0.5, 1.5], [2.0, 4.0, 2.0], instance=[5]))
    rig = Rig("test", "box", (camera(cam_id="FRONT"), camera(rotation=rot_z(np.pi), cam_id="BACK")))
    out = render_rig(s, 0, rig, None, (W, H))
    assert list(out) == ["FRONT", "BACK"] and all(isinstance(r, Rendered) for r in out.values())
    np.testing.assert_array_equal(out["FRONT"].rgb, render_camera(s, 0, rig.cameras[0], None, (W, H)).rgb)
    assert (out["FRONT"].object_id == 5).any() and not (out["BACK"].object_id == 5).any()


def test_full_resolution_renders_the_same_geometry():
    box = boxes([11.0, 0.5, 1.5], [2.0, 4.0, 2.0], instance=[42])
    body = EgoBody(box_mesh().apply_translation((-2.0, 0.0, 0.0)))  # behind the lens, out of view
    out = render_camera(scene(box), 0, camera(), body, (1280, 720))
    assert out.rgb.shape == (720, 1280, 3)
    # f = 640: u in [480, 736], v in [296, 424] -> columns 480..735, rows 296..423.
    np.testing.assert_array_equal(out.object_id == 42, rectangle((480, 735), (296, 423), (720, 1280)))


def test_shading_and_ego_rays_in_chunks_give_the_same_image(monkeypatch):
    s, cam = city(), camera((5.0, 0.0, 1.0), rot_z(np.pi - 0.5), fov=120.0)  # the body and the street
    whole = render_camera(s, 0, cam, ego_box(), (W, H))
    monkeypatch.setattr(render_module, "CHUNK", 97)  # many chunks of body rays too
    chunked = render_camera(s, 0, cam, ego_box(), (W, H))
    for name in ("rgb", "depth", "object_id"):
        np.testing.assert_array_equal(getattr(whole, name), getattr(chunked, name))
    bare = render_camera(s, 0, cam, None, (W, H))
    assert (whole.depth < bare.depth).sum() > 5 * 97  # the body is in view


# --- real lenses ------------------------------------------------------------------------------------------

def test_a_fisheye_camera_renders_at_the_asked_size_and_sees_below_its_lens_plane():
    from rigopt.camera import Lens

    lens = Lens(1280, 960, 380.0, 380.0, 640.0, 480.0, "fisheye", (-0.02, 0.003, 0.0, 0.0))  # ~200 degrees
    fisheye = Camera("FISH", np.array([0.0, 0.0, 1.5]), np.eye(3), lens)
    out = render_camera(scene(), 0, fisheye, None, (W, H))
    assert out.rgb.shape == (H, W, 3) and out.rgb.dtype == np.uint8
    assert out.depth.shape == (H, W) and out.object_id.shape == (H, W)
    assert out.model is not None and float(out.model.width) == W and out.model.distortion == "fisheye"
    # ground below the horizon row, sky above; at the image's left and right edges the lens looks ~100 deg
    # off the axis, behind its own plane: the ground there has negative depth along the axis.
    sky = np.isinf(out.depth)
    assert sky[: H // 2 - 1].all() and not sky[H // 2 + 1:].any()
    assert out.depth[-1, 0] < 0 < out.depth[-1, W // 2]


def test_a_radtan_camera_renders_the_ground_where_its_lens_puts_it():
    from rigopt.camera import CameraModel, Lens, pixel_centres

    lens = Lens(2048, 1550, 1773.0, 1773.0, 1024.0, 775.0, "radtan", (-0.26, 0.07, 0.0, 0.0, 0.0))
    level = Camera("ARGO", np.array([0.0, 0.0, 1.5]), np.eye(3), lens)
    size = (128, 97)
    out = render_camera(scene(), 0, level, None, size)
    assert out.rgb.shape == (97, 128, 3)
    # depth along the axis of the ground point each pixel's (distorted) ray meets: 1.5 / (-z) of its unit ray
    rays = CameraModel.of_lens(lens).resized(size).pixel_rays(pixel_centres(*size))
    down = rays[:, 2] < 0
    expected = np.where(down, 1.5 * rays[:, 0] / np.where(down, -rays[:, 2], 1.0), np.inf).reshape(97, 128)
    ground = np.isfinite(out.depth) & np.isfinite(expected) & (expected < 100)
    assert ground.sum() > 1000
    np.testing.assert_allclose(out.depth[ground], expected[ground], rtol=1e-5)
    pinhole = render_camera(scene(), 0, Camera.pinhole("P", level.position, level.rotation, 2 * np.degrees(
        np.arctan(1024 / 1773)), (2048, 1550)), None, size)
    assert not np.array_equal(np.isinf(pinhole.depth), np.isinf(out.depth)) or \
        not np.allclose(pinhole.depth[ground], out.depth[ground])


def test_a_fisheye_rig_sees_a_box_beside_it_and_a_pinhole_does_not():
    from rigopt.validation.synthetic.generate import visible_fractions
    from rigopt.camera import Lens

    lens = Lens(1280, 960, 380.0, 380.0, 640.0, 480.0, "fisheye", (-0.02, 0.003, 0.0, 0.0))
    beside = boxes([[0.0, 6.0, 1.0]], [[3.0, 2.0, 2.0]])  # left of the lens, 90 degrees off a forward axis
    fisheye = Rig("fish", "v", (Camera("F", np.array([0.0, 0.0, 1.5]), np.eye(3), lens),))
    pinhole = Rig("pin", "v", (camera(fov=120.0, cam_id="F"),))
    the_scene = scene(static=beside)
    fractions = [visible_fractions(beside, rig, np.eye(4), render_rig(the_scene, 0, rig, None, (W, H)))[0]
                 for rig in (fisheye, pinhole)]
    assert 0.2 < fractions[0] <= 1.0 and fractions[1] == 0.0


def test_the_ego_body_casts_each_camera_once_and_pickles_as_its_mesh(monkeypatch):
    """A body keeps each camera's view (the same arrays on the next frame), casts anew for another camera, and
    crosses to a worker process as its mesh alone: the view cast there is the same."""
    import pickle

    calls = []
    real = render_module._ego_hits
    monkeypatch.setattr(render_module, "_ego_hits", lambda *args: calls.append(1) or real(*args))
    s, body = city(), ego_box()
    cam = camera((5.0, 0.0, 1.0), rot_z(np.pi - 0.5), fov=120.0)
    first = render_camera(s, 0, cam, body, (W, H))
    again = render_camera(s, 0, cam, body, (W, H))
    assert len(calls) == 1
    np.testing.assert_array_equal(first.depth, again.depth)
    render_camera(s, 0, camera((5.0, 0.0, 1.0), rot_z(np.pi)), body, (W, H))
    assert len(calls) == 2
    copy = pickle.loads(pickle.dumps(body))
    assert copy._views == {} and len(copy.mesh.faces) == len(body.mesh.faces)
    np.testing.assert_array_equal(render_camera(s, 0, cam, copy, (W, H)).rgb, first.rgb)


def test_a_road_builds_its_regions_once_and_pickles_without_them():
    import pickle

    road = city().road
    assert road.regions is road.regions
    copy = pickle.loads(pickle.dumps(road))
    assert "regions" not in copy.__dict__ and (copy.kind, copy.marking_width) == (road.kind, road.marking_width)
    assert np.array_equal(copy.markings, road.markings) and np.array_equal(copy.kerbs, road.kerbs)
    assert [r is None for r in copy.regions] == [r is None for r in road.regions]
