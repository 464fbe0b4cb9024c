"""``rigopt check``: mount validity of a rig's cameras on a vehicle."""

from __future__ import annotations

from dataclasses import asdict
from typing import Optional

import typer

from rigopt.cli.app import app, print_json, print_table
from rigopt.rig.library import load_rig


@app.command("check")
def check_command(
    rig: str = typer.Argument(..., help="Library rig name or rig file."),
    vehicle: Optional[str] = typer.Option(None, help="Vehicle name, alias or blueprint (default: the rig's own)."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a table."),
):
    """Check that every camera can be mounted: on the surface, in a zone, housing and view clear of the body."""
    from rigopt.collision import check_rig
    from rigopt.vehicle.library import load_vehicle

    loaded = load_rig(rig)
    result = check_rig(loaded, load_vehicle(vehicle or loaded.vehicle))
    if as_json:
        print_json({"rig": result.rig, "vehicle": result.vehicle,
                    "cameras": [{**asdict(c), "problems": list(c.problems)} for c in result.cameras]})
    else:
        print_table(f"{result.rig} on {result.vehicle}: {'valid' if result.valid else 'INVALID'}",
                    ["camera", "valid", "distance (cm)", "zone", "problems"],
                    [[c.id, "yes" if c.valid else "NO", c.distance_to_surface * 100, c.zone or "-",
                      "; ".join(c.problems) or "-"] for c in result.cameras])
    if not result.valid:
        raise typer.Exit(1)
