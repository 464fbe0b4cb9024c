"""The second predictor study's test rigs: none of them measured before, on a vehicle no study has used.

    python studies/predictor_v2/rig_set.py

writes ``rigs/<rig>.json`` (benchmark JSON, perception cameras only) and ``rigs/index.csv`` (rig, vehicle, kind,
source and factor values), committed with ``preregistration.md``. The user-mesh vehicle ``van``
(``examples/raw_van.obj``) must have been added first (``preregistration.md`` says how).

- On the van, what the designer proposes from R1 and variations of R1 (the first predictor study's recipe,
  ``studies/predictor/rig_set.py``, with the van's own Sobol seed VAN_SEED): designs under five settings, R1's
  naive and height-matched copies, the searched copy, single-camera swaps, VAN_VARIATIONS variations.
- Variations of the benchmark's rigs (R1 to R9 and R1's variants are all known; their variations are not): each
  of BENCHMARK_SOURCES on its own vehicle, BENCHMARK_VARIATIONS times, every camera changed alike by factors drawn
  from a scrambled Sobol sequence (BENCHMARK_SEED): height offset, pitch, roll and yaw turns, and a FOV scale.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
OUT = HERE / "rigs"
sys.path.insert(0, str(HERE.parent))  # studies/: the studies' shared code (studylib)
from studylib.tables import write_rig_index  # noqa: E402

# the first predictor study's rig recipe (its module shares this one's name: loaded under another)
_spec = importlib.util.spec_from_file_location("predictor_rig_set", HERE.parent / "predictor" / "rig_set.py")
predictor_rig_set = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(predictor_rig_set)

VAN, VAN_SEED, VAN_VARIATIONS = "van", 100, 12
BENCHMARK_SOURCES = ("R1", "R2", "R3", "R4", "R5", "R6", "R7", "R8", "R9")
BENCHMARK_SEED, BENCHMARK_VARIATIONS = 101, 3
#: Factor ranges (low, high) of the benchmark rigs' variations.
BENCHMARK_FACTORS = {"height_offset_m": (-0.3, 0.6), "pitch_deg": (-12.0, 6.0), "roll_deg": (-5.0, 5.0),
                     "yaw_turn_deg": (-20.0, 20.0), "fov_scale": (0.8, 1.4)}
WIDEST_FOV = 150.0  # deg: a scaled FOV is capped here
COLUMNS = ["rig", "vehicle", "kind", "setting", "source", "height_offset_m", "pitch_deg", "roll_deg",
           "yaw_turn_deg", "fov_deg", "fov_scale", "cameras", "plan_offset_m"]


def benchmark_draws() -> list[dict]:
    """len(BENCHMARK_SOURCES) * BENCHMARK_VARIATIONS factor settings, in source order."""
    from scipy.stats import qmc

    n = len(BENCHMARK_SOURCES) * BENCHMARK_VARIATIONS
    points = qmc.Sobol(len(BENCHMARK_FACTORS), scramble=True, seed=BENCHMARK_SEED).random_base2(int(np.ceil(np.log2(n))))
    return [{name: round(low + u * (high - low), 3) for u, (name, (low, high)) in zip(row, BENCHMARK_FACTORS.items())}
            for row in points[:n]]


def varied(rig, values: dict, name: str):
    """``rig`` with every camera raised by the height offset, its yaw, pitch and roll angles (ISO 8855) shifted by
    the turns and its FOV scaled (capped at WIDEST_FOV)."""
    from rigopt.geometry import rotation_from_yaw_pitch_roll, yaw_pitch_roll_from_rotation
    from rigopt.rig.model import Camera

    cameras = []
    for camera in rig.cameras:
        yaw, pitch, roll = yaw_pitch_roll_from_rotation(camera.rotation[None])
        rotation = rotation_from_yaw_pitch_roll(yaw[0] + np.radians(values["yaw_turn_deg"]),
                                                pitch[0] + np.radians(values["pitch_deg"]),
                                                roll[0] + np.radians(values["roll_deg"]))
        position = camera.position + [0.0, 0.0, values["height_offset_m"]]
        fov = min(camera.fov * values["fov_scale"], WIDEST_FOV)
        cameras.append(Camera.pinhole(camera.id, position, rotation, fov, camera.image_size))
    return dataclasses.replace(rig, name=name, cameras=tuple(cameras))


def benchmark_rigs() -> list[tuple[dict, object]]:
    """(index row, rig) of the benchmark rigs' variations (perception cameras; every source is a pinhole rig)."""
    from rigopt.rig.library import load_rig

    draws = iter(benchmark_draws())
    out = []
    for source in BENCHMARK_SOURCES:
        rig = load_rig(source).perception()
        for k in range(BENCHMARK_VARIATIONS):
            values = next(draws)
            name = f"{source}_variation_{k}"
            out.append(({"rig": name, "vehicle": rig.vehicle, "kind": "benchmark_variation", "source": source,
                         "cameras": len(rig), **values}, varied(rig, values, name)))
    return out


def main() -> int:
    from rigopt.rig.pccr_format import write_rig

    OUT.mkdir(exist_ok=True)
    with tempfile.TemporaryDirectory() as scratch:
        made = predictor_rig_set.vehicle_rigs(VAN, Path(scratch), seed=VAN_SEED, variations=VAN_VARIATIONS) + benchmark_rigs()
    for row, rig in made:
        write_rig(rig, OUT / f"{rig.name}.json")
    write_rig_index(OUT / "index.csv", COLUMNS, [row for row, _ in made])
    kinds = [row["kind"] for row, _ in made]
    print(f"{len(made)} rigs: " + ", ".join(f"{k} {kinds.count(k)}" for k in dict.fromkeys(kinds)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
