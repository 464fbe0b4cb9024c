"""Distorted cameras (fisheyes) reach the detectors through their lens model, pinholes as before.

The benchmark's tables record a distorted lens (``calibrated_sensor`` ``distortion``), the split turns them into
camera models (``Batch.lenses``), and the LSS family lifts each feature cell along its lens's own ray
(:func:`layers.lens_cells`, the camera model's unprojection), leaving out a fisheye's cells that look behind its
lens plane. A split of pinholes only carries no lens models: the intrinsics rays, unchanged.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from rigopt.camera import CameraModel, Lens, intrinsic_matrix  # noqa: E402
from rigopt.design.near_field import fisheye_190  # noqa: E402
from rigopt.errors import DataError  # noqa: E402
from rigopt.geometry import R_CAM_OPTICAL  # noqa: E402
from rigopt.rig.library import load_rig  # noqa: E402
from rigopt.validation.detectors.config import model_config  # noqa: E402
from rigopt.validation.detectors.data import Batch, RigSplit  # noqa: E402
from rigopt.validation.detectors.layers import cell_centres, lens_cells, pixel_rays  # noqa: E402
from rigopt.validation.detectors.lss import LSSDetector  # noqa: E402
from rigopt.validation.detectors.petr import PETRDetector  # noqa: E402
from rigopt.validation.designs import PERCEPTION_ROLE, WHOLE_ROLE, fed_rigs  # noqa: E402

SIZE = (64, 36)  # width, height


def with_fisheye(name: str = "with_fisheye"):
    """R5 (4 pinholes) and a near_field 190-degree fisheye at its first camera's pose."""
    r5 = load_rig("R5")
    fisheye = dataclasses.replace(r5.cameras[0], id="FISHEYE", role="near_field", lens=fisheye_190().lens)
    return dataclasses.replace(r5, name=name, cameras=(*r5.cameras, fisheye))


def test_a_fisheyes_cell_rays_are_its_camera_models_unprojection():
    """Cell by cell: the equidistant lens by hand (a cell theta = its normalised radius off the axis), and
    CameraModel.pixel_rays at unit depth for the cells in front of the lens; the others are zero and left out."""
    model = CameraModel.of_lens(fisheye_190().lens).resized((160, 90))
    feature_hw, stride = (12, 20), 8
    rays, in_front = lens_cells(model, feature_hw, stride, torch.float64)
    assert rays.shape == (12, 20, 3) and in_front.shape == (12, 20)
    pixels = cell_centres(feature_hw, stride)
    x, y = (pixels[:, 0] - model.cx) / model.fx, (pixels[:, 1] - model.cy) / model.fy
    theta = np.hypot(x, y)  # zero coefficients: theta_d = theta
    front = theta < np.pi / 2
    assert 0 < (~front).sum() < len(front)  # the 190-degree lens's left and right columns look behind it
    np.testing.assert_array_equal(in_front.numpy().ravel(), front)
    by_hand = np.stack([np.tan(theta) * x / theta, np.tan(theta) * y / theta, np.ones_like(x)], -1)
    np.testing.assert_allclose(rays.numpy().reshape(-1, 3)[front], by_hand[front], rtol=1e-9, atol=1e-12)
    unprojected = model.pixel_rays(pixels[front], unit=False, frame="optical")
    np.testing.assert_allclose(rays.numpy().reshape(-1, 3)[front], unprojected, rtol=1e-12, atol=1e-12)
    assert (rays.numpy().reshape(-1, 3)[~front] == 0).all()


def test_a_pinholes_lens_rays_are_its_intrinsics_rays():
    """In a rig with a fisheye every camera takes the lens model's rays: a pinhole's are those of its intrinsics."""
    rig = load_rig("R5")
    model = CameraModel.of_lenses([fisheye_190().lens] + [c.lens for c in rig.cameras[1:]]).resized(SIZE)
    cam_to_ego = np.tile(np.eye(4), (len(rig), 1, 1))
    cam_to_ego[:, :3, :3] = rig.rotations @ R_CAM_OPTICAL
    args = (torch.tensor(model.intrinsic_matrix())[None], torch.tensor(cam_to_ego)[None], (5, 8), 8)
    camera_rays, in_front = lens_cells(model, (5, 8), 8, torch.float64)
    _, from_k = pixel_rays(*args)
    _, from_lens = pixel_rays(*args, camera_rays=camera_rays)
    assert in_front[1:].all() and not in_front[0].all()
    torch.testing.assert_close(from_lens[0, 1:], from_k[0, 1:], rtol=1e-12, atol=1e-12)


def test_a_split_of_pinholes_carries_no_lens_models(tiny_data):
    """Pinhole rigs keep the intrinsics rays: no lens model reaches the detector."""
    split = RigSplit(tiny_data, "R1", "test")
    assert split.lenses is None and split.batch([0]).lenses is None


def test_a_rendered_fisheye_reaches_the_split_as_its_lens(tmp_path):
    """The tables record the fisheye (its K and distortion at the rendered size); the pinholes keep the centred K
    of their FOV and no distortion."""
    from rigopt.validation.synthetic.generate import generate_split
    from rigopt.validation.synthetic.render import render_rig
    from rigopt.validation.synthetic.scenes import split_scenes

    rig = with_fisheye()
    generate_split([rig], split_scenes("test", 1, 1), tmp_path, SIZE, render_rig, lambda rig: None)
    split = RigSplit(tmp_path, rig.name, "test")
    cameras = {c.id: c for c in rig.cameras}
    fisheye = CameraModel.rendered(cameras["FISHEYE"], SIZE)
    for k, channel in enumerate(split.channels):
        expected = fisheye.intrinsic_matrix() if channel == "FISHEYE" else intrinsic_matrix(cameras[channel].fov, *SIZE)
        np.testing.assert_allclose(split.intrinsics[k].numpy(), expected, rtol=1e-6)
        np.testing.assert_allclose(split.lenses.intrinsic_matrix()[k], expected, rtol=1e-12)
        assert str(split.lenses.distortion[k]) == ("fisheye" if channel == "FISHEYE" else "none")
    half = RigSplit(tmp_path, rig.name, "test", image_size=(32, 18))
    np.testing.assert_allclose(half.lenses.fx, split.lenses.fx / 2, rtol=1e-12)
    assert half.batch([0]).lenses is half.lenses


def fisheye_batch() -> Batch:
    """One sample of one level fisheye at 1.5 m looking along ego x."""
    model = CameraModel.of_lenses([fisheye_190().lens]).resized(SIZE)
    T = torch.eye(4)
    T[:3, :3] = torch.tensor(R_CAM_OPTICAL, dtype=torch.float32)
    T[2, 3] = 1.5
    return Batch(torch.zeros(1, 1, 3, SIZE[1], SIZE[0]), torch.tensor(model.intrinsic_matrix(), dtype=torch.float32)
                 [None], T[None, None], [], ["a"], None, model)


def test_lss_lifts_no_fisheye_cell_that_looks_behind_its_lens():
    config = model_config("lss", "tiny")
    model = LSSDetector(config)
    batch = fisheye_batch()
    _, in_front = lens_cells(batch.lenses, (5, 8), 8)
    behind = ~in_front[0]
    assert behind.any() and not behind.all()
    depth = torch.full((1, 1, len(model.depths), 5, 8), 1.0 / len(model.depths))
    context = torch.zeros(1, 1, 2, 5, 8)
    context[0, 0, 0][behind] = 1.0  # features only where the cells look behind the lens
    assert torch.count_nonzero(model.splat(depth, context, batch)) == 0
    context[0, 0, 1][~behind] = 1.0  # and where they look ahead
    bev = model.splat(depth, context, batch)
    assert torch.count_nonzero(bev[0, 0]) == 0 and torch.count_nonzero(bev[0, 1]) > 0
    outputs = model.eval()(batch)
    assert torch.isfinite(outputs["heatmap"]).all()


def test_petr_refuses_a_distorted_lens():
    with pytest.raises(DataError, match="petr family takes pinholes only"):
        PETRDetector(model_config("petr", "tiny"))(fisheye_batch())


def test_fed_rigs_feed_the_perception_cameras_and_keep_the_whole_rig_where_the_family_takes_its_lenses():
    rig = with_fisheye()
    rows, record = fed_rigs(rig, "design", "lss")
    assert [(role, r.name, len(r)) for role, r in rows] == [(PERCEPTION_ROLE, "with_fisheye_perception", 4),
                                                            (WHOLE_ROLE, "with_fisheye_whole", 5)]
    assert record["near_field_cameras"] == ["FISHEYE"] and len(record["perception_cameras"]) == 4
    assert record["whole_rig"] == {"rig": "with_fisheye_whole", "n_cameras": 5, "measured": True, "reason": None}
    assert record["note"].endswith("measured on its 4 perception cameras, and whole (5 cameras) for the record")

    rows, record = fed_rigs(rig, "design", "petr")
    assert [role for role, _ in rows] == [PERCEPTION_ROLE]
    assert record["whole_rig"]["measured"] is False and "FISHEYE" in record["whole_rig"]["reason"]
    assert "not measured whole" in record["note"] and "petr detectors take pinholes only" in record["note"]

    r5 = load_rig("R5")
    assert fed_rigs(r5, "design", "petr") == ([("design", r5)], None)
