"""Mount checks through real lenses: the checked frustum and the probe rays follow the lens, and a wide
fisheye's frustum stays a convex solid that python-fcl can collide."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.camera import CameraModel, Lens
from rigopt.mounting.candidates import clear_directions, probe_directions
from rigopt.mounting.records import MountRules
from rigopt.mounting.rules import check_rig
from rigopt.mounting.shapes import frustum_vertices
from rigopt.rig.model import Camera, Rig

ARGO = Lens(2048, 1550, 1773.0, 1773.0, 1024.0, 775.0, "radtan", (-0.26, 0.07, 0.0, 0.0, 0.0))
FISHEYE = Lens(1280, 960, 380.0, 380.0, 640.0, 480.0, "fisheye", (-0.02, 0.003, 0.0, 0.0))


def test_probe_rays_of_a_lens_are_its_models_and_a_pinholes_are_its_fovs():
    rules = MountRules()
    np.testing.assert_array_equal(probe_directions(ARGO, rules),
                                  CameraModel.of_lens(ARGO).probe_rays(1 - rules.frustum_margin))
    np.testing.assert_array_equal(probe_directions(Lens.pinhole(90.0), rules),  # to the bit, as from its FOV
                                  CameraModel.from_fov(90.0, (1280, 720)).probe_rays(1 - rules.frustum_margin))
    with pytest.raises(TypeError, match="Lens.pinhole"):
        probe_directions(90.0, rules)
    # barrel distortion: wider probes than the pinhole of the same intrinsics
    pinhole = Lens(2048, 1550, 1773.0, 1773.0, 1024.0, 775.0)
    assert np.abs(probe_directions(ARGO, rules)[0, 1]) > np.abs(probe_directions(pinhole, rules)[0, 1])


def test_a_wider_lens_is_clear_in_fewer_directions(box_car):
    yaws = np.deg2rad(np.arange(-180, 180, 15))
    narrow = clear_directions(box_car, [[0.0, 0.93, 1.0]], yaws, np.array([0.0]), ARGO)
    wide = clear_directions(box_car, [[0.0, 0.93, 1.0]], yaws, np.array([0.0]), FISHEYE)
    assert wide.sum() < narrow.sum() and np.all(narrow | ~wide)


def test_a_fisheye_camera_is_checked_with_a_convex_frustum(box_car):
    camera = Camera("FISH", [2.04, 0.0, 1.0], np.eye(3), FISHEYE, zone="front")
    vertices = frustum_vertices(camera, MountRules())
    assert vertices.shape == (8, 3) and np.all(vertices[:, 0] > camera.position[0])
    check = check_rig(Rig("fish", box_car.blueprint, (camera,)), box_car)
    assert len(check.cameras) == 1  # fcl took the frustum; the verdict depends on the box car's zones
