"""The city bus's four replication rigs remade by today's designer, which infers a mirror zone on user meshes.

    python studies/replication/mirrors/make_rigs.py

adds ``examples/raw_bus.obj`` as ``citybus`` (``--forward +x --allow-size``, as the replication's bus) to a
RIGOPT_HOME of its own, then writes into ``rigs/`` the default design's perception cameras
(``citybus_from_R1_default``) and R1's naive, height-matched and searched copies, made as
``studies/predictor/rig_set.py`` made them (the same functions). No rig is measured here.
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]


def _predictor_rig_set():
    """studies/predictor/rig_set.py, loaded under a name of its own (it imports the validation study's rig_set)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("predictor_rig_set", ROOT / "studies" / "predictor" / "rig_set.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


VEHICLE = "citybus"


@contextmanager
def bus_home():
    """A temporary RIGOPT_HOME (set in the environment while inside) holding the city bus, added from its example
    mesh as the replication's bus was; yields the folder."""
    from rigopt.vehicle.user import add_user_vehicle

    before = os.environ.get("RIGOPT_HOME")
    with tempfile.TemporaryDirectory() as home:
        os.environ["RIGOPT_HOME"] = home
        try:
            added = add_user_vehicle(VEHICLE, ROOT / "examples" / "raw_bus.obj", forward="+x", allow_size=True)
            print(f"added {VEHICLE} to {home}; mirror zone: {added.mirror}", flush=True)
            yield Path(home)
        finally:
            if before is None:
                os.environ.pop("RIGOPT_HOME", None)
            else:
                os.environ["RIGOPT_HOME"] = before


def main() -> int:
    with bus_home() as home:
        from rigopt.metrics.calibration import load_weights
        from rigopt.rig.library import load_rig
        from rigopt.rig.pccr_format import write_rig
        from rigopt.validation.designs import comparison_rigs, load_design
        from rigopt.vehicle.library import load_vehicle

        out = home / "design"
        rigopt = Path(sys.executable).parent / "rigopt"
        subprocess.run([str(rigopt), "design", "--vehicle", VEHICLE, "--ref", "R1", "--out", str(out), "--json"],
                       check=True, capture_output=True, text=True)
        design = dataclasses.replace(load_design(out / "report.json").perception(), name=f"{VEHICLE}_from_R1_default")
        copies = dict(comparison_rigs(design, load_rig("R1"), load_weights("joint"))[1:])
        naive = copies["naive transfer"]
        matched = copies["height-matched transfer"]
        naive = dataclasses.replace(naive, name=f"{VEHICLE}_{naive.name}")
        matched = dataclasses.replace(matched, name=f"{VEHICLE}_{matched.name}")
        rigs = [design, naive, matched, _predictor_rig_set().searched_copy(matched, load_vehicle(VEHICLE))]
        (HERE / "rigs").mkdir(exist_ok=True)
        for rig in rigs:
            write_rig(rig, HERE / "rigs" / f"{rig.name}.json")
            print(f"wrote rigs/{rig.name}.json ({len(rig)} cameras)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
