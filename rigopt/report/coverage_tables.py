"""Regulation-field coverage as plain JSON values, text tables and the HTML tables of the coverage page and the
design report (no plotting library: the design report writes these where its pictures are drawn elsewhere)."""

from __future__ import annotations

from rigopt.coverage.regulations import RegionCoverage
from rigopt.report.html_page import escape, num, pct, table


def regions_dict(regions: tuple[RegionCoverage, ...]) -> list[dict]:
    """The regulation fields' coverage (:class:`RegionCoverage`) as plain JSON values, one entry per preset:
    ``covered`` (every required point seen), ``covered_frac`` and per height (seen at the pixels the field's
    ``test_object`` asks: its name, height and ``min_px``), ``in_view_frac`` (in some camera's
    view with nothing in between, however small), ``weighted_covered_frac`` (each point
    weighted by its criticality), the required points, those unseen and those not asked for (``n_excluded``:
    inside the body's footprint or a keep-out in force), the region's area and its unseen part
    (m^2), the sampling ``spacing_m``; ``cameras``: per camera the share of the field's required points it sees
    (``seen_frac``) and sees alone (``only_frac``); ``overlap_frac`` the share seen by two or more, so that the
    ``only_frac`` values and ``overlap_frac`` add up to ``covered_frac``."""
    return [{"key": r.key, "title": r.title, "source": r.source, "heights_m": [float(h) for h in r.heights],
             "covered": r.covered, "covered_frac": r.covered_frac, "in_view_frac": r.in_view_frac,
             "test_object": r.test_object.as_dict() if r.test_object else None,
             "weighted_covered_frac": r.weighted_covered_frac,
             "height_covered_frac": [{"height_m": float(h), "covered_frac": f}
                                     for h, f in zip(r.heights, r.height_covered_frac)],
             "n_points": r.n_points, "n_unseen": int(len(r.unseen)), "n_excluded": r.n_excluded, "area_m2": r.area_m2,
             "unseen_area_m2": r.unseen_area_m2, "spacing_m": r.spacing,
             "cameras": [{"camera": c.camera, "seen_frac": c.seen_frac, "only_frac": c.only_frac} for c in r.cameras],
             "overlap_frac": r.overlap_frac} for r in regions]


def _share_text(share: dict | None) -> str:
    """A camera's share of a field: '62.0 %', with '(4.0 % alone)' where it is the only camera seeing some of
    the field's points; '-' without an entry."""
    if share is None:
        return "-"
    alone = f" ({100 * share['only_frac']:.1f} % alone)" if share["only_frac"] > 0 else ""
    return f"{100 * share['seen_frac']:.1f} %{alone}"


def camera_field_rows(regions: list[dict]) -> tuple[list[str], list[list[str]]]:
    """The camera -> field table of ``regions_dict`` entries as text: (column titles, rows). One row per camera
    that sees some point of some field, one column per field, each cell the share of the field's required
    points the camera sees and, where it is the only camera for some of them, the share it sees alone in
    brackets; then the rows 'seen by >= 2' and 'seen by any' (the alone shares and the first add up to the
    second)."""
    columns = ["camera", *(r["key"] for r in regions)]
    cameras = list(dict.fromkeys(c["camera"] for r in regions for c in r["cameras"] if c["seen_frac"] > 0))
    shares = [{c["camera"]: c for c in r["cameras"]} for r in regions]
    rows = [[camera, *(_share_text(s.get(camera)) for s in shares)] for camera in cameras]
    rows.append(["seen by >= 2", *(f"{100 * r['overlap_frac']:.1f} %" for r in regions)])
    rows.append(["seen by any", *(f"{100 * r['covered_frac']:.1f} %" for r in regions)])
    return columns, rows


def resolution_text(region: dict) -> str:
    """What a field's points are seen at, e.g. "a cyclist 1.6 m tall at >= 25 px"; "in view" for a field without
    a test object."""
    thing = region.get("test_object")
    if not thing:
        return "in view"
    return f"{thing['name']} {thing['height_m']:g} m tall at >= {thing['min_px']:g} px"


def _heights_text(region: dict) -> str:
    """A field's seen share per test-object height, e.g. '0 m 100.0 %, 0.8 m 97.5 %'."""
    return ", ".join(f"{h['height_m']:g} m {pct(h['covered_frac'])}" for h in region["height_covered_frac"])


def field_tables_html(regions: list[dict]) -> list[str]:
    """The regulation fields in a report page (``regions_dict`` entries), as HTML fragments: a note and the table
    of the fields (covered, seen, unseen area, criticality-weighted seen, seen per height, area, source), then a
    note and the camera-by-field map (:func:`camera_field_rows`). Shared by the coverage page and the design
    report."""
    spacing = ", ".join(dict.fromkeys(f"{r['spacing_m']:g}" for r in regions))
    rows = [[f"<td>{escape(r['key'])}</td>", f"<td>{escape(r['title'])}</td>", "yes" if r["covered"] else "no",
             pct(r["covered_frac"]), f"<td>{escape(resolution_text(r))}</td>", pct(r["in_view_frac"]),
             num(r["unseen_area_m2"], 1, " m²"), pct(r["weighted_covered_frac"]),
             f"<td>{escape(_heights_text(r))}</td>", num(r["area_m2"], 1, " m²"), f"<td>{escape(r['source'])}</td>"]
            for r in regions]
    columns, shares = camera_field_rows(regions)
    return ['<p class="note">Share of each field\'s required points (a grid and the field\'s outline every '
            f"{escape(spacing)} m, at every test-object height, each checked for the body's occlusion) seen by at "
            "least one camera with the field's test object at least as many pixels tall as asked (in view: seen "
            "however small), and the field's ground where some height is unseen; weighted seen: each point "
            "weighted by its criticality (nearer the body and the nearside front corner weighs more). A field is "
            "covered when every point is. Fields, figures and sources: docs/regulations.md.</p>",
            table(["field", "what", "covered", "seen", "seen at", "in view", "unseen area", "weighted seen",
                   "seen per height", "area", "source"], rows),
            '<p class="note">Which camera covers which field: one row per camera that sees some field, each cell '
            "the share of the field's required points the camera sees and, where it is the only camera seeing some "
            "of them, the share it sees alone; the alone shares and the share seen by two cameras or more add up "
            "to the share seen by any.</p>",
            table(columns, [[f"<td>{escape(row[0])}</td>", *(escape(c) for c in row[1:])] for row in shares])]
