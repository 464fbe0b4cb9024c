"""Oracles of the scene bootstrap and the greedy matching of ``rigopt.validation.synthetic.evaluation``: the plain loops the
fast versions replaced, shared by tests/validation/synthetic/test_evaluation_bootstrap.py and
benchmarks/validation_bootstrap_speed.py."""

from __future__ import annotations

import numpy as np


def plain_resampled_maps(matched, groups, resamples, seed, visible_only=False) -> np.ndarray:
    """(resamples, K) mAP, one ``evaluation`` call per resample and run; the same draws as resampled_maps."""
    members = [np.asarray(g, dtype=int) for g in groups]
    rng = np.random.default_rng(seed)
    maps = np.empty((resamples, len(matched)))
    for r in range(resamples):
        drawn = np.concatenate([members[i] for i in rng.integers(len(members), size=len(members))])
        weights = np.bincount(drawn, minlength=len(matched[0].samples))
        maps[r] = [m.evaluation(weights, visible_only).map for m in matched]
    return maps


def plain_match(det_sample, det_xy, gt_sample, gt_xy, threshold) -> np.ndarray:
    """(m,) object taken by each ranked detection at one threshold, -1 for none: one detection at a time."""
    gt_order = np.lexsort((gt_xy[:, 1], gt_xy[:, 0], gt_sample))
    gt_sample, gt_xy = gt_sample[gt_order], gt_xy[gt_order]
    free = np.ones(len(gt_sample), dtype=bool)
    taken = np.full(len(det_sample), -1, dtype=int)
    for rank in range(len(det_sample)):
        candidates = np.flatnonzero(free & (gt_sample == det_sample[rank]))
        if len(candidates) == 0:
            continue
        distance = np.hypot(*(gt_xy[candidates] - det_xy[rank]).T)
        nearest = int(np.argmin(distance))
        if distance[nearest] < threshold:
            taken[rank] = gt_order[candidates[nearest]]
            free[candidates[nearest]] = False
    return taken
