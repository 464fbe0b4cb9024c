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
from pathlib import Path

HERE = Path(__file__).resolve().parent
DESIGNS = HERE / "designs"
sys.path.insert(0, str(HERE.parent))  # studies/: the studies' shared code (studylib)
from studylib.logs import timestamped_log  # noqa: E402


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
            ("naive transfer", copies["naive transfer"]),
            ("height-matched transfer", copies["height-matched transfer"])]


def searched_copy(vehicle_name: str):
    """(the design with the height search, R1's height-matched transfer with the same height search): each copy
    camera moved as the designer moves its perception cameras (``rigopt.design.heights.search_heights``, 0.75 m,
    the mount checks; the copy has no coverage requirements). An exploratory diagnostic, not pre-registered: is
    the design's gain over the copy more than the finer height grid?"""
    import dataclasses

    import numpy as np

    from rigopt.design.defaults import NEAREST_POSE
    from rigopt.design.heights import search_heights
    from rigopt.design.settings import DesignSettings
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.library import load_vehicle

    (_, design), _, _, (_, copy) = measured_rigs(vehicle_name)
    reference, vehicle = load_rig("R1"), load_vehicle(vehicle_name)
    matched = np.array([[c.id for c in reference.cameras].index(c.id) for c in copy.cameras])
    moved, _ = search_heights(copy, matched, reference, vehicle, NEAREST_POSE["height_search_m"], DesignSettings(),
                              lambda rig: True)
    return design, dataclasses.replace(moved, name=f"{copy.name}_searched")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", nargs="+", default=["firetruck", "hgv"])
    parser.add_argument("--cache", type=Path, default=None, help="renderings (default: rigopt validate's cache)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--searched-copy", action="store_true",
                        help="instead: the design against the height-matched copy given the same height search "
                             "(exploratory; designs/<vehicle>_heights_copy.json)")
    args = parser.parse_args(argv)
    from rigopt.validation.detectors.shipped import shipped_detector

    detector = shipped_detector("lss", "R1")
    for vehicle_name in args.vehicles:
        with timestamped_log(DESIGNS / f"{vehicle_name}_heights.log") as progress:
            measure_vehicle(vehicle_name, args, detector, progress)
    return 0


def measure_vehicle(vehicle_name: str, args, detector, progress) -> None:
    """Measure one vehicle's rigs as :func:`main`'s ``args`` say (the pre-registered four, or with
    ``--searched-copy`` the diagnostic's two) and write its JSON, whole or not at all."""
    from rigopt.output import write_text_atomic
    from rigopt.validation.detectors.shipped import measure, paired_differences, without_resamples
    from rigopt.validation.detectors.measuring import FULL  # the protocol this study was measured under

    if args.searched_copy:
        design, copy = searched_copy(vehicle_name)
        progress(f"{vehicle_name}: {design.name} and {copy.name} (heights {copy.positions[:, 2].round(2)})")
        entries = measure([design, copy], detector, args.cache, "cpu", args.workers, progress, FULL)
        out = DESIGNS / f"{vehicle_name}_heights_copy.json"
        result = {"vehicle": vehicle_name, "note": searched_copy.__doc__.split(". An")[0],
                  "copy_positions": copy.positions.round(3).tolist(),
                  "rigs": [without_resamples(entry) for entry in entries],
                  "design_minus_searched_copy": paired_differences(entries[0], entries[1])}
    else:
        rigs = measured_rigs(vehicle_name)
        progress(f"{vehicle_name}: {', '.join(rig.name for _, rig in rigs)}")
        entries = measure([rig for _, rig in rigs], detector, args.cache, "cpu", args.workers, progress, FULL)
        out = DESIGNS / f"{vehicle_name}_heights.json"
        result = {"vehicle": vehicle_name, "rigs": [{"role": role, "positions": rig.positions.round(3).tolist(),
                                                      **without_resamples(entry)}
                                                     for (role, rig), entry in zip(rigs, entries)],
                  "design_minus": [{"role": role, **paired_differences(entries[0], entry)}
                                   for (role, _), entry in zip(rigs[1:], entries[1:])]}
    write_text_atomic(out, json.dumps(result, indent=1))
    progress(f"wrote {out}")


if __name__ == "__main__":
    sys.exit(main())
