"""The trade-off sweep of ``rigopt design --pareto``: camera counts x coverage levels.

Every (count, level) pair is solved as its own MILP on one shared candidate set (no continuous
refinement, so the sweep stays quick), meeting the regulation fields named by ``--require`` at every
level (without it none). Each design is judged by its predicted drop, its near field (ground seen on the 2 m ring, unseen
ground within 5 m of the body), its coverage of the vehicle category's regulation fields and its relative
mounting cost (zone costs and tyre spray, :func:`rigopt.mounting.practice.mounting_costs`). A point is on
the frontier when no other feasible point is at least as good in predicted drop (lower), unseen near-field
ground (lower) and mounting cost (lower) and better in one of them.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable, Sequence

from rigopt.design.designer import no_progress, prepare, select_valid, summarise
from rigopt.design.requirements import design_requirements, fleet_requirements
from rigopt.design.problem import ReferenceRig
from rigopt.design.result import repredicted
from rigopt.design.selection import DesignInfeasible
from rigopt.design.settings import DesignSettings
from rigopt.metrics.calibration import Calibration
from rigopt.rig.model import Rig
from rigopt.vehicle.model import Vehicle

#: Coverage levels: (min_coverage, min_overlap) on top of the references' own coverage.
LEVELS = {"reference": (0, 0), "reference+overlap": (0, 2), "full": (1, 0)}


@dataclass(frozen=True)
class ParetoPoint:
    """One (camera count, coverage level) design: its worst predicted drop and RigCD over the references,
    coverage fraction (of the sector points), ``ring_2m_ground`` (fraction of the 2 m ring's ground seen),
    ``blind_area_m2`` (unseen ground within 5 m of the body), ``fields`` (the smallest covered fraction of the
    category's regulation fields), ``mounting_cost``, whether it is feasible (``reason`` when not) and on the
    frontier."""

    n_cameras: int
    level: str
    feasible: bool
    predicted_drop: float = float("nan")
    rigcd: float = float("nan")
    coverage: float = float("nan")
    ring_2m_ground: float = float("nan")
    blind_area_m2: float = float("nan")
    fields: float = float("nan")
    mounting_cost: float = float("nan")
    frontier: bool = False
    reason: str = ""
    rig: Rig | None = None


def pareto_designs(vehicle: Vehicle, references: Sequence[ReferenceRig], calibration: Calibration,
                   settings: DesignSettings, counts: tuple[int, int], levels: Sequence[str] = tuple(LEVELS),
                   progress: Callable[[str], None] = no_progress, drop_model=None) -> list[ParetoPoint]:
    """Solve every camera count in ``counts`` (inclusive range) at every coverage level, for the references
    each on its own vehicle; each point's predicted drop is ``drop_model``'s from the references it was fitted
    from (:func:`rigopt.design.result.repredicted`), else RigCD's under ``calibration``."""
    rigs = [r.rig for r in references]
    base = design_requirements(references, vehicle, settings)
    if settings.require is None:  # the sweep requires fields only when named; the category's are reported
        base, settings = base.sector_only(), replace(settings, require="none")
    prepared = prepare(vehicle, rigs, calibration, settings, base, progress)
    points = []
    for level in levels:
        min_coverage, min_overlap = LEVELS[level]
        level_settings = replace(settings, min_coverage=min_coverage, min_overlap=min_overlap)
        needed = base.with_sector_needs(fleet_requirements(references, level_settings, vehicle,
                                                           base.points[:base.n_sector]))
        for n in range(counts[0], counts[1] + 1):
            progress(f"pareto: {n} cameras, coverage level {level}")
            try:
                rig = select_valid(prepared, vehicle, calibration, needed, (n, n), level_settings, progress).rig
            except DesignInfeasible as error:
                points.append(ParetoPoint(n, level, False, reason=str(error)))
                continue
            summary = summarise(rig, vehicle, rigs, calibration, needed, level_settings)
            if drop_model is not None:
                summary = repredicted(summary, rigs, calibration, drop_model)
            ring, blind, fields, cost = near_field(rig, vehicle, level_settings)
            points.append(ParetoPoint(n, level, True, summary.prediction.predicted_drop, summary.prediction.rigcd,
                                      summary.coverage, ring, blind, fields, cost, rig=rig))
    return _mark_frontier(points)


def near_field(rig: Rig, vehicle: Vehicle, settings: DesignSettings) -> tuple[float, float, float, float]:
    """(ground fraction seen on the 2 m ring, unseen ground m^2 within 5 m, smallest covered fraction of the
    vehicle category's regulation fields, relative mounting cost) of ``rig`` on ``vehicle``."""
    from rigopt.coverage.measures import CoverageSettings, blind_zone, ring_coverage
    from rigopt.design.designer import field_coverage
    from rigopt.design.requirements import required_presets
    from rigopt.mounting.practice import mounting_costs

    footprint, measures = vehicle.footprint, CoverageSettings(ring_distances=(2.0,), ring_heights=(0.0,))
    ring = ring_coverage(vehicle, rig, measures, footprint)[0].covered_frac
    blind = blind_zone(vehicle, rig, measures, footprint).area_m2
    fields = min((r.covered_frac for r in field_coverage(rig, vehicle, required_presets(vehicle, settings, "default"),
                                                        settings)), default=1.0)
    cost = float(mounting_costs(vehicle, [c.zone for c in rig.cameras], rig.positions).sum())
    return float(ring), float(blind), float(fields), cost


def _mark_frontier(points: list[ParetoPoint]) -> list[ParetoPoint]:
    feasible = [p for p in points if p.feasible]

    def key(p: ParetoPoint) -> tuple[float, float, float]:
        return p.predicted_drop, p.blind_area_m2, p.mounting_cost  # all three: lower is better

    def dominated(p: ParetoPoint) -> bool:
        return any(all(a <= b for a, b in zip(key(q), key(p))) and key(q) != key(p) for q in feasible)

    return [replace(p, frontier=p.feasible and not dominated(p)) for p in points]


def write_pareto(points: list[ParetoPoint], out_dir) -> list[Path]:
    """pareto.csv (every point) and pareto.png (predicted drop against coverage, frontier joined)."""
    from matplotlib.figure import Figure

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    table = out_dir / "pareto.csv"
    with table.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["n_cameras", "level", "feasible", "predicted_drop", "rigcd", "coverage", "ring_2m_ground",
                         "blind_area_m2", "fields", "mounting_cost", "frontier", "reason"])
        for p in points:
            writer.writerow([p.n_cameras, p.level, p.feasible, *(f"{v:.6g}" for v in (
                p.predicted_drop, p.rigcd, p.coverage, p.ring_2m_ground, p.blind_area_m2, p.fields, p.mounting_cost)),
                p.frontier, p.reason])
    figure = Figure(figsize=(7, 5), dpi=120, layout="constrained")
    ax = figure.subplots()
    feasible = [p for p in points if p.feasible]
    markers = dict(zip(LEVELS, "osD"))
    scatter = None
    for level in LEVELS:
        mine = [p for p in feasible if p.level == level]
        if mine:
            scatter = ax.scatter([p.blind_area_m2 for p in mine], [p.predicted_drop for p in mine],
                                 c=[p.n_cameras for p in mine], marker=markers[level], cmap="viridis", s=60,
                                 vmin=min(p.n_cameras for p in feasible), vmax=max(p.n_cameras for p in feasible),
                                 label=f"coverage level: {level}")
    frontier = sorted((p for p in feasible if p.frontier), key=lambda p: p.blind_area_m2)
    if frontier:
        ax.plot([p.blind_area_m2 for p in frontier], [p.predicted_drop for p in frontier], "k--", linewidth=1,
                label="frontier (drop, blind area, mounting cost)")
    if scatter is not None:
        figure.colorbar(scatter, ax=ax, label="cameras")
    ax.set_xlabel("unseen ground within 5 m of the body (m²)")
    ax.set_ylabel("predicted relative mAP drop (worst reference)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    picture = out_dir / "pareto.png"
    figure.savefig(picture)
    return [table, picture]


def sweep_counts(references: Sequence[ReferenceRig]) -> tuple[int, int]:
    """The camera counts a Pareto sweep spans without --cameras: the (first) reference's count +- 2 (at least 1)."""
    n = len(references[0].rig)
    return max(1, n - 2), n + 2
