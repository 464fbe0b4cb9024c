"""Batched RigCD against naive per-pair loops on the same random pairs of 6-10-camera rigs.

Prints the time of each implementation, its ratio to the batched call, and its largest disagreement with it.
Every implementation starts from the same Rig objects, whose cached arrays (positions, rotations, FOVs and
the column bytes batched metrics join) are built once before any timing; that one-off cost is printed too.
  batched           rigopt.metrics.rigcd.rigcd_pairs(rigs_a, rigs_b): the whole call on lists of Rig
  core on arrays    rigcd_pairs on two RigBatch built beforehand (the (C, 8) camera rows of each side)
  naive (floats)    the tests' oracle oracles.metrics.rigcd_reference per pair: Python loops over camera pairs
                    on Python floats, arccos of the trace, scipy's linear_sum_assignment, the means, the count
  naive (numpy)     the same definition per pair with one numpy call per camera pair (norm, Ra^T Rb, trace,
                    arccos), as a first implementation would write it
The batched times are the median of --repeats runs, after one call on one pair that loads the compiled loops
(timed apart); each naive loop runs once. The load average (1 minute) is
printed before and after.

Usage: python benchmarks/rigcd_speed.py [--pairs 10000] [--seed 0] [--repeats 5]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import linear_sum_assignment

from rigopt.geometry import quaternion_to_matrix
from rigopt.metrics.rigcd import RigBatch, rigcd_pairs
from rigopt.rig.model import Camera, Rig

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the oracles live with the tests
from oracles.metrics import rigcd_reference  # noqa: E402


def random_rig(rng: np.random.Generator, name: str) -> Rig:
    """A rig of 6-10 cameras, positions within +-3 m, uniform random rotations, FOVs 60-120 deg."""
    n = int(rng.integers(6, 11))
    rotations = quaternion_to_matrix(rng.normal(size=(n, 4)))
    cameras = [Camera.pinhole(f"C{k}", rng.uniform(-3, 3, 3), rotations[k], float(rng.uniform(60, 120)))
               for k in range(n)]
    return Rig(name, "random", tuple(cameras))


def naive_numpy(a: Rig, b: Rig, alpha: float = 0.9) -> float:
    """RigCD of one pair (unit lambdas), one numpy call per camera pair, straight from the definition."""
    parts = np.zeros((len(a), len(b), 3))
    for i, ca in enumerate(a.cameras):
        for j, cb in enumerate(b.cameras):
            angle = np.arccos(np.clip((np.trace(ca.rotation.T @ cb.rotation) - 1.0) / 2.0, -1.0, 1.0))
            parts[i, j] = (np.linalg.norm(ca.position - cb.position), angle, abs(ca.fov - cb.fov))
    rows, cols = linear_sum_assignment(parts.sum(axis=2))
    match = parts[rows, cols].mean(axis=0).sum()
    return alpha * match + (1.0 - alpha) * abs(len(a) - len(b)) / max(len(a), len(b))


def timed(function, *args):
    start = time.perf_counter()
    value = function(*args)
    return value, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=10000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    load_before = os.getloadavg()[0]
    rng = np.random.default_rng(args.seed)
    rigs_a = [random_rig(rng, f"A{k}") for k in range(args.pairs)]
    rigs_b = [random_rig(rng, f"B{k}") for k in range(args.pairs)]

    # Rig arrays are built once on first access and cached; time that once, outside every comparison.
    _, t_arrays = timed(lambda: [(r.positions, r.rotations, r.fovs, r.column_bytes) for r in rigs_a + rigs_b])
    # The first call in a process loads the compiled loops (compiles them once per install); time it apart.
    _, t_first = timed(lambda: rigcd_pairs(rigs_a[:1], rigs_b[:1]))
    runs = [timed(lambda: rigcd_pairs(rigs_a, rigs_b).rigcd) for _ in range(args.repeats)]
    batched, t_batched = runs[0][0], float(np.median([seconds for _, seconds in runs]))
    arrays = [RigBatch.from_rigs(rigs) for rigs in (rigs_a, rigs_b)]
    core_runs = [timed(lambda: rigcd_pairs(*arrays).rigcd) for _ in range(args.repeats)]
    core, t_core = core_runs[0][0], float(np.median([seconds for _, seconds in core_runs]))
    floats, t_floats = timed(lambda: np.array([rigcd_reference(a, b)["rigcd"] for a, b in zip(rigs_a, rigs_b)]))
    numpy_loop, t_numpy = timed(lambda: np.array([naive_numpy(a, b) for a, b in zip(rigs_a, rigs_b)]))

    print(f"{args.pairs} random pairs of 6-10-camera rigs (seed {args.seed}); "
          f"building the rigs' arrays once took {t_arrays:.3f} s; the first call (loading the compiled loops) "
          f"{t_first:.3f} s")
    print(f"{'implementation':<16} {'seconds':>9} {'pairs/s':>10} {'ratio':>8} {'max |diff|':>11}")
    for name, seconds, values in (("batched", t_batched, batched), ("core on arrays", t_core, core),
                                  ("naive (floats)", t_floats, floats), ("naive (numpy)", t_numpy, numpy_loop)):
        diff = np.max(np.abs(values - batched))
        print(f"{name:<16} {seconds:9.3f} {args.pairs / seconds:10.0f} {seconds / t_batched:7.1f}x {diff:11.2e}")
    print(f"(batched: median of {args.repeats} calls on the Rig lists; the naive numpy loop takes "
          f"{t_numpy / t_batched:.1f}x its time; load average {load_before:.2f} before, "
          f"{os.getloadavg()[0]:.2f} after)")


if __name__ == "__main__":
    main()
