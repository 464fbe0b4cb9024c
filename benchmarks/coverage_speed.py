"""Coverage speed: a full report of a 10-camera rig, the designer's coverage matrix for 5,000 candidates,
and ray casting rays/s of embree and trimesh's triangle intersector against a brute-force reference.

Usage: python benchmarks/coverage_speed.py [--rays 20000] [--candidates 5000] [--seed 0]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from rigopt.coverage.matrix import coverage_matrix
from rigopt.coverage.measures import CoverageSettings, coverage_report
from rigopt.raycast import RayCaster, has_embree
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.rig.library import load_rig
from rigopt.mounting.sampling import sample_zone_points
from rigopt.vehicle.library import load_vehicle

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the oracles live with the tests
from oracles.raycast import first_hit_distance_bruteforce  # noqa: E402


def timed(function):
    start = time.perf_counter()
    value = function()
    return value, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rays", type=int, default=20000)
    parser.add_argument("--candidates", type=int, default=5000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    rig = load_rig("R1-c10")
    vehicle = load_vehicle(rig.vehicle)
    mesh = vehicle.mesh
    print(f"embree available: {has_embree()}; body: {vehicle.name}, {len(mesh.faces)} triangles")

    # Rays from around the body towards it and away from it.
    origins = rng.uniform(mesh.bounds[0] - 2.0, mesh.bounds[1] + 2.0, (args.rays, 3))
    directions = rng.normal(size=(args.rays, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    reference, t_brute = timed(lambda: first_hit_distance_bruteforce(mesh.triangles, origins, directions))
    rows = [("brute force", t_brute, reference)]
    backends = (["embree"] if has_embree() else []) + ["triangle"]
    for backend in backends:
        caster = RayCaster(mesh, backend)
        caster.first_hit_distance(origins[:10], directions[:10])  # build the intersector once
        hits, seconds = timed(lambda: caster.first_hit_distance(origins, directions))
        rows.append((backend, seconds, hits))
    print(f"\n{args.rays} random rays against the body")
    print(f"{'backend':<12} {'seconds':>8} {'rays/s':>12} {'vs brute':>9} {'disagree':>9}")
    for name, seconds, hits in rows:
        disagree = np.mean(~np.isclose(hits, reference, rtol=0, atol=1e-6) & ~(np.isinf(hits) & np.isinf(reference)))
        print(f"{name:<12} {seconds:8.3f} {args.rays / seconds:12,.0f} {t_brute / seconds:8.1f}x {disagree:9.4%}")

    settings = CoverageSettings()
    report, t_report = timed(lambda: coverage_report(rig, vehicle, settings))
    print(f"\nfull coverage report of {rig.name} ({len(rig)} cameras) on {vehicle.name}: {t_report:.2f} s "
          f"({len(settings.ring_distances) * len(settings.ring_heights)} rings x {settings.ring_samples} azimuths, "
          f"{len(report.bev.x)}x{len(report.bev.y)} BEV cells, blind zone, {len(rig)} image grids)")

    points, normals, _ = sample_zone_points(vehicle, 0.1)
    pick = rng.integers(0, len(points), args.candidates)
    yaw = np.arctan2(normals[pick, 1], normals[pick, 0]) + rng.uniform(-0.6, 0.6, args.candidates)
    rotations = rotation_from_yaw_pitch_roll(yaw, rng.uniform(-0.3, 0.3, args.candidates), np.zeros(args.candidates))
    fovs = rng.choice([60.0, 75.0, 90.0, 120.0], args.candidates)
    matrix, t_matrix = timed(lambda: coverage_matrix(vehicle, points[pick], rotations, fovs, settings=settings))
    print(f"coverage matrix: {args.candidates} candidates x {matrix.sees.shape[1]} sector points "
          f"({settings.sectors} sectors x {len(settings.ring_distances)} distances x {len(settings.ring_heights)} "
          f"heights): {t_matrix:.2f} s, {matrix.sees.mean():.1%} seen")


if __name__ == "__main__":
    main()
