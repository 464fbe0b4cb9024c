"""Many rigs measured with the shipped R1 detectors, resumably: each chunk's entries appended to a JSON-lines file
as it is done, the rigs already there skipped on a rerun (the renderings and scores are cached besides)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable, Sequence

#: Rigs measured per call of ``measure`` (its scoring processes start once per chunk).
CHUNK = 8
#: The quick protocol's pre-registered agreement with the full one (studies/validation/protocol/).
AGREEMENT = Path(__file__).resolve().parents[1] / "validation" / "protocol" / "results" / "agreement.json"


def study_protocol():
    """The protocol a measuring study uses: quick when its agreement with full passed, else full."""
    from rigopt.validation.detectors.measuring import FULL, QUICK

    if not AGREEMENT.is_file():
        raise SystemExit(f"{AGREEMENT} is missing: run studies/validation/protocol/agreement.py first")
    return QUICK if json.loads(AGREEMENT.read_text())["passes"] else FULL


def measured_names(lines: Path) -> set[str]:
    """The rigs whose entries ``lines`` (JSON lines) holds."""
    return {json.loads(line)["rig"] for line in lines.read_text().splitlines()} if lines.is_file() else set()


def measure_to_lines(rigs: Sequence, lines: Path, protocol, cache: Path | None, workers: int,
                     progress: Callable[[str], None], extra: Callable[[str], dict] = lambda name: {}) -> None:
    """Measure every rig of ``rigs`` not yet in ``lines`` under ``protocol`` and append its entry (without the
    resamples; ``extra(rig name)`` merged in) as soon as its chunk is done."""
    from rigopt.validation.detectors.shipped import measure, shipped_detector, without_resamples

    detector = shipped_detector("lss", "R1")
    done = measured_names(lines)
    todo = [rig for rig in rigs if rig.name not in done]
    progress(f"{len(done)} rigs measured before; {len(todo)} to go ({protocol.describe(detector.card['test_data'])})")
    lines.parent.mkdir(parents=True, exist_ok=True)
    for start in range(0, len(todo), CHUNK):
        entries = measure(todo[start:start + CHUNK], detector, cache, "cpu", workers, progress, protocol)
        with open(lines, "a") as handle:
            for entry in entries:
                handle.write(json.dumps({**extra(entry["rig"]), **without_resamples(entry)}) + "\n")
                progress(f"{entry['rig']}: drop {entry['drop']:.3f} [{entry['drop_ci'][0]:.3f}, {entry['drop_ci'][1]:.3f}]")


def add_measuring_options(parser) -> None:
    """The options every measuring study script takes: --cache (the renderings) and --workers."""
    parser.add_argument("--cache", type=Path, default=None, help="renderings (default: rigopt validate's cache)")
    parser.add_argument("--workers", type=int, default=2)


def measure_rig_index(study: Path, description: str, argv=None, columns: Sequence[str] = ("vehicle", "kind")) -> int:
    """A study's measuring command: every rig of ``study/rigs/index.csv`` (``--vehicles`` keeps some vehicles'),
    entries to ``study/results/measured.jsonl`` with the index's ``columns``, the log ``results/measure.log``."""
    import argparse
    import csv

    from studylib.logs import timestamped_log

    parser = argparse.ArgumentParser(description=description)
    add_measuring_options(parser)
    parser.add_argument("--vehicles", nargs="*", default=None, help="only these vehicles' rigs")
    args = parser.parse_args(argv)
    from rigopt.rig.library import load_rig

    with open(study / "rigs" / "index.csv", newline="") as handle:
        index = {row["rig"]: row for row in csv.DictReader(handle)
                 if args.vehicles is None or row["vehicle"] in args.vehicles}
    rigs = [load_rig(study / "rigs" / f"{name}.json") for name in index]
    results = study / "results"
    with timestamped_log(results / "measure.log") as progress:
        measure_to_lines(rigs, results / "measured.jsonl", study_protocol(), args.cache, args.workers, progress,
                         lambda name: {column: index[name][column] for column in columns})
    return 0
