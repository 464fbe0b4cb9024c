"""Amendment 3 of the replication (pre-registered in ``preregistration.md``): the rigs the windscreen rule changed,
measured on the replication's two scene sets beside the designs measured before.

    python studies/replication/windscreen/run.py [--cache DIR] [--workers 2] [--analyse-only]

Cells (``results/<vehicle>_<protocol>.json``) are written as soon as measured (a rerun skips them); the statistics to
``results/results.md`` and ``results/results.json``; the log to ``results/run.log``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
REPLICATION = HERE.parent / "results"
sys.path.insert(0, str(ROOT / "studies"))  # studylib
sys.path.insert(0, str(HERE.parent / "mirrors"))  # make_rigs.bus_home
from studylib.paired import run_cells, vehicle_draws, vehicle_mean  # noqa: E402
from studylib.tables import markdown  # noqa: E402

CHANGED = ("tt", "chrysler_pacifica_hybrid", "citybus")
#: The design each vehicle's new one is compared with: the one measured before.
BEFORE = {"tt": ROOT / "studies" / "predictor" / "rigs" / "tt_from_R1_default.json",
          "chrysler_pacifica_hybrid": ROOT / "studies" / "predictor" / "rigs" / "chrysler_pacifica_hybrid_from_R1_default.json",
          "citybus": HERE.parent / "mirrors" / "rigs" / "citybus_from_R1_default.json"}
AMENDMENT_2 = HERE.parent / "mirrors" / "results"
PROTOCOLS = ("quick", "quick-s1")
YARDSTICKS = {"naive copy": "{v}_naive_{v}_from_R1", "height-matched copy": "{v}_height_matched_{v}_from_R1",
              "searched copy": "{v}_height_matched_{v}_from_R1_searched"}
VEHICLES = ("tt", "renault_zoe", "ford_fusion_hybrid", "chrysler_pacifica_hybrid", "citybus")
RESAMPLES, SEED, LEVEL = 2000, 0, 1 - 0.05 / len(YARDSTICKS)


def measure_cell(vehicle: str, protocol_name: str, cache, workers: int, progress) -> dict:
    """One vehicle's cell on one scene set: its four new rigs and the design measured before."""
    import dataclasses

    from make_rigs import bus_home
    from rigopt.rig.library import load_rig
    from rigopt.validation.detectors.measuring import protocol_named
    from rigopt.validation.detectors.shipped import measure, paired_differences, shipped_detector, without_resamples

    names = [f"{vehicle}_from_R1_default", *(p.format(v=vehicle) for p in YARDSTICKS.values())]
    rigs = [load_rig(HERE / "rigs" / f"{name}.json") for name in names]
    rigs.append(dataclasses.replace(load_rig(BEFORE[vehicle]), name=f"{vehicle}_from_R1_default_before"))
    with bus_home():
        entries = measure(rigs, shipped_detector("lss", "R1"), cache, "cpu", workers, progress,
                          protocol_named(protocol_name))
    return {"vehicle": vehicle, "protocol": protocol_name, "rigs": [without_resamples(e) for e in entries],
            "design_minus": {role: paired_differences(entries[0], entry) for role, entry in zip(YARDSTICKS, entries[1:4])},
            "new_minus_before": paired_differences(entries[0], entries[4])}


def analyse(found: dict) -> dict:
    primary = {v: {p: found[(v, p)]["new_minus_before"] for p in PROTOCOLS} for v in CHANGED}
    costs = [v for v in CHANGED if all(primary[v][p]["ci"][0] > 0 for p in PROTOCOLS)]
    draws = vehicle_draws(len(VEHICLES), RESAMPLES, SEED)
    recomputed = {}
    for p in PROTOCOLS:
        cells = [found[(v, p)] if v in CHANGED else json.loads((REPLICATION / f"{v}_{p}.json").read_text())
                 for v in VEHICLES]
        recomputed[p] = {role: vehicle_mean([c["design_minus"][role] for c in cells], VEHICLES, draws, LEVEL)
                         for role in YARDSTICKS}
    return {"new_minus_before": primary, "worse_on_both_scene_sets": costs, "replication_with_new_cells": recomputed}


def report(found: dict, result: dict) -> str:
    rows = [["vehicle", "scenes", "new design", *YARDSTICKS, "design before", *(f"new - {r}" for r in YARDSTICKS),
             "new - before"]]
    for v in CHANGED:
        for p in PROTOCOLS:
            cell = found[(v, p)]
            diffs = [*(cell["design_minus"][r] for r in YARDSTICKS), cell["new_minus_before"]]
            rows.append([v, p, *(f"{r['drop']:.3f}" for r in cell["rigs"]),
                         *(f"{d['difference']:+.3f} [{d['ci'][0]:.3f}, {d['ci'][1]:.3f}]" for d in diffs)])
    summary = [["scenes", "yardstick", "mean design - yardstick", "95 % over vehicles", f"{100 * LEVEL:.1f} % (Bonferroni)"]]
    for p, per in result["replication_with_new_cells"].items():
        for role, s in per.items():
            summary.append([p, role, f"{s['mean']:+.3f}", "[{:.3f}, {:.3f}]".format(*s["ci95"]),
                            "[{:.3f}, {:.3f}]".format(*s["ci_bonferroni"])])
    worse = ", ".join(result["worse_on_both_scene_sets"]) or "none"
    return (f"# Amendment 3: the rigs the windscreen rule changed\n\nDrops (seeds averaged) and paired differences with "
            f"95 % scene intervals (per vehicle):\n\n{markdown(rows)}\n\nThe replication's statistics with these "
            f"vehicles' new cells (the pre-registered ones stand as measured, `../results/results.md`):\n\n"
            f"{markdown(summary)}\n\n**Decision (pre-registered rule): vehicles whose new design is worse on both scene "
            f"sets: {worse}; the rule stays.**\n")


def main(argv=None) -> int:
    return run_cells(argv, __doc__.splitlines()[0], HERE / "results", CHANGED, PROTOCOLS, measure_cell, analyse, report)


if __name__ == "__main__":
    sys.exit(main())
