"""Raised zones: cameras on posts above a roof rack (the etron's roof_rack, up to 1.1 m)."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.mounting.rules import check_rig, raised_mounts
from rigopt.mounting.sampling import sample_zone_points
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.library import load_vehicle

ROOF = 1.645  # etron roof skin height near x = 0 (m)


def camera(name, position, yaw_deg, pitch_deg=0.0):
    rotation = rotation_from_yaw_pitch_roll(np.deg2rad(yaw_deg), np.deg2rad(pitch_deg), 0.0)
    return Camera.pinhole(name, np.array(position, float), rotation, 70.0, (1600, 900), None)


@pytest.fixture(scope="module")
def etron():
    return load_vehicle("etron")


@pytest.fixture(scope="module")
def roof_rig_check(etron):
    """A nuScenes/Waymo-like roof rig: cameras 30, 60 and 100 cm above the roof skin, one too high, one
    looking down at its own post."""
    rig = Rig("roof", "etron", [
        camera("FRONT_30", [0.3, 0.0, ROOF + 0.3], 0), camera("BACK_100", [-1.0, 0.0, ROOF + 1.0], 180),
        camera("LEFT_60", [-0.5, 0.3, ROOF + 0.6], 90), camera("TOO_HIGH", [-0.5, -0.3, ROOF + 1.3], -90),
        camera("DOWN", [-0.2, 0.0, ROOF + 0.5], 0, -80)])
    return {c.id: c for c in check_rig(rig, etron).cameras}


@pytest.mark.parametrize("name", ["FRONT_30", "BACK_100", "LEFT_60"])
def test_roof_rack_cameras_are_valid(roof_rig_check, name):
    result = roof_rig_check[name]
    assert result.valid, result.problems
    assert result.zone == "roof_rack"


def test_a_camera_above_the_rack_height_is_refused(roof_rig_check):
    result = roof_rig_check["TOO_HIGH"]
    assert not result.valid
    assert any("off the surface" in p and "roof_rack 110 cm" in p for p in result.problems)


def test_a_camera_looking_down_sees_its_post(roof_rig_check):
    assert any("the post of DOWN" in p for p in roof_rig_check["DOWN"].problems)


def test_raised_mount_is_found_below_the_lens(etron):
    mounts = raised_mounts(etron, [[-0.5, 0.0, ROOF + 0.5], [2.0, 0.0, 1.5], [-0.5, 0.0, ROOF + 1.5]])
    assert mounts[0] is not None and mounts[0].zone.name == "roof_rack"
    assert mounts[0].height == pytest.approx(0.5, abs=0.02)
    assert mounts[1] is None and mounts[2] is None  # over the hood, and above the rack's height


def test_a_rack_camera_near_another_ones_post_collides(etron):
    rig = Rig("posts", "etron", [camera("HIGH", [-0.5, 0.0, ROOF + 0.8], 0),
                                 camera("LOW", [-0.5, 0.03, ROOF + 0.3], 90)])
    checks = {c.id: c for c in check_rig(rig, etron).cameras}
    assert any("collides with HIGH" in p for p in checks["LOW"].problems)


def test_raised_zones_are_sampled_only_when_named(etron):
    _, _, names = sample_zone_points(etron, 0.3)
    assert "roof_rack" not in set(names)
    points, normals, names = sample_zone_points(etron, 0.3, ["roof_rack"])
    assert set(names) == {"roof_rack"} and len(points) > 10
    np.testing.assert_allclose(normals, np.tile([0, 0, 1.0], (len(points), 1)))
    heights = [m.height for m in raised_mounts(etron, points)]
    assert min(heights) > 0.05 and max(heights) <= 1.1 + 1e-6


def test_raised_candidates_pass_the_mount_checks(etron):
    points, _, _ = sample_zone_points(etron, 0.4, ["roof_rack"])
    cameras = [camera(f"C{k}", p, 0) for k, p in enumerate(points[::7])]
    for result in check_rig(Rig("c", "etron", cameras[:1]), etron).cameras:
        assert result.valid, result.problems
    for cam in cameras:
        result = check_rig(Rig("c", "etron", [cam]), etron).cameras[0]
        assert result.zone == "roof_rack" and not any("off the surface" in p for p in result.problems)


def test_only_the_etron_has_a_raised_zone():
    for name in ("tt", "firetruck", "hgv"):
        assert not any(z.raised for z in load_vehicle(name).zones)
