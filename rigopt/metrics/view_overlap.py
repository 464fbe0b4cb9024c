"""View overlap: the share of a reference rig's viewing directions that a candidate rig's cameras also see.

RigCD and the drop models compare matched cameras and were fitted on rigs that look at the road round the vehicle.
A candidate whose cameras all look at the sky, or a rig of one camera, gets a predicted drop from terms those
fits never saw; this measure says how much of the reference's view such a candidate keeps, from calibration
alone (no vehicle).

Definition
----------
A rig sees a direction d (a unit vector, vehicle frame) when d lies in the view of at least one of its cameras
(:meth:`rigopt.camera.CameraModel.in_view` of ``R^T d``, through each camera's lens and distortion). Positions are
ignored: the directions are at infinity, and nothing occludes them (no ego body, which this layer does not
know). The directions are a fixed Fibonacci sphere of ``SPHERE_DIRECTIONS`` points (:func:`sphere_directions`),
equal areas of about 3.2 degrees a side, so the result is deterministic. Then

    overlap(reference, candidate) = |seen by both| / |seen by the reference|

in [0, 1]: 1 for the reference itself (or any rig that sees at least what it sees), 0 for a candidate that sees
none of it. It is not symmetric. A reference whose cameras see none of the directions (every lens narrower than
the grid's spacing) has no overlap to give: NaN.

>>> from rigopt.rig.library import load_rig
>>> r1 = load_rig("R1")
>>> float(view_overlap(r1, r1))
1.0
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from rigopt.camera import CameraModel, in_frustum
from rigopt.rig.model import Rig

#: Directions of the Fibonacci sphere the overlap is counted on: 4 pi / 4096 sr each, about 3.2 degrees apart;
#: the overlap of the benchmark's rigs moves by less than 0.01 between 4096 and 65536 directions.
SPHERE_DIRECTIONS = 4096
#: Below this overlap with the reference a candidate's predicted drop is flagged (``rigopt rank``, ``rigopt
#: rigcd``): every rig pair either shipped predictor was fitted or judged on lies above it. Overlaps with the
#: reference of the data behind them (docs/metrics.md): the benchmark's 14 rigs with R1 at least 0.85, its 196
#: measured pairs at least 0.43 (R5 -> R1-c6), the drop models' fitting rigs with R1 at least 0.295 (R1's layout
#: pitched 20 degrees down with 50-degree lenses), the real datasets' rigs with R1 at least 0.50 (Waymo's five
#: front cameras). Half, the first choice, would flag fitting rigs of the drop models and sits on Waymo's rig; a
#: quarter flags a rig that sees the sky (0) or one camera of R1 (0.18).
LOW_VIEW_OVERLAP = 0.25


def sphere_directions(count: int = SPHERE_DIRECTIONS) -> np.ndarray:
    """(count, 3) float: unit directions of a Fibonacci sphere (equal areas; z from near 1 down to near -1, each
    step turned by the golden angle about z)."""
    k = np.arange(count, dtype=float)
    z = 1.0 - (2.0 * k + 1.0) / count
    radius = np.sqrt(1.0 - z * z)
    azimuth = k * np.pi * (3.0 - np.sqrt(5.0))
    return np.stack([radius * np.cos(azimuth), radius * np.sin(azimuth), z], axis=1)


def seen_directions(rig: Rig, directions: np.ndarray | None = None) -> np.ndarray:
    """(n,) bool: the ``directions`` (n, 3) unit vectors, vehicle frame (default :func:`sphere_directions`), that
    at least one of the rig's cameras sees; the lenses' positions are ignored (directions at infinity)."""
    directions = sphere_directions() if directions is None else np.asarray(directions, dtype=float)
    model = CameraModel.of_cameras(rig.cameras)
    return in_frustum(model, np.zeros((len(rig), 3)), rig.rotations, directions).any(axis=0)


def view_overlaps(reference: Rig, candidates: Sequence[Rig], directions: np.ndarray | None = None) -> np.ndarray:
    """(k,) float: the view overlap of each of the k ``candidates`` with ``reference`` (see the module), in
    [0, 1]; NaN each where the reference sees none of the ``directions`` (default :func:`sphere_directions`)."""
    directions = sphere_directions() if directions is None else np.asarray(directions, dtype=float)
    reference_seen = seen_directions(reference, directions)
    total = int(reference_seen.sum())
    if total == 0:
        return np.full(len(candidates), np.nan)
    return np.array([(reference_seen & seen_directions(c, directions)).sum() / total for c in candidates],
                    dtype=float)


def view_overlap(reference: Rig, candidate: Rig, directions: np.ndarray | None = None) -> float:
    """The share of ``reference``'s viewing directions that ``candidate`` also sees (:func:`view_overlaps`)."""
    return float(view_overlaps(reference, [candidate], directions)[0])


def low_view_overlap(overlap: float) -> bool:
    """Whether ``overlap`` is below LOW_VIEW_OVERLAP, the share under which a predicted drop is flagged (NaN, no
    overlap to judge, is not)."""
    return bool(overlap < LOW_VIEW_OVERLAP)


def low_overlap_text(reference: str, overlap: float) -> str:
    """What a low overlap means for a predicted drop from ``reference``, in words, e.g. 'its predicted drop rests
    on cameras that see 12 % of what R1's see; the predictors were not calibrated on such rigs'."""
    return (f"its predicted drop rests on cameras that see {percent(overlap)} of what {reference}'s see; the "
            "predictors were not calibrated on such rigs")


def percent(overlap: float) -> str:
    """An overlap as whole percent, '12 %' ('-' for NaN)."""
    return "-" if np.isnan(overlap) else f"{100.0 * overlap:.0f} %"
