"""Designer speed and quality: `rigopt design --vehicle firetruck --ref R1` with default settings.

Prints the time of each stage, the candidate set sizes, the MILP status and gap, the refinement outcome,
and the design's predicted drop and coverage beside the naive transfer and the benchmark's own rig for the
vehicle. As a simple reference in the same run it solves the coverage-free assignment (each reference
camera's candidate by scipy's Hungarian method on the full candidate set): a lower bound on the
calibrated RigCD that any rig meeting the coverage requirements can reach on this grid.

Then the command as a whole: the outputs (rig file, report JSON, pictures, HTML report) written from the
same result, timed in the same process, and the installed ``rigopt design`` console script run in a
subprocess into a fresh folder, timed from start to exit (imports, loading, design stages, outputs); its
design stages' time is the ``solver.seconds`` of the report.json it writes. The ratio of the whole command
to its design stages is the figure to watch (aim: at most 2).

Usage: python benchmarks/design_speed.py [--vehicle firetruck] [--ref R1] [--weights joint] [--no-command]
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.optimize import linear_sum_assignment

from rigopt.design.candidates import build_candidates
from rigopt.design.designer import default_spacing, design_rig
from rigopt.design.problem import ReferenceRig, benchmark_rigs
from rigopt.design.settings import DesignSettings
from rigopt.metrics.calibration import load_weights
from rigopt.metrics.rigcd import camera_costs
from rigopt.report.design_report import write_design_outputs
from rigopt.rig.library import load_rig
from rigopt.vehicle.library import load_vehicle


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicle", default="firetruck")
    parser.add_argument("--ref", default="R1")
    parser.add_argument("--weights", default="joint")
    parser.add_argument("--no-command", action="store_true", help="skip the whole command in a subprocess")
    args = parser.parse_args()
    vehicle, reference, calibration = load_vehicle(args.vehicle), load_rig(args.ref), load_weights(args.weights)
    settings = DesignSettings()
    stamps = []
    start = time.perf_counter()
    result = design_rig(vehicle, ReferenceRig.on_own_vehicle(reference), calibration, settings,
                        compare_with=benchmark_rigs(vehicle),
                        progress=lambda message: stamps.append((time.perf_counter() - start, message)))
    total = time.perf_counter() - start
    print(f"design of {args.ref} -> {vehicle.name} ({args.weights} weights): {total:.1f} s in all")
    for (t0, message), (t1, _) in zip(stamps, stamps[1:] + [(total, "")]):
        print(f"  {t1 - t0:6.2f} s  {message}")
    milp = result.milp
    print(f"candidates {milp.n_candidates}, offered to the MILP {milp.n_offered}; MILP {milp.status}, gap "
          f"{milp.gap:.2e}, {milp.selection.seconds:.2f} s; repairs {milp.repairs}; "
          f"refinement {result.refinement.status}")

    spacing = settings.spacing or default_spacing(vehicle, settings)
    candidates = build_candidates(vehicle, settings.lenses, spacing, np.arange(-180.0, 180.0, settings.yaw_step_deg),
                                  settings.pitches_deg, settings.zones, settings.rules)
    lt, lr, lf = calibration.lambdas
    t, r, f = camera_costs(candidates.positions, candidates.rotations, candidates.fovs, reference.positions,
                           reference.rotations, reference.fovs)
    cost = lt * t + lr * r + lf * f
    rows, cols = linear_sum_assignment(cost)
    bound = calibration.alpha * cost[rows, cols].mean()
    print(f"coverage-free lower bound on the grid (Hungarian, no coverage, no housing clashes): RigCD {bound:.4f}")

    print(f"\n{'rig':<26} {'predicted drop':>14} {'RigCD':>8} {'coverage':>9} {'meets req.':>10}")
    rows = [("design", result.design)]
    if result.comparisons.naive_transfer:
        rows.append(("naive transfer", result.comparisons.naive_transfer))
    rows += [(f"benchmark {b.rig.name}", b) for b in result.comparisons.rigs]
    for name, summary in rows:
        p = summary.prediction
        print(f"{name:<26} {p.predicted_drop:14.3f} {p.rigcd:8.3f} {summary.coverage:9.3f} "
              f"{'yes' if summary.meets_requirements else 'no':>10}")
    print(f"{'reference ' + reference.name + ' on its vehicle':<26} {'':>14} {'':>8} {result.reference_coverage:9.3f}")

    with tempfile.TemporaryDirectory() as scratch:
        start = time.perf_counter()
        write_design_outputs(result, Path(scratch) / "outputs")
        outputs = time.perf_counter() - start
    print(f"\nin this process: design stages {total:.1f} s, outputs (rig file, report, pictures, HTML) {outputs:.1f} s, "
          f"together {total + outputs:.1f} s = {(total + outputs) / total:.2f}x the stages")
    if not args.no_command:
        command_figures(args)


def command_figures(args) -> None:
    """Time the installed console script end to end; its stages' time comes from the report it writes."""
    script = shutil.which("rigopt") or str(Path(sys.executable).with_name("rigopt"))
    with tempfile.TemporaryDirectory() as scratch:
        out = Path(scratch) / "design"
        start = time.perf_counter()
        subprocess.run([script, "design", "--vehicle", args.vehicle, "--ref", args.ref, "--weights", args.weights,
                        "--out", str(out)], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        whole = time.perf_counter() - start
        stages = json.loads((out / "report.json").read_text())["solver"]["seconds"]
    print(f"`rigopt design --vehicle {args.vehicle} --ref {args.ref}` as a subprocess: design stages {stages:.1f} s, "
          f"everything else (start-up, loading, outputs) {whole - stages:.1f} s, whole command {whole:.1f} s = "
          f"{whole / stages:.2f}x the stages")


if __name__ == "__main__":
    main()
