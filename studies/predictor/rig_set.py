"""The predictor study's rigs: on each of eight vehicles, what the designer proposes beside variations of R1.

    python studies/predictor/rig_set.py [--vehicles ...]

writes ``studies/predictor/rigs/<rig>.json`` (benchmark JSON, the perception cameras only: what the shipped
detectors are fed) and ``rigs/index.csv`` (rig, vehicle, kind, setting and factor values). The files are
committed with the pre-registration (``preregistration.md``); this script is how they were made. The user-mesh
vehicle ``citybus`` (``examples/raw_bus.obj``) must have been added first (``rigopt vehicle add``, see
``preregistration.md``).

Per vehicle, all from the reference R1:

- ``design``: ``rigopt design --vehicle V --ref R1`` under each of DESIGN_SETTINGS (its perception cameras);
- ``naive``, ``height_matched``: R1's naive and height-matched transfers (``comparison_rigs``: ``rigopt validate
  --compare``'s yardsticks); ``hand``: the benchmark's hand-designed rigs of the vehicle;
- ``searched_copy``: the height-matched transfer with the designer's height search (``search_heights``, 0.75 m);
- ``swap``: the height-matched transfer with one camera at a time replaced by the default design's camera matched
  to the same R1 camera (only where the two differ);
- ``variation``: FACTORIAL_RIGS rigs of R1's layout placed on the body (the validation study's placement,
  ``studies/validation/rig_set.py``: on the outline at the matched R1 camera's height plus an offset) with
  factors drawn by a scrambled Sobol sequence (seed 0): height offset, pitch, roll, yaw turn, FOV, count and plan
  offset (FACTORS).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
OUT = HERE / "rigs"
sys.path.insert(0, str(HERE.parent / "validation"))  # the validation study's placement on the body's outline
sys.path.insert(0, str(HERE.parent))  # studies/: the studies' shared code (studylib)
from rig_set import Outline, layout_yaws, matched_heights  # noqa: E402
from studylib.tables import write_rig_index  # noqa: E402

VEHICLES = ("firetruck", "hgv", "tt", "etron", "renault_zoe", "ford_fusion_hybrid", "chrysler_pacifica_hybrid",
            "citybus")
#: The designer settings, as ``rigopt design`` flags.
DESIGN_SETTINGS = {"default": [], "no_height_search": ["--height-search", "0"], "free_pose": ["--pose", "free"],
                   "count_6_10": ["--cameras", "6-10"], "fov_90_120": ["--fov", "90,120"]}
FACTORIAL_RIGS = 24
#: Factor ranges: continuous (low, high) or levels drawn uniformly.
FACTORS = {"height_offset_m": (-0.4, 1.2), "pitch_deg": (-20.0, 8.0), "roll_deg": (-8.0, 8.0),
           "yaw_turn_deg": (-25.0, 25.0), "fov_deg": (50.0, 65.0, 90.0, 120.0), "cameras": (6, 8, 10, 12),
           "plan_offset_m": (0.0, 2.5)}
MIN_HEIGHT = 0.3  # m: no variation camera lower than this
COLUMNS = ["rig", "vehicle", "kind", "setting", *FACTORS]


def designs(vehicle: str, work: Path) -> dict[str, Path]:
    """{setting: report.json} of ``rigopt design --vehicle V --ref R1`` under each setting, written under ``work``."""
    rigopt = Path(sys.executable).parent / "rigopt"
    reports = {}
    for setting, flags in DESIGN_SETTINGS.items():
        out = work / f"{vehicle}_from_R1_{setting}"
        process = subprocess.run([str(rigopt), "design", "--vehicle", vehicle, "--ref", "R1", *flags, "--out", str(out),
                                  "--json"], capture_output=True, text=True)
        if process.returncode:
            print(f"{vehicle} {setting}: no design ({process.stderr.strip().splitlines()[-1]})", flush=True)
            continue
        reports[setting] = out / "report.json"
    return reports


def swaps(copy, report: Path) -> list:
    """The copy with each camera replaced by the design's camera matched to the same R1 camera, where they differ."""
    from rigopt.validation.designs import load_design

    design = load_design(report)
    matched = {row["id"]: row["matched_reference_camera"]["id"]
               for row in json.loads(report.read_text())["cameras"] if row["role"] == "perception"}
    by_reference = {matched[c.id]: c for c in design.cameras if c.id in matched}
    out = []
    for k, camera in enumerate(copy.cameras):
        moved = by_reference.get(camera.id)
        if moved is None or (np.allclose(moved.position, camera.position, atol=1e-3)
                             and np.allclose(moved.rotation, camera.rotation, atol=1e-6) and moved.lens == camera.lens):
            continue
        cameras = copy.cameras[:k] + (dataclasses.replace(moved, id=camera.id),) + copy.cameras[k + 1:]
        out.append(dataclasses.replace(copy, name=f"{copy.name}_swap_{camera.id}", cameras=cameras))
    return out


def searched_copy(copy, vehicle):
    """The height-matched copy with the designer's height search (each camera to the valid mount nearest its R1
    camera's height within 0.75 m), named ``<copy>_searched``."""
    from rigopt.design.defaults import NEAREST_POSE
    from rigopt.design.heights import search_heights
    from rigopt.design.settings import DesignSettings
    from rigopt.rig.library import load_rig

    reference = load_rig("R1")
    matched = np.array([[c.id for c in reference.cameras].index(c.id) for c in copy.cameras])
    moved, _ = search_heights(copy, matched, reference, vehicle, NEAREST_POSE["height_search_m"], DesignSettings(),
                              lambda rig: True)
    return dataclasses.replace(moved, name=f"{copy.name}_searched")


def factor_draws(n: int, seed: int) -> list[dict]:
    """n factor settings: the first n points of a scrambled Sobol sequence (``seed``) of the next power of 2."""
    from scipy.stats import qmc

    points = qmc.Sobol(len(FACTORS), scramble=True, seed=seed).random_base2(int(np.ceil(np.log2(n))))[:n]
    draws = []
    for row in points:
        values = {}
        for u, (name, span) in zip(row, FACTORS.items()):
            if name in ("fov_deg", "cameras"):
                values[name] = span[min(int(u * len(span)), len(span) - 1)]
            else:
                values[name] = round(span[0] + u * (span[1] - span[0]), 3)
        draws.append(values)
    return draws


def variation(vehicle_name: str, outline: Outline, reference, values: dict, k: int):
    """R1's layout of ``values['cameras']`` cameras on the body with the factors ``values``."""
    from rigopt.geometry import rotation_from_yaw_pitch_roll
    from rigopt.rig.model import Camera, Rig
    from rigopt.vehicle.library import load_vehicle

    yaws = layout_yaws(values["cameras"]) if values["cameras"] != 10 else np.arange(10) * 36.0
    heights = np.maximum(matched_heights(yaws, reference) + values["height_offset_m"], MIN_HEIGHT)
    cameras = []
    for j, (yaw, z) in enumerate(zip(yaws + values["yaw_turn_deg"], heights)):
        xy = outline.mount(yaw, z, values["plan_offset_m"])
        rotation = rotation_from_yaw_pitch_roll(np.radians(yaw), np.radians(values["pitch_deg"]),
                                                np.radians(values["roll_deg"]))
        cameras.append(Camera.pinhole(f"CAM_{j:02d}_YAW_{int(round(yaw)) % 360:03d}", np.array([xy[0], xy[1], z]),
                                      rotation, values["fov_deg"]))
    return Rig(f"{vehicle_name}_variation_{k:02d}", load_vehicle(vehicle_name).blueprint, tuple(cameras))


def vehicle_rigs(vehicle_name: str, work: Path, seed: int | None = None,
                 variations: int = FACTORIAL_RIGS) -> list[tuple[dict, object]]:
    """(index row, rig) of every rig of one vehicle; ``variations`` variations drawn with Sobol ``seed`` (default:
    the vehicle's index in VEHICLES)."""
    from rigopt.metrics.calibration import load_weights
    from rigopt.rig.library import load_rig
    from rigopt.validation.designs import comparison_rigs, load_design
    from rigopt.vehicle.library import load_vehicle

    vehicle, reference = load_vehicle(vehicle_name), load_rig("R1")
    out = []
    reports = designs(vehicle_name, work)
    for setting, report in reports.items():
        rig = load_design(report).perception()
        out.append(({"kind": "design", "setting": setting}, dataclasses.replace(rig, name=report.parent.name)))
    anchor = load_design(reports["default"]).perception()
    kinds = {"hand-designed": "hand", "naive transfer": "naive", "height-matched transfer": "height_matched"}
    copies = comparison_rigs(anchor, reference, load_weights("joint"))[1:]
    for role, rig in copies:
        out.append(({"kind": kinds[role]}, dataclasses.replace(rig, name=f"{vehicle_name}_{rig.name}")))
    copy = dict(copies).get("height-matched transfer")
    if copy is not None:
        copy = dataclasses.replace(copy, name=f"{vehicle_name}_{copy.name}")
        out.append(({"kind": "searched_copy"}, searched_copy(copy, vehicle)))
        out += [({"kind": "swap"}, rig) for rig in swaps(copy, reports["default"])]
    outline = Outline(vehicle.mesh)
    seed = VEHICLES.index(vehicle_name) if seed is None else seed
    for k, values in enumerate(factor_draws(variations, seed)):
        out.append(({"kind": "variation", **values}, variation(vehicle_name, outline, reference, values, k)))
    for row, rig in out:
        row.update(rig=rig.name, vehicle=vehicle_name)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", nargs="+", default=list(VEHICLES))
    args = parser.parse_args(argv)
    from rigopt.rig.pccr_format import write_rig

    OUT.mkdir(exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for vehicle_name in args.vehicles:
            made = vehicle_rigs(vehicle_name, Path(scratch))
            for row, rig in made:
                write_rig(rig, OUT / f"{rig.name}.json")
                rows.append(row)
            kinds = [row["kind"] for row, _ in made]
            print(f"{vehicle_name}: {len(made)} rigs ({', '.join(f'{k} {kinds.count(k)}' for k in dict.fromkeys(kinds))})",
                  flush=True)
    write_rig_index(OUT / "index.csv", COLUMNS, rows)
    print(f"{len(rows)} rigs on {len(args.vehicles)} vehicles in {OUT.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
