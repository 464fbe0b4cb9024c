"""Rig-level uncertainty of the 9-rig validation's Spearman rhos (docs/detectors_study.md), from the committed
outputs in ``measurements/validation/``: the scene bootstrap there keeps the 9 rigs fixed (test noise only); this
resamples the rigs.

    python studies/detectors/rig_level.py

For each schedule (4, 8, 16 epochs) and seed: the measured drops of the 9 rigs (two firetruck designs, R6, the
naive and height-matched copies on each vehicle, the hgv design, R9) against the joint calibration's predicted
drops; Spearman rho pooled and within each vehicle, its 95 % rig-bootstrap interval (rigs drawn with
replacement, 2000 resamples, seed 0; within-vehicle draws stay in their vehicle) and the exact one-sided
permutation p of the pooled rho (all 9! orderings). Prints a markdown table.
"""

from __future__ import annotations

import itertools
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "studies" / "validation"))
from analysis import bootstrap_draws, interval, resampled_rhos, spearman  # noqa: E402

DESIGNS = ("firetruck_from_R1", "firetruck_from_R1_no_fields", "hgv_from_R1")
VEHICLE = {"firetruck_from_R1": "firetruck", "firetruck_from_R1_no_fields": "firetruck", "R6": "firetruck",
           "naive_firetruck_from_R1": "firetruck", "height_matched_firetruck_from_R1": "firetruck",
           "hgv_from_R1": "hgv", "R9": "hgv", "naive_hgv_from_R1": "hgv", "height_matched_hgv_from_R1": "hgv"}


def drops(folder: Path, seed: int) -> tuple[list[str], np.ndarray, np.ndarray]:
    """(rigs, measured (9,), predicted (9,)) of one schedule's folder and seed; rigs shared by two validations
    (R6) are taken once."""
    suffix = "" if seed == 0 else f"_seed{seed}"
    measured, predicted = {}, {}
    for design in DESIGNS:
        result = json.loads((folder / f"lss_{design}{suffix}.json").read_text())
        for entry in result["rigs"]:
            measured.setdefault(entry["rig"], entry["measured_drop"])
            predicted.setdefault(entry["rig"], entry["predicted_drop"])
    rigs = sorted(measured, key=list(VEHICLE).index)
    return rigs, np.array([measured[r] for r in rigs]), np.array([predicted[r] for r in rigs])


def exact_p(predicted: np.ndarray, measured: np.ndarray) -> float:
    """One-sided exact permutation p of Spearman rho > 0 over every ordering of the measured drops."""
    observed = spearman(predicted, measured)
    permuted = np.array(list(itertools.permutations(measured)))
    return float(np.mean(spearman(np.broadcast_to(predicted, permuted.shape), permuted) >= observed - 1e-12))


def main() -> int:
    print("| epochs | seed | rho, 9 rigs [rig bootstrap 95 %] | exact permutation p | firetruck rho [95 %] | "
          "hgv rho [95 %] |")
    print("|---|---|---|---|---|---|")
    for epochs, folder in ((4, ROOT / "measurements/validation"), (8, ROOT / "measurements/validation/epochs8"),
                           (16, ROOT / "measurements/validation/epochs16")):
        for seed in (0, 1, 2):
            suffix = "" if seed == 0 else f"_seed{seed}"
            if not (folder / f"lss_{DESIGNS[0]}{suffix}.json").is_file():
                continue
            rigs, measured, predicted = drops(folder, seed)
            vehicles = np.array([VEHICLE[r] for r in rigs])
            within = resampled_rhos(predicted, measured, vehicles, bootstrap_draws(vehicles))
            pooled = resampled_rhos(predicted, measured, np.array(["all"] * len(rigs)),
                                    bootstrap_draws(np.array(["all"] * len(rigs))))["pooled"]
            cells = []
            for g in ("firetruck", "hgv"):
                mask = vehicles == g
                low, high = interval(within[g])
                cells.append(f"{spearman(predicted[mask], measured[mask]):.2f} [{low:.2f}, {high:.2f}]")
            low, high = interval(pooled)
            print(f"| {epochs} | {seed} | {spearman(predicted, measured):.3f} [{low:.2f}, {high:.2f}] | "
                  f"{exact_p(predicted, measured):.3f} | {cells[0]} | {cells[1]} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
