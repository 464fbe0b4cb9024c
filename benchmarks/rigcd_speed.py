"""Batched RigCD against per-pair loops on random pairs of 6-10-camera rigs.

Prints the time of each implementation, its ratio to the batched one, and the largest disagreement.
References, in the same run:
  plain loop   rigopt.metrics.reference.rigcd_reference per pair (Python loops over camera pairs)
  numpy loop   per pair: a (Na, Nb) cost matrix with numpy broadcasting, then one Hungarian solve

Usage: python benchmarks/rigcd_speed.py [--pairs 10000] [--seed 0]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.optimize import linear_sum_assignment

from rigopt.geometry import geodesic_distance, quaternion_to_matrix
from rigopt.metrics.reference import rigcd_reference
from rigopt.metrics.rigcd import RigBatch, rigcd_pairs
from rigopt.rig.model import Camera, Rig


def random_rig(rng: np.random.Generator, name: str) -> Rig:
    """A rig of 6-10 cameras, positions within +-3 m, uniform random rotations, FOVs 60-120 deg."""
    n = int(rng.integers(6, 11))
    rotations = quaternion_to_matrix(rng.normal(size=(n, 4)))
    cameras = [Camera(f"C{k}", rng.uniform(-3, 3, 3), rotations[k], float(rng.uniform(60, 120))) for k in range(n)]
    return Rig(name, "random", tuple(cameras))


def numpy_loop(rigs_a, rigs_b) -> np.ndarray:
    out = np.zeros(len(rigs_a))
    for k, (a, b) in enumerate(zip(rigs_a, rigs_b)):
        t = np.linalg.norm(a.positions[:, None] - b.positions[None], axis=-1)
        r = geodesic_distance(a.rotations[:, None], b.rotations[None])
        f = np.abs(a.fovs[:, None] - b.fovs[None])
        rows, cols = linear_sum_assignment(t + r + f)
        match = t[rows, cols].mean() + r[rows, cols].mean() + f[rows, cols].mean()
        out[k] = 0.9 * match + 0.1 * abs(len(a) - len(b)) / max(len(a), len(b))
    return out


def timed(function, *args):
    start = time.perf_counter()
    value = function(*args)
    return value, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=10000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    rigs_a = [random_rig(rng, f"A{k}") for k in range(args.pairs)]
    rigs_b = [random_rig(rng, f"B{k}") for k in range(args.pairs)]

    # Rig arrays are built once on first access and cached; time that once, outside every comparison.
    _, t_arrays = timed(lambda: [(r.positions, r.rotations, r.fovs) for r in rigs_a + rigs_b])
    batched, t_batched = timed(lambda: rigcd_pairs(rigs_a, rigs_b).rigcd)
    batches, t_pack = timed(lambda: (RigBatch.from_rigs(rigs_a), RigBatch.from_rigs(rigs_b)))
    core, t_core = timed(lambda: rigcd_pairs(*batches).rigcd)
    plain, t_plain = timed(lambda: np.array([rigcd_reference(a, b)["rigcd"] for a, b in zip(rigs_a, rigs_b)]))
    looped, t_numpy = timed(numpy_loop, rigs_a, rigs_b)

    print(f"{args.pairs} random pairs of 6-10-camera rigs (seed {args.seed}); "
          f"building the rigs' arrays once took {t_arrays:.3f} s")
    print(f"{'implementation':<14} {'seconds':>9} {'pairs/s':>10} {'ratio':>8} {'max |diff|':>11}")
    for name, seconds, values in (("batched", t_batched, batched), ("core only", t_core, core), ("numpy loop", t_numpy, looped),
                                  ("plain loop", t_plain, plain)):
        diff = np.max(np.abs(values - batched))
        print(f"{name:<14} {seconds:9.3f} {args.pairs / seconds:10.0f} {seconds / t_batched:7.1f}x {diff:11.2e}")
    print(f"(batched = packing the Rig objects into RigBatch arrays, {t_pack:.3f} s, + the core on the arrays)")


if __name__ == "__main__":
    main()
