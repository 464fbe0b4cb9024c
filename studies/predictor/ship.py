"""Ship the predictor study's model: fitted on every measured rig, its intervals from the held-out residuals.

    python studies/predictor/ship.py

Reads ``results/analysis.json`` (``analysis.py``) and writes ``metrics/drop_models/lss-R1.json``, the model that
``rigopt rank``, ``rigcd``, ``design`` and ``validate`` print by default (``--predictor auto``) when the study's
pre-registered decision found it better than RigCD (``replaces_rigcd``) and the second predictor study
(studies/predictor_v2/) did not replace it; otherwise it ships marked not default and prints only when asked for
by name (``--predictor lss-R1``).
"""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # studies/: the studies' shared code (studylib)
from studylib.packs import PREVIOUS_R1_PACK  # noqa: E402

TARGET = HERE.parents[1] / "metrics" / "drop_models" / "lss-R1.json"


def main() -> int:
    from rigopt.metrics import drop_model
    from rigopt.output import write_text_atomic
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.placement import in_vehicle_frame

    analysis = json.loads((HERE / "results" / "analysis.json").read_text())
    terms = tuple(analysis["weights_all"])  # the study's pre-registered terms, in FEATURES order
    weights = np.array([analysis["weights_all"].get(name, 0.0) for name in drop_model.FEATURES])
    reference = in_vehicle_frame(load_rig("R1"))[0].perception()
    rigs = [in_vehicle_frame(load_rig(HERE / "rigs" / f"{row['rig']}.json"))[0] for row in analysis["per_rig"]]
    held_out = np.array([row["predicted"] for row in analysis["per_rig"]])
    measured = np.array([row["measured"] for row in analysis["per_rig"]])
    p, r = analysis["predictor"], analysis["rigcd"]
    study = (f"studies/predictor (pre-registered): {analysis['rigs']} rigs on {len(analysis['vehicles'])} vehicles, "
             f"leave-one-vehicle-out mean within-vehicle rho {p['mean_within_rho']:.3f} (RigCD "
             f"{r['mean_within_rho']:.3f}), MAE {p['mae']:.3f} (RigCD {r['mae']:.3f})")
    # printed by default when it beat RigCD, unless the second study's model replaced it (studies/predictor_v2/)
    later = HERE.parent / "predictor_v2" / "results" / "analysis.json"
    replaced = later.is_file() and json.loads(later.read_text())["v2_replaces_v1"]
    model = drop_model.DropModel("lss-R1", PREVIOUS_R1_PACK, "R1", drop_model.camera_table(reference), weights,
                                 drop_model.interval_halfwidths(held_out, measured), np.zeros((len(weights), 2)),
                                 bool(analysis["replaces_rigcd"]) and not replaced, study, features=terms)
    terms = model.terms(reference, rigs)  # each term's range over the fitting rigs, under the model's matching
    model = dataclasses.replace(model, ranges=np.column_stack([terms.min(axis=0), terms.max(axis=0)]))
    TARGET.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(TARGET, json.dumps(model.to_dict(), indent=1) + "\n")
    print(f"{TARGET}: default {model.default}; {study}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
