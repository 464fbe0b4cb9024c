"""The coverage report's JSON shape and its figures: bird's-eye counts, ring polar plots, blind-zone plot.

Every picture is drawn with forward (+x) up and the vehicle's left (+y) on the left, as seen from above:
in the polar plots azimuth 0 (forward) is up and azimuths grow counter-clockwise (90 deg = left); in the
top views (bird's-eye panels, blind zone, regulation fields) the horizontal axis is y with +y to the left,
and positions are measured from a datum (``datum``, :class:`rigopt.coverage.packaging.ReportDatum`: the
vehicle's centre by default, the report's datum where its tables use one), which the axis titles name.
The reports hold vehicle-centre positions; the drawing shifts them. Figures are matplotlib ``Figure``
objects (no pyplot) saved as PNG.
"""

from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np
import shapely
from matplotlib import colormaps
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from rigopt.coverage.measures import CoverageComparison, CoverageReport, RingReport
from rigopt.coverage.packaging import CENTRE_DATUM, ReportDatum
from rigopt.coverage.regulations import RegionCoverage
from rigopt.rig.model import Rig

DPI = 120
#: Length (m) of the horizontal frustum wedges drawn in the bird's-eye panels.
FRUSTUM_DRAW_LENGTH = 10.0
#: Half-size (m) of the near bird's-eye panel, around the footprint's centre.
NEAR_HALF_SIZE = 15.0
#: Radial shift between the curves of successive ring distances in the ring plots, so equal counts stay apart.
RING_CURVE_OFFSET = 0.07
#: Bird's-eye coverage fractions are reported within this distance (m) of the body.
BEV_SUMMARY_RADIUS = 20.0
_UNSEEN_COLOUR = (0.80, 0.80, 0.80)
_DIRECTION_TICKS = ([0, 45, 90, 135, 180, 225, 270, 315],
                    ["front", "45", "left", "135", "rear", "225", "right", "315"])


# --------------------------------------------------------------------------------------------------- JSON


def _number(value) -> float | None:
    """``value`` as a float, or None when it is NaN or inf (JSON has neither)."""
    value = float(value)
    return value if math.isfinite(value) else None


def bev_summary(report: CoverageReport, within: float = BEV_SUMMARY_RADIUS) -> dict:
    """Fractions of the bird's-eye cells outside the body and within ``within`` m of it seen by >= 1 and
    >= 2 cameras; the largest count."""
    bev = report.bev
    xx, yy = np.meshgrid(bev.x, bev.y)
    distance = report.footprint.distance_to(np.column_stack([xx.ravel(), yy.ravel()])).reshape(xx.shape)
    near = (distance > 0) & (distance <= within) & (bev.counts >= 0)
    counts = bev.counts[near]
    return {
        "covered_frac": float(np.mean(counts >= 1)) if counts.size else 0.0,
        "overlap2_frac": float(np.mean(counts >= 2)) if counts.size else 0.0,
        "max_count": int(bev.counts.max(initial=0)),
    }


def report_dict(report: CoverageReport, rig: Rig | None = None, datum: ReportDatum = CENTRE_DATUM) -> dict:
    """The coverage report as plain JSON values (inf and NaN become None).

    ``frame`` and ``origin_from_vehicle_centre_m``: the frame of its positions (``datum``, e.g. the report's,
    :func:`rigopt.coverage.packaging.report_origin`; :meth:`ReportDatum.to_dict`); ``rings``: covered (>= 1
    camera) and overlap (>= 2) fractions per ring; ``blind_area_m2_within_5m``: the unseen ground area within
    ``blind_radius_m`` (default 5) of the body; ``blind_distance_m``: statistics over azimuths of the distance
    at which the ground becomes visible (None when some azimuth sees no ground within ``blind_search_m``,
    counted by ``blind_not_found_frac``); ``bev``: the bird's-eye map's fractions within 20 m of the body.
    With ``rig`` (the measured rig, vehicle-centre frame) each camera's ``position`` [x, y, z] m from
    ``datum``. Distances, areas and shares hold in any frame.
    """
    settings, blind = report.settings, report.blind
    distance = np.asarray(blind.distance_m, dtype=float)
    bev = bev_summary(report)
    positions = ({c.id: (c.position - datum.point + 0.0).tolist() for c in rig.cameras}  # + 0.0: no -0.0
                 if rig is not None else {})
    return {
        "rig": report.rig,
        "vehicle": report.vehicle,
        **datum.to_dict(),
        "rings": [{"distance_m": r.distance_m, "height_m": r.height_m, "covered_frac": r.covered_frac,
                   "overlap2_frac": r.overlap2_frac} for r in report.rings],
        "blind_area_m2_within_5m": _number(blind.area_m2),
        "blind_radius_m": _number(blind.radius_m),
        "blind_distance_m": {"min": _number(np.min(distance)), "median": _number(np.median(distance)),
                             "max": _number(np.max(distance))},
        "blind_not_found_frac": float(np.mean(~np.isfinite(distance))),
        "blind_search_m": _number(settings.blind_search),
        "cameras": [{"id": c.id, **({"position": positions.get(c.id)} if rig is not None else {}),
                     "self_occluded_frac": c.self_occluded_frac,
                     "overlap_deg": {k: float(v) for k, v in c.overlap_deg.items()},
                     "lens": c.lens.summary()} for c in report.cameras],
        "overlap_ring": {"distance_m": settings.overlap_ring[0], "height_m": settings.overlap_ring[1]},
        "cameras_inside": list(report.cameras_inside),
        "bev": {"height_m": report.bev.height_m, "cell_m": settings.bev_cell, "extent_m": settings.bev_extent,
                "covered_frac_within_20m": bev["covered_frac"], "overlap2_frac_within_20m": bev["overlap2_frac"],
                "max_count": bev["max_count"]},
    }


def comparison_dict(comparison: CoverageComparison) -> dict:
    """The comparison as plain JSON values: every difference is ``b`` minus ``a``; ``sector_diff`` lists the
    per-sector covered fraction differences from azimuth -180 deg counter-clockwise."""
    return {
        "a": comparison.a,
        "b": comparison.b,
        "rings": [{"distance_m": r.distance_m, "height_m": r.height_m, "covered_diff": float(r.covered_diff),
                   "overlap2_diff": float(r.overlap2_diff),
                   "sector_diff": [float(v) for v in np.asarray(r.sector_diff, dtype=float)]}
                  for r in comparison.rings],
        "blind_area_diff_m2": _number(comparison.blind_area_diff_m2),
    }


# ---------------------------------------------------------------------------------------------- helpers


def _save(figure: Figure, path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=DPI)
    return path


def figure_png(figure: Figure) -> bytes:
    """The PNG bytes of ``figure``."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=DPI)
    return buffer.getvalue()


def _top(points, origin) -> tuple[np.ndarray, np.ndarray]:
    """Plot coordinates of vehicle-centre-frame points (..., >= 2) m in a forward-up top view measured from
    ``origin`` (>= 2,) m, a point in that frame: (y, x); the axes that show them have their horizontal axis
    inverted so that +y (left) is on the left."""
    points, origin = np.asarray(points, dtype=float), np.asarray(origin, dtype=float)
    return points[..., 1] - origin[1], points[..., 0] - origin[0]


def _top_titles(ax, datum: ReportDatum) -> None:
    """Name a top view's axes and the datum they are measured from."""
    ax.set_xlabel("y left (m), the vehicle's left on the left")
    ax.set_ylabel(f"x forward (m), {datum.axis_text}")


def _polar_axes(ax, title: str) -> None:
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(1)
    ax.set_thetagrids(*_DIRECTION_TICKS)
    ax.set_title(title, pad=14)


def _closed(azimuths, values) -> tuple[np.ndarray, np.ndarray]:
    """Azimuths sorted and the curve closed (first point repeated at the end) for a polar line."""
    order = np.argsort(azimuths)
    theta, r = np.asarray(azimuths, dtype=float)[order], np.asarray(values, dtype=float)[order]
    return np.append(theta, theta[0] + 2 * np.pi), np.append(r, r[0])


def _ring_heights(report: CoverageReport | RingReport) -> list[float]:
    return list(dict.fromkeys(r.height_m for r in report.rings))


def _distance_colours(distances) -> dict[float, tuple]:
    palette = colormaps["viridis"]
    n = max(len(distances) - 1, 1)
    return {d: palette(0.9 * k / n) for k, d in enumerate(distances)}


# ------------------------------------------------------------------------------------------ bird's eye


def _count_colours(top: int) -> tuple[ListedColormap, BoundaryNorm]:
    """Discrete colours for counts 0 .. top: grey for 0, a sequential palette for 1 .. top; masked cells white."""
    palette = colormaps["YlGnBu"]
    colours = [_UNSEEN_COLOUR] + [palette(0.25 + 0.6 * (k - 1) / max(top - 1, 1)) for k in range(1, top + 1)]
    cmap = ListedColormap(colours).with_extremes(bad="white")
    return cmap, BoundaryNorm(np.arange(-0.5, top + 1.0), cmap.N)


def _draw_frustums(ax, rig: Rig, labels: bool, origin, inside: tuple[str, ...] = ()) -> None:
    """Cameras (vehicle-centre frame) as dots with their horizontal frustum wedge, measured from ``origin``
    (3,) m; cameras inside the body as black crosses."""
    for camera in rig.cameras:
        half = np.deg2rad(camera.fov / 2.0)
        rays = [camera.rotation @ np.array([np.cos(a), np.sin(a), 0.0]) for a in np.linspace(-half, half, 16)]
        tips = np.array([camera.position + FRUSTUM_DRAW_LENGTH * r for r in rays])
        wedge = np.vstack([camera.position, tips, camera.position])
        ax.plot(*_top(wedge, origin), color="tab:red", linewidth=0.7, alpha=0.85, zorder=6)
        if camera.id in inside:
            ax.plot(*_top(camera.position, origin), "X", color="black", markersize=6, zorder=7)
        else:
            ax.plot(*_top(camera.position, origin), "o", color="tab:red", markersize=3.5, markeredgecolor="white",
                    markeredgewidth=0.5, zorder=7)
        if labels:
            tip = camera.position + 2.2 * camera.forward
            text = camera.id.removeprefix("CAM_") + (" (inside the body)" if camera.id in inside else "")
            ax.annotate(text, _top(tip, origin), fontsize=6, color="darkred", ha="center",
                        va="center", zorder=8,
                        bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.7})


def _draw_bev_panel(ax, report: CoverageReport, rig: Rig | None, half: float, cmap, norm, near: bool,
                    datum: ReportDatum):
    bev, footprint = report.bev, report.footprint
    cell, origin = report.settings.bev_cell, datum.point
    counts = np.ma.masked_less(bev.counts, 0).T  # rows along x (forward, up), columns along y
    y, x = _top(np.stack([bev.x[[0, -1]], bev.y[[0, -1]]], axis=1), origin)
    extent = (y[0] - cell / 2, y[1] + cell / 2, x[0] - cell / 2, x[1] + cell / 2)
    image = ax.imshow(counts, origin="lower", extent=extent, cmap=cmap, norm=norm, interpolation="nearest")
    ax.fill(*_top(footprint.outline, origin), facecolor="white", edgecolor="black", linewidth=1.0, zorder=3)
    azimuths = report.settings.azimuths(720)
    for distance in report.settings.ring_distances:
        ring = footprint.ring_points(azimuths, distance, bev.height_m)
        closed = np.vstack([ring, ring[:1]])
        ax.plot(*_top(closed, origin), color="black", linewidth=0.5, alpha=0.55, zorder=4)
        if distance < half * 1.3:
            label = footprint.ring_points([np.deg2rad(30.0)], distance, bev.height_m)[0]
            ax.annotate(f"{distance:g} m", _top(label, origin), fontsize=6 if near else 7, color="black", zorder=5,
                        bbox={"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.6})
    if rig is not None:
        _draw_frustums(ax, rig, near, origin, report.cameras_inside)
    cy, cx = _top(footprint.centre, origin)
    ax.set_xlim(cy + half, cy - half)  # +y (left) on the left
    ax.set_ylim(cx - half, cx + half)
    ax.set_aspect("equal")
    _top_titles(ax, datum)
    return image


def bev_figure(report: CoverageReport, rig: Rig | None = None, datum: ReportDatum = CENTRE_DATUM) -> Figure:
    """Two bird's-eye panels (full extent and +-15 m) of how many cameras see each cell at the map's height,
    positions measured from ``datum``."""
    top = max(int(report.bev.counts.max(initial=0)), 1)
    cmap, norm = _count_colours(top)
    figure = Figure(figsize=(14, 7.2), dpi=DPI, layout="constrained")
    full, near = figure.subplots(1, 2)
    image = _draw_bev_panel(full, report, rig, report.settings.bev_extent, cmap, norm, False, datum)
    _draw_bev_panel(near, report, rig, NEAR_HALF_SIZE, cmap, norm, True, datum)
    full.set_title(f"full extent (+-{report.settings.bev_extent:g} m)")
    near.set_title(f"near view (+-{NEAR_HALF_SIZE:g} m)" + (", frustums 10 m" if rig is not None else ""))
    rings = ", ".join(f"{d:g}" for d in report.settings.ring_distances)
    figure.suptitle(f"{report.rig} on {report.vehicle}: cameras seeing each {report.settings.bev_cell:g} m cell "
                    f"at {report.bev.height_m:g} m height (rings at {rings} m from the body; white = body)")
    bar = figure.colorbar(image, ax=[full, near], ticks=np.arange(0, top + 1), shrink=0.8)
    bar.set_label("cameras seeing the cell")
    return figure


def write_bev_figure(report: CoverageReport, path, rig: Rig | None = None, datum: ReportDatum = CENTRE_DATUM) -> Path:
    """The bird's-eye count map of ``report`` (with ``rig``'s cameras and frustum wedges when given), measured
    from ``datum``; PNG at ``path``."""
    return _save(bev_figure(report, rig, datum), path)


# ------------------------------------------------------------------------------------------------ rings


def rings_figure(report: CoverageReport | RingReport, compare: CoverageReport | RingReport | None = None) -> Figure:
    """One polar panel per ring height: cameras seeing each azimuth, one curve per ring distance; ``compare``
    dashed. Either report kind: only the rings are drawn."""
    heights = _ring_heights(report)
    distances = list(dict.fromkeys(r.distance_m for r in report.rings))
    colours = _distance_colours(distances)
    others = {(r.distance_m, r.height_m): r for r in compare.rings} if compare is not None else {}
    top = max([int(r.counts.max(initial=0)) for r in report.rings] +
              [int(r.counts.max(initial=0)) for r in others.values()] + [1])
    figure = Figure(figsize=(6.2 * len(heights) + 1.6, 6.6), dpi=DPI, layout="constrained")
    axes = figure.subplots(1, len(heights), subplot_kw={"projection": "polar"}, squeeze=False)[0]
    offsets = {d: RING_CURVE_OFFSET * (k - (len(distances) - 1) / 2) for k, d in enumerate(distances)}
    for ax, height in zip(axes, heights):
        _polar_axes(ax, f"rings at {height:g} m height")
        for ring in (r for r in report.rings if r.height_m == height):
            shift = offsets[ring.distance_m]
            ax.plot(*_closed(ring.azimuths, ring.counts + shift), color=colours[ring.distance_m], linewidth=1.3)
            other = others.get((ring.distance_m, height))
            if other is not None:
                ax.plot(*_closed(other.azimuths, other.counts + shift), color=colours[ring.distance_m],
                        linewidth=1.1, linestyle=(0, (3, 2)))
        ax.set_rorigin(-1.0)
        ax.set_rlim(-0.35, top + 0.35)
        ax.set_rticks(np.arange(0, top + 1))
        ax.set_rlabel_position(202.5)
    handles = [Line2D([], [], color=colours[d], label=f"{d:g} m") for d in distances]
    if compare is not None:
        handles += [Line2D([], [], color="black", label=report.rig),
                    Line2D([], [], color="black", linestyle=(0, (3, 2)), label=compare.rig)]
    figure.legend(handles=handles, loc="outside right center", title="ring distance", fontsize=9)
    title = f"{report.rig} on {report.vehicle}" + (f" vs {compare.rig} on {compare.vehicle} (dashed)"
                                                   if compare is not None else "")
    figure.suptitle(f"{title}: cameras seeing each azimuth of the rings\n(radius = camera count, each distance's "
                    f"curve shifted by {RING_CURVE_OFFSET:g} so that equal counts stay apart; forward up, "
                    "left on the left)")
    return figure


def write_rings_figure(report: CoverageReport | RingReport, path,
                       compare: CoverageReport | RingReport | None = None) -> Path:
    """Polar plots of the camera count per azimuth on every ring of ``report`` (``compare`` dashed); PNG."""
    return _save(rings_figure(report, compare), path)


# ------------------------------------------------------------------------------------------------ blind


def _blind_outline(report: CoverageReport) -> np.ndarray:
    """(a, 2) ground points where the ground becomes visible per azimuth (the search limit where it never
    does), grouped by distance so that each offset outline is built once."""
    blind, footprint = report.blind, report.footprint
    distance = np.where(np.isfinite(blind.distance_m), blind.distance_m, report.settings.blind_search)
    points = np.zeros((len(distance), 2))
    for value in np.unique(distance):
        pick = distance == value
        points[pick] = footprint.ring_points(blind.azimuths[pick], float(value), 0.0)[:, :2]
    return points


def blind_figure(report: CoverageReport, datum: ReportDatum = CENTRE_DATUM) -> Figure:
    """Left: polar plot of the blind distance per azimuth; right: the same boundary on the ground, top view
    measured from ``datum``."""
    blind, settings, origin = report.blind, report.settings, datum.point
    missing = ~np.isfinite(blind.distance_m)
    shown = np.where(missing, settings.blind_search, blind.distance_m)
    figure = Figure(figsize=(13.5, 6.6), dpi=DPI, layout="constrained")
    polar = figure.add_subplot(1, 2, 1, projection="polar")
    ground = figure.add_subplot(1, 2, 2)

    _polar_axes(polar, "blind distance (m from the body) per azimuth")
    polar.fill_between(*_closed(blind.azimuths, shown), 0, color="tab:red", alpha=0.15, linewidth=0)
    polar.plot(*_closed(blind.azimuths, shown), color="tab:red", linewidth=1.3, label="blind distance")
    circle = np.linspace(0, 2 * np.pi, 361)
    polar.plot(circle, np.full_like(circle, blind.radius_m), color="black", linestyle="--", linewidth=0.8,
               label=f"{blind.radius_m:g} m (area radius)")
    if missing.any():
        polar.plot(blind.azimuths[missing], shown[missing], "x", color="darkred", markersize=3,
                   label=f"not seen within {settings.blind_search:g} m")
    top = float(np.max(shown)) if shown.size else settings.blind_search
    polar.set_rlim(0, max(top, blind.radius_m) * 1.08)
    polar.set_rlabel_position(202.5)
    polar.legend(loc="lower left", bbox_to_anchor=(-0.12, -0.12), fontsize=8)

    outline = _blind_outline(report)
    closed = np.vstack([outline, outline[:1]])
    ground.fill(*_top(closed, origin), facecolor="tab:red", alpha=0.15, linewidth=0)
    ground.plot(*_top(closed, origin), color="tab:red", linewidth=1.2)
    if missing.any():
        ground.plot(*_top(outline[missing], origin), "x", color="darkred", markersize=3)
    radius = report.footprint.ring_points(settings.azimuths(720), blind.radius_m, 0.0)
    ground.plot(*_top(np.vstack([radius, radius[:1]]), origin), color="black", linestyle="--", linewidth=0.8)
    ground.fill(*_top(report.footprint.outline, origin), facecolor="white", edgecolor="black", linewidth=1.0)
    reach = max(float(np.max(np.abs(closed - report.footprint.centre))), float(np.max(np.abs(
        radius[:, :2] - report.footprint.centre)))) + 1.0
    cy, cx = _top(report.footprint.centre, origin)
    ground.set_xlim(cy + reach, cy - reach)
    ground.set_ylim(cx - reach, cx + reach)
    ground.set_aspect("equal")
    ground.grid(alpha=0.3)
    _top_titles(ground, datum)
    ground.set_title(f"top view: unseen ground area within {blind.radius_m:g} m = {blind.area_m2:.1f} m2")
    finite = blind.distance_m[~missing]
    median = float(np.median(blind.distance_m))
    stats = (f"min {finite.min():.2f} m, median {f'{median:.2f} m' if math.isfinite(median) else 'not found'}, "
             f"max {'not found' if missing.any() else f'{finite.max():.2f} m'}" if finite.size else
             f"no ground seen within {settings.blind_search:g} m")
    figure.suptitle(f"{report.rig} on {report.vehicle}: near-field blind zone on the ground ({stats}; "
                    "forward up, left on the left)")
    return figure


def write_blind_figure(report: CoverageReport, path, datum: ReportDatum = CENTRE_DATUM) -> Path:
    """Polar plot of the blind distance per azimuth (never seen: drawn at the search limit, marked x) and its
    top view measured from ``datum``; PNG at ``path``."""
    return _save(blind_figure(report, datum), path)


# ------------------------------------------------------------------------------------- regulation fields


def regions_figure(regions: tuple[RegionCoverage, ...], report: CoverageReport | RingReport,
                   rig: Rig | None = None, datum: ReportDatum = CENTRE_DATUM) -> Figure:
    """Top view of the regulation fields (outlines) over the body, the ground positions where some height is
    unseen marked, and ``rig``'s cameras with their frustum wedges; forward up, the vehicle's left on the left,
    positions measured from ``datum``. Either report kind: only its footprint and cameras inside the body are
    drawn."""
    origin = datum.point
    bounds = [report.footprint.polygon.bounds] + [r.polygon.bounds for r in regions if not r.polygon.is_empty]
    low = np.min([b[:2] for b in bounds], axis=0) - 1.0 - origin[:2]
    high = np.max([b[2:] for b in bounds], axis=0) + 1.0 - origin[:2]
    aspect = (high[1] - low[1]) / (high[0] - low[0])  # across / along, as drawn
    figure = Figure(figsize=(float(np.clip(9.0 * aspect + 1.5, 6.0, 16.0)), 9.0), dpi=DPI, layout="constrained")
    ax = figure.subplots()
    ax.fill(*_top(report.footprint.outline, origin), facecolor="white", edgecolor="black", linewidth=1.0, zorder=3)
    palette = colormaps["tab10"]
    for k, region in enumerate(regions):
        colour = palette(k % 10)
        for ring in _rings(region.polygon) if not region.polygon.is_empty else []:
            ax.plot(*_top(ring, origin), color=colour, linewidth=1.2, zorder=4)
        unseen = np.unique(np.round(region.unseen[:, :2], 6), axis=0) if len(region.unseen) else np.zeros((0, 2))
        ax.plot(*_top(unseen, origin), ".", color=colour, markersize=1.2, alpha=0.6, zorder=2,
                label=f"{region.key}: {100 * region.covered_frac:.1f} % seen ({region.unseen_area_m2:.1f} m² unseen)")
    if rig is not None:
        _draw_frustums(ax, rig, False, origin, report.cameras_inside)
    ax.set_xlim(high[1], low[1])  # +y (left) on the left
    ax.set_ylim(low[0], high[0])
    ax.set_aspect("equal")
    _top_titles(ax, datum)
    ax.legend(loc="best", fontsize=7, markerscale=6)
    ax.set_title(f"{report.rig} on {report.vehicle}: regulation fields (outlines)\nand their unseen ground positions "
                 "(dots: some height unseen)", fontsize=9)
    return figure


def _rings(geometry) -> list[np.ndarray]:
    """(k, 2) closed coordinate arrays of every ring of a Polygon or MultiPolygon."""
    return [shapely.get_coordinates(ring) for ring in shapely.get_rings(shapely.get_parts(geometry))]


def write_regions_figure(regions: tuple[RegionCoverage, ...], report: CoverageReport | RingReport, path,
                         rig: Rig | None = None, datum: ReportDatum = CENTRE_DATUM) -> Path:
    """The regulation fields figure (:func:`regions_figure`) as a PNG at ``path``."""
    return _save(regions_figure(regions, report, rig, datum), path)
