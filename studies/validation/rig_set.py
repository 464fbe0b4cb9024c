"""The validation study's test rigs: a fractional factorial on three vehicles, plus designs, copies and hand rigs.

Run ``python studies/validation/rig_set.py`` to (re)write ``studies/validation/rigs/`` (one rig file per test
rig, benchmark JSON, positions from the vehicle centre) and ``rigs/index.csv`` (name, vehicle, kind, factor
levels). The files are committed with the pre-registration; the script is how they were made.

**The factorial** (16 rigs per vehicle, the same 16 level combinations on the firetruck, the hgv and the tt):
an orthogonal array OA(16, 4^5) built over GF(4) (columns a, b, a+b, a+2b, a+3b of every (a, b)), with the
three-level factors read from four levels by doubling their middle level (0 1 2 1):

- height offset dh from the matched R1 camera: 0, +0.3, +0.6, +1.2 m;
- pitch: 0, -5, -10, -20 deg (down);
- FOV of every camera: 65, 90, 120 deg (90 twice);
- camera count: 6 (R1-c6's yaws), 8 (R1's yaws), 12 (every 30 deg from straight ahead) (8 twice);
- plan offset: 0, 1, 2.5 m along the body's outline (1 twice).

Each camera k has the yaw of its layout; its matched R1 camera is the R1 camera nearest in yaw (the first on
a tie). It sits at height z = z_R1 + dh on the body's outline at that height (the mesh sliced at z, grown by
5 cm so the lens sits just outside the skin), where the horizontal line from the footprint centre in the
camera's yaw leaves the outline (where the body at that height lies to one side of the line, its point
farthest in the camera's direction); the plan offset then moves it that far along the outline, towards the rear
on its own side (a camera on the centreline moves to the left). Where the body ends below z (the tt's roof
at 1.39 m), the camera stands on a mast over the outline 5 cm below the body's top. Roll is 0. These rigs
probe the detector (height, pitch, lens, count, plan position) and are not meant to pass ``rigopt check``.

**The other rigs**: the committed designs from R1 (``measurements/rigs/``: firetruck with and without the
regulation fields, hgv; the tt design from ``studies/designs/results/tt_from_R1``), the naive and the
height-matched transfers of R1 to each vehicle (``rigopt.validation.designs.comparison_rigs``, the naive one
refined under the joint calibration), and the benchmark's hand-designed rigs of each vehicle (R6; R9; R4, R5,
R8).
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import shapely
import trimesh
from shapely.geometry import LineString, Point
from shapely.ops import unary_union

from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.rig.library import load_rig
from rigopt.rig.model import Camera, Rig
from rigopt.rig.pccr_format import write_rig
from rigopt.vehicle.library import load_vehicle

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
OUT = HERE / "rigs"
sys.path.insert(0, str(HERE.parent))  # studies/: the studies' shared code (studylib)
from studylib.tables import write_rig_index  # noqa: E402

VEHICLES = ("firetruck", "hgv", "tt")
HEIGHT_OFFSETS = (0.0, 0.3, 0.6, 1.2)  # m
PITCHES = (0.0, -5.0, -10.0, -20.0)  # deg, negative: down
FOVS = (65.0, 90.0, 120.0, 90.0)  # deg; the middle level doubled
COUNTS = (6, 8, 12, 8)
PLAN_OFFSETS = (0.0, 1.0, 2.5, 1.0)  # m along the outline
SKIN = 0.05  # m the lens sits outside the body
MAST_BELOW_TOP = 0.05  # m below the body's top where a mast stands

#: GF(4) multiplication (elements 0, 1, a = 2, a + 1 = 3); addition is XOR.
GF4_MULTIPLY = np.array([[0, 0, 0, 0], [0, 1, 2, 3], [0, 2, 3, 1], [0, 3, 1, 2]])


def orthogonal_array() -> np.ndarray:
    """OA(16, 4^5): (16, 5) int levels in 0..3, every pair of columns taking each of the 16 level pairs once."""
    rows = []
    for a in range(4):
        for b in range(4):
            rows.append([a, b, a ^ b, a ^ GF4_MULTIPLY[2, b], a ^ GF4_MULTIPLY[3, b]])
    return np.array(rows)


def layout_yaws(count: int) -> np.ndarray:
    """(count,) yaws (deg) of a layout: R1-c6's, R1's, or every 30 deg."""
    if count == 12:
        return np.arange(12) * 30.0
    rig = load_rig({6: "R1-c6", 8: "R1"}[count])
    return np.array([np.degrees(np.arctan2(c.forward[1], c.forward[0])) for c in rig.cameras])


def matched_heights(yaws_deg: np.ndarray, reference: Rig) -> np.ndarray:
    """(N,) height (m) of the reference camera nearest in yaw to each yaw (the first on a tie)."""
    ref_yaws = np.array([np.arctan2(c.forward[1], c.forward[0]) for c in reference.cameras])
    gaps = np.abs(np.angle(np.exp(1j * (np.radians(yaws_deg)[:, None] - ref_yaws[None, :]))))
    return reference.positions[np.argmin(gaps, axis=1), 2]


class Outline:
    """The body's outline at heights z, grown by SKIN; sliced once per height."""

    def __init__(self, mesh: trimesh.Trimesh):
        self.mesh = mesh
        self.top = float(mesh.bounds[1, 2])
        self.centre = mesh.bounds[:, :2].mean(axis=0)
        self._cache: dict[float, shapely.Geometry] = {}

    def at(self, z: float):
        z = round(min(z, self.top - MAST_BELOW_TOP), 6)
        if z not in self._cache:
            to_plane = np.eye(4)
            to_plane[2, 3] = -z
            section, _ = self.mesh.section(plane_origin=[0, 0, z], plane_normal=[0, 0, 1]).to_2D(to_2D=to_plane)
            self._cache[z] = unary_union(section.polygons_full).buffer(SKIN)
        return self._cache[z]

    def mount(self, yaw_deg: float, z: float, plan_offset: float) -> np.ndarray:
        """(2,) plan position: where the line from the centre at ``yaw_deg`` leaves the outline at ``z``, moved
        ``plan_offset`` m along it towards the rear (on the centreline: to the left)."""
        shape = self.at(z)
        direction = np.array([np.cos(np.radians(yaw_deg)), np.sin(np.radians(yaw_deg))])
        ray = LineString([self.centre, self.centre + 60.0 * direction])
        crossing = ray.intersection(shape.boundary)
        points = shapely.get_coordinates(crossing)
        if len(points) == 0:  # the body at this height lies to one side of the line: its extreme point that way
            points = shapely.get_coordinates(shape.boundary)
        exit_point = points[np.argmax((points - self.centre) @ direction)]
        parts = getattr(shape, "geoms", [shape])
        ring = min(parts, key=lambda part: part.exterior.distance(Point(exit_point))).exterior
        if plan_offset == 0:
            return exit_point
        s0 = ring.project(Point(exit_point))
        options = [np.array(ring.interpolate((s0 + sign * plan_offset) % ring.length).coords[0]) for sign in (1, -1)]
        if abs(options[0][0] - options[1][0]) > 1e-6:
            return min(options, key=lambda p: p[0])
        return max(options, key=lambda p: p[1])


def factorial_rig(vehicle_name: str, outline: Outline, reference: Rig, levels) -> tuple[Rig, dict]:
    """The test rig of one row of the array on one vehicle, and its factor values."""
    h, p, f, n, d = levels
    values = {"height_offset_m": HEIGHT_OFFSETS[h], "pitch_deg": PITCHES[p], "fov_deg": FOVS[f],
              "cameras": COUNTS[n], "plan_offset_m": PLAN_OFFSETS[d]}
    yaws = layout_yaws(values["cameras"])
    heights = matched_heights(yaws, reference) + values["height_offset_m"]
    cameras = []
    for k, (yaw, z) in enumerate(zip(yaws, heights)):
        xy = outline.mount(yaw, z, values["plan_offset_m"])
        rotation = rotation_from_yaw_pitch_roll(np.radians(yaw), np.radians(values["pitch_deg"]), 0.0)
        cameras.append(Camera.pinhole(f"CAM_{k:02d}_YAW_{int(round(yaw)) % 360:03d}", np.array([xy[0], xy[1], z]),
                                      rotation, values["fov_deg"]))
    name = (f"{vehicle_name}_h{values['height_offset_m']:g}_p{abs(values['pitch_deg']):g}_f{values['fov_deg']:g}"
            f"_n{values['cameras']}_d{values['plan_offset_m']:g}")
    return Rig(name, load_vehicle(vehicle_name).blueprint, tuple(cameras)), values


def other_rigs() -> list[tuple[str, str, Rig]]:
    """(vehicle, kind, rig) of the designs, the naive and height-matched transfers and the hand rigs."""
    from rigopt.validation.designs import comparison_rigs
    from rigopt.metrics.calibration import load_weights

    joint = load_weights("joint")
    reference = load_rig("R1")
    designs = {"firetruck": [ROOT / "measurements/rigs/firetruck_from_R1.json",
                             ROOT / "measurements/rigs/firetruck_from_R1_no_fields.json"],
               "hgv": [ROOT / "measurements/rigs/hgv_from_R1.json"],
               "tt": [ROOT / "studies/designs/results/tt_from_R1/rig.json"]}
    out = []
    for vehicle, paths in designs.items():
        for path in paths:
            rig = load_rig(path)
            name = path.parent.name if path.name == "rig.json" else path.stem
            out.append((vehicle, "design", replace(rig, name=name)))
        for role, rig in comparison_rigs(load_rig(paths[0]), reference, joint)[1:]:
            kind = {"hand-designed": "hand", "naive transfer": "naive", "height-matched transfer": "height_matched"}[role]
            out.append((vehicle, kind, rig))
    return out


def main() -> int:
    reference = load_rig("R1")
    OUT.mkdir(exist_ok=True)
    rows = []
    array = orthogonal_array()
    for vehicle_name in VEHICLES:
        outline = Outline(load_vehicle(vehicle_name).mesh)
        for levels in array:
            rig, values = factorial_rig(vehicle_name, outline, reference, levels)
            write_rig(rig, OUT / f"{rig.name}.json")
            rows.append({"rig": rig.name, "vehicle": vehicle_name, "kind": "factorial", **values})
    for vehicle_name, kind, rig in other_rigs():
        write_rig(rig, OUT / f"{rig.name}.json")
        rows.append({"rig": rig.name, "vehicle": vehicle_name, "kind": kind, "cameras": len(rig)})
    columns = ["rig", "vehicle", "kind", "height_offset_m", "pitch_deg", "fov_deg", "cameras", "plan_offset_m"]
    write_rig_index(OUT / "index.csv", columns, rows)
    print(f"{len(rows)} test rigs in {OUT.relative_to(ROOT)} ({sum(r['kind'] == 'factorial' for r in rows)} factorial)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
