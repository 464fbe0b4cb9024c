"""A raw simulator-like car mesh written by the tests: separate parts (body without a floor, cabin, four
wheels), optionally in centimetres and turned, as an OBJ of ``o`` groups or any trimesh format.

ISO frame before turning (metres): body x in [-2.3, 2.3], |y| <= 0.9, z in [0.3, 1.0], open at the bottom;
cabin x in [-2.0, 0.6], |y| <= 0.8, z in [0.95, 1.5] (so the hood is at the front, +x); wheels of radius
0.33 m and width 0.22 m at x = +-1.45, centre planes |y| = 0.78 (track 1.56 m), standing on z = 0.
"""

from __future__ import annotations

import numpy as np
import trimesh

AXLES = (1.45, -1.45)
RADIUS, WIDTH, TRACK = 0.33, 0.22, 1.56
LENGTH, BODY_WIDTH, HEIGHT = 4.6, 1.8, 1.5


def sim_car_parts() -> dict[str, trimesh.Trimesh]:
    """The parts in the ISO frame (metres), by name."""
    body = trimesh.creation.box([4.6, 1.8, 0.7])
    body.apply_translation([0.0, 0.0, 0.65])
    body = body.subdivide().subdivide()
    body = trimesh.Trimesh(body.vertices, body.faces[body.face_normals[:, 2] > -0.5], process=False)  # no floor
    cabin = trimesh.creation.box([2.6, 1.6, 0.55])
    cabin.apply_translation([-0.7, 0.0, 1.225])
    parts = {"body": body, "cabin": cabin}
    for x in AXLES:
        for side, y in (("left", TRACK / 2), ("right", -TRACK / 2)):
            wheel = trimesh.creation.cylinder(RADIUS, WIDTH, sections=24)
            wheel.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
            wheel.apply_translation([x, y, RADIUS])
            parts[f"wheel_{'front' if x > 0 else 'rear'}_{side}"] = wheel
    return parts


def to_file_frame(mesh: trimesh.Trimesh, forward: str = "+x", up: str = "+z", scale: float = 1.0) -> trimesh.Trimesh:
    """The ISO-frame mesh written in a file frame whose ``forward`` and ``up`` axes are given, in units of
    ``1 / scale`` m (scale 0.01: centimetres)."""
    from rigopt.vehicle.orientation import frame_rotation

    rotation = frame_rotation(forward, up)  # file -> ISO; its transpose takes ISO back to the file
    return trimesh.Trimesh(mesh.vertices @ rotation / scale, mesh.faces, process=False)


def write_obj(path, forward: str = "+x", up: str = "+z", scale: float = 1.0, parts=None) -> None:
    """The parts as one OBJ file, one ``o`` group each, in the given file frame and unit."""
    lines, offset = ["# raw simulator export"], 1
    for name, part in (parts or sim_car_parts()).items():
        part = to_file_frame(part, forward, up, scale)
        lines.append(f"o {name}")
        lines += [f"v {x:.5f} {y:.5f} {z:.5f}" for x, y, z in part.vertices]
        lines += [f"f {a + offset} {b + offset} {c + offset}" for a, b, c in part.faces]
        offset += len(part.vertices)
    path.write_text("\n".join(lines) + "\n")


def sim_car_mesh(forward: str = "+x", up: str = "+z", scale: float = 1.0) -> trimesh.Trimesh:
    """All parts in one mesh (not merged: still open and overlapping), in the given file frame and unit."""
    return to_file_frame(trimesh.util.concatenate(list(sim_car_parts().values())), forward, up, scale)
