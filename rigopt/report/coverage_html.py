"""The self-contained HTML coverage report: tables and PNG figures embedded as data URIs, opens offline.

No external CSS, JavaScript, fonts or images: the page's only style is an inline ``<style>`` element and
every figure is a ``data:image/png;base64`` URI. Every piece of text from rigs and vehicles is escaped.
"""

from __future__ import annotations

import base64
import html
from datetime import datetime, timezone
from pathlib import Path

from rigopt.coverage.measures import CoverageComparison, CoverageReport
from rigopt.report.coverage_figures import (
    bev_figure,
    blind_figure,
    comparison_dict,
    figure_png,
    report_dict,
    rings_figure,
)
from rigopt.rig.model import Rig

REPORT_FILE = "report.html"

_STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; margin: 2em auto;
       max-width: 1200px; padding: 0 1em; color: #222; line-height: 1.4; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; }
h2 { font-size: 1.25em; margin-top: 1.8em; border-bottom: 1px solid #ccc; padding-bottom: 0.2em; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.92em; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; }
th { background: #f2f2f2; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
td.good { color: #1a7f37; } td.bad { color: #b42318; }
.warning { background: #fff4e5; border: 1px solid #f0a030; padding: 0.6em 0.9em; border-radius: 4px; }
.note { color: #555; font-size: 0.9em; }
figure { margin: 1em 0; } figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { color: #555; font-size: 0.9em; }
"""


def _e(value) -> str:
    return html.escape(str(value), quote=True)


def _pct(value) -> str:
    return "-" if value is None else f"{100.0 * value:.1f} %"


def _num(value, digits: int = 2, unit: str = "") -> str:
    return "-" if value is None else f"{value:.{digits}f}{unit}"


def _signed_pct(value) -> str:
    return f"{100.0 * value:+.1f} pp"


def _cell(text: str, cls: str = "") -> str:
    return f'<td class="{cls}">{text}</td>' if cls else f"<td>{text}</td>"


def _table(header: list[str], rows: list[list[str]], numeric_from: int = 1) -> str:
    """An HTML table; ``rows`` hold already escaped cell HTML; columns from ``numeric_from`` are right-aligned
    unless a cell is given as a ready ``<td ...>`` element."""
    head = "".join(f"<th>{_e(h)}</th>" for h in header)
    body = []
    for row in rows:
        cells = [c if c.startswith("<td") else _cell(c, "num" if k >= numeric_from else "") for k, c in enumerate(row)]
        body.append(f"<tr>{''.join(cells)}</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def _diff_cell(value: float, text: str, better_when_positive: bool = True) -> str:
    cls = "num"
    if abs(value) > 1e-12:
        cls += " good" if (value > 0) == better_when_positive else " bad"
    return f'<td class="{cls}">{_e(text)}</td>'


def _image(png: bytes, alt: str, caption: str) -> str:
    data = base64.b64encode(png).decode("ascii")
    return (f'<figure><img src="data:image/png;base64,{data}" alt="{_e(alt)}">'
            f"<figcaption>{_e(caption)}</figcaption></figure>")


def _figures(report: CoverageReport, rig: Rig, compare_report: CoverageReport | None,
             figures: dict[str, Path] | None) -> dict[str, bytes]:
    """PNG bytes of the bev, rings and blind figures: read from ``figures`` paths when given, else drawn."""
    if figures is not None:
        return {name: Path(path).read_bytes() for name, path in figures.items()}
    return {"bev": figure_png(bev_figure(report, rig)), "rings": figure_png(rings_figure(report, compare_report)),
            "blind": figure_png(blind_figure(report))}


_CAPTIONS = {
    "bev": "Bird's-eye view: how many cameras see each cell at the map's height (grey: none; white: the body), "
           "with the rings and the cameras' horizontal frustums (10 m). Forward is up, the vehicle's left on the left.",
    "rings": "Camera count per azimuth on each ring (forward up, left on the left; the curves of successive ring "
             "distances are shifted slightly apart); the compared rig dashed.",
    "blind": "Near-field blind zone: per azimuth, the distance from the body at which the ground becomes visible; "
             "azimuths with no ground seen within the search limit are drawn at the limit and marked x.",
}


def render_html(report: CoverageReport, rig: Rig, comparison: CoverageComparison | None = None,
                compare_report: CoverageReport | None = None, figures: dict[str, bytes] | None = None) -> str:
    """The report page as a string; ``figures`` maps ``bev``, ``rings``, ``blind`` to PNG bytes (omitted
    figures are left out)."""
    data = report_dict(report)
    other = report_dict(compare_report) if compare_report is not None else None
    settings = report.settings
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>Coverage of {_e(report.rig)} on {_e(report.vehicle)}</title>",
        f"<style>{_STYLE}</style></head><body>",
        f"<h1>Coverage of rig {_e(report.rig)} on {_e(report.vehicle)}</h1>",
        f'<p class="note">{len(rig.cameras)} cameras; generated by rigopt on '
        f"{_e(datetime.now(timezone.utc).strftime('%Y-%m-%d %H:%M UTC'))}. Distances are measured from the body's "
        "footprint outline; azimuth 0 is forward, counter-clockwise (90 deg = left).</p>",
    ]
    if report.cameras_inside:
        parts.append(f'<p class="warning"><strong>Warning:</strong> cameras inside the body: '
                     f"{_e(', '.join(report.cameras_inside))}. They are still used in every measure, but the body "
                     "blocks their view; check their positions.</p>")
    if compare_report is not None and compare_report.cameras_inside:
        parts.append(f'<p class="warning"><strong>Warning:</strong> cameras of {_e(compare_report.rig)} inside '
                     f"its body: {_e(', '.join(compare_report.cameras_inside))}.</p>")

    parts.append("<h2>Rings</h2>")
    parts.append(f'<p class="note">Fraction of each ring ({settings.ring_samples} azimuths, the given distance from '
                 "the body) seen by at least one camera (covered) and by at least two (overlap).</p>")
    header = ["distance (m)", "height (m)", "covered", "overlap >= 2"]
    others = {(r["distance_m"], r["height_m"]): r for r in other["rings"]} if other is not None else {}
    if other is not None:
        header += [f"covered ({compare_report.rig})", f"overlap >= 2 ({compare_report.rig})"]
    rows = []
    for ring in data["rings"]:
        row = [_num(ring["distance_m"], 1), _num(ring["height_m"], 1), _pct(ring["covered_frac"]),
               _pct(ring["overlap2_frac"])]
        if other is not None:
            match = others.get((ring["distance_m"], ring["height_m"]))
            row += [_pct(match["covered_frac"]), _pct(match["overlap2_frac"])] if match else ["-", "-"]
        rows.append(row)
    parts.append(_table(header, rows))

    parts.append("<h2>Blind zone and bird's-eye view</h2>")
    blind, bev = data["blind_distance_m"], data["bev"]
    max_text = (f"not found within {_num(data['blind_search_m'], 0)} m on {_pct(data['blind_not_found_frac'])} "
                "of azimuths" if data["blind_not_found_frac"] > 0 else _num(blind["max"], 2, " m"))
    parts.append(_table(["measure", "value"], [
        [f"unseen ground within {_num(data['blind_radius_m'], 0)} m of the body",
         _num(data["blind_area_m2_within_5m"], 1, " m²")],
        ["blind distance on the ground: min", _num(blind["min"], 2, " m")],
        ["blind distance on the ground: median", _num(blind["median"], 2, " m")],
        ["blind distance on the ground: max", _e(max_text)],
        [f"bird's-eye cells within 20 m seen (at {_num(bev['height_m'], 1)} m height)",
         _pct(bev["covered_frac_within_20m"])],
        ["bird's-eye cells within 20 m seen by >= 2", _pct(bev["overlap2_frac_within_20m"])],
        ["most cameras seeing one cell", str(bev["max_count"])],
    ]))

    parts.append("<h2>Cameras</h2>")
    ring_d, ring_h = data["overlap_ring"]["distance_m"], data["overlap_ring"]["height_m"]
    parts.append(f'<p class="note">Self-occluded: the fraction of the image that shows the body. Overlaps: degrees '
                 f"of the ring {_e(f'{ring_d:g}')} m from the body at {_e(f'{ring_h:g}')} m height seen by both "
                 "cameras.</p>")
    inside = set(report.cameras_inside)
    by_id = {c.id: c for c in rig.cameras}
    rows = []
    for camera in data["cameras"]:
        spec = by_id.get(camera["id"])
        position = ", ".join(f"{v:.2f}" for v in spec.position) if spec is not None else "-"
        overlaps = ", ".join(f"{k} {v:.1f}°" for k, v in camera["overlap_deg"].items()) or "none"
        rows.append([_e(camera["id"] + (" (inside the body)" if camera["id"] in inside else "")), _e(position),
                     _num(spec.fov, 1, "°") if spec is not None else "-", _pct(camera["self_occluded_frac"]),
                     f"<td>{_e(overlaps)}</td>"])
    parts.append(_table(["camera", "position (m)", "hfov", "self-occluded", "overlaps"], rows))

    if comparison is not None:
        diff = comparison_dict(comparison)
        sectors = settings.sectors
        parts.append(f"<h2>Comparison: {_e(diff['b'])} minus {_e(diff['a'])}</h2>")
        parts.append(f'<p class="note">Differences in percentage points (pp) of {_e(diff["b"])} minus '
                     f"{_e(diff['a'])}; sectors: of {sectors} equal azimuth sectors, how many {_e(diff['b'])} "
                     "covers more / less of.</p>")
        rows = []
        for ring in diff["rings"]:
            gained = sum(v > 1e-9 for v in ring["sector_diff"])
            lost = sum(v < -1e-9 for v in ring["sector_diff"])
            rows.append([_num(ring["distance_m"], 1), _num(ring["height_m"], 1),
                         _diff_cell(ring["covered_diff"], _signed_pct(ring["covered_diff"])),
                         _diff_cell(ring["overlap2_diff"], _signed_pct(ring["overlap2_diff"])),
                         str(gained), str(lost)])
        parts.append(_table(["distance (m)", "height (m)", "covered", "overlap >= 2", "sectors better",
                             "sectors worse"], rows))
        area = diff["blind_area_diff_m2"]
        parts.append("<p>Unseen ground area within the blind radius: "
                     + (f'<strong>{_e(f"{area:+.1f}")} m²</strong>' if area is not None else "-")
                     + f" ({_e(diff['b'])} minus {_e(diff['a'])}; negative is better).</p>")

    if figures:
        parts.append("<h2>Figures</h2>")
        for name in ("bev", "rings", "blind"):
            if name in figures:
                parts.append(_image(figures[name], f"{name} figure of {report.rig}", _CAPTIONS[name]))
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def write_html_report(report: CoverageReport, out_dir, rig: Rig, comparison: CoverageComparison | None = None,
                      compare_report: CoverageReport | None = None, *,
                      figures: dict[str, Path] | None = None) -> Path:
    """Write ``report.html`` into ``out_dir`` (created): self-contained, figures embedded as PNG data URIs.

    ``figures`` maps ``bev``, ``rings``, ``blind`` to PNG files already written (e.g. by the CLI) so that they
    are not drawn twice; without it the figures are drawn here (``compare_report`` dashed in the ring plot).
    Returns the path of the page.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    page = render_html(report, rig, comparison, compare_report, _figures(report, rig, compare_report, figures))
    path = out_dir / REPORT_FILE
    path.write_text(page, encoding="utf-8")
    return path
