"""The torch pixel rays of the detectors mirror the camera model: both give the same rays for a rig's cameras.

:func:`rigopt.validation.detectors.layers.pixel_rays` is torch's copy of :meth:`rigopt.camera.CameraModel.pixel_rays`
(rays scaled to unit depth), turned into the ego frame by the optical-to-ego transform; the two must agree
for every camera, cell and stride, so that a change of the camera model (intrinsics, distortion) that is not
mirrored in torch fails here.
"""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from rigopt.validation.detectors.layers import cell_centres, lens_rays, pixel_rays  # noqa: E402
from rigopt.camera import CameraModel, Lens  # noqa: E402
from rigopt.geometry import R_CAM_OPTICAL  # noqa: E402
from rigopt.rig.library import library_rig  # noqa: E402


@pytest.mark.parametrize("rig_name, size, stride", [("R1", (160, 90), 8), ("R5", (1280, 720), 16)])
def test_torch_pixel_rays_agree_with_the_camera_model(rig_name, size, stride):
    rig = library_rig(rig_name)
    model = CameraModel.from_fov(rig.fovs, np.tile(size, (len(rig), 1)))
    cam_to_ego = np.tile(np.eye(4), (len(rig), 1, 1))
    cam_to_ego[:, :3, :3] = rig.rotations @ R_CAM_OPTICAL  # optical frame -> ego
    cam_to_ego[:, :3, 3] = rig.positions
    h, w = -(-size[1] // stride), -(-size[0] // stride)
    origins, directions = pixel_rays(torch.tensor(model.intrinsic_matrix())[None], torch.tensor(cam_to_ego)[None],
                                     (h, w), stride)
    rows, cols = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    cell_centres = np.stack([stride * cols.ravel() + 0.5, stride * rows.ravel() + 0.5], axis=-1)  # (h w, 2) px
    body = model.pixel_rays(cell_centres, unit=False)  # (c, h w, 3), unit depth
    expected = np.einsum("cij,cnj->cni", rig.rotations, body).reshape(len(rig), h, w, 3)
    np.testing.assert_allclose(directions[0].numpy(), expected, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(origins[0, :, 0, 0].numpy(), rig.positions, rtol=0, atol=0)


def _cam_to_ego(rig):
    cam_to_ego = np.tile(np.eye(4), (len(rig), 1, 1))
    cam_to_ego[:, :3, :3] = rig.rotations @ R_CAM_OPTICAL
    cam_to_ego[:, :3, 3] = rig.positions
    return cam_to_ego


def test_lens_rays_of_pinholes_are_the_torch_intrinsics_rays():
    rig = library_rig("R1")
    model = CameraModel.from_fov(rig.fovs, np.tile((160, 90), (len(rig), 1)))
    args = (torch.tensor(model.intrinsic_matrix())[None], torch.tensor(_cam_to_ego(rig))[None], (12, 20), 8)
    _, from_k = pixel_rays(*args)
    _, from_model = pixel_rays(*args, camera_rays=lens_rays(model, (12, 20), 8, torch.float64))
    np.testing.assert_allclose(from_model.numpy(), from_k.numpy(), rtol=1e-12, atol=1e-12)


def test_lens_rays_follow_the_lens_distortion():
    # Argoverse-2-like barrel distortion: the rays differ from the pinhole's of the same intrinsics and agree
    # with the camera model's, cell by cell.
    rig = library_rig("R1")
    lens = Lens(2048, 1550, 1773.0, 1773.0, 1024.0, 775.0, "radtan", (-0.26, 0.07, 0.0, 0.0, 0.0))
    model = CameraModel.of_lenses([lens] * len(rig)).resized((256, 194))
    feature_hw, stride = (25, 32), 8
    args = (torch.tensor(model.intrinsic_matrix())[None], torch.tensor(_cam_to_ego(rig))[None], feature_hw, stride)
    _, pinhole = pixel_rays(*args)
    _, distorted = pixel_rays(*args, camera_rays=lens_rays(model, feature_hw, stride, torch.float64))
    body = model.pixel_rays(cell_centres(feature_hw, stride), unit=False)
    expected = np.einsum("cij,cnj->cni", rig.rotations, body).reshape(len(rig), *feature_hw, 3)
    np.testing.assert_allclose(distorted[0].numpy(), expected, rtol=1e-12, atol=1e-12)
    assert (distorted - pinhole).abs().max().item() > 0.05  # barrel distortion moves the corner rays outwards
