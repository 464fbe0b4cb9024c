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
from studylib.paired import run_cells, vehicle_draws, vehicle_mean  # noqa: E402
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
    draws = vehicle_draws(len(VEHICLES), RESAMPLES, SEED)
    out = {"level": LEVEL, "scene_sets": {}}
    for protocol in PROTOCOLS:
        out["scene_sets"][protocol] = {
            role: vehicle_mean([found[(v, protocol)]["design_minus"][role] for v in VEHICLES], VEHICLES, draws, LEVEL)
            for role in YARDSTICKS}
    out["beats"] = {role: all(out["scene_sets"][p][role]["ci_bonferroni"][1] < 0
                              and not out["scene_sets"][p][role]["vehicles_wholly_above_0"] for p in PROTOCOLS)
                    for role in YARDSTICKS}
    return out


def report(found: dict, result: dict) -> str:
    rows = [["vehicle", "scenes", "design", *YARDSTICKS, *(f"design - {r}" for r in YARDSTICKS)]]
    for v in VEHICLES:
        for p in PROTOCOLS:
            entry = found[(v, p)]
            minus = entry["design_minus"]
            rows.append([v, p, *(f"{r['drop']:.3f}" for r in entry["rigs"]),
                         *(f"{minus[r]['difference']:+.3f} [{minus[r]['ci'][0]:.3f}, {minus[r]['ci'][1]:.3f}]"
                           for r in YARDSTICKS)])
    summary = [["scenes", "yardstick", "mean design - yardstick", "95 % over vehicles",
                f"{100 * LEVEL:.1f} % (Bonferroni)", "vehicles wholly above 0"]]
    for p, per in result["scene_sets"].items():
        for role, s in per.items():
            summary.append([p, role, f"{s['mean']:+.3f}", "[{:.3f}, {:.3f}]".format(*s["ci95"]),
                            "[{:.3f}, {:.3f}]".format(*s["ci_bonferroni"]), ", ".join(s["vehicles_wholly_above_0"]) or "-"])
    verdict = "; ".join(f"{role}: {'beaten' if won else 'not beaten'}" for role, won in result["beats"].items())
    return (f"# The designer's claim on held-out vehicles and new scenes\n\n{markdown(rows)}\n\n{markdown(summary)}\n\n"
            f"**Decision (pre-registered rule): {verdict}.**\n")


def main(argv=None) -> int:
    return run_cells(argv, __doc__.splitlines()[0], RESULTS, VEHICLES, PROTOCOLS, measure_vehicle, analyse, report)


if __name__ == "__main__":
    sys.exit(main())
