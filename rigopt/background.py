"""Work beside the main line of a command: one worker process for steps that need nothing the main line is
still computing (a design's near-field stage, its pictures), so that a machine's second core shares the work.

A :class:`Background` with a worker runs each submitted call there (a spawned interpreter: no state shared with
this process but the pickled arguments, so no native library's threads are inherited half-way); without one
(one core, or ``RIGOPT_WORKERS=0``) a call runs inline when its result is first asked for. Either way the result
is the same: the same function on the same inputs. Nothing here decides a result by the clock.
"""

from __future__ import annotations

import os
import signal
import sys
from typing import Any, Callable

#: The environment variable that turns the worker off (``0``) or on (``1``); unset: on with two cores or more.
WORKERS_VARIABLE = "RIGOPT_WORKERS"


def available_cores() -> int:
    """The number of CPU cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def wanted() -> bool:
    """Whether a command should start a worker: ``RIGOPT_WORKERS`` when set, else two cores or more."""
    setting = os.environ.get(WORKERS_VARIABLE, "").strip()
    if setting:
        return setting not in ("0", "false", "no", "off")
    return available_cores() >= 2


def worker_setup() -> None:
    """In a worker process: the main process handles Ctrl-C and ends its workers (:func:`end_workers`); a worker
    whose main process dies (SIGTERM, SIGKILL) gets SIGTERM and ends too (Linux); nothing reaches its stdout."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        import ctypes

        ctypes.CDLL(None).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
        if os.getppid() == 1:  # the main process died before the line above: end now
            os._exit(1)
    os.dup2(2, 1)


#: prctl's option that sends a signal to this process when its parent dies (linux/prctl.h).
PR_SET_PDEATHSIG = 1


def end_workers(pool) -> None:
    """End a ProcessPoolExecutor's workers now, whatever they are doing (their results are not needed): no
    waiting for a running call, no orphan left behind."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        process.terminate()
    for process in processes:
        process.join()


def _import(modules: tuple[str, ...]) -> None:
    """Import ``modules`` (in the worker, ahead of the calls that need them)."""
    import importlib

    for module in modules:
        importlib.import_module(module)


class Job:
    """A submitted call; :meth:`result` returns its value or raises its exception (in this process)."""

    def __init__(self, function: Callable, args: tuple, kwargs: dict, pending=None):
        self._call, self._pending, self._done = (function, args, kwargs), pending, False
        self._value: Any = None
        self._error: BaseException | None = None

    def result(self):
        if not self._done:
            try:
                if self._pending is not None:
                    self._value = self._pending.result()  # a worker that died raises BrokenProcessPool
                else:
                    function, args, kwargs = self._call
                    self._value = function(*args, **kwargs)
            except Exception as error:  # kept, so that asking again raises the same
                self._error = error
            self._done, self._call, self._pending = True, None, None
        if self._error is not None:
            raise self._error
        return self._value


class Background:
    """One worker process (``workers`` True), or none: calls then run inline, when their result is asked for
    (``workers`` None: :func:`wanted`). ``later_imports``: modules the worker imports right after the first call
    (what a later call needs, loaded while the worker would wait for it). Use as a context manager; closing ends
    the worker, finished or not."""

    def __init__(self, workers: bool | None = None, later_imports: tuple[str, ...] = ()):
        self._pool, self._later_imports = None, tuple(later_imports)
        if wanted() if workers is None else workers:
            import multiprocessing
            from concurrent.futures import ProcessPoolExecutor

            self._pool = ProcessPoolExecutor(1, multiprocessing.get_context("spawn"), initializer=worker_setup)

    @property
    def parallel(self) -> bool:
        """True when calls run in a worker process."""
        return self._pool is not None

    def submit(self, function: Callable, *args, **kwargs) -> Job:
        """Run ``function(*args, **kwargs)`` in the worker (a module-level function; picklable arguments), or
        inline at the first :meth:`Job.result`."""
        pending = self._pool.submit(function, *args, **kwargs) if self._pool is not None else None
        if pending is not None and self._later_imports:
            self._pool.submit(_import, self._later_imports)
            self._later_imports = ()
        return Job(function, args, kwargs, pending)

    def close(self) -> None:
        """End the worker (whatever it is doing: results not asked for are not needed)."""
        if self._pool is not None:
            end_workers(self._pool)  # a call still running is not needed: end it now
            self._pool = None

    def __enter__(self) -> "Background":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


#: Calls run inline (no worker): the default of the library's functions that accept a Background.
INLINE = Background(workers=False)
