"""Measure the second predictor study's test rigs with the shipped R1 detectors (resumable; progress and a log).

    python studies/predictor_v2/measure.py [--cache DIR] [--workers 2] [--vehicles ...]

Each rig of ``rigs/index.csv`` as ``rigopt validate RIG --ref R1 --model lss`` does without ``--data``, under the
protocol the first predictor study used (quick, its agreement with full having passed). Entries go to
``results/measured.jsonl`` with the rig's vehicle, kind and source, the log to ``results/measure.log``; a rerun
skips the rigs measured. The user vehicle ``van`` must be added first (``preregistration.md``).
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # studies/: the studies' shared code (studylib)
from studylib.measuring import measure_rig_index  # noqa: E402

if __name__ == "__main__":
    sys.exit(measure_rig_index(HERE, __doc__.splitlines()[0], columns=("vehicle", "kind", "source")))
