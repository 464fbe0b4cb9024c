"""Train (resumable) and pack the R1 detectors rigopt shipped until commit c16e580: the LSS-style family trained on
R1, one per seed (8 epochs of 48 scenes). The packs shipped since are made by ``studies/stronger_detector/ship.py``.

    python studies/validation/ship_detectors.py --data DIR [--seeds 0 1 2] [--train]

``--data`` is a benchmark folder holding R1's train split (48 scenes x 40 samples) and test split (16 x 40) at
160 x 90, as made by::

    rigopt bench generate --rigs R1 --split train --scenes 48 --out DIR --workers 2
    rigopt bench generate --rigs R1 --split test --scenes 16 --out DIR --workers 2

With ``--train`` each seed is trained (or resumed) first, as ``rigopt bench train --data DIR --rig R1 --model
lss --epochs 8 --seed K --runs DIR/runs-epochs8-seedK``; then the runs are packed into ``detectors/lss-R1/``,
replacing the pack there (float16 weights, the card with each model's own mAP on R1's test split:
``rigopt.validation.detectors.shipped.pack``).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
EPOCHS = 8
REFERENCE = "R1"


def run_folder(data: Path, seed: int) -> Path:
    return data / f"runs-epochs{EPOCHS}-seed{seed}" / "lss" / REFERENCE


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--train", action="store_true")
    args = parser.parse_args(argv)
    from rigopt.validation.detectors.config import model_config
    from rigopt.validation.detectors.models import load_checkpoint
    from rigopt.validation.detectors.shipped import pack

    for seed in args.seeds:
        if args.train:
            subprocess.run(["rigopt", "bench", "train", "--data", str(args.data), "--rig", REFERENCE, "--model", "lss",
                            "--epochs", str(EPOCHS), "--seed", str(seed), "--runs",
                            str(args.data / f"runs-epochs{EPOCHS}-seed{seed}")], check=True)
        state = load_checkpoint(run_folder(args.data, seed) / "checkpoint.pt", "lss")
        if state["epoch"] < EPOCHS:
            raise SystemExit(f"seed {seed} has trained {state['epoch']} of {EPOCHS} epochs; rerun with --train")
    config = model_config("lss", "small", epochs=EPOCHS)
    recipe = {"family": "lss", "preset": "small", "epochs": EPOCHS, "batch_size": config.batch_size,
              "steps": EPOCHS * 1920 // config.batch_size, "optimizer": "AdamW", "lr": config.lr,
              "weight_decay": config.weight_decay, "schedule": "50-step linear warm-up, cosine to 5 %",
              "bev_augment": config.bev_augment, "depth_weight": config.depth_weight,
              "command": f"rigopt bench train --data DIR --rig {REFERENCE} --model lss --epochs {EPOCHS} --seed K"}
    train_data = {"split": "train", "scenes": 48, "frames": 40, "seed_offset": 0, "image_size": [160, 90],
                  "samples": 1920, "command": "rigopt bench generate --rigs R1 --split train --scenes 48"}
    detector = pack({seed: run_folder(args.data, seed) for seed in args.seeds}, args.data,
                    ROOT / "detectors" / f"lss-{REFERENCE}", recipe, train_data, progress=print)
    for seed in detector.seeds:
        entry = detector.card["seeds"][str(seed)]
        print(f"seed {seed}: own mAP {entry['mAP']:.3f} (fixed set), {entry['mAP_visible']:.3f} (visible only), "
              f"{entry['training_minutes']} minutes")
    print(f"packed {len(detector.seeds)} models, {detector.size_bytes() / 1e6:.1f} MB, in {detector.folder}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
