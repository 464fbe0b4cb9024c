"""The candidate distances of the validation study, fitted once on the fitting data and frozen.

Run ``python studies/validation/candidates.py`` to write ``studies/validation/candidates.json``: each
candidate's terms and non-negative weights (the linear prediction is ``weights . terms``), how it was fitted,
and a leave-one-rig-out figure on the fitting data. The pre-registration (``preregistration.md``) fixes this
list and this fitting; the file is committed before any test rig is measured.

**Fitting data** (never a test rig): the pairs of the synthetic LSS-style transfer matrix
(``measurements/transfer/lss``, 20 rigs) among the 13 rigs that are not test rigs (R1, R1-c10, R1-c6, R1-f, R1-r,
R1-t, R2, R3, R7, nuscenes, argoverse2, waymo, ddad: 169 pairs, diagonal included), and the real benchmark's
control pairs (``../shared/pccr/results``: the six control rigs, 36 pairs for each of the four detectors, 144).
Every pair weighs the same. Terms come from :func:`rigopt.metrics.lifting.lifting_terms` (RigCD's unit-weight
matching; rigs in their vehicle's centre frame), rounded to 10 decimals as the calibration does.

**Fit**: ``scipy.optimize.nnls`` of the relative drops on the candidate's terms, no intercept (RigCD's own
model has none). The published RigCD is also scored with its shipped weights (joint; sim-lss), unfitted.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
from scipy.optimize import nnls
from scipy.stats import spearmanr

from rigopt.metrics.calibration import FEATURE_DECIMALS, load_weights
from rigopt.metrics.lifting import TERMS, lifting_terms
from rigopt.metrics.protocol import CONTROL_RIGS
from rigopt.metrics.transfer import read_transfer
from rigopt.vehicle.placement import benchmark_rig_lookup

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
SYNTHETIC = ROOT / "measurements" / "transfer"
SYNTHETIC_RIGS = ROOT / "measurements" / "rigs"
BENCHMARK = ROOT.parent / "shared" / "pccr" / "results"
OUT = HERE / "candidates.json"

#: Candidate name -> the terms it weighs (fitted), in TERMS' names.
FITTED = {
    "rigcd_refit": ("t", "r", "f", "count"),
    "split": ("t_plan", "t_vert", "r_yaw", "r_tilt", "f", "count"),
    "depth_prior": ("dpm", "count"),
    "rigcd_depth": ("t", "r", "f", "count", "dpm"),
    "split_depth": ("t_plan", "t_vert", "r_yaw", "r_tilt", "f", "count", "dpm"),
}
#: The published RigCD with shipped weights, not refitted: candidate name -> weights name.
PUBLISHED = {"rigcd_joint": "joint", "rigcd_sim_lss": "sim-lss"}
#: The candidates the decision rule may ship (the others are yardsticks).
NEW = ("split", "depth_prior", "rigcd_depth", "split_depth")


def test_rig_names() -> set[str]:
    import csv

    with open(HERE / "rigs" / "index.csv", newline="") as handle:
        return {row["rig"] for row in csv.DictReader(handle)}


def fitting_pairs() -> tuple[np.ndarray, np.ndarray, list[str], list[str]]:
    """(terms (P, len(TERMS)), drops (P,), source per pair, training-test label per pair) of the fitting data."""
    excluded = test_rig_names()
    lookup_synthetic = benchmark_rig_lookup(SYNTHETIC_RIGS)
    lookup_benchmark = benchmark_rig_lookup()
    rows_a, rows_b, drops, sources, labels = [], [], [], [], []
    synthetic = read_transfer(SYNTHETIC).drops()
    for model, a, b, d in zip(synthetic.model, synthetic.train, synthetic.test, synthetic.delta):
        if a in excluded or b in excluded:
            continue
        rows_a.append(lookup_synthetic(a))
        rows_b.append(lookup_synthetic(b))
        drops.append(d)
        sources.append(f"synthetic:{model}")
        labels.append(f"{a}>{b}")
    benchmark = read_transfer(BENCHMARK).drops()
    for model, a, b, d in zip(benchmark.model, benchmark.train, benchmark.test, benchmark.delta):
        if a in CONTROL_RIGS and b in CONTROL_RIGS:
            rows_a.append(lookup_benchmark(a))
            rows_b.append(lookup_benchmark(b))
            drops.append(d)
            sources.append(f"benchmark:{model}")
            labels.append(f"{a}>{b}")
    terms = np.round(lifting_terms(rows_a, rows_b), FEATURE_DECIMALS) + 0.0
    return terms, np.array(drops), sources, labels


def columns(names) -> list[int]:
    return [TERMS.index(name) for name in names]


def fit(terms: np.ndarray, drops: np.ndarray, names) -> np.ndarray:
    """Non-negative weights (len(names),) of the least-squares fit of ``drops`` on the named terms."""
    weights, _ = nnls(terms[:, columns(names)], drops)
    return weights


def published_weights(name: str) -> dict[str, float]:
    """The shipped RigCD calibration as weights on (t, r, f, count): K alpha lambda_x and K (1 - alpha)."""
    c = load_weights(name)
    return {"t": c.K * c.alpha * c.lambda_t, "r": c.K * c.alpha * c.lambda_r, "f": c.K * c.alpha * c.lambda_f,
            "count": c.K * (1 - c.alpha)}


def leave_rigs_out(terms, drops, labels, sources, names) -> float:
    """Spearman rho over the synthetic pairs, each A -> B predicted by the fit without every pair that involves
    A or B (the benchmark's control pairs stay in the fit when they do not): a figure on the fitting data,
    reported beside the test, never deciding it."""
    pairs = [set(label.split(">")) for label in labels]
    synthetic = np.flatnonzero([s.startswith("synthetic") for s in sources])
    predicted = np.empty(len(synthetic))
    for k, p in enumerate(synthetic):
        keep = np.array([not (pair & pairs[p]) for pair in pairs])
        predicted[k] = terms[p, columns(names)] @ fit(terms[keep], drops[keep], names)
    return float(spearmanr(predicted, drops[synthetic])[0])


def main() -> int:
    terms, drops, sources, labels = fitting_pairs()
    out = {"terms": list(TERMS), "fitting_pairs": len(drops),
           "fitting_sources": {s: sources.count(s) for s in dict.fromkeys(sources)},
           "candidates": {}}
    for name, weights_name in PUBLISHED.items():
        weights = published_weights(weights_name)
        out["candidates"][name] = {"weights": weights, "fitted": False, "source": f"metrics/weights {weights_name}"}
    for name, names in FITTED.items():
        weights = fit(terms, drops, names)
        residual = drops - terms[:, columns(names)] @ weights
        out["candidates"][name] = {
            "weights": {n: float(w) for n, w in zip(names, weights)}, "fitted": True, "source": "nnls",
            "rmse_fitting": float(np.sqrt(np.mean(residual ** 2))),
            "rho_fitting": float(spearmanr(terms[:, columns(names)] @ weights, drops)[0]),
            "rho_rigs_left_out_synthetic": leave_rigs_out(terms, drops, labels, sources, names)}
    OUT.write_text(json.dumps(out, indent=2) + "\n")
    for name, entry in out["candidates"].items():
        weights = ", ".join(f"{k} {v:.4g}" for k, v in entry["weights"].items())
        extra = (f"  rho fit {entry['rho_fitting']:.3f}, rigs left out {entry['rho_rigs_left_out_synthetic']:.3f}"
                 if entry["fitted"] else "")
        print(f"{name:14s} {weights}{extra}")
    print(f"wrote {OUT.relative_to(ROOT)} ({len(drops)} fitting pairs)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
