"""Write ``raw_bus.obj``: a 12 m low-floor city bus (class M3) as a raw user mesh, to try ``rigopt vehicle add``
on something much larger than a car.

    python examples/make_raw_bus.py

The bus is built here from boxes and cylinders (no downloaded data): a body 12.0 m long, 2.55 m wide and
3.10 m high over its roof-top HVAC unit, 0.30 m off the ground, with rounded vertical corners and a slightly
raked windscreen; two axles (the front one 2.7 m behind the front face, the rear one 6.6 m behind that) with
wheels of radius 0.50 m; and the "rabbit-ear" mirrors that reach forward from the top front corners. It is put
the way raw exports often are: in metres, front facing +x, Z up, with its origin at the centre of the front
bumper at ground level, and its parts are separate, overlapping, unwelded meshes.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import trimesh

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))  # the examples' shared mesh parts
import mesh_parts  # noqa: E402

LENGTH, WIDTH, HEIGHT = 12.0, 2.55, 3.10  # m, overall (mirrors aside)
CLEARANCE, ROOF = 0.30, 2.85  # underside and roof of the body; the HVAC unit rises to HEIGHT
CORNER = 0.25  # radius of the rounded vertical front and rear edges
RAKE = 0.15  # how far the top of the windscreen lies behind the front bumper
FRONT_AXLE, WHEELBASE = -2.7, 6.6  # x of the front axle; distance to the rear axle
WHEEL_R, WHEEL_W = 0.50, 0.30


def rounded_outline(x_front: float, x_rear: float, half_width: float, segments: int = 6) -> np.ndarray:
    """Corners (x, y) of the footprint: a rectangle whose four corners are rounded by CORNER."""
    points = []
    for cx, cy, start in [
        (x_front - CORNER, half_width - CORNER, 0.0),
        (x_rear + CORNER, half_width - CORNER, 0.5 * np.pi),
        (x_rear + CORNER, -half_width + CORNER, np.pi),
        (x_front - CORNER, -half_width + CORNER, 1.5 * np.pi),
    ]:
        angles = start + np.linspace(0.0, 0.5 * np.pi, segments)
        points += [(cx + CORNER * np.cos(a), cy + CORNER * np.sin(a)) for a in angles]
    return np.array(points)


def body() -> trimesh.Trimesh:
    """The body: the rounded footprint from the floor to the roof, its front leaning back above the dashboard."""
    rings = []
    for z, x_front in [(CLEARANCE, 0.0), (1.10, 0.0), (ROOF, -RAKE)]:  # bumper and dash upright, windscreen raked
        outline = rounded_outline(x_front, -LENGTH, WIDTH / 2)
        rings.append(np.column_stack([outline, np.full(len(outline), z)]))
    return trimesh.convex.convex_hull(np.vstack(rings))


def box(size, centre) -> trimesh.Trimesh:
    return trimesh.creation.box(extents=size, transform=trimesh.transformations.translation_matrix(centre))


def wheels() -> list[trimesh.Trimesh]:
    """Four wheels, cylinders along y standing on the ground, their outer faces just inside the body's sides."""
    return mesh_parts.wheels((FRONT_AXLE, FRONT_AXLE - WHEELBASE), WIDTH / 2 - 0.05 - WHEEL_W / 2, WHEEL_R, WHEEL_W)


def mirrors() -> list[trimesh.Trimesh]:
    """Rabbit-ear mirrors: a thin arm from each top front corner, forward and out, holding a head that hangs down."""
    parts = []
    for side in (1.0, -1.0):
        root = np.array([-RAKE - 0.10, side * (WIDTH / 2 - 0.10), ROOF - 0.10])
        tip = np.array([0.45, side * (WIDTH / 2 + 0.15), ROOF - 0.30])
        parts.append(trimesh.creation.cylinder(radius=0.025, segment=[root, tip], sections=8))
        parts.append(box([0.10, 0.25, 0.40], tip + [0.0, 0.0, -0.18]))  # head: 0.25 wide, 0.1 thick, 0.4 tall
    return parts


def raw_bus() -> trimesh.Trimesh:
    """The bus's parts, concatenated without welding."""
    hvac = box([2.5, 1.6, HEIGHT - ROOF], [-4.5, 0.0, (ROOF + HEIGHT) / 2])  # over the middle of the front half
    return trimesh.util.concatenate([body(), hvac, *wheels(), *mirrors()])


if __name__ == "__main__":
    path = HERE / "raw_bus.obj"
    bus = raw_bus()
    bus.export(path)
    print(f"wrote {path}: {len(bus.faces)} faces, bounds {np.round(bus.bounds, 2).tolist()}")
