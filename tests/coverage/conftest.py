"""Small vehicles, cameras and settings for the coverage tests, independent of the built-in vehicles.

The box car is one prism: the box x in [-2, 2], y in [-1, 1], z in [0.3, 1.5] m (ISO frame, x forward,
y left, z up), so its footprint is the rectangle [-2, 2] x [-1, 1] with its centre at the origin. Test
modules cannot import this file, so they get the vehicle, factories and settings as fixtures.
"""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.vehicle.footprint import Footprint
from rigopt.coverage.measures import CoverageSettings
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

#: Half-sizes of the box car: x in [-BOX_X, BOX_X], y in [-BOX_Y, BOX_Y], z in [BOX_Z_LOW, BOX_Z_HIGH].
BOX_X, BOX_Y, BOX_Z_LOW, BOX_Z_HIGH = 2.0, 1.0, 0.3, 1.5

BOX_SPEC = """name = "covbox"
blueprint = "vehicle.test.covbox"

[[solids]]
name = "body"
type = "prism"
side = [[-2, 0.3], [2, 0.3], [2, 1.5], [-2, 1.5]]
plan = [[2, 0], [2, 1.0], [-2, 1.0], [-2, 0]]
"""


@pytest.fixture(scope="session")
def box_dims():
    """(half-length, half-width, bottom, top) of the box car, metres."""
    return BOX_X, BOX_Y, BOX_Z_LOW, BOX_Z_HIGH


@pytest.fixture(scope="session")
def box_vehicle(tmp_path_factory) -> Vehicle:
    path = tmp_path_factory.mktemp("covbox") / "vehicle.toml"
    path.write_text(BOX_SPEC)
    vehicle = Vehicle.from_spec(read_spec(path))
    # The tests derive their expectations from these bounds: check the build once.
    np.testing.assert_allclose(vehicle.mesh.bounds, [[-BOX_X, -BOX_Y, BOX_Z_LOW], [BOX_X, BOX_Y, BOX_Z_HIGH]],
                               atol=1e-6)
    assert vehicle.mesh.is_watertight
    return vehicle


@pytest.fixture(scope="session")
def box_footprint(box_vehicle) -> Footprint:
    return Footprint.of_mesh(box_vehicle.mesh)


def _camera(position, yaw_deg=0.0, pitch_deg=0.0, fov=90.0, image_size=(1280, 720), id="CAM"):
    rotation = rotation_from_yaw_pitch_roll(np.deg2rad(yaw_deg), np.deg2rad(pitch_deg), 0.0)
    return Camera.pinhole(id, np.asarray(position, dtype=float), rotation, fov, tuple(image_size))


@pytest.fixture(scope="session")
def camera():
    """Factory: ``camera(position, yaw_deg=0, pitch_deg=0, fov=90, image_size=(1280, 720), id="CAM")``."""
    return _camera


@pytest.fixture(scope="session")
def rig():
    """Factory: ``rig(*cameras, name="test")`` -> Rig on the box car."""

    def make(*cameras, name="test"):
        return Rig(name, "vehicle.test.covbox", tuple(cameras))

    return make


@pytest.fixture(scope="session")
def arrays():
    """Factory: the (positions, rotations, fovs, image_sizes) arrays of cameras, as `visible` takes them."""

    def split(*cameras):
        return (np.array([c.position for c in cameras]), np.array([c.rotation for c in cameras]),
                np.array([c.fov for c in cameras]), np.array([c.image_size for c in cameras]))

    return split


@pytest.fixture(scope="session")
def small_settings() -> CoverageSettings:
    """Coarse settings that keep a whole coverage report well under a second on the box car."""
    return CoverageSettings(
        ring_distances=(2.0, 50.0),
        ring_heights=(0.0, 0.8),
        ring_samples=180,
        sectors=36,
        bev_extent=8.0,
        bev_cell=1.0,
        bev_height=0.8,
        blind_radius=2.0,
        blind_search=6.0,
        blind_azimuths=45,
        blind_cell=0.1,
        image_grid=(16, 10),
        overlap_ring=(50.0, 0.8),
    )
