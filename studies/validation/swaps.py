"""One camera at a time: the height-matched copy of R1 with one camera moved to the direction design's mount.

    python studies/validation/swaps.py [--vehicles firetruck hgv] [--cache DIR] [--workers 2]

Pre-registered in ``designs/preregistration_swaps.md``. For each vehicle: the height-matched transfer of R1
(validate's yardstick, ``rigopt.validation.designs.comparison_rigs``) and, for each R1 camera, that copy with
the camera replaced by the direction design's camera matched to the same R1 camera (pose and lens from
``designs/<vehicle>_from_R1_direction/report.json``). All measured as ``rigopt validate`` does without
``--data`` (renderings cached, so a rerun resumes), the copy and its swaps scored on the same scene resamples;
the result (each rig's drops, each swap minus the copy per seed with its paired interval) goes to
``designs/<vehicle>_swaps.json``, the log to ``designs/<vehicle>_swaps.log``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
DESIGNS = HERE / "designs"
sys.path.insert(0, str(HERE.parent))  # studies/: the studies' shared code (studylib)
from studylib.logs import timestamped_log  # noqa: E402


def swap_rigs(vehicle_name: str):
    """(height-matched copy, [(R1 camera id, the copy with that camera swapped), ...])."""
    from rigopt.validation.designs import comparison_rigs, load_design
    from rigopt.rig.library import load_rig

    folder = DESIGNS / f"{vehicle_name}_from_R1_direction"
    design = load_design(folder / "report.json")
    copy = dict((role, rig) for role, rig in comparison_rigs(design, load_rig("R1")))["height-matched transfer"]
    matched = {row["id"]: row["matched_reference_camera"]["id"]
               for row in json.loads((folder / "report.json").read_text())["cameras"] if row["role"] == "perception"}
    by_reference = {matched[camera.id]: camera for camera in design.cameras if camera.id in matched}
    swaps = []
    for k, camera in enumerate(copy.cameras):
        moved = dataclasses.replace(by_reference[camera.id], id=camera.id)
        cameras = copy.cameras[:k] + (moved,) + copy.cameras[k + 1:]
        swaps.append((camera.id, dataclasses.replace(copy, name=f"{copy.name}_swap_{camera.id}", cameras=cameras)))
    return copy, swaps


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", nargs="+", default=["firetruck", "hgv"])
    parser.add_argument("--cache", type=Path, default=None, help="renderings (default: rigopt validate's cache)")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    from rigopt.output import write_text_atomic
    from rigopt.validation.detectors.shipped import measure, paired_differences, shipped_detector, without_resamples
    from rigopt.validation.detectors.measuring import FULL  # the protocol this study was measured under

    detector = shipped_detector("lss", "R1")
    for vehicle_name in args.vehicles:
        with timestamped_log(DESIGNS / f"{vehicle_name}_swaps.log") as progress:
            copy, swaps = swap_rigs(vehicle_name)
            progress(f"{vehicle_name}: {copy.name} and {len(swaps)} swaps")
            entries = measure([copy] + [rig for _, rig in swaps], detector, args.cache, "cpu", args.workers,
                              progress, FULL)
            result = {"vehicle": vehicle_name, "copy": without_resamples(entries[0]), "swaps": []}
            for (camera_id, rig), entry in zip(swaps, entries[1:]):
                moved = next(c for c in rig.cameras if c.id == camera_id)
                result["swaps"].append({"camera": camera_id, "position": moved.position.round(3).tolist(),
                                        "fov": moved.fov, **without_resamples(entry),
                                        "minus_copy": paired_differences(entry, entries[0])})
            out = write_text_atomic(DESIGNS / f"{vehicle_name}_swaps.json", json.dumps(result, indent=1))
            progress(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
