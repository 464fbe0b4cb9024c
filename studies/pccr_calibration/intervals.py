"""The shipped calibrations' prediction intervals judged on the benchmark's held-out pairs, as markdown.

Runs the protocol (``rigopt.metrics.protocol.calibrate``) on the shipped measured transfer
(metrics/pccr_transfer.csv) and prints, for each detector's own fit and for the joint fit on each detector's
pairs: the interval's coverage, mean width within [0, 1] and clipped share per predicted-drop bin and overall
(``prediction.interval_report``); then the bounded MAE beside the constant predictors'. docs/metrics.md holds
its output. Usage: python studies/pccr_calibration/intervals.py [--metric rigcd|rigcd+]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rigopt.metrics.protocol import CalibrationStudy, calibrate
from rigopt.metrics.transfer import read_transfer
from rigopt.resources import data_dir

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies/: the studies' shared code (studylib)
from studylib.tables import markdown  # noqa: E402


def fits(study: CalibrationStudy) -> list:
    """(fit name, IntervalReport) of each detector's own fit, then of the joint fit on each detector's pairs."""
    return ([(m.model, m.interval_heldout) for m in study.models]
            + [(f"joint: {r.model}", r.interval_heldout) for r in study.joint.models])


def markdown_tables(study: CalibrationStudy) -> str:
    """The bins table (fit, bin, pairs, coverage, mean width, clipped share) and the MAE table."""
    bins = [["fit", "bin", "pairs", "coverage", "mean width", "clipped share"]]
    for name, report in fits(study):
        for k, b in enumerate(report.bins):
            closing = "]" if k == len(report.bins) - 1 else ")"
            bins.append([name, f"[{b.low:g}, {b.high:g}{closing}", b.n, *_values(b)])
        bins.append([name, "all", report.overall.n, *_values(report.overall)])
    maes = [["fit", "half-width", "informative", "bounded MAE", "constant (median of calibration drops)",
             "its MAE", "hindsight constant's MAE"]]
    maes += [[name, r.halfwidth, "yes" if r.informative else "no", r.bounded_mae, r.constant, r.constant_mae,
              r.oracle_constant_mae] for name, r in fits(study)]
    return "\n\n".join([markdown(bins), markdown(maes)])


def _values(b) -> list:
    return [None if b.n == 0 else value for value in (b.coverage, b.mean_width, b.clipped)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--metric", default="rigcd", choices=["rigcd", "rigcd+"])
    args = parser.parse_args()
    study = calibrate(read_transfer(data_dir("metrics") / "pccr_transfer.csv"), resamples=0, metric=args.metric)
    print(markdown_tables(study))


if __name__ == "__main__":
    main()
