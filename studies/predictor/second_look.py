"""A look after the decision, not pre-registered: the shipped model (fitted on this study's 329 rigs) on the
validation study's 63 rigs (studies/validation/: R1 variations, designs and copies on the fire truck, hgv and tt,
measured under the full protocol before this study; never used to fit the shipped model), beside RigCD.

    python studies/predictor/second_look.py

Writes ``results/second_look.md``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
VALIDATION = HERE.parent / "validation"


def main() -> int:
    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.drop_model import load_drop_model
    from rigopt.metrics.ranking import predict_transfer
    from rigopt.metrics.reliability import spearman
    from rigopt.output import write_text_atomic
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.placement import in_vehicle_frame

    entries = [json.loads(line) for line in (VALIDATION / "results" / "measured.jsonl").read_text().splitlines()]
    rigs = []
    for entry in entries:
        path = VALIDATION / "rigs" / f"{entry['rig']}.json"
        rigs.append(in_vehicle_frame(load_rig(path if path.is_file() else entry["rig"]))[0].perception())
    reference, model = load_rig("R1"), load_drop_model("lss-R1")
    predicted, halfwidths, _ = model.predict(reference, rigs)
    rigcd = np.array([p.predicted_drop for p in predict_transfer(reference, rigs, load_weights("joint"))])
    measured = np.array([e["drop"] for e in entries])
    vehicles = np.array([e["vehicle"] for e in entries])
    rows = ["| vehicles | rigs | rho model | rho RigCD | MAE model | MAE RigCD |", "|---|---|---|---|---|---|"]
    for name, keep in [*((v, vehicles == v) for v in np.unique(vehicles)), ("all (pooled)", np.ones(len(entries), bool))]:
        rows.append(f"| {name} | {keep.sum()} | {spearman(predicted[keep], measured[keep])[0]:.3f} | "
                    f"{spearman(rigcd[keep], measured[keep])[0]:.3f} | {np.abs(predicted - measured)[keep].mean():.3f} | "
                    f"{np.abs(rigcd - measured)[keep].mean():.3f} |")
    worst = np.argsort(-np.abs(predicted - measured))[:5]
    text = ("# The shipped drop model on the validation study's 63 rigs (a look after the decision)\n\n"
            + "\n".join(rows) + f"\n\n90 % interval coverage: {np.mean(np.abs(predicted - measured) <= halfwidths):.3f}.\n\n"
            "Largest errors:\n\n" + "\n".join(f"- {entries[k]['rig']}: measured {measured[k]:.3f}, predicted "
                                              f"{predicted[k]:.3f}" for k in worst) + "\n")
    write_text_atomic(HERE / "results" / "second_look.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
