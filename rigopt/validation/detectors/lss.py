"""An LSS-style detector (the family of BEVDet and BEVFusion's camera branch): lift, splat, detect.

1. Encode each camera image to (C, h, w) features at 1/8 (or, ``feature_stride`` 4, 1/4) resolution.
2. Lift: per feature cell predict a distribution over D depth bins and a context vector; the outer
   product places the context along the cell's ray at every bin's depth, weighted by its probability.
3. Splat: every lifted point goes, through the camera calibration, to the ego-frame bird's-eye cell
   below it (points more than 2 m below the ground or 6 m above it are dropped); cells sum their points.
   The rays come from the intrinsics for pinholes; where the batch carries lens models (``Batch.lenses``:
   some camera is distorted, e.g. a fisheye), every camera's rays come from its lens model's unprojection,
   and a fisheye's cells 90 degrees or more off its axis (no point at positive depth) are not lifted; where
   it carries pixel ray maps (``Batch.rays``, the detector contract's input), from those.
4. A bird's-eye CNN and a centre-heatmap head (``center_head.py``) detect the boxes.

Depth supervision (as BEVDepth): where the batch carries the renderer's depth maps, each feature cell's depth
distribution is also taught the nearest surface in its image patch (cross-entropy over the bins, weight
``config.depth_weight``; cells whose nearest surface lies outside the bins are left out).

Any camera count works: the calibration of the rig at hand decides where each camera's features land.
"""

from __future__ import annotations

import torch
from torch import nn
from torch.nn import functional as F

from rigopt.validation.detectors.center_head import CenterHead
from rigopt.validation.detectors.config import FAMILY_DEFAULTS, ModelConfig
from rigopt.validation.detectors.data import Batch
from rigopt.validation.detectors.layers import ImageEncoder, conv_block, lens_cells, pixel_rays

HEIGHT_LIMITS = (-2.0, 6.0)  # m, ego z of the lifted points kept


class LSSDetector(nn.Module):
    """The LSS-style family (see the module docstring); satisfies ``families.Detector``."""

    family = "lss"
    config_defaults = FAMILY_DEFAULTS["lss"]
    takes_lenses = True

    def __init__(self, config: ModelConfig):
        super().__init__()
        self.config = config
        self.encoder = ImageEncoder(config.width, config.feature_stride)
        channels = self.encoder.out_channels
        self.context_channels = config.bev_channels
        self.depth_net = nn.Conv2d(channels, config.depth_bins + config.bev_channels, 1)
        step = (config.depth_max - config.depth_min) / config.depth_bins
        self.register_buffer("depths", config.depth_min + step * (torch.arange(config.depth_bins) + 0.5),
                             persistent=False)
        self.head = CenterHead(config.bev_channels, config.bev_range, config.bev_cell)
        c = config.bev_channels
        self.bev_near = nn.Sequential(conv_block(c, c), conv_block(c, c))
        self.bev_far = nn.Sequential(conv_block(c, 2 * c, 2), conv_block(2 * c, 2 * c))
        self.bev_merge = conv_block(3 * c, c)

    def forward(self, batch: Batch) -> dict:
        b, n = batch.images.shape[:2]
        features = self.encoder(batch.images.flatten(0, 1))  # (B*N, C, h, w)
        h, w = features.shape[-2:]
        lifted = self.depth_net(features)
        depth = lifted[:, :self.config.depth_bins].softmax(dim=1)  # (B*N, D, h, w)
        context = lifted[:, self.config.depth_bins:]  # (B*N, Cc, h, w)
        bev = self.splat(depth.view(b, n, *depth.shape[1:]), context.view(b, n, *context.shape[1:]), batch)
        near = self.bev_near(bev)
        far = F.interpolate(self.bev_far(near), size=near.shape[-2:], mode="bilinear", align_corners=False)
        outputs = self.head(self.bev_merge(torch.cat([near, far], dim=1)))
        outputs["depth_logits"] = lifted[:, :self.config.depth_bins]
        return outputs

    def splat(self, depth: torch.Tensor, context: torch.Tensor, batch: Batch) -> torch.Tensor:
        """Lift and splat: depth (B, N, D, h, w) probabilities and context (B, N, Cc, h, w) features -> (B, Cc, G, G)
        bird's-eye features, the sum per cell of depth x context over the frustum points that fall in the grid.
        Only those points' products are formed (not the whole (B, N, D, Cc, h, w) volume)."""
        b, n, d, h, w = depth.shape
        g, cell, half = self.head.grid, self.config.bev_cell, self.config.bev_range
        camera_rays = in_front = None
        if batch.rays is not None:  # pixel ray maps: a cell's ray is its centre pixel's (pixel_rays' convention)
            stride = self.encoder.stride
            camera_rays = batch.rays[:, :, ::stride, ::stride][:, :, :h, :w]  # (B, N, h, w, 3)
            in_front = camera_rays[..., 2] > 0
        elif batch.lenses is not None:  # some lens is distorted: every camera's rays through its lens model
            camera_rays, in_front = lens_cells(batch.lenses, (h, w), self.encoder.stride, depth.dtype)
        origins, directions = pixel_rays(batch.intrinsics, batch.cam_to_ego, (h, w), self.encoder.stride,
                                         camera_rays)
        points = origins[:, :, None] + self.depths[None, None, :, None, None, None] * directions[:, :, None]
        ix = torch.floor((points[..., 0] + half) / cell).long()  # (B, N, D, h, w)
        iy = torch.floor((points[..., 1] + half) / cell).long()
        kept = (ix >= 0) & (ix < g) & (iy >= 0) & (iy < g) & (points[..., 2] >= HEIGHT_LIMITS[0]) & (
            points[..., 2] <= HEIGHT_LIMITS[1])
        if in_front is not None:  # a fisheye's cells that look behind its lens plane have no point to lift
            kept &= in_front.to(kept.device).expand(b, n, h, w)[:, :, None]
        sample, camera, _, row, col = kept.nonzero(as_tuple=True)  # in the volume's order
        flat = sample * g * g + ix[kept] * g + iy[kept]
        values = depth[kept][:, None] * context.permute(0, 1, 3, 4, 2)[sample, camera, row, col]  # (P, Cc)
        bev = depth.new_zeros(b * g * g, context.shape[2]).index_add_(0, flat, values)
        return bev.view(b, g, g, -1).permute(0, 3, 1, 2).contiguous()

    def loss(self, outputs: dict, batch: Batch) -> tuple[torch.Tensor, dict]:
        loss, parts = self.head.loss(outputs, batch.boxes)
        if batch.depths is None or self.config.depth_weight <= 0:
            return loss, parts
        logits = outputs["depth_logits"]  # (B*N, D, h, w)
        bins = self.depth_bins(batch.depths.flatten(0, 1), logits.shape[-2:])
        depth_loss = F.cross_entropy(logits, bins, ignore_index=-1) if (bins >= 0).any() else logits.sum() * 0
        return loss + self.config.depth_weight * depth_loss, {**parts, "depth": float(depth_loss.detach())}

    def depth_bins(self, depths: torch.Tensor, feature_hw) -> torch.Tensor:
        """(M, H, W) depth maps (m, 0: none) -> (M, h, w) long: the bin of the nearest surface in each feature
        cell's stride x stride patch, -1 where it has none inside [depth_min, depth_max)."""
        h, w = feature_hw
        s = self.encoder.stride
        padded = F.pad(depths, (0, w * s - depths.shape[-1], 0, h * s - depths.shape[-2]))
        nearest = -F.max_pool2d(-torch.where(padded > 0, padded, torch.full_like(padded, float("inf")))[:, None], s)[:, 0]
        step = (self.config.depth_max - self.config.depth_min) / self.config.depth_bins
        index = torch.floor((nearest - self.config.depth_min) / step)
        inside = (index >= 0) & (index < self.config.depth_bins)
        return torch.where(inside, index, torch.full_like(index, -1)).long()

    def detections(self, outputs: dict, top_k: int = 100) -> list[dict]:
        return self.head.decode(outputs, top_k)
