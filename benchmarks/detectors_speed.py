"""Detector speed: training and inference throughput (samples/s) of each family and size on synthetic
batches of a rig's shape, the time a control matrix would take, and the LSS splat against a plain
per-point loop (the reference implementation) on the same volume.

Usage: python benchmarks/detectors_speed.py [--rig R1] [--sizes small] [--device cpu] [--steps 6]
                                            [--samples 480] [--epochs 8]
"""

from __future__ import annotations

import argparse
import time

import torch

from rigopt.benchmark import SYNTHETIC_IMAGE_SIZE
from rigopt.validation.detectors.config import model_config
from rigopt.validation.detectors.families import DETECTORS
from rigopt.validation.detectors.data import Batch, BoxTargets
from rigopt.validation.detectors.models import build_model, resolve_device
from rigopt.validation.synthetic.scene_model import CLASSES
from rigopt.rig.library import load_rig

CONTROL_RIGS = 6


def synthetic_batch(rig_name: str, batch_size: int, size=SYNTHETIC_IMAGE_SIZE, boxes: int = 40, seed: int = 0) -> Batch:
    """A batch shaped like ``rig_name``'s data: random images, the rig's real calibration, random boxes."""
    import numpy as np

    from rigopt.camera import intrinsic_matrix
    from rigopt.geometry import optical_from_body

    generator = torch.Generator().manual_seed(seed)
    rig = load_rig(rig_name)
    intrinsics = torch.tensor(np.stack([intrinsic_matrix(c.fov, *size) for c in rig.cameras]), dtype=torch.float32)
    poses = np.tile(np.eye(4), (len(rig), 1, 1))
    for k, camera in enumerate(rig.cameras):
        poses[k, :3, :3], poses[k, :3, 3] = optical_from_body(camera.rotation), camera.position
    cam_to_ego = torch.tensor(poses, dtype=torch.float32)
    n = len(rig)
    targets = [BoxTargets(torch.cat([torch.rand(boxes, 2, generator=generator) * 80 - 40, torch.ones(boxes, 1)], 1),
                          torch.tensor([[4.6, 1.9, 1.7]]).repeat(boxes, 1), torch.rand(boxes, generator=generator) * 6,
                          torch.randint(0, len(CLASSES), (boxes,), generator=generator)) for _ in range(batch_size)]
    return Batch(torch.rand(batch_size, n, 3, size[1], size[0], generator=generator),
                 intrinsics.expand(batch_size, -1, -1, -1), cam_to_ego.expand(batch_size, -1, -1, -1), targets,
                 [str(k) for k in range(batch_size)])


def throughput(family: str, size: str, batch: Batch, device: torch.device, steps: int) -> tuple[float, float]:
    """(training, inference) samples per second over ``steps`` steps after one warm-up step."""
    torch.manual_seed(0)
    model = build_model(model_config(family, size)).to(device)
    optimizer = torch.optim.AdamW(model.parameters(), lr=1e-4)
    batch = batch.to(device)

    def train_step():
        loss, _ = model.loss(model(batch), batch)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()

    def timed(step) -> float:
        step()
        if device.type == "cuda":
            torch.cuda.synchronize()
        start = time.perf_counter()
        for _ in range(steps):
            step()
        if device.type == "cuda":
            torch.cuda.synchronize()
        return steps * len(batch.tokens) / (time.perf_counter() - start)

    model.train()
    training = timed(train_step)
    model.eval()
    with torch.no_grad():
        inference = timed(lambda: model.detections(model(batch)))
    return training, inference


def splat_reference(model, volume: torch.Tensor, batch: Batch, feature_hw) -> torch.Tensor:
    """The LSS splat as a plain loop over lifted points: (B, N, D, Cc, h, w) -> (B, Cc, G, G)."""
    from rigopt.validation.detectors.layers import pixel_rays
    from rigopt.validation.detectors.lss import HEIGHT_LIMITS

    b, n, d, c, h, w = volume.shape
    g, cell, half = model.head.grid, model.config.bev_cell, model.config.bev_range
    origins, directions = pixel_rays(batch.intrinsics, batch.cam_to_ego, feature_hw, model.encoder.stride)
    bev = torch.zeros(b, c, g, g)
    for s in range(b):
        for k in range(n):
            for depth_index, depth in enumerate(model.depths.tolist()):
                for i in range(h):
                    for j in range(w):
                        x, y, z = (origins[s, k, 0, 0] + depth * directions[s, k, i, j]).tolist()
                        ix, iy = int((x + half) // cell), int((y + half) // cell)
                        if 0 <= ix < g and 0 <= iy < g and HEIGHT_LIMITS[0] <= z <= HEIGHT_LIMITS[1]:
                            bev[s, :, ix, iy] += volume[s, k, depth_index, :, i, j]
    return bev


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rig", default="R1")
    parser.add_argument("--sizes", nargs="+", default=["small"])
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--steps", type=int, default=6)
    parser.add_argument("--samples", type=int, default=480, help="training samples per rig (the study's split)")
    parser.add_argument("--epochs", type=int, default=8, help="epochs per training run (the study's)")
    args = parser.parse_args()
    device = resolve_device(args.device)
    print(f"torch {torch.__version__}, {torch.get_num_threads()} threads, device {device}; rig {args.rig}, 160x90")
    for size in args.sizes:
        for family in DETECTORS:
            batch = synthetic_batch(args.rig, model_config(family, size).batch_size)
            training, inference = throughput(family, size, batch, device, args.steps)
            hours = CONTROL_RIGS * args.samples * args.epochs / training / 3600
            print(f"{family} {size}: train {training:.1f} samples/s, inference {inference:.1f} samples/s; "
                  f"{CONTROL_RIGS}-rig control matrix ({args.samples} samples x {args.epochs} epochs each): "
                  f"{hours:.2f} h of training")

    model = build_model(model_config("lss", "tiny")).eval()
    batch = synthetic_batch(args.rig, 1)
    h, w = 12, 20
    volume = torch.rand(1, len(batch.intrinsics[0]), model.config.depth_bins, model.context_channels, h, w)
    start = time.perf_counter()
    fast = model.splat(volume, batch, (h, w))
    fast_seconds = time.perf_counter() - start
    start = time.perf_counter()
    slow = splat_reference(model, volume, batch, (h, w))
    slow_seconds = time.perf_counter() - start
    print(f"LSS splat of {volume[0, :, :, 0].numel()} lifted points: vectorised {fast_seconds * 1e3:.2f} ms, "
          f"per-point loop {slow_seconds * 1e3:.0f} ms ({slow_seconds / fast_seconds:.0f}x); max difference "
          f"{(fast - slow).abs().max().item():.2e}")


if __name__ == "__main__":
    main()
