"""Libraries kept quiet: their banners and log lines must not reach either of a command's streams.

HiGHS prints a licence banner on the native stdout when a process makes its first ``Highs`` object, whatever
its options; cvxpy makes one inside ``solve``. :func:`quiet_highs` makes that first object with the native
stdout sent to the null device, so that later ones (each solve's, with ``output_flag`` off) print nothing. trimesh logs warnings such as
"only got 3952/4000 samples!" where rigopt asks for evenly spread samples and takes what it gets:
:func:`quiet_trimesh` holds them back around such calls.
"""

from __future__ import annotations

import logging
import os
import sys
from contextlib import contextmanager
from functools import cache


#: Options every HiGHS solve of rigopt passes (``problem.solve(solver=cp.HIGHS, **HIGHS_OPTIONS, ...)``): no log,
#: one thread and a fixed seed, so that answers do not depend on the machine. One thread count for all: HiGHS's
#: scheduler keeps the count of a process's first solve and fails a later solve that asks for another.
HIGHS_OPTIONS = {"threads": 1, "random_seed": 0, "output_flag": False}


@cache
def quiet_highs() -> None:
    """Make the process's first HiGHS object silently (once); a no-op when highspy is missing."""
    try:
        import highspy
    except ImportError:
        return
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            highspy.Highs()
    finally:
        os.dup2(saved, 1)
        os.close(saved)


@contextmanager
def quiet_trimesh():
    """Within the block, trimesh logs errors only (its warnings are expected outcomes here, not news)."""
    logger = logging.getLogger("trimesh")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        yield
    finally:
        logger.setLevel(level)
