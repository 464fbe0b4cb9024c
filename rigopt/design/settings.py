"""What the designer may choose from and what it must achieve: ``DesignSettings`` and its defaults.

Light to import (numpy only at import time): the command line shows these defaults in its help. The
coverage ring settings and the mount rules, whose modules pull in the geometry libraries, are built on
first use.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Sequence

import numpy as np

from rigopt.errors import RigoptError

if TYPE_CHECKING:
    from rigopt.mounting.rules import MountRules
    from rigopt.coverage.measures import CoverageSettings

#: The lens catalogue: horizontal FOVs (deg) of the lenses a design may use.
DEFAULT_LENSES = (60.0, 65.0, 70.0, 75.0, 80.0, 90.0, 100.0, 110.0, 120.0)
#: Pitch angles (deg, > 0 up) of the orientation grid.
DEFAULT_PITCHES_DEG = (-20.0, -10.0, 0.0, 10.0)
#: Step (deg) of the yaw grid, from -180 deg.
DEFAULT_YAW_STEP_DEG = 10.0
#: Step (deg) of the discrete lenses that seed a continuous FOV range.
RANGE_STEP = 10.0


def _design_coverage() -> CoverageSettings:
    from rigopt.coverage.measures import CoverageSettings

    return CoverageSettings(ring_distances=(2.0, 5.0, 10.0, 20.0), sectors=36)


def _mount_rules() -> MountRules:
    from rigopt.mounting.rules import MountRules

    return MountRules()


def _check_fovs(fovs: Sequence[float]) -> None:
    bad = [f for f in fovs if not 0.0 < f < 180.0]
    if bad:
        raise RigoptError(f"lens FOVs must lie within (0, 180) degrees, got {', '.join(f'{f:g}' for f in bad)}")


def lens_catalogue(fovs: Sequence[float]) -> tuple[float, ...]:
    """The discrete lens catalogue ``fovs`` (deg) as floats, checked to lie within (0, 180) degrees."""
    lenses = tuple(float(f) for f in fovs)
    if not lenses:
        raise RigoptError("a lens catalogue needs at least one FOV")
    _check_fovs(lenses)
    return lenses


def range_lenses(low: float, high: float) -> tuple[float, ...]:
    """The lenses (deg) that seed a continuous FOV range [``low``, ``high``] deg: every RANGE_STEP degrees
    from ``low`` (``high`` itself when the range is a whole number of steps). The MILP picks among them
    and the refinement then adjusts each camera's FOV within the range (``DesignSettings.fov_range``)."""
    _check_fovs((low, high))
    if low > high:
        raise RigoptError(f"a FOV range needs low <= high, got {low:g}-{high:g}")
    return tuple(float(f) for f in np.arange(low, high + 1e-9, RANGE_STEP))


@dataclass(frozen=True)
class DesignSettings:
    """What the designer may choose from and what it must achieve."""

    cameras: tuple[int, int] | None = None
    """(min, max) camera count, inclusive; None for the (first) reference's count."""
    lenses: tuple[float, ...] = DEFAULT_LENSES
    """The lens catalogue: horizontal FOVs (deg)."""
    zones: tuple[str, ...] | None = None
    """The zone names cameras may be mounted on; None for every zone of the vehicle."""
    pitches_deg: tuple[float, ...] = DEFAULT_PITCHES_DEG
    """Pitch angles (deg, > 0 up) of the orientation grid; their range also bounds the refinement."""
    yaw_step_deg: float = DEFAULT_YAW_STEP_DEG
    """Step (deg) of the yaw grid, from -180 deg."""
    spacing: float | None = None
    """Mount point spacing (m); None to size it from the vehicle (about ``target_mounts`` points)."""
    target_mounts: int = 400
    """How many mount points a sized spacing aims at on the allowed zones."""
    min_coverage: int = 0
    """Cameras every sector point needs (0: only where the reference sees it, 1)."""
    min_overlap: int = 0
    """Cameras needed where the reference sees a sector point with >= 2 (0: no overlap requirement)."""
    keep_per_reference: int = 150
    """Pruning: each reference camera's cheapest candidates offered to the MILP."""
    keep_per_sector: int = 6
    """Pruning: for every required sector point, the cheapest candidates that see it offered to the MILP."""
    coverage_mounts: int = 80
    """About how many mount points offer every orientation for coverage (the coverage pool)."""
    time_limit: float = 60.0
    """MILP time limit (s); the best selection found within it is returned."""
    mip_gap: float = 1e-4
    """MILP relative optimality gap at which HiGHS stops."""
    refine: bool = True
    """Run the continuous stage (casadi + IPOPT) after the MILP (single-reference designs only)."""
    fov_range: tuple[float, float] | None = None
    """(min, max) deg when the lens is continuous (the refinement then adjusts FOVs; see ``range_lenses``)."""
    coverage: CoverageSettings = field(default_factory=_design_coverage)
    """The rings and sectors of the coverage requirements (rings at 2, 5, 10, 20 m, 36 sectors)."""
    rules: MountRules = field(default_factory=_mount_rules)
    """The mount checks every camera of a design passes."""
