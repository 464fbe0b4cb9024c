"""The replication rigs the windscreen rule changed, remade by today's designer.

    python studies/replication/windscreen/make_rigs.py

For the tt, the chrysler_pacifica_hybrid and the city bus (added to a RIGOPT_HOME of its own as in amendment 2)
writes into ``rigs/`` the default design's perception cameras (``<V>_from_R1_default``) and R1's naive,
height-matched and searched copies, made as ``studies/predictor/rig_set.py`` made them
(``studies/replication/remake.py``). No rig is measured here.
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the replication's shared pieces (remake)
from remake import write_remade  # noqa: E402

VEHICLES = ("tt", "chrysler_pacifica_hybrid", "citybus")


def main() -> int:
    write_remade(VEHICLES, HERE / "rigs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
