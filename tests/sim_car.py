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


# --- more raw vehicles: a body that hugs its tyres, a truck with dual rear wheels, a truck of thin open panels ------


def _wheel(x: float, y: float, radius: float, width: float, sections: int = 32) -> trimesh.Trimesh:
    """A closed tyre standing on z = 0, its axis along y, centred at (x, y)."""
    wheel = trimesh.creation.cylinder(radius, width, sections=sections)
    wheel.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
    wheel.apply_translation([x, y, radius])
    return wheel


def _box(low, high) -> trimesh.Trimesh:
    low, high = np.asarray(low, float), np.asarray(high, float)
    box = trimesh.creation.box(high - low)
    box.apply_translation((low + high) / 2)
    return box


#: The hugging car (ISO, m): tyres of radius 0.31 m, width 0.2 m at x = 1.4 and -1.35, centre planes |y| = 0.76,
#: under a body x in [-2.25, 2.25], |y| <= 0.88, z in [0.14, 1.0] whose arches (radius 0.34 m) clear them by 3 cm.
HUG_AXLES, HUG_RADIUS, HUG_WIDTH, HUG_TRACK = (1.4, -1.35), 0.31, 0.2, 1.52


def hugging_car_parts() -> dict[str, trimesh.Trimesh]:
    """A hatchback whose body hugs its tyres: a closed body with wheel arches cut 3 cm around the tyres, its
    sills 14 cm above the ground, a cabin, four closed tyres (parts overlap, nothing is joined)."""
    body = _box([-2.25, -0.88, 0.14], [2.25, 0.88, 1.0])
    for x in HUG_AXLES:
        arch = trimesh.creation.cylinder(HUG_RADIUS + 0.03, 2.0, sections=48)
        arch.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
        arch.apply_translation([x, 0, HUG_RADIUS])
        body = trimesh.boolean.difference([body, arch], engine="manifold")
    parts = {"body": body, "cabin": _box([-1.9, -0.8, 0.95], [0.7, 0.8, 1.48])}
    for x in HUG_AXLES:
        for y in (HUG_TRACK / 2, -HUG_TRACK / 2):
            parts[f"tyre_{x:+.2f}_{y:+.2f}"] = _wheel(x, y, HUG_RADIUS, HUG_WIDTH)
    return parts


#: The truck with dual rear wheels (ISO, m): front tyres radius 0.5, width 0.3 at x = 2.6, centre planes
#: |y| = 1.0; rear twin tyres of the same radius, each 0.27 wide with a 4 cm gap, at x = -1.9, the pair's
#: outer faces at |y| = 1.24 (pair width 0.58, centre planes |y| = 0.95).
DUAL_AXLES, DUAL_RADIUS = (2.6, -1.9), 0.5
DUAL_FRONT_WIDTH, DUAL_FRONT_TRACK = 0.3, 2.0
DUAL_REAR_WIDTH, DUAL_REAR_TRACK = 0.58, 1.9


def dual_truck_parts() -> dict[str, trimesh.Trimesh]:
    """A rigid truck: cab (lower, at the front), box body, a chassis, front single and rear twin tyres."""
    parts = {"cab": _box([2.0, -1.2, 0.75], [3.7, 1.2, 3.0]), "box": _box([-3.6, -1.25, 1.05], [1.9, 1.25, 3.6]),
             "chassis": _box([-3.4, -0.5, 0.6], [3.5, 0.5, 1.05])}
    for y in (1, -1):
        parts[f"front_{y:+d}"] = _wheel(2.6, y * 1.0, DUAL_RADIUS, DUAL_FRONT_WIDTH)
        for k, centre in enumerate((1.105, 0.795)):
            parts[f"rear_{y:+d}_{k}"] = _wheel(-1.9, y * centre, DUAL_RADIUS, 0.27)
    return parts


#: The thin open fire truck (ISO, m): 8.4 x 2.5 x 3.42 (ladder on top); wheels radius 0.55, width 0.35 at
#: x = 2.6 and -2.5, centre planes |y| = 1.0.
THIN_AXLES, THIN_RADIUS, THIN_WIDTH, THIN_TRACK = (2.6, -2.5), 0.55, 0.35, 2.0
PANEL = 0.025


def thin_fire_truck_parts() -> dict[str, trimesh.Trimesh]:
    """A fire truck as a simulator exports it: every wall a separate panel 2.5 cm thick (closed slabs that do
    not join: a few cm gaps at the corners), no floor, an open windshield (one single-sided sheet), a ladder
    of 3 cm rails and 2 cm rungs on posts above the body's roof, a 4 cm light bar on posts above the cab, four
    tyres."""
    t = PANEL
    parts = {
        # cab: x in [2.3, 4.2], lower than the body
        "cab_left": _box([2.3, 1.25 - t, 0.7], [3.7, 1.25, 2.9]),
        "cab_right": _box([2.3, -1.25, 0.7], [3.7, -1.25 + t, 2.9]),
        "cab_left_low": _box([3.72, 1.25 - t, 0.7], [4.15, 1.25, 1.8]),
        "cab_right_low": _box([3.72, -1.25, 0.7], [4.15, -1.25 + t, 1.8]),
        "cab_roof": _box([2.3, -1.22, 2.9], [3.7, 1.22, 2.9 + t]),
        "cab_grille": _box([4.2 - t, -1.2, 0.7], [4.2, 1.2, 1.75]),
        "cab_back": _box([2.3, -1.2, 0.9], [2.3 + t, 1.2, 2.88]),
        # body: x in [-4.2, 2.25]
        "body_left": _box([-4.2, 1.25 - t, 0.9], [2.25, 1.25, 3.2]),
        "body_right": _box([-4.2, -1.25, 0.9], [2.25, -1.25 + t, 3.2]),
        "body_roof": _box([-4.2, -1.22, 3.2], [2.25, 1.22, 3.2 + t]),
        "body_rear": _box([-4.2, -1.2, 0.9], [-4.2 + t, 1.2, 3.18]),
        "body_front": _box([2.25 - t, -1.2, 0.9], [2.25, 1.2, 3.18]),
        "light_bar": _box([3.38, -0.8, 2.99], [3.42, 0.8, 3.03]),  # a 4 x 4 cm LED bar on two posts
        "light_bar_post_left": _box([3.39, 0.49, 2.9 + t], [3.41, 0.51, 2.99]),
        "light_bar_post_right": _box([3.39, -0.51, 2.9 + t], [3.41, -0.49, 2.99]),
    }
    windshield = trimesh.Trimesh([[4.2, -1.2, 1.8], [4.2, 1.2, 1.8], [3.7, 1.2, 2.85], [3.7, -1.2, 2.85]],
                                 [[0, 1, 2], [0, 2, 3]], process=False)
    parts["windshield"] = windshield.subdivide().subdivide()
    for y in (0.45, -0.45):  # ladder rails on posts
        parts[f"rail_{y:+.2f}"] = _box([-3.9, y - 0.015, 3.35], [1.9, y + 0.015, 3.38])
        for x in (-3.7, -1.0, 1.7):
            parts[f"post_{x:+.1f}_{y:+.2f}"] = _box([x - 0.015, y - 0.015, 3.2 + t], [x + 0.015, y + 0.015, 3.35])
    for k, x in enumerate(np.arange(-3.8, 1.9, 0.3)):
        parts[f"rung_{k}"] = _box([x - 0.01, -0.45, 3.355], [x + 0.01, 0.45, 3.375])
    for x in THIN_AXLES:
        for y in (THIN_TRACK / 2, -THIN_TRACK / 2):
            parts[f"tyre_{x:+.1f}_{y:+.1f}"] = _wheel(x, y, THIN_RADIUS, THIN_WIDTH)
    return parts


def joined(parts: dict[str, trimesh.Trimesh]) -> trimesh.Trimesh:
    """The parts in one mesh, not merged (still open and overlapping)."""
    return trimesh.util.concatenate(list(parts.values()))
