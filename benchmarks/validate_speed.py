"""``rigopt validate RIG --ref R1 --model lss`` without --data, from an empty cache, under each measurement
protocol: the whole command's time for one rig (the installed console script, start to exit) under ``quick`` (every
4th frame of the test scenes) beside ``full`` (every frame, the reference), their drops and the ratio of the
times. The figures are seconds.

Usage: python benchmarks/validate_speed.py [--rig R4] [--workers 2] [--skip-full]
Needs the shipped detectors (detectors/lss-R1). Results are recorded in docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def timed_validate(rig: str, protocol: str, workers: int, home: Path) -> tuple[float, dict]:
    """Seconds of one ``rigopt validate`` run from an empty ``$RIGOPT_HOME`` and its rig entry."""
    started = time.perf_counter()
    process = subprocess.run([str(Path(sys.executable).parent / "rigopt"), "validate", rig, "--ref", "R1", "--model",
                              "lss", "--json", "--workers", str(workers), "--protocol", protocol],
                             capture_output=True, text=True, env={**os.environ, "RIGOPT_HOME": str(home)})
    seconds = time.perf_counter() - started
    if process.returncode:
        raise SystemExit(process.stderr)
    return seconds, json.loads(process.stdout)["rigs"][0]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rig", default="R4", help="the rig measured (default R4; R1's geometry would be a no-op)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--skip-full", action="store_true", help="time only the quick protocol")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as scratch:
        quick, entry = timed_validate(args.rig, "quick", args.workers, Path(scratch) / "quick")
        seeds = " / ".join(f"{s['drop']:.3f}" for s in entry["seeds"].values())
        print(f"{args.rig} ({entry['n_cameras']} cameras), quick: {quick:.1f} s, drop {entry['drop']:.3f} ({seeds})")
        if args.skip_full:
            return 0
        full, reference = timed_validate(args.rig, "full", args.workers, Path(scratch) / "full")
        seeds = " / ".join(f"{s['drop']:.3f}" for s in reference["seeds"].values())
        print(f"{args.rig}, full: {full:.1f} s, drop {reference['drop']:.3f} ({seeds}); quick / full = "
              f"{quick / full:.2f} of the time, drop difference {entry['drop'] - reference['drop']:+.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
