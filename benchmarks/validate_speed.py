"""``rigopt validate RIG --ref R1 --model lss`` without --data, from an empty cache: the time of the whole
command for one rig, split into rendering and scoring, beside the plain way of measuring the same drops
(render the reference's test split too, then score each checkpoint on both rigs separately, as ``--data``
does). Both give the same drops; the figures are seconds and their ratio.

Usage: python benchmarks/validate_speed.py [--rig R1-c10] [--workers 2] [--skip-plain]
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


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rig", default="R3", help="the rig measured (default R3; R1's geometry would be a no-op)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--skip-plain", action="store_true", help="time only the command")
    args = parser.parse_args(argv)
    from rigopt.validation.detectors.protocol import evaluate_on_rigs
    from rigopt.validation.detectors.shipped import render_cached, shipped_detector
    from rigopt.rig.library import load_rig

    detector = shipped_detector("lss", "R1")
    rig = load_rig(args.rig)
    with tempfile.TemporaryDirectory() as scratch:
        home = Path(scratch) / "home"
        started = time.perf_counter()
        process = subprocess.run([str(Path(sys.executable).parent / "rigopt"), "validate", args.rig, "--ref", "R1",
                                  "--model", "lss", "--json", "--workers", str(args.workers)],
                                 capture_output=True, text=True, env={**os.environ, "RIGOPT_HOME": str(home)})
        command = time.perf_counter() - started
        if process.returncode:
            raise SystemExit(process.stderr)
        result = json.loads(process.stdout)["rigs"][0]
        started = time.perf_counter()
        render_cached([rig], detector, Path(scratch) / "again", args.workers)
        render = time.perf_counter() - started
        print(f"{args.rig} ({len(rig)} cameras), {detector.card['test_data']['samples']} samples, "
              f"{len(detector.seeds)} models: validate {command:.1f} s (rendering alone {render:.1f} s, so "
              f"scoring and start-up {command - render:.1f} s); drop {result['drop']:.3f}")
        if args.skip_plain:
            return 0
        plain = Path(scratch) / "plain"
        started = time.perf_counter()
        names = render_cached([load_rig(detector.reference), rig], detector, plain, args.workers)
        drops = []
        for seed in detector.seeds:
            maps = evaluate_on_rigs(detector.checkpoint(seed), plain, names, family="lss")
            drops.append((maps[names[0]]["mAP"] - maps[names[1]]["mAP"]) / maps[names[0]]["mAP"])
        plain_seconds = time.perf_counter() - started
        print(f"plain way (render both rigs, score each checkpoint on each): {plain_seconds:.1f} s, drop "
              f"{sum(drops) / len(drops):.3f}; validate / plain = {command / plain_seconds:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
