"""A study's progress log: each message printed with the time and appended to a log file."""

from __future__ import annotations

import time
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def timestamped_log(path: Path):
    """A ``progress(message)`` function for the ``with`` block: prints ``HH:MM:SS message`` and appends the same
    line to ``path`` (flushed at once, so a long run's log shows where it is); its folder is made if missing."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with Path(path).open("a") as log:
        def progress(message: str) -> None:
            line = f"{time.strftime('%H:%M:%S')} {message}"
            print(line, flush=True)
            log.write(line + "\n")
            log.flush()

        yield progress
