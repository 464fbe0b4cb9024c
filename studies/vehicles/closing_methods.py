"""Which closing method for raw vehicle meshes: closing error and time per method, on the tests' raw vehicles.

Meshes (tests/sim_car.py, ISO frame, metres): the simulator car (body without a floor, cabin, four wheels as
separate parts), the hugging hatchback and the dual-wheel truck with their floors removed (open, multi-part),
and the fire truck of thin open panels with a ladder of thin bars. Methods (rigopt.vehicle.closing): the first
closing (``smooth``: voxel inside votes, smoothed 0/1 field) at the default pitch (length / 200 in [1, 4] cm)
and at a finer, thin-part pitch of 2 cm; the signed distance closing (``distance``) at both pitches; and
``distance`` with the generalised winding number as its inside test (``winding``, needs ``pip install
libigl``; left out when it is missing). A closing refused (95th percentile over 5 cm) is still measured.

Writes studies/vehicles/results/closing_methods.csv and .md (the markdown table is also printed).
Usage: python studies/vehicles/closing_methods.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import trimesh

from rigopt.vehicle import closing

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies/: the studies' shared code (studylib)
from studylib.tables import markdown, write_csv  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "tests"))  # the raw vehicles are the tests' own
import sim_car  # noqa: E402

FINE_PITCH = 0.02


def without_floor(parts: dict, name: str) -> dict:
    """``parts`` with the downward faces of part ``name`` removed (an open body)."""
    parts = dict(parts)
    part = parts[name].subdivide()
    parts[name] = trimesh.Trimesh(part.vertices, part.faces[part.face_normals[:, 2] > -0.5], process=False)
    return parts


def meshes() -> dict[str, trimesh.Trimesh]:
    return {"sim car (no floor)": sim_car.joined(sim_car.sim_car_parts()),
            "hatchback (no floor)": sim_car.joined(without_floor(sim_car.hugging_car_parts(), "body")),
            "dual-wheel truck (box without floor)": sim_car.joined(without_floor(sim_car.dual_truck_parts(), "box")),
            "fire truck (thin open panels, ladder)": sim_car.joined(sim_car.thin_fire_truck_parts())}


def methods() -> list[tuple[str, str, float | None]]:
    """(label, method, pitch or None for the default)."""
    rows = [("smooth", "smooth", None), ("smooth, 2 cm", "smooth", FINE_PITCH),
            ("distance", "distance", None), ("distance, 2 cm", "distance", FINE_PITCH)]
    try:
        import igl  # noqa: F401
        rows.append(("winding", "winding", None))
    except ImportError:
        print("libigl is not installed: the winding method is left out (pip install libigl)")
    return rows


def measure(mesh: trimesh.Trimesh, method: str, pitch: float | None) -> list:
    """[pitch cm, p95 cm, max cm, buried, thin, faces, seconds] of one closing (refused ones too)."""
    limit = closing.CLOSING_P95_LIMIT
    closing.CLOSING_P95_LIMIT = np.inf  # measure what a refusal would hide
    try:
        start = time.perf_counter()
        closed, report = closing.close_mesh(mesh, method=method, pitch=pitch)
        seconds = time.perf_counter() - start
    finally:
        closing.CLOSING_P95_LIMIT = limit
    return [report.pitch * 100, report.p95_error * 100, report.max_error * 100, report.buried, report.thin,
            len(closed.faces), seconds]


def main() -> None:
    rows = []
    for mesh_name, mesh in meshes().items():
        for label, method, pitch in methods():
            rows.append([mesh_name, label, *measure(mesh, method, pitch)])
            print(rows[-1], flush=True)
    out = HERE / "results"
    out.mkdir(exist_ok=True)
    table = write_csv(out / "closing_methods.csv", ["mesh", "method", "pitch_cm", "p95_cm", "max_cm", "buried",
                                                    "thin", "faces", "seconds"], rows)
    text = markdown(table)
    (out / "closing_methods.md").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
