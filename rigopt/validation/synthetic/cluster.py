"""Running independent jobs in parallel: rendering (rig, scene) pairs, training rigs.

Two ways, one interface (:func:`run_tasks`): ``--workers N`` runs the jobs in N processes on this machine,
``--ray ADDRESS`` as Ray tasks on a cluster. Every job reads and writes the benchmark folder itself, so on a
cluster of several machines that folder must be on storage every node sees (the same path everywhere). Ray's
'local' starts a Ray instance on this machine.
"""

from __future__ import annotations

from typing import Callable, Hashable, Iterator

from rigopt.errors import DataError, RigoptError


def run_tasks(function: Callable, calls: dict[Hashable, tuple], ray_address: str | None = None, workers: int = 1,
              gpus: float = 0, what: str = "task") -> Iterator[tuple[Hashable, object]]:
    """``function(*calls[key])`` for every key, yielded as (key, result) as the jobs finish: as Ray tasks with
    ``ray_address`` (each asking for ``gpus`` GPUs), else in ``workers`` local processes, else here in order."""
    if ray_address:
        yield from ray_tasks(ray_address, function, calls, gpus, what)
    elif workers > 1 and len(calls) > 1:
        yield from process_tasks(workers, function, calls, what)
    else:
        for key, arguments in calls.items():
            yield key, function(*arguments)


def process_tasks(workers: int, function: Callable, calls: dict[Hashable, tuple],
                  what: str = "task") -> Iterator[tuple[Hashable, object]]:
    """Run ``function(*calls[key])`` in a pool of ``workers`` fresh (spawned) processes on this machine; yields
    (key, result) as the jobs finish. A job's RigoptError is raised again as itself; any other failure as a
    DataError naming the ``what`` of its key. Spawned, not forked: a worker may use CUDA. The workers ignore
    Ctrl-C and end with this process: on any exception here (an interrupt too) they are terminated at once, and
    one whose parent dies gets SIGTERM (:func:`rigopt.background.worker_setup`)."""
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    from rigopt.background import end_workers, worker_setup

    context = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(max_workers=min(workers, len(calls)), mp_context=context, initializer=worker_setup)
    try:
        pending = {pool.submit(function, *arguments): key for key, arguments in calls.items()}
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                key = pending.pop(future)
                try:
                    result = future.result()
                except RigoptError:
                    raise
                except Exception as error:
                    raise DataError(f"{what} {key} failed in a worker process: {error}") from None
                yield key, result
    except BaseException:  # Ctrl-C, SIGTERM, a failed job, the caller stopping early: end the workers now
        end_workers(pool)
        raise
    pool.shutdown()


def ray_tasks(address: str, function: Callable, calls: dict[Hashable, tuple], gpus: float = 0,
              what: str = "task") -> Iterator[tuple[Hashable, object]]:
    """Run ``function(*calls[key])`` for every key as a Ray task on the cluster at ``address``; yields (key,
    result) as the tasks finish. A task's RigoptError is raised again as itself; any other failure as a
    DataError naming the ``what`` of its key."""
    try:
        import ray
    except ImportError:
        raise RigoptError("--ray needs the ray package: pip install ray") from None
    try:
        ray.init(address=None if address == "local" else address, ignore_reinit_error=True,
                 include_dashboard=False, log_to_driver=False)
    except Exception as error:  # ray raises ConnectionError and others for an unreachable cluster
        raise RigoptError(f"--ray {address}: cannot connect to a Ray cluster ({error})") from None
    task = ray.remote(num_gpus=gpus)(function)
    pending = {task.remote(*arguments): key for key, arguments in calls.items()}
    while pending:
        done, _ = ray.wait(list(pending), num_returns=1)
        key = pending.pop(done[0])
        try:
            result = ray.get(done[0])
        except Exception as error:
            cause = getattr(error, "cause", None)
            if isinstance(cause, RigoptError):
                raise type(cause)(str(cause)) from None
            raise DataError(f"Ray {what} {key} failed: {error}") from None
        yield key, result
