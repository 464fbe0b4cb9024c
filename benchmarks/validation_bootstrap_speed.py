"""The validation bootstrap: ``resampled_maps`` (chunks of resamples scored at once from the ranked true
positives) against the plain loop it replaced (one ``MatchedDetections.evaluation(weights)`` per resample),
and ``match`` against the plain greedy loop over ranked detections, on a test split shaped like the shipped
detectors' (scene blocks of 40 samples). Both ways give the same mAPs and matchings; the script prints the
times, the ratios and the largest mAP difference.

Usage: python benchmarks/validation_bootstrap_speed.py [--samples 640] [--objects 15] [--detections 50]
                                                      [--resamples 1000] [--scene 40]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from rigopt.validation.synthetic.evaluation import Detections, GroundTruth, _rank, match, resampled_maps
from rigopt.validation.synthetic.scene_model import CLASSES

ORACLES = Path(__file__).resolve().parents[1] / "tests" / "validation" / "synthetic"  # the oracles live with the tests
sys.path.insert(0, str(ORACLES))
from evaluation_oracles import plain_match, plain_resampled_maps  # noqa: E402


def split_like(samples: int, objects: int, detections: int, seed: int = 0) -> tuple[Detections, GroundTruth]:
    """``objects`` per sample (random classes and places, 75 % seen by the rig); 70 % of the seen ones found
    (1 m noise, scores 0.3-1) and the rest of ``detections`` per sample false (random class and place,
    scores 0-0.5): mAP about 0.25, as the shipped detectors score on R1."""
    rng = np.random.default_rng(seed)
    gt_sample = np.repeat(np.arange(samples), objects)
    gt_cls = rng.integers(len(CLASSES), size=len(gt_sample))
    gt_xy = rng.uniform(-35, 35, (len(gt_sample), 2))
    seen = rng.random(len(gt_sample)) < 0.75
    found = seen & (rng.random(len(gt_sample)) < 0.7)
    false = detections * samples - int(found.sum())
    return (Detections(np.concatenate([gt_sample[found], rng.integers(samples, size=false)]),
                       np.concatenate([gt_cls[found], rng.integers(len(CLASSES), size=false)]),
                       np.concatenate([gt_xy[found] + rng.normal(0, 1.0, (int(found.sum()), 2)),
                                       rng.uniform(-35, 35, (false, 2))]),
                       np.concatenate([rng.uniform(0.3, 1.0, int(found.sum())), rng.uniform(0.0, 0.5, false)])),
            GroundTruth(gt_sample, gt_cls, gt_xy, seen))


def plain_matching(detections: Detections, truth: GroundTruth, thresholds) -> list[np.ndarray]:
    """The greedy loop ``_match`` replaced, per class: (T, m) object taken by each ranked detection."""
    taken = []
    for c in range(len(CLASSES)):
        d_rows, g_rows = detections.cls == c, truth.cls == c
        order = _rank(detections.sample[d_rows], detections.xy[d_rows], detections.score[d_rows])
        ranked = detections.sample[d_rows][order], detections.xy[d_rows][order]
        taken.append(np.array([plain_match(*ranked, truth.sample[g_rows], truth.xy[g_rows], d)
                               for d in thresholds]).reshape(len(thresholds), -1))
    return taken


def timed(function, *args):
    start = time.perf_counter()
    result = function(*args)
    return result, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=640)
    parser.add_argument("--objects", type=int, default=15)
    parser.add_argument("--detections", type=int, default=50)
    parser.add_argument("--resamples", type=int, default=1000)
    parser.add_argument("--scene", type=int, default=40, help="samples per resampled block")
    args = parser.parse_args()
    detections, truth = split_like(args.samples, args.objects, args.detections)
    scenes = [np.arange(i, min(i + args.scene, args.samples)) for i in range(0, args.samples, args.scene)]
    print(f"{args.samples} samples in {len(scenes)} scenes, {len(truth)} objects, {len(detections)} detections, "
          f"{args.resamples} resamples; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")

    matched, fast_match = timed(match, detections, truth)
    taken, plain_match = timed(plain_matching, detections, truth, matched.thresholds)
    same = all(np.array_equal(matched.tp[c], t >= 0) for c, t in enumerate(taken))
    print(f"match:                 {fast_match:7.2f} s   plain loop {plain_match:7.2f} s   "
          f"({plain_match / fast_match:.0f}x, same true positives: {same})")
    total_fast = total_plain = 0.0
    for visible in (False, True):
        fast, fast_time = timed(resampled_maps, [matched], scenes, args.resamples, 0, visible)
        plain, plain_time = timed(plain_resampled_maps, [matched], scenes, args.resamples, 0, visible)
        total_fast, total_plain = total_fast + fast_time, total_plain + plain_time
        print(f"resampled_maps {'visible' if visible else 'fixed  '}: {fast_time:7.2f} s   plain loop "
              f"{plain_time:7.2f} s   ({plain_time / fast_time:.1f}x, largest mAP difference "
              f"{np.abs(fast - plain).max():.1e}; mAP {matched.evaluation(visible_only=visible).map:.3f})")
    print(f"validate's share, 3 models: {3 * (fast_match + total_fast):6.1f} s   plain "
          f"{3 * (plain_match + total_plain):6.1f} s; load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
