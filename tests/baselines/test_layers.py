"""The torch pixel rays of the detectors mirror the camera model: both give the same rays for a rig's cameras.

:func:`rigopt.baselines.layers.pixel_rays` is torch's copy of :meth:`rigopt.camera.CameraModel.pixel_rays`
(rays scaled to unit depth), turned into the ego frame by the optical-to-ego transform; the two must agree
for every camera, cell and stride, so that a change of the camera model (intrinsics, distortion) that is not
mirrored in torch fails here.
"""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from rigopt.baselines.layers import pixel_rays  # noqa: E402
from rigopt.camera import CameraModel  # noqa: E402
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
