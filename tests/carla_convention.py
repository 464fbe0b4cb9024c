"""CARLA's own rotation, written out from LibCarla's ``geom/Rotation.h`` (``Rotation::RotateVector``), independently
of rigopt: the oracle the convention tests compare rigopt's conversions with. Test modules import this file as
``carla_convention`` (the tests folder is on sys.path through its conftest.py)."""

from __future__ import annotations

import math

import numpy as np


def carla_rotate_vector(pitch_deg: float, yaw_deg: float, roll_deg: float) -> np.ndarray:
    """(3, 3) float: the matrix RotateVector applies for CARLA angles in degrees, in CARLA's axes (x forward, y
    right, z up); its third row is (sp, -cp sr, cp cr)."""
    cp, sp = math.cos(math.radians(pitch_deg)), math.sin(math.radians(pitch_deg))
    cy, sy = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    cr, sr = math.cos(math.radians(roll_deg)), math.sin(math.radians(roll_deg))
    return np.array([[cp * cy, cy * sp * sr - sy * cr, -cy * sp * cr - sy * sr],
                     [cp * sy, sy * sp * sr + cy * cr, -sy * sp * cr + cy * sr],
                     [sp, -cp * sr, cp * cr]])
