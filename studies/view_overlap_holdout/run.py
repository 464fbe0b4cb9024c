"""The view-overlap warning on rigs not used to choose its threshold (see preregistration.md).

Usage: python studies/view_overlap_holdout/run.py   (writes results.md beside this file)
"""

from __future__ import annotations

from pathlib import Path

from scipy.stats import beta

from rigopt.metrics.view_overlap import LOW_VIEW_OVERLAP, view_overlaps
from rigopt.rig.library import load_rig

HERE = Path(__file__).resolve().parent
STUDIES = HERE.parent
TEST_SET = sorted((STUDIES / "drop_model_designer" / "rigs").glob("*.json")) + sorted(
    (STUDIES / "validation" / "designs").glob("*/rig.json"))


def upper_bound(flagged: int, total: int) -> float:
    """The 95 % Clopper-Pearson upper bound of a share ``flagged`` / ``total``."""
    return 1.0 if flagged == total else float(beta.ppf(0.975, flagged + 1, total - flagged))


def main() -> None:
    reference = load_rig("R1")
    rigs = [load_rig(str(path)) for path in TEST_SET]
    overlaps = view_overlaps(reference, [rig.perception() for rig in rigs])
    rows = sorted(zip((str(p.relative_to(STUDIES)) for p in TEST_SET), (r.vehicle for r in rigs), overlaps),
                  key=lambda row: row[2])
    flagged = [row for row in rows if row[2] < LOW_VIEW_OVERLAP]
    vehicles = sorted({vehicle for _, vehicle, _ in rows})
    flagged_vehicles = sorted({vehicle for _, vehicle, _ in flagged})
    lines = ["# The view-overlap warning on rigs not used to choose it", "",
             f"Reference R1; threshold {LOW_VIEW_OVERLAP:g}; {len(rows)} rigs on {len(vehicles)} vehicles "
             "(preregistration.md).", "",
             f"Flagged: {len(flagged)} of {len(rows)} rigs (95 % upper bound {upper_bound(len(flagged), len(rows)):.3f}), "
             f"{len(flagged_vehicles)} of {len(vehicles)} vehicles (95 % upper bound "
             f"{upper_bound(len(flagged_vehicles), len(vehicles)):.3f}). Lowest overlap {rows[0][2]:.3f} "
             f"({rows[0][0]}).", "",
             "Decision (pre-registered): " + ("the warning holds on unseen rigs: none is flagged." if not flagged else
                                              "rigs are flagged: " + ", ".join(f"{n} {o:.3f}" for n, _, o in flagged)),
             "", "| vehicle | lowest overlap |", "|---|---|"]
    lines += [f"| {vehicle} | {min(o for _, v, o in rows if v == vehicle):.3f} |" for vehicle in vehicles]
    lines += ["", "| rig | vehicle | overlap with R1 |", "|---|---|---|"]
    lines += [f"| {name} | {vehicle} | {overlap:.3f} |" for name, vehicle, overlap in rows]
    (HERE / "results.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines[:8]))


if __name__ == "__main__":
    main()
