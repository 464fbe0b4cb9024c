"""The detectors rigopt ships, and measuring any rig's transfer drop with them (no training, no data).

``rigopt validate RIG --ref R1 --model lss`` without ``--data`` renders the reference's test scenes under RIG
(cached) and scores the shipped models trained on the reference, one per training seed.

Shipped layout (``detectors/<family>-<reference>/``, found by :func:`rigopt.resources.data_dir`, or under
``$RIGOPT_DETECTORS`` when set: a folder of your own packed models, :func:`pack`):

- ``seed<k>.pt``: a checkpoint without optimizer state, weights stored as float16 (loaded into float32);
- ``card.json``: family, reference, the recipe (model config, epochs, steps), the training and test data
  (split, scenes, samples per scene, scene seed offset, image size), and per seed the file, the training
  time and the model's own mAP on the reference's test split (fixed set and visible only);
- ``bootstrap.npz``: the same scores under every scene resample of the card's ``bootstrap`` (resamples, seed,
  blocks; arrays ``seed<k>_mAP`` and ``seed<k>_mAP_visible``), so that a rig's drop is resampled paired with the
  reference without rendering the reference again.

Cache: ``<cache>/<rig name>-<geometry key>/test/``, a benchmark split as ``rigopt bench generate`` writes it;
the key hashes the rig as rendered (cameras, lenses, vehicle, frame), so a changed rig file never reuses old
renderings, and an interrupted rendering resumes.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from rigopt.errors import DataError
from rigopt.resources import data_dir
from rigopt.rig.model import Rig

CARD = "card.json"
BOOTSTRAP = "bootstrap.npz"


def default_cache() -> Path:
    """``$RIGOPT_HOME/cache/validate`` (default ``~/.rigopt/cache/validate``)."""
    return Path(os.environ.get("RIGOPT_HOME", Path.home() / ".rigopt")) / "cache" / "validate"


@dataclass(frozen=True)
class ShippedDetector:
    """One shipped family trained on one reference rig: ``folder`` and its parsed ``card``."""

    folder: Path
    card: dict

    @property
    def family(self) -> str:
        return self.card["family"]

    @property
    def reference(self) -> str:
        return self.card["reference"]

    @property
    def seeds(self) -> list[int]:
        return sorted(int(seed) for seed in self.card["seeds"])

    def checkpoint(self, seed: int) -> Path:
        return self.folder / self.card["seeds"][str(seed)]["file"]

    def size_bytes(self) -> int:
        return sum(self.checkpoint(seed).stat().st_size for seed in self.seeds)


def detectors_root() -> Path | None:
    """``$RIGOPT_DETECTORS`` when set, else the shipped ``detectors/`` folder (None if this installation has none)."""
    if os.environ.get("RIGOPT_DETECTORS"):
        return Path(os.environ["RIGOPT_DETECTORS"])
    try:
        return data_dir("detectors")
    except FileNotFoundError:
        return None


def shipped_names() -> list[str]:
    """``<family>-<reference>`` of every shipped detector."""
    root = detectors_root()
    return sorted(p.parent.name for p in root.glob(f"*/{CARD}")) if root is not None else []


def shipped_detector(family: str, reference: str) -> ShippedDetector:
    """The shipped ``family`` models trained on ``reference``; a DataError that lists what ships otherwise."""
    name = f"{family}-{reference}"
    if name not in shipped_names():
        listed = ", ".join(shipped_names()) or "none"
        raise DataError(f"rigopt ships no {family} models trained on {reference} (shipped: {listed}); pass --data "
                        f"with a benchmark folder holding a trained run (rigopt bench generate, rigopt bench train)")
    folder = detectors_root() / name
    return ShippedDetector(folder, json.loads((folder / CARD).read_text()))


def rig_key(rig: Rig) -> str:
    """12 hex digits that change with anything that changes the rig's renderings (its file form in its vehicle's
    centre frame, vehicle included), not with its name."""
    from rigopt.rig.pccr_format import rig_to_dict
    from rigopt.vehicle.placement import in_vehicle_frame

    placed, _ = in_vehicle_frame(rig)
    data = rig_to_dict(placed)
    text = json.dumps({"vehicle": data.get("vehicle_type"), "cameras": data["cameras"], "origin": data.get("origin")},
                      sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def cache_name(rig: Rig) -> str:
    """The cache folder of a rig: its name (letters, digits, ._- kept) and :func:`rig_key`."""
    safe = re.sub(r"[^A-Za-z0-9._-]+", "_", rig.name).strip("._") or "rig"
    return f"{safe[:60]}-{rig_key(rig)}"


def test_scenes(detector: ShippedDetector):
    """The reference's test scenes the shipped models were scored on."""
    from rigopt.validation.synthetic.scenes import split_scenes

    test = detector.card["test_data"]
    return split_scenes(test["split"], test["scenes"], test["frames"], test["seed_offset"])


def render_cached(rigs: Sequence[Rig], detector: ShippedDetector, cache: Path, workers: int = 1,
                  progress: Callable[[str], None] = lambda message: None) -> list[str]:
    """Render the reference's test scenes under each rig into ``cache`` (what is there is kept); returns the
    rigs' folder names there."""
    import dataclasses

    from rigopt.validation.synthetic.generate import ego_body_lookup, generate_split
    from rigopt.validation.synthetic.render import render_rig

    named = [dataclasses.replace(rig, name=cache_name(rig)) for rig in rigs]
    size = tuple(detector.card["test_data"]["image_size"])
    generate_split(named, test_scenes(detector), cache, size, render_rig, ego_body_lookup(progress), progress,
                   workers=workers)
    return [rig.name for rig in named]


def measure(rigs: Sequence[Rig], detector: ShippedDetector, cache: Path | None = None, device: str = "cpu",
            workers: int = 1, progress: Callable[[str], None] = lambda message: None) -> list[dict]:
    """Each rig's measured drop with every shipped seed: a list (one per rig) of JSON-ready dicts.

    Per seed: ``mAP`` and ``mAP_visible`` on the reference's test scenes rendered under the rig, the reference's
    own (from the card), the relative drops and their 95 % intervals over the card's scene resamples (paired
    with the reference's scores under the same resamples: test noise only). Over the seeds: the mean drops and
    the interval of the mean drop over the same resamples. Each seed's entry keeps its (resamples,) fixed-set
    drops under those resamples (``resampled_drops``, an array: :func:`paired_differences` pairs two rigs by
    them; :func:`without_resamples` before writing JSON). Rendering runs in ``workers`` processes, and so does
    scoring on the CPU (one seed's model per process, the cores shared among them; on a GPU one process).
    """
    from rigopt.validation.synthetic.evaluation import interval
    from rigopt.validation.synthetic.cluster import run_tasks

    cache = Path(cache) if cache is not None else default_cache()
    folders = render_cached(rigs, detector, cache, workers, progress)
    # On the CPU with workers > 1, one process per seed, the cores shared among them: on 2 cores three
    # one-thread processes finish sooner than two (the third seed would run alone on one core) or than one
    # two-thread process in turn (a second thread speeds a small network up 1.75x, not 2x).
    scorers = 1 if device != "cpu" or workers <= 1 else len(detector.seeds)
    threads = max(1, (os.cpu_count() or 1) // scorers)
    results = []
    for rig, folder in zip(rigs, folders):
        progress(f"{rig.name}: scoring {len(detector.seeds)} {detector.family} model(s)"
                 + (f" in {scorers} processes" if scorers > 1 else ""))
        calls = {seed: (detector, seed, cache, folder, device, threads if scorers > 1 else None)
                 for seed in detector.seeds}
        scored = dict(run_tasks(score_seed, calls, workers=scorers, what="scoring seed"))
        seeds = {str(seed): {**scored[seed][0], "resampled_drops": scored[seed][1]} for seed in detector.seeds}
        resampled_drops = [scored[seed][1] for seed in detector.seeds]
        resampled_visible = [scored[seed][2] for seed in detector.seeds]
        results.append({
            "rig": rig.name, "n_cameras": len(rig), "cache": str(cache / folder), "seeds": seeds,
            "drop": float(np.mean([s["drop"] for s in seeds.values()])),
            "drop_ci": interval(np.mean(resampled_drops, axis=0)),
            "drop_visible": float(np.mean([s["drop_visible"] for s in seeds.values()])),
            "drop_visible_ci": interval(np.mean(resampled_visible, axis=0))})
    return results


def without_resamples(entry: dict) -> dict:
    """A :func:`measure` entry without its seeds' ``resampled_drops`` arrays: JSON-ready."""
    return {**entry, "seeds": {seed: {key: value for key, value in fields.items() if key != "resampled_drops"}
                               for seed, fields in entry["seeds"].items()}}


def paired_differences(first: dict, other: dict) -> dict:
    """``first`` minus ``other`` (two entries of :func:`measure`, scored on the same scene resamples): per seed
    the difference of the fixed-set drops and its 95 % paired interval (test noise only), and over the seeds the
    mean difference and the interval of the mean. Below 0: ``first`` loses less."""
    from rigopt.validation.synthetic.evaluation import interval

    seeds, resampled = {}, []
    for seed, entry in first["seeds"].items():
        gap = entry["resampled_drops"] - other["seeds"][seed]["resampled_drops"]
        resampled.append(gap)
        seeds[seed] = {"difference": entry["drop"] - other["seeds"][seed]["drop"], "ci": interval(gap)}
    return {"rig": other["rig"], "seeds": seeds, "difference": float(np.mean([s["difference"] for s in seeds.values()])),
            "ci": interval(np.mean(resampled, axis=0))}


def score_seed(detector: ShippedDetector, seed: int, cache: Path, folder: str, device: str = "cpu",
               threads: int | None = None) -> tuple[dict, np.ndarray, np.ndarray]:
    """One shipped model (``seed``) scored on the rendering ``cache/folder``: its JSON-ready entry (mAPs, the
    reference's, drops and their intervals) and its (resamples,) drops under the card's scene resamples, fixed
    set and visible only. ``threads``: torch's CPU threads (None: as set)."""
    import torch

    from rigopt.validation.detectors.data import RigSplit
    from rigopt.validation.detectors.inference import match_split
    from rigopt.validation.detectors.models import load_checkpoint, model_from_checkpoint
    from rigopt.validation.detectors.protocol import TEST_SPLIT
    from rigopt.validation.synthetic.evaluation import interval, sample_blocks
    from rigopt.validation.synthetic.evaluation import resampled_maps

    if threads is not None:
        torch.set_num_threads(threads)
    split = RigSplit(cache, folder, TEST_SPLIT, None, depths=False)
    blocks = sample_blocks(split.samples)
    boot = detector.card["bootstrap"]
    if len(blocks) != boot["blocks"] or len(split) != detector.card["test_data"]["samples"]:
        raise DataError(f"{cache / folder}: {len(split)} samples in {len(blocks)} scenes, not the "
                        f"{detector.card['test_data']['samples']} in {boot['blocks']} the shipped models were "
                        "scored on; delete that folder and run again")
    model = model_from_checkpoint(load_checkpoint(detector.checkpoint(seed), detector.family))[0]
    matched = match_split(model, split, device)
    own = detector.card["seeds"][str(seed)]
    entry = {"mAP": matched.evaluation().map, "mAP_visible": matched.evaluation(visible_only=True).map}
    with np.load(detector.folder / BOOTSTRAP) as stored:
        reference_maps = {key: stored[f"seed{seed}_mAP{key}"] for key in ("", "_visible")}
    drops = []
    for key, visible in (("", False), ("_visible", True)):
        maps = resampled_maps([matched], blocks, boot["resamples"], boot["seed"], visible_only=visible)[:, 0]
        drops.append((reference_maps[key] - maps) / reference_maps[key])
        entry[f"reference_mAP{key}"] = own[f"mAP{key}"]
        entry[f"drop{key}"] = (own[f"mAP{key}"] - entry[f"mAP{key}"]) / own[f"mAP{key}"]
        entry[f"drop{key}_ci"] = interval(drops[-1])
    return entry, drops[0], drops[1]


def pack(runs: dict[int, Path], data: Path, out: Path, recipe: dict, train_data: dict,
         resamples: int = 1000, bootstrap_seed: int = 0, device: str = "cpu",
         progress: Callable[[str], None] = lambda message: None) -> ShippedDetector:
    """Write a shipped detector folder ``out`` from trained run folders ``runs`` {seed: folder holding
    checkpoint.pt, train_log.csv} whose reference's test split is in ``data``: float16 weights, the card with each
    seed's own mAP measured with the packed weights. ``recipe`` and ``train_data`` go into the card as given."""
    from rigopt.validation.detectors.data import RigSplit
    from rigopt.validation.detectors.inference import match_split
    from rigopt.validation.detectors.models import (
        load_checkpoint,
        model_from_checkpoint,
        save_checkpoint,
    )
    from rigopt.validation.detectors.protocol import TEST_SPLIT
    from rigopt.validation.synthetic.evaluation import sample_blocks
    from rigopt.validation.synthetic.evaluation import resampled_maps
    from rigopt.validation.synthetic.generate import split_layout
    from rigopt.output import atomic_folder

    states = {seed: load_checkpoint(Path(folder) / "checkpoint.pt") for seed, folder in runs.items()}
    first = next(iter(states.values()))
    family, reference = first["family"], first["rig"]
    scenes, size = split_layout(Path(data) / reference / TEST_SPLIT)
    split = RigSplit(data, reference, TEST_SPLIT, None, depths=False)
    blocks = sample_blocks(split.samples)
    card = {"family": family, "reference": reference, "recipe": recipe, "train_data": train_data,
            "test_data": {"split": TEST_SPLIT, "scenes": len(scenes), "frames": len(scenes[0].frames),
                          "seed_offset": _seed_offset(scenes), "image_size": list(size), "samples": len(split)},
            "bootstrap": {"resamples": resamples, "seed": bootstrap_seed, "blocks": len(blocks), "unit": "scene"},
            "seeds": {}}
    resampled = {}
    with atomic_folder(out, force=True) as work:
        for seed, state in states.items():
            if (state["family"], state["rig"]) != (family, reference):
                raise DataError(f"{runs[seed]}: trained as {state['family']} on {state['rig']}, not {family} on {reference}")
            slim = {key: state[key] for key in ("family", "config", "rig", "channels", "epoch", "step", "seed")}
            slim["model"] = {k: v.half() if v.is_floating_point() else v for k, v in state["model"].items()}
            path = work / f"seed{seed}.pt"
            save_checkpoint(path, slim)
            progress(f"scoring seed {seed} on {reference}'s test split")
            model = model_from_checkpoint(load_checkpoint(path, family))[0]
            matched = match_split(model, split, device)
            if not matched.evaluation().map > 0:
                raise DataError(f"{runs[seed]}: seed {seed} scores mAP 0 on {reference}'s test split; a drop needs a "
                                "model that detects something: train it longer")
            card["seeds"][str(seed)] = {
                "file": path.name, "epochs": state["epoch"], "steps": state["step"],
                "training_minutes": round(training_seconds(Path(runs[seed]) / "train_log.csv") / 60, 1),
                "mAP": matched.evaluation().map, "mAP_visible": matched.evaluation(visible_only=True).map}
            for key, visible in (("", False), ("_visible", True)):
                resampled[f"seed{seed}_mAP{key}"] = resampled_maps([matched], blocks, resamples, bootstrap_seed,
                                                                   visible_only=visible)[:, 0]
        np.savez(work / BOOTSTRAP, **resampled)
        card["size_bytes"] = sum((work / f"seed{seed}.pt").stat().st_size for seed in states)
        (work / CARD).write_text(json.dumps(card, indent=1) + "\n")
    return ShippedDetector(Path(out), card)


def training_seconds(log: Path) -> float:
    """Seconds a run trained in all, from its train_log.csv: each resumed session restarts the seconds column,
    so the total is the sum of each session's last value."""
    import csv

    with open(log, newline="") as handle:
        seconds = [float(row["seconds"]) for row in csv.DictReader(handle)]
    ends = [a for a, b in zip(seconds, seconds[1:]) if b < a]
    return float(sum(ends) + (seconds[-1] if seconds else 0.0))


def _seed_offset(scenes) -> int:
    """The scene seed offset of a generated split (its first scene's seed against the split's first)."""
    from rigopt.validation.synthetic.scenes import SEED_OFFSET_STEP, split_seeds

    seed = int(scenes[0].name.rsplit("-s", 1)[1])
    return (seed - split_seeds(scenes[0].split, 1)[0]) // SEED_OFFSET_STEP
