"""Amendment 3 of the replication (pre-registered in ``preregistration.md``): the rigs the windscreen rule changed,
measured on the replication's two scene sets beside the designs measured before.

    python studies/replication/windscreen/run.py [--cache DIR] [--workers 2] [--analyse-only]

Cells (``results/<vehicle>_<protocol>.json``) are written as soon as measured (a rerun skips them); the statistics to
``results/results.md`` and ``results/results.json``; the log to ``results/run.log``.
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
sys.path.insert(0, str(HERE.parent))  # the replication's shared pieces (remake)
from remake import LEVEL, PROTOCOLS, YARDSTICKS, measure_remade, with_new_cells  # noqa: E402
from studylib.paired import run_cells  # noqa: E402
from studylib.tables import markdown  # noqa: E402

CHANGED = ("tt", "chrysler_pacifica_hybrid", "citybus")
#: The design each vehicle's new one is compared with: the one measured before.
BEFORE = {"tt": ROOT / "studies" / "predictor" / "rigs" / "tt_from_R1_default.json",
          "chrysler_pacifica_hybrid": ROOT / "studies" / "predictor" / "rigs" / "chrysler_pacifica_hybrid_from_R1_default.json",
          "citybus": HERE.parent / "mirrors" / "rigs" / "citybus_from_R1_default.json"}


def measure_cell(vehicle: str, protocol_name: str, cache, workers: int, progress) -> dict:
    """One vehicle's cell on one scene set: its four new rigs and the design measured before (remake.measure_remade)."""
    return measure_remade(vehicle, protocol_name, HERE / "rigs", BEFORE[vehicle], f"{vehicle}_from_R1_default_before",
                          "new_minus_before", cache, workers, progress)


def analyse(found: dict) -> dict:
    primary = {v: {p: found[(v, p)]["new_minus_before"] for p in PROTOCOLS} for v in CHANGED}
    costs = [v for v in CHANGED if all(primary[v][p]["ci"][0] > 0 for p in PROTOCOLS)]
    return {"new_minus_before": primary, "worse_on_both_scene_sets": costs,
            "replication_with_new_cells": with_new_cells(found)}


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
