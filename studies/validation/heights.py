"""The height search measured: the default design against the naive copy, the height-matched copy and the design
without the search.

    python studies/validation/heights.py [--vehicles firetruck hgv] [--cache DIR] [--workers 2]

Pre-registered in ``designs/preregistration_heights.md``. For each vehicle, four rigs, each its perception
cameras: the default design from R1 (``designs/<vehicle>_from_R1_heights/``, made by ``rigopt design --vehicle V
--ref R1`` with the height search), the default design before it (``designs/<vehicle>_from_R1_nearest_free/``),
and the naive and the height-matched transfers of R1 (``rigopt validate``'s yardsticks, the naive one refined
under the joint calibration, as there). All measured as ``rigopt validate`` does without ``--data`` (renderings
cached, so a rerun resumes) on the same scene resamples; the result (each rig's drops, the design minus each
other rig per seed with its paired interval) goes to ``designs/<vehicle>_heights.json``, the log to
``designs/<vehicle>_heights.log``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
DESIGNS = HERE / "designs"


def measured_rigs(vehicle_name: str):
    """[(role, rig)]: the design with the height search, the design before it, the naive and height-matched copies
    (each rig's perception cameras, named after its folder or role)."""
    from rigopt.metrics.calibration import load_weights
    from rigopt.rig.library import load_rig
    from rigopt.validation.designs import comparison_rigs, load_design

    design = load_design(DESIGNS / f"{vehicle_name}_from_R1_heights" / "report.json").perception()
    before = load_design(DESIGNS / f"{vehicle_name}_from_R1_nearest_free" / "report.json").perception()
    copies = dict(comparison_rigs(design, load_rig("R1"), load_weights("joint")))
    return [("design with the height search", design), ("design before it", before),
            ("naive transfer", copies["naive transfer"]), ("height-matched transfer", copies["height-matched transfer"])]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", nargs="+", default=["firetruck", "hgv"])
    parser.add_argument("--cache", type=Path, default=None, help="renderings (default: rigopt validate's cache)")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    from rigopt.validation.detectors.shipped import measure, paired_differences, shipped_detector, without_resamples

    detector = shipped_detector("lss", "R1")
    for vehicle_name in args.vehicles:
        log = open(DESIGNS / f"{vehicle_name}_heights.log", "a")

        def progress(message: str) -> None:
            line = f"{time.strftime('%H:%M:%S')} {message}"
            print(line, flush=True)
            log.write(line + "\n")
            log.flush()

        rigs = measured_rigs(vehicle_name)
        progress(f"{vehicle_name}: {', '.join(rig.name for _, rig in rigs)}")
        entries = measure([rig for _, rig in rigs], detector, args.cache, "cpu", args.workers, progress)
        result = {"vehicle": vehicle_name, "rigs": [{"role": role, "positions": rig.positions.round(3).tolist(),
                                                      **without_resamples(entry)}
                                                     for (role, rig), entry in zip(rigs, entries)],
                  "design_minus": [{"role": role, **paired_differences(entries[0], entry)}
                                   for (role, _), entry in zip(rigs[1:], entries[1:])]}
        out = DESIGNS / f"{vehicle_name}_heights.json"
        temporary = out.with_suffix(".tmp")
        temporary.write_text(json.dumps(result, indent=1))
        temporary.replace(out)
        progress(f"wrote {out}")
        log.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
