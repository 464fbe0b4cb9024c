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
#: Depth range (m) of the depth-prior comparison: the LSS-style detector's depth bins (``ModelConfig``).
DEPTH_RANGE = (1.0, 61.0)
#: Sample pixels (columns, rows) per image of the depth-prior comparison, at cell centres.
GRID = (16, 9)


def ground_depths(cameras: Sequence[Camera], grid: tuple[int, int] = GRID) -> np.ndarray:
    """(N, grid columns x rows) float: ln of the optical-axis depth (m) at which each grid pixel's ray meets
    the ground plane z = 0, clipped to DEPTH_RANGE; the far end where the ray never meets it in front."""
    model = CameraModel.of_cameras(list(cameras))
    cols, rows = grid
    u, v = np.meshgrid((np.arange(cols) + 0.5) / cols, (np.arange(rows) + 0.5) / rows)
    fractions = np.stack([u.ravel(), v.ravel()], axis=1)  # (G, 2) in (0, 1)
    pixels = fractions[None] * np.stack([model.width, model.height], axis=-1)[:, None, :]  # (N, G, 2)
    rays = model.pixel_rays(pixels, unit=True, frame="body")  # (N, G, 3), body frame (x along the axis)
    rotations = np.stack([camera.rotation for camera in cameras])
    heights = np.array([camera.position[2] for camera in cameras])
    down = -np.einsum("nj,ngj->ng", rotations[:, 2, :], rays)  # descent per unit length along each ray
    with np.errstate(divide="ignore", invalid="ignore"):
        along = np.where(down > 0, heights[:, None] / down, np.inf)  # distance to the ground along the ray
        depth = along * rays[..., 0]
    depth = np.where(np.isfinite(depth) & (depth > 0), depth, DEPTH_RANGE[1])
    return np.log(np.clip(depth, *DEPTH_RANGE))


def lifting_terms(rigs_a: Sequence[Rig], rigs_b: Sequence[Rig]) -> np.ndarray:
    """(P, len(TERMS)) float: the terms of the pairs (rigs_a[p], rigs_b[p]) under RigCD's unit-weight matching
    (the published one), both rigs measured from their vehicle's centre on the ground."""
    if len(rigs_a) != len(rigs_b):
        raise ValueError("lifting_terms pairs rigs_a[p] with rigs_b[p]: give lists of one length")
    index = np.arange(len(rigs_a))
    values, assignments = match_pairs(RigBatch.from_rigs(rigs_a), index, RigBatch.from_rigs(rigs_b), index,
                                      DEFAULT_ALPHA, DEFAULT_LAMBDAS, keep_assignment=True)
    angles = {}  # id(rig) -> (yaw, pitch, roll, ln depths) per camera
    out = np.zeros((len(rigs_a), len(TERMS)))
    for p, (a, b) in enumerate(zip(rigs_a, rigs_b)):
        rows, cols = assignments[p]
        ya, yb = (_camera_geometry(rig, angles) for rig in (a, b))
        dxy = a.positions[rows, :2] - b.positions[cols, :2]
        yaw = np.angle(np.exp(1j * (ya[0][rows] - yb[0][cols])))
        roll = np.angle(np.exp(1j * (ya[2][rows] - yb[2][cols])))
        out[p, 4] = np.mean(np.linalg.norm(dxy, axis=1))
        out[p, 5] = np.mean(np.abs(a.positions[rows, 2] - b.positions[cols, 2]))
        out[p, 6] = np.mean(np.abs(yaw))
        out[p, 7] = np.mean(np.abs(ya[1][rows] - yb[1][cols]) + np.abs(roll))
        out[p, 8] = np.mean(np.abs(ya[3][rows] - yb[3][cols]))
    for k, key in enumerate(TERMS[:4]):
        out[:, k] = values[key]
    return out


def _camera_geometry(rig: Rig, cache: dict) -> tuple:
    if id(rig) not in cache:
        yaw, pitch, roll = yaw_pitch_roll_from_rotation(rig.rotations)
        cache[id(rig)] = (yaw, pitch, roll, ground_depths(rig.cameras))
    return cache[id(rig)]
