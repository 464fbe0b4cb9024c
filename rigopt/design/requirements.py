"""What a design must see: the reference's coverage and the new vehicle's own safety fields.

Two kinds of requirement points, in the target vehicle's frame (ISO, metres):

- **sector points**: the centres of the ring sectors (``DesignSettings.coverage``: 36 sectors x rings at
  2, 5, 10, 20 m x heights 0 and 0.8 m, see :mod:`rigopt.coverage.matrix`). A sector point needs one camera
  where the reference, on its own vehicle, sees it (``min_overlap`` where it sees it twice, at least
  ``min_coverage`` everywhere); none inside a keep-out in force (a coupled trailer).
- **field points**: the regulation presets' regions (``DesignSettings.require``, see
  :mod:`rigopt.coverage.regulations`), a grid every REGION_SPACING m with the regions' outlines, at each
  preset's test-object heights. Each needs one camera that resolves it (the preset's test object standing there
  as many pixels tall in its image as asked, ``pixel_demand``), except inside the footprint or a keep-out in
  force.

The designer meets every point exactly in its MILP; afterwards the fields are checked densely (every
``regions.DENSE_SPACING`` m) and unseen dense points become requirements of another round
(:func:`rigopt.design.designer.design_rig`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np

from rigopt.camera import CameraModel
from rigopt.coverage.matrix import rig_coverage_matrix, sector_points
from rigopt.coverage.regulations import RegionPreset, parse_require, required_mask
from rigopt.coverage.visibility import no_pixel_demand, resolved_by
from rigopt.design.problem import ReferenceRig
from rigopt.design.settings import DesignSettings
from rigopt.mounting.practice import in_keep_outs
from rigopt.rig.model import Rig
from rigopt.vehicle.model import Vehicle

#: Grid spacing (m) of the field points the MILP must see.
REGION_SPACING = 0.5
#: Spacing (m) of the dense check of the fields after a design.
DENSE_SPACING = 0.1


@dataclass(frozen=True)
class Requirements:
    """Requirement points and how many cameras each needs.

    points (q, 3) m, vehicle frame; needed (q,) int; labels (q,) str, what each point is (for messages);
    the first ``n_sector`` are sector points, the rest field points of ``presets``; pixel_demand (q, 2) float
    each point's (test object height m, pixels its image must span; 0: in view is enough), None: nothing asked.
    """

    points: np.ndarray
    needed: np.ndarray
    labels: tuple[str, ...]
    n_sector: int
    presets: tuple[RegionPreset, ...] = ()
    pixel_demand: np.ndarray | None = None

    @property
    def demands(self) -> np.ndarray:
        """(q, 2) float: ``pixel_demand``, nothing asked where None."""
        return no_pixel_demand(len(self.points)) if self.pixel_demand is None else self.pixel_demand

    def counts_matrix(self, rig: Rig, vehicle: Vehicle, settings: DesignSettings) -> np.ndarray:
        """(k, q) bool: which points each camera of ``rig`` on ``vehicle`` resolves (occlusion-aware, each point's
        test object as many pixels tall as it asks)."""
        return resolved_by(vehicle.caster(settings.coverage.backend), CameraModel.of_cameras(rig.cameras),
                           rig.positions, rig.rotations, self.points, self.demands, settings.coverage.max_range)

    def counts(self, rig: Rig, vehicle: Vehicle, settings: DesignSettings) -> np.ndarray:
        """(q,) int: how many cameras of ``rig`` on ``vehicle`` see each point."""
        return self.counts_matrix(rig, vehicle, settings).sum(axis=0)

    def sector_only(self) -> "Requirements":
        """These requirements with the fields asking for nothing (the points kept, so that a shared coverage
        pool still lines up)."""
        needed = self.needed.copy()
        needed[self.n_sector:] = 0
        return replace(self, needed=needed)

    def with_sector_needs(self, needed_sectors: np.ndarray) -> "Requirements":
        """These requirements with the sector points' needs replaced by ``needed_sectors`` (n_sector,) int."""
        return replace(self, needed=np.concatenate([needed_sectors, self.needed[self.n_sector:]]).astype(int))

    def extended(self, points: np.ndarray, labels: Sequence[str], pixel_demand=None) -> "Requirements":
        """These requirements and ``points`` (k, 3) m more, each needing one camera that resolves it at
        ``pixel_demand`` (k, 2) (None: in view is enough)."""
        more = no_pixel_demand(len(points)) if pixel_demand is None else np.asarray(pixel_demand, dtype=float)
        return replace(self, points=np.concatenate([self.points, points]),
                       needed=np.concatenate([self.needed, np.ones(len(points), dtype=int)]),
                       labels=self.labels + tuple(labels), pixel_demand=np.concatenate([self.demands, more]))


def reference_requirements(reference: Rig, reference_vehicle: Vehicle, settings: DesignSettings) -> np.ndarray:
    """(q,) int cameras needed at each sector point: where the reference (on its own vehicle) sees a point,
    one; where it sees it twice, ``min_overlap``; everywhere at least ``min_coverage``."""
    counts = rig_coverage_matrix(reference, reference_vehicle, settings.coverage).sees.sum(axis=0)
    needed = np.minimum(counts, 1)
    if settings.min_overlap:
        needed = np.where(counts >= 2, np.maximum(needed, settings.min_overlap), needed)
    return np.maximum(needed, settings.min_coverage).astype(int)


def fleet_requirements(references: Sequence[ReferenceRig], settings: DesignSettings,
                       target: Vehicle | None = None, points: np.ndarray | None = None) -> np.ndarray:
    """(q,) int: the largest requirement of any reference (on its own vehicle) at each sector point; with the
    ``target`` vehicle and its sector ``points`` (q, 3) m, none at points inside its keep-outs in force (a
    coupled trailer fills the space behind a tractor: there is nothing there to see)."""
    needed = np.max([reference_requirements(r.rig, r.vehicle, settings) for r in references], axis=0)
    if target is not None and settings.rules.practice.enabled:
        inside = np.array([bool(b) for b in in_keep_outs(target, points, settings.rules.practice.lifted)])
        needed = np.where(inside, 0, needed)
    return needed


def required_presets(vehicle: Vehicle, settings: DesignSettings, require: str | None = None
                     ) -> tuple[RegionPreset, ...]:
    """The regulation presets ``require`` names for ``vehicle`` (None: ``settings.require``; 'default' or None:
    its category's), each test object asking ``settings.field_pixels`` pixels when set."""
    presets = parse_require(require or settings.require or "default", vehicle)
    if settings.field_pixels is None:
        return presets
    return tuple(preset.with_min_px(settings.field_pixels) for preset in presets)


def design_requirements(references: Sequence[ReferenceRig], vehicle: Vehicle,
                        settings: DesignSettings) -> Requirements:
    """The sector points of ``vehicle`` with the references' needs, then the required fields' points."""
    points, distance, height, _, azimuth = sector_points(vehicle.footprint, settings.coverage)
    needed = fleet_requirements(references, settings, vehicle, points)
    if settings.near_field:  # the nearer rings are the near-field cameras' ground
        needed = np.where(distance < settings.perception_range_m, 0, needed)
    labels = [f"ring {d:g} m at height {h:g} m, azimuth {np.rad2deg(a):+.0f} deg"
              for d, h, a in zip(distance, height, azimuth)]
    presets = required_presets(vehicle, settings)
    field_points, field_needed, demands = [points], [needed], [no_pixel_demand(len(points))]
    for preset in presets:
        mine = preset.points(vehicle, REGION_SPACING)
        field_points.append(mine)
        field_needed.append(required_mask(vehicle, mine, settings.rules.practice.lifted).astype(int))
        demands.append(preset.pixel_demands(len(mine)))
        labels += field_labels(preset.key, mine)
    return Requirements(np.concatenate(field_points), np.concatenate(field_needed).astype(int), tuple(labels),
                        len(points), presets, np.concatenate(demands))


def field_labels(key: str, points: np.ndarray) -> list[str]:
    """A label per field point (k, 3) m of preset ``key``."""
    return [f"{key} field at x {p[0]:+.1f} m, y {p[1]:+.1f} m, height {p[2]:g} m" for p in points]


def explain_uncoverable(requirements: Requirements, seen: np.ndarray) -> str:
    """Why no design exists: the points (up to 8) fewer candidates see than they need, and what would help."""
    needed = requirements.needed
    bad = np.flatnonzero(seen < needed)
    lines = [f"{requirements.labels[q]} (needs {needed[q]} camera(s), at most {seen[q]} candidate(s) see it)"
             for q in bad[:8]]
    more = f" and {len(bad) - 8} more" if len(bad) > 8 else ""
    fields = " or fewer regulation fields (--require)" if np.any(bad >= requirements.n_sector) else ""
    return ("no valid camera position covers " + "; ".join(lines) + more +
            ". To make it feasible: allow more zones, more pitch angles (e.g. --pitch -30,-20,-10,0,10), "
            f"wider lenses, or lower --min-coverage / --min-overlap{fields}")
