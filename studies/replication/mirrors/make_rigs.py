"""The city bus's four replication rigs remade by today's designer, which infers a mirror zone on user meshes.

    python studies/replication/mirrors/make_rigs.py

adds ``examples/raw_bus.obj`` as ``citybus`` (``--forward +x --allow-size``, as the replication's bus) to a
RIGOPT_HOME of its own, then writes into ``rigs/`` the default design's perception cameras
(``citybus_from_R1_default``) and R1's naive, height-matched and searched copies, made as
``studies/predictor/rig_set.py`` made them (``studies/replication/remake.py``). No rig is measured here.
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the replication's shared pieces (remake)
from remake import BUS, write_remade  # noqa: E402


def main() -> int:
    write_remade((BUS,), HERE / "rigs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
