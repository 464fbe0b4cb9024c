"""Ship the second drop model as the study's pre-registered decision says.

    python studies/predictor_v2/ship.py

Reads ``models/lss-R1-v2.json`` (``fit.py``, committed with the pre-registration) and ``results/analysis.json``
(``analysis.py``); writes ``metrics/drop_models/lss-R1-v2.json``: the same model, its evidence line naming the
test figures, marked default when the decision (``v2_replaces_v1``) chose it. The first model's file
(``studies/predictor/ship.py``) reads that decision and is marked not default when it was replaced.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
TARGET = HERE.parents[1] / "metrics" / "drop_models" / "lss-R1-v2.json"


def main() -> int:
    from rigopt.metrics.drop_model import load_drop_model
    from rigopt.output import write_text_atomic

    analysis = json.loads((HERE / "results" / "analysis.json").read_text())
    v1, v2 = analysis["statistics"]["lss-R1"], analysis["statistics"]["lss-R1-v2"]
    study = (f"studies/predictor_v2 (pre-registered): fitted on the 392 rigs measured before it; on {analysis['rigs']} "
             f"new rigs (a van, variations of R1-R9) pooled rho {v2['pooled_rho']:.3f} (lss-R1 {v1['pooled_rho']:.3f}), "
             f"MAE {v2['mae']:.3f} (lss-R1 {v1['mae']:.3f})")
    model = dataclasses.replace(load_drop_model(HERE / "models" / "lss-R1-v2.json"),
                                default=bool(analysis["v2_replaces_v1"]), study=study)
    write_text_atomic(TARGET, json.dumps(model.to_dict(), indent=1) + "\n")
    print(f"{TARGET}: default {model.default}; {study}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
