"""Write ``raw_van.obj``: a 6 m high-roof panel van (class N2) as a raw CAD export, a third kind of user vehicle
beside the car and the bus.

    python examples/make_raw_van.py

The van is built here from convex pieces (no downloaded data): a load box 4.1 m long, 2.05 m wide and 2.60 m
high; a cab in front of it whose windscreen leans back from the bonnet's rear edge (1.20 m) to the roof; a short
bonnet sloping down to a 0.95 m high front face; 0.20 m ground clearance; two axles 3.66 m apart with wheels of
radius 0.36 m; and door mirrors on short stalks at the foot of the A-pillars. It is put the way CAD exports
often come: in millimetres, front facing +x, Z up, its origin at the middle of the rear axle on the ground.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import trimesh

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))  # the examples' shared mesh parts
import mesh_parts  # noqa: E402

WIDTH, HEIGHT, CLEARANCE = 2.05, 2.60, 0.20  # m: overall (mirrors aside), underside of the body
FRONT, REAR = 4.65, -1.25  # x (m) of the front and rear faces, from the rear axle
BONNET_X, BONNET_Z, NOSE_Z = 3.55, 1.20, 0.95  # the bonnet's rear edge (windscreen foot) and the front face's top
ROOF_FRONT = 2.45  # x where the windscreen meets the roof
WHEELBASE, WHEEL_R, WHEEL_W = 3.66, 0.36, 0.24
MM = 1000.0  # file units per metre


def slab(points_xz, half_width: float) -> trimesh.Trimesh:
    """The convex solid of a side profile ``points_xz`` ((k, 2) m) extruded across +-``half_width``."""
    profile = np.asarray(points_xz, dtype=float)
    corners = [np.column_stack([profile[:, 0], np.full(len(profile), side * half_width), profile[:, 1]])
               for side in (1.0, -1.0)]
    return trimesh.convex.convex_hull(np.vstack(corners))


def body() -> list[trimesh.Trimesh]:
    """The load box with the cab's roof, and the cab's front: bonnet, windscreen and nose, slightly narrower."""
    box = slab([(REAR, CLEARANCE), (ROOF_FRONT, CLEARANCE), (ROOF_FRONT, HEIGHT), (REAR, HEIGHT)], WIDTH / 2)
    cab = slab([(ROOF_FRONT, CLEARANCE), (FRONT, CLEARANCE), (FRONT, NOSE_Z), (BONNET_X, BONNET_Z),
                (ROOF_FRONT, HEIGHT - 0.05)], WIDTH / 2 - 0.04)
    return [box, cab]


def wheels() -> list[trimesh.Trimesh]:
    """Four wheels, cylinders along y standing on the ground, their outer faces just inside the body's sides."""
    return mesh_parts.wheels((0.0, WHEELBASE), WIDTH / 2 - 0.06 - WHEEL_W / 2, WHEEL_R, WHEEL_W)


def mirrors() -> list[trimesh.Trimesh]:
    """Door mirrors: a stalk from the A-pillar's foot out to a head 0.20 wide, 0.08 thick and 0.35 tall."""
    parts = []
    for side in (1.0, -1.0):
        root = np.array([BONNET_X - 0.15, side * (WIDTH / 2 - 0.05), BONNET_Z + 0.05])
        tip = np.array([BONNET_X - 0.20, side * (WIDTH / 2 + 0.18), BONNET_Z + 0.15])
        parts.append(trimesh.creation.cylinder(radius=0.02, segment=[root, tip], sections=8))
        head = trimesh.creation.box(extents=[0.08, 0.20, 0.35])
        head.apply_translation(tip + [0.0, side * 0.08, 0.10])
        parts.append(head)
    return parts


def raw_van() -> trimesh.Trimesh:
    """The van's parts, concatenated without welding, in millimetres."""
    van = trimesh.util.concatenate([*body(), *wheels(), *mirrors()])
    van.apply_scale(MM)
    return van


if __name__ == "__main__":
    path = HERE / "raw_van.obj"
    van = raw_van()
    van.export(path)
    print(f"wrote {path}: {len(van.faces)} faces, bounds (mm) {np.round(van.bounds).tolist()}")
