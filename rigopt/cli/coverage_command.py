"""``rigopt coverage``: rings, bird's-eye map, blind zone and per-camera coverage of a rig, optionally
against a second rig, as tables, JSON or a folder with figures and a self-contained HTML page."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from rigopt.cli.app import (FIELD_PIXELS_HELP, FORCE_HELP, NO_TRAILER_HELP, app, console, finite, note_vehicle,
                            print_json, print_next, print_table)
from rigopt.errors import RigoptError


#: The --require option's help (also for other commands that take regulation fields).
REQUIRE_HELP = ("Regulation fields every camera-visible point of which is checked, comma-separated: r158 (rear, "
                "reversing), r151 (nearside blind spot), r159 (front, moving off), r46-ii, r46-iv, r46-v, r46-vi (R46 "
                "classes II, IV, V, VI), dvs (London Direct Vision Standard); default (the vehicle category's: trucks "
                "and buses r151,r159,r158, cars and vans r158) or none. Add :lht for left-hand traffic (nearside on the left), e.g. "
                "r151:lht. See docs/regulations.md.")

def _placed(rig_name: str, vehicle: Optional[str]):
    """The rig on ``vehicle`` (or its own), origin converted to the vehicle's centre, cameras inside the body
    refused; that vehicle; and the note naming the vehicle and origin used (a callable, called once the command
    has succeeded: bad input gets its one error line alone)."""
    from functools import partial

    from rigopt.rig.library import load_rig
    from rigopt.vehicle.placement import rig_on_vehicle

    loaded = load_rig(rig_name)
    rig, on, change = rig_on_vehicle(loaded, vehicle)
    return rig, on, partial(note_vehicle, loaded, on, change)


def _report(rig_name: str, vehicle: Optional[str]):
    """The rig placed as by :func:`_placed`, its coverage report and its note."""
    from rigopt.coverage.measures import coverage_report

    rig, on, announce = _placed(rig_name, vehicle)
    return rig, coverage_report(rig, on), announce


def _refuse_blind(report, rig, vehicle) -> None:
    """A rig that sees nothing on any ring is an error with the mount check's reasons (a camera pressed
    against the body sees only the body), not a 0 % answer."""
    if any(ring.covered_frac > 0 for ring in report.rings):
        return
    from rigopt.mounting.rules import check_rig

    reasons = [f"{c.id} ({', '.join(c.problems)})" for c in check_rig(rig, vehicle).cameras if c.problems]
    raise RigoptError(f"{rig.name} on {vehicle.name} sees nothing on any ring"
                      + (f": {'; '.join(reasons)}" if reasons else "")
                      + f"; run rigopt check {rig.name} for the mount checks and move the cameras onto the surface, "
                        "facing away from the body")


@app.command("coverage")
def coverage_command(
    rig: str = typer.Argument(..., help="Library rig name or rig file."),
    vehicle: Optional[str] = typer.Option(None, help="Vehicle name, alias or blueprint to place the rig on (default: "
                                                     "its own, its vehicle_type for files); the rig's origin is "
                                                     "converted to the vehicle's centre and a camera inside the "
                                                     "body is an error."),
    compare: Optional[str] = typer.Option(None, "--compare", help="A second rig (name or file) to compare with, "
                                                                  "on its own vehicle; differences are RIG minus it."),
    out: Optional[str] = typer.Option(None, "--out", help="Folder for coverage.json, bev.png, rings.png, blind.png "
                                                          "and report.html (self-contained)."),
    force: bool = typer.Option(False, "--force", help=FORCE_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print the JSON report instead of tables."),
    require: str = typer.Option("none", "--require", help=REQUIRE_HELP),
    field_pixels: Optional[float] = typer.Option(None, "--field-pixels", min=0.0, callback=finite(),
                                                 help=FIELD_PIXELS_HELP),
    no_trailer: bool = typer.Option(False, "--no-trailer", help=NO_TRAILER_HELP + " It then neither blocks views nor "
                                    "shapes the fields."),
    articulation: Optional[float] = typer.Option(None, "--articulation", min=0.0, max=90.0, callback=finite(),
                                                 help="With --require on a tractor with a semi-trailer: also the fields "
                                                      "with the trailer turned this many degrees about its kingpin, "
                                                      "both ways (as a right and a left turn swing it)."),
):
    """Coverage of a rig around its vehicle: rings at 2-50 m, bird's-eye counts, near-field blind zone, per camera."""
    from rigopt.coverage.measures import CoverageSettings, compare_coverage, coverage_report
    from rigopt.coverage.packaging import report_origin
    from rigopt.coverage.regulations import category_dict, parse_require, region_coverage
    from rigopt.report.coverage_figures import comparison_dict, report_dict
    from rigopt.report.coverage_tables import regions_dict

    from rigopt.output import check_out_folder

    out_dir = check_out_folder(out, force=force) if out is not None else None
    loaded, on, announce = _placed(rig, vehicle)
    presets = parse_require(require, on)
    if field_pixels is not None:
        presets = tuple(preset.with_min_px(field_pixels) for preset in presets)
    lifted = ("trailer",) if no_trailer else ()
    report = coverage_report(loaded, on, CoverageSettings(lifted=lifted))
    _refuse_blind(report, loaded, on)
    regions = region_coverage(loaded, on, presets, backend=report.settings.backend,
                              max_range=report.settings.max_range, lifted=lifted)
    turned = _articulated_regions(loaded, on, presets, articulation, report.settings, lifted)
    other = comparison = None
    if compare is not None:
        _, other, announce_other = _report(compare, None)
        comparison = compare_coverage(other, report)  # differences: RIG minus --compare
    data = report_dict(report, loaded, report_origin(on))  # the design report's frame, as the --out folder's
    data["vehicle_category"] = category_dict(on)
    data["regions"] = regions_dict(regions)
    if turned:
        data["regions_articulated"] = [{"articulation_deg": angle, "regions": regions_dict(found)}
                                       for angle, found in turned]
    if comparison is not None:
        data["compare"] = comparison_dict(comparison)

    written = _write_out(out_dir, force, report, loaded, other, comparison, regions, on) if out_dir is not None else []
    announce()
    if compare is not None:
        announce_other()
    message = f"wrote {', '.join(p.name for p in written)} to {out_dir}"
    if as_json:
        print_json(data)
        if written:
            typer.echo(message, err=True)
        return
    _print_tables(data, report_dict(other) if other is not None else None)
    if written:
        console.print(message)
        print_next(f"open {out_dir / 'report.html'} (the coverage page: rings, bird's-eye map, blind zone, 3D view)")
    else:
        print_next(f"rigopt coverage {rig} --out FOLDER (the same as figures and an HTML page)")


def _print_field_tables(data: dict) -> None:
    """The regulation fields' tables of a coverage report (``data``: report_dict with ``regions`` and, with
    --articulation, ``regions_articulated``): the fields, the cameras by field, the fields with the trailer turned."""
    from rigopt.report.coverage_tables import camera_field_rows, resolution_text

    if data.get("regions"):
        print_table("regulation fields (--require): required points seen by >= 1 camera with the field's test object "
                    "as many pixels tall as asked (in view: however small), the unseen ground beside it; weighted: "
                    "each point by its criticality (docs/regulations.md); covered = all of them",
                    ["field", "covered", "seen", "seen at", "in view", "unseen area (m²)", "weighted seen",
                     "seen per height", "area (m²)", "points"],
                    [[r["key"], "yes" if r["covered"] else "no", f"{100 * r['covered_frac']:.1f} %",
                      resolution_text(r), f"{100 * r['in_view_frac']:.1f} %", f"{r['unseen_area_m2']:.1f}",
                      f"{100 * r['weighted_covered_frac']:.1f} %",
                      ", ".join(f"{h['height_m']:g} m {100 * h['covered_frac']:.1f} %" for h in r["height_covered_frac"]),
                      f"{r['area_m2']:.1f}", r["n_points"]] for r in data["regions"]])
        columns, rows = camera_field_rows(data["regions"])
        print_table("regulation fields by camera: share of each field's required points a camera sees (and sees "
                    "alone); the alone shares and 'seen by >= 2' add up to 'seen by any'", columns, rows)
    if data.get("regions_articulated"):
        turned = data["regions_articulated"]
        print_table("regulation fields with the semi-trailer turned about its kingpin (> 0: its rear swung right, as "
                    "in a right turn; < 0: left): share seen as above",
                    ["field", "straight", *(f"turned {t['articulation_deg']:+g} deg" for t in turned)],
                    [[r["key"], f"{100 * r['covered_frac']:.1f} %",
                      *(f"{100 * t['regions'][k]['covered_frac']:.1f} %" for t in turned)]
                     for k, r in enumerate(data["regions"])])


def _articulated_regions(rig, vehicle, presets, articulation, settings, lifted) -> list[tuple[float, tuple]]:
    """[(angle deg, the fields' coverage with the semi-trailer turned by it), ...] for +-``articulation`` (none
    without it, without fields, or with the trailer lifted); an error on a vehicle without a semi-trailer."""
    from rigopt.coverage.regulations import region_coverage
    from rigopt.vehicle.articulation import articulated

    if articulation is None or not presets or "trailer" in lifted:
        return []
    if not any(box.kingpin is not None for box in vehicle.spec.keep_outs):
        raise RigoptError(f"--articulation turns a semi-trailer, and {vehicle.name} has none (a [[keep_out]] with a "
                          "kingpin); drop --articulation")
    return [(angle, region_coverage(rig, articulated(vehicle, angle), presets, backend=settings.backend,
                                    max_range=settings.max_range, lifted=lifted))
            for angle in (articulation, -articulation)]


def _write_out(out_dir: Path, force: bool, report, rig, other, comparison, regions=(), vehicle=None) -> list[Path]:
    """Write the report folder whole (a temporary sibling renamed into place), or leave ``out_dir`` as it was."""
    from rigopt.output import atomic_folder, published
    from rigopt.report.coverage_html import write_coverage_folder

    with atomic_folder(out_dir, force=force) as work:
        written = write_coverage_folder(work, report, rig, comparison, other, vehicle, regions)
    return published(written, work, out_dir)


def _lens_text(lens: dict | None) -> str:
    """A report's lens entry in one line: size, fx, distortion model, hFOV x vFOV."""
    if lens is None:
        return "-"
    model = "pinhole" if lens["distortion"] == "none" else lens["distortion"]
    return (f"{lens['width']}x{lens['height']} fx {lens['fx']:.0f} {model} "
            f"{lens['hfov_deg']:.1f}x{lens['vfov_deg']:.1f} deg")


def _print_tables(data: dict, other: dict | None) -> None:
    from rigopt.coverage.regulations import category_text

    others = {(r["distance_m"], r["height_m"]): r for r in other["rings"]} if other is not None else {}
    columns = ["distance (m)", "height (m)", "covered", "overlap >= 2"]
    if other is not None:
        columns += [f"covered {other['rig']}", f"overlap >= 2 {other['rig']}"]
    rows = []
    for ring in data["rings"]:
        row = [ring["distance_m"], ring["height_m"], ring["covered_frac"], ring["overlap2_frac"]]
        if other is not None:
            match = others.get((ring["distance_m"], ring["height_m"]), {})
            row += [match.get("covered_frac", "-"), match.get("overlap2_frac", "-")]
        rows.append(row)
    print_table(f"{data['rig']} on {data['vehicle']}: ring coverage (fraction of azimuths)", columns, rows)

    inside = set(data["cameras_inside"])
    ring = data["overlap_ring"]
    print_table(f"cameras (positions: {data['frame']}; overlap: degrees of the {ring['distance_m']:g} m ring at "
                f"{ring['height_m']:g} m seen by both)",
                ["camera", "x, y, z (m)", "lens", "self-occluded", "overlaps (deg)"],
                [[c["id"] + (" (INSIDE BODY)" if c["id"] in inside else ""),
                  ", ".join(f"{v:.2f}" for v in c["position"]), _lens_text(c["lens"]), c["self_occluded_frac"],
                  ", ".join(f"{k} {v:.1f}" for k, v in c["overlap_deg"].items()) or "-"] for c in data["cameras"]])

    blind, bev = data["blind_distance_m"], data["bev"]
    search = f"not within {data['blind_search_m']:g} m"
    shown = {k: search if v is None else f"{v:.2f} m" for k, v in blind.items()}
    missing = (f"; {100 * data['blind_not_found_frac']:.1f} % of azimuths see no ground within "
               f"{data['blind_search_m']:g} m" if data["blind_not_found_frac"] > 0 else "")
    console.print(f"blind zone: {data['blind_area_m2_within_5m']:.1f} m² of ground unseen within "
                  f"{data['blind_radius_m']:g} m of the body; ground visible from {shown['min']} (min), "
                  f"{shown['median']} (median), {shown['max']} (max){missing}")
    console.print(f"bird's-eye ({bev['height_m']:g} m height, {bev['cell_m']:g} m cells): "
                  f"{100 * bev['covered_frac_within_20m']:.1f} % of cells within 20 m seen, "
                  f"{100 * bev['overlap2_frac_within_20m']:.1f} % by >= 2 cameras, at most {bev['max_count']}")

    console.print(category_text(data["vehicle_category"]))
    _print_field_tables(data)

    if "compare" in data:
        diff = data["compare"]
        print_table(f"comparison: {diff['b']} minus {diff['a']}",
                    ["distance (m)", "height (m)", "covered diff", "overlap >= 2 diff", "sectors better",
                     "sectors worse"],
                    [[r["distance_m"], r["height_m"], r["covered_diff"], r["overlap2_diff"],
                      sum(v > 1e-9 for v in r["sector_diff"]), sum(v < -1e-9 for v in r["sector_diff"])]
                     for r in diff["rings"]])
        area = diff["blind_area_diff_m2"]
        console.print(f"unseen ground within the blind radius: {area:+.1f} m² ({diff['b']} minus {diff['a']})"
                      if area is not None else "unseen ground within the blind radius: -")
