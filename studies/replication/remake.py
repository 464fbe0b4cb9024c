"""What the replication and its amendments share: the test's constants, the rigs remade by today's designer, and a
remade vehicle's cell measured beside the design measured before it (a library: no main).

Amendments 2 (``mirrors/``) and 3 (``windscreen/``) remake the replication rigs a designer change moved
(:func:`vehicle_rigs`, the city bus in a RIGOPT_HOME of its own: :func:`bus_home`), measure them
(:func:`measure_remade`) and recompute the five-vehicle statistics with the new cells (:func:`with_new_cells`).
"""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT / "studies"))  # studylib
from studylib.paired import vehicle_draws, vehicle_mean  # noqa: E402

#: The replication's test (preregistration.md): its vehicles, scene sets, yardsticks and resampling.
VEHICLES = ("tt", "renault_zoe", "ford_fusion_hybrid", "chrysler_pacifica_hybrid", "citybus")
PROTOCOLS = ("quick", "quick-s1")
YARDSTICKS = {"naive copy": "{v}_naive_{v}_from_R1", "height-matched copy": "{v}_height_matched_{v}_from_R1",
              "searched copy": "{v}_height_matched_{v}_from_R1_searched"}
RESAMPLES, SEED, LEVEL = 2000, 0, 1 - 0.05 / len(YARDSTICKS)
#: The replication's own cells (``<vehicle>_<protocol>.json``).
REPLICATION_RESULTS = HERE / "results"
BUS = "citybus"


def predictor_rig_set():
    """studies/predictor/rig_set.py, loaded under a name of its own (it imports the validation study's rig_set)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("predictor_rig_set", ROOT / "studies" / "predictor" / "rig_set.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@contextmanager
def bus_home():
    """A temporary RIGOPT_HOME (set in the environment while inside) holding the city bus, added from its example
    mesh as the replication's bus was (without it the renderer draws no ego body, and only warns); yields the
    folder."""
    from rigopt.vehicle.user import add_user_vehicle

    before = os.environ.get("RIGOPT_HOME")
    with tempfile.TemporaryDirectory() as home:
        os.environ["RIGOPT_HOME"] = home
        try:
            added = add_user_vehicle(BUS, ROOT / "examples" / "raw_bus.obj", forward="+x", allow_size=True)
            print(f"added {BUS} to {home}; mirror zone: {added.mirror}", flush=True)
            yield Path(home)
        finally:
            if before is None:
                os.environ.pop("RIGOPT_HOME", None)
            else:
                os.environ["RIGOPT_HOME"] = before


def vehicle_rigs(vehicle: str, work: Path) -> list:
    """The default design from R1 (its perception cameras, ``<V>_from_R1_default``) and R1's naive, height-matched
    and searched copies on ``vehicle``, made as ``studies/predictor/rig_set.py`` made them (``work``: scratch)."""
    from rigopt.metrics.calibration import load_weights
    from rigopt.rig.library import load_rig
    from rigopt.validation.designs import comparison_rigs, load_design
    from rigopt.vehicle.library import load_vehicle

    out = Path(work) / vehicle
    rigopt = Path(sys.executable).parent / "rigopt"
    subprocess.run([str(rigopt), "design", "--vehicle", vehicle, "--ref", "R1", "--out", str(out), "--json"],
                   check=True, capture_output=True, text=True)
    design = dataclasses.replace(load_design(out / "report.json").perception(), name=f"{vehicle}_from_R1_default")
    copies = dict(comparison_rigs(design, load_rig("R1"), load_weights("joint"))[1:])
    naive, matched = copies["naive transfer"], copies["height-matched transfer"]
    naive = dataclasses.replace(naive, name=f"{vehicle}_{naive.name}")
    matched = dataclasses.replace(matched, name=f"{vehicle}_{matched.name}")
    return [design, naive, matched, predictor_rig_set().searched_copy(matched, load_vehicle(vehicle))]


def write_remade(vehicles, rigs_folder: Path) -> None:
    """:func:`vehicle_rigs` of each of ``vehicles`` written into ``rigs_folder`` (the bus in :func:`bus_home`)."""
    from rigopt.rig.pccr_format import write_rig

    rigs_folder.mkdir(exist_ok=True)
    with bus_home(), tempfile.TemporaryDirectory() as work:
        for vehicle in vehicles:
            for rig in vehicle_rigs(vehicle, Path(work)):
                write_rig(rig, rigs_folder / f"{rig.name}.json")
                print(f"wrote rigs/{rig.name}.json ({len(rig)} cameras)", flush=True)


def measure_remade(vehicle: str, protocol_name: str, rigs_folder: Path, before: Path, before_name: str,
                   before_key: str, cache, workers: int, progress) -> dict:
    """One vehicle's cell on one scene set: its four remade rigs in ``rigs_folder`` and the design measured before
    (the rig file ``before``, renamed ``before_name``), measured with the shipped R1 models inside
    :func:`bus_home`; the new design minus each yardstick (``design_minus``) and minus the one before
    (``before_key``), with paired scene intervals."""
    from rigopt.rig.library import load_rig
    from rigopt.validation.detectors.measuring import protocol_named
    from rigopt.validation.detectors.shipped import measure, paired_differences, shipped_detector, without_resamples

    names = [f"{vehicle}_from_R1_default", *(pattern.format(v=vehicle) for pattern in YARDSTICKS.values())]
    rigs = [load_rig(rigs_folder / f"{name}.json") for name in names]
    rigs.append(dataclasses.replace(load_rig(before), name=before_name))
    with bus_home():
        entries = measure(rigs, shipped_detector("lss", "R1"), cache, "cpu", workers, progress,
                          protocol_named(protocol_name))
    return {"vehicle": vehicle, "protocol": protocol_name, "rigs": [without_resamples(e) for e in entries],
            "design_minus": {role: paired_differences(entries[0], entry) for role, entry in zip(YARDSTICKS, entries[1:4])},
            before_key: paired_differences(entries[0], entries[4])}


def with_new_cells(found: dict) -> dict:
    """The replication's five-vehicle statistics per scene set, each yardstick's mean over vehicles with its
    intervals resampling vehicles, the cells of ``found`` {(vehicle, protocol): cell} in place of the
    replication's own."""
    draws = vehicle_draws(len(VEHICLES), RESAMPLES, SEED)
    out = {}
    for p in PROTOCOLS:
        cells = [found.get((v, p)) or json.loads((REPLICATION_RESULTS / f"{v}_{p}.json").read_text()) for v in VEHICLES]
        out[p] = {role: vehicle_mean([c["design_minus"][role] for c in cells], VEHICLES, draws, LEVEL)
                  for role in YARDSTICKS}
    return out
