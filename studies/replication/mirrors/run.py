"""Amendment 2 of the replication (pre-registered in ``preregistration.md``): the city bus's rigs remade with a
mirror zone, measured on the replication's two scene sets beside its committed design.

    python studies/replication/mirrors/run.py [--cache DIR] [--workers 2] [--analyse-only]

Cells (``results/citybus_<protocol>.json``) are written as soon as measured (a rerun skips them); the statistics to
``results/results.md`` and ``results/results.json``; the log to ``results/run.log``.
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
COMMITTED = ROOT / "studies" / "predictor" / "rigs" / "citybus_from_R1_default.json"
sys.path.insert(0, str(HERE.parent))  # the replication's shared pieces (remake)
from remake import LEVEL, PROTOCOLS, YARDSTICKS, measure_remade, with_new_cells  # noqa: E402
from studylib.paired import run_cells  # noqa: E402
from studylib.tables import markdown  # noqa: E402


def measure_cell(vehicle: str, protocol_name: str, cache, workers: int, progress) -> dict:
    """The bus's cell of one scene set, its committed design beside its remade rigs (remake.measure_remade)."""
    return measure_remade(vehicle, protocol_name, HERE / "rigs", COMMITTED, "citybus_from_R1_default_committed",
                          "new_minus_committed", cache, workers, progress)


def analyse(found: dict) -> dict:
    primary = {p: found[("citybus", p)]["new_minus_committed"] for p in PROTOCOLS}
    worse = all(primary[p]["ci"][0] > 0 for p in PROTOCOLS)
    return {"new_minus_committed": primary, "mirror_zone_kept_for_perception": not worse,
            "replication_with_new_bus": with_new_cells(found)}


def report(found: dict, result: dict) -> str:
    rows = [["scenes", "new design", *YARDSTICKS, "committed design", *(f"new design - {r}" for r in YARDSTICKS),
             "new - committed design"]]
    for p in PROTOCOLS:
        cell = found[("citybus", p)]
        diffs = [*(cell["design_minus"][r] for r in YARDSTICKS), cell["new_minus_committed"]]
        rows.append([p, *(f"{r['drop']:.3f}" for r in cell["rigs"]),
                     *(f"{d['difference']:+.3f} [{d['ci'][0]:.3f}, {d['ci'][1]:.3f}]" for d in diffs)])
    summary = [["scenes", "yardstick", "mean design - yardstick", "95 % over vehicles", f"{100 * LEVEL:.1f} % (Bonferroni)"]]
    for p, per in result["replication_with_new_bus"].items():
        for role, s in per.items():
            summary.append([p, role, f"{s['mean']:+.3f}", "[{:.3f}, {:.3f}]".format(*s["ci95"]),
                            "[{:.3f}, {:.3f}]".format(*s["ci_bonferroni"])])
    kept = result["mirror_zone_kept_for_perception"]
    return (f"# Amendment 2: the city bus with mirror zones\n\nDrops (seeds averaged) and paired differences with 95 % "
            f"scene intervals (one vehicle):\n\n{markdown(rows)}\n\nThe replication's statistics with the bus's new "
            f"cells (the pre-registered ones stand as measured, `../results/results.md`):\n\n{markdown(summary)}\n\n"
            f"**Decision (pre-registered rule): the mirror zone {'stays for both roles' if kept else 'serves the near-field cameras only'}.**\n")


def main(argv=None) -> int:
    return run_cells(argv, __doc__.splitlines()[0], HERE / "results", ("citybus",), PROTOCOLS, measure_cell, analyse,
                     report)


if __name__ == "__main__":
    sys.exit(main())
