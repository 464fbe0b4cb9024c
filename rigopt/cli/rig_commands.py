"""``rigopt rigs`` (the built-in library), ``rigopt import FORMAT`` and ``rigopt export`` (docs/formats.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from rigopt.cli.app import app, console, import_app, note, print_json, print_next, print_table, status_console
from rigopt.cli.parsing import parse_image_size, parse_origin_offset
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
    """Write the imported rig, print the notes on stderr and a summary (or JSON) on stdout."""
    from rigopt.output import atomic_file
    from rigopt.rig.pccr_format import write_rig

    rig = imported.rig
    with atomic_file(out) as work:
        write_rig(rig, work)
    for note in imported.notes:
        status_console.print(note, highlight=False, markup=False, soft_wrap=True)
    if as_json:
        print_json({"rig": rig.name, "vehicle": rig.vehicle, "out": str(out), "source": source,
                    "origin": rig.origin.kind, "notes": list(imported.notes),
                    "cameras": [_camera_row(c) for c in rig.cameras]})
        return
    console.print(f"wrote {out}: {len(rig)} cameras ({', '.join(c.id for c in rig.cameras)})", highlight=False,
                  markup=False, soft_wrap=True)
    print_next(f"rigopt check {out} (is every camera mountable on {rig.vehicle}?)",
               f"rigopt rigcd R1 {out} (distance and predicted drop from a benchmark rig)",
               f"rigopt coverage {out} --out {out.with_suffix('')}-coverage (what it sees around its vehicle)")


def _camera_row(camera) -> dict:
    lens = camera.lens_model
    return {"id": camera.id, "image_size": list(camera.image_size), "hfov": lens.hfov, "vfov": lens.vfov,
            "distortion": lens.distortion, "position": [float(v) for v in camera.position]}


def _print_listing(rows: list[dict], as_json: bool, title: str) -> None:
    if as_json:
        print_json(rows)
        return
    columns = [k for k in rows[0] if not k.startswith("_")] if rows else ["calibration"]
    print_table(title, columns, [[", ".join(map(str, r[c])) if isinstance(r[c], list) else r[c] for c in columns]
                                 for r in rows])


@import_app.command("nuscenes")
def import_nuscenes_command(
    directory: Path = typer.Argument(..., help="nuScenes table folder (sensor.json, calibrated_sensor.json; "
                                               "sample_data, sample, scene and log tables where present)."),
    out: Optional[Path] = typer.Option(None, "--out", help=OUT_HELP),
    log: Optional[str] = typer.Option(None, help="Take the calibration this log used (logfile name or token)."),
    scene: Optional[str] = typer.Option(None, help="Take the calibration this scene used (name or token)."),
    calibration: Optional[int] = typer.Option(None, help="Take the K-th distinct calibration (0-based; --list)."),
    list_: bool = typer.Option(False, "--list", help="List the distinct calibrations with their logs and vehicles."),
    image_size: str = typer.Option("1600x900", help="Image size WIDTHxHEIGHT where sample_data gives none; "
                                                    "per channel: 1600x900,CAM_BACK=1440x900."),
    vehicle: Optional[str] = typer.Option(None, help="The rigopt vehicle the rig is on (default: nuscenes)."),
    name: Optional[str] = typer.Option(None, help="The rig's name (default: the log's or the folder's)."),
    origin: Optional[str] = typer.Option(None, help=ORIGIN_HELP),
    origin_offset: Optional[str] = typer.Option(None, "--origin-offset", help=ORIGIN_OFFSET_HELP),
    force: bool = typer.Option(False, "--force", help=IMPORT_FORCE_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a summary."),
):
    """Read a rig from nuScenes calibration tables (camera channels, rectified) and write it as a rig file."""
    from rigopt.rig.formats.nuscenes import describe_calibrations, nuscenes_calibrations, read_nuscenes

    sizes = parse_image_sizes(image_size)
    if list_:
        _print_listing(describe_calibrations(nuscenes_calibrations(directory, sizes)), as_json,
                       f"distinct calibrations in {directory}")
        return
    out = _check_out(out, force, False)
    _check_vehicle(vehicle)
    imported = read_nuscenes(directory, sizes, calibration, log, scene, name, vehicle or "nuscenes", _origin(origin, origin_offset))
    _finish_import(imported, out, as_json, "nuscenes")


@import_app.command("argoverse1")
def import_argoverse1_command(
    path: Path = typer.Argument(..., help="Argoverse 1 log folder (holding vehicle_calibration_info.json) or the "
                                          "file itself."),
    out: Optional[Path] = typer.Option(None, "--out", help=OUT_HELP),
    cameras: str = typer.Option("ring", help="ring (the seven ring cameras) or all (and the two stereo cameras)."),
    raw_lens: bool = typer.Option(False, "--raw-lens", help="Keep the lenses' radial distortion (radtan k1, k2, 0, 0, "
                                                            "k3) instead of the pinholes of the undistorted images."),
    axle_height: Optional[float] = typer.Option(None, help="The rear axle's height above the ground in metres, by "
                                                           "which positions are raised (default: 0.328, the Ford "
                                                           "Fusion Hybrid's tyre radius)."),
    vehicle: Optional[str] = typer.Option(None, help="The rigopt vehicle the rig is on (default: argoverse1)."),
    name: Optional[str] = typer.Option(None, help="The rig's name (default: the log folder's)."),
    origin: Optional[str] = typer.Option(None, help=ORIGIN_HELP),
    origin_offset: Optional[str] = typer.Option(None, "--origin-offset", help=ORIGIN_OFFSET_HELP),
    force: bool = typer.Option(False, "--force", help=IMPORT_FORCE_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a summary."),
):
    """Read a rig from Argoverse 1 calibration (vehicle_calibration_info.json of argoverse-api)."""
    from rigopt.rig.formats.argoverse1 import read_argoverse1

    out = _check_out(out, force, False)
    _check_vehicle(vehicle)
    imported = read_argoverse1(path, name, vehicle or "argoverse1", _origin(origin, origin_offset), axle_height,
                               cameras, raw_lens)
    _finish_import(imported, out, as_json, "argoverse1")


@import_app.command("argoverse2")
def import_argoverse2_command(
    path: Path = typer.Argument(..., help="Argoverse 2 log folder (holding calibration/) or its calibration/ folder."),
    out: Optional[Path] = typer.Option(None, "--out", help=OUT_HELP),
    vehicle: Optional[str] = typer.Option(None, help="The rigopt vehicle the rig is on (default: argoverse2)."),
    name: Optional[str] = typer.Option(None, help="The rig's name (default: the log folder's)."),
    origin: Optional[str] = typer.Option(None, help=ORIGIN_HELP),
    origin_offset: Optional[str] = typer.Option(None, "--origin-offset", help=ORIGIN_OFFSET_HELP),
    force: bool = typer.Option(False, "--force", help=IMPORT_FORCE_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a summary."),
):
    """Read a rig from Argoverse 2 calibration (egovehicle_SE3_sensor.feather, intrinsics.feather)."""
    from rigopt.rig.formats.datasets import read_argoverse2

    out = _check_out(out, force, False)
    _check_vehicle(vehicle)
    _finish_import(read_argoverse2(path, name, vehicle or "argoverse2", _origin(origin, origin_offset)), out, as_json, "argoverse2")


@import_app.command("dgp")
def import_dgp_command(
    path: Path = typer.Argument(..., help="DGP (DDAD) scene folder (calibration/*.json, scene*.json) or a "
                                          "calibration JSON."),
    out: Optional[Path] = typer.Option(None, "--out", help=OUT_HELP),
    calibration: Optional[int] = typer.Option(None, help="Take the K-th distinct calibration (0-based; --list)."),
    list_: bool = typer.Option(False, "--list", help="List the distinct calibrations with their files."),
    image_size: str = typer.Option("1936x1216", help="Image size WIDTHxHEIGHT where no scene JSON gives one."),
    vehicle: Optional[str] = typer.Option(None, help="The rigopt vehicle the rig is on (default: dgp)."),
    name: Optional[str] = typer.Option(None, help="The rig's name (default: the scene folder's)."),
    origin: Optional[str] = typer.Option(None, help=ORIGIN_HELP),
    origin_offset: Optional[str] = typer.Option(None, "--origin-offset", help=ORIGIN_OFFSET_HELP),
    force: bool = typer.Option(False, "--force", help=IMPORT_FORCE_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a summary."),
):
    """Read a rig from a DGP (DDAD) calibration JSON (names, intrinsics, extrinsics)."""
    from rigopt.rig.formats.datasets import dgp_calibrations, read_dgp

    size = parse_image_size(image_size)
    if list_:
        _print_listing(dgp_calibrations(path, size), as_json, f"distinct calibrations in {path}")
        return
    out = _check_out(out, force, False)
    _check_vehicle(vehicle)
    _finish_import(read_dgp(path, size, calibration, name, vehicle or "dgp", _origin(origin, origin_offset)), out, as_json, "dgp")


@import_app.command("waymo")
def import_waymo_command(
    path: Path = typer.Argument(..., help="Waymo v2 camera_calibration Parquet file or v1 Frame .tfrecord file, or "
                                          "a folder of them."),
    out: Optional[Path] = typer.Option(None, "--out", help=OUT_HELP),
    segment: Optional[str] = typer.Option(None, help="Take this segment's calibration (key.segment_context_name)."),
    calibration: Optional[int] = typer.Option(None, help="Take the K-th distinct calibration (0-based; --list)."),
    list_: bool = typer.Option(False, "--list", help="List the distinct calibrations with their segments."),
    vehicle: Optional[str] = typer.Option(None, help="The rigopt vehicle the rig is on (default: waymo)."),
    name: Optional[str] = typer.Option(None, help="The rig's name (default: the segment's)."),
    origin: Optional[str] = typer.Option(None, help=ORIGIN_HELP),
    origin_offset: Optional[str] = typer.Option(None, "--origin-offset", help=ORIGIN_OFFSET_HELP),
    force: bool = typer.Option(False, "--force", help=IMPORT_FORCE_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a summary."),
):
    """Read a rig from the Waymo Open Dataset: v2 camera_calibration (Parquet) or v1 Frame TFRecords."""
    from rigopt.rig.formats.datasets import read_waymo, waymo_calibrations

    if list_:
        rows = [{"calibration": k, "cameras": [c.id for c in g["cameras"]], "segments": g["segments"]}
                for k, g in enumerate(waymo_calibrations(path))]
        _print_listing(rows, as_json, f"distinct calibrations in {path}")
        return
    out = _check_out(out, force, False)
    _check_vehicle(vehicle)
    imported = read_waymo(path, calibration, segment, name, vehicle or "waymo", _origin(origin, origin_offset))
    _finish_import(imported, out, as_json, "waymo")


@import_app.command("opencv")
def import_opencv_command(
    path: Path = typer.Argument(..., help="Kalibr / OpenCV camchain YAML (cam0, cam1, ...)."),
    out: Optional[Path] = typer.Option(None, "--out", help=OUT_HELP),
    vehicle: Optional[str] = typer.Option(None, help="The rigopt vehicle the rig is on (default: opencv)."),
    name: Optional[str] = typer.Option(None, help="The rig's name (default: the file's stem)."),
    origin: Optional[str] = typer.Option(None, help=ORIGIN_HELP),
    origin_offset: Optional[str] = typer.Option(None, "--origin-offset", help=ORIGIN_OFFSET_HELP),
    force: bool = typer.Option(False, "--force", help=IMPORT_FORCE_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a summary."),
):
    """Read a rig from a Kalibr camchain YAML (pinhole cameras, radtan or equidistant distortion)."""
    from rigopt.rig.formats.opencv import read_camchain

    out = _check_out(out, force, False)
    _check_vehicle(vehicle)
    _finish_import(read_camchain(path, name, vehicle or "opencv", _origin(origin, origin_offset)), out, as_json, "opencv")


@import_app.command("urdf")
def import_urdf_command(
    path: Path = typer.Argument(..., help="URDF with <gazebo> camera sensors (as rigopt export writes)."),
    out: Optional[Path] = typer.Option(None, "--out", help=OUT_HELP),
    vehicle: Optional[str] = typer.Option(None, help="The rigopt vehicle the rig is on (default: urdf)."),
    name: Optional[str] = typer.Option(None, help="The rig's name (default: the robot's name)."),
    origin: Optional[str] = typer.Option(None, help=ORIGIN_HELP),
    origin_offset: Optional[str] = typer.Option(None, "--origin-offset", help=ORIGIN_OFFSET_HELP),
    force: bool = typer.Option(False, "--force", help=IMPORT_FORCE_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a summary."),
):
    """Read a rig from a ROS URDF: camera links under the root link, SDFormat camera sensors."""
    from rigopt.rig.formats.urdf import read_urdf

    out = _check_out(out, force, False)
    _check_vehicle(vehicle)
    _finish_import(read_urdf(path, name, vehicle or "urdf", _origin(origin, origin_offset)), out, as_json, "urdf")


@import_app.command("carla")
def import_carla_command(
    path: Path = typer.Argument(..., help="CARLA camera spawn list JSON (as rigopt export writes)."),
    out: Optional[Path] = typer.Option(None, "--out", help=OUT_HELP),
    vehicle: Optional[str] = typer.Option(None, help="The rigopt vehicle the rig is on (default: the file's)."),
    name: Optional[str] = typer.Option(None, help="The rig's name (default: the file's)."),
    origin: Optional[str] = typer.Option(None, help=ORIGIN_HELP),
    origin_offset: Optional[str] = typer.Option(None, "--origin-offset", help=ORIGIN_OFFSET_HELP),
    force: bool = typer.Option(False, "--force", help=IMPORT_FORCE_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a summary."),
):
    """Read a rig from a CARLA camera spawn list (sensor.camera.rgb blueprints and transforms)."""
    from rigopt.rig.formats.carla import read_carla

    out = _check_out(out, force, False)
    _check_vehicle(vehicle)
    _finish_import(read_carla(path, name, vehicle, _origin(origin, origin_offset)), out, as_json, "carla")


@app.command("export")
def export_command(
    rig: str = typer.Argument(..., help="Library rig name or rig JSON file."),
    format_name: str = typer.Option(..., "--format", help="nuscenes (a folder of tables), urdf, opencv (Kalibr "
                                                          "camchain YAML) or carla (spawn list JSON)."),
    out: Path = typer.Option(..., "--out", help="Folder (nuscenes) or file (.urdf, .yaml, .json) to write."),
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
    from rigopt.rig.formats import EXPORT_FORMATS, EXPORT_ORIGINS, EXPORT_SUFFIXES, export_rig
    from rigopt.rig.library import load_rig
    from rigopt.rig.model import RigOrigin
    from rigopt.vehicle.placement import convert_origin, known_vehicle

    if format_name not in EXPORT_FORMATS:
        raise RigoptError(f"--format {format_name!r} is not one rigopt writes; use one of {', '.join(EXPORT_FORMATS)}")
    suffixes = EXPORT_SUFFIXES[format_name]
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
        loaded, change = convert_origin(loaded, vehicle, RigOrigin(EXPORT_ORIGINS[format_name]))
        if change is not None:
            note(change.describe())
    exported = export_rig(loaded, format_name)
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
