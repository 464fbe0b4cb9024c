"""The replication rigs the windscreen rule changed, remade by today's designer.

    python studies/replication/windscreen/make_rigs.py

For the tt, the chrysler_pacifica_hybrid and the city bus (added to a RIGOPT_HOME of its own as in amendment 2)
writes into ``rigs/`` the default design's perception cameras (``<V>_from_R1_default``) and R1's naive,
height-matched and searched copies, made as ``studies/predictor/rig_set.py`` made them. No rig is measured here.
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "mirrors"))
from make_rigs import _predictor_rig_set, bus_home  # noqa: E402  (amendment 2's helpers)

VEHICLES = ("tt", "chrysler_pacifica_hybrid", "citybus")


def vehicle_rigs(vehicle: str, work: Path) -> list:
    """The design from R1 (its perception cameras) and R1's naive, height-matched and searched copies on ``vehicle``."""
    from rigopt.metrics.calibration import load_weights
    from rigopt.rig.library import load_rig
    from rigopt.validation.designs import comparison_rigs, load_design
    from rigopt.vehicle.library import load_vehicle

    out = work / vehicle
    rigopt = Path(sys.executable).parent / "rigopt"
    subprocess.run([str(rigopt), "design", "--vehicle", vehicle, "--ref", "R1", "--out", str(out), "--json"],
                   check=True, capture_output=True, text=True)
    design = dataclasses.replace(load_design(out / "report.json").perception(), name=f"{vehicle}_from_R1_default")
    copies = dict(comparison_rigs(design, load_rig("R1"), load_weights("joint"))[1:])
    naive, matched = copies["naive transfer"], copies["height-matched transfer"]
    naive = dataclasses.replace(naive, name=f"{vehicle}_{naive.name}")
    matched = dataclasses.replace(matched, name=f"{vehicle}_{matched.name}")
    return [design, naive, matched, _predictor_rig_set().searched_copy(matched, load_vehicle(vehicle))]


def main() -> int:
    from rigopt.rig.pccr_format import write_rig

    (HERE / "rigs").mkdir(exist_ok=True)
    with bus_home(), tempfile.TemporaryDirectory() as work:
        for vehicle in VEHICLES:
            for rig in vehicle_rigs(vehicle, Path(work)):
                write_rig(rig, HERE / "rigs" / f"{rig.name}.json")
                print(f"wrote rigs/{rig.name}.json ({len(rig)} cameras)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
