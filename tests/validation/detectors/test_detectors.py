"""The two detector families on rigs of different camera counts, and the geometry they rest on.

Oracles:
* pixel rays: the ray through the principal point is the camera's optical axis (the third column of
  cam_to_ego's rotation); any other pixel (u, v) goes along forward + (u - cx)/fx * right + (v - cy)/fy * down,
  with forward, right, down the camera's axes in the ego frame (hand-written for a camera yawed by psi:
  forward (cos psi, sin psi, 0), right (sin psi, -cos psi, 0), down (0, 0, -1)).
* splat: a volume that is zero except at chosen (sample, depth bin, pixel, channel) entries gives a bird's-eye
  map that is zero except at the cells below the hand-computed 3D points, floor((x + range) / cell) and
  floor((y + range) / cell); points outside the square or the height limits leave no trace.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from rigopt.validation.detectors.config import model_config  # noqa: E402
from rigopt.validation.detectors.families import DETECTORS  # noqa: E402
from rigopt.validation.detectors.data import Batch, BoxTargets, RigSplit  # noqa: E402
from rigopt.validation.detectors.layers import pixel_rays  # noqa: E402
from rigopt.validation.detectors.lss import HEIGHT_LIMITS, LSSDetector  # noqa: E402
from rigopt.validation.detectors.models import build_model, resolve_device  # noqa: E402
from rigopt.validation.synthetic.scene_model import CLASSES  # noqa: E402
from rigopt.errors import DataError, RigoptError, UnknownNameError  # noqa: E402
from rigopt.geometry import R_CAM_OPTICAL, rot_z  # noqa: E402

RIG_CAMERAS = {"R1": 8, "R5": 4}
HEIGHT, WIDTH = 36, 64


def camera_to_ego(yaw: float, position) -> torch.Tensor:
    """cam_to_ego (4, 4) of a level camera yawed by ``yaw`` about ego z, at ``position``."""
    T = np.eye(4)
    T[:3, :3] = rot_z(yaw) @ R_CAM_OPTICAL
    T[:3, 3] = position
    return torch.tensor(T, dtype=torch.float32)


def intrinsics(fx: float, fy: float, cx: float, cy: float) -> torch.Tensor:
    return torch.tensor([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]], dtype=torch.float32)


def hand_point(yaw, position, fx, fy, cx, cy, u, v, depth):
    """The ego point at ``depth`` (along the optical axis) on the ray of pixel (u, v), by hand."""
    forward = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    right = np.array([math.sin(yaw), -math.cos(yaw), 0.0])
    down = np.array([0.0, 0.0, -1.0])
    return np.asarray(position, float) + depth * (forward + (u - cx) / fx * right + (v - cy) / fy * down)


# ---------------------------------------------------------------- data


@pytest.mark.parametrize("rig", sorted(RIG_CAMERAS))
def test_rig_split_batch_has_the_documented_shapes(tiny_data, rig):
    split = RigSplit(tiny_data, rig, "train")
    n = RIG_CAMERAS[rig]
    assert len(split) == 4 and split.n_cameras == n and list(split.channels) == sorted(split.channels)
    batch = split.batch([2, 0])
    assert batch.images.shape == (2, n, 3, HEIGHT, WIDTH) and batch.images.dtype == torch.float32
    assert 0.0 <= float(batch.images.min()) and float(batch.images.max()) <= 1.0
    assert float(batch.images.std()) > 0.01  # rendered pictures, not blank
    assert batch.intrinsics.shape == (2, n, 3, 3) and batch.cam_to_ego.shape == (2, n, 4, 4)
    assert batch.tokens == [split.samples[2].token, split.samples[0].token]
    assert len(batch.boxes) == 2 and all(len(b.classes) > 0 for b in batch.boxes)
    for boxes in batch.boxes:
        m = len(boxes.classes)
        assert boxes.centers.shape == (m, 3) and boxes.sizes.shape == (m, 3) and boxes.yaws.shape == (m,)
        assert boxes.classes.dtype == torch.int64 and int(boxes.classes.min()) >= 0
        assert int(boxes.classes.max()) < len(CLASSES)


def test_rig_split_resize_scales_the_intrinsics_and_range_filters_boxes(tiny_data):
    native = RigSplit(tiny_data, "R5", "train")
    half = RigSplit(tiny_data, "R5", "train", image_size=(32, 18), max_range=20.0)
    assert half.batch([0]).images.shape == (1, 4, 3, 18, 32)
    expected = native.intrinsics.clone()
    expected[:, :2] *= 0.5
    torch.testing.assert_close(half.intrinsics, expected)
    near = half.targets(0)
    assert len(near.classes) < len(native.targets(0).classes)
    assert float(torch.hypot(near.centers[:, 0], near.centers[:, 1]).max()) <= 20.0


def test_batch_depths_are_the_renderers_depth_in_metres(tiny_data):
    from rigopt.validation.synthetic.render import render_rig
    from rigopt.validation.synthetic.scenes import split_scenes
    from rigopt.rig.library import load_rig

    from tests.validation.detectors.conftest import TINY_FRAMES

    split = RigSplit(tiny_data, "R5", "train")
    assert split.has_depth
    depths = split.batch([1]).depths
    assert depths.shape == (1, 4, HEIGHT, WIDTH) and depths.dtype == torch.float32
    rendered = render_rig(split_scenes("train", 1, TINY_FRAMES)[0], 1, load_rig("R5"), None, (WIDTH, HEIGHT))
    for k, channel in enumerate(split.channels):
        truth = rendered[channel].depth
        surface = np.isfinite(truth) & (truth > 0)
        assert surface.mean() > 0.3 and (~surface).any()  # ground and objects below, sky above
        np.testing.assert_allclose(depths[0, k].numpy()[surface], truth[surface], atol=0.006)
        assert (depths[0, k].numpy()[~surface] == 0).all()


def test_lss_depth_targets_are_the_nearest_surface_of_each_patch():
    config = model_config("lss", "tiny", depth_min=1.0, depth_max=25.0, depth_bins=6)  # 4 m bins
    model = LSSDetector(config)
    depth = torch.zeros(1, 12, 20)  # feature map 2 x 3 at stride 8 (the last row and column padded)
    depth[0, :8, :8] = 30.0  # beyond depth_max: no target
    depth[0, 3, 5] = 6.5  # a nearer surface in the same patch wins: bin (6.5 - 1) // 4 = 1
    depth[0, :8, 8:16] = 20.9  # bin 4
    depth[0, 8:, :8] = 0.5  # before depth_min: no target
    depth[0, 8:, 8:16] = 0.0  # no surface at all
    depth[0, 10, 17] = 24.9  # the padded corner cell: bin 5
    bins = model.depth_bins(depth, (2, 3))
    assert bins.tolist() == [[[1, 4, -1], [-1, -1, 5]]]


def test_lss_learns_from_depth_only_when_the_data_has_it_and_the_weight_is_positive(tiny_data):
    batch = RigSplit(tiny_data, "R5", "train").batch([0, 1])
    no_depth = Batch(batch.images, batch.intrinsics, batch.cam_to_ego, batch.boxes, batch.tokens)
    for config, data, supervised in ((model_config("lss", "tiny", depth_weight=1.0), batch, True),
                                     (model_config("lss", "tiny", depth_weight=0.0), batch, False),
                                     (model_config("lss", "tiny", depth_weight=1.0), no_depth, False)):
        torch.manual_seed(0)
        model = build_model(config)
        outputs = model(data)
        loss, parts = model.loss(outputs, data)
        box_loss, _ = model.head.loss(outputs, data.boxes)
        assert ("depth" in parts) == supervised
        if supervised:
            assert parts["depth"] > 0
            assert loss.item() == pytest.approx(box_loss.item() + config.depth_weight * parts["depth"], rel=1e-5)
        else:
            assert loss.item() == pytest.approx(box_loss.item())


def test_augmented_batches_keep_every_box_where_the_calibration_projects_it(tiny_data):
    from rigopt.validation.detectors.data import augment

    batch = RigSplit(tiny_data, "R1", "train").batch([0, 1, 2, 3])
    moved = augment(batch, np.random.default_rng(3))
    assert moved.images is batch.images and moved.depths is batch.depths
    changed = 0
    for b in range(4):
        before, after = batch.boxes[b], moved.boxes[b]
        changed += int(not torch.allclose(before.centers, after.centers))
        torch.testing.assert_close(after.centers.norm(dim=1), before.centers.norm(dim=1))  # turned, not moved
        for k in range(batch.n_cameras):  # the centre in each camera's optical frame is unchanged
            seen_before = torch.linalg.solve(batch.cam_to_ego[b, k], torch.cat([before.centers, torch.ones(len(before.centers), 1)], 1).T)
            seen_after = torch.linalg.solve(moved.cam_to_ego[b, k], torch.cat([after.centers, torch.ones(len(after.centers), 1)], 1).T)
            torch.testing.assert_close(seen_after, seen_before, atol=1e-4, rtol=1e-4)
            # and so is the heading: a point 1 m ahead of the box along its yaw
            ahead = lambda t: t.centers + torch.stack([torch.cos(t.yaws), torch.sin(t.yaws), torch.zeros_like(t.yaws)], 1)
            tip_before = torch.linalg.solve(batch.cam_to_ego[b, k], torch.cat([ahead(before), torch.ones(len(before.yaws), 1)], 1).T)
            tip_after = torch.linalg.solve(moved.cam_to_ego[b, k], torch.cat([ahead(after), torch.ones(len(after.yaws), 1)], 1).T)
            torch.testing.assert_close(tip_after, tip_before, atol=1e-4, rtol=1e-4)
    assert changed == 4


def test_rig_split_on_a_folder_lacking_the_rig_names_the_rigs_there(tiny_data):
    with pytest.raises(DataError) as caught:
        RigSplit(tiny_data, "R9", "train")
    message = str(caught.value)
    assert "R9" in message and "R1" in message and "R5" in message


def test_rig_split_on_a_missing_data_folder_is_a_data_error(tmp_path):
    with pytest.raises(DataError, match="no such data folder"):
        RigSplit(tmp_path / "nowhere", "R1", "train")


# ---------------------------------------------------------------- settings and devices


def test_unknown_family_and_size_are_unknown_names():
    with pytest.raises(UnknownNameError) as caught:
        model_config("yolo", "tiny")
    assert "yolo" in str(caught.value) and all(f in str(caught.value) for f in DETECTORS)
    with pytest.raises(UnknownNameError, match="huge"):
        model_config("lss", "huge")
    assert isinstance(caught.value, RigoptError)


def test_bad_model_settings_are_refused():
    with pytest.raises(RigoptError, match="depth_bins"):
        model_config("lss", "tiny", depth_bins=0)
    with pytest.raises(RigoptError, match="heads"):
        model_config("petr", "tiny", width=8, heads=3)
    assert model_config("LSS", "Tiny", width=None).width == model_config("lss", "tiny").width  # None ignored
    with pytest.raises(RigoptError, match="feature_stride is 4 or 8"):
        model_config("lss", "tiny", feature_stride=6)


def test_cuda_device_without_cuda_is_refused():
    if torch.cuda.is_available():
        pytest.skip("this machine has CUDA")
    with pytest.raises(RigoptError, match="cpu"):
        resolve_device("cuda")
    with pytest.raises(RigoptError):
        resolve_device("cuda:0")


def test_device_names():
    assert resolve_device("CPU") == torch.device("cpu")
    with pytest.raises(RigoptError, match="use cpu, cuda"):
        resolve_device("tpu")


# ---------------------------------------------------------------- forward and backward


@pytest.mark.parametrize("rig", sorted(RIG_CAMERAS))
@pytest.mark.parametrize("family", sorted(DETECTORS))
def test_forward_backward_on_rigs_of_different_camera_counts(tiny_data, family, rig):
    torch.manual_seed(0)
    config = model_config(family, "tiny")
    model = build_model(config)
    assert model.family == family
    batch = RigSplit(tiny_data, rig, "train").batch([0, 1])
    assert batch.n_cameras == RIG_CAMERAS[rig]

    outputs = model(batch)
    loss, parts = model.loss(outputs, batch)
    assert loss.dim() == 0 and torch.isfinite(loss) and loss.item() > 0
    assert parts and all(math.isfinite(v) for v in parts.values())
    loss.backward()
    for name, parameter in model.named_parameters():
        assert parameter.grad is None or torch.isfinite(parameter.grad).all(), name
    encoder = dict(model.encoder.named_parameters())
    assert all(p.grad is not None for p in encoder.values())
    first_conv = model.encoder.stage1[0][0].weight
    assert float(first_conv.grad.abs().sum()) > 0, "no gradient reached the image encoder's first layer"

    top_k = 7
    found = model.detections(outputs, top_k)
    assert len(found) == 2
    for d in found:
        assert d["centers"].shape == (top_k, 3) and d["sizes"].shape == (top_k, 3)
        assert d["yaws"].shape == d["classes"].shape == d["scores"].shape == (top_k,)
        assert d["classes"].dtype == torch.int64
        assert int(d["classes"].min()) >= 0 and int(d["classes"].max()) < len(CLASSES)
        scores = d["scores"]
        assert float(scores.min()) >= 0 and float(scores.max()) <= 1
        assert torch.all(scores[:-1] >= scores[1:])  # best first
        assert torch.isfinite(d["centers"]).all() and (d["sizes"] > 0).all()
        assert float(d["centers"][:, :2].abs().max()) <= config.bev_range + 1e-4  # inside the square


@pytest.mark.parametrize("family", sorted(DETECTORS))
def test_outputs_follow_the_calibration(tiny_data, family):
    """Same images, one camera moved: the detector's outputs change (it uses the rig's calibration)."""
    torch.manual_seed(0)
    model = build_model(model_config(family, "tiny")).eval()
    batch = RigSplit(tiny_data, "R5", "train").batch([0])
    moved = batch.cam_to_ego.clone()
    moved[:, 0, :3, 3] += torch.tensor([7.0, -5.0, 0.0])
    other = Batch(batch.images, batch.intrinsics, moved, batch.boxes, batch.tokens)
    with torch.no_grad():
        a, b = model(batch), model(other)
    key = "heatmap" if family == "lss" else "logits"
    first, second = (a[key], b[key]) if family == "lss" else (a[key][-1], b[key][-1])
    assert not torch.allclose(first, second)


# ---------------------------------------------------------------- geometry


def test_principal_point_ray_is_the_optical_axis():
    yaw = math.radians(30.0)
    K = intrinsics(40.0, 50.0, 8.5, 16.5)
    T = camera_to_ego(yaw, [1.0, -0.5, 1.6])
    origins, directions = pixel_rays(K[None, None], T[None, None], (3, 2), 8)  # cell (2, 1) centred on (8.5, 16.5)
    origins, directions = origins, directions[:, :, 2:, 1:]
    assert origins.shape == (1, 1, 1, 1, 3) and directions.shape == (1, 1, 1, 1, 3)
    torch.testing.assert_close(origins[0, 0, 0, 0], torch.tensor([1.0, -0.5, 1.6]))
    forward = torch.tensor([math.cos(yaw), math.sin(yaw), 0.0])
    torch.testing.assert_close(directions[0, 0, 0, 0], forward)
    torch.testing.assert_close(directions[0, 0, 0, 0], T[:3, 2])


def test_pixel_rays_match_a_hand_computation():
    yaw = math.radians(-60.0)
    fx, fy, cx, cy = 40.0, 50.0, 30.0, 20.0
    T = camera_to_ego(yaw, [0.3, 0.2, 1.2])
    _, directions = pixel_rays(intrinsics(fx, fy, cx, cy)[None, None], T[None, None], (2, 4), 8)
    assert directions.shape == (1, 1, 2, 4, 3)
    for i in range(2):
        for j in range(4):
            u, v = 8 * j + 0.5, 8 * i + 0.5  # the cell centre in image pixels: stride 8
            expected = hand_point(yaw, [0, 0, 0], fx, fy, cx, cy, u, v, 1.0)
            np.testing.assert_allclose(directions[0, 0, i, j].numpy(), expected, atol=1e-6)
    # depth is along the optical axis: every direction has optical-z component 1
    optical = torch.einsum("ij,hwi->hwj", T[:3, :3], directions[0, 0])
    torch.testing.assert_close(optical[..., 2], torch.ones(2, 4))


@pytest.mark.parametrize("rig", sorted(RIG_CAMERAS))
def test_rig_cameras_principal_rays_are_their_optical_axes(tiny_data, rig):
    split = RigSplit(tiny_data, rig, "test")
    batch = split.batch([0])
    K = batch.intrinsics.clone()
    # put the principal point on the centre of the single feature cell, pixel (0.5, 0.5)
    K[..., 0, 2], K[..., 1, 2] = 0.5, 0.5
    _, directions = pixel_rays(K, batch.cam_to_ego, (1, 1), 8)
    torch.testing.assert_close(directions[0, :, 0, 0], batch.cam_to_ego[0, :, :3, 2])
    if "CAM_BUMPER_FRONT" in split.channels:  # R1's front camera looks along ego +x
        front = directions[0, split.channels.index("CAM_BUMPER_FRONT"), 0, 0]
        assert float(front[0]) > 0.9


def test_splat_puts_each_lifted_feature_in_the_cell_below_it():
    config = model_config("lss", "tiny", bev_cell=0.8)  # 128 x 128 cells of 0.8 m over +-51.2 m
    model = LSSDetector(config)
    depths = model.depths.tolist()
    assert depths == pytest.approx([6.0, 16.0, 26.0, 36.0, 46.0, 56.0])
    h, w, channels = 4, 8, 6
    fx = fy = 40.0
    cx, cy = 32.0, 16.5  # feature row 2 (v = 16.5) is level
    cameras = [(0.0, [1.0, 0.5, 1.5]), (math.pi / 2, [-2.0, 0.0, 5.0])]  # sample 0: looks +x, sample 1: +y
    K = intrinsics(fx, fy, cx, cy).expand(2, 1, 3, 3).clone()
    T = torch.stack([camera_to_ego(yaw, p) for yaw, p in cameras])[:, None]
    empty = BoxTargets(torch.zeros(0, 3), torch.zeros(0, 3), torch.zeros(0), torch.zeros(0, dtype=torch.int64))
    batch = Batch(torch.zeros(2, 1, 3, HEIGHT, WIDTH), K, T, [empty, empty], ["a", "b"])

    # (sample, depth bin, feature row, feature column, channel, value)
    entries = [(0, 1, 1, 6, 2, 1.0),   # (17, -6.1, 4.7): kept
               (1, 2, 2, 1, 5, 2.0),   # (-17.3, 26, 5.0): kept
               (0, 2, 3, 3, 0, 4.0),   # (27, 5.4, -3.7): inside the square but below the ground, dropped
               (0, 2, 0, 3, 3, 16.0),  # (27, 5.4, 11.9): inside the square but too high, dropped
               (1, 5, 2, 4, 1, 8.0)]   # (-1.3, 56, 5.0): within the height limits but beyond the square
    # one entry per pixel: its depth bin carries the value, its channel 1, so depth x context is the entry alone
    depth, context = torch.zeros(2, 1, len(depths), h, w), torch.zeros(2, 1, channels, h, w)
    expected = torch.zeros(2, channels, model.head.grid, model.head.grid)
    kept_cells = []
    for b, k, i, j, c, value in entries:
        depth[b, 0, k, i, j], context[b, 0, c, i, j] = value, 1.0
        u, v = 8 * j + 0.5, 8 * i + 0.5
        x, y, z = hand_point(*cameras[b], fx, fy, cx, cy, u, v, depths[k])
        ix, iy = math.floor((x + 51.2) / 0.8), math.floor((y + 51.2) / 0.8)
        if 0 <= ix < 128 and 0 <= iy < 128 and HEIGHT_LIMITS[0] <= z <= HEIGHT_LIMITS[1]:
            expected[b, c, ix, iy] += value
            kept_cells.append((b, c, ix, iy))
    assert kept_cells == [(0, 2, 85, 56), (1, 5, 42, 96)]  # the hand geometry itself, spelled out

    bev = model.splat(depth, context, batch)
    assert bev.shape == (2, channels, 128, 128)
    assert torch.count_nonzero(bev) == 2
    torch.testing.assert_close(bev, expected)


@pytest.mark.parametrize("family", sorted(DETECTORS))
def test_stride_four_features_are_twice_as_fine_and_train(tiny_data, family):
    """At feature_stride 4 the encoder gives (M, 2 width, ceil(H / 4), ceil(W / 4)) features, four times the cells of
    stride 8, and each family trains on them (finite loss, a gradient into the encoder's first layer)."""
    torch.manual_seed(0)
    coarse, fine = (build_model(model_config(family, "tiny", feature_stride=s)) for s in (8, 4))
    batch = RigSplit(tiny_data, "R5", "train").batch([0, 1])
    images = batch.images.flatten(0, 1)
    h, w = images.shape[-2:]
    assert fine.encoder.stride == 4 and coarse.encoder.stride == 8
    assert fine.encoder(images).shape == (len(images), fine.encoder.out_channels, -(-h // 4), -(-w // 4))
    assert coarse.encoder(images).shape[-2:] == (-(-h // 8), -(-w // 8))
    loss, _ = fine.loss(fine(batch), batch)
    loss.backward()
    assert torch.isfinite(loss) and float(fine.encoder.stage1[0][0].weight.grad.abs().sum()) > 0


def test_stride_four_lifts_along_the_rays_of_its_own_cells():
    """A cell (i, j) of stride-4 features is centred on pixel (4 j + 0.5, 4 i + 0.5): the same splat as at stride 8
    with intrinsics whose fx, fy are doubled and cx, cy moved to 2 c - 0.5 (so that 8 j + 0.5 maps to the same ray)."""
    torch.manual_seed(0)
    fine = LSSDetector(model_config("lss", "tiny", feature_stride=4))
    coarse = LSSDetector(model_config("lss", "tiny"))
    fx, fy, cx, cy = 30.0, 28.0, 33.0, 17.0
    T = torch.stack([camera_to_ego(0.3, [1.0, 0.5, 1.5]), camera_to_ego(-2.0, [-2.0, 0.2, 2.0])])[None]
    empty = BoxTargets(torch.zeros(0, 3), torch.zeros(0, 3), torch.zeros(0), torch.zeros(0, dtype=torch.int64))
    k_fine = intrinsics(fx, fy, cx, cy).expand(1, 2, 3, 3).clone()
    k_coarse = intrinsics(2 * fx, 2 * fy, 2 * cx - 0.5, 2 * cy - 0.5).expand(1, 2, 3, 3).clone()
    images = torch.zeros(1, 2, 3, HEIGHT, WIDTH)
    depth = torch.rand(1, 2, fine.config.depth_bins, 9, 16).softmax(dim=2)
    context = torch.rand(1, 2, fine.config.bev_channels, 9, 16)
    bev_fine = fine.splat(depth, context, Batch(images, k_fine, T, [empty], ["a"]))
    bev_coarse = coarse.splat(depth, context, Batch(images, k_coarse, T, [empty], ["a"]))
    assert torch.count_nonzero(bev_fine) > 0
    torch.testing.assert_close(bev_fine, bev_coarse, rtol=1e-5, atol=1e-5)


def test_splat_equals_summing_the_whole_lifted_volume():
    """The splat forms only the kept points' products; summing the whole (B, N, D, Cc, h, w) volume of depth x
    context into the same cells in the same order gives the same bird's-eye features, bit for bit."""
    config = model_config("lss", "tiny")
    model = LSSDetector(config)
    generator = torch.Generator().manual_seed(3)
    b, n, d, c, h, w = 2, 3, len(model.depths), 5, 4, 8
    depth = torch.rand(b, n, d, h, w, generator=generator).softmax(dim=2)
    context = torch.randn(b, n, c, h, w, generator=generator)
    K = intrinsics(40.0, 40.0, 28.5, 16.5).expand(b, n, 3, 3)
    T = torch.stack([torch.stack([camera_to_ego(yaw, [0.5 * k, -0.2 * k, 1.2 + 0.3 * k]) for k, yaw in
                                  enumerate((0.3, 2.0, -1.9))]) for _ in range(b)])
    batch = Batch(torch.zeros(b, n, 3, HEIGHT, WIDTH), K, T, [], ["a", "b"])
    bev = model.splat(depth, context, batch)

    g, cell, half = model.head.grid, config.bev_cell, config.bev_range
    origins, directions = pixel_rays(K, T, (h, w), model.encoder.stride)
    points = origins[:, :, None] + model.depths[None, None, :, None, None, None] * directions[:, :, None]
    ix = torch.floor((points[..., 0] + half) / cell).long()
    iy = torch.floor((points[..., 1] + half) / cell).long()
    kept = (ix >= 0) & (ix < g) & (iy >= 0) & (iy < g) & (points[..., 2] >= HEIGHT_LIMITS[0]) & (
        points[..., 2] <= HEIGHT_LIMITS[1])
    volume = depth[:, :, :, None] * context[:, :, None]  # (B, N, D, Cc, h, w)
    sample = torch.arange(b)[:, None, None, None, None].expand_as(ix)
    flat = (sample * g * g + ix * g + iy)[kept]
    whole = torch.zeros(b * g * g, c).index_add_(0, flat, volume.permute(0, 1, 2, 4, 5, 3)[kept])
    assert kept.any() and not kept.all()
    assert torch.equal(bev, whole.view(b, g, g, c).permute(0, 3, 1, 2))


def test_splat_keeps_the_in_range_points_of_a_level_ray_and_sums_shared_cells():
    """All depth bins of the pixel on the optical axis of a level forward camera at 1.5 m: points at x = 6,
    16, ..., 56 m; those within the 51.2 m square land in their x cells of row iy = 7 (y just below 0). A
    second pixel's nearest point shares a cell with the first point, and the cell holds their sum."""
    config = model_config("lss", "tiny")  # 16 x 16 cells of 6.4 m
    model = LSSDetector(config)
    K = intrinsics(40.0, 40.0, 28.5, 16.5)[None, None]  # on feature row 2; column 4 (u = 32.5) is 4 px right
    T = camera_to_ego(0.0, [0.0, 0.0, 1.5])[None, None]
    batch = Batch(torch.zeros(1, 1, 3, HEIGHT, WIDTH), K, T, [], ["a"])
    depth, context = torch.zeros(1, 1, 6, 4, 8), torch.zeros(1, 1, 3, 4, 8)
    depth[0, 0, :, 2, 4] = torch.arange(1.0, 7.0)  # bins 0..5 carry 1..6; cell (2, 4) has u = 32.5
    depth[0, 0, 0, 2, 5] = 10.0  # u = 40.5: (6, -1.8, 1.5), the cell (8, 7) of bin 0 above
    context[0, 0, 1, 2, 4:6] = 1.0  # channel 1 of both pixels
    bev = model.splat(depth, context, batch)
    # u = 32.5 is 4 px right of cx: y = -d * 0.1, so y in [-5.6, -0.6] -> iy = floor((y + 51.2) / 6.4) = 7
    expected = torch.zeros(3, 16, 16)
    for value, depth in zip(range(1, 7), (6.0, 16.0, 26.0, 36.0, 46.0, 56.0)):
        if depth + 51.2 < 102.4:
            expected[1, math.floor((depth + 51.2) / 6.4), 7] += value
    assert float(expected.sum()) == 15.0  # 56 m is outside; 6 -> ix 8, 16 -> 10, 26 -> 12, 36 -> 13, 46 -> 15
    expected[1, 8, 7] += 10.0
    torch.testing.assert_close(bev[0], expected)


# ---------------------------------------------------------------- PETR query denoising


def _boxes(centers, classes):
    n = len(classes)
    return BoxTargets(torch.tensor(centers, dtype=torch.float32), torch.full((n, 3), 2.0), torch.zeros(n),
                      torch.tensor(classes, dtype=torch.long))


def test_denoising_queries_attend_only_within_their_group_and_never_to_padding(tiny_data):
    from rigopt.validation.detectors.petr import PETRDetector

    config = model_config("petr", "tiny", dn_groups=2, queries=5)
    model = PETRDetector(config).train()
    batch = RigSplit(tiny_data, "R5", "train").batch([0])
    # sample 0: two boxes; sample 1: one box, so its second slot in each group is padding
    batch = Batch(batch.images.repeat(2, 1, 1, 1, 1), batch.intrinsics.repeat(2, 1, 1, 1),
                  batch.cam_to_ego.repeat(2, 1, 1, 1),
                  [_boxes([[5.0, 1.0, 0.5], [-8.0, 3.0, 0.5]], [0, 5]), _boxes([[10.0, -2.0, 0.5]], [1])], ["a", "b"])
    dn = model.denoising_queries(batch)
    d, q, heads = 4, 5, config.heads  # 2 groups x 2 slots, then the object queries
    assert dn["valid"].tolist() == [[True, True, True, True], [True, False, True, False]]
    assert dn["classes"][0].tolist() == [0, 5, 0, 5] and dn["classes"][1, 0] == 1
    torch.testing.assert_close(dn["target"][0, 2, :2], torch.tensor([(5 + 51.2) / 102.4, (1 + 51.2) / 102.4]))
    jitter = (torch.sigmoid(dn["reference"]) - dn["target"][..., :2]).abs() * 102.4
    assert float(jitter[dn["valid"]].max()) <= 1.0 + 1e-4  # 2 m boxes: jitter at most max(0.5 x 2 m, 1 m)
    assert dn["blocked"].shape == (2 * heads, d + q, d + q)
    allowed = ~dn["blocked"][::heads]  # one mask per sample
    assert not allowed[:, d:, :d].any()  # object queries never see a denoising query
    assert allowed[:, :, d:].all()  # everybody sees the object queries
    assert allowed[0, 0, 1] and not allowed[0, 0, 2] and not allowed[0, 2, 1]  # groups see only themselves
    assert not allowed[1, 0, 1] and not allowed[1, 2, 3]  # padding is seen by nobody but itself
    assert allowed[1, 1, 1] and allowed[1, 3, 3]


def test_denoising_changes_training_outputs_but_not_inference(tiny_data):
    from rigopt.validation.detectors.petr import PETRDetector

    torch.manual_seed(0)
    model = PETRDetector(model_config("petr", "tiny", dn_groups=2))
    batch = RigSplit(tiny_data, "R1", "train").batch([0, 1])
    model.train()
    outputs = model(batch)
    n_max = max(len(b.classes[(b.centers[:, :2].abs() < 51.2).all(dim=1)]) for b in batch.boxes)
    assert outputs["logits"][-1].shape == (2, model.config.queries, len(CLASSES))
    assert outputs["denoising"]["logits"][-1].shape == (2, 2 * n_max, len(CLASSES))
    loss, _ = model.loss(outputs, batch)
    loss.backward()
    assert model.label_embedding.weight.grad.abs().sum() > 0  # the denoising queries are trained
    # object queries cannot see denoising queries, so their outputs equal a run without them
    plain = PETRDetector(model_config("petr", "tiny", dn_groups=0))
    plain.load_state_dict(model.state_dict())
    plain.train()
    torch.testing.assert_close(plain(batch)["boxes"][-1], outputs["boxes"][-1], atol=1e-5, rtol=1e-4)
    model.eval()
    assert "denoising" not in model(batch)


def test_negative_denoising_groups_are_refused():
    with pytest.raises(RigoptError, match="dn_groups"):
        model_config("petr", "tiny", dn_groups=-1)


def test_token_targets_mark_the_cell_of_each_projected_centre_with_the_nearest_depth():
    """A camera at the origin looking along ego x (fx = fy = 10, principal point (32, 18), 64 x 36 image;
    right = -y, down = -z): ego (10, 2, -1) is at (right, down, depth) = (-2, 1, 10), so (u, v) = (30, 19),
    cell (19 // 8, 30 // 8) = (2, 3); ego (20, 4, -2) projects to the same pixel at depth 20; ego (-5, 0, 0) is
    behind the camera; ego (10, -40, 0) projects outside the image (u = 72); ego (10, -1, 0.5) to (u, v) =
    (33, 17.5), cell (2, 4)."""
    from rigopt.validation.detectors.petr import PETRDetector

    model = PETRDetector(model_config("petr", "tiny"))
    centers = [[10.0, 2.0, -1.0], [20.0, 4.0, -2.0], [-5.0, 0.0, 0.0], [10.0, -40.0, 0.0], [10.0, -1.0, 0.5]]
    batch = Batch(torch.zeros(1, 1, 3, HEIGHT, WIDTH), intrinsics(10.0, 10.0, 32.0, 18.0)[None, None],
                  camera_to_ego(0.0, [0.0, 0.0, 0.0])[None, None], [_boxes(centers, [0, 1, 2, 3, 4])], ["s"])
    holds, depth = model.token_targets(batch, (5, 8))
    assert holds.shape == depth.shape == (1, 1, 5, 8)
    expected = torch.zeros(5, 8, dtype=torch.bool)
    expected[2, 3] = expected[2, 4] = True
    assert torch.equal(holds[0, 0], expected)
    assert float(depth[0, 0, 2, 3]) == pytest.approx(10.0)  # the nearer of the two centres in that cell
    assert float(depth[0, 0, 2, 4]) == pytest.approx(10.0)
    assert torch.isinf(depth[0, 0][~expected]).all()
    tokens = torch.zeros(1, 1, 2, 5, 8)
    tokens[:, :, 1] = math.log(10.0)  # exact depths: only the centre term is left
    exact = model.token_loss(tokens, batch)
    tokens[:, :, 1] = math.log(20.0)
    assert float(model.token_loss(tokens, batch) - exact) == pytest.approx(math.log(2.0), rel=1e-5)


def test_azimuth_bias_is_zero_along_the_ray_over_the_query_and_falls_off_per_cell():
    """Camera at the origin looking along ego x, fx = 10, stride 8: one cell is 0.8 rad of azimuth wide. A
    query over ego (20, 0) sees the central column's rays (azimuth 0 at u = 32, cell centre u = 32.5 is off by
    atan(0.05)) almost unpenalised; a ray one cell width (0.8 rad) away gets -w / 2 with w = 1 at the start."""
    from rigopt.validation.detectors.petr import PETRDetector

    model = PETRDetector(model_config("petr", "tiny"))
    b_intrinsics = intrinsics(10.0, 10.0, 32.0, 18.0)[None, None]
    origins, directions = pixel_rays(b_intrinsics, camera_to_ego(0.0, [0.0, 0.0, 0.0])[None, None], (5, 8), 8)
    origin, azimuth, width = model.ray_azimuths(origins, directions, b_intrinsics)
    assert origin.shape == (1, 40, 2) and azimuth.shape == width.shape == (1, 40)
    torch.testing.assert_close(width, torch.full((1, 40), 0.8))
    r = model.config.bev_range
    reference = torch.logit(torch.tensor([[[(20.0 + r) / (2 * r), 0.5]]]))  # (1, 1, 2): ego (20, 0)
    bias = model.azimuth_bias(reference, (origin, azimuth, width), 0)
    assert bias.shape == (model.config.heads, 1, 40)
    angle = azimuth[0]  # (40,) rad; the query is straight ahead, so the gap is the ray's own azimuth
    bias = bias.detach()
    torch.testing.assert_close(bias[0, 0], -0.5 * (angle / 0.8) ** 2, atol=1e-5, rtol=1e-5)
    assert float(bias[0, 0].max()) > -0.01  # the column over the query
    # a reference point behind the camera: the gap is pi - |azimuth| for every (forward-looking) ray
    behind = torch.logit(torch.tensor([[[(-20.0 + r) / (2 * r), 0.5]]]))
    torch.testing.assert_close(model.azimuth_bias(behind, (origin, azimuth, width), 0)[0, 0].detach(),
                               -0.5 * ((math.pi - angle.abs()) / 0.8) ** 2, atol=1e-4, rtol=1e-4)


def _reference_head_loss(head, outputs: dict, boxes: list) -> torch.Tensor:
    """The centre head's loss written the plain way, one sample, one box and one class at a time: the oracle
    of the batched ``CenterHead.loss``."""
    from rigopt.validation.detectors.center_head import focal_heatmap_loss

    total_heat, total_reg, n_boxes = 0.0, 0.0, 0
    for b, sample_boxes in enumerate(boxes):
        target = torch.zeros(head.n_classes, head.grid, head.grid)
        for j in range(len(sample_boxes.classes)):
            centre, size = sample_boxes.centers[j], sample_boxes.sizes[j]
            ix, iy = (int(math.floor((float(v) + head.bev_range) / head.cell)) for v in centre[:2])
            if not (0 <= ix < head.grid and 0 <= iy < head.grid):
                continue
            sigma = max(0.25 * float(size[:2].max()) / head.cell, 0.8)
            for x in range(head.grid):
                for y in range(head.grid):
                    value = math.exp(-((x - ix) ** 2 + (y - iy) ** 2) / (2 * sigma**2))
                    c = int(sample_boxes.classes[j])
                    target[c, x, y] = max(float(target[c, x, y]), value)
            offset = [(float(centre[0]) + head.bev_range) / head.cell - ix,
                      (float(centre[1]) + head.bev_range) / head.cell - iy]
            yaw = float(sample_boxes.yaws[j])
            wanted = torch.tensor([*offset, float(centre[2]), *torch.log(size.clamp(min=0.05)).tolist(),
                                   math.sin(yaw), math.cos(yaw)])
            total_reg += float((outputs["regression"][b, :, ix, iy] - wanted).abs().sum())
            n_boxes += 1
        total_heat += float(focal_heatmap_loss(outputs["heatmap"][b], target))
    return (total_heat + total_reg) / max(n_boxes, 1)


def test_batched_centre_head_loss_equals_the_per_box_reference():
    """Two samples: overlapping boxes of one class, boxes of two classes, one outside the grid, an empty
    sample; the batched loss equals the plain per-box computation."""
    torch.manual_seed(0)
    model = build_model(model_config("lss", "tiny"))
    head = model.head
    g = head.grid
    outputs = {"heatmap": torch.randn(3, head.n_classes, g, g), "regression": torch.randn(3, 8, g, g)}
    boxes = [BoxTargets(torch.tensor([[3.0, -4.0, 0.8], [4.0, -4.5, 0.9], [-20.0, 10.0, 1.0], [500.0, 0.0, 0.0]]),
                        torch.tensor([[4.6, 1.9, 1.7], [4.5, 1.8, 1.6], [11.0, 2.9, 3.4], [1.0, 1.0, 1.0]]),
                        torch.tensor([0.3, -0.2, 1.5, 0.0]), torch.tensor([0, 0, 2, 1])),
             BoxTargets(torch.zeros(0, 3), torch.zeros(0, 3), torch.zeros(0), torch.zeros(0, dtype=torch.long)),
             BoxTargets(torch.tensor([[-8.0, -8.0, 0.9]]), torch.tensor([[0.7, 0.7, 1.75]]), torch.tensor([2.0]),
                        torch.tensor([5]))]
    loss, parts = head.loss(outputs, boxes)
    assert loss.item() == pytest.approx(_reference_head_loss(head, outputs, boxes), rel=1e-5)
    heatmap, sample, cells, _ = head.targets(boxes)
    assert sample.tolist() == [0, 0, 0, 2]  # the box outside the grid is left out
    assert heatmap.shape == (3, head.n_classes, g, g) and float(heatmap[1].max()) == 0.0
    assert all(float(heatmap[s, c, x, y]) == 1.0 for s, c, (x, y) in zip(sample.tolist(), [0, 0, 2, 5],
                                                                         cells.tolist()))
