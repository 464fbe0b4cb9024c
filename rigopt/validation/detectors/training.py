"""Training a detector on one rig's train split: seeded, checkpointed every epoch, resumable.

A run folder holds ``checkpoint.pt`` (see ``models.py``) and ``train_log.csv`` (one row per step: epoch,
step, loss, its terms, learning rate, elapsed seconds). Rerunning with the same folder resumes after the
last finished epoch (log rows past it are dropped); asking for more epochs than were run continues.

Determinism: weights are initialised from ``seed``; the sample order of epoch e is a permutation drawn
from ``numpy.random.default_rng([seed, e])`` (and step s's augmentation from ``[seed, e, s]``); the learning rate is a pure function of the step (linear
warm-up, then cosine decay to 5 % over all epochs). So an interrupted and resumed run takes the same steps.
A run extended to more epochs keeps its finished steps; its remaining steps follow the schedule of the new
total, so it differs slightly from a run asked for that total from the start.
"""

from __future__ import annotations

import csv
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import torch

from rigopt.validation.detectors.config import ModelConfig
from rigopt.validation.detectors.data import RigSplit, augment
from rigopt.validation.detectors.families import Detector
from rigopt.validation.detectors.models import build_model, check_compatible, load_checkpoint, resolve_device, save_checkpoint

WARMUP_STEPS = 50
GRADIENT_CLIP = 10.0


@dataclass(frozen=True)
class TrainingRun:
    """What a training call did: run folder, epochs finished in total, steps taken now, final epoch's mean
    loss, seconds spent now, and training throughput (samples/s) now."""

    folder: Path
    epochs: int
    steps_now: int
    final_loss: float
    seconds: float
    samples_per_second: float

    @property
    def checkpoint(self) -> Path:
        return self.folder / "checkpoint.pt"


def learning_rate(config: ModelConfig, step: int, total_steps: int) -> float:
    """The learning rate at ``step`` of ``total_steps`` (warm-up, then cosine to 5 % of ``config.lr``)."""
    if step < WARMUP_STEPS:
        return config.lr * (step + 1) / WARMUP_STEPS
    progress = min(1.0, (step - WARMUP_STEPS) / max(1, total_steps - WARMUP_STEPS))
    return config.lr * (0.05 + 0.95 * 0.5 * (1 + math.cos(math.pi * progress)))


def train(split: RigSplit, config: ModelConfig, folder, device: str = "cpu", seed: int = 0,
          progress: Callable[[int, int, int, float], None] = lambda epoch, step, steps, loss: None) -> TrainingRun:
    """Train (or resume training) ``config`` on ``split`` in ``folder``; ``progress(epoch, step, total_steps,
    loss)`` after every step."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    target = resolve_device(device)
    path, log_path = folder / "checkpoint.pt", folder / "train_log.csv"
    torch.manual_seed(seed)
    model: Detector = build_model(config).to(target)
    optimizer = torch.optim.AdamW(model.parameters(), lr=config.lr, weight_decay=config.weight_decay)
    epoch = step = 0
    if path.is_file():
        state = load_checkpoint(path)
        check_compatible(state, config, split.rig, split.channels, path)
        model.load_state_dict(state["model"])
        optimizer.load_state_dict(state["optimizer"])
        epoch, step = state["epoch"], state["step"]
    _trim_log(log_path, step)

    steps_per_epoch = math.ceil(len(split) / config.batch_size)
    total_steps = steps_per_epoch * config.epochs
    started, steps_now, samples_now, epoch_losses = time.perf_counter(), 0, 0, []
    with open(log_path, "a", newline="") as log:
        writer = csv.writer(log)
        while epoch < config.epochs:
            model.train()
            order = np.random.default_rng([seed, epoch]).permutation(len(split))
            epoch_losses = []
            for batch in split.batches(config.batch_size, order):
                rate = learning_rate(config, step, total_steps)
                for group in optimizer.param_groups:
                    group["lr"] = rate
                if config.bev_augment:
                    batch = augment(batch, np.random.default_rng([seed, epoch, step]))
                batch = batch.to(target)
                loss, parts = model.loss(model(batch), batch)
                optimizer.zero_grad(set_to_none=True)
                loss.backward()
                torch.nn.utils.clip_grad_norm_(model.parameters(), GRADIENT_CLIP)
                optimizer.step()
                step += 1
                steps_now += 1
                samples_now += len(batch.tokens)
                epoch_losses.append(float(loss.detach()))
                if log.tell() == 0:
                    writer.writerow(["epoch", "step", "loss", *parts, "lr", "seconds"])
                writer.writerow([epoch, step, f"{epoch_losses[-1]:.6g}", *(f"{v:.6g}" for v in parts.values()),
                                 f"{rate:.6g}", f"{time.perf_counter() - started:.3f}"])
                progress(epoch, step, total_steps, epoch_losses[-1])
            epoch += 1
            log.flush()
            save_checkpoint(path, {"family": config.family, "config": config.to_dict(), "rig": split.rig,
                                   "channels": list(split.channels), "epoch": epoch, "step": step, "seed": seed,
                                   "model": model.state_dict(), "optimizer": optimizer.state_dict()})
    seconds = time.perf_counter() - started
    return TrainingRun(folder, epoch, steps_now, float(np.mean(epoch_losses)) if epoch_losses else float("nan"),
                       seconds, samples_now / seconds if steps_now and seconds > 0 else float("nan"))


def _trim_log(log_path: Path, step: int) -> None:
    """Keep the log's header and its rows up to ``step`` (rows past the checkpoint are redone)."""
    if not log_path.is_file():
        return
    with open(log_path, newline="") as handle:
        rows = list(csv.reader(handle))
    kept = rows[:1] + [row for row in rows[1:] if row and int(row[1]) <= step]
    with open(log_path, "w", newline="") as handle:
        csv.writer(handle).writerows(kept if step else [])
