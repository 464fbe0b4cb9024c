"""Regulation fields measured: the points each preset asks for on the firetruck, and the coverage of every preset
by R6 on the firetruck and R1 on the etron (covered, criticality-weighted, unseen area, each camera's share), with
timings. The tables of docs/regulations.md ("Measured") come from this script.

Usage: python benchmarks/regulation_fields.py [--spacing 0.1]
"""

from __future__ import annotations

import argparse
import time

from rigopt.coverage.regulations import PRESETS, region_coverage
from rigopt.raycast import has_embree
from rigopt.rig.library import load_rig
from rigopt.vehicle.library import load_vehicle
from rigopt.vehicle.placement import rig_on_vehicle


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spacing", type=float, default=0.1)
    args = parser.parse_args()
    presets = list(PRESETS.values())
    firetruck = load_vehicle("firetruck")
    print(f"embree available: {has_embree()}")
    print("| preset | heights (m) | area (m²) | points at 0.5 m | points at 0.1 m |")
    print("|---|---|---|---|---|")
    for preset in presets:
        heights = ", ".join(f"{h:g}" for h in preset.heights)
        counts = [len(preset.points(firetruck, spacing)) for spacing in (0.5, 0.1)]
        print(f"| {preset.key} | {heights} | {preset.polygon(firetruck).area:.1f} | {counts[0]:,} | {counts[1]:,} |")

    for rig_name in ("R6", "R1"):
        rig, vehicle, _ = rig_on_vehicle(load_rig(rig_name), None)
        start = time.perf_counter()
        regions = region_coverage(rig, vehicle, presets, spacing=args.spacing)
        elapsed = time.perf_counter() - start
        print(f"\n{rig_name} on {vehicle.name}: all {len(presets)} presets at {args.spacing:g} m in {elapsed:.2f} s")
        print("| preset | seen | weighted | unseen area (m²) | best camera (seen, alone) | seen by >= 2 |")
        print("|---|---|---|---|---|---|")
        for region in regions:
            best = max(region.cameras, key=lambda share: share.seen_frac)
            print(f"| {region.key} | {100 * region.covered_frac:.1f} % | {100 * region.weighted_covered_frac:.1f} % | "
                  f"{region.unseen_area_m2:.1f} | {best.camera} ({100 * best.seen_frac:.1f} %, "
                  f"{100 * best.only_frac:.1f} %) | {100 * region.overlap_frac:.1f} % |")
        print("per height: " + "; ".join(
            f"{r.key} " + ", ".join(f"{h:g} m {100 * f:.1f} %" for h, f in zip(r.heights, r.height_covered_frac))
            for r in regions))


if __name__ == "__main__":
    main()
