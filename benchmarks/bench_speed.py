"""Synthetic benchmark speed: images per second at 160 x 90 and 1280 x 720, and the time to generate
scenes of the training split for one 8-camera rig (R1), extrapolated to the default split size.

Usage: python benchmarks/bench_speed.py [--scenes 2] [--split-size 100]
"""

from __future__ import annotations

import argparse
import tempfile
import time

from rigopt.benchmark import BENCHMARK_IMAGE_SIZE, SYNTHETIC_IMAGE_SIZE
from rigopt.validation.synthetic.generate import generate_split
from rigopt.validation.synthetic.render import render_rig
from rigopt.validation.synthetic.scenes import generate_scene, split_seeds
from rigopt.rig.library import load_rig
from rigopt.vehicle.library import load_vehicle


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=int, default=2)
    parser.add_argument("--split-size", type=int, default=100, help="scenes of a full training split")
    args = parser.parse_args()
    rig = load_rig("R1")
    mesh = load_vehicle(rig.vehicle).mesh
    scene = generate_scene(split_seeds("train", 1)[0], "train")
    print(f"scene: {len(scene.boxes_at(0))} boxes in frame 0; rig {rig.name}, {len(rig)} cameras")
    for size, frames in ((SYNTHETIC_IMAGE_SIZE, 10), (BENCHMARK_IMAGE_SIZE, 1)):
        render_rig(scene, 0, rig, mesh, size)  # warm caches (road regions, ray intersector)
        start = time.perf_counter()
        for k in range(frames):
            render_rig(scene, k, rig, mesh, size)
        seconds = time.perf_counter() - start
        images = frames * len(rig)
        print(f"{size[0]}x{size[1]}: {images} images in {seconds:.2f} s, {images / seconds:.1f} images/s")
    ego_body_cache(scene, rig, mesh)
    scenes = [generate_scene(s, "train") for s in split_seeds("train", args.scenes)]
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        generate_split([rig], scenes, out, SYNTHETIC_IMAGE_SIZE, render_rig, lambda r: mesh)
        seconds = time.perf_counter() - start
    per_scene = seconds / len(scenes)
    print(f"generate {len(scenes)} training scenes x {len(scene.frames)} samples x {len(rig)} cameras at 160x90 "
          f"(render, annotate, write PNGs and tables): {seconds:.1f} s, {per_scene:.1f} s per scene; "
          f"a {args.split_size}-scene split: about {per_scene * args.split_size / 60:.0f} min")


def ego_body_cache(scene, rig, mesh, frames: int = 10) -> None:
    """The body cast once per camera (the renderer's cache) against casting it every frame, the reference:
    time and identical images."""
    import numpy as np

    from rigopt.validation.synthetic import render

    def run(fresh: bool):
        images, start = [], time.perf_counter()
        for k in range(frames):
            if fresh:
                render._EGO_CACHE.clear()
            images.append(render_rig(scene, k, rig, mesh))
        return time.perf_counter() - start, images

    render._EGO_CACHE.clear()
    reference, expected = run(fresh=True)
    render._EGO_CACHE.clear()
    cached, got = run(fresh=False)
    same = all(np.array_equal(a[c].rgb, b[c].rgb) and np.array_equal(a[c].depth, b[c].depth)
               for a, b in zip(expected, got) for c in a)
    print(f"ego body at 160x90, {frames} frames x {len(rig)} cameras: cast once per camera {cached:.2f} s, "
          f"every frame (reference) {reference:.2f} s, {reference / cached:.2f}x; identical images: {same}")


if __name__ == "__main__":
    main()
