"""The perception cameras' pose tolerance: how far a camera lies from a reference camera in units of the tolerances
(height, pitch, yaw, FOV: ``DesignSettings.match_*``), and what the designer makes of it.

Where the tolerance is a hard constraint (a zero tolerance, or the pairs beyond it once a design is chosen) a
pair costs OUT_OF_TOLERANCE_COST, which no MILP chooses while another selection exists (:func:`tolerated`).
Where it is a cost (the body offers no mount within it: a rearward view past a trailer, a bumper height a tailboard
takes) a pair beyond it costs EXCESS_COST per tolerance (:func:`tolerance_penalty`), so the design keeps the
nearest pose the body allows, and the tolerance is widened for that reference camera afterwards
(:func:`matched_widening`), said so in the report.
"""

from __future__ import annotations

import numpy as np

from rigopt.design.settings import DesignSettings
from rigopt.geometry import yaw_pitch_roll_from_rotation
from rigopt.rig.model import Rig

#: Raw-unit matching cost of a (candidate, reference camera) pair that breaks a zero tolerance (or, in
#: :func:`tolerated`, lies outside the tolerance): the MILP never chooses one while another selection exists
#: (a chosen one makes the design infeasible).
OUT_OF_TOLERANCE_COST = 1e6


def pose_gaps(heights: np.ndarray, pitches: np.ndarray, reference: Rig, settings: DesignSettings,
              yaws: np.ndarray | None = None, fovs: np.ndarray | None = None) -> np.ndarray:
    """(n, R) float: how far a camera at height ``heights`` (n,) m above the ground, pitched ``pitches`` (n,) rad,
    turned to ``yaws`` (n,) rad with horizontal FOV ``fovs`` (n,) deg lies from each reference camera, in units
    of ``settings``' tolerances (``match_height_m``, ``match_pitch_deg``, ``match_yaw_deg``, ``match_fov_deg``;
    yaws and fovs needed only by their own): the largest gap over the tolerances set, each less a rounding
    allowance (1e-9 m, 1e-6 deg) and divided by its tolerance; a zero tolerance gives 0 or inf. <= 1: within."""
    ref_yaws, ref_pitches, _ = yaw_pitch_roll_from_rotation(reference.rotations)
    gaps = [(np.abs(heights[:, None] - reference.positions[None, :, 2]), settings.match_height_m, 1e-9),
            (np.rad2deg(np.abs(pitches[:, None] - ref_pitches[None, :])), settings.match_pitch_deg, 1e-6)]
    if settings.match_yaw_deg is not None:
        gaps.append((np.rad2deg(np.abs(np.angle(np.exp(1j * (yaws[:, None] - ref_yaws[None, :]))))),
                     settings.match_yaw_deg, 1e-6))
    if settings.match_fov_deg is not None:
        gaps.append((np.abs(np.asarray(fovs, float)[:, None] - reference.fovs[None, :]), settings.match_fov_deg, 1e-6))
    worst = np.zeros((len(heights), len(reference)))
    for gap, tolerance, allowance in gaps:
        if tolerance is None:
            continue
        excess = np.maximum(gap - allowance, 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            scaled = excess / tolerance if tolerance > 0 else np.where(excess > 0, np.inf, 0.0)
        worst = np.maximum(worst, scaled)
    return worst


def within_pose_tolerance(heights: np.ndarray, pitches: np.ndarray, reference: Rig, settings: DesignSettings,
                          yaws: np.ndarray | None = None, fovs: np.ndarray | None = None) -> np.ndarray:
    """(n, R) bool: whether each camera may be matched to each reference camera under ``settings``' tolerances
    (:func:`pose_gaps` <= 1)."""
    return pose_gaps(heights, pitches, reference, settings, yaws, fovs) <= 1.0


def tolerance_gaps(positions: np.ndarray, rotations: np.ndarray, fovs: np.ndarray, reference: Rig,
                   settings: DesignSettings | None) -> np.ndarray:
    """(n, R) float: :func:`pose_gaps` of cameras at ``positions`` (n, 3) m (vehicle frame, ground at z = 0)
    with ``rotations`` (n, 3, 3) and ``fovs`` (n,) deg; zeros without a tolerance."""
    if settings is None or not settings.tolerances:
        return np.zeros((len(positions), len(reference)))
    yaws, pitches, _ = yaw_pitch_roll_from_rotation(rotations)
    return pose_gaps(positions[:, 2], pitches, reference, settings, yaws, np.asarray(fovs, float))


def tolerance_text(settings: DesignSettings) -> str:
    """The pose tolerance in words, e.g. "0.1 m in height and 2 deg in pitch"."""
    return describe_tolerance(settings.match_height_m, settings.match_pitch_deg, settings.match_yaw_deg,
                              settings.match_fov_deg)


def describe_tolerance(height_m, pitch_deg, yaw_deg, fov_deg) -> str:
    """:func:`tolerance_text` of the four tolerances (None: not held), e.g. as a report's ``pose_tolerance`` gives
    them."""
    parts = [f"{value:g} {unit} in {name}" for value, unit, name in (
        (height_m, "m", "height"), (pitch_deg, "deg", "pitch"), (yaw_deg, "deg", "yaw"), (fov_deg, "deg", "FOV"))
        if value is not None]
    return " and ".join(parts) or "any pose"


def tolerated(costs: np.ndarray, positions: np.ndarray, rotations: np.ndarray, fovs: np.ndarray, reference: Rig,
               settings: DesignSettings | None, widen: np.ndarray | None = None) -> np.ndarray:
    """(n, R) ``costs`` with OUT_OF_TOLERANCE_COST for the pairs outside ``settings``' pose tolerance, widened
    per reference camera by ``widen`` (R,) (`matched_widening`; None: as set)."""
    if settings is None or not settings.tolerances:
        return costs
    gaps = tolerance_gaps(positions, rotations, fovs, reference, settings)
    limit = np.ones(len(reference)) if widen is None else np.asarray(widen, float)
    return np.where(gaps <= limit[None, :], costs, OUT_OF_TOLERANCE_COST)


#: Matching cost (raw units) per tolerance of a pair beyond the pose tolerance: far above any calibrated cost
#: difference, so a design keeps each camera as near its reference camera's pose as the body allows.
EXCESS_COST = 100.0
#: Tolerances beyond which a pair costs no more (kept well below OUT_OF_TOLERANCE_COST).
MAX_EXCESS = 1000.0


def tolerance_penalty(gaps: np.ndarray) -> np.ndarray:
    """(n, R) float added to the calibrated costs of n candidates for R reference cameras, from their
    :func:`pose_gaps`: EXCESS_COST per tolerance beyond the tolerance (where the body offers no mount within it,
    a rearward view past a trailer or a bumper height a tailboard takes, the design keeps the nearest pose it
    allows); OUT_OF_TOLERANCE_COST for a broken zero tolerance, except in the columns of reference cameras no
    candidate meets (lifted: matched by the calibrated cost alone)."""
    finite = np.isfinite(gaps)
    excess = np.minimum(np.maximum(np.where(finite, gaps, 0.0) - 1.0, 0.0), MAX_EXCESS)
    penalty = np.where(finite, EXCESS_COST * excess, OUT_OF_TOLERANCE_COST)
    return np.where(finite.any(axis=0)[None, :], penalty, 0.0)


def matched_widening(gaps: np.ndarray, matched: np.ndarray) -> np.ndarray:
    """(R,) float: per reference camera, the factor its pose tolerance was widened by in a design whose cameras
    have the :func:`pose_gaps` ``gaps`` (k, R) and are matched to the reference cameras ``matched`` (k,) int:
    1 where the matched camera is within the tolerance (or none is matched), its gap where it lies beyond,
    inf where a zero tolerance is broken (lifted)."""
    widen = np.ones(gaps.shape[1])
    if len(matched):
        mine = gaps[np.arange(len(matched)), matched]
        widen[matched] = np.maximum(mine + WIDENING_SLACK * (mine > 1.0), 1.0)
    return widen


#: Added to a widened tolerance (in its units) so that a continuous stage that keeps a camera's pose up to
#: rounding stays within it.
WIDENING_SLACK = 1e-6
