"""``rigopt rigs`` (the built-in library), ``rigopt import FORMAT PATH`` and ``rigopt export`` (docs/formats.md):
one command each way over the format registry (``rigopt.rig.formats.registry.FORMATS``); their help on which
format takes which option, and which formats write, comes from the light ``rigopt.rig.formats.catalogue``."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Optional

import typer

from rigopt.cli.app import app, console, note, print_json, print_next, print_table, status_console
from rigopt.cli.parsing import parse_image_size, parse_origin_offset
from rigopt.errors import RigoptError
from rigopt.rig.formats.catalogue import (AXLE_HEIGHT, CALIBRATION, CAMERAS, IMAGE_SIZE, LIST, LOG, RAW_LENS,
                                          SCENE, SEGMENT, SPECS, ImportOption, taking, writing)


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


def parse_image_sizes(text: str) -> dict:
    """``"1600x900"`` or ``"1600x900,CAM_FRONT=1920x1080"`` -> {None: default, channel: size}."""
    sizes = {}
    for part in text.split(","):
        channel, _, size = part.strip().rpartition("=")
        sizes[channel.strip() or None] = parse_image_size(size)
    return sizes


ORIGIN_HELP = ("Where the file's positions are measured from: vehicle_centre, rear_axle, or custom (a point given by "
               "--origin-offset); default: the format's own, see docs/formats.md.")
ORIGIN_OFFSET_HELP = ("With --origin custom: X,Y,Z metres from the vehicle centre on the ground (ISO 8855: x forward, "
                      "y left, z up) to the point the file's positions are measured from.")
OUT_HELP = "Rig file to write (rigopt's rig JSON)."
IMPORT_FORCE_HELP = "Replace an existing --out file."


def _origin(text: str | None, offset: str | None):
    """The RigOrigin of ``--origin`` and ``--origin-offset`` (None when neither is given: the format's own)."""
    from rigopt.rig.model import ORIGIN_KINDS, RigOrigin

    if text is None:
        if offset is not None:
            raise RigoptError("--origin-offset needs --origin custom (it places the custom origin)")
        return None
    if text not in ORIGIN_KINDS:
        raise RigoptError(f"--origin must be one of {', '.join(ORIGIN_KINDS)}, got {text!r}")
    if text != "custom":
        if offset is not None:
            raise RigoptError(f"--origin-offset goes with --origin custom, not --origin {text}; drop one")
        return RigOrigin(text)
    if offset is None:
        raise RigoptError("--origin custom needs --origin-offset X,Y,Z: the origin's place in metres from the vehicle "
                          "centre on the ground (x forward, y left, z up), e.g. --origin-offset -1.4,0,0.3")
    return RigOrigin("custom", parse_origin_offset(offset))


def _check_vehicle(vehicle):
    """A --vehicle must name a rigopt vehicle (name, alias or CARLA blueprint)."""
    if vehicle is not None:
        from rigopt.vehicle.library import find_spec

        find_spec(vehicle)


def _check_out(out, force: bool, listing: bool) -> Path | None:
    from rigopt.output import check_out_file

    if out is None:
        if listing:
            return None
        raise RigoptError("--out is missing; give the rig file to write, e.g. --out rig.json")
    out = check_out_file(out, suffixes=(".json",))
    if out.exists() and not force:
        raise RigoptError(f"--out {out}: the file exists; add --force to replace it, or choose another --out")
    return out


def _finish_import(imported, out: Path, as_json: bool, source: str) -> None:
    """Write the imported rig, print the notes on stderr and a summary (or JSON) on stdout. Cameras closer than a
    module's size (calibration files say nothing of housings) are written as one module, noted."""
    from rigopt.mounting.practice import as_modules
    from rigopt.mounting.records import MountPractice
    from rigopt.output import atomic_file
    from rigopt.rig.pccr_format import write_rig

    rig = as_modules(imported.rig)
    notes = list(imported.notes)
    grouped = [f"{c.id} in {c.module}" for c, before in zip(rig.cameras, imported.rig.cameras)
               if c.module != before.module]
    if grouped:
        notes.append(f"cameras closer than {MountPractice().module_distance:g} m share one housing, as the mount rules "
                     f"ask: written as modules ({', '.join(grouped)})")
    with atomic_file(out) as work:
        write_rig(rig, work)
    for line in notes:
        status_console.print(line, highlight=False, markup=False, soft_wrap=True)
    if as_json:
        print_json({"rig": rig.name, "vehicle": rig.vehicle, "out": str(out), "source": source,
                    "origin": rig.origin.kind, "notes": notes,
                    "cameras": [_camera_row(c) for c in rig.cameras]})
        return
    console.print(f"wrote {out}: {len(rig)} cameras ({', '.join(c.id for c in rig.cameras)})", highlight=False,
                  markup=False, soft_wrap=True)
    print_next(f"rigopt check {out} (is every camera mountable on {rig.vehicle}?)",
               f"rigopt rigcd R1 {out} (distance and predicted drop from a benchmark rig)",
               f"rigopt coverage {out} --out {out.with_suffix('')}-coverage (what it sees around its vehicle)")


def _camera_row(camera) -> dict:
    lens = camera.lens
    return {"id": camera.id, "image_size": list(camera.image_size), "hfov": lens.hfov, "vfov": lens.vfov,
            "distortion": lens.distortion, "position": [float(v) for v in camera.position]}


def _print_listing(rows: list[dict], as_json: bool, title: str) -> None:
    if as_json:
        print_json(rows)
        return
    columns = [k for k in rows[0] if not k.startswith("_")] if rows else ["calibration"]
    print_table(title, columns, [[", ".join(map(str, r[c])) if isinstance(r[c], list) else r[c] for c in columns]
                                 for r in rows])


def _listed(specs) -> str:
    """``a (its summary), b (...) or c``."""
    names = [f"{s.name} ({s.summary})" for s in specs]
    return f"{', '.join(names[:-1])} or {names[-1]}"


def _option_help(option: ImportOption, defaults: str = "") -> str:
    """``option``'s help after the formats that take it (``nuscenes, dgp: ...``)."""
    return f"{', '.join(s.name for s in taking(option))}: {option.help}{defaults}."


def _image_size_defaults() -> str:
    """`` (nuscenes 1600x900, per channel: 1600x900,CAM_BACK=1440x900; dgp 1936x1216)``."""
    sizes = [f"{s.name} {s.image_size}" + (f", per channel: {s.image_size},{s.channel_size}" if s.channel_size else "")
             for s in taking(IMAGE_SIZE)]
    return f" ({'; '.join(sizes)})"


FORMAT_HELP = f"The file's format (docs/formats.md): {_listed(SPECS.values())}."
EXPORT_FORMAT_HELP = f"{_listed(writing())}."
EXPORT_OUT_HELP = (f"Folder ({', '.join(s.name for s in writing() if s.suffixes is None)}) or file "
                   f"({', '.join(s.suffixes[0] for s in writing() if s.suffixes is not None)}) to write.")


@app.command("import")
def import_command(
    format_name: str = typer.Argument(..., metavar="FORMAT", help=FORMAT_HELP),
    path: Path = typer.Argument(..., help="The calibration file or folder (each format's is in docs/formats.md)."),
    out: Optional[Path] = typer.Option(None, "--out", help=OUT_HELP),
    vehicle: Optional[str] = typer.Option(None, help="The rigopt vehicle the rig is on (default: the format's name; "
                                                     "carla: the file's)."),
    name: Optional[str] = typer.Option(None, help="The rig's name (default: the log's, scene's, segment's or file's)."),
    origin: Optional[str] = typer.Option(None, help=ORIGIN_HELP),
    origin_offset: Optional[str] = typer.Option(None, "--origin-offset", help=ORIGIN_OFFSET_HELP),
    calibration: Optional[int] = typer.Option(None, CALIBRATION.flag, help=_option_help(CALIBRATION)),
    list_: bool = typer.Option(False, LIST.flag, help=_option_help(LIST)),
    image_size: Optional[str] = typer.Option(None, IMAGE_SIZE.flag,
                                             help=_option_help(IMAGE_SIZE, _image_size_defaults())),
    log: Optional[str] = typer.Option(None, LOG.flag, help=_option_help(LOG)),
    scene: Optional[str] = typer.Option(None, SCENE.flag, help=_option_help(SCENE)),
    segment: Optional[str] = typer.Option(None, SEGMENT.flag, help=_option_help(SEGMENT)),
    cameras: Optional[str] = typer.Option(None, CAMERAS.flag, help=_option_help(CAMERAS)),
    raw_lens: bool = typer.Option(False, RAW_LENS.flag, help=_option_help(RAW_LENS)),
    axle_height: Optional[float] = typer.Option(None, AXLE_HEIGHT.flag, help=_option_help(AXLE_HEIGHT)),
    force: bool = typer.Option(False, "--force", help=IMPORT_FORCE_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a summary."),
):
    """Read a rig from another format's calibration and write it as a rig file (rigopt's, the benchmark's JSON).

    Each format's options are marked with its name."""
    from rigopt.rig.formats.registry import ImportRequest, find_format

    fmt = find_format(format_name)
    # Each format-bound option's value as parsed (None or False: not given).
    values = {CALIBRATION: calibration, LIST: list_, IMAGE_SIZE: image_size, LOG: log, SCENE: scene,
              SEGMENT: segment, CAMERAS: cameras, RAW_LENS: raw_lens, AXLE_HEIGHT: axle_height}
    foreign = [o.flag for o, value in values.items()
               if value is not None and value is not False and o not in fmt.spec.options]
    if foreign:
        takes = sorted(o.flag for o in fmt.spec.options)
        raise RigoptError(f"{', '.join(foreign)}: not an option of {format_name} (it takes "
                          f"{', '.join(takes) or 'none beyond --out, --vehicle, --name, --origin'}); drop "
                          f"{'them' if len(foreign) > 1 else 'it'}")
    sizes = parse_image_sizes(image_size or fmt.spec.image_size) if IMAGE_SIZE in fmt.spec.options else None
    if sizes is not None and fmt.spec.channel_size is None and set(sizes) != {None}:
        raise RigoptError(f"--image-size {image_size}: {format_name} takes one WIDTHxHEIGHT for every camera")
    request = ImportRequest(path, name, vehicle, None, calibration, sizes, log, scene, segment, cameras or "ring",
                            raw_lens, axle_height)
    if list_:
        _print_listing(fmt.listing(request), as_json, f"distinct calibrations in {path}")
        return
    out = _check_out(out, force, False)
    _check_vehicle(vehicle)
    _finish_import(fmt.read(replace(request, origin=_origin(origin, origin_offset))), out, as_json, format_name)


@app.command("export")
def export_command(
    rig: str = typer.Argument(..., help="Library rig name or rig JSON file."),
    format_name: str = typer.Option(..., "--format", help=EXPORT_FORMAT_HELP),
    out: Path = typer.Option(..., "--out", help=EXPORT_OUT_HELP),
    force: bool = typer.Option(False, "--force", help="Replace an existing --out."),
    perception: bool = typer.Option(False, "--perception",
                                    help="Write only the perception cameras (the ones a detector is fed; e.g. a "
                                         "CARLA spawn list to render training data), not the near-field ones."),
):
    """Write a rig in another format; what the format cannot carry is said on stderr (docs/formats.md).

    Positions are converted to the origin the format assumes (nuScenes: the rear axle; the others: the vehicle
    centre) when rigopt knows the rig's vehicle, and the conversion is noted; otherwise they are written
    unchanged, with a warning."""
    from rigopt.output import atomic_file, atomic_folder, check_out_file, check_out_folder
    from rigopt.rig.formats.registry import find_format
    from rigopt.rig.library import load_rig
    from rigopt.rig.model import RigOrigin
    from rigopt.vehicle.placement import convert_origin, known_vehicle

    fmt = find_format(format_name, writing=True)
    suffixes = fmt.spec.suffixes
    if suffixes is None:
        out = check_out_folder(out, force=force)
    else:
        out = check_out_file(out, suffixes=suffixes)
        if out.exists() and not force:
            raise RigoptError(f"--out {out}: the file exists; add --force to replace it, or choose another --out")
    loaded = load_rig(rig)
    if perception and loaded.near_field_count:
        note(f"{loaded.name}: its {loaded.near_field_count} near_field camera(s) left out (--perception)")
        loaded = loaded.perception()
    vehicle = known_vehicle(loaded)
    if vehicle is not None:
        loaded, change = convert_origin(loaded, vehicle, RigOrigin(fmt.spec.origin))
        if change is not None:
            note(change.describe())
    exported = fmt.write(loaded)
    if suffixes is None:
        with atomic_folder(out, force=force) as work:
            for file_name, text in exported.files.items():
                (work / file_name).write_text(text)
    else:
        with atomic_file(out) as work:
            Path(work).write_text(exported.files[""])
    for warning in exported.warnings:
        status_console.print(f"warning: {warning}", highlight=False, markup=False, soft_wrap=True)
    console.print(f"wrote {out}: {loaded.name} as {format_name} ({len(loaded)} cameras)", highlight=False,
                  markup=False, soft_wrap=True)
    print_next(f"load it in its tool (docs/formats.md, section on {format_name}, says how); "
               f"rigopt import {format_name} {out} --out back.json reads it back as the same rig")
