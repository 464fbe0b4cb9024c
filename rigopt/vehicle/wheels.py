"""Wheels found on a vehicle mesh from its lowest contact patches.

The tyres are what touches the ground: surface samples within a thin band above the mesh's lowest point
(:func:`ground_band`, 5 % of the height clamped to [3, 12] cm) form patches. Patches are grouped along x
(gaps over 25 cm split them): each group is an axle when it is shorter than 1 m along x and has patches on
both sides of the centre line. Per axle: x = the middle of the group's x span (the contact patch of a
round tyre is centred under its hub), track = the distance between the left and right patches' middles,
width = the mean y span of a side's patches (a twin tyre's pair counts as one), radius from the tyre's
outline in the side view below 80 % of a first guess (each outline point (dx, z) of a circle touching the
ground gives r = (dx^2 + z^2) / 2z; the median is taken). ISO vehicle frame, metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

#: Surface samples drawn to find the wheels.
WHEEL_SAMPLES = 40000
#: Contact patches further apart than this along x belong to different axles (m).
AXLE_GAP = 0.25
#: A contact group longer than this along x is a skirt or a floor, not a tyre (m).
MAX_PATCH_LENGTH = 1.0


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


def _samples(mesh: trimesh.Trimesh, seed: int = 0) -> np.ndarray:
    points, _ = trimesh.sample.sample_surface(mesh, WHEEL_SAMPLES, seed=seed)
    return np.concatenate([points, mesh.vertices])


def find_wheels(mesh: trimesh.Trimesh, axles=None) -> tuple[FoundWheels, ...]:
    """The axles' wheels of ``mesh`` (ISO frame, wheels on the ground), front first; () when no wheels are
    found. ``axles`` (x m each) forces the axles' positions: only the wheels near them are measured."""
    points = _samples(mesh)
    bottom, band = mesh.bounds[0, 2], ground_band(mesh)
    low = points[points[:, 2] <= bottom + band]
    if len(low) == 0:
        return ()
    centre_y = 0.5 * (mesh.bounds[0, 1] + mesh.bounds[1, 1])
    if axles is not None:
        groups = [low[np.abs(low[:, 0] - x) <= 0.6] for x in axles]
    else:
        order = np.argsort(low[:, 0])
        xs = low[order, 0]
        cuts = np.flatnonzero(np.diff(xs) > AXLE_GAP) + 1
        groups = [low[part] for part in np.split(order, cuts)]
    found = []
    for k, group in enumerate(groups):
        if len(group) == 0:
            continue
        span = np.ptp(group[:, 0])
        left, right = group[group[:, 1] > centre_y], group[group[:, 1] < centre_y]
        if axles is None and (span > MAX_PATCH_LENGTH or len(left) < 3 or len(right) < 3):
            continue
        if len(left) < 3 or len(right) < 3:
            continue
        x = float(axles[k]) if axles is not None else float(0.5 * (group[:, 0].min() + group[:, 0].max()))
        left_mid = 0.5 * (left[:, 1].min() + left[:, 1].max())
        right_mid = 0.5 * (right[:, 1].min() + right[:, 1].max())
        width = 0.5 * (np.ptp(left[:, 1]) + np.ptp(right[:, 1]))
        radius = _radius(points, x, (right[:, 1].min(), right[:, 1].max()), (left[:, 1].min(), left[:, 1].max()),
                         bottom, band, span)
        found.append(FoundWheels(x, radius, float(width), float(left_mid - right_mid)))
    if axles is None and len(found) < 2:
        return ()
    return tuple(sorted(found, key=lambda w: -w.x))


def _radius(points, x, right_span, left_span, bottom, band, chord) -> float:
    """Tyre radius (m) at axle ``x`` from the side-view outline of the points in the tyres' y spans."""
    # first guess from the contact chord at the band's height: chord^2 / 4 = r^2 - (r - band)^2
    guess = (chord**2 / 4 + band**2) / (2 * band)
    in_tyre = ((points[:, 1] >= right_span[0]) & (points[:, 1] <= right_span[1])) | \
              ((points[:, 1] >= left_span[0]) & (points[:, 1] <= left_span[1]))
    z = points[:, 2] - bottom
    dx = np.abs(points[:, 0] - x)
    near = in_tyre & (z > band) & (z < 0.8 * guess) & (dx < 1.5 * guess)
    if near.sum() < 10:
        return float(guess)
    bins = np.floor(z[near] / 0.02).astype(int)
    estimates = []
    for b in np.unique(bins):
        chosen = bins == b
        k = np.argmax(dx[near][chosen])
        height, reach = z[near][chosen][k], dx[near][chosen][k]
        estimates.append((reach**2 + height**2) / (2 * height))
    return float(np.median(estimates))
