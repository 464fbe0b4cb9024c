"""Wheels found on a vehicle mesh: axles from the ground contact patches, radius and width from the tyres'
own surface.

1. Axles: surface samples within a thin band above the mesh's lowest point (:func:`ground_band`, 5 % of the
   height clamped to [3, 12] cm) form contact patches, grouped along x (gaps over 25 cm split them); a group
   shorter than 1 m along x with patches on both sides of the centre line is an axle, at the middle of its
   x span (the contact patch of a round tyre is centred under its hub).
2. Tyres: a tyre standing on the ground at axle x is a circle in the side view through the contact point,
   centred above it at the height of its radius r. A surface sample at (dx, h) from the contact point
   (h above it) lies on such a circle for r = (dx^2 + h^2) / 2h, and on the tyre's tread its face normal points
   along the radius (to within 10 degrees: a polygonal tyre's facets). Samples in the side's contact y span
   (plus 5 cm) whose normal is radial for their own r are tread candidates; the tread is the strongest peak of
   their r (5 mm bins): a wheel arch around the tyre, a sill or a bumper beside it gives a different r at
   every height, and its normals point elsewhere. Radius = the median r within 1 cm of the peak; width = the y
   span of that tread on a side (a twin tyre's pair counts as one, gap included), mean of the two sides;
   track = between the two treads' middles. The tread must cover an arc of at least 60 degrees (a flat wall
   at distance d from the axle looks like a tread of radius d at one height only).
3. Plausibility: a road wheel's radius lies in ``RADIUS_RANGE``; an axle found with a radius outside it is
   dropped (given ``axles``: refused, see :func:`find_wheels`).

ISO vehicle frame (z up, wheels on the ground), metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from rigopt.errors import DataError

#: Surface samples drawn to find the wheels.
WHEEL_SAMPLES = 60000
#: Contact patches further apart than this along x belong to different axles (m).
AXLE_GAP = 0.25
#: A contact group longer than this along x is a skirt or a floor, not a tyre (m).
MAX_PATCH_LENGTH = 1.0
#: A given axle must lie within this distance (m) of the middle of the tyres' contact patches near it.
AXLE_TOLERANCE = 0.1
#: A road wheel's radius (m): tyres measured outside it are not wheels.
RADIUS_RANGE = (0.2, 0.8)
#: Tread samples: normal within this angle of the radius (deg); at least this many per axle.
TREAD_ANGLE_DEG = 10.0
MIN_TREAD_SAMPLES = 30
#: The tread samples must cover this arc of the tyre's side view (deg, 5th to 95th percentile).
MIN_TREAD_ARC_DEG = 60.0
#: Histogram bin of the candidates' radii, and the window around its peak kept as the tread (m).
RADIUS_BIN, TREAD_WINDOW = 0.005, 0.01


@dataclass(frozen=True)
class FoundWheels:
    """One axle's wheels: ``x`` m, ``radius`` m, ``width`` m (one side's tyres), ``track`` m (between
    the sides' centre planes)."""

    x: float
    radius: float
    width: float
    track: float


def ground_band(mesh: trimesh.Trimesh) -> float:
    """Height (m) of the band above the lowest point in which the tyres' contact patches are sought."""
    return float(np.clip(0.05 * np.ptp(mesh.bounds[:, 2]), 0.03, 0.12))


def contact_height(mesh: trimesh.Trimesh, wheels) -> float | None:
    """z (m) of the lowest tyre contact of ``wheels`` found on ``mesh`` (the ground they stand on), None when
    there are none."""
    if not wheels:
        return None
    vertices = mesh.vertices
    low = [vertices[np.abs(vertices[:, 0] - w.x) <= w.radius, 2].min(initial=np.inf) for w in wheels]
    return float(min(low)) if np.isfinite(min(low)) else None


def find_wheels(mesh: trimesh.Trimesh, axles=None) -> tuple[FoundWheels, ...]:
    """The axles' wheels of ``mesh`` (ISO frame, wheels on the ground), front first; () when no wheels are
    found. ``axles`` (x m each) gives the axles' positions: the tyres near them (within 0.6 m) are measured;
    a tyre centred more than AXLE_TOLERANCE from its given axle, or whose radius is outside RADIUS_RANGE, is a
    DataError; an axle without a tyre is left out."""
    points, face = trimesh.sample.sample_surface(mesh, WHEEL_SAMPLES, seed=0)
    normals = mesh.face_normals[face]
    contacts = np.concatenate([points, mesh.vertices])
    bottom, band = mesh.bounds[0, 2], ground_band(mesh)
    low = contacts[contacts[:, 2] <= bottom + band]
    if len(low) == 0:
        return ()
    centre_y = 0.5 * (mesh.bounds[0, 1] + mesh.bounds[1, 1])
    if axles is not None:
        groups = [low[np.abs(low[:, 0] - x) <= 0.6] for x in axles]
    else:
        order = np.argsort(low[:, 0])
        cuts = np.flatnonzero(np.diff(low[order, 0]) > AXLE_GAP) + 1
        groups = [low[part] for part in np.split(order, cuts)]
    found = []
    for k, group in enumerate(groups):
        left, right = group[group[:, 1] > centre_y], group[group[:, 1] < centre_y]
        if len(left) < 3 or len(right) < 3:
            continue
        span = np.ptp(group[:, 0])
        if axles is None and span > MAX_PATCH_LENGTH:
            continue
        centre = float(0.5 * (group[:, 0].min() + group[:, 0].max()))
        tyre = _tyre(points, normals, centre, float(group[:, 2].min()), band,
                     [(side[:, 1].min(), side[:, 1].max()) for side in (left, right)])
        x = float(axles[k]) if axles is not None else centre
        if tyre is None:
            continue
        if axles is not None and abs(centre - x) > AXLE_TOLERANCE:
            raise DataError(f"--axles {x:g}: the tyres there stand centred at x = {centre:.2f} m, "
                            f"{abs(centre - x):.2f} m away; give --axles {centre:.2f} (each axle's x, from the vehicle "
                            "centre)")
        radius, width, track = tyre
        if not RADIUS_RANGE[0] <= radius <= RADIUS_RANGE[1]:
            if axles is not None:
                raise DataError(f"at --axles x = {x:g} m the tyre measures a radius of {radius:.2f} m, outside a road "
                                f"wheel's {RADIUS_RANGE[0]:g}-{RADIUS_RANGE[1]:g} m: give the x of each axle's centre")
            continue
        found.append(FoundWheels(x, radius, width, track))
    if axles is None and len(found) < 2:
        return ()
    return tuple(sorted(found, key=lambda w: -w.x))


def _tyre(points, normals, x: float, ground: float, band: float, spans) -> tuple[float, float, float] | None:
    """(radius, width, track) m of the tyres standing at (``x``, ``ground``) whose contact patches span the
    y ranges ``spans`` [(low, high) left, (low, high) right], from their tread (module doc, step 2)."""
    dx = points[:, 0] - x
    h = points[:, 2] - ground
    in_side = np.zeros(len(points), dtype=int)  # 1 left, 2 right
    for k, (low, high) in enumerate(spans):
        in_side[(points[:, 1] >= low - 0.05) & (points[:, 1] <= high + 0.05)] = k + 1
    chosen = (in_side > 0) & (np.abs(dx) < 1.6) & (h > band) & (h < 1.7) & (np.abs(normals[:, 1]) < 0.5)
    dx, h, normal_xz = dx[chosen], h[chosen], normals[chosen][:, [0, 2]]
    radius = (dx**2 + h**2) / (2 * h)
    radial = np.stack([dx, h - radius], axis=1) / radius[:, None]
    normal_xz = normal_xz / np.linalg.norm(normal_xz, axis=1, keepdims=True)
    tread = np.abs(np.einsum("ij,ij->i", radial, normal_xz)) >= np.cos(np.deg2rad(TREAD_ANGLE_DEG))
    tread &= (radius > 0.1) & (radius < 1.5)
    if tread.sum() < MIN_TREAD_SAMPLES:
        return None
    counts, edges = np.histogram(radius[tread], bins=np.arange(0.1, 1.5 + RADIUS_BIN, RADIUS_BIN))
    smoothed = np.convolve(counts, [1, 2, 1], mode="same")
    peak = 0.5 * (edges[np.argmax(smoothed)] + edges[np.argmax(smoothed) + 1])
    on_tread = tread & (np.abs(radius - peak) <= TREAD_WINDOW)
    if on_tread.sum() < MIN_TREAD_SAMPLES:
        return None
    angle = np.degrees(np.arctan2(radial[on_tread, 0], -radial[on_tread, 1]))  # 0 at the contact, 180 on top
    low_angle, high_angle = np.percentile(np.abs(angle), [5, 95])
    if high_angle - low_angle < MIN_TREAD_ARC_DEG:  # a wall or a panel edge, not a round tread
        return None
    y, side = points[chosen][on_tread, 1], in_side[chosen][on_tread]
    if not (np.any(side == 1) and np.any(side == 2)):
        return None
    left, right = y[side == 1], y[side == 2]
    width = 0.5 * (np.ptp(left) + np.ptp(right))
    track = 0.5 * (left.min() + left.max()) - 0.5 * (right.min() + right.max())
    return float(np.median(radius[on_tread])), float(width), float(track)
