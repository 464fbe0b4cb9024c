"""The designer's claim where it was not tuned (pre-registered in ``preregistration.md``): the default design against
R1's naive, height-matched and searched copies on five held-out vehicles, on R1's test scenes and on new scenes.

    python studies/replication/run.py [--cache DIR] [--workers 2] [--analyse-only]

Each vehicle's four rigs (``studies/predictor/rigs/``) are measured under ``quick`` and ``quick-s1`` as ``rigopt
validate`` does (renderings and scores cached: a rerun scores nothing). Per vehicle and scene set the paired
differences go to ``results/<vehicle>_<protocol>.json`` as soon as they are measured (a rerun skips those files);
the pre-registered statistics and decision to ``results/results.md`` and ``results/results.json``; the log to
``results/run.log``.
"""

from __future__ import annotations

import sys
from pathlib import Path


HERE = Path(__file__).resolve().parent
RIGS = HERE.parent / "predictor" / "rigs"
RESULTS = HERE / "results"
sys.path.insert(0, str(HERE.parent))  # studies/: the studies' shared code (studylib)
from studylib.paired import beaten, cell_rows, run_cells, scene_set_means, summary_rows  # noqa: E402
from studylib.tables import markdown  # noqa: E402
from remake import LEVEL, PROTOCOLS, RESAMPLES, SEED, VEHICLES, YARDSTICKS  # noqa: E402  (the test's constants)


def measure_vehicle(vehicle: str, protocol_name: str, cache, workers: int, progress) -> dict:
    from rigopt.rig.library import load_rig
    from rigopt.validation.detectors.measuring import protocol_named
    from rigopt.validation.detectors.shipped import measure, paired_differences, shipped_detector, without_resamples

    names = [f"{vehicle}_from_R1_default", *(pattern.format(v=vehicle) for pattern in YARDSTICKS.values())]
    rigs = [load_rig(RIGS / f"{name}.json") for name in names]
    entries = measure(rigs, shipped_detector("lss", "R1"), cache, "cpu", workers, progress, protocol_named(protocol_name))
    return {"vehicle": vehicle, "protocol": protocol_name, "rigs": [without_resamples(e) for e in entries],
            "design_minus": {role: paired_differences(entries[0], entry)
                             for role, entry in zip(YARDSTICKS, entries[1:])}}


def analyse(found: dict) -> dict:
    scene_sets = scene_set_means(found, VEHICLES, PROTOCOLS, YARDSTICKS, RESAMPLES, SEED, LEVEL)
    return {"level": LEVEL, "scene_sets": scene_sets, "beats": beaten(scene_sets, YARDSTICKS)}


def report(found: dict, result: dict) -> str:
    verdict = "; ".join(f"{role}: {'beaten' if won else 'not beaten'}" for role, won in result["beats"].items())
    return (f"# The designer's claim on held-out vehicles and new scenes\n\n"
            f"{markdown(cell_rows(found, VEHICLES, PROTOCOLS, YARDSTICKS))}\n\n"
            f"{markdown(summary_rows(result['scene_sets'], LEVEL))}\n\n**Decision (pre-registered rule): {verdict}.**\n")


def main(argv=None) -> int:
    return run_cells(argv, __doc__.splitlines()[0], RESULTS, VEHICLES, PROTOCOLS, measure_vehicle, analyse, report)


if __name__ == "__main__":
    sys.exit(main())
