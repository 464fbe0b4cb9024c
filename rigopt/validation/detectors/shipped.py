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

A rig is measured under a protocol (:mod:`rigopt.validation.detectors.measuring`: ``full``, every frame of the
test scenes, ``quick``, every fourth, or ``quick-s1``, quick's frames of new scenes); a pack holds the reference's own scores under each (:func:`pack`, or
:func:`add_protocol` for an older pack).

Cache: ``<cache>/<rig name>-<geometry key>[-<protocol>]/test/``, a benchmark split as ``rigopt bench generate``
writes it (no suffix for ``full``); the key hashes the rig as rendered (cameras, lenses, vehicle, frame), so a
changed rig file never reuses old renderings, and an interrupted rendering resumes. Beside the split,
``scores/<detector>-seed<k>-<digest>.npz`` keeps each model's scores on it, so a rerun scores nothing twice.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from rigopt.benchmark import SYNTHETIC_IMAGE_SIZE
from rigopt.errors import DataError
from rigopt.resources import data_dir
from rigopt.rig.model import Rig
from rigopt.validation.detectors.config import EXTERNAL_FAMILY
from rigopt.validation.detectors.measuring import DEFAULT_PROTOCOL, FULL, PROTOCOLS, Protocol

CARD = "card.json"
BOOTSTRAP = "bootstrap.npz"
#: The reference rig a pack was trained on, when it is no library rig (``rigopt detectors train --ref FILE``).
REFERENCE_RIG = "rig.json"
SCORES = "scores"


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

    def scores_file(self, seed: int) -> str | None:
        """The name under which a rendering keeps model ``seed``'s scores: it changes with the weights and the
        card's bootstrap."""
        boot = self.card["bootstrap"]
        digest = hashlib.sha256(self.checkpoint(seed).read_bytes()
                                + f"{boot['resamples']}/{boot['seed']}".encode()).hexdigest()[:16]
        return f"{self.folder.name}-seed{seed}-{digest}.npz"

    def match(self, seed: int, split, device: str = "cpu"):
        """Model ``seed``'s detections on ``split`` matched to its ground truth (``inference.match_split``)."""
        from rigopt.validation.detectors.inference import match_split

        return match_split(_loaded_model(self.checkpoint(seed), self.family), split, device)

    def own_scores(self, protocol: Protocol) -> dict[int, dict]:
        """The reference's own scores under ``protocol`` (:func:`reference_scores`)."""
        return reference_scores(self, protocol)

    @property
    def reference_rig(self) -> Rig:
        """The rig the models were trained on: the pack's ``rig.json`` where it has one, else the library's."""
        from rigopt.rig.library import load_rig
        from rigopt.rig.pccr_format import read_rig

        path = self.folder / REFERENCE_RIG
        return read_rig(path, self.reference) if path.is_file() else load_rig(self.reference)


#: The test set and bootstrap a detector is scored with on a reference that no pack gives them for: those of the
#: shipped packs (16 test scenes of 40 frames, scene seed offset 0; 1000 scene resamples drawn with seed 0).
DEFAULT_TEST_DATA = {"split": "test", "scenes": 16, "frames": 40, "seed_offset": 0}
DEFAULT_BOOTSTRAP = {"resamples": 1000, "seed": 0, "blocks": 16, "unit": "scene"}


@dataclass(frozen=True)
class UserDetector:
    """A detector of the user's (``external.ExternalDetector``: the detector contract) measured as the shipped
    ones are: on ``reference``'s test scenes and bootstrap (``card``: a shipped pack's on that reference where
    there is one, else DEFAULT_TEST_DATA and DEFAULT_BOOTSTRAP), rendered at the detector's image size. One
    model ("seed" 0); the reference's own scores are measured beside the rigs (``own_scores`` None)."""

    detector: object
    reference_rig: Rig
    card: dict
    family = EXTERNAL_FAMILY
    seeds = (0,)

    @property
    def reference(self) -> str:
        return self.reference_rig.name

    def scores_file(self, seed: int) -> str | None:
        """None for an entry point: scored afresh each time (``ExternalDetector.digest``)."""
        boot = self.card["bootstrap"]
        digest = self.detector.digest
        return f"external-{digest}-{boot['resamples']}-{boot['seed']}.npz" if digest else None

    def match(self, seed: int, split, device: str = "cpu"):
        return self.detector.match(split, device)

    def own_scores(self, protocol: Protocol) -> None:
        return None


def user_detector(detector, reference: Rig, root: Path | None = None) -> UserDetector:
    """``detector`` (``external.ExternalDetector``) measured on ``reference``'s test scenes: those of a pack on
    that reference in :func:`detectors_root` (the same fixed annotation set and scene resamples as its models),
    else the defaults."""
    packs = [name for name in shipped_names(root) if name.split("-", 1)[1] == reference.name]
    card = json.loads((detectors_root(root) / packs[0] / CARD).read_text()) if packs else {
        "test_data": DEFAULT_TEST_DATA, "bootstrap": DEFAULT_BOOTSTRAP}
    test_data = {key: card["test_data"][key] for key in DEFAULT_TEST_DATA}
    size = list(detector.image_size)
    return UserDetector(detector, reference, {"reference": reference.name, "bootstrap": card["bootstrap"],
                                              "test_data": {**test_data, "image_size": size,
                                                            "samples": test_data["scenes"] * test_data["frames"]}})


def detectors_root(root: Path | None = None) -> Path | None:
    """``root`` when given (validate's ``--detectors``), else ``$RIGOPT_DETECTORS`` when set, else the shipped
    ``detectors/`` folder (None if this installation has none)."""
    if root is not None:
        return Path(root)
    if os.environ.get("RIGOPT_DETECTORS"):
        return Path(os.environ["RIGOPT_DETECTORS"])
    try:
        return data_dir("detectors")
    except FileNotFoundError:
        return None


def shipped_names(root: Path | None = None) -> list[str]:
    """``<family>-<reference>`` of every packed detector in :func:`detectors_root`."""
    root = detectors_root(root)
    return sorted(p.parent.name for p in root.glob(f"*/{CARD}")) if root is not None else []


def reference_rig(ref: str, root: Path | None = None) -> Rig:
    """``--ref``: a library rig, a rig file, or else the reference of a pack in :func:`detectors_root` that
    carries its rig (``rig.json``: a pack made by ``rigopt detectors train --ref FILE``, e.g. ``nuscenes``). The
    library's error, naming those packs too, otherwise."""
    from rigopt.errors import UnknownNameError
    from rigopt.rig.library import load_rig, rig_names

    try:
        return load_rig(ref)
    except UnknownNameError as error:
        library = {name.lower() for name in rig_names()}  # a library rig's pack may carry it too: not named here
        carried = {name.split("-", 1)[1]: name for name in shipped_names(root)
                   if (detectors_root(root) / name / REFERENCE_RIG).is_file()
                   and name.split("-", 1)[1].lower() not in library}
        if str(ref) in carried:
            return shipped_detector(*carried[str(ref)].split("-", 1), root).reference_rig
        if carried:
            raise UnknownNameError(f"{error}; or a packed reference: {', '.join(sorted(carried))}") from None
        raise


def shipped_detector(family: str, reference: str, root: Path | None = None) -> ShippedDetector:
    """The packed ``family`` models trained on ``reference`` (in :func:`detectors_root`); a DataError that lists
    the packs there otherwise."""
    name = f"{family}-{reference}"
    if name not in shipped_names(root):
        listed = ", ".join(shipped_names(root)) or "none"
        where = (f"rigopt ships no {family} models trained on {reference} (shipped: {listed})" if root is None and
                 not os.environ.get("RIGOPT_DETECTORS") else
                 f"no {family} models trained on {reference} in {detectors_root(root)} (packed there: {listed})")
        raise DataError(f"{where}; make them with rigopt detectors train --ref {reference} --out DIR and pass "
                        "--detectors DIR, or pass --data with a benchmark folder holding a trained run")
    folder = detectors_root(root) / name
    return ShippedDetector(folder, json.loads((folder / CARD).read_text()))


def rig_key(rig: Rig) -> str:
    """12 hex digits that change with anything that changes the rig's renderings (its file form in its vehicle's
    centre frame, vehicle included, and the ego body drawn into them: :func:`body_digest`), not with its name."""
    from rigopt.rig.pccr_format import rig_to_dict
    from rigopt.vehicle.placement import in_vehicle_frame, known_vehicle

    placed, _ = in_vehicle_frame(rig)
    data = rig_to_dict(placed)
    vehicle = known_vehicle(rig)
    text = json.dumps({"vehicle": data.get("vehicle_type"), "cameras": data["cameras"], "origin": data.get("origin"),
                       "body": body_digest(vehicle.mesh) if vehicle is not None else None}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def body_digest(mesh) -> str:
    """16 hex digits of a body mesh's vertices and faces: a vehicle added again with another mesh under the same
    name renders anew, and a rig rendered without its body (its vehicle unknown then) is not taken for one with it."""
    return hashlib.sha256(np.asarray(mesh.vertices, dtype=float).tobytes()
                          + np.asarray(mesh.faces, dtype=np.int64).tobytes()).hexdigest()[:16]


def cache_name(rig: Rig, protocol: Protocol = FULL, size: tuple[int, int] = SYNTHETIC_IMAGE_SIZE) -> str:
    """The cache folder of a rig: its name (letters, digits, ._- kept), :func:`rig_key`, but for ``full`` the
    protocol's name, and but for the benchmark's image size the rendering's (``-WxH``)."""
    safe = re.sub(r"[^A-Za-z0-9._-]+", "_", rig.name).strip("._") or "rig"
    return (f"{safe[:60]}-{rig_key(rig)}" + ("" if protocol == FULL else f"-{protocol.name}")
            + ("" if tuple(size) == SYNTHETIC_IMAGE_SIZE else f"-{size[0]}x{size[1]}"))


def test_scenes(detector: ShippedDetector, protocol: Protocol = FULL):
    """The reference's test scenes the shipped models were scored on, with the frames ``protocol`` scores."""
    from rigopt.validation.synthetic.scenes import split_scenes

    test = detector.card["test_data"]
    scenes = split_scenes(test["split"], test["scenes"], test["frames"], protocol.seed_offset(test))
    return [dataclasses.replace(scene, frames=scene.frames[::protocol.frame_stride]) for scene in scenes]


def render_cached(rigs: Sequence[Rig], detector: ShippedDetector, cache: Path, workers: int = 1,
                  progress: Callable[[str], None] = lambda message: None, protocol: Protocol = FULL,
                  ray_address: str | None = None) -> list[str]:
    """Render the reference's test scenes (the frames of ``protocol``) under each rig into ``cache`` (what is
    there is kept), in ``workers`` processes or as Ray tasks at ``ray_address``; returns the rigs' folder names
    there."""
    from rigopt.validation.synthetic.generate import ego_body_lookup, generate_split
    from rigopt.validation.synthetic.render import render_rig

    size = tuple(detector.card["test_data"]["image_size"])
    named = [dataclasses.replace(rig, name=cache_name(rig, protocol, size)) for rig in rigs]
    generate_split(named, test_scenes(detector, protocol), cache, size, render_rig, ego_body_lookup(progress),
                   progress, ray_address=ray_address, workers=workers)
    return [rig.name for rig in named]


def measure(rigs: Sequence[Rig], detector: ShippedDetector | UserDetector, cache: Path | None = None,
            device: str = "cpu", workers: int = 1, progress: Callable[[str], None] = lambda message: None,
            protocol: Protocol = DEFAULT_PROTOCOL, ray_address: str | None = None) -> list[dict]:
    """Each rig's measured drop with every shipped seed (or the user's detector) under ``protocol``: a list (one
    per rig) of JSON-ready dicts.

    Per seed: ``mAP`` and ``mAP_visible`` on the reference's test scenes (the protocol's frames) rendered under the
    rig, the reference's own on the same frames (the pack's; a user's detector's, measured here beside the rigs),
    the relative drops and their 95 % intervals over the card's
    scene resamples (paired with the reference's scores under the same resamples: test noise only). Over the
    seeds: the mean drops and the interval of the mean drop over the same resamples. Each seed's entry keeps its
    (resamples,) fixed-set drops under those resamples (``resampled_drops``, an array: :func:`paired_differences`
    pairs two rigs by them; :func:`without_resamples` before writing JSON). Rendering runs in ``workers``
    processes, and so does scoring on the CPU: one pool for every (rig, seed), each process loading a model
    once, the cores shared among them (on a GPU one process). With ``ray_address`` the renderings and the (rig,
    seed) scorings run as Ray tasks there instead (``cache`` on storage every node sees); the figures are the same.
    ``progress`` hears of each rig as it is scored.
    """
    from rigopt.validation.synthetic.cluster import run_tasks

    cache = Path(cache) if cache is not None else default_cache()
    references = detector.own_scores(protocol)  # a pack without this protocol fails before any work
    scored_rigs = list(rigs) if references is not None else [detector.reference_rig, *rigs]
    folders = render_cached(scored_rigs, detector, cache, workers, progress, protocol, ray_address)
    # On the CPU with workers > 1, as many one-thread processes as seeds, the cores shared among them: on 2 cores
    # three one-thread processes finish sooner than two (the third seed would run alone on one core) or than one
    # two-thread process in turn (a second thread speeds a small network up 1.75x, not 2x).
    scorers = 1 if device != "cpu" or workers <= 1 else len(detector.seeds)
    threads = max(1, (os.cpu_count() or 1) // scorers) if scorers > 1 else None
    calls = {(k, seed): (detector, seed, cache, folder, protocol, device, threads)
             for k, folder in enumerate(folders) for seed in detector.seeds}
    where = " as Ray tasks" if ray_address else f" in {scorers} processes" if scorers > 1 else ""
    progress(f"scoring {len(scored_rigs)} rig(s) with {len(detector.seeds)} {detector.family} model(s){where}")
    scores, left = {}, {k: len(detector.seeds) for k in range(len(scored_rigs))}
    for (k, seed), scored in run_tasks(score_seed, calls, ray_address, workers=scorers, what="scoring (rig, seed)"):
        scores[k, seed] = scored
        left[k] -= 1
        if not left[k]:
            progress(f"{scored_rigs[k].name}: scored ({sum(not n for n in left.values())} of {len(scored_rigs)} rigs)")
    if references is None:  # the reference, measured first
        references = {seed: scores[0, seed] for seed in detector.seeds}
    first = len(scored_rigs) - len(rigs)
    return [_rig_entry(rig, protocol, cache / folder, {seed: scores[k, seed] for seed in detector.seeds}, references)
            for k, (rig, folder) in enumerate(zip(scored_rigs, folders)) if k >= first]


def _rig_entry(rig: Rig, protocol: Protocol, folder: Path, scores: dict[int, dict],
               references: dict[int, dict]) -> dict:
    """One rig's :func:`measure` entry from each seed's :func:`score_seed` and the reference's scores."""
    from rigopt.validation.synthetic.evaluation import interval

    seeds, resampled = {}, {"": [], "_visible": []}
    for seed, scored in scores.items():
        entry = {"mAP": scored["mAP"], "mAP_visible": scored["mAP_visible"]}
        for key in ("", "_visible"):
            own = references[seed][f"mAP{key}"]
            drops = (references[seed][f"resampled{key}"] - scored[f"resampled{key}"]) / references[seed][f"resampled{key}"]
            resampled[key].append(drops)
            entry.update({f"reference_mAP{key}": own, f"drop{key}": (own - scored[f"mAP{key}"]) / own,
                          f"drop{key}_ci": interval(drops)})
        seeds[str(seed)] = {**entry, "resampled_drops": resampled[""][-1]}
    return {"rig": rig.name, "n_cameras": len(rig), "protocol": protocol.name, "cache": str(folder), "seeds": seeds,
            "drop": float(np.mean([s["drop"] for s in seeds.values()])),
            "drop_ci": interval(np.mean(resampled[""], axis=0)),
            "drop_visible": float(np.mean([s["drop_visible"] for s in seeds.values()])),
            "drop_visible_ci": interval(np.mean(resampled["_visible"], axis=0))}


def reference_scores(detector: ShippedDetector, protocol: Protocol = FULL) -> dict[int, dict]:
    """The reference's own scores under ``protocol``, per seed: ``mAP``, ``mAP_visible`` and their (resamples,)
    values under the card's scene resamples (``resampled``, ``resampled_visible``). A DataError for a pack made
    without that protocol."""
    if protocol == FULL:
        own, path = detector.card["seeds"], detector.folder / BOOTSTRAP
    else:
        entry = detector.card.get("protocols", {}).get(protocol.name)
        if entry is None or (entry.get("frame_stride"), entry.get("scene_offset")) != (protocol.frame_stride,
                                                                                         protocol.scene_offset):
            raise DataError(f"{detector.folder}: the pack has no reference scores for protocol {protocol.name}; add "
                            f"them with rigopt.validation.detectors.shipped.add_protocol, or use --protocol full")
        own, path = entry["seeds"], detector.folder / f"bootstrap-{protocol.name}.npz"
    with np.load(path) as stored:
        return {seed: {"mAP": own[str(seed)]["mAP"], "mAP_visible": own[str(seed)]["mAP_visible"],
                       "resampled": stored[f"seed{seed}_mAP"], "resampled_visible": stored[f"seed{seed}_mAP_visible"]}
                for seed in detector.seeds}


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


def score_seed(detector: ShippedDetector | UserDetector, seed: int, cache: Path, folder: str,
               protocol: Protocol = FULL, device: str = "cpu", threads: int | None = None) -> dict:
    """One model (``seed``) scored on the rendering ``cache/folder`` (made under ``protocol``): ``mAP``
    and ``mAP_visible``, and their (resamples,) values under the card's scene resamples (``resampled``,
    ``resampled_visible``). Kept in ``cache/folder/scores/`` and read from there when scored before.
    ``threads``: torch's CPU threads (None: as set)."""
    from rigopt.validation.detectors.data import RigSplit
    from rigopt.validation.detectors.protocol import TEST_SPLIT
    from rigopt.validation.synthetic.evaluation import sample_blocks
    from rigopt.output import atomic_file

    boot = detector.card["bootstrap"]
    name = detector.scores_file(seed)
    kept = Path(cache) / folder / SCORES / name if name else None
    if kept is not None and kept.is_file():
        with np.load(kept) as stored:
            return {key: stored[key] if stored[key].ndim else float(stored[key]) for key in stored.files}
    split = RigSplit(cache, folder, TEST_SPLIT, None, depths=False)
    blocks = sample_blocks(split.samples)
    expected = protocol.samples(detector.card["test_data"])
    if len(blocks) != boot["blocks"] or len(split) != expected:
        raise DataError(f"{Path(cache) / folder}: {len(split)} samples in {len(blocks)} scenes, not the {expected} in "
                        f"{boot['blocks']} that protocol {protocol.name} scores; delete that folder and run again")
    if threads is not None:
        import torch

        torch.set_num_threads(threads)
    matched = detector.match(seed, split, device)
    scores = scores_on_frames(matched, blocks, FULL, boot["resamples"], boot["seed"])
    if kept is not None:
        with atomic_file(kept) as work:
            with open(work, "wb") as handle:
                np.savez(handle, **scores)
    return scores


@lru_cache(maxsize=8)
def _loaded_model(checkpoint: Path, family: str):
    """The model of a shipped checkpoint, loaded once per process."""
    from rigopt.validation.detectors.models import load_checkpoint, model_from_checkpoint

    return model_from_checkpoint(load_checkpoint(checkpoint, family))[0]


def scores_on_frames(matched, blocks: Sequence[np.ndarray], protocol: Protocol, resamples: int,
                     bootstrap_seed: int) -> dict:
    """A matched run's scores on ``protocol``'s frames of its scenes: ``mAP``, ``mAP_visible`` and their
    (resamples,) values under ``resamples`` scene resamples (``resampled``, ``resampled_visible``).

    ``matched`` : MatchedDetections over the full frames of the scenes; blocks : each scene's sample indices in
    frame order (``sample_blocks``). The protocol's frames weigh 1, the others 0: the scores of a split rendered
    with only those frames (a sample is matched within itself), to rounding."""
    from rigopt.validation.synthetic.evaluation import resampled_maps

    groups = [np.asarray(block)[::protocol.frame_stride] for block in blocks]
    weights = np.zeros(len(matched.samples), dtype=int)
    weights[np.concatenate(groups)] = 1
    scores = {}
    for key, visible in (("", False), ("_visible", True)):
        scores[f"mAP{key}"] = matched.evaluation(weights, visible_only=visible).map
        scores[f"resampled{key}"] = resampled_maps([matched], groups, resamples, bootstrap_seed,
                                                   visible_only=visible)[:, 0]
    return scores


def pack(runs: dict[int, Path], data: Path, out: Path, recipe: dict, train_data: dict,
         resamples: int = 1000, bootstrap_seed: int = 0, device: str = "cpu",
         progress: Callable[[str], None] = lambda message: None, trained_on: Rig | None = None) -> ShippedDetector:
    """Write a shipped detector folder ``out`` from trained run folders ``runs`` {seed: folder holding
    checkpoint.pt, train_log.csv} whose reference's test split is in ``data``: float16 weights, the card with each
    seed's own mAP measured with the packed weights. ``recipe`` and ``train_data`` go into the card as given;
    ``trained_on``, the reference rig, into ``rig.json`` (``--ref`` then finds it by name)."""
    from rigopt.rig.pccr_format import write_rig
    from rigopt.validation.detectors.data import RigSplit
    from rigopt.validation.detectors.inference import match_split
    from rigopt.validation.detectors.models import (
        load_checkpoint,
        model_from_checkpoint,
        save_checkpoint,
    )
    from rigopt.validation.detectors.protocol import TEST_SPLIT
    from rigopt.validation.synthetic.evaluation import sample_blocks
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
    matched = {}
    with atomic_folder(out, force=True) as work:
        for seed, state in states.items():
            if (state["family"], state["rig"]) != (family, reference):
                raise DataError(f"{runs[seed]}: trained as {state['family']} on {state['rig']}, not {family} on {reference}")
            slim = {key: state[key] for key in ("family", "config", "rig", "channels", "epoch", "step", "seed")}
            slim["model"] = {k: v.half() if v.is_floating_point() else v for k, v in state["model"].items()}
            path = work / f"seed{seed}.pt"
            save_checkpoint(path, slim)
            progress(f"scoring seed {seed} on {reference}'s test split")
            matched[seed] = match_split(model_from_checkpoint(load_checkpoint(path, family))[0], split, device)
            if not matched[seed].evaluation().map > 0:
                raise DataError(f"{runs[seed]}: seed {seed} scores mAP 0 on {reference}'s test split; a drop needs a "
                                "model that detects something: train it longer")
            card["seeds"][str(seed)] = {
                "file": path.name, "epochs": state["epoch"], "steps": state["step"],
                "training_minutes": round(training_seconds(Path(runs[seed]) / "train_log.csv") / 60, 1)}
        for protocol in PROTOCOLS.values():
            if protocol.scene_offset is None:  # the test split at hand; new scenes: add_protocol
                _write_protocol(card, work, protocol, matched, blocks)
        card["size_bytes"] = sum((work / f"seed{seed}.pt").stat().st_size for seed in states)
        (work / CARD).write_text(json.dumps(card, indent=1) + "\n")
        if trained_on is not None:
            write_rig(trained_on, work / REFERENCE_RIG)
    return ShippedDetector(Path(out), card)


def add_protocol(detector: ShippedDetector, protocol: Protocol, cache: Path, device: str = "cpu", workers: int = 1,
                 progress: Callable[[str], None] = lambda message: None) -> ShippedDetector:
    """Add the reference's own scores under ``protocol`` to an existing pack (its card and
    ``bootstrap-<protocol>.npz``, the card rewritten whole), rendering into ``cache`` and scoring every seed.

    On the card's scenes the reference's full test split is rendered and scored, its full scores must equal the
    card's (a DataError otherwise), and the protocol's frames are taken by weight (:func:`scores_on_frames`); on
    new scenes (``protocol.scene_offset``) the reference is rendered under the protocol and scored as it is."""
    from rigopt.validation.detectors.data import RigSplit
    from rigopt.validation.detectors.protocol import TEST_SPLIT
    from rigopt.validation.synthetic.evaluation import sample_blocks
    from rigopt.output import write_text_atomic

    import torch

    known_scenes = protocol.scene_offset is None
    rendered = FULL if known_scenes else protocol
    folder = render_cached([detector.reference_rig], detector, cache, workers, progress, rendered)[0]
    split = RigSplit(cache, folder, TEST_SPLIT, None, depths=False)
    blocks = sample_blocks(split.samples)
    matched = {}
    torch.set_num_threads(1)  # as measure's scoring processes run on the CPU
    for seed in detector.seeds:
        progress(f"scoring seed {seed} on {detector.reference}'s test split ({rendered.name})")
        matched[seed] = detector.match(seed, split, device)
        own = detector.card["seeds"][str(seed)]
        # another thread count sums a convolution in another order: a score moves by about 1e-7, no more
        if known_scenes and not np.isclose(matched[seed].evaluation().map, own["mAP"], rtol=0, atol=1e-6):
            raise DataError(f"{detector.folder}: seed {seed} scores {matched[seed].evaluation().map} on "
                            f"{detector.reference}'s test split, its card {own['mAP']}: not the pack's test data")
        if not known_scenes and not matched[seed].evaluation().map > 0:
            raise DataError(f"{detector.folder}: seed {seed} scores mAP 0 on {detector.reference}'s {protocol.name} "
                            "scenes; a drop needs a model that detects something there")
    card = json.loads(json.dumps(detector.card))
    _write_protocol(card, detector.folder, protocol, matched, blocks, taken=protocol if known_scenes else FULL)
    write_text_atomic(detector.folder / CARD, json.dumps(card, indent=1) + "\n")
    return ShippedDetector(detector.folder, card)


def _write_protocol(card: dict, folder: Path, protocol: Protocol, matched: dict, blocks,
                    taken: Protocol | None = None) -> None:
    """Put the reference's scores under ``protocol`` into ``card`` (the full protocol's in its seeds, another's
    under ``protocols``) and write their resamples (``bootstrap[-<protocol>].npz`` in ``folder``, whole).
    ``matched`` : each seed's matched run; ``taken`` : the protocol whose frames are taken from it (default
    ``protocol``: the runs hold every frame; FULL: they hold only the protocol's)."""
    from rigopt.output import atomic_file

    boot = card["bootstrap"]
    taken = protocol if taken is None else taken
    scores = {seed: scores_on_frames(m, blocks, taken, boot["resamples"], boot["seed"]) for seed, m in matched.items()}
    own = {str(seed): {"mAP": s["mAP"], "mAP_visible": s["mAP_visible"]} for seed, s in scores.items()}
    if protocol == FULL:
        for seed, values in own.items():
            card["seeds"][seed].update(values)
        name = BOOTSTRAP
    else:
        samples = sum(len(np.asarray(block)[::taken.frame_stride]) for block in blocks)
        card.setdefault("protocols", {})[protocol.name] = {"frame_stride": protocol.frame_stride,
                                                           "scene_offset": protocol.scene_offset,
                                                           "samples": samples, "seeds": own}
        name = f"bootstrap-{protocol.name}.npz"
    with atomic_file(folder / name) as work:
        with open(work, "wb") as handle:
            np.savez(handle, **{f"seed{seed}_mAP{key}": s[f"resampled{key}"] for seed, s in scores.items()
                                for key in ("", "_visible")})


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
