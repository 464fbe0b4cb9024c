"""Fit the second drop model before any of its test rigs is measured: every rig measured so far, all terms
(the first model's and ``body``), its intervals from leave-one-vehicle-out residuals.

    python studies/predictor_v2/fit.py

The fitting rigs (``known_rigs``): the first predictor study's 329 (studies/predictor/, quick protocol) and the
validation study's 63 (studies/validation/, full protocol), all from R1 with the shipped LSS models. Writes
``models/lss-R1-v2.json`` (a drop model file, not default: ``preregistration.md``'s decision rule sets that after
the test) and ``results/fit.md`` (the leave-one-vehicle-out figures on the fitting rigs: known data, not the test).
The user vehicle ``citybus`` must be added (studies/predictor/preregistration.md).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
STUDIES = HERE.parent
MODEL = HERE / "models" / "lss-R1-v2.json"
sys.path.insert(0, str(STUDIES))  # studies/: the studies' shared code (studylib)
from studylib.packs import PREVIOUS_R1_PACK  # noqa: E402
from studylib.tables import markdown  # noqa: E402


def known_rigs() -> list[dict]:
    """{rig, vehicle, kind, drop, source} of every rig measured before this study, each rig from its vehicle's
    centre on the ground (perception cameras)."""
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.placement import in_vehicle_frame

    out = []
    for source in ("predictor", "validation"):
        for line in (STUDIES / source / "results" / "measured.jsonl").read_text().splitlines():
            entry = json.loads(line)
            path = STUDIES / source / "rigs" / f"{entry['rig']}.json"
            rig = load_rig(path if path.is_file() else entry["rig"])  # the validation study's hand rigs by name
            out.append({"rig": in_vehicle_frame(rig)[0].perception(), "vehicle": entry["vehicle"],
                        "kind": entry["kind"], "drop": float(entry["drop"]), "source": source})
    return out


def held_out(terms, drops: np.ndarray, vehicles: np.ndarray) -> np.ndarray:
    """(P,) each rig's drop predicted by the fit on the other vehicles' rigs."""
    from rigopt.metrics import drop_model

    out = np.empty(len(drops))
    for vehicle in np.unique(vehicles):
        test = vehicles == vehicle
        weights = drop_model.fit_weights([t for t, keep in zip(terms, ~test) if keep], drops[~test])
        out[test] = drop_model.predict(weights, [t for t, keep in zip(terms, test) if keep])
    return out


def main() -> int:
    import dataclasses

    from rigopt.metrics import drop_model
    from rigopt.metrics.reliability import spearman
    from rigopt.mounting.candidates import rig_body_share
    from rigopt.output import write_text_atomic
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.placement import in_vehicle_frame

    rigs = known_rigs()
    reference = in_vehicle_frame(load_rig("R1"))[0].perception()
    drops = np.array([r["drop"] for r in rigs])
    vehicles = np.array([r["vehicle"] for r in rigs])
    terms = [drop_model.PairTerms.of(reference, r["rig"], rig_body_share) for r in rigs]
    predicted = held_out(terms, drops, vehicles)
    weights = drop_model.fit_weights(terms, drops)
    study = (f"studies/predictor_v2 (pre-registered): fitted on {len(rigs)} rigs of {len(set(vehicles))} vehicles "
             "measured before it; tested on 54 new rigs (see its results)")
    model = drop_model.DropModel("lss-R1-v2", PREVIOUS_R1_PACK, "R1", drop_model.camera_table(reference), weights,
                                 drop_model.interval_halfwidths(predicted, drops), np.zeros((len(weights), 2)),
                                 False, study)
    x = model.terms(reference, [r["rig"] for r in rigs], rig_body_share)
    model = dataclasses.replace(model, ranges=np.column_stack([x.min(axis=0), x.max(axis=0)]))
    MODEL.parent.mkdir(exist_ok=True)
    write_text_atomic(MODEL, json.dumps(model.to_dict(), indent=1) + "\n")

    rows = [["vehicle", "rigs", "held-out rho", "held-out MAE"]]
    for vehicle in np.unique(vehicles):
        keep = vehicles == vehicle
        rows.append([vehicle, int(keep.sum()), f"{spearman(predicted[keep], drops[keep])[0]:.3f}",
                     f"{np.abs(predicted[keep] - drops[keep]).mean():.3f}"])
    rows.append(["all (pooled)", len(rigs), f"{spearman(predicted, drops)[0]:.3f}",
                 f"{np.abs(predicted - drops).mean():.3f}"])
    text = (f"# The second drop model's fit (known rigs; not the test)\n\n{len(rigs)} rigs, each predicted by the fit "
            f"without its vehicle:\n\n{markdown(rows)}\n\nWeights (all rigs): "
            + ", ".join(f"{name} {w:.3f}" for name, w in zip(drop_model.FEATURES, weights))
            + "\n\n90 % half-widths per predicted-drop bin (below 0.15, 0.15-0.4, above): "
            + ", ".join(f"{w:.3f}" for w in model.halfwidths) + "\n")
    (HERE / "results").mkdir(exist_ok=True)
    write_text_atomic(HERE / "results" / "fit.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
