"""Measure the predictor study's rigs with the shipped R1 detectors (resumable; progress and a log).

    python studies/predictor/measure.py [--cache DIR] [--workers 2] [--vehicles ...]

Each rig of ``rigs/index.csv`` as ``rigopt validate RIG --ref R1 --model lss`` does without ``--data``, under the
quick protocol when its pre-registered agreement with the full one passed
(``studies/validation/protocol/results/agreement.json``), else the full one. Entries go to
``results/measured.jsonl`` (with the rig's vehicle and kind) in chunks as they are done; a rerun skips the rigs
there. The log is ``results/measure.log``. The user vehicle ``citybus`` must be added first (README.md).
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # studies/: the studies' shared code (studylib)
from studylib.measuring import measure_rig_index  # noqa: E402

if __name__ == "__main__":
    sys.exit(measure_rig_index(HERE, __doc__.splitlines()[0]))
