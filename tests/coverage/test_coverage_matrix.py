"""The designer's coverage matrix: one row per candidate, one column per ring sector point."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.coverage.matrix import coverage_matrix, rig_coverage_matrix, sector_points
from rigopt.coverage.visibility import visible
from rigopt.geometry import rotation_from_yaw_pitch_roll


@pytest.fixture(scope="module")
def candidates():
    """40 candidates on a shell around the box car, random yaw, pitch and FOV (some inside the body)."""
    rng = np.random.default_rng(21)
    count = 40
    positions = rng.uniform([-2.5, -1.5, 0.2], [2.5, 1.5, 2.0], (count, 3))
    rotations = rotation_from_yaw_pitch_roll(rng.uniform(-np.pi, np.pi, count), rng.uniform(-0.6, 0.4, count),
                                             np.zeros(count))
    fovs = rng.uniform(40.0, 170.0, count)
    sizes = np.tile([1280, 720], (count, 1))
    return positions, rotations, fovs, sizes


def test_shape_and_layout(box_vehicle, small_settings, candidates):
    matrix = coverage_matrix(box_vehicle, *candidates, settings=small_settings)
    s = small_settings
    columns = s.sectors * len(s.ring_distances) * len(s.ring_heights)
    assert matrix.sees.shape == (len(candidates[0]), columns)
    assert matrix.sees.dtype == bool
    for name in ("distance_m", "height_m", "sector", "azimuth"):
        assert getattr(matrix, name).shape == (columns,)
    assert matrix.points.shape == (columns, 3)
    # Heights outermost, then distances, then sectors from azimuth -pi.
    block = s.sectors
    np.testing.assert_array_equal(matrix.height_m, np.repeat(s.ring_heights, len(s.ring_distances) * block))
    np.testing.assert_array_equal(matrix.distance_m, np.tile(np.repeat(s.ring_distances, block), len(s.ring_heights)))
    np.testing.assert_array_equal(matrix.sector, np.tile(np.arange(block), len(s.ring_distances) * len(s.ring_heights)))
    # Sector k's centre azimuth is -pi + (k + 1/2) 2 pi / sectors.
    np.testing.assert_allclose(matrix.azimuth, -np.pi + (matrix.sector + 0.5) * 2 * np.pi / block)


def test_points_are_the_ring_points(box_vehicle, box_footprint, small_settings):
    points, distance, height, sector, azimuth = sector_points(box_footprint, small_settings)
    for d in small_settings.ring_distances:
        for h in small_settings.ring_heights:
            pick = (distance == d) & (height == h)
            np.testing.assert_allclose(points[pick], box_footprint.ring_points(azimuth[pick], d, h))
            np.testing.assert_array_equal(sector[pick], np.arange(small_settings.sectors))


def test_rows_are_per_camera_visibility(box_vehicle, box_footprint, small_settings, candidates):
    matrix = coverage_matrix(box_vehicle, *candidates, settings=small_settings)
    points = sector_points(box_footprint, small_settings)[0]
    assert np.array_equal(matrix.points, points)
    # One camera at a time, through `visible`.
    for k in range(len(candidates[0])):
        row = visible(box_vehicle.caster(small_settings.backend), *(a[k:k + 1] for a in candidates), points,
                      small_settings.max_range)[0]
        np.testing.assert_array_equal(matrix.sees[k], row)
    # Not vacuous: some candidates see much, some little, and the body hides part of the near ring.
    per_row = matrix.sees.sum(axis=1)
    assert per_row.max() > 20 and per_row.min() < 10


def test_default_image_size_is_1280_by_720(box_vehicle, small_settings, candidates):
    positions, rotations, fovs, _ = candidates
    default = coverage_matrix(box_vehicle, positions, rotations, fovs, settings=small_settings)
    explicit = coverage_matrix(box_vehicle, positions, rotations, fovs, np.tile([1280, 720], (len(fovs), 1)),
                               settings=small_settings)
    np.testing.assert_array_equal(default.sees, explicit.sees)


def test_rig_matrix_matches_the_arrays(box_vehicle, small_settings, camera, rig):
    # A square image has a taller vertical FOV: the rig's image sizes must be passed through. LEFT_DOWN
    # (pitch -25, FOV 60) sees depressions -5 .. 55 deg with 800 x 800 but only 7 .. 43 deg with 1280 x 720:
    # the ground 3 m to the left (45 deg) and the far ring (2.5 to 3.4 deg) tell them apart.
    cameras = (camera((2.05, 0, 1.0), id="FRONT"),
               camera((0, 0, 3.0), yaw_deg=90, pitch_deg=-25, fov=60, image_size=(800, 800), id="LEFT_DOWN"),
               camera((-2.05, 0.5, 1.0), yaw_deg=170, fov=120, id="REAR"))
    the_rig = rig(*cameras)
    got = rig_coverage_matrix(the_rig, box_vehicle, small_settings)
    sizes = np.array([c.image_size for c in cameras])
    expected = coverage_matrix(box_vehicle, the_rig.positions, the_rig.rotations, the_rig.fovs, sizes, small_settings)
    np.testing.assert_array_equal(got.sees, expected.sees)
    np.testing.assert_array_equal(got.points, expected.points)
    default_sizes = coverage_matrix(box_vehicle, the_rig.positions, the_rig.rotations, the_rig.fovs,
                                    settings=small_settings)
    assert not np.array_equal(default_sizes.sees[1], got.sees[1])  # the square image matters here
