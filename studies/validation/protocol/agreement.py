"""The quick protocol against the full one on the validation study's 63 rigs (pre-registered in
``preregistration.md``).

    python studies/validation/protocol/agreement.py [--cache DIR] [--workers 2]   # measure (resumable), then analyse
    python studies/validation/protocol/agreement.py --analyse-only

Each rig of ``studies/validation/rigs/index.csv`` is measured under ``quick`` as ``rigopt validate RIG --ref R1
--model lss --protocol quick`` does (renderings and scores cached, so a rerun resumes; rigs measured in chunks,
each chunk's entries appended to ``results/quick.jsonl``). The full protocol's drops are those measured before
(``studies/validation/results/measured.csv``). The statistics and the decision of the pre-registration go to
``results/agreement.md`` and ``results/agreement.json``; the log to ``results/measure.log``.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
STUDY = HERE.parent
RESULTS = HERE / "results"
sys.path.insert(0, str(STUDY.parent))  # studies/: the studies' shared code (studylib)
from studylib.logs import timestamped_log  # noqa: E402
from studylib.measuring import add_measuring_options, measure_to_lines  # noqa: E402
from studylib.tables import markdown  # noqa: E402

#: The pre-registered decision rule.
MAX_MEAN_ABS, MIN_RHO, MAX_ABS = 0.025, 0.97, 0.08


def measure_quick(cache: Path | None, workers: int) -> None:
    from rigopt.rig.library import load_rig
    from rigopt.validation.detectors.measuring import QUICK

    with open(STUDY / "rigs" / "index.csv", newline="") as handle:
        names = [row["rig"] for row in csv.DictReader(handle)]
    with timestamped_log(RESULTS / "measure.log") as progress:
        measure_to_lines([load_rig(STUDY / "rigs" / f"{name}.json") for name in names], RESULTS / "quick.jsonl",
                         QUICK, cache, workers, progress)


def full_drops() -> dict[str, dict[str, float]]:
    """{rig: {seed: full-protocol drop}} from the validation study's measurements."""
    found: dict[str, dict[str, float]] = {}
    with open(STUDY / "results" / "measured.csv", newline="") as handle:
        for row in csv.DictReader(handle):
            found.setdefault(row["rig"], {})[row["seed"]] = float(row["drop"])
    return found


def analyse() -> dict:
    from rigopt.metrics.reliability import spearman

    full = full_drops()
    quick = [json.loads(line) for line in (RESULTS / "quick.jsonl").read_text().splitlines()]
    rigs = [e["rig"] for e in quick]
    q = np.array([e["drop"] for e in quick])
    f = np.array([np.mean(list(full[r].values())) for r in rigs])
    gap = q - f
    rng = np.random.default_rng(0)
    resampled = [np.abs(gap[rng.integers(len(gap), size=len(gap))]).mean() for _ in range(2000)]
    per_seed = {seed: float(np.mean([abs(e["seeds"][seed]["drop"] - full[e["rig"]][seed]) for e in quick]))
                for seed in quick[0]["seeds"]}
    inside = float(np.mean([e["drop_ci"][0] <= fv <= e["drop_ci"][1] for e, fv in zip(quick, f)]))
    result = {"rigs": len(rigs), "mean_abs_difference": float(np.abs(gap).mean()),
              "mean_abs_difference_ci": [float(np.percentile(resampled, 2.5)), float(np.percentile(resampled, 97.5))],
              "spearman": float(spearman(q, f)[0]), "max_abs_difference": float(np.abs(gap).max()),
              "worst_rig": rigs[int(np.argmax(np.abs(gap)))], "mean_difference": float(gap.mean()),
              "per_seed_mean_abs_difference": per_seed, "full_inside_quick_interval": inside,
              "rule": {"max_mean_abs": MAX_MEAN_ABS, "min_rho": MIN_RHO, "max_abs": MAX_ABS}}
    result["passes"] = bool(result["mean_abs_difference"] <= MAX_MEAN_ABS and result["spearman"] >= MIN_RHO
                            and result["max_abs_difference"] <= MAX_ABS)
    result["per_rig"] = [{"rig": r, "quick": float(a), "full": float(b)} for r, a, b in zip(rigs, q, f)]
    return result


def write_report(result: dict) -> None:
    from rigopt.output import write_text_atomic

    write_text_atomic(RESULTS / "agreement.json", json.dumps(result, indent=1) + "\n")
    rows = [["statistic", "value", "rule"],
            ["rigs", result["rigs"], "63"],
            ["mean abs difference (95 % over rigs)", f"{result['mean_abs_difference']:.4f} [{result['mean_abs_difference_ci'][0]:.4f}, "
             f"{result['mean_abs_difference_ci'][1]:.4f}]", f"<= {MAX_MEAN_ABS}"],
            ["Spearman rho", f"{result['spearman']:.4f}", f">= {MIN_RHO}"],
            ["largest abs difference", f"{result['max_abs_difference']:.4f} ({result['worst_rig']})", f"<= {MAX_ABS}"],
            ["mean signed difference (quick - full)", f"{result['mean_difference']:+.4f}", "-"],
            ["mean abs difference per seed", " / ".join(f"{v:.4f}" for v in result["per_seed_mean_abs_difference"].values()), "-"],
            ["full drop inside quick's 95 % scene interval", f"{result['full_inside_quick_interval']:.2f}", "-"]]
    verdict = "passes: quick becomes the default" if result["passes"] else "does not pass: full stays the default"
    text = (f"# Quick protocol against full: the pre-registered agreement\n\n{markdown(rows)}\n\n**Decision: {verdict}.**\n\n"
            + markdown([["rig", "quick", "full", "quick - full"]]
                       + [[r["rig"], f"{r['quick']:.3f}", f"{r['full']:.3f}", f"{r['quick'] - r['full']:+.3f}"]
                          for r in result["per_rig"]]) + "\n")
    write_text_atomic(RESULTS / "agreement.md", text)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_measuring_options(parser)
    parser.add_argument("--analyse-only", action="store_true")
    args = parser.parse_args(argv)
    if not args.analyse_only:
        measure_quick(args.cache, args.workers)
    result = analyse()
    write_report(result)
    print(f"mean |quick - full| {result['mean_abs_difference']:.4f}, rho {result['spearman']:.4f}, largest "
          f"{result['max_abs_difference']:.4f}: {'passes' if result['passes'] else 'does not pass'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
