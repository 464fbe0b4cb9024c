"""A centre-heatmap detection head on a bird's-eye grid (the CenterPoint head of the LSS family).

Grid: G x G square cells of ``cell`` m covering x, y in [-range, range) in the ego frame; tensors are laid
out (B, C, G, G) with dim 2 the x index and dim 3 the y index. Per cell the head predicts a heatmap per
class and 8 regression channels: the centre's offset inside its cell (2, in cells), z (m), log length,
width and height (m), and sin, cos of the yaw.
"""

from __future__ import annotations

import math

import torch
from torch import nn
from torch.nn import functional as F

from rigopt.baselines.data import BoxTargets
from rigopt.bench.scene_model import CLASSES

REGRESSION_CHANNELS = 8


class CenterHead(nn.Module):
    """(B, C_in, G, G) bird's-eye features -> heatmap logits (B, K, G, G) and regression (B, 8, G, G)."""

    def __init__(self, channels: int, bev_range: float, cell: float, n_classes: int = len(CLASSES)):
        super().__init__()
        self.bev_range, self.cell, self.n_classes = bev_range, cell, n_classes
        self.grid = round(2 * bev_range / cell)
        self.heatmap = nn.Sequential(nn.Conv2d(channels, channels, 3, 1, 1), nn.ReLU(inplace=True),
                                     nn.Conv2d(channels, n_classes, 1))
        self.regression = nn.Sequential(nn.Conv2d(channels, channels, 3, 1, 1), nn.ReLU(inplace=True),
                                        nn.Conv2d(channels, REGRESSION_CHANNELS, 1))
        nn.init.constant_(self.heatmap[-1].bias, -math.log((1 - 0.1) / 0.1))  # start at p = 0.1

    def forward(self, bev: torch.Tensor) -> dict:
        return {"heatmap": self.heatmap(bev), "regression": self.regression(bev)}

    def targets(self, boxes: BoxTargets) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """One sample's targets: heatmap (K, G, G) in [0, 1], centre cells (n, 2) long, regression (n, 8).

        Each box puts a Gaussian (sigma a quarter of its larger footprint side, at least 0.8 cell) at its
        centre cell, peak exactly 1; boxes outside the grid are left out.
        """
        g, device = self.grid, boxes.centers.device
        cells = torch.floor((boxes.centers[:, :2] + self.bev_range) / self.cell)
        inside = ((cells >= 0) & (cells < g)).all(dim=1)
        centers, sizes, yaws, classes = (boxes.centers[inside], boxes.sizes[inside], boxes.yaws[inside],
                                         boxes.classes[inside])
        cells = cells[inside].long()
        heatmap = torch.zeros(self.n_classes, g, g, device=device)
        if len(cells):
            index = torch.arange(g, device=device, dtype=torch.float32)
            sigma = torch.clamp(0.25 * sizes[:, :2].max(dim=1).values / self.cell, min=0.8)
            dx = (index[None, :] - cells[:, 0:1]) ** 2  # (n, G)
            dy = (index[None, :] - cells[:, 1:2]) ** 2
            gauss = torch.exp(-(dx[:, :, None] + dy[:, None, :]) / (2 * sigma[:, None, None] ** 2))
            for c in classes.unique():
                heatmap[c] = gauss[classes == c].amax(dim=0)
        offsets = (centers[:, :2] + self.bev_range) / self.cell - cells
        regression = torch.cat([offsets, centers[:, 2:3], torch.log(sizes.clamp(min=0.05)),
                                torch.sin(yaws)[:, None], torch.cos(yaws)[:, None]], dim=1)
        return heatmap, cells, regression

    def loss(self, outputs: dict, boxes: list) -> tuple[torch.Tensor, dict]:
        """Focal heatmap loss plus L1 regression at the centre cells, each averaged over the boxes."""
        heat_losses, reg_losses, n_boxes = [], [], 0
        for b, sample_boxes in enumerate(boxes):
            heat_target, cells, reg_target = self.targets(sample_boxes)
            heat_losses.append(focal_heatmap_loss(outputs["heatmap"][b], heat_target))
            if len(cells):
                predicted = outputs["regression"][b][:, cells[:, 0], cells[:, 1]].T  # (n, 8)
                reg_losses.append(F.l1_loss(predicted, reg_target, reduction="sum"))
            n_boxes += len(cells)
        normaliser = max(n_boxes, 1)
        heat = torch.stack(heat_losses).sum() / normaliser
        reg = torch.stack(reg_losses).sum() / normaliser if reg_losses else outputs["regression"].sum() * 0
        return heat + reg, {"heatmap": float(heat.detach()), "regression": float(reg.detach())}

    @torch.no_grad()
    def decode(self, outputs: dict, top_k: int = 100) -> list[dict]:
        """Per sample the ``top_k`` local heatmap maxima: centers (k, 3) m, sizes (k, 3), yaws (k,), classes
        (k,), scores (k,), tensors on the CPU."""
        heat = torch.sigmoid(outputs["heatmap"])
        peaks = heat * (F.max_pool2d(heat, 3, 1, 1) == heat)
        b, k, g, _ = heat.shape
        scores, flat = peaks.reshape(b, -1).topk(min(top_k, k * g * g), dim=1)
        classes, cell = flat // (g * g), flat % (g * g)
        ix, iy = cell // g, cell % g
        results = []
        for i in range(b):
            reg = outputs["regression"][i][:, ix[i], iy[i]].T  # (k, 8)
            x = (ix[i] + reg[:, 0]) * self.cell - self.bev_range
            y = (iy[i] + reg[:, 1]) * self.cell - self.bev_range
            results.append({"centers": torch.stack([x, y, reg[:, 2]], dim=1).cpu(),
                            "sizes": torch.exp(reg[:, 3:6].clamp(max=4)).cpu(),
                            "yaws": torch.atan2(reg[:, 6], reg[:, 7]).cpu(),
                            "classes": classes[i].cpu(), "scores": scores[i].cpu()})
        return results


def focal_heatmap_loss(logits: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """CenterNet's penalty-reduced focal loss, summed: logits and target (K, G, G); target 1 at centres."""
    p = torch.sigmoid(logits).clamp(1e-4, 1 - 1e-4)
    positive = target.eq(1).float()
    pos = -torch.log(p) * (1 - p) ** 2 * positive
    neg = -torch.log(1 - p) * p ** 2 * (1 - target) ** 4 * (1 - positive)
    return (pos + neg).sum()
