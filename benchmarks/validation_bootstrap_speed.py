"""The validation bootstrap: mAP of a resampled test split by weights on detections matched once
(``MatchedDetections.evaluation``) against the plain way, writing the resample out as copies of its samples
and matching them again (``evaluate``). Both give the same mAP; the figure is the time per resample.

Usage: python benchmarks/validation_bootstrap_speed.py [--samples 160] [--objects 30] [--detections 100]
                                                      [--resamples 20]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rigopt.bench.evaluation import Detections, GroundTruth, evaluate, match
from rigopt.bench.scene_model import CLASSES


def split_like(samples: int, objects: int, detections: int, seed: int = 0):
    """Ground truth (``objects`` per sample, random classes and places) and per sample a noisy hit on 60 % of
    its objects plus ``detections - objects`` random detections; scores distinct."""
    rng = np.random.default_rng(seed)
    ids = np.repeat([f"s{i:04d}" for i in range(samples)], objects)
    gt_cls = rng.integers(len(CLASSES), size=len(ids))
    gt_xy = rng.uniform(-35, 35, (len(ids), 2))
    hits = rng.random(len(ids)) < 0.6
    misses = detections - objects
    det_ids = np.concatenate([ids[hits], np.repeat([f"s{i:04d}" for i in range(samples)], misses)])
    det_cls = np.concatenate([gt_cls[hits], rng.integers(len(CLASSES), size=samples * misses)])
    det_xy = np.concatenate([gt_xy[hits] + rng.normal(0, 1.0, (hits.sum(), 2)),
                             rng.uniform(-35, 35, (samples * misses, 2))])
    scores = rng.permutation(len(det_ids)) / len(det_ids)
    return Detections(det_ids, det_cls, det_xy, scores), GroundTruth(ids, gt_cls, gt_xy)


def written_out(detections: Detections, truth: GroundTruth, weights: dict) -> tuple[Detections, GroundTruth]:
    """The multiset as explicit copies: copy k of sample s is sample 's#k'."""
    def copies(sample, *columns):
        counts = np.array([weights[s] for s in sample])
        names = np.array([f"{s}#{k}" for s, n in zip(sample, counts) for k in range(n)])
        return (names, *(np.repeat(c, counts, axis=0) for c in columns))
    return Detections(*copies(detections.sample, detections.cls, detections.xy, detections.score)), \
        GroundTruth(*copies(truth.sample, truth.cls, truth.xy))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=160)
    parser.add_argument("--objects", type=int, default=30)
    parser.add_argument("--detections", type=int, default=100)
    parser.add_argument("--resamples", type=int, default=20)
    args = parser.parse_args()
    detections, truth = split_like(args.samples, args.objects, args.detections)
    samples = [f"s{i:04d}" for i in range(args.samples)]
    rng = np.random.default_rng(1)
    draws = [np.bincount(rng.integers(args.samples, size=args.samples), minlength=args.samples)
             for _ in range(args.resamples)]

    start = time.perf_counter()
    matched = match(detections, truth, samples=samples)
    match_once = time.perf_counter() - start
    start = time.perf_counter()
    by_weights = [matched.evaluation(w).map for w in draws]
    weighted = (time.perf_counter() - start) / args.resamples
    start = time.perf_counter()
    by_copies = [evaluate(*written_out(detections, truth, dict(zip(samples, w)))).map for w in draws]
    plain = (time.perf_counter() - start) / args.resamples

    difference = max(abs(a - b) for a, b in zip(by_weights, by_copies))
    print(f"{args.samples} samples, {len(truth)} objects, {len(detections)} detections, {args.resamples} resamples")
    print(f"match once:                      {match_once * 1e3:8.1f} ms")
    print(f"mAP of a resample, weights:      {weighted * 1e3:8.1f} ms")
    print(f"mAP of a resample, copies:       {plain * 1e3:8.1f} ms  ({plain / weighted:.0f}x the weights)")
    print(f"largest mAP difference:          {difference:.1e}")
    print(f"1000 resamples x 4 rigs:         {4 * (match_once + 1000 * weighted):8.1f} s by weights, "
          f"{4 * 1000 * plain:8.1f} s by copies")


if __name__ == "__main__":
    main()
