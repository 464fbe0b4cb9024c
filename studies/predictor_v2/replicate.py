"""The second predictor study's replication on new scenes (``preregistration.md``, amendment 1): the van's rigs
measured under ``quick-s1`` and predicted by the committed models, nothing refitted.

    python studies/predictor_v2/replicate.py [--cache DIR] [--workers 2]

Resumable: entries go to ``results/new_scenes.jsonl`` (a rerun measures only the rigs missing), the log to
``results/new_scenes.log``; then writes ``results/new_scenes.md``. The user vehicle ``van`` must be added.
"""

from __future__ import annotations

import argparse
import csv
import importlib.util
import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
LINES = RESULTS / "new_scenes.jsonl"
sys.path.insert(0, str(HERE.parent))  # studies/: the studies' shared code (studylib)
from studylib.logs import timestamped_log  # noqa: E402
from studylib.measuring import add_measuring_options, measure_to_lines  # noqa: E402
from studylib.tables import markdown  # noqa: E402

# this study's analysis (other studies have a module of that name: loaded under its own)
_spec = importlib.util.spec_from_file_location("predictor_v2_analysis", HERE / "analysis.py")
_analysis = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_analysis)
DESIGNER_KINDS, PREDICTORS = _analysis.DESIGNER_KINDS, _analysis.PREDICTORS
interval, rho = _analysis.interval, _analysis.rho

#: The pre-registered bar of the replication.
BAR = {"pooled_rho": 0.8, "mae": 0.10}


def van_rows() -> dict[str, dict]:
    with open(HERE / "rigs" / "index.csv", newline="") as handle:
        return {row["rig"]: row for row in csv.DictReader(handle) if row["vehicle"] == "van"}


def measure(args) -> None:
    from rigopt.rig.library import load_rig
    from rigopt.validation.detectors.measuring import protocol_named

    rows = van_rows()
    rigs = [load_rig(HERE / "rigs" / f"{name}.json") for name in rows]
    with timestamped_log(RESULTS / "new_scenes.log") as progress:
        measure_to_lines(rigs, LINES, protocol_named("quick-s1"), args.cache, args.workers, progress,
                         lambda name: {"vehicle": "van", "kind": rows[name]["kind"]})


def report() -> str:
    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.drop_model import load_drop_model
    from rigopt.metrics.ranking import predict_transfer
    from rigopt.mounting.candidates import rig_body_share
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.placement import in_vehicle_frame

    entries = [json.loads(line) for line in LINES.read_text().splitlines()]
    reference = in_vehicle_frame(load_rig("R1"))[0].perception()
    rigs = [in_vehicle_frame(load_rig(HERE / "rigs" / f"{e['rig']}.json"))[0].perception() for e in entries]
    measured = np.array([e["drop"] for e in entries])
    names = [e["rig"] for e in entries]
    kinds = np.array([e["kind"] for e in entries])
    predictions = {name: load_drop_model(name if name == "lss-R1" else HERE / "models" / f"{name}.json").predict(
        reference, rigs, rig_body_share)[0] for name in PREDICTORS[:2]}
    predictions[PREDICTORS[2]] = np.array([p.predicted_drop for p in predict_transfer(reference, rigs,
                                                                                       load_weights("joint"))])
    every, designer = np.arange(len(entries)), np.isin(kinds, DESIGNER_KINDS)
    design, naive = names.index("van_from_R1_default"), int(np.flatnonzero(kinds == "naive")[0])
    table = [["statistic (27 van rigs, 16 new scenes)", *PREDICTORS]]
    cells = {}
    for name, p in predictions.items():
        error = np.abs(p - measured)
        cells[name] = {"pooled_rho": rho(p, measured), "mae": float(error.mean()),
                       "rho_ci": interval(lambda k: rho(p[k], measured[k]), every),
                       "mae_ci": interval(lambda k: float(error[k].mean()), every),
                       "designer_rho": rho(p[designer], measured[designer]),
                       "design_vs_naive": bool(np.sign(p[design] - p[naive])
                                               == np.sign(measured[design] - measured[naive]))}
    for label, key in (("pooled rho (95 % over rigs)", "pooled_rho"), ("MAE (95 % over rigs)", "mae")):
        ci = "rho_ci" if key == "pooled_rho" else "mae_ci"
        table.append([label, *(f"{cells[n][key]:.3f} [{cells[n][ci][0]:.3f}, {cells[n][ci][1]:.3f}]"
                               for n in PREDICTORS)])
    table.append(["rho on the designer's rigs", *(f"{cells[n]['designer_rho']:.3f}" for n in PREDICTORS)])
    table.append(["design vs naive copy as measured", *(str(cells[n]["design_vs_naive"]) for n in PREDICTORS)])
    v2 = cells["lss-R1-v2"]
    replicates = v2["pooled_rho"] >= BAR["pooled_rho"] and v2["mae"] <= BAR["mae"] and v2["design_vs_naive"]
    per_rig = [["rig", "kind", "measured", *PREDICTORS]] + [
        [n, k, f"{m:.3f}", *(f"{predictions[p][i]:.3f}" for p in PREDICTORS)]
        for i, (n, k, m) in enumerate(zip(names, kinds, measured))]
    return (f"# Second predictor study: replication on new scenes (amendment 1; protocol "
            f"{', '.join(sorted({e['protocol'] for e in entries}))})\n\n{markdown(table)}\n\n"
            f"**Pre-registered bar (pooled rho >= 0.8, MAE <= 0.10, design and naive copy in order): "
            f"{'replicates' if replicates else 'does not replicate'}.**\n\n## Every rig\n\n{markdown(per_rig)}\n")


def main(argv=None) -> int:
    from rigopt.output import write_text_atomic

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_measuring_options(parser)
    args = parser.parse_args(argv)
    measure(args)
    text = report()
    write_text_atomic(RESULTS / "new_scenes.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
