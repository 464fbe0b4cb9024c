"""Studies measured per (vehicle, scene set): each cell measured once into ``results/<vehicle>_<protocol>.json``
(a rerun skips the cells there), the pre-registered analysis once every cell is in, and the vehicle-level
statistic of paired differences the replications decide on."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from studylib.logs import timestamped_log
from studylib.measuring import add_measuring_options


def vehicle_draws(n_vehicles: int, resamples: int, seed: int) -> np.ndarray:
    """(resamples, n_vehicles) int: vehicles drawn with replacement, the resampling of a vehicle-level interval."""
    return np.random.default_rng(seed).integers(n_vehicles, size=(resamples, n_vehicles))


def vehicle_mean(paired: Sequence[dict], vehicles: Sequence[str], draws: np.ndarray, level: float) -> dict:
    """The mean over vehicles of paired differences (``paired``: each vehicle's ``paired_differences``, with
    ``difference`` and its scene interval ``ci``, in the order of ``vehicles``): ``per_vehicle``, ``mean``,
    ``ci95`` and ``ci_bonferroni`` (at ``level``) over the vehicle resamples ``draws``, and
    ``vehicles_wholly_above_0``, those whose own scene interval lies above 0."""
    values = np.array([p["difference"] for p in paired])
    means = values[draws].mean(axis=1)
    return {"per_vehicle": dict(zip(vehicles, values.tolist())), "mean": float(values.mean()),
            "ci95": [float(np.percentile(means, 2.5)), float(np.percentile(means, 97.5))],
            "ci_bonferroni": [float(np.percentile(means, 100 * (1 - level) / 2)),
                              float(np.percentile(means, 100 * (1 + level) / 2))],
            "vehicles_wholly_above_0": [v for v, p in zip(vehicles, paired) if p["ci"][0] > 0]}


def scene_set_means(found: dict, vehicles: Sequence[str], protocols: Sequence[str], yardsticks, resamples: int,
                    seed: int, level: float) -> dict:
    """{protocol: {yardstick: :func:`vehicle_mean`}} of the cells ``found`` {(vehicle, protocol): cell with
    ``design_minus`` per yardstick}, the vehicles drawn alike for every scene set and yardstick."""
    draws = vehicle_draws(len(vehicles), resamples, seed)
    return {p: {role: vehicle_mean([found[(v, p)]["design_minus"][role] for v in vehicles], vehicles, draws, level)
                for role in yardsticks} for p in protocols}


def beaten(scene_sets: dict, yardsticks) -> dict:
    """{yardstick: the replications' rule}: on every scene set the mean design minus yardstick has its Bonferroni
    vehicle interval below 0 and no vehicle's scene interval lies wholly above 0."""
    return {role: all(per[role]["ci_bonferroni"][1] < 0 and not per[role]["vehicles_wholly_above_0"]
                      for per in scene_sets.values()) for role in yardsticks}


def cell_rows(found: dict, vehicles: Sequence[str], protocols: Sequence[str], yardsticks) -> list[list[str]]:
    """One table row per (vehicle, scene set), header first: each rig's drop, then design minus each yardstick with
    its paired scene interval."""
    rows = [["vehicle", "scenes", "design", *yardsticks, *(f"design - {r}" for r in yardsticks)]]
    for v in vehicles:
        for p in protocols:
            entry = found[(v, p)]
            minus = entry["design_minus"]
            rows.append([v, p, *(f"{r['drop']:.3f}" for r in entry["rigs"]),
                         *(f"{minus[r]['difference']:+.3f} [{minus[r]['ci'][0]:.3f}, {minus[r]['ci'][1]:.3f}]"
                           for r in yardsticks)])
    return rows


def summary_rows(scene_sets: dict, level: float) -> list[list[str]]:
    """The table of :func:`scene_set_means`, header first: per scene set and yardstick the mean, its 95 % and
    Bonferroni vehicle intervals and the vehicles whose scene interval lies wholly above 0."""
    rows = [["scenes", "yardstick", "mean design - yardstick", "95 % over vehicles",
             f"{100 * level:.1f} % (Bonferroni)", "vehicles wholly above 0"]]
    for p, per in scene_sets.items():
        for role, s in per.items():
            rows.append([p, role, f"{s['mean']:+.3f}", "[{:.3f}, {:.3f}]".format(*s["ci95"]),
                         "[{:.3f}, {:.3f}]".format(*s["ci_bonferroni"]), ", ".join(s["vehicles_wholly_above_0"]) or "-"])
    return rows


def run_cells(argv, description: str, results: Path, vehicles: Sequence[str], protocols: Sequence[str],
              measure_cell: Callable, analyse: Callable[[dict], dict], report: Callable[[dict, dict], str]) -> int:
    """A study's command line (--cache, --workers, --analyse-only, --results): ``measure_cell(vehicle, protocol,
    cache, workers, progress)`` for every cell not yet in ``results``, then, with every cell in, ``analyse(found)``
    to ``results/results.json`` and ``report(found, result)`` to ``results/results.md`` (and stdout); the log to
    ``results/run.log``. ``found``: {(vehicle, protocol): the cell's JSON}. ``--results DIR`` keeps a measurement
    with other detectors (``$RIGOPT_DETECTORS``) apart from the study's own."""
    from rigopt.output import write_text_atomic

    parser = argparse.ArgumentParser(description=description)
    add_measuring_options(parser)
    parser.add_argument("--analyse-only", action="store_true")
    parser.add_argument("--results", type=Path, default=results, help=f"the cells and analysis (default {results})")
    args = parser.parse_args(argv)
    results = args.results
    results.mkdir(parents=True, exist_ok=True)
    found = {}
    with timestamped_log(results / "run.log") as progress:
        for protocol in protocols:
            for vehicle in vehicles:
                path = results / f"{vehicle}_{protocol}.json"
                if not path.is_file() and not args.analyse_only:
                    cell = measure_cell(vehicle, protocol, args.cache, args.workers, progress)
                    write_text_atomic(path, json.dumps(cell, indent=1) + "\n")
                if path.is_file():
                    found[(vehicle, protocol)] = json.loads(path.read_text())
    if len(found) < len(vehicles) * len(protocols):
        print(f"{len(found)} of {len(vehicles) * len(protocols)} (vehicle, scenes) measured; analysis waits")
        return 0
    result = analyse(found)
    write_text_atomic(results / "results.json", json.dumps(result, indent=1) + "\n")
    write_text_atomic(results / "results.md", report(found, result))
    print(report(found, result))
    return 0
