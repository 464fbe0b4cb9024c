"""A yardstick for sim-to-real: RigCD's joint weights fitted on random synthetic drops, judged on the real
benchmark's held-out pairs exactly as the weights fitted on a measured synthetic matrix are.

RigCD's structure (Hungarian matching, the camera-count term, a linear link) orders the real drops to some
degree whatever its weights; a sim-calibrated figure means something only where it beats weights fitted on
noise. Per rig set (v1's 9 matrix rigs, the v2 matrix's 20) and seed: every rig's own mAP 0.2, every other
pair's relative drop drawn uniformly in [0, 1], the joint calibration fitted on the control pairs (the
benchmark's protocol), its held-out Spearman rho per real detector (``protocol.null_yardstick``, which
``rigopt calibrate --test-on REAL --null N`` runs on a measured table's own pairs). Usage:

    python studies/detectors/null_calibration.py [--seeds 20]

Writes results/null_calibration.csv (one row per rig set, seed, detector) and prints the summary
(``run.null_summary``: median and 5th-95th percentiles per rig set and detector; also in results.md).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from run import MATRIX, REAL_RESULTS, RESULTS, RIGS, null_summary, rig_name  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies/: the studies' shared code (studylib)
from studylib.tables import markdown, write_csv  # noqa: E402

RIG_SETS = {"v1 (9 rigs)": ["R1", "R1-r", "R1-t", "R1-f", "R1-c6", "R1-c10", "R2", "R5", "R9"],
            "v2 matrix (20 rigs)": [rig_name(rig) for rig in MATRIX]}
OWN_MAP = 0.2


def structure(rigs: list[str]):
    """A TransferTable of one model over every pair of ``rigs``, own mAP OWN_MAP (its off-diagonal values are
    replaced by chance drops, ``protocol.null_transfer``)."""
    from rigopt.metrics.transfer import TransferTable

    train, test = (np.array(v) for v in zip(*[(a, b) for a in rigs for b in rigs]))
    return TransferTable(np.full(len(train), "random"), train, test, np.full(len(train), OWN_MAP))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    args = parser.parse_args()
    from rigopt.metrics.protocol import null_yardstick
    from rigopt.metrics.transfer import read_transfer
    from rigopt.vehicle.placement import benchmark_rig_lookup

    lookup = benchmark_rig_lookup(RIGS)
    real = read_transfer(REAL_RESULTS)
    rows = []
    for name, rigs in RIG_SETS.items():
        yardstick = null_yardstick(structure(rigs), real, args.seeds, rig_lookup=lookup)
        rows += [[name, seed, model, float(rhos[seed])] for model, rhos in yardstick.heldout_rho.items()
                 for seed in range(args.seeds)]
    write_csv(RESULTS / "null_calibration.csv", ["rig set", "seed", "detector", "rho held-out"], rows)
    print(markdown(null_summary()))


if __name__ == "__main__":
    main()
