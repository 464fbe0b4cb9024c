"""Start-up speed of the CLI: wall time of ``rigopt --help``, ``rigopt design --help`` and ``rigopt rigs`` (the
installed console script, median of several runs), beside a bare ``python -c pass``, and which modules
``import rigopt.cli`` loads.

Usage: python benchmarks/help_speed.py [--runs 7]
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

HEAVY = ("numpy", "scipy", "cvxpy", "casadi", "trimesh", "matplotlib", "torch")


def median_seconds(command: list[str], runs: int) -> float:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=7)
    args = parser.parse_args()
    script = Path(sys.executable).parent / "rigopt"
    rigopt = str(script) if script.is_file() else shutil.which("rigopt")
    rows = [("python -c pass", [sys.executable, "-c", "pass"]), ("rigopt --help", [rigopt, "--help"]),
            ("rigopt design --help", [rigopt, "design", "--help"]), ("rigopt rigs", [rigopt, "rigs"])]
    for label, command in rows:
        print(f"{label:24s} {median_seconds(command, args.runs):.3f} s (median of {args.runs})")
    probe = f"import sys, rigopt.cli; print(sorted(m for m in {HEAVY!r} if m in sys.modules))"
    loaded = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout.strip()
    print(f"heavy libraries loaded by import rigopt.cli: {loaded}")


if __name__ == "__main__":
    main()
