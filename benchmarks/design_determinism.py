"""The same design at any machine load: `rigopt design --vehicle V --ref R1` run twice by the installed
console script, once as the machine is and once beside busy processes that keep every core loaded; the two
rig.json files must be byte-identical (no clock decides the rig: the MILPs stop on work limits only).

Prints each run's whole-command time, its design stages' time (``solver.seconds`` of its report.json), the
MILP statuses and whether the rig files are identical; exits 1 when they differ.

Usage: python benchmarks/design_determinism.py [--vehicle firetruck] [--ref R1] [--load N]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def spin(stop) -> None:
    """Keep one core busy until ``stop`` is set."""
    while not stop.is_set():
        sum(k * k for k in range(10_000))


def design(vehicle: str, ref: str, out: Path) -> tuple[float, dict]:
    """Run the console script into ``out``; (whole-command seconds, its report.json)."""
    started = time.perf_counter()
    process = subprocess.run([str(Path(sys.executable).parent / "rigopt"), "design", "--vehicle", vehicle,
                              "--ref", ref, "--out", str(out), "--json"], capture_output=True, text=True)
    seconds = time.perf_counter() - started
    if process.returncode:
        raise SystemExit(process.stderr)
    return seconds, json.loads((out / "report.json").read_text())


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicle", default="firetruck")
    parser.add_argument("--ref", default="R1")
    parser.add_argument("--load", type=int, default=os.cpu_count() or 1, help="busy processes in the second run")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as scratch:
        first, second = Path(scratch) / "as_is", Path(scratch) / "loaded"
        seconds_first, report_first = design(args.vehicle, args.ref, first)
        stop = multiprocessing.Event()
        busy = [multiprocessing.Process(target=spin, args=(stop,)) for _ in range(args.load)]
        for process in busy:
            process.start()
        try:
            seconds_second, report_second = design(args.vehicle, args.ref, second)
        finally:
            stop.set()
            for process in busy:
                process.join()
        identical = (first / "rig.json").read_bytes() == (second / "rig.json").read_bytes()
    for label, seconds, report in (("as the machine is", seconds_first, report_first),
                                   (f"beside {args.load} busy processes", seconds_second, report_second)):
        solver = report["solver"]
        near_field = solver.get("near_field") or {}
        print(f"{label}: whole command {seconds:.1f} s, design stages {solver['seconds']:.1f} s, MILP "
              f"{solver['milp_status']} (gap {solver['milp_gap']:.1e}), near-field MILP "
              f"{near_field.get('status', '-')}, {report['n_cameras']} cameras")
    print(f"rig.json byte-identical: {'yes' if identical else 'NO'}; loaded / as-is time "
          f"{seconds_second / seconds_first:.2f}")
    return 0 if identical else 1


if __name__ == "__main__":
    sys.exit(main())
