"""rigopt.background: calls run in a worker process or inline, with the same results and the same errors."""

from __future__ import annotations

import os

import pytest

from rigopt.background import INLINE, Background, wanted
from rigopt.errors import DataError


def pid_and_square(value: int) -> tuple[int, int]:
    return os.getpid(), value * value


def fail(message: str) -> None:
    raise DataError(message)


def test_inline_calls_run_when_their_result_is_asked_for():
    calls = []
    job = INLINE.submit(calls.append, 3)
    assert calls == []  # not yet
    assert job.result() is None and calls == [3]
    assert job.result() is None and calls == [3]  # once
    assert not INLINE.parallel


def test_a_worker_runs_calls_in_another_process():
    with Background(workers=True) as background:
        assert background.parallel
        first, second = background.submit(pid_and_square, 7), background.submit(pid_and_square, 8)
        (pid, square), (pid_again, square_again) = first.result(), second.result()
    assert (square, square_again) == (49, 64)
    assert pid != os.getpid() and pid == pid_again  # one worker, not this process


@pytest.mark.parametrize("workers", [False, True], ids=["inline", "worker"])
def test_a_calls_error_is_raised_where_its_result_is_asked_for(workers):
    with Background(workers=workers) as background:
        job = background.submit(fail, "no such rig")
        for _ in range(2):  # and again, the same
            with pytest.raises(DataError, match="no such rig"):
                job.result()


def test_closing_ends_the_worker():
    background = Background(workers=True)
    background.submit(pid_and_square, 2).result()
    background.close()
    assert not background.parallel
    background.close()  # twice is fine


@pytest.mark.parametrize(("setting", "expected"), [("0", False), ("off", False), ("1", True)])
def test_the_environment_turns_the_worker_on_or_off(monkeypatch, setting, expected):
    monkeypatch.setenv("RIGOPT_WORKERS", setting)
    assert wanted() is expected


def imported(module: str) -> bool:
    import sys

    return module in sys.modules


def test_later_imports_follow_the_first_call():
    with Background(workers=True, later_imports=("rigopt.report.palette",)) as background:
        assert background.submit(imported, "rigopt.report.palette").result() is False  # the first call: not yet
        assert background.submit(imported, "rigopt.report.palette").result() is True  # then imported


def die() -> None:
    os._exit(3)


def test_a_worker_that_dies_is_an_error_not_a_wait():
    from concurrent.futures.process import BrokenProcessPool

    with Background(workers=True) as background:
        with pytest.raises(BrokenProcessPool):
            background.submit(die).result()


def test_closing_ends_a_call_still_running():
    import time

    background = Background(workers=True)
    pid, _ = background.submit(pid_and_square, 1).result()
    background.submit(time.sleep, 600)  # never asked for
    background.close()  # returns without waiting for it: the worker is ended
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)
