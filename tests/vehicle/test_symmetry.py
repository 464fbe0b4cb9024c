"""Mirror symmetry across y = 0: of bodies (``mirror_symmetry``), of camera poses (``camera_mirrors``,
``rig_symmetry``) and of the symmetric mount points and candidates the designer places pairs on."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from rigopt.design.candidates import build_candidates
from rigopt.design.settings import DesignSettings
from rigopt.geometry import rotation_from_yaw_pitch_roll, yaw_pitch_roll_from_rotation
from rigopt.mounting.sampling import sample_symmetric_zone_points
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.library import load_vehicle
from rigopt.vehicle.symmetry import (SYMMETRY_TOLERANCE_M, camera_mirrors, mirror_rotations, mirror_symmetry,
                                     rig_symmetry)


@pytest.fixture(scope="module")
def firetruck():
    return load_vehicle("firetruck")


@pytest.mark.parametrize("name", ["etron", "tt", "firetruck", "hgv"])
def test_the_builtin_vehicles_are_mirror_symmetric(name):
    assert load_vehicle(name).symmetry.symmetric


def test_a_box_with_a_bulge_on_one_side_is_not_symmetric():
    box = trimesh.creation.box([4.0, 1.8, 1.5])
    bulge = trimesh.creation.box([3.0, 0.4, 1.0])
    bulge.apply_translation([0.0, 1.05, 0.0])
    body = trimesh.util.concatenate([box, bulge])
    symmetric, lopsided = mirror_symmetry(box), mirror_symmetry(body)
    assert symmetric.p99 < 1e-6 and symmetric.symmetric
    assert lopsided.p99 > SYMMETRY_TOLERANCE_M and not lopsided.symmetric
    assert "not mirror-symmetric" in lopsided.describe()


def test_a_mirrored_rotation_negates_yaw_and_roll_and_keeps_pitch():
    rotation = rotation_from_yaw_pitch_roll(np.deg2rad(35.0), np.deg2rad(-12.0), np.deg2rad(4.0))
    yaw, pitch, roll = yaw_pitch_roll_from_rotation(mirror_rotations(rotation[None])[0])
    assert np.rad2deg([yaw, pitch, roll]) == pytest.approx([-35.0, -12.0, -4.0], abs=1e-9)
    assert np.linalg.det(mirror_rotations(rotation[None])[0]) == pytest.approx(1.0)


def camera(id, x, y, z, yaw_deg, fov=90.0):
    return Camera.pinhole(id, np.array([x, y, z]), rotation_from_yaw_pitch_roll(np.deg2rad(yaw_deg), 0.0, 0.0), fov)


def test_rig_symmetry_finds_pairs_centreline_cameras_and_the_unpaired():
    rig = Rig("r", "car", (camera("front", 2.0, 0.0, 1.0, 0.0), camera("left", 0.0, 0.9, 1.0, 80.0),
                           camera("right", 0.0, -0.93, 1.0, -80.0), camera("back", -2.0, 0.0, 1.0, 180.0)))
    symmetry = rig_symmetry(rig)
    assert symmetry.symmetric
    assert symmetry.pairs == (("left", "right"),)
    assert set(symmetry.centreline) == {"front", "back"}
    assert symmetry.largest_offset == pytest.approx(0.03)
    crooked = Rig("r", "car", rig.cameras[:2] + (camera("right", 0.0, -0.9, 1.0, -70.0),))
    assert camera_mirrors(crooked.positions, crooked.rotations, crooked.fovs).tolist() == [0, -1, -1]
    assert set(rig_symmetry(crooked).unpaired) == {"left", "right"}
    narrower = Rig("r", "car", rig.cameras[:2] + (camera("right", 0.0, -0.9, 1.0, -80.0, fov=60.0),))
    assert not rig_symmetry(narrower).symmetric


@pytest.mark.slow
def test_symmetric_mount_points_pair_up_across_the_centre_plane(firetruck):
    points, normals, names, mirror = sample_symmetric_zone_points(firetruck, 0.4)
    assert np.array_equal(mirror[mirror], np.arange(len(mirror)))
    centre = mirror == np.arange(len(mirror))
    assert centre.any() and np.all(points[centre, 1] == 0.0) and np.all(normals[centre, 1] == 0.0)
    assert np.all(names[mirror] == names)
    reflected = points[mirror] * [1.0, -1.0, 1.0]
    assert np.abs(reflected[:, [0, 2]] - points[:, [0, 2]]).max() < 0.01
    assert np.abs(reflected[:, 1] - points[:, 1]).max() <= 0.07  # the firetruck's own asymmetry, 6 cm


@pytest.mark.slow
def test_symmetric_candidates_are_closed_under_their_mirror(firetruck):
    settings = DesignSettings(lenses=(65.0, 90.0), pitches_deg=(-10.0, 0.0))
    candidates = build_candidates(firetruck, settings.lenses, 0.5, np.arange(-180.0, 180.0, 30.0),
                                  settings.pitches_deg, None, settings.rules, 0.1, symmetric=True)
    m = candidates.mirror
    assert np.array_equal(m[m], np.arange(len(m)))
    assert np.array_equal(candidates.fovs[m], candidates.fovs)
    assert np.array_equal(candidates.pitches[m], candidates.pitches)
    assert np.abs(np.angle(np.exp(1j * (candidates.yaws[m] + candidates.yaws)))).max() < 1e-12
    self_mirrored = m == np.arange(len(m))
    assert np.all(np.isin(np.round(np.rad2deg(candidates.yaws[self_mirrored])), [0.0, -180.0]))
    assert candidates.mirror_closed([0]).tolist() == sorted({0, int(m[0])})
    free = build_candidates(firetruck, settings.lenses, 0.5, np.arange(-180.0, 180.0, 30.0), settings.pitches_deg,
                            None, settings.rules, 0.1)
    assert free.mirror is None
