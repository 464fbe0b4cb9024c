"""``rigopt check``, ``rigopt vehicles`` and ``rigopt vehicle show|export|add``."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import Optional

import typer

from rigopt.cli.app import (MIN_HEIGHT_HELP, NO_TRAILER_HELP, PICTURE_SUFFIXES, app, console, mount_rules, note,
                            note_vehicle, print_json, print_next, print_table, vehicle_app)
from rigopt.errors import RigoptError


@app.command("check")
def check_command(
    rig: str = typer.Argument(..., help="Library rig name or rig file."),
    vehicle: Optional[str] = typer.Option(None, help="Vehicle name, alias or blueprint (default: the rig's own); "
                                                     "the rig's origin is converted to the vehicle's centre."),
    min_height: Optional[float] = typer.Option(None, "--min-height", min=0.0, max=5.0, help=MIN_HEIGHT_HELP),
    no_trailer: bool = typer.Option(False, "--no-trailer", help=NO_TRAILER_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a table."),
):
    """Check that every camera can be mounted: on the surface, in a zone, housing and view clear of the body."""
    from rigopt.mounting.rules import check_rig
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.library import load_vehicle
    from rigopt.vehicle.placement import known_vehicle, place_rig

    loaded = load_rig(rig)
    on = load_vehicle(vehicle) if vehicle is not None else known_vehicle(loaded)
    if on is None:
        raise RigoptError(f"rig {loaded.name!r} is on {loaded.vehicle!r}, which is not a rigopt vehicle; add --vehicle "
                          "NAME to check it on one (see rigopt vehicles)")
    placed, change = place_rig(loaded, on, refuse_inside=False)  # check reports cameras inside the body itself
    result = check_rig(placed, on, mount_rules(min_height, no_trailer))
    note_vehicle(loaded, on, change)
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


#: Mesh formats ``vehicle export`` writes (trimesh picks the format from the extension).
MESH_SUFFIXES = (".ply", ".stl", ".obj", ".glb")
FRAME_HELP = "Frame of the mesh file: iso (x forward, y left, z up; rigopt's) or carla (y right)."


@app.command("vehicles")
def vehicles_command(as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a table.")):
    """List the known vehicles (built-in and your own) with their size and zones."""
    from rigopt.vehicle.library import broken_user_vehicles, load_vehicle, vehicle_names

    for folder, problem in broken_user_vehicles().items():
        typer.echo(f"rigopt: warning: user vehicle {folder!r} skipped: {problem}", err=True)
    rows = []
    for name in vehicle_names():
        try:
            v = load_vehicle(name)
        except RigoptError as error:  # a user vehicle whose spec reads but whose body does not (body.ply missing)
            typer.echo(f"rigopt: warning: user vehicle {name!r} skipped: {error}; add it again with rigopt vehicle "
                       f"add {name} --mesh FILE --force", err=True)
            continue
        rows.append({"vehicle": v.name, "blueprint": v.blueprint, "aliases": list(v.spec.aliases),
                     "category": v.category, "length": float(v.size[0]), "width": float(v.size[1]),
                     "height": float(v.size[2]), "zones": sorted({z.name for z in v.zones})})
    if as_json:
        print_json(rows)
        return
    print_table("vehicles", ["vehicle", "blueprint", "aliases", "category", "length (m)", "width (m)", "height (m)",
                             "zones"],
                [[r["vehicle"], r["blueprint"], ", ".join(r["aliases"]), r["category"], r["length"], r["width"],
                  r["height"], len(r["zones"])] for r in rows])


@vehicle_app.command("show")
def vehicle_show_command(
    name: str = typer.Argument(..., help="Vehicle name, alias or blueprint."),
    out: Path = typer.Option(..., "--out", help="Picture to write: .png (or .pdf, .svg, .jpg)."),
    rig: Optional[str] = typer.Option(None, "--rig", help="Draw this rig's cameras and frustums too."),
):
    """Draw top and side views of a vehicle with its zones coloured (and a rig's cameras), measured in the reports'
    frame (ISO 8855 from the ground below the rear axle's centre)."""
    import numpy as np

    from rigopt.coverage.packaging import report_origin
    from rigopt.output import atomic_file, check_out_file
    from rigopt.report.vehicle_figures import write_vehicle_figure
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.library import load_vehicle
    from rigopt.vehicle.placement import place_rig

    out = check_out_file(out, suffixes=PICTURE_SUFFIXES)
    vehicle, drawn = load_vehicle(name), None
    if rig:
        loaded = load_rig(rig)
        drawn, change = place_rig(loaded, vehicle, refuse_inside=False)
        note_vehicle(loaded, vehicle, change)
    datum = report_origin(vehicle)
    with atomic_file(out) as work:
        write_vehicle_figure(vehicle, work, drawn, datum)
    console.print(f"wrote {out}")
    features = vehicle.body_features()
    if features:
        def box(row) -> str:
            if row["min"] is None:
                return "-"
            low, high = (np.asarray(row[k]) - datum.point for k in ("min", "max"))
            return " .. ".join(", ".join(f"{v:.2f}" for v in corner) for corner in (low, high))

        print_table(f"body features of {vehicle.name} the mount rules read (boxes x, y, z m, {datum.frame})",
                    ["kind", "name", "note", "box (min .. max)"],
                    [[r["kind"], r["name"], r["note"] or "-", box(r)] for r in features])


@vehicle_app.command("export")
def vehicle_export_command(
    name: str = typer.Argument(..., help="Vehicle name, alias or blueprint."),
    out: Path = typer.Option(..., "--out", help="Mesh file to write; the format follows the extension (.ply .stl .obj .glb)."),
    frame: str = typer.Option("iso", help=FRAME_HELP),
):
    """Write a vehicle's body mesh in the internal (ISO) or the benchmark's CARLA frame."""
    from rigopt.output import atomic_file, check_out_file
    from rigopt.vehicle.library import load_vehicle
    from rigopt.vehicle.user import FRAMES, carla_mesh_to_iso

    if frame not in FRAMES:
        raise RigoptError(f"--frame must be one of {', '.join(FRAMES)}, got {frame!r}")
    out = check_out_file(out, suffixes=MESH_SUFFIXES)
    mesh = load_vehicle(name).mesh
    mesh = carla_mesh_to_iso(mesh) if frame == "carla" else mesh  # the reflection is its own inverse
    with atomic_file(out) as work:
        mesh.export(work)
    console.print(f"wrote {out} ({len(mesh.faces)} triangles, {frame} frame)")


def _parse_axles(text: str | None):
    if text is None:
        return None
    try:
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise RigoptError(f"--axles takes the x (m) of each axle separated by commas, e.g. 1.5,-1.4; got {text!r}") \
            from None


def _print_found(added, datum, zones_given: bool) -> None:
    """What ``vehicle add`` found on the mesh (an ``AddedVehicle``), each box measured from ``datum`` (ReportDatum)."""
    import numpy as np

    from rigopt.vehicle.supports import KEEP_OUT_REASON

    def span(box: dict, axes=(0, 2)) -> str:
        low, high = (np.asarray(box[k], dtype=float) - datum.point for k in ("min", "max"))
        return ", ".join(f"{'xyz'[a]} {low[a]:.2f}..{high[a]:.2f} m" for a in axes)

    narrow = [k for k in added.keep_outs if k["reason"] == KEEP_OUT_REASON]
    panes = [k for k in added.keep_outs if k["reason"] != KEEP_OUT_REASON]
    console.print(f"found on the mesh (x, y, z m, {datum.frame}):")
    if narrow:
        console.print(f"keep-outs: {len(narrow)} narrow part(s) where no housing fits (rails, ladders, bars): "
                      + "; ".join(f"{k['name']} {span(k)}" for k in narrow))
    if added.glass or panes:
        console.print("glass (parts its materials call glass): " + "; ".join(
            [f"{z['name']} zone {span(z)} (a camera there sits behind the glass)" for z in added.glass]
            + [f"{k['name']} {span(k, (0, 1, 2))} ({k['reason']})" for k in panes]))
    elif not zones_given:
        console.print("glass: no part of the file is marked glass (no material named glass or window, none "
                      "see-through): the windshield zones are the box's upper front and rear")
    named = [f for f in added.fixtures if f["kind"] != "mud_flap"]
    flaps = [f for f in added.fixtures if f["kind"] == "mud_flap"]
    if named:
        console.print("lamps and number plates (named by their materials), where no lens sits: " + "; ".join(
            f"{f['name']} {span(f, (0, 1, 2))}" for f in named))
    if flaps:
        console.print("mud flaps: thin plates hanging behind the tyres, where no lens sits: " + "; ".join(
            f"{f['name']} {span(f, (0, 1, 2))}" for f in flaps))
    if added.mirror:
        console.print(f"mirrors: the narrow parts high on the front that reach out beyond the side are mirror arms; "
                      f"the body outboard of the side around them ({span(added.mirror)}, both sides) is a 'mirror' "
                      "zone, where side and surround-view cameras mount (the arms stay keep-outs)")
    if added.treads:
        console.print("steps: patches facing up at step height, shallow enough to stand on, are treads where no lens "
                      "sits: " + "; ".join(f"{t['name']} {span(t, (0, 1))}" for t in added.treads)
                      + r" ([\[steps]] in vehicle.toml to change)")


@vehicle_app.command("add")
def vehicle_add_command(
    name: str = typer.Argument(..., help="Name to give the vehicle."),
    mesh: Path = typer.Option(..., "--mesh", help="Mesh file: OBJ, STL, PLY, GLB/GLTF, DAE (COLLADA) or OFF; the "
                              "parts of a scene are merged; open, multi-part or thin meshes are closed."),
    zones: Optional[Path] = typer.Option(None, "--zones", help="TOML file of \\[\\[zones]] tables (name, min, max, "
                                         "normal, cone_deg); default: zones from the body's box."),
    frame: str = typer.Option("iso", help=FRAME_HELP),
    scale: Optional[float] = typer.Option(None, "--scale", help="Multiply coordinates by this (metres per file "
                                          "unit): 0.01 for centimetres, 0.001 millimetres, 0.0254 inches; default: "
                                          "a COLLADA file's declared unit, else 1."),
    length: Optional[float] = typer.Option(None, "--length", help="Scale the mesh so that its length (longest "
                                           "extent) is this many metres (instead of --scale)."),
    forward: Optional[str] = typer.Option(None, "--forward", help="The file's axis that points to the front: +x "
                                          "-x +y -y (+z -z); default +x, checked against the shape."),
    up: Optional[str] = typer.Option(None, "--up", help="The file's axis that points up: +z or +y (-z -y +x -x); "
                                     "default +z, checked against the shape."),
    allow_size: bool = typer.Option(False, "--allow-size", help="Accept a size outside road-vehicle limits "
                                    "(length 2.5-25 m, width 1.4-3.0 m, height 1.0-4.5 m) with a warning."),
    ground: bool = typer.Option(False, "--ground", help="Put the mesh's lowest point on the ground (a mesh with "
                                "tyres is always stood on them)."),
    axles: Optional[str] = typer.Option(None, "--axles", help="x (m, from the centre of the body's footprint box, "
                                        "after the flags) of each axle, e.g. 1.5,-1.4; default: found from the "
                                        "tyres' ground contacts."),
    roof_rack: Optional[float] = typer.Option(None, "--roof-rack", help="Add a raised zone 'roof_rack' over the "
                                              "roof: cameras up to this many metres above it."),
    pitch: Optional[float] = typer.Option(None, "--pitch", help="Grid spacing (m) that closes an open or "
                                          "multi-part mesh; default: length / 200 within 1-4 cm."),
    force: bool = typer.Option(False, "--force", help="Replace a stored vehicle of the same name (any case)."),
    category: Optional[str] = typer.Option(None, "--category", help="UN vehicle category: M1, M2, M3 (carrying "
                                           "people), N1, N2, N3 (goods); sets the regulation fields required by "
                                           "default. Default: the one the shape suggests (stated, with why)."),
):
    """Check a mesh and store it as a vehicle so that --vehicle NAME works everywhere."""
    from rigopt.coverage.packaging import report_origin
    from rigopt.coverage.regulations import CATEGORY_DEFAULTS
    from rigopt.vehicle.library import load_vehicle
    from rigopt.vehicle.user import add_user_vehicle

    added = add_user_vehicle(name, mesh, zones, frame, force=force, scale=scale, length=length, forward=forward,
                             up=up, allow_size=allow_size, axles=_parse_axles(axles), roof_rack=roof_rack,
                             ground=ground, pitch=pitch, category=category)
    for warning in added.warnings:
        typer.echo(f"rigopt: warning: {warning}", err=True)
    for message in added.notes:
        note(message)
    console.print(f"mesh: {added.closing.describe()}")
    if added.wheels:
        console.print("wheels: " + "; ".join(f"axle x {w.x:.2f} m, radius {w.radius:.2f} m, track {w.track:.2f} m, "
                                             f"width {w.width:.2f} m" for w in added.wheels))
    else:
        console.print("wheels: none found (give --axles X1,X2 to set the axles)" if not added.axles else
                      f"axles: {', '.join(f'{x:.2f}' for x in added.axles)} m (given; no tyre found at them)")
    _print_found(added, report_origin(load_vehicle(name)), zones_given=zones is not None)
    console.print(f"category: {added.category}, {added.category_reason}; fields required by default: "
                  f"{', '.join(CATEGORY_DEFAULTS[added.category])} (--category, or category in vehicle.toml, to change)")
    console.print(f"added vehicle {name!r}: {added.path}")
    print_next(f"rigopt vehicle show {name} --out {name}.png (its zones, wheels and keep-outs, to check them)",
               f"rigopt design --vehicle {name} --ref R1 (a rig on it that transfers from the benchmark's R1)")
