"""Ship the validation study's winner: write its frozen weights as a metric rigopt's commands can name.

Run ``python studies/validation/ship.py`` after ``analysis.py``. It reads the decision in
``results/analysis.json``; when a candidate ships, it writes that candidate's weights from ``candidates.json``
(fitted and frozen before the measurement, unchanged here) as ``metrics/weights-<metric>/joint.json``, the metric
being the candidate's name with hyphens (``depth_prior`` -> ``depth-prior``). The metric becomes nameable once it
is listed in ``rigopt.metrics.calibration.LIFTING_METRICS``. When no candidate ships, it writes nothing and says so.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]


def metric_name(candidate: str) -> str:
    """The command-line name of a candidate distance: 'split_depth' -> 'split-depth'."""
    return candidate.replace("_", "-")


def main() -> int:
    from rigopt.metrics.calibration import lifting_calibration, write_weights

    decision = json.loads((HERE / "results" / "analysis.json").read_text())["decision"]
    winner = decision["ships"]
    if winner is None:
        print("no candidate beats RigCD under the pre-registered rule: nothing ships")
        return 0
    entry = json.loads((HERE / "candidates.json").read_text())["candidates"][winner]
    metric = metric_name(winner)
    path = write_weights(lifting_calibration("joint", entry["weights"], metric),
                         ROOT / "metrics" / f"weights-{metric}" / "joint.json")
    print(f"{winner} ships as --metric {metric}: {path.relative_to(ROOT)} (designer default: "
          f"{decision['designer_default']})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
