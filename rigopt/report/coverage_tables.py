"""Regulation-field coverage as plain JSON values and text tables (no plotting library: the design report
writes these where its pictures are drawn elsewhere)."""

from __future__ import annotations

from rigopt.coverage.regulations import RegionCoverage


def regions_dict(regions: tuple[RegionCoverage, ...]) -> list[dict]:
    """The regulation fields' coverage (:class:`RegionCoverage`) as plain JSON values, one entry per preset:
    ``covered`` (every required point seen), ``covered_frac`` and per height, ``weighted_covered_frac`` (each point
    weighted by its criticality), the required points and those unseen, the region's area and its unseen part
    (m^2), the sampling ``spacing_m``; ``cameras``: per camera the share of the field's required points it sees
    (``seen_frac``) and sees alone (``only_frac``); ``overlap_frac`` the share seen by two or more, so that the
    ``only_frac`` values and ``overlap_frac`` add up to ``covered_frac``."""
    return [{"key": r.key, "title": r.title, "source": r.source, "heights_m": [float(h) for h in r.heights],
             "covered": r.covered, "covered_frac": r.covered_frac,
             "weighted_covered_frac": r.weighted_covered_frac,
             "height_covered_frac": [{"height_m": float(h), "covered_frac": f}
                                     for h, f in zip(r.heights, r.height_covered_frac)],
             "n_points": r.n_points, "n_unseen": int(len(r.unseen)), "area_m2": r.area_m2,
             "unseen_area_m2": r.unseen_area_m2, "spacing_m": r.spacing,
             "cameras": [{"camera": c.camera, "seen_frac": c.seen_frac, "only_frac": c.only_frac} for c in r.cameras],
             "overlap_frac": r.overlap_frac} for r in regions]


def camera_field_rows(regions: list[dict]) -> tuple[list[str], list[list[str]]]:
    """The camera -> field table of ``regions_dict`` entries as text: (column titles, rows). One row per camera,
    one column per field, each cell the share of the field's required points the camera sees and, in brackets,
    sees alone; then the rows 'seen by >= 2' and 'seen by any' (the alone shares and the first add up to the
    second)."""
    columns = ["camera", *(r["key"] for r in regions)]
    cameras = list(dict.fromkeys(c["camera"] for r in regions for c in r["cameras"]))
    shares = [{c["camera"]: c for c in r["cameras"]} for r in regions]
    rows = [[camera, *(f"{100 * s[camera]['seen_frac']:.1f} % ({100 * s[camera]['only_frac']:.1f} % alone)"
                       if camera in s else "-" for s in shares)] for camera in cameras]
    rows.append(["seen by >= 2", *(f"{100 * r['overlap_frac']:.1f} %" for r in regions)])
    rows.append(["seen by any", *(f"{100 * r['covered_frac']:.1f} %" for r in regions)])
    return columns, rows
