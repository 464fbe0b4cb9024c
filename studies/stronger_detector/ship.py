"""Ship a pack of the final recipe (amendment 3) as rigopt's own: into ``detectors/<family>-<reference>/``, replacing
the pack there, only if every seed in it reaches the registered own mAP on its test split; then the ``quick-s1``
protocol's scores are added, as the packs it replaces had them.

    python studies/stronger_detector/ship.py PACK [--cache DIR] [--workers 2]

``PACK`` is a folder ``rigopt detectors train`` packed. The shipped ones were made by (2 cores, resumable)::

    rigopt detectors train --ref R1 --scenes 96 --epochs 16 --seeds 0,1,2 --out DIR
    rigopt detectors train --ref studies/second_reference/nuscenes.json --scenes 96 --epochs 16 --seeds 0 --out DIR

``--cache``: where the reference's ``quick-s1`` scenes are rendered (default: rigopt validate's cache).
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
#: The registered bar (PREREGISTRATION.md): every seed's own mAP on its test split, fixed set.
BAR = 0.30
#: The final recipe (amendment 3): the small lss preset, 16 epochs of 96 training scenes.
RECIPE = {"family": "lss", "preset": "small", "epochs": 16}
TRAIN_SCENES = 96


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("pack", type=Path)
    parser.add_argument("--cache", type=Path, default=None)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    from rigopt.output import atomic_folder
    from rigopt.validation.detectors.measuring import protocol_named
    from rigopt.validation.detectors.shipped import add_protocol, default_cache, shipped_detector

    family, reference = args.pack.name.split("-", 1)
    card = shipped_detector(family, reference, args.pack.parent).card
    recipe = {key: card["recipe"][key] for key in RECIPE}
    if recipe != RECIPE or card["train_data"]["scenes"] != TRAIN_SCENES:
        raise SystemExit(f"{args.pack}: recipe {recipe} on {card['train_data']['scenes']} scenes, not the final "
                         f"recipe {RECIPE} on {TRAIN_SCENES}")
    own = {seed: entry["mAP"] for seed, entry in card["seeds"].items()}
    print(f"{args.pack.name}: own mAP on its test split " + ", ".join(f"seed {s} {m:.3f}" for s, m in own.items()))
    if min(own.values()) < BAR:
        print(f"not shipped: a seed is below {BAR} (the registered decision keeps the shipped pack)")
        return 1
    target = ROOT / "detectors" / args.pack.name
    with atomic_folder(target, force=True) as work:
        for item in args.pack.iterdir():
            shutil.copy2(item, work / item.name)
    detector = add_protocol(shipped_detector(family, reference, target.parent), protocol_named("quick-s1"),
                            args.cache or default_cache(), "cpu", args.workers, lambda m: print(m, flush=True))
    for seed, scores in detector.card["protocols"]["quick-s1"]["seeds"].items():
        print(f"seed {seed}: quick-s1 mAP {scores['mAP']:.4f}")
    print(f"shipped into {target.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
