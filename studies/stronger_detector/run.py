"""A stronger shipped detector (issue 45, part 4): the pre-registered candidates (PREREGISTRATION.md), each trained
on R1's train split and scored on R1's val split beside the one it changes.

    python studies/stronger_detector/run.py --data DIR [--candidates s4 s4d60] [--threads 2] [--device cuda]

``--data`` holds R1's train split (96 scenes: the shipped recipe's 48 are its first) and val split (16 scenes)
from ``rigopt bench generate``. Runs go to ``<data>/stronger-runs/<candidate>`` (resumable: rerun the same
command); each candidate's row is written to ``results/val.csv`` as soon as it is scored, and its matched
detections are kept beside its run so that later comparisons need no second scoring.
"""

from __future__ import annotations

import argparse
import pickle
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies/: the studies' shared code (studylib)
from studylib.tables import markdown, read_csv, write_csv  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
#: The baseline: the lss-R1 pack shipped when the study was registered (8 epochs of 48 scenes), replaced by its
#: outcome since; its weights are read from git at that commit.
BASELINE_COMMIT, BASELINE_EPOCHS = "c16e580", 8
#: candidate -> (the candidate it changes, its settings of the small preset, training scenes)
CANDIDATES = {
    "baseline": (None, None, 48),
    "s4": ("baseline", dict(feature_stride=4), 48),
    "s4d60": ("s4", dict(feature_stride=4, depth_bins=60), 48),
    "d96": ("baseline", dict(epochs=4), 96),  # amendment 1
    "e16": ("d96", dict(epochs=16), 96),  # registered: the adopted recipe (d96) at 16 epochs
}
RESAMPLES, BOOT_SEED, LEVEL = 1000, 0, 0.95
HEADER = ["candidate", "changes", "mAP fixed", "minus compared", "ci low", "ci high", "mAP visible", "AP 0.5 m",
          "AP 1 m", "AP 2 m", "AP 4 m", "train minutes"]


def run_name(name: str, seed: int) -> str:
    """A candidate's run (and row) name: the candidate for seed 0, ``<candidate>-seed<S>`` for another seed."""
    return name if seed == 0 else f"{name}-seed{seed}"


def baseline_checkpoint(data: Path, seed: int) -> Path:
    """The baseline's model ``seed`` (the pack of BASELINE_COMMIT), written from git into ``data`` once."""
    import subprocess

    path = data / f"baseline-{BASELINE_COMMIT}" / f"seed{seed}.pt"
    if not path.is_file():
        weights = subprocess.run(["git", "-C", str(ROOT), "show", f"{BASELINE_COMMIT}:detectors/lss-R1/seed{seed}.pt"],
                                 check=True, capture_output=True).stdout
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(weights)
    return path


def matched_on_val(data: Path, name: str, device: str = "cpu", seed: int = 0):
    """The candidate's detections on R1's val split, matched (trained first where needed) and its training minutes."""
    from rigopt.validation.detectors.config import model_config
    from rigopt.validation.detectors.data import RigSplit
    from rigopt.validation.detectors.inference import match_split
    from rigopt.validation.detectors.models import build_model, load_checkpoint
    from rigopt.validation.detectors.shipped import training_seconds
    from rigopt.validation.detectors.training import train

    folder = data / "stronger-runs" / run_name(name, seed)
    kept = folder / "val_matched.pkl"
    if kept.is_file():
        return pickle.loads(kept.read_bytes())
    if name == "baseline":
        checkpoint, minutes = baseline_checkpoint(data, seed), float("nan")
        config = model_config("lss", "small")
    else:
        _, settings, scenes = CANDIDATES[name]
        config = model_config("lss", "small", **{"epochs": BASELINE_EPOCHS, **settings})
        split = RigSplit(data, "R1", "train", max_range=config.bev_range)
        chosen = sorted({s.scene for s in split.samples})[:scenes]
        if len(chosen) < scenes:
            raise SystemExit(f"{name} trains on {scenes} scenes; {data} holds {len(chosen)} of R1's train split")
        split.samples = [s for s in split.samples if s.scene in chosen]
        step_every = max(1, len(split) // config.batch_size // 4)
        run = train(split, config, folder, device, seed, progress=lambda epoch, step, steps, loss: step % step_every or print(
            f"{name}: epoch {epoch + 1}/{config.epochs}, step {step}/{steps}, loss {loss:.3f}", flush=True))
        checkpoint, minutes = run.checkpoint, training_seconds(folder / "train_log.csv") / 60
    model = build_model(config)
    model.load_state_dict(load_checkpoint(checkpoint)["model"])
    split = RigSplit(data, "R1", "val", max_range=config.bev_range)
    matched = match_split(model.to(device), split, device)
    scenes = np.array([s.scene for s in split.samples])
    folder.mkdir(parents=True, exist_ok=True)
    kept.write_bytes(pickle.dumps((matched, scenes, minutes)))
    return matched, scenes, minutes


def scene_weights(scenes: np.ndarray) -> np.ndarray:
    """(RESAMPLES, S) int: how often each sample counts when the split's scenes are drawn with replacement."""
    names, index = np.unique(scenes, return_inverse=True)
    draws = np.random.default_rng(BOOT_SEED).integers(len(names), size=(RESAMPLES, len(names)))
    counts = np.stack([np.bincount(d, minlength=len(names)) for d in draws])
    return counts[:, index]


def row(data: Path, name: str, device: str, seed: int = 0) -> list:
    matched, scenes, minutes = matched_on_val(data, name, device, seed)
    fixed, visible = matched.evaluation(), matched.evaluation(visible_only=True)
    compared = CANDIDATES[name][0]
    difference, low, high = (float("nan"),) * 3
    if compared:
        if compared != "baseline" and not (data / "stronger-runs" / run_name(compared, seed) / "val_matched.pkl").is_file():
            raise SystemExit(f"{name} is compared with {compared}: score {compared} first (--candidates {compared})")
        other = matched_on_val(data, compared, device, seed)[0]
        weights = scene_weights(scenes)
        differences = [matched.evaluation(w).map - other.evaluation(w).map for w in weights]
        difference = fixed.map - other.evaluation().map
        low, high = np.percentile(differences, [100 * (1 - LEVEL) / 2, 100 * (1 + LEVEL) / 2])
    changes = ", ".join([f"{k} {v}" for k, v in (CANDIDATES[name][1] or {}).items()]
                        + ([f"{CANDIDATES[name][2]} scenes"] if CANDIDATES[name][2] != 48 else [])) or f"shipped seed {seed}"
    by_threshold = np.nanmean(fixed.ap, axis=0)
    return [run_name(name, seed), changes, fixed.map, difference, low, high, visible.map, *by_threshold, minutes]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--candidates", nargs="+", default=list(CANDIDATES), choices=list(CANDIDATES))
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0, help="training seed (the baseline: the shipped seed's model)")
    parser.add_argument("--device", default="cpu", help="cpu, cuda or cuda:K (training minutes are then a GPU's)")
    args = parser.parse_args()
    import torch

    torch.set_num_threads(args.threads)
    out = HERE / "results" / "val.csv"
    rows = {r[0]: r for r in read_csv(out)[1:]} if out.is_file() else {}
    for name in args.candidates:
        rows[run_name(name, args.seed)] = row(args.data, name, args.device, args.seed)
        write_csv(out, HEADER, [rows[n] for n in sorted(rows, key=lambda n: (list(CANDIDATES).index(n.split("-seed")[0]), n))])
    print(markdown(read_csv(out)))


if __name__ == "__main__":
    main()
