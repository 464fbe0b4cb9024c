"""How the LSS-style family's CPU recipe was chosen: one variant per row, trained on R1 and tested on R1's
16-scene test split (fixed-set and visible-only mAP).

Each variant changes one thing of the row it names: the number of training scenes (12 or 48, the first
scenes of the train split), the bird's-eye augmentation, the depth supervision weight, the steps (epochs x
samples / batch size); g4 and g16 ask whether batches of 16 (a quarter of the steps, the GPU's cost being
per step) train as well as batches of 4 on the GPU matrix's data. Usage (resumable; --data must hold R1's
train split of 48 scenes with depth maps and its test split of 16, or for g4 and g16 the GPU matrix's R1)::

    python studies/detectors/recipe.py --data DIR [--variants e0 e2 ...] [--threads 1]

Writes results/recipe.csv. Runs go to <data>/recipe-runs/<variant>.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies/: the studies' shared code (studylib)
from studylib.tables import markdown, read_csv, write_csv  # noqa: E402

HERE = Path(__file__).resolve().parent
#: variant -> (training scenes, settings of the small preset changed)
VARIANTS = {
    "e0": (12, dict(bev_augment=False, epochs=8)),
    "e1": (12, dict(bev_augment=False, epochs=8, depth_weight=1.0)),
    "e3a": (12, dict(bev_augment=True, epochs=8)),
    "e2": (48, dict(bev_augment=True, epochs=2)),
    "s0": (48, dict(bev_augment=True, epochs=4)),
    "e5": (48, dict(bev_augment=True, epochs=4, depth_weight=0.3)),
    "ext8": (48, dict(bev_augment=True, epochs=8)),
    "ext16": (48, dict(bev_augment=True, epochs=16)),
    # the GPU matrix's data (gpu_matrix.py: 28 train scenes of 20 samples; test 16 scenes of 20)
    "g4": (28, dict(bev_augment=True, epochs=12)),
    "g16": (28, dict(bev_augment=True, epochs=12, batch_size=16, lr=2e-3)),
}
HEADER = ["variant", "train scenes", "bev augment", "depth weight", "steps", "batch", "mAP fixed", "mAP visible",
          "train minutes"]


def run_variant(data: Path, name: str) -> list:
    from rigopt.validation.detectors.config import model_config
    from rigopt.validation.detectors.data import RigSplit
    from rigopt.validation.detectors.inference import match_split
    from rigopt.validation.detectors.models import build_model, load_checkpoint
    from rigopt.validation.detectors.training import train

    scenes, settings = VARIANTS[name]
    config = model_config("lss", "small", **settings)
    split = RigSplit(data, "R1", "train", max_range=config.bev_range)
    kept = sorted({s.scene for s in split.samples})[:scenes]
    split.samples = [s for s in split.samples if s.scene in kept]
    run = train(split, config, data / "recipe-runs" / name)
    model = build_model(config)
    model.load_state_dict(load_checkpoint(run.checkpoint)["model"])
    matched = match_split(model, RigSplit(data, "R1", "test", max_range=config.bev_range))
    steps = config.epochs * -(-len(split) // config.batch_size)
    log = (data / "recipe-runs" / name / "train_log.csv").read_text().strip().splitlines()
    return [name, scenes, config.bev_augment, config.depth_weight, steps, config.batch_size, matched.evaluation().map,
            matched.evaluation(visible_only=True).map, float(log[-1].split(",")[-1]) / 60]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    import torch

    torch.set_num_threads(args.threads)
    out = HERE / "results" / "recipe.csv"
    rows = {row[0]: row for row in read_csv(out)[1:]} if out.is_file() else {}
    rows = {name: row if len(row) == len(HEADER) else [*row[:5], 4, *row[5:]] for name, row in rows.items()}
    for name in args.variants:
        rows[name] = run_variant(args.data, name)
        write_csv(out, HEADER, [rows[n] for n in VARIANTS if n in rows])
    print(markdown(read_csv(out)))


if __name__ == "__main__":
    main()
