"""``rigopt rigs`` (the built-in library) and ``rigopt import nuscenes`` (rigs from calibration tables)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from rigopt.cli.app import app, console, import_app, print_json, print_table
from rigopt.errors import RigoptError


@app.command("rigs")
def rigs_command(as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a table.")):
    """List the built-in rigs (the PCCR benchmark's 14): vehicle, camera count, FOVs, RigV."""
    from rigopt.metrics.rigv import rigv
    from rigopt.rig.library import library_rig, rig_names

    rows = []
    for name in rig_names():
        rig = library_rig(name)
        fovs = sorted(set(float(f) for f in rig.fovs))
        rows.append({"rig": name, "vehicle": rig.vehicle, "cameras": len(rig), "fovs": fovs, "rigv": rigv(rig).rigv})
    if as_json:
        print_json(rows)
        return
    print_table("rigopt rig library", ["rig", "vehicle", "cameras", "fovs", "rigv"],
                [[r["rig"], r["vehicle"], r["cameras"], ", ".join(f"{f:g}" for f in r["fovs"]), r["rigv"]] for r in rows])


def parse_image_size(text: str) -> tuple[int, int]:
    """``"1600x900"`` -> (1600, 900); raises RigoptError on anything else."""
    parts = text.lower().split("x")
    if len(parts) != 2 or not all(p.strip().isdigit() and int(p) > 0 for p in parts):
        raise RigoptError(f"--image-size must look like WIDTHxHEIGHT in pixels, e.g. 1600x900; got {text!r}")
    return int(parts[0]), int(parts[1])


@import_app.command("nuscenes")
def import_nuscenes_command(
    directory: Path = typer.Argument(..., help="Folder with the nuScenes tables sensor.json and calibrated_sensor.json."),
    out: Path = typer.Option(..., "--out", help="Rig file to write (the benchmark's JSON format)."),
    image_size: str = typer.Option("1600x900", help="Image size WIDTHxHEIGHT of the cameras, in pixels."),
    index: Optional[int] = typer.Option(None, help="Which calibration of each channel to take (0-based, file "
                                                   "order) when a channel has several different ones."),
    vehicle: str = typer.Option("nuscenes", help="Vehicle name written as the rig's vehicle_type."),
):
    """Read a rig from nuScenes calibration tables (camera channels only) and write it as a rig file."""
    from rigopt.output import atomic_file, check_out_file
    from rigopt.rig.nuscenes_format import read_nuscenes_rig
    from rigopt.rig.pccr_format import write_rig

    out = check_out_file(out, suffixes=(".json",))
    rig = read_nuscenes_rig(directory, image_size=parse_image_size(image_size), index=index, vehicle=vehicle)
    with atomic_file(out) as work:
        write_rig(rig, work)
    console.print(f"wrote {out}: {len(rig)} cameras ({', '.join(c.id for c in rig.cameras)})")
