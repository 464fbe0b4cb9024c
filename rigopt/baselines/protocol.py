"""The cross-rig protocol of the PCCR benchmark: train on each rig, test on every rig, write the results.

Folders:
  runs   ``<runs>/<model>/<rig>/`` per training run (checkpoint.pt, train_log.csv); defaults to
         ``<data>/runs``, so ``bench train``, ``bench matrix`` and ``validate`` share trained models.
  out    ``<out>/<model>/trained_on_<rig>.json``, the benchmark's own layout::

             {"model": "lss", "trained_on": "R1",
              "results": {"R1-c6": {"metrics": {"mAP": 0.31, "mAP_visible": 0.35,
                                                "raw": {"car_AP_dist_0.5": ...}, "raw_visible": {...}}}, ...}}

         which ``rigopt calibrate --results <out>`` reads unchanged. ``mAP`` and ``raw`` score the fixed
         set (every annotated object, an object in the test rig's blind zone included), ``mAP_visible`` and
         ``raw_visible`` the objects the test rig sees (``rigopt.bench.evaluation``). Results files made
         before the fixed set hold only ``mAP`` and ``raw`` (then scored against the seen objects).

A finished results file is skipped when the matrix is run again, and training resumes from its
checkpoint, so an interrupted matrix picks up where it stopped. With a Ray address each training run
(and its tests) is one Ray task; the data and runs folders must then be reachable by every worker.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Callable, Sequence

from rigopt.baselines.config import ModelConfig
from rigopt.errors import RigoptError

TRAIN_SPLIT, TEST_SPLIT = "train", "test"


def run_folder(runs, family: str, rig: str) -> Path:
    return Path(runs) / family / rig


def results_path(out, family: str, rig: str) -> Path:
    return Path(out) / family / f"trained_on_{rig}.json"


def train_on(data, rig: str, config: ModelConfig, runs, device: str = "cpu", seed: int = 0,
             progress: Callable = lambda epoch, step, steps, loss: None):
    """Train ``config`` on ``<data>/<rig>/train`` in ``run_folder(runs, family, rig)`` (resuming); a TrainingRun."""
    from rigopt.baselines.data import RigSplit
    from rigopt.baselines.training import train

    split = RigSplit(data, rig, TRAIN_SPLIT, config.image_size)
    return train(split, config, run_folder(runs, config.family, rig), device, seed, progress)


def evaluate_on(checkpoint, data, rig: str, device: str = "cpu", family: str | None = None,
                split_name: str = TEST_SPLIT) -> dict:
    """The benchmark's metrics dict ({"mAP", "mAP_visible", "raw", "raw_visible"}; see
    ``MatchedDetections.metrics``) of a checkpoint on ``<data>/<rig>/<split_name>``."""
    return evaluate_on_rigs(checkpoint, data, [rig], device, family, split_name)[rig]


def evaluate_on_rigs(checkpoint, data, rigs: Sequence[str], device: str = "cpu", family: str | None = None,
                     split_name: str = TEST_SPLIT) -> dict:
    """{rig: metrics dict} of a checkpoint, loaded once, on ``<data>/<rig>/<split_name>`` of every rig."""
    matched = match_on_rigs(checkpoint, data, rigs, device, family, split_name)
    return {rig: matched[rig].metrics() for rig in rigs}


def match_on_rigs(checkpoint, data, rigs: Sequence[str], device: str = "cpu", family: str | None = None,
                  split_name: str = TEST_SPLIT) -> dict:
    """{rig: MatchedDetections} of a checkpoint, loaded once, on ``<data>/<rig>/<split_name>`` of every rig."""
    from rigopt.baselines.data import RigSplit
    from rigopt.baselines.inference import match_split
    from rigopt.baselines.models import load_checkpoint, model_from_checkpoint

    model, config = model_from_checkpoint(load_checkpoint(checkpoint, family))
    return {rig: match_split(model, RigSplit(data, rig, split_name, config.image_size), device) for rig in rigs}


def train_and_test(data, trained_on: str, tests: Sequence[str], config: ModelConfig, runs, device: str = "cpu",
                   seed: int = 0, progress: Callable = lambda epoch, step, steps, loss: None) -> dict:
    """One row of the matrix: train on ``trained_on``, then its results on every rig of ``tests``."""
    run = train_on(data, trained_on, config, runs, device, seed, progress)
    metrics = evaluate_on_rigs(run.checkpoint, data, tests, device, config.family)
    results = {test: {"metrics": metrics[test]} for test in tests}
    return {"model": config.family, "trained_on": trained_on, "results": results,
            "training": {"epochs": run.epochs, "seed": seed, "config": config.to_dict()}}


def write_results(out, row: dict) -> Path:
    path = results_path(out, row["model"], row["trained_on"])
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_suffix(".tmp")
    temporary.write_text(json.dumps(row, indent=1) + "\n")
    temporary.replace(path)
    return path


def check_splits(data, rigs: Sequence[str]) -> None:
    """Raise before any training if some rig lacks its train or test split."""
    from rigopt.baselines.data import split_root

    for rig in rigs:
        for split in (TRAIN_SPLIT, TEST_SPLIT):
            split_root(data, rig, split)


def transfer_matrix(data, rigs: Sequence[str], config: ModelConfig, out, runs=None, device: str = "cpu",
                    seed: int = 0, ray_address: str | None = None,
                    progress: Callable[[str], None] = lambda message: None,
                    step_progress: Callable = lambda epoch, step, steps, loss: None) -> list[Path]:
    """Train on every rig of ``rigs``, test on all of them, and write one results file per training rig.

    Rows whose results file exists are kept as they are. ``progress(message)`` tells of each row and, when
    run locally, ``step_progress(epoch, step, total_steps, loss)`` of each training step. Returns the
    results files in ``rigs`` order.
    """
    rigs = list(dict.fromkeys(rigs))
    if not rigs:
        raise RigoptError("the matrix needs at least one rig (--rigs R1 R1-c6 ...)")
    runs = Path(runs) if runs is not None else Path(data) / "runs"
    check_splits(data, rigs)
    todo = [rig for rig in rigs if not results_path(out, config.family, rig).is_file()]
    for rig in rigs:
        if rig not in todo:
            progress(f"{config.family} trained on {rig}: results exist, kept")
    rows = (_rows_on_ray(ray_address, data, todo, rigs, config, runs, device, seed) if ray_address else
            (train_and_test(data, rig, rigs, config, runs, device, seed, step_progress) for rig in todo))
    for row in rows:
        write_results(out, row)
        own = row["results"][row["trained_on"]]["metrics"]["mAP"]
        progress(f"{config.family} trained on {row['trained_on']}: done, mAP on its own test split "
                 + ("n/a" if own is None else f"{own:.3f}"))
    return [results_path(out, config.family, rig) for rig in rigs]


def _rows_on_ray(address: str, data, todo, rigs, config: ModelConfig, runs, device, seed):
    """Matrix rows as their Ray tasks finish, one task per training rig (``bench.cluster.ray_tasks``)."""
    from rigopt.bench.cluster import ray_tasks

    calls = {rig: (str(Path(data).resolve()), rig, rigs, config, str(Path(runs).resolve()), device, seed)
             for rig in todo}
    gpus = 1 if str(device).startswith("cuda") else 0
    for _, row in ray_tasks(address, train_and_test, calls, gpus, what="training on"):
        yield row


def configured(config: ModelConfig, epochs: int | None) -> ModelConfig:
    """``config`` with ``epochs`` if given."""
    if epochs is None:
        return config
    if epochs < 1:
        raise RigoptError(f"--epochs must be at least 1, got {epochs}")
    return replace(config, epochs=epochs)
