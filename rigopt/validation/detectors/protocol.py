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
         ``raw_visible`` the objects the test rig sees (``rigopt.validation.synthetic.evaluation``). Results files made
         before the fixed set hold only ``mAP`` and ``raw`` (then scored against the seen objects).

A finished results file is skipped when the matrix is run again, and training resumes from its
checkpoint, so an interrupted matrix picks up where it stopped. Training runs and test jobs can run in a
local process pool (``workers``) or as Ray tasks (a Ray address; the data and runs folders must then be
reachable by every worker).
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Callable, Sequence

from rigopt.validation.detectors.config import ModelConfig
from rigopt.errors import RigoptError

TRAIN_SPLIT, TEST_SPLIT = "train", "test"


def run_folder(runs, family: str, rig: str) -> Path:
    return Path(runs) / family / rig


def results_path(out, family: str, rig: str) -> Path:
    return Path(out) / family / f"trained_on_{rig}.json"


def train_on(data, rig: str, config: ModelConfig, runs, device: str = "cpu", seed: int = 0,
             progress: Callable = lambda epoch, step, steps, loss: None):
    """Train ``config`` on ``<data>/<rig>/train`` in ``run_folder(runs, family, rig)`` (resuming); a TrainingRun."""
    from rigopt.validation.detectors.data import RigSplit
    from rigopt.validation.detectors.training import train

    split = RigSplit(data, rig, TRAIN_SPLIT, config.image_size, depths=config.depth_weight > 0)
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
    from rigopt.validation.detectors.data import RigSplit
    from rigopt.validation.detectors.inference import match_split
    from rigopt.validation.detectors.models import load_checkpoint, model_from_checkpoint

    model, config = model_from_checkpoint(load_checkpoint(checkpoint, family))
    return {rig: match_split(model, RigSplit(data, rig, split_name, config.image_size, depths=False), device)
            for rig in rigs}


def score_models_on(data, rig: str, checkpoints: dict, device: str = "cpu", family: str | None = None,
                   split_name: str = TEST_SPLIT) -> dict:
    """{name: metrics dict} of every checkpoint of ``checkpoints`` ({name: path}) on ``<data>/<rig>/<split_name>``;
    the split's images are decoded once for all of them (once per image size the models take)."""
    from rigopt.validation.detectors.data import RigSplit
    from rigopt.validation.detectors.inference import match_split
    from rigopt.validation.detectors.models import load_checkpoint, model_from_checkpoint

    splits, metrics = {}, {}
    for name, checkpoint in checkpoints.items():
        model, config = model_from_checkpoint(load_checkpoint(checkpoint, family))
        if config.image_size not in splits:
            splits[config.image_size] = RigSplit(data, rig, split_name, config.image_size, depths=False)
        metrics[name] = match_split(model, splits[config.image_size], device).metrics()
    return metrics


def matrix_rows(data, trained: Sequence[str], tests: Sequence[str], family: str, runs, device: str = "cpu",
                ray_address: str | None = None, workers: int = 1) -> list[dict]:
    """The matrix rows (results file contents) of the models trained on each rig of ``trained`` (their runs
    under ``runs``), each tested on every rig of ``tests``: one job per test rig, which decodes its split once
    for every model (``bench.cluster.run_tasks``: here, in ``workers`` processes, or as Ray tasks)."""
    from rigopt.validation.synthetic.cluster import run_tasks
    from rigopt.validation.detectors.models import load_checkpoint

    if not trained:
        return []
    checkpoints = {rig: str((run_folder(runs, family, rig) / "checkpoint.pt").resolve()) for rig in trained}
    calls = {test: (str(Path(data).resolve()), test, checkpoints, device, family) for test in tests}
    gpus = 1 if str(device).startswith("cuda") else 0
    by_test = dict(run_tasks(score_models_on, calls, ray_address, workers, gpus, what="testing on"))
    rows = []
    for rig in trained:
        state = load_checkpoint(checkpoints[rig], family)
        rows.append({"model": family, "trained_on": rig,
                     "results": {test: {"metrics": by_test[test][rig]} for test in tests},
                     "training": {"epochs": state["epoch"], "seed": state["seed"], "config": state["config"]}})
    return rows


def write_results(out, row: dict) -> Path:
    path = results_path(out, row["model"], row["trained_on"])
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_suffix(".tmp")
    temporary.write_text(json.dumps(row, indent=1) + "\n")
    temporary.replace(path)
    return path


def check_splits(data, rigs: Sequence[str]) -> None:
    """Raise before any training if some rig lacks its train or test split."""
    from rigopt.validation.detectors.data import split_root

    for rig in rigs:
        for split in (TRAIN_SPLIT, TEST_SPLIT):
            split_root(data, rig, split)


def transfer_matrix(data, rigs: Sequence[str], config: ModelConfig, out, runs=None, device: str = "cpu",
                    seed: int = 0, ray_address: str | None = None,
                    progress: Callable[[str], None] = lambda message: None,
                    step_progress: Callable = lambda epoch, step, steps, loss: None, workers: int = 1) -> list[Path]:
    """Train on every rig of ``rigs``, test on all of them, and write one results file per training rig.

    Rows whose results file exists are kept as they are. First every missing row's model is trained (or its
    finished run loaded), then all are tested, one job per test rig (:func:`matrix_rows`); jobs run here one
    after another, in ``workers`` processes of this machine (sharing ``device``: several small runs keep one
    GPU busier than one), or as Ray tasks with ``ray_address``. ``progress(message)`` tells of each training
    and row and, when run here in order, ``step_progress(epoch, step, total_steps, loss)`` of each training
    step. Returns the results files in ``rigs`` order.
    """
    from rigopt.validation.synthetic.cluster import run_tasks

    rigs = list(dict.fromkeys(rigs))
    if not rigs:
        raise RigoptError("the matrix needs at least one rig (--rigs R1 R1-c6 ...)")
    runs = Path(runs) if runs is not None else Path(data) / "runs"
    check_splits(data, rigs)
    todo = [rig for rig in rigs if not results_path(out, config.family, rig).is_file()]
    for rig in rigs:
        if rig not in todo:
            progress(f"{config.family} trained on {rig}: results exist, kept")
    parallel = bool(ray_address) or (workers > 1 and len(todo) > 1)
    # Jobs get absolute paths (a Ray worker's folder is not ours) and no step callback (it cannot travel).
    calls = {rig: (str(Path(data).resolve()), rig, config, str(runs.resolve()), device, seed,
                   *(() if parallel else (step_progress,))) for rig in todo}
    gpus = 1 if str(device).startswith("cuda") else 0
    for rig, run in run_tasks(train_on, calls, ray_address, workers, gpus, what="training on"):
        progress(f"{config.family} trained on {rig}: {run.epochs} epochs, {run.steps_now} steps now")
    for row in matrix_rows(data, todo, rigs, config.family, runs, device, ray_address, workers):
        write_results(out, row)
        own = row["results"][row["trained_on"]]["metrics"]["mAP"]
        progress(f"{config.family} trained on {row['trained_on']}: done, mAP on its own test split "
                 + ("n/a" if own is None else f"{own:.3f}"))
    return [results_path(out, config.family, rig) for rig in rigs]


def configured(config: ModelConfig, epochs: int | None) -> ModelConfig:
    """``config`` with ``epochs`` if given."""
    if epochs is None:
        return config
    if epochs < 1:
        raise RigoptError(f"--epochs must be at least 1, got {epochs}")
    return replace(config, epochs=epochs)
