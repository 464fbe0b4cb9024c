"""``rigopt design``: a rig on a vehicle that a detector trained on the reference transfers to best."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Optional

import typer

from rigopt.cli.app import (FIELD_PIXELS_HELP, FORCE_HELP, MIN_HEIGHT_HELP, NO_TRAILER_HELP, app, between, finite,
                            more_than, mount_rules, note, note_fallback, print_json, print_next, print_table)
from rigopt.cli.metric_commands import METRIC_HELP, PREDICTOR_HELP
from rigopt.cli.parsing import image_size_text, parse_image_size
from rigopt.benchmark import BENCHMARK_IMAGE_SIZE
from rigopt.design.defaults import DEFAULT_FOVS, DEFAULT_MAX_NODES, DEFAULT_PITCHES_DEG, DEFAULT_YAW_STEP_DEG, POSES
from rigopt.errors import RigoptError

if TYPE_CHECKING:
    from rich.console import Console

#: Widest mount point spacing (m) --spacing takes: a zone narrower than it would hold no mount point.
MAX_SPACING_M = 2.0
#: Finest mount point spacing (m): half a housing; finer points could not both hold a camera, and their candidates
#: would not fit in memory.
MIN_SPACING_M = 0.05
SPACING_WHY = " (mount points finer than half a housing hold no more cameras)"


def numbers_text(values) -> str:
    """(60.0, 65.0) -> ``"60,65"``: the form ``parse_numbers`` reads."""
    return ",".join(f"{v:g}" for v in values)


def parse_numbers(text: str, what: str) -> tuple[float, ...]:
    """``"60,65,70"`` -> (60.0, 65.0, 70.0); raises RigoptError naming ``what`` otherwise."""
    try:
        values = tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise RigoptError(f"{what} must be comma-separated numbers, got {text!r}") from None
    if not values:
        raise RigoptError(f"{what} needs at least one number")
    return values


def parse_camera_count(text: Optional[str]) -> tuple[int, int] | None:
    """``"8"`` -> (8, 8); ``"6-10"`` -> (6, 10); None stays None (the reference's count)."""
    if text is None:
        return None
    low, _, high = text.partition("-")
    try:
        counts = (int(low), int(high or low))
    except ValueError:
        raise RigoptError(f"--cameras must be a count or a range like 6-10, got {text!r}") from None
    if counts[0] < 1 or counts[1] < counts[0]:
        raise RigoptError(f"--cameras must be 1 or more and low <= high, got {text!r}")
    return counts


def parse_fovs(text: str) -> tuple[tuple[float, ...], tuple[float, float] | None]:
    """The catalogue's FOVs (deg) ``"60,65,70"``, or a continuous range ``"60-120"`` (its FOVs by the library's
    rule, ``design.settings.range_fovs``). Returns (FOVs, range or None)."""
    from rigopt.design.settings import fov_catalogue, range_fovs

    if "-" in text.strip()[1:] and "," not in text:
        low_text, _, high_text = text.partition("-")
        fov_range = (parse_numbers(low_text, "--fov")[0], parse_numbers(high_text, "--fov")[0])
    else:
        catalogue, fov_range = parse_numbers(text, "--fov"), None
    try:
        fovs = range_fovs(*fov_range) if fov_range else fov_catalogue(catalogue)
    except RigoptError:
        raise RigoptError(f"--fov must be lenses or a range (low-high) within (0, 180) degrees, got {text!r}") from None
    return fovs, fov_range


#: The headings of design --help beyond the options a user changes day to day.
POSE_PANEL = "Pose of the perception cameras (the --pose preset's, unless given)"
OBJECTIVE_PANEL = "What the designer minimises"
SEARCH_PANEL = "Catalogue, orientation grid and MILP"

@app.command("design")
def design_command(
    vehicle: str = typer.Option(..., help="Vehicle to design for: name, alias or CARLA blueprint."),
    ref: str = typer.Option(..., help="Reference rig the detector was trained on: library name or rig file; "
                                      "several, comma-separated, for a fleet (minimise the worst predicted drop)."),
    weights: Optional[str] = typer.Option(None, rich_help_panel=OBJECTIVE_PANEL,
                                          help="Calibrated RigCD weights the designer minimises: BEVDet, "
                                          "BEVFusion, Fast-BEV, PETR, joint (default), or a file."),
    metric: str = typer.Option("rigcd", "--metric", rich_help_panel=OBJECTIVE_PANEL, help=METRIC_HELP),
    predictor: str = typer.Option("auto", "--predictor", help=PREDICTOR_HELP + " It predicts; --objective designs."),
    objective: str = typer.Option("rigcd", "--objective", rich_help_panel=OBJECTIVE_PANEL,
                                  help="What the MILP minimises: rigcd (the calibrated "
                                  "RigCD under --weights, default) or a model of the measured drop (a shipped name, "
                                  "lss-R1, or a drop model JSON file) fitted from REF; the continuous stage is then "
                                  "off."),
    cameras: Optional[str] = typer.Option(None, help="Camera count or range (e.g. 6-10); default: the reference's."),
    fov: str = typer.Option(numbers_text(DEFAULT_FOVS), help="Lens catalogue: horizontal FOVs in degrees of "
                                                                "pinholes at --image-size, or a continuous range "
                                                                "such as 60-120."),
    image_size: str = typer.Option(image_size_text(BENCHMARK_IMAGE_SIZE), "--image-size",
                                   rich_help_panel=SEARCH_PANEL,
                                   help="Image size WIDTHxHEIGHT (px) of the --fov pinholes."),
    cameras_file: Optional[Path] = typer.Option(None, "--cameras-file",
                                                rich_help_panel=SEARCH_PANEL,
                                                help="Camera catalogue file (TOML or JSON): real cameras with "
                                                     "name, width, height, fx, fy, cx, cy, distortion, "
                                                     "coefficients; replaces --fov."),
    zones: Optional[str] = typer.Option(None, help="Allowed zones, comma-separated (default: all of the vehicle's)."),
    pitch: str = typer.Option(numbers_text(DEFAULT_PITCHES_DEG), rich_help_panel=SEARCH_PANEL,
                              help="Pitch angles to consider, degrees (> 0 up)."),
    yaw_step: float = typer.Option(DEFAULT_YAW_STEP_DEG, callback=more_than(0, " degrees", 180),
                                   rich_help_panel=SEARCH_PANEL, help="Yaw grid step, degrees."),
    spacing: Optional[float] = typer.Option(None, callback=between(MIN_SPACING_M, MAX_SPACING_M, " m", SPACING_WHY),
                                            rich_help_panel=SEARCH_PANEL,
                                            help="Mount point spacing (m), 0.05 to 2; default: sized to the vehicle."),
    min_coverage: int = typer.Option(0, min=0, rich_help_panel=SEARCH_PANEL,
                                     help="Cameras every ring sector needs, beyond the reference's coverage."),
    min_overlap: int = typer.Option(0, min=0, rich_help_panel=SEARCH_PANEL,
                                    help="Cameras needed where the reference sees a sector twice (e.g. 2)."),
    max_nodes: int = typer.Option(DEFAULT_MAX_NODES, "--max-nodes", min=1, max=10_000_000,
                                  rich_help_panel=SEARCH_PANEL,
                                  help="MILP work limit in branch-and-bound nodes: the same design on any machine; "
                                       "a design not proven best within it is an error."),
    accept_gap: bool = typer.Option(False, "--accept-gap",
                                    rich_help_panel=SEARCH_PANEL,
                                    help="Take the best design found within --max-nodes, reported with its gap, "
                                         "instead of refusing one not proven best."),
    min_height: Optional[float] = typer.Option(None, "--min-height", min=0.0, max=5.0,
                                               help=MIN_HEIGHT_HELP),
    no_trailer: bool = typer.Option(False, "--no-trailer", help=NO_TRAILER_HELP),
    require: Optional[str] = typer.Option(None, "--require",
                                          help="Regulation fields the design must see: comma-separated r158, r151, "
                                               "r159, r46-iv, r46-v, r46-vi, dvs (':lht' for left-hand traffic), "
                                               "'default' (the vehicle category's: trucks and buses "
                                               "r151,r159,r158; cars and vans r158) or 'none'. Without it the "
                                               "category's fields are required unless no design sees them all "
                                               "(then reported). See "
                                               "docs/regulations.md."),
    field_pixels: Optional[float] = typer.Option(None, "--field-pixels", min=0.0, callback=finite(),
                                                 help=FIELD_PIXELS_HELP),
    cost_weight: float = typer.Option(0.0, "--cost-weight", min=0.0, callback=finite(),
                                      rich_help_panel=OBJECTIVE_PANEL,
                                      help="Weight of the cameras' mean relative mounting cost (zone cost, +0.5 in "
                                           "tyre spray) added to the calibrated RigCD; 0 reports it only."),
    asymmetric: bool = typer.Option(False, "--asymmetric",
                                    rich_help_panel=SEARCH_PANEL,
                                    help="Place cameras freely; by default a mirror-symmetric vehicle gets cameras "
                                         "in mirrored pairs and on its centreline."),
    pose: str = typer.Option("nearest", "--pose",
                             rich_help_panel=POSE_PANEL,
                             help="The perception cameras' pose in a two-role design: nearest (each at the nearest "
                                  "pose the body allows to its matched reference camera's: 0.05 m of height, its "
                                  "pitch, 5 deg of yaw, its lens; the reference's coverage kept from 20 m; placed "
                                  "freely beside mirrored near-field cameras; measured in "
                                  "studies/validation/designs) or free (no tolerance, every ring, mirrored pairs: "
                                  "the earlier default). --match-*, --perception-range and --free-perception "
                                  "override it; one camera set (--single-set, --pareto) is always free."),
    free_perception: Optional[bool] = typer.Option(None, "--free-perception/--mirrored-perception",
                                                   rich_help_panel=POSE_PANEL,
                                                   help="Place the perception cameras freely (the reference's own "
                                                        "layout, which a mirrored body may not offer) while the "
                                                        "near-field cameras keep their mirrored pairs; default: as "
                                                        "--pose says."),
    match_height: Optional[float] = typer.Option(None, "--match-height", min=0.0, callback=finite(),
                                                 rich_help_panel=POSE_PANEL,
                                                 help="Pose tolerance (m): each perception camera within this "
                                                      "height of its matched reference camera, or as near as the "
                                                      "body allows (a lifting detector's depth prior is its "
                                                      "training rig's; docs/design.md, 'Pose tolerance')."),
    match_pitch: Optional[float] = typer.Option(None, "--match-pitch", min=0.0, callback=finite(),
                                                rich_help_panel=POSE_PANEL,
                                                help="Pose tolerance (deg): each perception camera's pitch within "
                                                     "this of its matched reference camera's."),
    match_yaw: Optional[float] = typer.Option(None, "--match-yaw", min=0.0, callback=finite(),
                                              rich_help_panel=POSE_PANEL,
                                              help="Pose tolerance (deg): each perception camera's yaw within this "
                                                   "of its matched reference camera's (half the yaw step keeps the "
                                                   "nearest grid yaw)."),
    match_fov: Optional[float] = typer.Option(None, "--match-fov", min=0.0, callback=finite(),
                                              rich_help_panel=POSE_PANEL,
                                              help="Lens tolerance (deg): each perception camera's horizontal FOV "
                                                   "within this of its matched reference camera's (0: the "
                                                   "reference's lens)."),
    height_search: Optional[float] = typer.Option(None, "--height-search", min=0.0, callback=finite(),
                                                  rich_help_panel=POSE_PANEL,
                                                  help="With --match-height and free perception cameras: move each "
                                                       "perception camera, within this many metres, to the valid "
                                                       "mount (0.03 m grid) nearest its matched reference camera's "
                                                       "height (0: off; default: as --pose says, 0.75 for nearest)."),
    perception_range: Optional[float] = typer.Option(None, "--perception-range", min=0.0, callback=finite(),
                                           rich_help_panel=POSE_PANEL,
                                           help="With near-field cameras: the perception cameras keep the "
                                                "reference's coverage only on the rings at least this far (m) from "
                                                "the body (rings at 2, 5, 10, 20 m; 0: all of them; default: as "
                                                "--pose says, 20 for nearest)."),
    near_field: Optional[bool] = typer.Option(None, "--near-field/--single-set",
                                              help="Two camera roles (the default): perception cameras designed "
                                                   "for the reference alone, then near-field fisheyes (190 deg) "
                                                   "that see the regulation fields and the ground right around "
                                                   "the body (docs/design.md, 'Near-field cameras'). "
                                                   "--single-set: one camera set serves both."),
    pareto: bool = typer.Option(False, "--pareto", help="Sweep camera counts (--cameras, default the reference's "
                                                        "+-2) and coverage levels; write the frontier of predicted "
                                                        "drop, unseen near-field ground and mounting cost."),
    ref_vehicle: Optional[str] = typer.Option(None, "--ref-vehicle",
                                              help="Vehicle the reference rigs were mounted on, for rigs whose own "
                                                   "vehicle rigopt does not know (imported rigs) or to override it; "
                                                   "origins are converted to its centre."),
    measure: bool = typer.Option(False, "--measure", help="Also measure the design and R1's naive and "
                                 "height-matched copies with the shipped detectors (rigopt validate, no data needed) "
                                 "and show measured beside predicted, saying where they disagree."),
    protocol: str = typer.Option("quick", "--protocol", help="With --measure: quick (every 4th frame of the test "
                                 "scenes), full or quick-s1 (new scenes), as rigopt validate --protocol."),
    out: Optional[Path] = typer.Option(None, help="Output folder (default: design-<vehicle>-<ref>)."),
    force: bool = typer.Option(False, "--force", help=FORCE_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print the JSON summary."),
):
    """Design a rig on VEHICLE for a detector trained on REF: perception cameras at the nearest pose the body allows
    to REF's (heights searched), near-field fisheyes for the regulation fields; predicted drops printed."""
    from rich.console import Console

    from rigopt.background import INLINE, Background
    from rigopt.design.designer import design_rig
    from rigopt.design.problem import benchmark_rigs
    from rigopt.design.result import predicted_by
    from rigopt.design.settings import DesignSettings
    from rigopt.output import atomic_folder, check_out_folder, published
    from rigopt.report.design_report import write_design_report

    if out is not None:
        check_out_folder(out, force=force)
    lenses, fov_range = _catalogue(fov, image_size, cameras_file)
    pose_fields = _pose_fields(pose, match_height, match_pitch, match_yaw, match_fov, perception_range,
                               free_perception, height_search)
    settings = DesignSettings.preset(  # the flags mapped onto the library's preset
        pose, **pose_fields, cameras=parse_camera_count(cameras), lenses=lenses, fov_range=fov_range,
        zones=tuple(z.strip() for z in zones.split(",")) if zones else None, pitches_deg=_pitches(pitch),
        yaw_step_deg=yaw_step, spacing=spacing, min_coverage=min_coverage, min_overlap=min_overlap,
        max_nodes=max_nodes, accept_gap=accept_gap, rules=mount_rules(min_height, no_trailer),
        symmetric=False if asymmetric else None, cost_weight=cost_weight, require=require, field_pixels=field_pixels,
        near_field=not pareto if near_field is None else near_field, drop_model=_objective(objective, ref))
    # a worker process beside this one (with a second core): the near-field stage and the pictures go there
    background = INLINE if pareto else Background(later_imports=("rigopt.report.vehicle_figures",
                                                                 "rigopt.report.coverage_figures"))
    try:
        references, target, calibration, drop_model = _inputs(ref, ref_vehicle, vehicle, weights, metric, predictor,
                                                              require)
        label = "+".join(r.rig.name for r in references)
        out = check_out_folder(out or Path(f"design-{target.name}-{label}"), force=force)
        status = Console(stderr=True)
        _check_pareto(pareto, near_field, measure)
        if pareto:
            _pareto(target, references, calibration, drop_model, settings, out, force, as_json, status)
            return
        if measure:
            _check_measurable(references[0].rig.name, protocol)
        with status.status(f"designing a rig on {target.name} from {label}") as spinner:
            result = design_rig(target, references, calibration, settings, compare_with=benchmark_rigs(target),
                                progress=lambda message: spinner.update(message) or status.print(f"  {message}"),
                                background=background)
        result = predicted_by(result, drop_model)
        measured = _measured(result, references, calibration, drop_model, protocol, status) if measure else None
        with atomic_folder(out, force=force) as work:
            files, summary = write_design_report(result, work, background, measured)
            files = published(files, work, out)
        background.close()  # its work is done
        summary = {**summary, "rig_file": str(files[0])}  # as written: the report names it relative to its folder
        if as_json:
            print_json(summary)
            return
        _print_design(summary, label, target.name, calibration, drop_model is not None, measured, files, out)

    finally:
        background.close()


def _inputs(ref: str, ref_vehicle, vehicle: str, weights, metric: str, predictor: str, require) -> tuple:
    """(references, the target vehicle, the calibration, the drop model that predicts or None) of the command line,
    every one checked before any design work (a bad --require too)."""
    from rigopt.coverage.regulations import parse_require
    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.drop_model import choose_model
    from rigopt.vehicle.library import load_vehicle

    references = [_reference(name.strip(), ref_vehicle) for name in ref.split(",") if name.strip()]
    if not references:
        raise RigoptError("--ref needs at least one rig")
    target, calibration = load_vehicle(vehicle), load_weights(weights or "joint", metric)
    drop_model = choose_model(predictor, references[0].rig, weights is not None or metric != "rigcd")
    if require is not None:
        parse_require(require, target)
    if drop_model is None:
        note_fallback(calibration)
    return references, target, calibration, drop_model


def _pose_fields(pose: str, match_height, match_pitch, match_yaw, match_fov, perception_range, free_perception,
                 height_search) -> dict:
    """The pose settings given on the command line (the --pose preset keeps the others)."""
    if pose.lower() not in POSES:
        raise RigoptError(f"--pose must be one of {', '.join(POSES)}, got {pose!r}")
    given = {"match_height_m": match_height, "match_pitch_deg": match_pitch, "match_yaw_deg": match_yaw,
             "match_fov_deg": match_fov, "perception_range_m": perception_range,
             "perception_symmetric": None if free_perception is None else not free_perception,
             "height_search_m": height_search}
    return {k: v for k, v in given.items() if v is not None}


def _pitches(pitch: str) -> tuple[float, ...]:
    """--pitch: angles in degrees within [-90, 90] (> 0 up)."""
    pitches = parse_numbers(pitch, "--pitch")
    if not all(-90 <= p <= 90 for p in pitches):
        raise RigoptError(f"--pitch angles must be within [-90, 90] degrees (> 0 up), got {pitch!r}")
    return pitches


def _check_pareto(pareto: bool, near_field, measure: bool) -> None:
    """--pareto sweeps one camera set and measures nothing."""
    if pareto and near_field:
        raise RigoptError("--pareto sweeps one camera set; leave out --near-field or add --single-set "
                          "(or leave out --pareto)")
    if pareto and measure:
        raise RigoptError("--measure measures one design: leave out --pareto (or --measure)")


def _catalogue(fov: str, image_size: str, cameras_file: Optional[Path]) -> tuple:
    """(lenses, fov_range) of --fov and --image-size, or of --cameras-file (which gives the whole catalogue)."""
    from rigopt.design.settings import pinhole_catalogue, read_catalogue

    fovs, fov_range = parse_fovs(fov)
    size = parse_image_size(image_size)
    if cameras_file is None:
        return pinhole_catalogue(fovs, size), fov_range
    if fov_range is not None or fov != numbers_text(DEFAULT_FOVS) or size != BENCHMARK_IMAGE_SIZE:
        raise RigoptError("--cameras-file gives the whole catalogue: leave out --fov and --image-size")
    return read_catalogue(cameras_file), fov_range


def _print_design(summary: dict, label: str, vehicle: str, calibration, by_model: bool, measured, files, out) -> None:
    """The design's table of predicted drops (design, naive transfer, benchmark rigs), its notes on stderr (intervals
    that say nothing, extrapolation, symmetry, fields, height moves, solver) and what was written."""
    rows, flagged, uninformative = [], [], []
    for name, entry in (("design", {**summary, "meets_coverage_requirements": True}),
                        ("naive transfer", summary["comparisons"]["naive_transfer"]),
                        *((f"benchmark {s['name']}", s) for s in summary["comparisons"]["benchmark_rigs"])):
        if entry:
            interval = "-" if entry["interval"] is None else "[{:.2f}, {:.2f}]".format(*entry["interval"])
            if entry.get("interval_informative") is False:  # spans the range a drop can take: no finding
                interval, uninformative = "uninformative", uninformative + [name]
            rows.append([name, entry["predicted_drop"], interval, entry["rigcd"], entry["n_cameras"],
                         entry["coverage"], "yes" if entry["meets_coverage_requirements"] else "no",
                         "yes" if entry["extrapolation"] else "-"])
            flagged += [name] if entry["extrapolation"] else []
    print_table(f"{label} -> {vehicle} (predicted by {summary['predictor']}); reference coverage "
                f"{summary['reference_coverage']:.3f}",
                ["rig", "predicted drop", "interval", f"{calibration.metric} ({calibration.name} weights)", "cameras",
                 "coverage", "meets coverage", "extrapolates"], rows)
    if uninformative:
        from rigopt.metrics.prediction import UNINFORMATIVE_TEXT

        print(f"rigopt: note: {', '.join(uninformative)}: {UNINFORMATIVE_TEXT}; the predicted drops are point "
              "estimates only (report.json keeps the numbers)", file=sys.stderr)
    if flagged:
        print(f"rigopt: note: {', '.join(flagged)}: beyond the {'fitting rigs' if by_model else 'calibration pairs'}"
              " (see report.json 'extrapolation'); their predicted drops are less certain than the intervals say",
              file=sys.stderr)
    _print_matches(summary, label)
    _print_design_notes(summary)
    if measured is not None:
        _print_measured(measured)
    from rigopt.report.design_html import NEXT_STEPS

    print(f"wrote {', '.join(str(f) for f in files)}")
    print_next(f"open {out / 'report.html'} (the design for a packaging review: cameras, fields, 3D view)",
               *(f"in {out}: {command} ({why})" for command, why in NEXT_STEPS))


#: The pose tolerance's keys in a report (height m, pitch, yaw, FOV deg).
TOLERANCE_KEYS = ("height_m", "pitch_deg", "yaw_deg", "fov_deg")


def _print_matches(summary: dict, label: str) -> None:
    """Each perception camera beside the reference camera it was designed for, and how far its pose is from that
    camera's, so that a name (where a camera is mounted and where it looks) is never read as its place; a note where
    RigCD's own matching of the final rig pairs a camera otherwise."""
    from rigopt.design.tolerance import describe_tolerance

    cameras = [c for c in summary["cameras"] if "stands_in_for" in c]
    if not cameras:
        return
    tolerance = summary["pose_tolerance"]
    rows = [[c["id"], s["id"], s["height_m"], s["pitch_deg"], s["yaw_deg"], s["fov_deg"], s["lenses_apart_m"]]
            for c in cameras for s in [c["stands_in_for"]]]
    print_table(f"each perception camera and the {label} camera it was designed for (its pose, not its place, is "
                f"kept near that camera's: {describe_tolerance(*(tolerance[k] for k in TOLERANCE_KEYS))})",
                ["camera", f"{label} camera", "height (m)", "pitch (deg)", "yaw (deg)", "FOV (deg)",
                 "lenses apart (m)"], rows)
    other = [f"{c['id']} with {c['matched_reference_camera']['id']}" for c in cameras
             if c.get("matched_reference_camera") and c["matched_reference_camera"]["id"] != c["stands_in_for"]["id"]]
    if other:
        print(f"rigopt: note: RigCD's own matching of the final rig pairs {len(other)} camera(s) otherwise "
              f"({'; '.join(other)}); report.json keeps both (stands_in_for, matched_reference_camera)",
              file=sys.stderr)


def _print_design_notes(summary: dict) -> None:
    """Symmetry, the fields seen, the height moves and the solver's figures (stderr), then the report's notes."""
    from rigopt.coverage.regulations import category_text
    from rigopt.report.coverage_tables import resolution_text
    from rigopt.report.design_html import blocked_by_keep_outs_text

    print(f"{summary['symmetry']['describe']}", file=sys.stderr)
    print(category_text(summary["vehicle_category"]), file=sys.stderr)
    if summary["regions_fallback"]:
        print(f"rigopt: note: {summary['regions_fallback']}", file=sys.stderr)
    blocked = [f"{sheet['camera']} {blocked_by_keep_outs_text(sheet)}" for sheet in summary["packaging"]
               if blocked_by_keep_outs_text(sheet)]
    if blocked:
        print(f"views blocked by keep-outs (share of the image): {'; '.join(blocked)}", file=sys.stderr)
    for region in summary["regions"]:
        state = "required" if summary["regions_required"] else "reported"
        print(f"field {region['key']} ({state}): {region['covered_frac']:.1%} of its points seen with "
              f"{resolution_text(region)}, {region['in_view_frac']:.1%} in view "
              f"({region['weighted_covered_frac']:.1%} weighted by criticality), unseen area "
              f"{region['unseen_area_m2']:.1f} m²" + _excluded_text(region), file=sys.stderr)
    moves = summary["pose_tolerance"]["height_moves"]
    if moves:
        heights = ", ".join(f"{m['camera']} {m['from_m']:.2f} -> {m['to_m']:.2f} m" for m in moves)
        print(f"height search: {len(moves)} perception camera(s) moved nearer their reference camera's height "
              f"({heights})", file=sys.stderr)
    solver = summary["solver"]
    print(f"MILP {solver['milp_status']} (gap {solver['milp_gap']:.2e}) on {solver['offered_to_milp']} of "
          f"{solver['candidates']} candidates; refinement {solver['refine_status']}; {solver['seconds']:.1f} s",
          file=sys.stderr)
    for line in summary["notes"]:
        print(line)


def _objective(objective: str, ref: str):
    """--objective: None for RigCD, else the drop model, refused unless fitted from the (one) reference."""
    from rigopt.metrics.drop_model import RIGCD, load_drop_model
    from rigopt.rig.library import load_rig

    if objective.lower() == RIGCD:
        return None
    model = load_drop_model(objective)
    names = [name.strip() for name in ref.split(",") if name.strip()]
    if len(names) != 1 or not model.applies_to(load_rig(names[0]).perception()):
        raise RigoptError(f"--objective {objective}: the {model.name} drop model was fitted from {model.reference}; "
                          f"design from --ref {model.reference} alone, or leave out --objective")
    return model


def _check_measurable(reference: str, protocol: str) -> None:
    """--measure before any design work: torch installed, the protocol known, models shipped for the reference."""
    from rigopt.cli.detector_commands import require_torch
    from rigopt.validation.detectors.measuring import protocol_named
    from rigopt.validation.detectors.shipped import reference_scores, shipped_detector, shipped_names

    require_torch()
    chosen = protocol_named(protocol)
    if f"lss-{reference}" not in shipped_names():
        raise RigoptError(f"--measure needs the shipped lss models trained on {reference}, and rigopt ships "
                          f"{', '.join(shipped_names()) or 'none'}: design from R1, or leave out --measure and "
                          "measure with rigopt validate RIG --ref REF --model lss --data DIR")
    reference_scores(shipped_detector("lss", reference), chosen)


def _measured(result, references, calibration, drop_model, protocol: str, status) -> dict:
    """--measure: the design and its copies measured with the shipped detectors of the first reference."""
    import os

    from rigopt.validation.designs import measure_design
    from rigopt.validation.detectors.measuring import protocol_named

    chosen = protocol_named(protocol)
    if len(references) > 1:
        note(f"--measure measures against the first reference, {references[0].rig.name}, alone")
    with status.status("measuring the design and its copies with the shipped detectors") as spinner:
        return measure_design(result.design.rig, references[0].rig, calibration, chosen,
                              workers=os.cpu_count() or 1, progress=spinner.update, drop_model=drop_model)


def _print_measured(measured: dict) -> None:
    print_table(f"measured with {measured['detector']} ({measured['protocol']}) beside the predicted drop "
                f"({measured['predicted_by']})",
                ["rig", "cameras", "predicted drop", "measured drop", "95 % interval (test scenes)"],
                [[r["role"], r["n_cameras"], f"{r['predicted_drop']:.3f}", f"{r['measured_drop']:.3f}",
                  "[{:.3f}, {:.3f}]".format(*r["measured_drop_ci"])] for r in measured["rigs"]])
    for line in measured["contradictions"]:
        note(f"prediction and measurement disagree: {line}")


def _excluded_text(region: dict) -> str:
    """What a field line adds when some of the field's points are not asked for (inside the body's footprint or a
    keep-out in force, such as a coupled trailer)."""
    excluded = region["n_excluded"]
    if not excluded:
        return ""
    return (f"; {excluded} of its {excluded + region['n_points']} points lie inside the body or a keep-out in force "
            "and are not asked for")


def _reference(name: str, vehicle: Optional[str]):
    """A --ref rig (a library rig, a rig file or a packed reference: ``shipped.reference_rig``) on its vehicle
    (``vehicle`` when given), origin converted (noted), cameras inside refused."""
    from rigopt.design.problem import ReferenceRig
    from rigopt.validation.detectors.shipped import reference_rig
    from rigopt.vehicle.placement import rig_on_vehicle

    rig, on, change = rig_on_vehicle(reference_rig(name), vehicle)
    if change is not None:
        note(change.describe())
    return ReferenceRig(rig, on)


def _pareto(target, references, calibration, drop_model, settings, out: Path, force: bool, as_json: bool,
            status: Console) -> None:
    from dataclasses import asdict

    from rigopt.design.pareto import pareto_designs, sweep_counts, write_pareto
    from rigopt.output import atomic_folder, published

    counts = settings.cameras or sweep_counts(references)
    with status.status("sweeping camera counts and coverage levels") as spinner:
        points = pareto_designs(target, references, calibration, settings, counts,
                                progress=lambda message: spinner.update(message) or status.print(f"  {message}"),
                                drop_model=drop_model)
    if not any(p.feasible for p in points):
        count = str(counts[0]) if counts[0] == counts[1] else f"{counts[0]}-{counts[1]}"
        raise RigoptError(f"no design of {count} camera(s) on {target.name} is feasible at any coverage "
                          "level, so there is no frontier to draw; allow more cameras (--cameras), more zones or "
                          "wider lenses")
    with atomic_folder(out, force=force) as work:
        files = published(write_pareto(points, work), work, out)
    if as_json:
        print_json([{k: v for k, v in asdict(p).items() if k != "rig"} for p in points])
        return
    by = (f"the {drop_model.name} drop model" if drop_model is not None
          else f"{calibration.metric} under {calibration.name} weights")
    print_table(f"designs for {target.name}: predicted drop ({by}) against the near field and the mounting cost",
                ["cameras", "coverage level", "predicted drop", "rigcd", "coverage", "2 m ring ground",
                 "unseen within 5 m (m²)", "fields seen (min)", "mounting cost", "frontier"],
                [[p.n_cameras, p.level, p.predicted_drop, p.rigcd, p.coverage, p.ring_2m_ground, p.blind_area_m2,
                  p.fields, p.mounting_cost, "yes" if p.frontier else "-"]
                 if p.feasible else [p.n_cameras, p.level, "infeasible", *["-"] * 7] for p in points])
    print(f"wrote {', '.join(str(f) for f in files)}")
