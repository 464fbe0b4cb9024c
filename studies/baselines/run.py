"""The cross-rig study of rigopt's torch baselines on its synthetic benchmark.

Steps (each resumable; rerun the script to continue):
  1. data:        render the train split (12 scenes) of the matrix rigs and the test split (4 scenes) of
                  those and of the validation rigs, 160 x 90, under --data;
  2. matrix:      per family, train on every matrix rig and test on every one (rigopt bench matrix);
  3. calibration: RigCD calibrated on the measured synthetic transfer (rigopt calibrate), held-out rho;
  4. agreement:   Spearman rho of synthetic against real relative drops on the same pairs;
  5. validation:  the firetruck and hgv designs from R1 (rigopt validate).
Writes results/ (matrices, loss logs, calibration, figures, tables, results.md); checkpoints stay under
--data. Usage: python studies/baselines/run.py --data DIR [--families lss petr] [--epochs 8]
              [--steps data matrix calibration agreement validation] [--device cpu]
"""

from __future__ import annotations

import argparse
import csv
import json
import shutil
import subprocess
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
CONTROL = ["R1", "R1-r", "R1-t", "R1-f", "R1-c6", "R1-c10"]
DIVERSE = ["R2", "R5", "R9"]
DESIGNS = [HERE / "rigs" / "firetruck_from_R1.json", HERE / "rigs" / "hgv_from_R1.json"]
#: Each synthetic family against its real counterparts in the benchmark.
COUNTERPARTS = {"lss": ["BEVDet", "BEVFusion"], "petr": ["PETR"]}
STEPS = ("data", "matrix", "calibration", "agreement", "validation")


def rigopt(*args: str) -> None:
    command = ["rigopt", *map(str, args)]
    print("$", " ".join(command), flush=True)
    subprocess.run(command, check=True)


def data_step(data: Path) -> None:
    rigopt("bench", "generate", "--rigs", *CONTROL, *DIVERSE, "--split", "train", "--scenes", 12, "--out", data)
    rigopt("bench", "generate", "--rigs", *CONTROL, *DIVERSE, "R6", *DESIGNS, "--split", "test", "--scenes", 4,
           "--out", data)


def matrix_step(data: Path, family: str, epochs: int, device: str) -> None:
    rigopt("bench", "matrix", "--data", data, "--rigs", *CONTROL, *DIVERSE, "--model", family, "--epochs", epochs,
           "--device", device, "--out", RESULTS / "transfer")
    logs = RESULTS / "logs" / family
    logs.mkdir(parents=True, exist_ok=True)
    for rig in CONTROL + DIVERSE:
        shutil.copy(data / "runs" / family / rig / "train_log.csv", logs / f"{rig}.csv")


def calibration_step() -> None:
    rigopt("calibrate", "--results", RESULTS / "transfer", "--out", RESULTS / "calibration")


def agreement_step() -> list[list]:
    from rigopt.metrics.agreement import drop_agreement
    from rigopt.metrics.transfer import read_transfer
    from rigopt.resources import data_dir

    synthetic = read_transfer(RESULTS / "transfer").drops()
    real = read_transfer(data_dir("metrics") / "pccr_transfer.csv").drops()
    rows = []
    for family, detectors in COUNTERPARTS.items():
        if family not in set(synthetic.model):
            continue
        for detector in detectors:
            agreement = drop_agreement(synthetic, family, real, detector)
            rows.append([family, detector, agreement.n, agreement.rho, agreement.ci[0], agreement.ci[1], agreement.p,
                         agreement.mae])
    with (RESULTS / "agreement.csv").open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["family", "real_detector", "pairs", "rho", "ci_low", "ci_high", "p", "mae"])
        writer.writerows([[f"{v:.6g}" if isinstance(v, float) else v for v in row] for row in rows])
    return rows


def validation_step(data: Path, family: str, device: str) -> None:
    for design in DESIGNS:
        rigopt("validate", design, "--ref", "R1", "--model", family, "--data", data, "--device", device,
               "--out", RESULTS / "validation" / f"{family}_{design.stem}.json")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--families", nargs="+", default=["lss", "petr"])
    parser.add_argument("--epochs", type=int, default=8)
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--steps", nargs="+", default=list(STEPS), choices=STEPS)
    args = parser.parse_args()
    RESULTS.mkdir(parents=True, exist_ok=True)
    if "data" in args.steps:
        data_step(args.data)
    for family in args.families:
        if "matrix" in args.steps:
            matrix_step(args.data, family, args.epochs, args.device)
        if "validation" in args.steps:
            validation_step(args.data, family, args.device)
    if "calibration" in args.steps:
        calibration_step()
    if "agreement" in args.steps:
        for row in agreement_step():
            print(json.dumps(dict(zip(["family", "real", "pairs", "rho", "low", "high", "p", "mae"], row))))


if __name__ == "__main__":
    main()
