"""Rig Variance (RigV): how diverse the cameras inside one rig are.

Over all unordered camera pairs i < j of a rig (docs/metrics.md):

    tv = mean ||t_i - t_j|| (m), dmax = max ||t_i - t_j|| (m), rv = mean dR (rad), fv = mean |f_i - f_j| (deg)
    rigv = lt clip(tv / (dmax + 1e-9), 0, 1) + lr clip(rv / pi, 0, 1) + lf clip(fv / 180, 0, 1)

A rig with one camera has RigV 0 and all components 0.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from rigopt.metrics.rigcd import DEFAULT_ALPHA, DEFAULT_LAMBDAS, camera_costs, check_weights
from rigopt.rig.model import Rig

#: Added to dmax before dividing, as the definition does.
DMAX_EPSILON = 1e-9


@dataclass(frozen=True)
class RigVBreakdown:
    """RigV of one rig: ``tv``/``dmax`` in metres, ``rv`` radians, ``fv`` degrees, ``*_norm`` in [0, 1]."""

    rig: str
    rigv: float
    tv: float
    rv: float
    fv: float
    tv_norm: float
    rv_norm: float
    fv_norm: float
    dmax: float
    lambdas: tuple[float, float, float]


def rigv(rig: Rig, lambdas: Sequence[float] = DEFAULT_LAMBDAS) -> RigVBreakdown:
    """RigV of ``rig`` with weights ``lambdas`` = (lt, lr, lf); unit weights are "no calibration"."""
    _, lambdas = check_weights(DEFAULT_ALPHA, lambdas)
    n = len(rig)
    if n < 2:
        return RigVBreakdown(rig.name, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, lambdas)
    t, r, f = camera_costs(rig.positions, rig.rotations, rig.fovs, rig.positions, rig.rotations, rig.fovs)
    i, j = np.triu_indices(n, k=1)
    tv, rv, fv, dmax = t[i, j].mean(), r[i, j].mean(), f[i, j].mean(), t[i, j].max()
    tv_norm = float(np.clip(tv / (dmax + DMAX_EPSILON), 0.0, 1.0))
    rv_norm = float(np.clip(rv / np.pi, 0.0, 1.0))
    fv_norm = float(np.clip(fv / 180.0, 0.0, 1.0))
    lt, lr, lf = lambdas
    value = lt * tv_norm + lr * rv_norm + lf * fv_norm
    return RigVBreakdown(rig.name, float(value), float(tv), float(rv), float(fv), tv_norm, rv_norm, fv_norm,
                         float(dmax), lambdas)
