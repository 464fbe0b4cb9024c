"""Running independent jobs as Ray tasks (``--ray ADDRESS``): rendering (rig, scene) pairs, training rigs.

Every task reads and writes the benchmark folder itself, so on a cluster of several machines that folder
must be on storage every node sees (the same path everywhere). 'local' starts a Ray instance on this machine.
"""

from __future__ import annotations

from typing import Callable, Hashable, Iterator

from rigopt.errors import DataError, RigoptError


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
