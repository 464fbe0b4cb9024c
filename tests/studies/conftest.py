"""The studies' own modules are scripts' neighbours, not part of the package: put each studied folder on
sys.path so that its tests import them by name, as the study's run.py does (``import plus_study``)."""

from __future__ import annotations

import sys
from pathlib import Path

STUDIES = Path(__file__).resolve().parents[2] / "studies"

for folder in (STUDIES / "rigcd_plus", STUDIES / "validation"):
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))
