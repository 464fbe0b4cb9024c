"""Designer speed and quality: `rigopt design --vehicle firetruck --ref R1` with default settings.

Prints the time of each stage, the candidate set sizes, the MILP status and gap, the refinement outcome,
and the design's predicted drop and coverage beside the naive transfer and the benchmark's own rig for the
vehicle. As a simple reference in the same run it solves the coverage-free assignment (each reference
camera's candidate by scipy's Hungarian method on the full candidate set): a lower bound on the
calibrated RigCD that any rig meeting the coverage requirements can reach on this grid.

Then the command as a whole: the outputs (rig file, report JSON, pictures, HTML report) written from the
same result, timed in the same process; and the installed ``rigopt design`` console script run in a subprocess
into a fresh folder, timed from start to exit (imports, loading, design stages, outputs), this checkout's code
against a baseline checkout's (``--baseline``, e.g. main's worktree: the same console script with PYTHONPATH
set to each), alternating, ``--rounds`` times each, in one run: the ratio of the medians is the figure to
compare on a shared machine (the load average is printed with each run). Each run's CPU seconds (its process
and its worker's) are printed too, and each pair of runs' rig.json is compared byte for byte and its
report.json without the timing fields.

Usage: python benchmarks/design_speed.py [--vehicle firetruck] [--ref R1] [--weights joint] [--no-command]
       [--command-only] [--baseline /path/to/main] [--rounds 2]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
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
    parser.add_argument("--command-only", action="store_true", help="only the whole command in a subprocess")
    parser.add_argument("--baseline", help="another checkout (e.g. main's) whose command to time alternately")
    parser.add_argument("--rounds", type=int, default=2, help="runs of each command")
    args = parser.parse_args()
    if args.command_only:
        command_figures(args)
        return
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


def strip_timing(value):
    """A report.json value without its timing fields (any key naming seconds)."""
    if isinstance(value, dict):
        return {k: strip_timing(v) for k, v in value.items() if "seconds" not in k}
    if isinstance(value, list):
        return [strip_timing(v) for v in value]
    return value


def differences(a, b, path: str = "") -> list[str]:
    """Where two JSON values differ (paths like /cameras[2]/id)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return [d for k in sorted(set(a) | set(b)) for d in differences(a.get(k), b.get(k), f"{path}/{k}")]
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        return [d for k, (x, y) in enumerate(zip(a, b)) for d in differences(x, y, f"{path}[{k}]")]
    return [] if a == b else [path or "/"]


def run_command(code: Path, args, out: Path) -> tuple[float, float, dict]:
    """`rigopt design` of ``code`` (a checkout, put first on PYTHONPATH) into ``out``: (wall s, CPU s of it and
    its children, report.json)."""
    script = shutil.which("rigopt") or str(Path(sys.executable).with_name("rigopt"))
    env = {**os.environ, "PYTHONPATH": str(code)}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run([script, "design", "--vehicle", args.vehicle, "--ref", args.ref, "--weights", args.weights,
                    "--out", str(out)], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, json.loads((out / "report.json").read_text())


def command_figures(args) -> None:
    """Time the console script end to end, this checkout against ``args.baseline`` (alternating), and check
    that both write the same rig and report."""
    here = Path(__file__).resolve().parents[1]
    codes = [("this checkout", here)] + ([("baseline", Path(args.baseline).resolve())] if args.baseline else [])
    walls = {name: [] for name, _ in codes}
    print(f"\n`rigopt design --vehicle {args.vehicle} --ref {args.ref}` as a subprocess (console script, PYTHONPATH "
          f"= each checkout), {args.rounds} round(s):")
    with tempfile.TemporaryDirectory() as scratch:
        for round_ in range(args.rounds):
            outs = {}
            for name, code in (codes if round_ % 2 == 0 else codes[::-1]):
                out = Path(scratch) / f"{round_}-{name.replace(' ', '_')}"
                load = os.getloadavg()[0]
                wall, cpu, report = run_command(code, args, out)
                walls[name].append(wall)
                outs[name] = (out, report)
                print(f"  round {round_ + 1}, {name:<13}: whole command {wall:6.1f} s, CPU {cpu:6.1f} s, design stages "
                      f"{report['solver']['seconds']:5.1f} s (load average {load:.1f} at the start)")
            if args.baseline:
                (a, ra), (b, rb) = outs["this checkout"], outs["baseline"]
                same_rig = (a / "rig.json").read_bytes() == (b / "rig.json").read_bytes()
                differ = differences(strip_timing(ra), strip_timing(rb))
                print(f"    rig.json {'identical' if same_rig else 'DIFFERENT'}; report.json "
                      f"{'identical but for timing' if not differ else 'DIFFERENT at ' + ', '.join(differ[:5])}")
    medians = {name: float(np.median(w)) for name, w in walls.items()}
    line = f"median whole command: this checkout {medians['this checkout']:.1f} s"
    if args.baseline:
        line += (f", baseline {medians['baseline']:.1f} s: {medians['this checkout'] / medians['baseline']:.2f}x "
                 f"the baseline's time ({medians['baseline'] / medians['this checkout']:.2f}x faster)")
    print(line)

if __name__ == "__main__":
    main()
