"""A yardstick for sim-to-real: RigCD's joint weights fitted on random synthetic drops, judged on the real
benchmark's held-out pairs exactly as the weights fitted on a measured synthetic matrix are.

RigCD's structure (Hungarian matching, the camera-count term, a linear link) orders the real drops to some
degree whatever its weights; a sim-calibrated figure means something only where it beats weights fitted on
noise. Per rig set (v1's 9 matrix rigs, the v2 matrix's 20) and seed: every rig's own mAP 0.2, every other
pair's relative drop drawn uniformly in [0, 1], the joint calibration fitted on the control pairs (the
benchmark's protocol), its held-out Spearman rho and bounded-drop MAE per real detector. Usage:

    python studies/baselines/null_calibration.py [--seeds 20]

Writes results/null_calibration.csv (one row per rig set, seed, detector) and prints the summary
(``run.null_summary``: median and 5th-95th percentiles per rig set and detector; also in results.md).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from rigopt.report.tables import markdown, write_csv

sys.path.insert(0, str(Path(__file__).resolve().parent))
from run import MATRIX, REAL_RESULTS, RESULTS, RIGS, null_summary, rig_name  # noqa: E402

RIG_SETS = {"v1 (9 rigs)": ["R1", "R1-r", "R1-t", "R1-f", "R1-c6", "R1-c10", "R2", "R5", "R9"],
            "v2 matrix (20 rigs)": [rig_name(rig) for rig in MATRIX]}
OWN_MAP = 0.2


def random_transfer(rigs: list[str], rng: np.random.Generator):
    """A TransferTable of one model over ``rigs``: own mAP OWN_MAP, other drops uniform in [0, 1]."""
    from rigopt.metrics.transfer import TransferTable

    train, test = (np.array(v) for v in zip(*[(a, b) for a in rigs for b in rigs]))
    drop = np.where(train == test, 0.0, rng.uniform(0.0, 1.0, len(train)))
    return TransferTable(np.full(len(train), "random"), train, test, OWN_MAP * (1.0 - drop))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    args = parser.parse_args()
    from rigopt.metrics.protocol import CONTROL_RIGS, calibrate, calibration_on
    from rigopt.metrics.transfer import read_transfer
    from rigopt.vehicle.placement import benchmark_rig_lookup

    lookup = benchmark_rig_lookup(RIGS)
    real = read_transfer(REAL_RESULTS)
    rows = []
    for name, rigs in RIG_SETS.items():
        for seed in range(args.seeds):
            table = random_transfer(rigs, np.random.default_rng(seed))
            fit = calibrate(table, CONTROL_RIGS, lookup, 0, 0).joint.fit.calibration
            for model in calibration_on(fit, real, CONTROL_RIGS, lookup, 0, 0).models:
                rows.append([name, seed, model.model, model.heldout.rho, model.bounded_heldout.mae])
            print(f"{name} seed {seed}: " + ", ".join(f"{r[2]} {r[3]:.3f}" for r in rows[-4:]), flush=True)
    write_csv(RESULTS / "null_calibration.csv", ["rig set", "seed", "detector", "rho held-out", "MAE bounded"], rows)
    print(markdown(null_summary()))


if __name__ == "__main__":
    main()
