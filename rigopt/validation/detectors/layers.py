"""Pieces both detector families share: the image encoder and the pixel rays of a calibrated rig (pinhole
rays from the intrinsic matrices in torch, or any lens's rays from the camera model in numpy: :func:`lens_rays`,
and :func:`lens_cells` for lenses that see beyond 90 degrees off their axis)."""

from __future__ import annotations

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from rigopt.camera import MIN_DEPTH, CameraModel

#: Per-channel image normalisation (RGB in [0, 1]).
IMAGE_MEAN, IMAGE_STD = 0.45, 0.25


def conv_block(c_in: int, c_out: int, stride: int = 1) -> nn.Sequential:
    """3 x 3 convolution, batch norm, ReLU."""
    return nn.Sequential(nn.Conv2d(c_in, c_out, 3, stride, 1, bias=False), nn.BatchNorm2d(c_out), nn.ReLU(inplace=True))


class ImageEncoder(nn.Module):
    """A small CNN: (M, 3, H, W) images in [0, 1] -> (M, 2 * width, ~H/stride, ~W/stride) features, stride 8 or 4.

    Four stride-2 stages (to 1/16) and a top-down merge of the last stage into the 1/8 map, so that each
    1/8 feature sees a wide context; at stride 4 the merged 1/8 map is merged once more, top-down, into the
    second stage's 1/4 map (finer rays to lift along, at the cost of four times the cells).
    """

    def __init__(self, width: int, stride: int = 8):
        super().__init__()
        if stride not in (4, 8):
            raise ValueError(f"ImageEncoder stride is 4 or 8, got {stride}")
        self.stride = stride
        self.out_channels = 2 * width
        self.stage1 = nn.Sequential(conv_block(3, width, 2), conv_block(width, width))
        self.stage2 = nn.Sequential(conv_block(width, width, 2), conv_block(width, width))
        self.stage3 = nn.Sequential(conv_block(width, 2 * width, 2), conv_block(2 * width, 2 * width))
        self.stage4 = nn.Sequential(conv_block(2 * width, 4 * width, 2), conv_block(4 * width, 4 * width))
        self.lateral = nn.Conv2d(4 * width, 2 * width, 1)
        self.merge = conv_block(2 * width, 2 * width)
        if stride == 4:
            self.lateral_quarter = nn.Conv2d(width, 2 * width, 1)
            self.merge_quarter = conv_block(2 * width, 2 * width)

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        x = (images - IMAGE_MEAN) / IMAGE_STD
        quarter = self.stage2(self.stage1(x))
        eighth = self.stage3(quarter)
        sixteenth = self.stage4(eighth)
        top_down = F.interpolate(self.lateral(sixteenth), size=eighth.shape[-2:], mode="bilinear", align_corners=False)
        merged = self.merge(eighth + top_down)
        if self.stride == 8:
            return merged
        top_down = F.interpolate(merged, size=quarter.shape[-2:], mode="bilinear", align_corners=False)
        return self.merge_quarter(self.lateral_quarter(quarter) + top_down)


def cell_centres(feature_hw: tuple[int, int], stride: int = 8) -> np.ndarray:
    """(h * w, 2) float: pixel coordinates (u, v) of the centres of a feature map's cells, row by row (see
    :func:`pixel_rays`)."""
    h, w = feature_hw
    rows, cols = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    return np.stack([stride * cols.ravel() + 0.5, stride * rows.ravel() + 0.5], axis=-1)


def lens_rays(model: CameraModel, feature_hw: tuple[int, int], stride: int = 8,
              dtype: torch.dtype = torch.float32) -> torch.Tensor:
    """(..., h, w, 3) optical-frame rays at unit depth through the cells of a feature map, computed by the
    camera model (numpy) through each lens's distortion, for :func:`pixel_rays` ``camera_rays``. ``model``
    has batch shape (...,) (e.g. (N,) cameras) at the image size the features were made from. A fisheye
    cell 90 degrees or more off the axis has no such ray (RigoptError)."""
    h, w = feature_hw
    rays = model.pixel_rays(cell_centres(feature_hw, stride), unit=False, frame="optical")
    return torch.as_tensor(rays.reshape(*model.shape, h, w, 3), dtype=dtype)


def lens_cells(model: CameraModel, feature_hw: tuple[int, int], stride: int = 8,
               dtype: torch.dtype = torch.float32) -> tuple[torch.Tensor, torch.Tensor]:
    """The cells of a feature map that look in front of their lens, and their rays, through each lens's
    distortion (the camera model's unprojection, numpy). ``model`` has batch shape (...,) (e.g. (N,) cameras)
    at the image size the features were made from. Returns (..., h, w, 3) optical-frame rays at unit depth,
    for :func:`pixel_rays` ``camera_rays``, and (..., h, w) bool: the cells whose ray points in front of the
    lens (depth > 0). A fisheye cell 90 degrees or more off the axis has no point at positive depth: its ray
    is zero and it is False, to be left out by the caller; the other cells' rays are :func:`lens_rays`'."""
    h, w = feature_hw
    unit = model.pixel_rays(cell_centres(feature_hw, stride), unit=True, frame="optical")
    depth = unit[..., 2:]
    in_front = depth > MIN_DEPTH
    rays = np.where(in_front, unit / np.where(in_front, depth, 1.0), 0.0)
    return (torch.as_tensor(rays.reshape(*model.shape, h, w, 3), dtype=dtype),
            torch.as_tensor(in_front.reshape(*model.shape, h, w)))


def pinhole_rays(intrinsics: torch.Tensor, feature_hw: tuple[int, int], stride: int = 8) -> torch.Tensor:
    """(..., h, w, 3) optical-frame rays at unit depth of distortion-free lenses with ``intrinsics`` (..., 3, 3) px
    through the cells of a feature map made by ``stride`` (cell (i, j) at pixel (stride j + 0.5, stride i + 0.5));
    stride 1: through every pixel's centre (the detector contract's ray maps)."""
    h, w = feature_hw
    device, dtype = intrinsics.device, intrinsics.dtype
    v = torch.arange(h, device=device, dtype=dtype) * stride + 0.5
    u = torch.arange(w, device=device, dtype=dtype) * stride + 0.5
    vv, uu = torch.meshgrid(v, u, indexing="ij")  # (h, w)
    fx, fy = intrinsics[..., 0, 0, None, None], intrinsics[..., 1, 1, None, None]
    cx, cy = intrinsics[..., 0, 2, None, None], intrinsics[..., 1, 2, None, None]
    return torch.stack([(uu - cx) / fx, (vv - cy) / fy, torch.ones_like(uu).expand_as(fx * uu)], dim=-1)


def pixel_rays(intrinsics: torch.Tensor, cam_to_ego: torch.Tensor, feature_hw: tuple[int, int],
               stride: int = 8, camera_rays: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor]:
    """Rays through the centres of a feature map's cells, in the ego frame.

    intrinsics (B, N, 3, 3) pixels; cam_to_ego (B, N, 4, 4) optical frame -> ego; feature_hw (h, w) of a map
    made by ``stride``: its cell (i, j) is centred on image pixel (row stride i, column stride j), i.e. at
    pixel coordinates (u, v) = (stride j + 0.5, stride i + 0.5) with (0, 0) the image's top-left corner (the
    centre of the stride-2, padding-1 convolutions' receptive fields). Returns origins (B, N, 1, 1, 3) m and
    directions (B, N, h, w, 3) scaled so that a point at depth d (m, along the optical axis) is
    ``origin + d * direction``.

    Without ``camera_rays`` the rays are those of distortion-free lenses with ``intrinsics``: the torch
    mirror of :meth:`rigopt.camera.CameraModel.pixel_rays` (``unit=False``), which owns the projection
    model; tests/validation/detectors/test_layers.py checks that the two agree. For distorted lenses pass
    ``camera_rays`` ((B, N, h, w, 3) or (N, h, w, 3) optical-frame rays at unit depth, from
    :func:`lens_rays` or :func:`lens_cells`): they replace the ``intrinsics`` rays.
    """
    h, w = feature_hw
    if camera_rays is None:
        camera_rays = pinhole_rays(intrinsics, feature_hw, stride)
    else:
        camera_rays = camera_rays.to(device=intrinsics.device, dtype=intrinsics.dtype).expand(*cam_to_ego.shape[:2], h,
                                                                                             w, 3)
    rotation = cam_to_ego[..., :3, :3]  # (B, N, 3, 3)
    directions = torch.einsum("bnij,bnhwj->bnhwi", rotation, camera_rays)
    return cam_to_ego[..., None, None, :3, 3], directions
