"""Rig-distance terms for lifting detectors, over RigCD's own matched camera pairs.

A lifting detector (LSS, BEVDet) shares one image encoder and depth network across its cameras and is trained
with turned and mirrored extrinsics, so it learns to ignore a camera's yaw and plan position but keeps the
image-row-to-depth prior of its training rig's heights and pitches. RigCD weighs every offset alike. These
terms split them (docs/metrics.md, "Distances for lifting detectors"):

- ``t_plan`` (m): mean horizontal distance, ``t_vert`` (m): mean height difference of the matched cameras;
- ``r_yaw`` (rad): mean |yaw difference|; ``r_tilt`` (rad): mean |pitch difference| + |roll difference|
  (yaw, pitch, roll of :func:`rigopt.geometry.yaw_pitch_roll_from_rotation`, ISO 8855);
- ``dpm`` (log-metres): the depth-prior mismatch. For each camera, the optical-axis depth at which the rays of
  a GRID of pixels (at the same relative places in every image) meet the ground plane z = 0 of the vehicle
  frame, clipped to the LSS-style detector's depth range DEPTH_RANGE (a ray that never descends, or meets the
  ground beyond the range or behind the lens, counts as the far end); between two matched cameras, the mean
  over the grid of |ln depth_a - ln depth_b|; ``dpm`` is its mean over the matched pairs.

Beside them, RigCD's own unit-weight features (t, r, f, count) of the same matching. Positions must be measured
from the vehicle's centre on the ground (the benchmark's frame: z is the height above the ground), so every rig
passes through :func:`rigopt.vehicle.placement.in_vehicle_frame` first (the callers' job).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from rigopt.camera import CameraModel
from rigopt.geometry import yaw_pitch_roll_from_rotation
from rigopt.metrics.rigcd import DEFAULT_ALPHA, DEFAULT_LAMBDAS, RigBatch, match_pairs
from rigopt.rig.model import Camera, Rig

#: Every term, in this order in :func:`lifting_terms`' columns.
TERMS = ("t", "r", "f", "count", "t_plan", "t_vert", "r_yaw", "r_tilt", "dpm")
#: The per-pair terms a lifting distance adds to RigCD's own (:func:`pair_terms`).
PAIR_TERMS = TERMS[4:]
#: Depth range (m) of the depth-prior comparison: the LSS-style detector's depth bins (``ModelConfig``).
DEPTH_RANGE = (1.0, 61.0)
#: Sample pixels (columns, rows) per image of the depth-prior comparison, at cell centres.
GRID = (16, 9)


def ground_depths(cameras: Sequence[Camera], grid: tuple[int, int] = GRID) -> np.ndarray:
    """(N, grid columns x rows) float: ln of the optical-axis depth (m) at which each grid pixel's ray meets
    the ground plane z = 0, clipped to DEPTH_RANGE; the far end where the ray never meets it in front."""
    cameras = list(cameras)
    return depths_on_ground(CameraModel.of_cameras(cameras), np.stack([c.rotation for c in cameras]),
                            np.array([c.position[2] for c in cameras]), grid)


def depths_on_ground(model: CameraModel, rotations: np.ndarray, heights: np.ndarray,
                     grid: tuple[int, int] = GRID) -> np.ndarray:
    """(N, grid columns x rows) float: :func:`ground_depths` of N cameras given as their lenses ``model`` (batch
    (N,)), ``rotations`` (N, 3, 3) (body to vehicle frame) and ``heights`` (N,) m above the ground."""
    cols, rows = grid
    u, v = np.meshgrid((np.arange(cols) + 0.5) / cols, (np.arange(rows) + 0.5) / rows)
    fractions = np.stack([u.ravel(), v.ravel()], axis=1)  # (G, 2) in (0, 1)
    pixels = fractions[None] * np.stack([model.width, model.height], axis=-1)[:, None, :]  # (N, G, 2)
    rays = model.pixel_rays(pixels, unit=True, frame="body")  # (N, G, 3), body frame (x along the axis)
    down = -np.einsum("nj,ngj->ng", np.asarray(rotations)[:, 2, :], rays)  # descent per unit length along each ray
    with np.errstate(divide="ignore", invalid="ignore"):
        along = np.where(down > 0, np.asarray(heights, dtype=float)[:, None] / down, np.inf)  # to the ground
        depth = along * rays[..., 0]
    depth = np.where(np.isfinite(depth) & (depth > 0), depth, DEPTH_RANGE[1])
    return np.log(np.clip(depth, *DEPTH_RANGE))


def pair_terms(positions: np.ndarray, rotations: np.ndarray, model: CameraModel, reference: Rig) -> np.ndarray:
    """(n, R, len(PAIR_TERMS)) float: t_plan (m), t_vert (m), r_yaw (rad), r_tilt (rad) and dpm (log-m) between
    each of n cameras (``positions`` (n, 3) m and ``rotations`` (n, 3, 3) in the vehicle frame from its centre
    on the ground, lenses ``model`` of batch (n,)) and each of the R cameras of ``reference`` (same frame): the
    per-pair values whose means over a matching are :func:`lifting_terms`' last five columns."""
    mine = _geometry(np.asarray(positions), np.asarray(rotations), model)
    theirs = _geometry(reference.positions, reference.rotations, CameraModel.of_cameras(reference.cameras))
    return np.stack(_differences(mine, theirs, np.s_[:, None], np.s_[None, :], depth_axis=-1), axis=-1)


def lifting_terms(rigs_a: Sequence[Rig], rigs_b: Sequence[Rig]) -> np.ndarray:
    """(P, len(TERMS)) float: the terms of the pairs (rigs_a[p], rigs_b[p]) under RigCD's unit-weight matching
    (the published one), both rigs measured from their vehicle's centre on the ground."""
    if len(rigs_a) != len(rigs_b):
        raise ValueError("lifting_terms pairs rigs_a[p] with rigs_b[p]: give lists of one length")
    index = np.arange(len(rigs_a))
    values, assignments = match_pairs(RigBatch.from_rigs(rigs_a), index, RigBatch.from_rigs(rigs_b), index,
                                      DEFAULT_ALPHA, DEFAULT_LAMBDAS, keep_assignment=True)
    cache = {}  # id(rig) -> its cameras' geometry
    out = np.zeros((len(rigs_a), len(TERMS)))
    for p, (a, b) in enumerate(zip(rigs_a, rigs_b)):
        rows, cols = assignments[p]
        ga, gb = (_rig_geometry(rig, cache) for rig in (a, b))
        out[p, 4:] = [np.mean(d) for d in _differences(ga, gb, rows, cols, depth_axis=None)]
    for k, key in enumerate(TERMS[:4]):
        out[:, k] = values[key]
    return out


def _geometry(positions: np.ndarray, rotations: np.ndarray, model: CameraModel) -> tuple:
    """(plan positions (N, 2) m, heights (N,) m, yaws, pitches, rolls (N,) rad, ln ground depths (N, G))."""
    yaw, pitch, roll = yaw_pitch_roll_from_rotation(rotations)
    return positions[:, :2], positions[:, 2], yaw, pitch, roll, depths_on_ground(model, rotations, positions[:, 2])


def _rig_geometry(rig: Rig, cache: dict) -> tuple:
    if id(rig) not in cache:
        cache[id(rig)] = _geometry(rig.positions, rig.rotations, CameraModel.of_cameras(rig.cameras))
    return cache[id(rig)]


def _differences(a: tuple, b: tuple, index_a, index_b, depth_axis) -> tuple:
    """(t_plan, t_vert, r_yaw, r_tilt, dpm) between the cameras ``a[index_a]`` and ``b[index_b]`` of two
    :func:`_geometry` tuples (broadcast); dpm's grid averaged over ``depth_axis`` (None: kept, for a mean over
    pairs and grid at once)."""
    plan_a, height_a, yaw_a, pitch_a, roll_a, depth_a = a
    plan_b, height_b, yaw_b, pitch_b, roll_b, depth_b = b
    dyaw = np.angle(np.exp(1j * (yaw_a[index_a] - yaw_b[index_b])))
    droll = np.angle(np.exp(1j * (roll_a[index_a] - roll_b[index_b])))
    depth = np.abs(depth_a[index_a] - depth_b[index_b])
    return (np.linalg.norm(plan_a[index_a] - plan_b[index_b], axis=-1), np.abs(height_a[index_a] - height_b[index_b]),
            np.abs(dyaw), np.abs(pitch_a[index_a] - pitch_b[index_b]) + np.abs(droll),
            depth if depth_axis is None else depth.mean(axis=depth_axis))
