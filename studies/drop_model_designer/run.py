"""Does a designer that minimises the measured-drop model beat today's designer where neither was tuned?
Pre-registered in ``preregistration.md``.

    python studies/drop_model_designer/run.py [--cache DIR] [--workers 2] [--analyse-only]

1. Per test vehicle V, the drop model fitted (``fit_weights``) on the predictor study's measured rigs of the other
   seven vehicles, written to ``models/<V>.json``.
2. Per arm and vehicle, ``rigopt design --vehicle V --ref R1 --objective models/<V>.json`` (arm ``model``) and the
   same with ``--pose free`` (arm ``model_free``); the design's perception cameras to ``rigs/<V>_from_R1_<arm>.json``.
3. Each arm's design measured beside today's default design and R1's height-matched and searched copies
   (``studies/predictor/rigs/``) under ``quick`` and ``quick-s1`` as ``rigopt validate`` does; per vehicle and
   scene set the paired differences to ``results/<V>_<protocol>.json`` (a rerun skips those files).
4. The pre-registered statistics and decision to ``results/results.md`` and ``results/results.json``; the log to
   ``results/run.log``.

The user vehicle ``citybus`` must be added first (``studies/predictor/README.md``).
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
PREDICTOR = HERE.parent / "predictor"
RESULTS, MODELS, RIGS = HERE / "results", HERE / "models", HERE / "rigs"
sys.path.insert(0, str(HERE.parent))  # studies/: the studies' shared code (studylib)
from studylib.paired import run_cells, vehicle_draws, vehicle_mean  # noqa: E402
from studylib.tables import markdown  # noqa: E402

VEHICLES = ("tt", "renault_zoe", "ford_fusion_hybrid", "chrysler_pacifica_hybrid", "citybus")
PROTOCOLS = ("quick", "quick-s1")
ARMS = {"model": [], "model_free": ["--pose", "free"]}
YARDSTICKS = {"today's design": "{v}_from_R1_default", "height-matched copy": "{v}_height_matched_{v}_from_R1",
              "searched copy": "{v}_height_matched_{v}_from_R1_searched"}
RESAMPLES, SEED, LEVEL = 2000, 0, 1 - 0.05 / len(ARMS)


def held_out_model(vehicle: str):
    """The drop model fitted on the predictor study's rigs of every vehicle but ``vehicle``."""
    from rigopt.metrics import drop_model as dm
    from rigopt.rig.library import load_rig

    entries = [json.loads(line) for line in (PREDICTOR / "results" / "measured.jsonl").read_text().splitlines()]
    entries = [e for e in entries if e["vehicle"] != vehicle]
    reference = load_rig("R1").perception()
    terms = [dm.PairTerms.of(reference, load_rig(PREDICTOR / "rigs" / f"{e['rig']}.json")) for e in entries]
    weights = dm.fit_weights(terms, np.array([e["drop"] for e in entries]))
    n = len(dm.FEATURES)
    return dm.DropModel(f"lss-R1-without-{vehicle}", "lss-R1", "R1", dm.camera_table(reference), weights,
                        np.full(len(dm.INTERVAL_BINS) + 1, np.inf), np.zeros((n, 2)), False,
                        f"fitted on {len(entries)} rigs of the predictor study without {vehicle}")


def design(vehicle: str, arm: str, progress) -> Path:
    """rigs/<vehicle>_from_R1_<arm>.json: the arm's design's perception cameras (made once)."""
    import dataclasses

    from rigopt.output import write_text_atomic
    from rigopt.rig.pccr_format import write_rig
    from rigopt.validation.designs import load_design

    path = RIGS / f"{vehicle}_from_R1_{arm}.json"
    if path.is_file():
        return path
    model = MODELS / f"{vehicle}.json"
    if not model.is_file():
        MODELS.mkdir(exist_ok=True)
        write_text_atomic(model, json.dumps(held_out_model(vehicle).to_dict(), indent=1) + "\n")
    rigopt = Path(sys.executable).parent / "rigopt"
    with tempfile.TemporaryDirectory() as work:
        out = Path(work) / "design"
        command = [str(rigopt), "design", "--vehicle", vehicle, "--ref", "R1", "--objective", str(model),
                   *ARMS[arm], "--out", str(out)]
        progress(" ".join(command[1:]))
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode != 0:
            raise SystemExit(f"{vehicle} {arm}: no design: {done.stderr.strip().splitlines()[-1]}")
        rig = dataclasses.replace(load_design(out / "report.json").perception(), name=path.stem)
        RIGS.mkdir(exist_ok=True)
        write_rig(rig, path)
    return path


def measure_vehicle(vehicle: str, protocol_name: str, cache, workers: int, progress) -> dict:
    from rigopt.rig.library import load_rig
    from rigopt.validation.detectors.measuring import protocol_named
    from rigopt.validation.detectors.shipped import measure, paired_differences, shipped_detector, without_resamples

    arms = [load_rig(design(vehicle, arm, progress)) for arm in ARMS]
    yardsticks = [load_rig(PREDICTOR / "rigs" / f"{pattern.format(v=vehicle)}.json") for pattern in YARDSTICKS.values()]
    entries = measure(arms + yardsticks, shipped_detector("lss", "R1"), cache, "cpu", workers, progress,
                      protocol_named(protocol_name))
    return {"vehicle": vehicle, "protocol": protocol_name, "rigs": [without_resamples(e) for e in entries],
            "minus": {arm: {role: paired_differences(entries[k], entry)
                            for role, entry in zip(YARDSTICKS, entries[len(ARMS):])} for k, arm in enumerate(ARMS)}}


def analyse(found: dict) -> dict:
    draws = vehicle_draws(len(VEHICLES), RESAMPLES, SEED)
    out = {"level": LEVEL, "arms": {}}
    for arm in ARMS:
        per = {f"{protocol} / {role}": vehicle_mean([found[(v, protocol)]["minus"][arm][role] for v in VEHICLES],
                                                    VEHICLES, draws, LEVEL)
               for protocol in PROTOCOLS for role in YARDSTICKS}
        beats = {role: all(per[f"{p} / {role}"]["ci_bonferroni"][1] < 0 and not per[f"{p} / {role}"]["vehicles_wholly_above_0"]
                           for p in PROTOCOLS) for role in YARDSTICKS}
        out["arms"][arm] = {"differences": per, "beats": beats}
    winners = [arm for arm in ARMS if out["arms"][arm]["beats"]["today's design"]]
    out["replaces_today"] = min(winners, key=lambda a: out["arms"][a]["differences"]["quick-s1 / today's design"]["mean"],
                                default=None)
    return out


def report(found: dict, result: dict) -> str:
    names = [*ARMS, *YARDSTICKS]
    rows = [["vehicle", "scenes", *names]]
    for v in VEHICLES:
        for p in PROTOCOLS:
            rows.append([v, p, *(f"{r['drop']:.3f} [{r['drop_ci'][0]:.3f}, {r['drop_ci'][1]:.3f}]"
                                 for r in found[(v, p)]["rigs"])])
    summary = [["arm", "scenes / yardstick", "mean arm - yardstick", "95 % over vehicles",
                f"{100 * LEVEL:.1f} % (Bonferroni)", "vehicles wholly above 0"]]
    for arm, entry in result["arms"].items():
        for key, s in entry["differences"].items():
            summary.append([arm, key, f"{s['mean']:+.3f}", "[{:.3f}, {:.3f}]".format(*s["ci95"]),
                            "[{:.3f}, {:.3f}]".format(*s["ci_bonferroni"]), ", ".join(s["vehicles_wholly_above_0"]) or "-"])
    verdicts = "; ".join(f"{arm}: " + ", ".join(f"{role} {'beaten' if won else 'not beaten'}"
                                                for role, won in entry["beats"].items())
                         for arm, entry in result["arms"].items())
    decision = (f"the {result['replaces_today']} arm replaces today's designer" if result["replaces_today"]
                else "today's designer stays")
    return (f"# A designer minimising the measured-drop model, on held-out vehicles and new scenes\n\n"
            f"Drops (mean of the three shipped seeds, 95 % scene interval):\n\n{markdown(rows)}\n\n{markdown(summary)}\n\n"
            f"**Decision (pre-registered rule): {decision}.** {verdicts}.\n")


def main(argv=None) -> int:
    return run_cells(argv, __doc__.splitlines()[0], RESULTS, VEHICLES, PROTOCOLS, measure_vehicle, analyse, report)


if __name__ == "__main__":
    sys.exit(main())
