"""Write ``raw_car.obj``: a car mesh as simulator and CAD exports often come, for the walk-through in
docs/your_rig_and_vehicle.md.

    python examples/make_raw_car.py

It is rigopt's built-in ``tt`` body (a 4.18 m coupe) put the way raw exports are: in centimetres, its front
facing -y, lifted 12 cm off the ground (its wheels float) and with its origin at the front bumper rather than
the car's centre. ``rigopt vehicle add`` reads it by following the hints it prints.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from rigopt.vehicle.library import load_vehicle

HERE = Path(__file__).resolve().parent


def raw_car() -> trimesh.Trimesh:
    """The tt body in the raw pose described above."""
    car = load_vehicle("tt").mesh.copy()
    car.apply_translation([-car.bounds[1, 0], 0.0, 0.12])  # origin at the front bumper; floating 12 cm
    car.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, [0.0, 0.0, 1.0]))  # front: +x -> -y
    car.apply_scale(100.0)  # metres -> centimetres
    return car


if __name__ == "__main__":
    path = HERE / "raw_car.obj"
    raw_car().export(path)
    print(f"wrote {path}")
