"""Models for any reference rig in one call (``rigopt detectors train``): render the reference's training and
test scenes, train one model per seed, and pack them as rigopt packs its own (``shipped.pack``: float16 weights,
the card with the recipe, the data and each seed's own mAP, the scene bootstrap, the quick protocol's scores).

The work folder keeps what a rerun resumes from::

    <work>/data/<rig>/{train,test}/                 the rendered splits (rigopt bench generate's layout)
    <work>/runs/seed<k>/<family>/<rig>/             each seed's checkpoint.pt and train_log.csv

A rerun of the same call skips the scenes rendered, resumes each seed after its last finished epoch, and packs
again (the pack is written whole, replacing the one before).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from rigopt.benchmark import SYNTHETIC_IMAGE_SIZE

if TYPE_CHECKING:  # the command line imports this module for the recipe's defaults: no numpy at import
    from rigopt.rig.model import Rig

#: The shipped recipe (detectors/lss-R1/card.json): 16 epochs of the small preset on 96 training scenes.
SHIPPED_EPOCHS, SHIPPED_TRAIN_SCENES = 16, 96


@dataclass(frozen=True)
class Recipe:
    """What ``rigopt detectors train`` makes: ``family`` at size preset ``size`` trained for ``epochs`` on
    ``train_scenes`` scenes of ``frames`` samples at ``image_size`` (width, height) px, one model per seed of
    ``seeds``, tested on ``test_scenes`` scenes of as many frames. The defaults are the shipped models' recipe."""

    family: str = "lss"
    size: str = "small"
    epochs: int = SHIPPED_EPOCHS
    seeds: tuple[int, ...] = (0, 1, 2)
    train_scenes: int = SHIPPED_TRAIN_SCENES
    test_scenes: int = 16
    frames: int = 40
    image_size: tuple[int, int] = SYNTHETIC_IMAGE_SIZE

    def command(self, reference: str) -> str:
        """The command line that makes this recipe's pack, for the card."""
        return (f"rigopt detectors train --ref {reference} --model {self.family} --size {self.size} --epochs "
                f"{self.epochs} --seeds {','.join(map(str, self.seeds))} --scenes {self.train_scenes} --test-scenes "
                f"{self.test_scenes} --frames {self.frames} --image-size {self.image_size[0]}x{self.image_size[1]}")


def default_work(out: Path, reference: Rig, family: str) -> Path:
    """``<out>/.work/<family>-<rig name>-<rig key>``: a reference's work folder beside its pack (the key keeps two
    rigs of one name apart)."""
    from rigopt.validation.detectors.shipped import cache_name

    return Path(out) / ".work" / f"{family}-{cache_name(reference)}"


def train_pack(reference: Rig, recipe: Recipe, out: Path, work: Path, device: str = "cpu", workers: int = 1,
               progress: Callable[[str], None] = lambda message: None,
               step: Callable = lambda epoch, step, steps, loss: None):
    """Render, train and pack ``recipe`` for ``reference`` into ``<out>/<family>-<reference>/`` (resumable
    through ``work``); returns the ``shipped.ShippedDetector``. ``progress`` hears each stage with an estimate
    of the training time left; ``step(epoch, step, total_steps, loss)`` follows each training step."""
    from rigopt.validation.detectors.config import model_config
    from rigopt.validation.detectors.protocol import configured, train_on
    from rigopt.validation.detectors.shipped import pack, training_seconds
    from rigopt.validation.synthetic.generate import ego_body_lookup, generate_split
    from rigopt.validation.synthetic.render import render_rig
    from rigopt.validation.synthetic.scenes import split_scenes

    config = configured(model_config(recipe.family, recipe.size), recipe.epochs)
    data = Path(work) / "data"
    for split, scenes in (("train", recipe.train_scenes), ("test", recipe.test_scenes)):
        progress(f"rendering {reference.name}'s {split} split: {scenes} scenes of {recipe.frames} samples")
        generate_split([reference], split_scenes(split, scenes, recipe.frames), data, tuple(recipe.image_size),
                       render_rig, ego_body_lookup(progress), progress, workers=workers)
    runs, spent = {}, []
    for k, seed in enumerate(recipe.seeds):
        left = f"; about {sum(spent) / len(spent) * (len(recipe.seeds) - k) / 60:.0f} min of training left" if spent else ""
        progress(f"training seed {seed} ({k + 1} of {len(recipe.seeds)}){left}")
        run = train_on(data, reference.name, config, Path(work) / "runs" / f"seed{seed}", device, seed,
                       _epoch_lines(step, progress, f"seed {seed}", config.epochs))
        runs[seed] = run.folder
        spent.append(training_seconds(run.folder / "train_log.csv"))  # over every session it trained in
    steps = max(1, -(-recipe.train_scenes * recipe.frames // config.batch_size)) * config.epochs
    card_recipe = {"family": config.family, "preset": recipe.size, "epochs": config.epochs,
                   "batch_size": config.batch_size, "steps": steps, "optimizer": "AdamW", "lr": config.lr,
                   "weight_decay": config.weight_decay, "schedule": "50-step linear warm-up, cosine to 5 %",
                   "bev_augment": config.bev_augment, "depth_weight": config.depth_weight,
                   "command": recipe.command(reference.name)}
    train_data = {"split": "train", "scenes": recipe.train_scenes, "frames": recipe.frames, "seed_offset": 0,
                  "image_size": list(recipe.image_size), "samples": recipe.train_scenes * recipe.frames}
    progress(f"packing {len(runs)} model(s) into {Path(out) / f'{config.family}-{reference.name}'}")
    return pack(runs, data, Path(out) / f"{config.family}-{reference.name}", card_recipe, train_data, device=device,
                progress=progress, trained_on=reference)


def _epoch_lines(step: Callable, progress: Callable[[str], None], label: str, epochs: int) -> Callable:
    """``step`` that also says, as each epoch begins, where training stands and the minutes left for this seed at
    the pace of this session (a line a log keeps, where a progress bar is not drawn)."""
    began = {"time": time.monotonic(), "step": None, "epoch": None}

    def each(epoch: int, done: int, total: int, loss: float) -> None:
        step(epoch, done, total, loss)
        if began["step"] is None:
            began["step"] = done - 1
        if epoch != began["epoch"]:
            began["epoch"] = epoch
            taken = done - began["step"] - 1  # the steps of this session before this one
            pace = (time.monotonic() - began["time"]) / max(1, taken)
            left = f"; about {pace * (total - done) / 60:.0f} min left for it" if taken else ""
            progress(f"{label}: epoch {epoch + 1} of {epochs}, step {done} of {total}, loss {loss:.3f}{left}")

    return each

