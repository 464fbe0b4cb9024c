"""Measure the pre-registered test rigs with the shipped detectors (resumable; progress and a log).

    python studies/validation/measure.py [--cache DIR] [--workers 2] [--device cpu] [--only NAME ...]

Each rig of ``rigs/index.csv``, in its order, is measured as ``rigopt validate RIG --ref R1 --model lss`` does
without ``--data`` (``rigopt.validation.detectors.shipped.measure``: R1's 16 test scenes rendered under the rig into the
cache, the shipped models of every seed scored on them). One row per (rig, seed) goes to
``results/measured.csv`` as soon as a rig is done, its whole entry to ``results/measured.jsonl``; a rerun skips
the rigs already there. The log is ``results/measure.log``.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
COLUMNS = ["rig", "vehicle", "kind", "seed", "mAP", "mAP_visible", "reference_mAP", "reference_mAP_visible", "drop",
           "drop_visible", "drop_ci_low", "drop_ci_high"]


def done_rigs(path: Path) -> set[str]:
    if not path.is_file():
        return set()
    with open(path, newline="") as handle:
        return {row["rig"] for row in csv.DictReader(handle)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cache", type=Path, default=None, help="renderings (default: rigopt validate's cache)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--only", nargs="*", default=None, help="measure only these rigs")
    args = parser.parse_args(argv)
    from rigopt.validation.detectors.shipped import measure, shipped_detector, without_resamples
    from rigopt.validation.detectors.measuring import FULL  # the protocol this study was measured under
    from rigopt.rig.library import load_rig

    detector = shipped_detector("lss", "R1")
    with open(HERE / "rigs" / "index.csv", newline="") as handle:
        index = list(csv.DictReader(handle))
    RESULTS.mkdir(exist_ok=True)
    table, lines, log = RESULTS / "measured.csv", RESULTS / "measured.jsonl", RESULTS / "measure.log"
    done = done_rigs(table)
    todo = [row for row in index if row["rig"] not in done and (args.only is None or row["rig"] in args.only)]
    print(f"{len(done)} of {len(index)} rigs measured before; {len(todo)} to go", flush=True)
    for k, row in enumerate(todo, start=1):
        started = time.perf_counter()
        rig = load_rig(HERE / "rigs" / f"{row['rig']}.json")
        entry = without_resamples(measure([rig], detector, args.cache, args.device, args.workers, protocol=FULL)[0])
        seconds = time.perf_counter() - started
        fresh = not table.is_file()
        with open(table, "a", newline="") as handle:
            writer = csv.DictWriter(handle, COLUMNS)
            if fresh:
                writer.writeheader()
            for seed, s in entry["seeds"].items():
                writer.writerow({"rig": row["rig"], "vehicle": row["vehicle"], "kind": row["kind"], "seed": seed,
                                 **{c: s[c] for c in COLUMNS[4:10]},
                                 "drop_ci_low": s["drop_ci"][0], "drop_ci_high": s["drop_ci"][1]})
        with open(lines, "a") as handle:
            handle.write(json.dumps({**row, **entry, "seconds": round(seconds, 1)}) + "\n")
        message = (f"[{k}/{len(todo)}] {row['rig']}: drop {entry['drop']:.3f} "
                   f"[{entry['drop_ci'][0]:.3f}, {entry['drop_ci'][1]:.3f}], {seconds:.0f} s")
        print(message, flush=True)
        with open(log, "a") as handle:
            handle.write(time.strftime("%Y-%m-%d %H:%M:%S ") + message + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
