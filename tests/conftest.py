"""Shared test set-up: the hypothesis profile and strategies for random cameras and rigs.

The tests run without ``__init__.py`` files (``--import-mode=importlib`` style), so test modules cannot
import this file. The strategies reach them through hypothesis itself: :class:`Camera` and :class:`Rig`
are registered here, and a test draws them with ``st.from_type(Camera)`` / ``st.from_type(Rig)``.

Random values, all in the ISO 8855 vehicle frame:

* positions: each coordinate in [-5, 5] metres;
* rotations: uniform random unit quaternions (Shoemake's method from three uniforms) turned into
  matrices by :func:`rigopt.geometry.quaternion_to_matrix`;
* fovs: [30, 150] degrees;
* rigs: 1 to 10 cameras with unique ids ``CAM_0``, ``CAM_1``, ...
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

from rigopt.geometry import quaternion_to_matrix
from rigopt.rig.model import Camera, Rig

settings.register_profile(
    "rigopt",
    max_examples=60,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.load_profile("rigopt")

POSITION_LIMIT_M = 5.0
FOV_RANGE_DEG = (30.0, 150.0)
MAX_CAMERAS = 10


def unit_quaternions():
    """Uniform random unit quaternions ``(w, x, y, z)`` (Shoemake 1992) from three uniforms in [0, 1]."""
    unit = st.floats(0.0, 1.0)

    def shoemake(u):
        u1, u2, u3 = u
        a, b = math.sqrt(1.0 - u1), math.sqrt(u1)
        return np.array([a * math.sin(2 * math.pi * u2), a * math.cos(2 * math.pi * u2),
                         b * math.sin(2 * math.pi * u3), b * math.cos(2 * math.pi * u3)])

    return st.tuples(unit, unit, unit).map(shoemake)


def rotations():
    """(3, 3) rotation matrices, uniform on SO(3)."""
    return unit_quaternions().map(quaternion_to_matrix)


def positions(limit: float = POSITION_LIMIT_M):
    """(3,) positions in metres, each coordinate in [-limit, limit]."""
    coordinate = st.floats(-limit, limit)
    return st.tuples(coordinate, coordinate, coordinate).map(np.array)


def fovs():
    """Horizontal FOVs in degrees."""
    return st.floats(*FOV_RANGE_DEG)


def cameras(camera_id: str = "CAM"):
    """One Camera with a random pose and FOV."""
    return st.builds(Camera.pinhole, st.just(camera_id), positions(), rotations(), fovs())


def rigs(min_cameras: int = 1, max_cameras: int = MAX_CAMERAS, name: str = "random"):
    """A Rig of min_cameras..max_cameras random cameras with ids CAM_0, CAM_1, ..."""
    poses = st.lists(st.tuples(positions(), rotations(), fovs()), min_size=min_cameras, max_size=max_cameras)
    return poses.map(
        lambda cams: Rig(name, "vehicle.test", tuple(Camera.pinhole(f"CAM_{k}", *c) for k, c in enumerate(cams)))
    )


st.register_type_strategy(Camera, cameras())
st.register_type_strategy(Rig, rigs())
