"""Measure the predictor study's rigs with the shipped R1 detectors (resumable; progress and a log).

    python studies/predictor/measure.py [--cache DIR] [--workers 2] [--vehicles ...]

Each rig of ``rigs/index.csv`` as ``rigopt validate RIG --ref R1 --model lss`` does without ``--data``, under the
quick protocol when its pre-registered agreement with the full one passed
(``studies/validation/protocol/results/agreement.json``), else the full one. Entries go to
``results/measured.jsonl`` (with the rig's vehicle and kind) in chunks as they are done; a rerun skips the rigs
there. The log is ``results/measure.log``. The user vehicle ``citybus`` must be added first (README.md).
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
AGREEMENT = HERE.parent / "validation" / "protocol" / "results" / "agreement.json"
sys.path.insert(0, str(HERE.parent))  # studies/: the studies' shared code (studylib)
from studylib.logs import timestamped_log  # noqa: E402
from studylib.measuring import add_measuring_options, measure_to_lines  # noqa: E402


def study_protocol():
    """quick when its agreement with full passed, else full."""
    from rigopt.validation.detectors.measuring import FULL, QUICK

    if not AGREEMENT.is_file():
        raise SystemExit(f"{AGREEMENT} is missing: run studies/validation/protocol/agreement.py first")
    return QUICK if json.loads(AGREEMENT.read_text())["passes"] else FULL


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_measuring_options(parser)
    parser.add_argument("--vehicles", nargs="*", default=None, help="only these vehicles' rigs")
    args = parser.parse_args(argv)
    from rigopt.rig.library import load_rig

    with open(HERE / "rigs" / "index.csv", newline="") as handle:
        index = {row["rig"]: row for row in csv.DictReader(handle)
                 if args.vehicles is None or row["vehicle"] in args.vehicles}
    rigs = [load_rig(HERE / "rigs" / f"{name}.json") for name in index]
    with timestamped_log(RESULTS / "measure.log") as progress:
        measure_to_lines(rigs, RESULTS / "measured.jsonl", study_protocol(), args.cache, args.workers, progress,
                         lambda name: {"vehicle": index[name]["vehicle"], "kind": index[name]["kind"]})
    return 0


if __name__ == "__main__":
    sys.exit(main())
