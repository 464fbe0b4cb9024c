"""The default predictor against the new detectors (``PREREGISTRATION.md``, amendment 4, item 3).

    python studies/stronger_detector/predictor_check.py

``lss-R1-v2`` (fitted on the previous pack's drops, not refitted) predicts the replication's 20 rigs (five held-out
vehicles' design and three copies of R1); measured is each rig's drop, the mean over the pack's seeds, under
``quick`` and ``quick-s1`` (40 cells). Pooled Spearman rho and mean absolute error, with 95 % intervals from 2000
resamples of the rigs (a rig's two scene sets drawn together), against the new pack
(``studies/replication/stronger_detector``) and against the previous one (``studies/replication/results``). Writes
``results/predictor_check.json`` and ``results/predictor_check.md``. The user vehicle ``citybus`` must be added
(``RIGOPT_HOME`` as when the rigs were measured): its body enters the model.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
STUDIES = HERE.parent
sys.path.insert(0, str(STUDIES))  # studies/: the studies' shared code (studylib)
from studylib.modules import study_module  # noqa: E402
from studylib.tables import markdown  # noqa: E402

PACKS = {"previous pack (c16e580)": STUDIES / "replication" / "results",
         "new pack": STUDIES / "replication" / "stronger_detector"}
PROTOCOLS = ("quick", "quick-s1")
PREDICTOR = "lss-R1-v2"
#: The rule (amendment 4): the bar of predictor_v2's replication.
BAR = {"pooled_rho": 0.8, "mae": 0.10}

# predictor_v2's statistics (Spearman rho, the percentile interval over resampled groups); the replication's vehicles
_analysis = study_module("predictor_v2_analysis", STUDIES / "predictor_v2" / "analysis.py")
interval, rho = _analysis.interval, _analysis.rho
VEHICLES = study_module("replication_remake", STUDIES / "replication" / "remake.py").VEHICLES


def measured_cells(folder: Path) -> list[dict]:
    """One entry per (rig, scene set) of the replication's cells in ``folder``: rig, protocol, measured drop."""
    cells = []
    for vehicle in VEHICLES:
        for protocol in PROTOCOLS:
            found = json.loads((folder / f"{vehicle}_{protocol}.json").read_text())
            cells += [{"rig": entry["rig"], "protocol": protocol, "drop": entry["drop"]} for entry in found["rigs"]]
    return cells


def predictions(names: list[str]) -> dict[str, float]:
    """``lss-R1-v2``'s predicted drop of each rig from R1 (perception cameras, in their vehicle's frame)."""
    from rigopt.metrics.drop_model import load_drop_model
    from rigopt.mounting.candidates import rig_body_share
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.placement import in_vehicle_frame

    rigs_folder = STUDIES / "predictor" / "rigs"
    reference = in_vehicle_frame(load_rig("R1"))[0].perception()
    rigs = [in_vehicle_frame(load_rig(rigs_folder / f"{name}.json"))[0].perception() for name in names]
    return dict(zip(names, map(float, load_drop_model(PREDICTOR).predict(reference, rigs, rig_body_share)[0])))


def statistics(cells: list[dict], predicted: dict[str, float]) -> dict:
    measured = np.array([c["drop"] for c in cells])
    p = np.array([predicted[c["rig"]] for c in cells])
    groups = np.array([c["rig"] for c in cells])
    error = np.abs(p - measured)
    return {"pooled_rho": rho(p, measured), "rho_ci": interval(lambda k: rho(p[k], measured[k]), groups),
            "mae": float(error.mean()), "mae_ci": interval(lambda k: float(error[k].mean()), groups),
            "mean_measured": float(measured.mean()), "mean_predicted": float(p.mean())}


def report(result: dict) -> str:
    rows = [["against", "pooled rho (95 % over rigs)", "mean error (95 % over rigs)", "mean measured",
             "mean predicted"]]
    for pack, s in result["packs"].items():
        rows.append([pack, f"{s['pooled_rho']:.3f} [{s['rho_ci'][0]:.3f}, {s['rho_ci'][1]:.3f}]",
                     f"{s['mae']:.3f} [{s['mae_ci'][0]:.3f}, {s['mae_ci'][1]:.3f}]", f"{s['mean_measured']:.3f}",
                     f"{s['mean_predicted']:.3f}"])
    verdict = "holds" if result["holds"] else "does not hold"
    every = [["rig", "scenes", *result["packs"], PREDICTOR]] + [
        [c["rig"], c["protocol"], *(f"{d:.3f}" for d in c["drops"]), f"{c['predicted']:.3f}"] for c in result["cells"]]
    return (f"# {PREDICTOR} against the new detectors (amendment 4, item 3)\n\n20 rigs x 2 scene sets (the "
            f"replication's five held-out vehicles; R1's test scenes and 16 new scenes, quick protocol).\n\n"
            f"{markdown(rows)}\n\n**Rule (pooled rho >= {BAR['pooled_rho']}, mean error <= {BAR['mae']} against "
            f"the new pack): {verdict}.**\n\n## Every cell\n\n{markdown(every)}\n")


def main() -> int:
    from rigopt.output import write_text_atomic

    measured = {pack: measured_cells(folder) for pack, folder in PACKS.items()}
    first = next(iter(measured.values()))
    predicted = predictions(sorted({c["rig"] for c in first}))
    packs = {pack: statistics(cells, predicted) for pack, cells in measured.items()}
    new = packs["new pack"]
    result = {"predictor": PREDICTOR, "bar": BAR, "packs": packs,
              "holds": bool(new["pooled_rho"] >= BAR["pooled_rho"] and new["mae"] <= BAR["mae"]),
              "cells": [{"rig": c["rig"], "protocol": c["protocol"], "predicted": predicted[c["rig"]],
                         "drops": [cells[k]["drop"] for cells in measured.values()]} for k, c in enumerate(first)]}
    write_text_atomic(HERE / "results" / "predictor_check.json", json.dumps(result, indent=1) + "\n")
    text = report(result)
    write_text_atomic(HERE / "results" / "predictor_check.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
