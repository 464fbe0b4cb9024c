"""A PETR-style detector: image features that know their 3D rays, decoded by object queries.

1. Encode each camera image to (C, h, w) features at 1/8 resolution.
2. 3D position embedding: each feature cell's ray, through the camera calibration, sampled at P depths
   (m, along the optical axis, spaced closer near the camera) in the ego frame, normalised by the
   bird's-eye range, becomes a (3 P)-vector; an MLP maps it to C and it is added to the features. The
   tokens of all N cameras form one memory of N h w tokens.
3. Q object queries, each anchored at a learned bird's-eye reference point, attend to the memory through
   a transformer decoder whose attention sees each query's position embedding (of its current reference
   point) and, with ``azimuth_prior``, favours the tokens whose rays pass over that point (an additive
   bias on the cross-attention logits, Gaussian in the azimuth gap, one cell wide, weighted per head and
   layer by a learned factor); after every layer a class head (sigmoid per class) and a box head predict the box: the centre
   as a refinement of the reference point, which becomes the next layer's reference, z, log sizes, sin
   and cos of the yaw.
4. Training matches queries to boxes one to one (Hungarian, on class and centre costs) and applies a
   focal class loss to all queries and L1 box losses to the matched ones, after every layer.
5. Auxiliary token supervision (training only, ``token_supervision``): a 1 x 1 head on the image features
   predicts, per token, whether a box centre projects into it and that centre's log depth, against the
   projections of the true boxes through the calibration (focal loss and L1), so that the features learn
   where objects are and how far before the sparse set loss can teach it.
6. Query denoising (training only, as DN-DETR): ``dn_groups`` copies of the true boxes, their centres jittered
   by up to half the box's length and width and 1 in 5 labels flipped, enter the decoder as extra queries
   (label embedding as content, jittered centre as reference) and must reconstruct their box and class; no
   matching is needed for them. An attention mask keeps the object queries and the other groups from
   seeing a group, so inference, which has no such queries, is unchanged. On small data it shortens the
   slow start of set prediction several-fold.

Any camera count works: the memory is as long as the rig's cameras make it.
"""

from __future__ import annotations

import math

import numpy as np
import torch
from scipy.optimize import linear_sum_assignment
from torch import nn
from torch.nn import functional as F

from rigopt.errors import DataError
from rigopt.validation.detectors.config import FAMILY_DEFAULTS, ModelConfig
from rigopt.validation.detectors.data import Batch
from rigopt.validation.detectors.layers import ImageEncoder, pixel_rays
from rigopt.validation.synthetic.scene_model import CLASSES

Z_SCALE = 4.0  # m: z of centres and position-embedding points is divided by this
#: Loss weights: focal class loss, L1 of the normalised centre, L1 of the other box terms.
CLASS_WEIGHT, CENTER_WEIGHT, BOX_WEIGHT = 2.0, 10.0, 1.0
#: Query denoising: centre jitter as a fraction of the box's length / width (at least DN_MIN_NOISE m), and
#: the probability that a denoising query's label is replaced by a random class.
DN_NOISE, DN_MIN_NOISE, DN_FLIP = 0.5, 1.0, 0.2
#: Weight of the auxiliary image-token loss (object centre and its depth per token).
TOKEN_WEIGHT = 1.0


def _mlp(c_in: int, c_hidden: int, c_out: int) -> nn.Sequential:
    return nn.Sequential(nn.Linear(c_in, c_hidden), nn.ReLU(inplace=True), nn.Linear(c_hidden, c_out))


class DecoderLayer(nn.Module):
    """A DETR decoder layer (post-norm): self-attention among the queries and cross-attention to the
    memory, both with the queries' position embedding added to their queries (and keys), then an MLP.
    x (B, Q, C), position (B, Q, C), memory (B, M, C) -> (B, Q, C)."""

    def __init__(self, channels: int, heads: int):
        super().__init__()
        self.self_attention = nn.MultiheadAttention(channels, heads, batch_first=True)
        self.cross_attention = nn.MultiheadAttention(channels, heads, batch_first=True)
        self.feed_forward = _mlp(channels, 2 * channels, channels)
        self.norms = nn.ModuleList([nn.LayerNorm(channels) for _ in range(3)])

    def forward(self, x: torch.Tensor, position: torch.Tensor, memory: torch.Tensor,
                blocked: torch.Tensor | None = None, memory_bias: torch.Tensor | None = None) -> torch.Tensor:
        """``blocked`` (B * heads, Q, Q) bool: True where query i must not attend to query j;
        ``memory_bias`` (B * heads, Q, M) float: added to the cross-attention logits."""
        q = x + position
        x = self.norms[0](x + self.self_attention(q, q, x, attn_mask=blocked, need_weights=False)[0])
        x = self.norms[1](x + self.cross_attention(x + position, memory, memory, attn_mask=memory_bias,
                                                   need_weights=False)[0])
        return self.norms[2](x + self.feed_forward(x))


class PETRDetector(nn.Module):
    """The PETR-style family (see the module docstring); satisfies ``families.Detector``."""

    family = "petr"
    config_defaults = FAMILY_DEFAULTS["petr"]
    takes_lenses = False  # its rays, cell widths and token targets are a pinhole's of the intrinsics

    def __init__(self, config: ModelConfig, n_classes: int = len(CLASSES)):
        super().__init__()
        self.config, self.n_classes = config, n_classes
        self.encoder = ImageEncoder(config.width, config.feature_stride)
        c = self.encoder.out_channels
        fraction = (torch.arange(config.position_depths) + 0.5) / config.position_depths
        self.register_buffer("depths", config.depth_min + (config.depth_max - config.depth_min) * fraction ** 1.5,
                             persistent=False)
        self.position = _mlp(3 * config.position_depths, c, c)
        self.input_projection = nn.Conv2d(c, c, 1)
        side = math.ceil(math.sqrt(config.queries))
        grid = (torch.stack(torch.meshgrid(torch.arange(side), torch.arange(side), indexing="ij"), -1)
                .reshape(-1, 2)[:config.queries].float() + 0.5) / side
        self.reference = nn.Parameter(torch.logit(grid.clamp(0.02, 0.98)))  # (Q, 2) in logit space
        self.query_content = nn.Parameter(torch.zeros(config.queries, c))
        self.query_position = _mlp(2, c, c)
        self.layers = nn.ModuleList([DecoderLayer(c, config.heads) for _ in range(config.decoder_layers)])
        self.label_embedding = nn.Embedding(n_classes, c)
        # per layer and head, softplus -> the weight of the azimuth prior (1 at the start)
        self.azimuth_weight = nn.Parameter(torch.full((config.decoder_layers, config.heads), math.log(math.e - 1)))
        self.class_head = nn.Linear(c, n_classes)
        self.box_head = _mlp(c, c, 8)
        self.token_head = nn.Conv2d(c, 2, 1)  # per image token: object-centre logit, log depth (m)
        nn.init.constant_(self.class_head.bias, -math.log((1 - 0.01) / 0.01))
        nn.init.constant_(self.token_head.bias[0], -math.log((1 - 0.01) / 0.01))

    def forward(self, batch: Batch) -> dict:
        if batch.lenses is not None:
            raise DataError("a camera of this rig has a distorted lens (radtan or fisheye) and the petr family "
                            "takes pinholes only (its rays come from the intrinsics); use --model lss")
        b, n = batch.images.shape[:2]
        features = self.input_projection(self.encoder(batch.images.flatten(0, 1)))  # (B*N, C, h, w)
        h, w = features.shape[-2:]
        origins, directions = pixel_rays(batch.intrinsics, batch.cam_to_ego, (h, w), self.encoder.stride)
        points = origins[..., None, :] + self.depths[:, None] * directions[..., None, :]  # (B, N, h, w, P, 3)
        scale = points.new_tensor([self.config.bev_range, self.config.bev_range, Z_SCALE])
        embedding = self.position((points / scale).flatten(-2))  # (B, N, h, w, C)
        memory = features.view(b, n, -1, h, w).permute(0, 1, 3, 4, 2) + embedding
        memory = memory.reshape(b, n * h * w, -1)
        rays = self.ray_azimuths(origins, directions, batch.intrinsics)

        reference = self.reference[None].expand(b, -1, -1)  # (B, Q, 2) logits of [0, 1] over the square
        x = self.query_content[None].expand(b, -1, -1)
        denoising = self.denoising_queries(batch) if self.training and self.config.dn_groups else None
        blocked = None
        if denoising is not None:
            x = torch.cat([denoising["content"], x], dim=1)
            reference = torch.cat([denoising["reference"], reference], dim=1)
            blocked = denoising["blocked"]
        logits, boxes = [], []
        for k, layer in enumerate(self.layers):
            bias = self.azimuth_bias(reference, rays, k) if self.config.azimuth_prior else None
            x = layer(x, self.query_position(torch.sigmoid(reference) * 2 - 1), memory, blocked, bias)
            raw = self.box_head(x)  # (B, D + Q, 8)
            center_logit = reference + raw[..., :2]
            boxes.append(torch.cat([torch.sigmoid(center_logit), raw[..., 2:]], dim=-1))
            logits.append(self.class_head(x))
            reference = center_logit.detach()  # the next layer refines this layer's centres
        outputs = {"logits": logits, "boxes": boxes}
        if self.training and self.config.token_supervision:
            outputs["tokens"] = self.token_head(features).view(b, n, 2, h, w)
        if denoising is not None:
            d = denoising["valid"].shape[1]
            outputs.update({"logits": [l[:, d:] for l in logits], "boxes": [x[:, d:] for x in boxes],
                            "denoising": {**denoising, "logits": [l[:, :d] for l in logits],
                                          "boxes": [x[:, :d] for x in boxes]}})
        return outputs

    def ray_azimuths(self, origins, directions, intrinsics) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Per memory token (M = N h w): its camera's (x, y) (B, M, 2) m, its ray's azimuth (B, M) rad in the
        ego frame, and the azimuth width of one feature cell (B, M) rad (stride / fx)."""
        b, n, h, w = directions.shape[:4]
        origin = origins[..., :2].expand(b, n, h, w, 2).reshape(b, -1, 2)
        azimuth = torch.atan2(directions[..., 1], directions[..., 0]).reshape(b, -1)
        width = (self.encoder.stride / intrinsics[..., 0, 0])[:, :, None].expand(b, n, h * w).reshape(b, -1)
        return origin, azimuth, width

    def azimuth_bias(self, reference: torch.Tensor, rays, layer: int) -> torch.Tensor:
        """The azimuth prior of layer ``layer``'s cross-attention, (B * heads, Q, M): -weight x (da / width)^2 / 2
        with da the angle between a token's ray and the direction from its camera to the query's reference
        point (Q queries, reference (B, Q, 2) logits). A query thus looks first along the rays that pass over
        it; each head learns its weight (softplus)."""
        origin, azimuth, width = rays
        r = self.config.bev_range
        point = (torch.sigmoid(reference) * 2 - 1) * r  # (B, Q, 2) m
        offset = point[:, :, None, :] - origin[:, None]  # (B, Q, M, 2)
        angle = torch.remainder(torch.atan2(offset[..., 1], offset[..., 0]) - azimuth[:, None] + math.pi,
                                2 * math.pi) - math.pi
        penalty = -0.5 * (angle / width[:, None]) ** 2  # (B, Q, M)
        weight = F.softplus(self.azimuth_weight[layer])  # (heads,)
        return (weight[None, :, None, None] * penalty[:, None]).flatten(0, 1)

    def targets(self, batch: Batch) -> list[tuple[torch.Tensor, torch.Tensor]]:
        """Per sample the classes (n,) and box targets (n, 8) of the boxes inside the bird's-eye square."""
        r = self.config.bev_range
        result = []
        for boxes in batch.boxes:
            inside = (boxes.centers[:, :2].abs() < r).all(dim=1)
            result.append((boxes.classes[inside], self.box_targets(boxes.centers[inside], boxes.sizes[inside],
                                                                   boxes.yaws[inside])))
        return result

    def denoising_queries(self, batch: Batch) -> dict | None:
        """The denoising queries of a training batch, D = dn_groups x (most boxes in a sample), slot
        g * n_max + j holding box j of group g: content (B, D, C), reference (B, D, 2) logits, classes
        (B, D) true labels, target (B, D, 8), valid (B, D) bool (False: padding), blocked (B * heads,
        D + Q, D + Q) self-attention mask. None when the batch has no boxes."""
        targets = self.targets(batch)
        n_max = max(len(classes) for classes, _ in targets)
        if n_max == 0:
            return None
        groups, device = self.config.dn_groups, batch.images.device
        b, d, q = len(targets), self.config.dn_groups * n_max, self.config.queries
        classes = torch.zeros(b, d, dtype=torch.long, device=device)
        target = torch.zeros(b, d, 8, device=device)
        target[..., :2] = 0.5
        valid = torch.zeros(b, d, dtype=torch.bool, device=device)
        r = self.config.bev_range
        for i, (labels, boxes) in enumerate(targets):
            n = len(labels)
            for g in range(groups):
                classes[i, g * n_max:g * n_max + n] = labels
                target[i, g * n_max:g * n_max + n] = boxes
                valid[i, g * n_max:g * n_max + n] = True
        half_extent = (torch.exp(target[..., 3:5]) * DN_NOISE).clamp(min=DN_MIN_NOISE) / (2 * r)  # normalised
        center = target[..., :2] + (2 * torch.rand_like(half_extent) - 1) * half_extent
        flip = torch.rand(b, d, device=device) < DN_FLIP
        labels = torch.where(flip, torch.randint_like(classes, self.n_classes), classes)
        content = self.label_embedding(labels) * valid[..., None]
        reference = torch.logit(center.clamp(0.01, 0.99))

        group = torch.arange(d, device=device) // n_max
        allowed = torch.zeros(d + q, d + q, dtype=torch.bool, device=device)
        allowed[:d, :d] = group[:, None] == group[None, :]  # a denoising group sees itself ...
        allowed[:, d:] = True  # ... and every query sees the object queries, which see no denoising query
        allowed = allowed[None].repeat(b, 1, 1)
        allowed[:, :, :d] &= valid[:, None, :]  # nobody attends to padding ...
        allowed |= torch.eye(d + q, dtype=torch.bool, device=device)  # ... but every query to itself
        blocked = (~allowed).repeat_interleave(self.config.heads, dim=0)
        return {"content": content, "reference": reference, "classes": classes, "target": target,
                "valid": valid, "blocked": blocked}

    def box_targets(self, centers, sizes, yaws) -> torch.Tensor:
        """(n, 8) regression targets in the box head's units: centre x, y in [0, 1] over the square,
        z / Z_SCALE, log sizes, sin and cos of the yaw."""
        r = self.config.bev_range
        return torch.cat([(centers[:, :2] + r) / (2 * r), centers[:, 2:3] / Z_SCALE, torch.log(sizes.clamp(min=0.05)),
                          torch.sin(yaws)[:, None], torch.cos(yaws)[:, None]], dim=1)

    def loss(self, outputs: dict, batch: Batch) -> tuple[torch.Tensor, dict]:
        total, parts = 0.0, {"class": 0.0, "center": 0.0, "box": 0.0}
        targets = self.targets(batch)
        n_boxes = max(sum(len(t[0]) for t in targets), 1)
        for logits, boxes in zip(outputs["logits"], outputs["boxes"]):
            class_target = torch.zeros_like(logits)
            center_loss = box_loss = logits.new_zeros(())
            for i, (classes, target) in enumerate(targets):
                if not len(classes):
                    continue
                queries, matched = hungarian_match(logits[i], boxes[i], classes, target)
                class_target[i, queries, classes[matched]] = 1.0
                center_loss = center_loss + F.l1_loss(boxes[i, queries, :2], target[matched, :2], reduction="sum")
                box_loss = box_loss + F.l1_loss(boxes[i, queries, 2:], target[matched, 2:], reduction="sum")
            class_loss = sigmoid_focal_loss(logits, class_target) / n_boxes
            layer_loss = (CLASS_WEIGHT * class_loss + CENTER_WEIGHT * center_loss / n_boxes
                          + BOX_WEIGHT * box_loss / n_boxes)
            total = total + layer_loss
            parts = {"class": float(class_loss.detach()), "center": float(center_loss.detach()) / n_boxes,
                     "box": float(box_loss.detach()) / n_boxes}  # the last layer's terms
        if "denoising" in outputs:
            total = total + self.denoising_loss(outputs["denoising"])
        if "tokens" in outputs:
            token_loss = self.token_loss(outputs["tokens"], batch)
            total = total + TOKEN_WEIGHT * token_loss
            parts["tokens"] = float(token_loss.detach())
        return total, parts

    def token_targets(self, batch: Batch, feature_hw: tuple[int, int]) -> tuple[torch.Tensor, torch.Tensor]:
        """Which image tokens hold a box centre, and the depth of the nearest one: (B, N, h, w) bool and
        (B, N, h, w) float depth (m along the optical axis; inf where there is none). A centre belongs to the
        cell (v // stride, u // stride) of its projection (u, v) when in front of the camera (depth > 0.5 m)
        and inside the image."""
        b, n, _, height, width = batch.images.shape
        h, w = feature_hw
        stride = self.encoder.stride
        depth = batch.images.new_full((b, n * h * w), math.inf)
        ego_to_cam = torch.linalg.inv(batch.cam_to_ego)  # (B, N, 4, 4)
        for i, boxes in enumerate(batch.boxes):
            if not len(boxes.classes):
                continue
            points = ego_to_cam[i, :, :3, :3] @ boxes.centers.T + ego_to_cam[i, :, :3, 3:]  # (N, 3, n)
            z = points[:, 2]
            k = batch.intrinsics[i]
            u = k[:, 0, 0, None] * points[:, 0] / z.clamp(min=1e-3) + k[:, 0, 2, None]
            v = k[:, 1, 1, None] * points[:, 1] / z.clamp(min=1e-3) + k[:, 1, 2, None]
            seen = (z > 0.5) & (u >= 0) & (u < width) & (v >= 0) & (v < height)
            camera = torch.arange(n, device=z.device)[:, None].expand_as(z)
            cell = (camera * h + (v // stride).clamp(0, h - 1).long()) * w + (u // stride).clamp(0, w - 1).long()
            depth[i].scatter_reduce_(0, cell[seen], z[seen], reduce="amin")
        depth = depth.view(b, n, h, w)
        return torch.isfinite(depth), depth

    def token_loss(self, tokens: torch.Tensor, batch: Batch) -> torch.Tensor:
        """Auxiliary supervision of the image tokens (tokens (B, N, 2, h, w)): focal loss of the centre
        logits, per centre-holding token, plus the L1 error of their log depth."""
        holds, depth = self.token_targets(batch, tokens.shape[-2:])
        n = max(int(holds.sum()), 1)
        centre_loss = sigmoid_focal_loss(tokens[:, :, 0], holds.float()) / n
        depth_loss = F.l1_loss(tokens[:, :, 1][holds], torch.log(depth[holds]), reduction="sum") / n
        return centre_loss + depth_loss

    def denoising_loss(self, denoising: dict) -> torch.Tensor:
        """Reconstruction loss of the denoising queries, every layer: focal class loss towards the true
        label and L1 box losses, over the valid queries, per query, with the matching loss's weights."""
        valid = denoising["valid"]
        n = max(int(valid.sum()), 1)
        class_target = F.one_hot(denoising["classes"], self.n_classes).float()
        total = 0.0
        for logits, boxes in zip(denoising["logits"], denoising["boxes"]):
            class_loss = sigmoid_focal_loss(logits[valid], class_target[valid])
            center_loss = F.l1_loss(boxes[valid][:, :2], denoising["target"][valid][:, :2], reduction="sum")
            box_loss = F.l1_loss(boxes[valid][:, 2:], denoising["target"][valid][:, 2:], reduction="sum")
            total = total + (CLASS_WEIGHT * class_loss + CENTER_WEIGHT * center_loss + BOX_WEIGHT * box_loss) / n
        return total

    @torch.no_grad()
    def detections(self, outputs: dict, top_k: int = 100) -> list[dict]:
        """Per sample the ``top_k`` best (query, class) pairs of the last layer: centers (k, 3) m, sizes (k, 3),
        yaws (k,), classes (k,), scores (k,), tensors on the CPU."""
        logits, boxes = outputs["logits"][-1], outputs["boxes"][-1]
        b, q, k = logits.shape
        scores, flat = torch.sigmoid(logits).reshape(b, -1).topk(min(top_k, q * k), dim=1)
        query, classes = flat // k, flat % k
        r = self.config.bev_range
        results = []
        for i in range(b):
            box = boxes[i, query[i]]
            results.append({"centers": torch.cat([box[:, :2] * 2 * r - r, box[:, 2:3] * Z_SCALE], dim=1).cpu(),
                            "sizes": torch.exp(box[:, 3:6].clamp(max=4)).cpu(),
                            "yaws": torch.atan2(box[:, 6], box[:, 7]).cpu(),
                            "classes": classes[i].cpu(), "scores": scores[i].cpu()})
        return results


@torch.no_grad()
def hungarian_match(logits: torch.Tensor, boxes: torch.Tensor, classes: torch.Tensor,
                    target: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """One-to-one matching of Q queries to n boxes minimising CLASS_WEIGHT x focal class cost + CENTER_WEIGHT
    x L1 centre distance; logits (Q, K), boxes (Q, 8), classes (n,), target (n, 8). Returns matched query
    indices and box indices, (m,) each, m = min(Q, n)."""
    p = torch.sigmoid(logits[:, classes])  # (Q, n)
    class_cost = 0.25 * (1 - p) ** 2 * -torch.log(p + 1e-8) - 0.75 * p ** 2 * -torch.log(1 - p + 1e-8)
    center_cost = torch.cdist(boxes[:, :2], target[:, :2], p=1)
    cost = (CLASS_WEIGHT * class_cost + CENTER_WEIGHT * center_cost).cpu().numpy()
    rows, cols = linear_sum_assignment(np.nan_to_num(cost, nan=1e6))
    device = logits.device
    return torch.as_tensor(rows, device=device, dtype=torch.long), torch.as_tensor(cols, device=device, dtype=torch.long)


def sigmoid_focal_loss(logits: torch.Tensor, target: torch.Tensor, alpha: float = 0.25, gamma: float = 2.0):
    """Summed sigmoid focal loss of logits and 0/1 targets of the same shape."""
    p = torch.sigmoid(logits)
    ce = F.binary_cross_entropy_with_logits(logits, target, reduction="none")
    p_t = p * target + (1 - p) * (1 - target)
    weight = alpha * target + (1 - alpha) * (1 - target)
    return (weight * ce * (1 - p_t) ** gamma).sum()
