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

from rigopt.validation.detectors.data import BoxTargets
from rigopt.validation.synthetic.scene_model import CLASSES

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

    def targets(self, boxes: list) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
        """A batch's targets from its B samples' BoxTargets: heatmap (B, K, G, G) in [0, 1], and per box inside
        the grid (n of them, all samples) its sample (n,) long, centre cell (n, 2) long and regression (n, 8).

        Each box puts a Gaussian (sigma a quarter of its larger footprint side, at least 0.8 cell) at its
        centre cell, peak exactly 1, on its class's map; where boxes overlap a cell keeps the largest value.
        Built for the whole batch at once (a few dozen tensor operations, not a few per box and class: on a
        GPU each costs launch time).
        """
        g, k, device = self.grid, self.n_classes, boxes[0].centers.device
        sample = torch.cat([torch.full((len(b.classes),), i, dtype=torch.long, device=device)
                            for i, b in enumerate(boxes)])
        centers, sizes, yaws, classes = (torch.cat([getattr(b, name) for b in boxes])
                                         for name in ("centers", "sizes", "yaws", "classes"))
        cells = torch.floor((centers[:, :2] + self.bev_range) / self.cell)
        inside = ((cells >= 0) & (cells < g)).all(dim=1)
        sample, centers, sizes, yaws, classes = (v[inside] for v in (sample, centers, sizes, yaws, classes))
        cells = cells[inside].long()
        heatmap = torch.zeros(len(boxes) * k, g * g, device=device)
        if len(cells):
            index = torch.arange(g, device=device, dtype=torch.float32)
            sigma = torch.clamp(0.25 * sizes[:, :2].max(dim=1).values / self.cell, min=0.8)
            spread = (2 * sigma**2)[:, None]
            gx = torch.exp(-((index[None, :] - cells[:, 0:1]) ** 2) / spread)  # (n, G), separable Gaussian
            gy = torch.exp(-((index[None, :] - cells[:, 1:2]) ** 2) / spread)
            gauss = (gx[:, :, None] * gy[:, None, :]).reshape(len(cells), g * g)
            heatmap.scatter_reduce_(0, (sample * k + classes)[:, None].expand(-1, g * g), gauss, "amax")
        offsets = (centers[:, :2] + self.bev_range) / self.cell - cells
        regression = torch.cat([offsets, centers[:, 2:3], torch.log(sizes.clamp(min=0.05)),
                                torch.sin(yaws)[:, None], torch.cos(yaws)[:, None]], dim=1)
        return heatmap.view(len(boxes), k, g, g), sample, cells, regression

    def loss(self, outputs: dict, boxes: list) -> tuple[torch.Tensor, dict]:
        """Focal heatmap loss plus L1 regression at the centre cells, each summed over the batch and divided
        by its number of boxes (at least 1)."""
        heat_target, sample, cells, reg_target = self.targets(boxes)
        normaliser = max(len(cells), 1)
        heat = focal_heatmap_loss(outputs["heatmap"], heat_target) / normaliser
        if len(cells):
            predicted = outputs["regression"][sample, :, cells[:, 0], cells[:, 1]]  # (n, 8)
            reg = F.l1_loss(predicted, reg_target, reduction="sum") / normaliser
        else:
            reg = outputs["regression"].sum() * 0
        return heat + reg, {"heatmap": float(heat.detach()), "regression": float(reg.detach())}

    @torch.no_grad()
    def decode(self, outputs: dict, top_k: int = 100) -> list[dict]:
        """Per sample the ``top_k`` local heatmap maxima: centers (k, 3) m, sizes (k, 3), yaws (k,), classes
        (k,), scores (k,), tensors on the CPU (:meth:`decode_batch`'s rows)."""
        found = self.decode_batch(outputs, top_k)
        return [{key: value[i].cpu() for key, value in found.items()} for i in range(len(found["scores"]))]

    def decode_batch(self, outputs: dict, top_k: int = 100) -> dict:
        """The ``top_k`` local heatmap maxima of every sample, best first, as (B, k, ...) tensors on the
        outputs' device: centers (B, k, 3) m, sizes (B, k, 3), yaws (B, k), classes (B, k), scores (B, k).
        No Python loop over the batch, so that a traced model takes any batch size."""
        heat = torch.sigmoid(outputs["heatmap"])
        peaks = heat * (F.max_pool2d(heat, 3, 1, 1) == heat)
        b, k, g, _ = heat.shape
        scores, flat = peaks.reshape(b, -1).topk(min(top_k, k * g * g), dim=1)
        classes, cell = flat // (g * g), flat % (g * g)
        ix, iy = cell // g, cell % g
        regression = outputs["regression"].flatten(2)  # (B, 8, G * G)
        reg = regression.gather(2, cell[:, None].expand(-1, regression.shape[1], -1)).transpose(1, 2)  # (B, k, 8)
        x = (ix + reg[..., 0]) * self.cell - self.bev_range
        y = (iy + reg[..., 1]) * self.cell - self.bev_range
        return {"centers": torch.stack([x, y, reg[..., 2]], dim=-1), "sizes": torch.exp(reg[..., 3:6].clamp(max=4)),
                "yaws": torch.atan2(reg[..., 6], reg[..., 7]), "classes": classes, "scores": scores}


def focal_heatmap_loss(logits: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """CenterNet's penalty-reduced focal loss, summed: logits and target of one shape ((B, K, G, G) or one
    sample's (K, G, G)); target 1 at centres."""
    p = torch.sigmoid(logits).clamp(1e-4, 1 - 1e-4)
    positive = target.eq(1).float()
    pos = -torch.log(p) * (1 - p) ** 2 * positive
    neg = -torch.log(1 - p) * p ** 2 * (1 - target) ** 4 * (1 - positive)
    return (pos + neg).sum()
