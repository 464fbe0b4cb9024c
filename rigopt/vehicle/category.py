"""What a body's shape says of the vehicle: the UN category (ECE/TRANS/WP.29/78, R.E.3) it suggests, with the reason
in words, and its width without mirrors against the legal maximum.

The category is set by mass and seats, which a mesh does not carry; its size and shape narrow it down, and the user
confirms or overrides (``vehicle add --category``, ``category`` in ``vehicle.toml``):

- **heavy** (longer than HEAVY_LENGTH or with a roof above HEAVY_ROOF): a bus (M3) when its front axle sits at
  least BUS_OVERHANG behind the front face (the entrance door ahead of the axle) and its roof runs level over
  its length (within LEVEL_ROOF), else a truck (N3);
- **van-shaped** (the roof at least VAN_ROOF high over at least VAN_SHARE of the length): a light goods vehicle
  (N1, up to 3.5 t);
- otherwise a car (M1).

The roof profile is read by rays cast straight down at PROFILE_SAMPLES stations along the body (on the centreline
and a quarter-width either side, the highest hit), so that a thin mast or roof antenna does not count as roof.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

HEAVY_LENGTH, HEAVY_ROOF = 7.5, 3.0  # m
BUS_OVERHANG = 1.8  # m from the front face to the front axle
LEVEL_ROOF = 0.6  # m: the largest rise of a bus's roof over the middle 80 % of its length
VAN_ROOF, VAN_SHARE = 2.0, 0.5  # m, share of the length
PROFILE_SAMPLES = 60


@dataclass(frozen=True)
class CategoryGuess:
    """``category`` (one of M1, N1, M3, N3) and ``reason``: the measurements it rests on, in words."""

    category: str
    reason: str


def roof_profile(vehicle) -> tuple[np.ndarray, np.ndarray]:
    """(x (S,) m, roof (S,) m): the highest point of the body over each of PROFILE_SAMPLES stations along its length,
    vehicle frame; NaN where a station has no body (between a cab and its trailer)."""
    low, high = vehicle.mesh.bounds
    x = np.linspace(low[0], high[0], PROFILE_SAMPLES + 2)[1:-1]
    width = high[1] - low[1]
    ys = (low[1] + high[1]) / 2 + np.array([-0.25, 0.0, 0.25]) * width
    origins = np.array([[xi, yi, high[2] + 1.0] for xi in x for yi in ys])
    down = np.tile([0.0, 0.0, -1.0], (len(origins), 1))
    distance = vehicle.ray_caster.first_hit_distance(origins, down)
    roof = (high[2] + 1.0 - distance).reshape(len(x), len(ys))
    roof = np.where(np.isfinite(roof), roof, -np.inf).max(axis=1)
    return x, np.where(np.isfinite(roof), roof, np.nan)


def guess_category(vehicle) -> CategoryGuess:
    """The category ``vehicle``'s shape suggests (module docstring), and why."""
    low, high = vehicle.mesh.bounds
    length = float(high[0] - low[0])
    x, roof = roof_profile(vehicle)
    top = float(np.nanmax(roof))
    size = f"{length:.2f} m long, roof up to {top:.2f} m"
    if length > HEAVY_LENGTH or top > HEAVY_ROOF:
        axles = vehicle.axles
        if not axles:
            return CategoryGuess("N3", f"{size}: a heavy vehicle; no axles known to tell a bus from a truck, taken as "
                                       "a truck")
        overhang = float(high[0] - max(axles))
        middle = roof[(x > low[0] + 0.1 * length) & (x < high[0] - 0.1 * length)]
        rise = float(np.nanmax(middle) - np.nanmin(middle)) if np.isfinite(middle).all() else np.inf
        if overhang >= BUS_OVERHANG and rise <= LEVEL_ROOF:
            return CategoryGuess("M3", f"{size}, front axle {overhang:.2f} m behind the front and one level roof: a "
                                       "bus (M3, over 5 t; M2 if lighter)")
        return CategoryGuess("N3", f"{size}, front axle {overhang:.2f} m behind the front"
                                   + ("" if rise <= LEVEL_ROOF else f", roof rising {rise:.2f} m along it")
                                   + ": a truck (N3, over 12 t; N2 if lighter)")
    tall = float(np.mean(np.nan_to_num(roof, nan=0.0) >= VAN_ROOF))
    if tall >= VAN_SHARE:
        return CategoryGuess("N1", f"{size}, roof at {VAN_ROOF:.1f} m or more over {tall:.0%} of its length: a "
                                   "van (N1, up to 3.5 t; N2 if heavier, M1 or M2 if it carries people)")
    return CategoryGuess("M1", f"{size}, roof at {VAN_ROOF:.1f} m or more over {tall:.0%} of its length: a car (M1)")


#: The largest width (m) of a road vehicle's body in the EU (Council Directive 96/53/EC, Annex I 1.2): 2.55 m, 2.60 m
#: for the superstructure of a conditioned (refrigerated) vehicle; mirrors are not counted.
MAX_BODY_WIDTH, MAX_CONDITIONED_WIDTH = 2.55, 2.60


def body_width(vehicle) -> float:
    """The body's width (m) without its mirrors: at each of PROFILE_SAMPLES stations along the length the widest of
    rays cast across at 20-80 % of the height, the median over the stations (mirrors, a step or a handle stand out
    over a few stations only)."""
    low, high = vehicle.mesh.bounds
    x = np.linspace(low[0], high[0], PROFILE_SAMPLES + 2)[1:-1]
    z = low[2] + np.array([0.2, 0.35, 0.5, 0.65, 0.8]) * (high[2] - low[2])
    reach = high[1] - low[1] + 2.0
    stations = np.array([[xi, zi] for xi in x for zi in z])
    widths = np.zeros(len(stations))
    sides = []
    for sign in (1.0, -1.0):  # from the left (+y) inward, then from the right
        origins = np.column_stack([stations[:, 0], np.full(len(stations), sign * reach), stations[:, 1]])
        direction = np.tile([0.0, -sign, 0.0], (len(stations), 1))
        sides.append(sign * (reach - vehicle.ray_caster.first_hit_distance(origins, direction)))
    hit = np.isfinite(sides[0]) & np.isfinite(sides[1])
    widths[hit] = sides[0][hit] - sides[1][hit]
    per_station = widths.reshape(len(x), len(z)).max(axis=1)
    return float(np.median(per_station[per_station > 0])) if np.any(per_station > 0) else 0.0


def width_warning(vehicle) -> str | None:
    """A warning when the body without mirrors is wider than MAX_BODY_WIDTH (None within it)."""
    width = body_width(vehicle)
    if width <= MAX_BODY_WIDTH + 1e-3:
        return None
    return (f"the body is {width:.2f} m wide without its mirrors, above the {MAX_BODY_WIDTH} m a road vehicle may be "
            f"({MAX_CONDITIONED_WIDTH} m for a refrigerated body; Directive 96/53/EC): check the mesh's scale "
            "(--scale, --length) or that it is meant to be this wide")
