"""The designer's claim from a second reference (pre-registered in ``preregistration.md``): the default design from
nuScenes' rig against its naive and height-matched copies on five vehicles, measured by the lss model trained on
nuScenes (``detectors/lss-nuscenes``), on its test scenes and on new scenes.

    python studies/second_reference/run.py --make-rigs      # the designs and copies into rigs/ (commit them)
    python studies/second_reference/run.py [--cache DIR] [--workers 2] [--analyse-only]

Each vehicle's three rigs are measured under ``quick`` and ``quick-s1`` as ``rigopt validate`` does (renderings and
scores cached); per vehicle and scene set the paired differences and the predicted drops go to
``results/<vehicle>_<protocol>.json`` as soon as they are measured (a rerun skips those files); the pre-registered
statistics and decision to ``results/results.md`` and ``results/results.json``; the log to ``results/run.log``.
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
RIGS, RESULTS = HERE / "rigs", HERE / "results"
sys.path.insert(0, str(HERE.parent))  # studies/: the studies' shared code (studylib)
from studylib.paired import beaten, cell_rows, run_cells, scene_set_means, summary_rows  # noqa: E402
from studylib.tables import markdown  # noqa: E402

#: The test (preregistration.md). The reference as imported (``rigopt import nuscenes
#: measurements/rigs/real/nuscenes --name nuscenes``): the rig its models were trained on.
REFERENCE = "nuscenes"
REFERENCE_FILE = HERE / "nuscenes.json"
VEHICLES = ("firetruck", "hgv", "tt", "ford_fusion_hybrid", "chrysler_pacifica_hybrid")
PROTOCOLS = ("quick", "quick-s1")
YARDSTICKS = {"naive copy": "naive transfer", "height-matched copy": "height-matched transfer"}
RESAMPLES, SEED, LEVEL = 2000, 0, 1 - 0.05 / len(YARDSTICKS)
#: The own mAP under which the study is inconclusive.
WEAKEST_MODEL = 0.10


def rig_names(vehicle: str) -> list[str]:
    return [f"{vehicle}_from_{REFERENCE}_default", *(f"{vehicle}_{role.split()[0]}_copy_of_{REFERENCE}"
                                                     for role in YARDSTICKS)]


def make_rigs() -> None:
    """Each vehicle's default design from the reference (its perception cameras) and the reference's naive and
    height-matched copies (``designs.comparison_rigs``, as ``validate --compare`` makes them), into rigs/."""
    from rigopt.metrics.calibration import load_weights
    from rigopt.rig.pccr_format import write_rig
    from rigopt.rig.library import load_rig
    from rigopt.validation.designs import comparison_rigs, load_design

    RIGS.mkdir(exist_ok=True)
    reference = load_rig(REFERENCE_FILE)
    rigopt = Path(sys.executable).parent / "rigopt"
    with tempfile.TemporaryDirectory() as work:
        for vehicle in VEHICLES:
            out = Path(work) / vehicle
            subprocess.run([str(rigopt), "design", "--vehicle", vehicle, "--ref", str(REFERENCE_FILE), "--out",
                            str(out), "--json"], check=True, capture_output=True, text=True)
            design = load_design(out / "report.json").perception()
            copies = dict(comparison_rigs(design, reference, load_weights("joint"))[1:])
            rigs = [design, *(copies[role] for role in YARDSTICKS.values())]
            for name, rig in zip(rig_names(vehicle), rigs):
                write_rig(dataclasses.replace(rig, name=name), RIGS / f"{name}.json")
                print(f"wrote rigs/{name}.json ({len(rig)} cameras)", flush=True)


def measure_vehicle(vehicle: str, protocol_name: str, cache, workers: int, progress) -> dict:
    from rigopt.metrics.calibration import load_weights
    from rigopt.rig.library import load_rig
    from rigopt.validation.designs import predicted_transfers
    from rigopt.validation.detectors.measuring import protocol_named
    from rigopt.validation.detectors.shipped import measure, paired_differences, shipped_detector, without_resamples

    rigs = [load_rig(RIGS / f"{name}.json") for name in rig_names(vehicle)]
    detector = shipped_detector("lss", REFERENCE)
    entries = measure(rigs, detector, cache, "cpu", workers, progress, protocol_named(protocol_name))
    predicted = predicted_transfers(load_rig(REFERENCE_FILE), rigs, load_weights("joint"))
    return {"vehicle": vehicle, "protocol": protocol_name, "reference": REFERENCE, "seeds": list(detector.seeds),
            "rigs": [{**without_resamples(e), "predicted_drop": p.predicted_drop, "predicted_by": p.predictor}
                     for e, p in zip(entries, predicted)],
            "design_minus": {role: paired_differences(entries[0], entry) for role, entry in zip(YARDSTICKS, entries[1:])}}


def analyse(found: dict) -> dict:
    own = {p: found[(VEHICLES[0], p)]["rigs"][0]["seeds"]["0"]["reference_mAP"] for p in PROTOCOLS}
    scene_sets = scene_set_means(found, VEHICLES, PROTOCOLS, YARDSTICKS, RESAMPLES, SEED, LEVEL)
    orders = {p: {v: _same_order(found[(v, p)]["rigs"]) for v in VEHICLES} for p in PROTOCOLS}
    inconclusive = min(own.values()) < WEAKEST_MODEL
    return {"level": LEVEL, "own_mAP": own, "scene_sets": scene_sets, "orders": orders, "inconclusive": inconclusive,
            "beats": {role: not inconclusive and won for role, won in beaten(scene_sets, YARDSTICKS).items()}}


def _same_order(rigs: list) -> bool:
    """Whether the predicted drops order the rigs as the measured drops do."""
    return sorted(range(len(rigs)), key=lambda k: rigs[k]["drop"]) == sorted(range(len(rigs)),
                                                                             key=lambda k: rigs[k]["predicted_drop"])


def report(found: dict, result: dict) -> str:
    rows = cell_rows(found, VEHICLES, PROTOCOLS, YARDSTICKS)
    rows[0] += ["predicted (design / naive / height-matched)", "same order"]
    for row, (v, p) in zip(rows[1:], [(v, p) for v in VEHICLES for p in PROTOCOLS]):
        row += [" / ".join(f"{r['predicted_drop']:.3f}" for r in found[(v, p)]["rigs"]),
                "yes" if result["orders"][p][v] else "no"]
    own = ", ".join(f"{p} {value:.3f}" for p, value in result["own_mAP"].items())
    verdict = ("inconclusive: the model's own mAP is below the pre-registered 0.10" if result["inconclusive"] else
               "; ".join(f"{role}: {'beaten' if won else 'not beaten'}" for role, won in result["beats"].items()))
    return (f"# The designer's claim from a second reference ({REFERENCE}, one lss model trained on it; own mAP "
            f"{own})\n\n{markdown(rows)}\n\n{markdown(summary_rows(result['scene_sets'], LEVEL))}\n\n"
            f"**Decision (pre-registered rule): {verdict}.**\n")


def main(argv=None) -> int:
    if argv is None and "--make-rigs" in sys.argv[1:]:
        make_rigs()
        return 0
    return run_cells(argv, __doc__.splitlines()[0], RESULTS, VEHICLES, PROTOCOLS, measure_vehicle, analyse, report)


if __name__ == "__main__":
    sys.exit(main())
