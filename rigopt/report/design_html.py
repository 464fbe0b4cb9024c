"""The self-contained HTML report of a design: the comparison table, solver facts, cameras and pictures."""

from __future__ import annotations

from datetime import datetime, timezone
from pathlib import Path

from rigopt.coverage.regulations import category_text
from rigopt.report.coverage_tables import field_tables_html
from rigopt.report.html_page import escape, image, num, page, pct, table

_CAPTIONS = {
    "design": "The design on its vehicle (top and side views, zones coloured, cameras and their frustums).",
    "reference": "The reference rig on its own vehicle.",
    "naive_transfer": "The naive transfer: each reference camera moved to the nearest mount point facing its way.",
    "coverage": "Camera count per azimuth on each ring: the design solid, the reference (on its own vehicle) "
                "dashed. Forward is up, the vehicle's left on the left.",
    "fields": "The regulation fields over the design's near-field blind zones (x forward, y left): unseen field "
              "points marked.",
}


def _distortion_text(lens: dict) -> str:
    """``none``, or the model and its coefficients, e.g. ``radtan -0.26, 0.07, 0, 0, 0``."""
    if lens["distortion"] == "none":
        return "none"
    return f"{lens['distortion']} " + ", ".join(f"{k:.4g}" for k in lens["coefficients"])


def _designed_for_text(camera: dict) -> str:
    """The reference camera a perception camera was designed for and how far its pose is from it, e.g.
    ``CAM_SIDE_LEFT: height +0.03 m, pitch +0, yaw -5, FOV +0 deg; 4.03 m apart``; '-' for the others."""
    s = camera.get("stands_in_for")
    if s is None:
        return "-"
    return (f"{s['id']}: height {s['height_m']:+.2f} m, pitch {s['pitch_deg']:+.0f}, yaw {s['yaw_deg']:+.0f}, "
            f"FOV {s['fov_deg']:+.0f} deg; {s['lenses_apart_m']:.2f} m apart")


def _match_text(camera: dict) -> str:
    match = camera.get("matched_reference_camera")
    if match is None and camera.get("role") == "near_field":
        return "- (near-field camera: not fed to the detector, not compared)"
    if match is None:
        return "- (no partner: more perception cameras than the reference)"
    return f"{match['id']} ({match['t_m']:.2f}, {match['r_rad']:.2f}, {match['f_deg']:.1f})"


def _interval_text(entry: dict) -> str:
    """'[low, high]', '-' without an interval, the uninformative text where it spans the range a drop can take."""
    from rigopt.metrics.prediction import UNINFORMATIVE_TEXT

    if entry.get("interval") is None:
        return "-"
    if entry.get("interval_informative") is False:
        return UNINFORMATIVE_TEXT
    return "[{:.2f}, {:.2f}]".format(*entry["interval"])


def _extrapolation_text(entry: dict) -> str:
    """'-' within the calibration data, else its out-of-range terms and hull distance."""
    from rigopt.metrics.prediction import describe_extrapolation

    flag = entry.get("extrapolation")
    return "-" if flag is None else describe_extrapolation(flag)


def scene_section(scene: str, compared: str | None, frame: str | None = None) -> list[str]:
    """The "3D view" section: its heading, a note on what is drawn and in which frame (``frame``: the report's,
    e.g. "ISO 8855, origin on the ground below the rear axle's centre"; the view's own words without it), and
    the ``scene`` fragment (``report.scene_3d.scene_html``); ``compared``: the name of the rig drawn in grey."""
    from rigopt.report.frustums import FRUSTUM_RANGE_M
    from rigopt.report.scene_3d import FRAME_TEXT

    grey = f" The reference rig {escape(compared)} is drawn in grey, dashed." if compared else ""
    where = f"{frame} (x forward, y left, z up, metres), as the tables" if frame else FRAME_TEXT
    return ["<h2>3D view</h2>",
            '<p class="note">Drag to turn, scroll to zoom, hover for details; click a legend entry to hide or show '
            "it. The design's cameras with their frustums to "
            f"{FRUSTUM_RANGE_M:g} m (lines to the image corners along the lens's own corner rays, outline through "
            "its edges' rays; a ray that meets the ground sooner ends there) and, in the camera's colour on the "
            "ground, where each frustum meets the ground; the "
            "mounting zones as in the pictures, the keep-outs in orange, the wheels (not mountable) dark grey."
            f"{grey} Frame: {escape(where)}.</p>",
            scene]


def _value(value, digits: int = 1) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def _feature_text(sheet: dict) -> str:
    """The zone a camera sits in, or 'none (nearest: zone, d m)'."""
    if sheet["zone"] is not None:
        return sheet["zone"]
    if sheet["nearest_zone"] is None:
        return "none"
    return f"none (nearest: {sheet['nearest_zone']}, {sheet['nearest_zone_m']:.2f} m)"


def packaging_section(packaging: list[dict], frame: str) -> list[str]:
    """The "Packaging" section: one row per camera of ``packaging`` (``design_report.packaging_rows``), the
    columns' definitions below the table; positions in ``frame``."""
    from rigopt.coverage.packaging import BLOCKED_GRID, PERSON_DISTANCE_M

    def resolution(sheet: dict) -> str:
        return "; ".join(f"{g['distance_m']:g} m: {_value(g['lateral'], 0)} / {_value(g['longitudinal'], 0)}"
                         for g in sheet["ground_resolution_px_per_m"])

    def people(sheet: dict, person: str) -> str:
        entry = next(p for p in sheet["person_height_px"] if p["person"] == person)
        return " / ".join(_value(entry[place], 0) for place in ("left", "centre", "right"))

    heights = {p["person"]: p["height_m"] for p in packaging[0]["person_height_px"]} if packaging else {}
    rows = [[escape(c["camera"]), escape(_feature_text(c)),
             escape(", ".join(f"{v:.2f}" for v in c["mount_point_m"])),
             escape(", ".join(f"{v:.2f}" for v in c["surface_normal"])), num(c["wedge_angle_deg"], 1, "°"),
             num(c["protrusion_m"], 3), num(c["nearest_ground_m"], 2), num(c["nearest_ground_from_body_m"], 2),
             escape(resolution(c)), escape(people(c, "adult")), escape(people(c, "child")), pct(c["blocked_frac"]),
             escape(blocked_by_keep_outs_text(c) or "-")]
            for c in packaging]
    adult, child = heights.get("adult", 1.8), heights.get("child", 0.8)
    return ["<h2>Packaging</h2>",
            table(["camera", "body feature (zone)", f"mount point x, y, z (m, {frame})", "surface normal",
                   "bracket wedge", "protrusion (m)", "nearest ground from lens (m)", "from body (m)",
                   "ground px/m across / along", f"{adult:g} m adult px (left / centre / right)",
                   f"{child:g} m child px (left / centre / right)", "image blocked by body",
                   "by keep-outs (trailer)"], rows, numeric_from=4),
            '<p class="note">Per camera, through its own lens: the body feature is the mounting zone of its mount '
            "point (the lens's foot on the body surface), or the nearest zone and its distance; the surface normal "
            "is the body's outward unit normal there, and the bracket wedge the angle between it and the optical "
            "axis (0° when the camera looks straight out of the surface); the protrusion is how far the lens stands "
            "in front of the surface along that normal. Nearest ground: the shortest horizontal distance from the "
            "lens's ground point (and from the body's footprint) to ground the camera sees, the body's blocking "
            "ray-cast. Ground px/m: image pixels per metre across and along the ground, 5, 10 and 20 m from the "
            "lens's ground point straight ahead along the optical axis's ground direction (- where the camera "
            f"does not see that ground). People: a person standing {PERSON_DISTANCE_M:g} m from the lens's ground "
            "point in the direction of the image's left edge, its centre and its right edge, height in pixels of "
            "the part in the image and not hidden by the body. Image blocked: the share of a "
            f"{BLOCKED_GRID[0]} x {BLOCKED_GRID[1]} grid of pixel rays that meets the body; by keep-outs: the "
            "share that meets a keep-out blocking views (a coupled trailer) before the body. Definitions in "
            "docs/design.md and rigopt/coverage/packaging.py.</p>", *bracket_section(packaging, frame)]


def blocked_by_keep_outs_text(sheet: dict) -> str:
    """The shares of a camera's image that keep-outs block, e.g. 'trailer 41 %' ('' where none does)."""
    return ", ".join(f"{label} {100 * share:.0f} %" for label, share in sheet.get("blocked_by_keep_outs", {}).items()
                     if share > 0)


def bracket_section(packaging: list[dict], frame: str) -> list[str]:
    """The "Brackets" table: each camera's bracket sheet (``packaging[k]["bracket"]``,
    :mod:`rigopt.coverage.bracket`); the ECU in ``frame``."""
    from rigopt.coverage.bracket import SERVICE_LOOP_M
    from rigopt.mounting.features import BUMP_TRAVEL_M, STEER_LOCK_DEG

    sheets = [(c["camera"], c["bracket"]) for c in packaging if "bracket" in c]
    if not sheets:
        return []

    def flag(value) -> str:
        return "-" if value is None else "yes" if value is True else "no" if value is False else str(value)

    rows = [[escape(name), escape(", ".join(f"{a:.1f}" for a in b["bracket_ypr_deg"])),
             escape(" x ".join(f"{v:.3f}" for v in b["housing_m"])), num(b["depth_behind_skin_m"], 2),
             num(b["clearance_m"]["door"], 2), escape(flag(b["door_swing"])), num(b["clearance_m"]["wheel_envelope"], 2),
             escape(flag(b["tilt_cab_sweep"])), num(b["outside_wiped_area_m"], 2), num(b["harness_m"], 1),
             escape(b["stone_chip"]), escape(b["soiling"]), escape(flag(b["washer"]))] for name, b in sheets]
    ecu = ", ".join(f"{v:.2f}" for v in sheets[0][1]["ecu_m"])
    return ["<h2>Brackets</h2>",
            table(["camera", "bracket yaw, pitch, roll (deg)", "housing w x h x d (m)", "depth behind skin (m)",
                   "door clearance (m)", "in a door's swing", "wheel envelope clearance (m)", "tilt-cab sweep",
                   "outside the wiped area (m)", "harness (m)", "stone chips", "soiling", "washer"], rows,
                  numeric_from=3),
            '<p class="note">Bracket angles: the camera\'s yaw, pitch and roll against a bracket looking straight '
            "out of the surface with its up along the surface's up. Depth behind the skin: how far the body reaches "
            "inward along the surface normal (at most 1 m). Clearances (0: inside): the nearest door opening, a "
            f"door's swing about its hinge; the wheels' envelope (each tyre up to {BUMP_TRAVEL_M:g} m of bump travel, "
            f"a steered one turned up to {STEER_LOCK_DEG:g} deg either way); the tilting cab's sweep; the wipers' "
            "sweep for a camera "
            f"on the windscreen. Harness: the length along the vehicle's axes to an ECU assumed at ({escape(ecu)}) m "
            f"({escape(frame)}), plus a {SERVICE_LOOP_M:g} m service loop: an estimate to start routing from. "
            "Stone chips and soiling from where the lens sits and looks (docs/design.md, rigopt/coverage/bracket.py); "
            "a washer is advised where either is high.</p>"]


def breakdown_note(summary: dict) -> str:
    """The note giving the RigCD breakdown (``summary["rigcd_breakdown"]``, unit weights) of the reference to the
    design's perception cameras, the ones ``rigopt rigcd`` compares; it says how many near-field cameras were
    left out (``summary["roles"]``)."""
    values = dict(summary["rigcd_breakdown"])
    compared = values.pop("design_cameras", summary["n_cameras"])
    reference = values.pop("reference_cameras", None)
    near_field = summary.get("roles", {}).get("near_field", 0)
    left_out = (f"; as rigopt rigcd compares them, the design's {near_field} near-field "
                f"camera{'s' if near_field != 1 else ''}, not fed to the detector, left out" if near_field else "")
    of_reference = f"'s {reference} cameras" if reference is not None else ""
    return (f'<p class="note">RigCD of the reference{escape(of_reference)} to the {compared} perception cameras of the '
            f"design (unit weights{escape(left_out)}): "
            + escape("; ".join(f"{k} {v:.3f}" for k, v in values.items())) + ".</p>")


def measured_section(measured: dict) -> list[str]:
    """``rigopt design --measure``'s measurements beside the predictions, and every disagreement said in words."""
    rows = [[escape(r["role"]), str(r["n_cameras"]), num(r["predicted_drop"], 3), num(r["measured_drop"], 3),
             escape("[{:.3f}, {:.3f}]".format(*r["measured_drop_ci"])),
             escape(" / ".join(f"{v:.3f}" for v in r["measured_per_seed"]))] for r in measured["rigs"]]
    notes = measured["contradictions"] or ["the prediction and the measurement agree on every rig and every order"]
    return ["<h2>Measured with the shipped detectors</h2>",
            f'<p class="note">{escape(measured["detector"])} models trained on {escape(measured["reference"])}, '
            f'{escape(measured["protocol"])}; predicted with {escape(measured["predicted_by"])}. Measured drops '
            "with 95 % intervals over resampled test scenes (test noise only).</p>",
            table(["rig", "cameras", "predicted drop", "measured drop", "95 % interval", "per seed"], rows),
            "<p>Where the prediction and the measurement disagree:</p>", "<ul>",
            *(f"<li>{escape(line)}</li>" for line in notes), "</ul>"]


def render_design_html(summary: dict, figures: dict[str, bytes], scene: str | None = None,
                       compared: str | None = None) -> str:
    """The page for ``summary`` (the ``design_dict`` of a result) and PNG ``figures`` by name; ``scene``: the
    3D view's HTML fragment (plotly.js inline), ``compared`` the name of the rig it draws in grey."""
    comparisons = summary["comparisons"]
    named = [("design", {**summary, "meets_coverage_requirements": True}),
             ("naive transfer", comparisons["naive_transfer"]),
             *((f"benchmark rig {entry['name']}", entry) for entry in comparisons["benchmark_rigs"])]
    rows = [[name, e["n_cameras"], e["predicted_drop"], _interval_text(e), e["rigcd"], e["coverage"],
             e["meets_coverage_requirements"], _extrapolation_text(e)] for name, e in named if e]
    solver = summary["solver"]
    frame = summary.get("frame") or "ISO 8855, origin on the ground at the vehicle's centre"
    parts = [
        f"<h1>Design for {escape(summary['vehicle'])} from {escape(summary['reference'])}</h1>",
        f'<p class="note">Generated by rigopt on {escape(datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"))}. '
        f"Predicted drop: the relative mAP drop of a detector trained on the reference, predicted by "
        f"{escape(summary.get('predictor') or summary['metric'])}; coverage: the "
        "fraction of ring sectors seen; a rig meets the requirements when it sees every sector the reference sees "
        f"on its own vehicle (reference coverage {pct(summary['reference_coverage'])}). The interval is the "
        "predictor's 90 % prediction interval, or said to be uninformative where it spans (nearly) every drop "
        "from 0 to 1 (half-width 0.45 or more); a rig beyond the data the predictor was fitted on extrapolates, and "
        "its prediction is less certain than the interval says.</p>",
        "<h2>Predicted transfer and coverage</h2>",
        table(["rig", "cameras", "predicted drop", "90 % interval", f"{summary['metric']} ({summary['weights']} weights)",
               "coverage", "meets coverage",
               "extrapolates"],
              [[escape(r[0]), str(r[1]), num(r[2], 3), escape(r[3]), num(r[4], 3), pct(r[5]),
                "yes" if r[6] else "no", escape(r[7])] for r in rows]),
        *(f'<p class="note">{escape(line)}.</p>' for line in summary.get("notes", ())),
    ]
    if summary.get("measured"):
        parts += measured_section(summary["measured"])
    if len(summary["per_reference"]) > 1:
        parts += ["<h2>Each reference rig</h2>",
                  table(["reference", "predicted drop", f"{summary['metric']} ({summary['weights']} weights)"],
                        [[escape(p["reference"]), num(p["predicted_drop"], 3), num(p["rigcd"], 3)]
                         for p in summary["per_reference"]])]
    parts += [
        "<h2>Solver</h2>",
        table(["stage", "value"], [
            ["MILP status", escape(solver["milp_status"])], ["MILP relative gap", f"{solver['milp_gap']:.1e}"],
            ["MILP time", num(solver["milp_seconds"], 1, " s")],
            ["candidates (offered to the MILP)", f"{solver['candidates']} ({solver['offered_to_milp']})"],
            ["repairs after mount checks", str(solver["repairs"])],
            ["continuous refinement", escape(solver["refine_status"])], ["total time", num(solver["seconds"], 1, " s")],
        ]),
        "<h2>Cameras</h2>",
        table(["camera", "zone", f"x, y, z (m, {frame})", "yaw, pitch, roll (deg; yaw > 0 left, pitch > 0 up)",
               "hfov", "image (px)", "fx (px)", "distortion", "lens hFOV x vFOV",
               "designed for (its pose against that camera's)", "RigCD's matching (t m, r rad, f deg)",
               "zone cost", "tyre spray"],
              [[escape(c["id"]), escape(c["zone"] or "-"),
                escape(", ".join(f"{v:.2f}" for v in c["position"])),
                escape(", ".join(f"{v:.1f}" for v in c["yaw_pitch_roll_deg"])),
                num(c["fov"], 1, "°"), escape(f"{c['lens']['width']}x{c['lens']['height']}"),
                num(c["lens"]["fx"], 1, ""), escape(_distortion_text(c["lens"])),
                escape(f"{c['lens']['hfov_deg']:.1f}° x {c['lens']['vfov_deg']:.1f}°"), escape(_designed_for_text(c)),
                escape(_match_text(c)), num(c.get("zone_cost"), 2, ""), escape(c.get("spray") or "-")]
               for c in summary["cameras"]], numeric_from=4),
        breakdown_note(summary),
        f'<p class="note">Positions and angles in this report: {escape(frame)} (x forward, y left, z up). The rig '
        f'file, {escape(summary["rig_file"])} beside this report, is in the benchmark\'s JSON format, whose frame is '
        "CARLA's (origin at the vehicle's centre, y to the right).</p>",
    ]
    if summary.get("packaging"):
        parts += packaging_section(summary["packaging"], frame)
    if summary.get("regions"):
        state = ("reported, not required (--require to enforce)" if not summary["regions_required"] else
                 "required of the near-field cameras" if summary["solver"].get("near_field") else "required")
        parts += [f"<h2>Regulation fields ({escape(state)})</h2>", *field_tables_html(summary["regions"])]
    if summary.get("vehicle_category"):
        parts += [f'<p class="note">Vehicle {escape(category_text(summary["vehicle_category"]))}.</p>']
    if scene is not None:
        parts += scene_section(scene, compared, summary.get("frame"))
    if figures:
        parts += ["<h2>Pictures</h2>",
                  f'<p class="note">Positions in the pictures as in the tables: {escape(frame)} (x forward, y left, '
                  "z up, metres); the reference rig on its own vehicle, from that vehicle's datum.</p>"]
        parts += [image(figures[name], name, _CAPTIONS.get(name, name)) for name in _CAPTIONS if name in figures]
    parts += ["<h2>Next steps</h2>", "<p>In this folder:</p>", "<ul>",
              *(f"<li><code>{escape(command)}</code>: {escape(why)}</li>" for command, why in NEXT_STEPS), "</ul>"]
    return page(f"Design for {summary['vehicle']} from {summary['reference']}", parts)


#: What to run next in a design's folder (the report lists them; the command prints them with full paths).
NEXT_STEPS = (
    ("rigopt check rig.json", "every mount rule, camera by camera"),
    ("rigopt coverage rig.json --out coverage", "rings, blind zone and regulation fields as a page of its own"),
    ("rigopt export rig.json --format carla --perception --out rig_carla.json", "a CARLA spawn list of the "
     "perception cameras, to render what the detector sees; opencv also carries the near-field fisheyes"),
)


def write_design_html(summary: dict, out_dir, pictures: dict[str, Path], scene: str | None = None,
                      compared: str | None = None) -> Path:
    """Write ``report.html`` into ``out_dir`` with the PNG files of ``pictures`` and the 3D view ``scene``
    (see :func:`render_design_html`) embedded."""
    path = Path(out_dir) / "report.html"
    figures = {name: Path(p).read_bytes() for name, p in pictures.items()}
    path.write_text(render_design_html(summary, figures, scene, compared), encoding="utf-8")
    return path


