"""``rigopt detectors train | export``: packed models for any reference rig, and a rigopt model behind the
detector contract (docs/detectors.md). torch is imported only inside the commands."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from rigopt.benchmark import SYNTHETIC_IMAGE_SIZE
from rigopt.cli.app import app, console, note, print_next, resumable, status_console
from rigopt.cli.bench_commands import render_size
from rigopt.cli.detector_commands import DEVICE_HELP, MODEL_HELP, SIZE_HELP, require_torch, training_bar
from rigopt.cli.parsing import image_size_text
from rigopt.errors import RigoptError
from rigopt.validation.detectors.reference_models import SHIPPED_EPOCHS, SHIPPED_TRAIN_SCENES

#: Own mAP under which ``detectors train`` says the pack's drops will be mostly noise.
NOISY_MAP = 0.05

detectors_app = typer.Typer(help="Packed detector models: train them for any reference rig, export one to the "
                                 "detector contract.", no_args_is_help=True)
app.add_typer(detectors_app, name="detectors")


def seed_list(text: str) -> tuple[int, ...]:
    """``"0,1,2"`` -> (0, 1, 2): distinct whole numbers from 0, or a RigoptError."""
    try:
        seeds = tuple(int(part) for part in text.split(",") if part.strip())
    except ValueError:
        seeds = ()
    if not seeds or min(seeds) < 0 or len(set(seeds)) != len(seeds):
        raise RigoptError(f"--seeds {text!r}: give distinct whole numbers from 0, separated by commas (e.g. 0,1,2)")
    return seeds


@detectors_app.command("train")
def train_command(
    ref: str = typer.Option(..., "--ref", help="The reference rig: a library name or a rig file."),
    out: Path = typer.Option(..., "--out", help="Folder of packed models to write <out>/<model>-<rig>/ into (point "
                                                "$RIGOPT_DETECTORS or validate --detectors at it); the work to "
                                                "resume from is kept in <out>/.work/ unless --work."),
    model: str = typer.Option("lss", "--model", help=MODEL_HELP),
    size: str = typer.Option("small", "--size", help=SIZE_HELP),
    epochs: int = typer.Option(SHIPPED_EPOCHS, "--epochs", min=1,
                               help=f"Epochs per seed (the shipped models: {SHIPPED_EPOCHS})."),
    seeds: str = typer.Option("0,1,2", "--seeds", help="Training seeds, one model each (e.g. 0,1,2)."),
    scenes: int = typer.Option(SHIPPED_TRAIN_SCENES, "--scenes", min=1,
                               help=f"Training scenes (the shipped models: {SHIPPED_TRAIN_SCENES})."),
    test_scenes: int = typer.Option(16, "--test-scenes", min=1, help="Test scenes the pack scores its models and "
                                    "every rig on (the shipped models: 16)."),
    frames: int = typer.Option(40, "--frames", min=1, help="Samples per scene (2 Hz)."),
    image_size: str = typer.Option(image_size_text(SYNTHETIC_IMAGE_SIZE), "--image-size",
                                   help="Rendered image size WIDTHxHEIGHT in pixels."),
    device: str = typer.Option("cpu", "--device", help=DEVICE_HELP),
    workers: int = typer.Option(0, "--workers", min=0, help="Rendering processes (0: one per core)."),
    work: Optional[Path] = typer.Option(None, "--work", help="Work folder (renderings, training runs) to resume "
                                        "from; default <out>/.work/<model>-<rig>-<key>."),
):
    """Render a reference's training and test scenes, train one model per seed and pack them as rigopt ships
    its own (card with the recipe, the data and each model's own mAP; bootstrap; the quick protocol's scores).
    Resumable: rerun the same command."""
    require_torch()
    import os

    from rigopt.output import check_out_folder
    from rigopt.validation.detectors.config import model_config
    from rigopt.validation.detectors.models import resolve_device
    from rigopt.validation.detectors.reference_models import Recipe, default_work, train_pack
    from rigopt.validation.detectors.shipped import reference_rig

    check_out_folder(out, resume=True)
    if work is not None:
        check_out_folder(work, resume=True, option="--work")
    reference = reference_rig(ref, out if out.is_dir() else None)  # a pack's reference there trains on
    family = model_config(model, size).family
    resolve_device(device)
    recipe = Recipe(family, size.lower(), epochs, seed_list(seeds), scenes, test_scenes, frames,
                    render_size(image_size))
    work = work if work is not None else default_work(out, reference, family)
    resumable(f"rerun the same command: the scenes rendered and the epochs trained so far in {work} are kept")
    with training_bar(f"{family} on {reference.name}") as step:
        packed = train_pack(reference, recipe, out, work, device, workers or os.cpu_count() or 1,
                            lambda message: status_console.print(message, markup=False, highlight=False), step)
    maps = {seed: packed.card["seeds"][str(seed)]["mAP"] for seed in packed.seeds}
    own = ", ".join(f"seed {seed} {value:.3f}" for seed, value in maps.items())
    if min(maps.values()) < NOISY_MAP:
        note(f"own mAP below {NOISY_MAP}: a drop relative to it is mostly test noise; train longer (--epochs, "
             f"--scenes; the shipped models: {SHIPPED_EPOCHS} epochs of {SHIPPED_TRAIN_SCENES} scenes, own mAP 0.34-0.35 "
             "on R1)")
    console.print(f"packed {len(packed.seeds)} {family} model(s) trained on {reference.name} into {packed.folder}; "
                  f"own mAP on its {test_scenes} test scenes: {own}")
    print_next(f"rigopt validate RIG --ref {ref} --model {family} --detectors {out} (a rig's drop with these models)")


@detectors_app.command("export")
def export_command(
    out: Path = typer.Option(..., "--out", help="TorchScript file to write (.pt)."),
    ref: Optional[str] = typer.Option(None, "--ref", help="Export a packed model trained on this reference (with "
                                      "--model and --seed; from --detectors, $RIGOPT_DETECTORS or the shipped ones)."),
    model: str = typer.Option("lss", "--model", help="Family of the packed model (lss)."),
    seed: int = typer.Option(0, "--seed", help="Which packed model (its training seed)."),
    checkpoint: Optional[Path] = typer.Option(None, "--checkpoint", help="Export this checkpoint (a bench train "
                                              "run's checkpoint.pt or a pack's seed<k>.pt) instead of --ref."),
    image_size: Optional[str] = typer.Option(None, "--image-size", help="Image size WIDTHxHEIGHT the card "
                                             "declares (default: the pack's test images, or "
                                             f"{image_size_text(SYNTHETIC_IMAGE_SIZE)})."),
    detectors: Optional[Path] = typer.Option(None, "--detectors", help="Folder of packed models (default "
                                             "$RIGOPT_DETECTORS, else the shipped ones)."),
):
    """Write a rigopt lss model as a TorchScript detector behind the detector contract, its card inside: what
    rigopt validate --detector takes, and a worked example of the contract."""
    require_torch()
    from rigopt.cli.parsing import parse_image_size
    from rigopt.output import check_out_file, existing_file
    from rigopt.validation.detectors.external import export_torchscript
    from rigopt.validation.detectors.shipped import reference_rig, shipped_detector

    check_out_file(out, suffixes=(".pt",))
    if (ref is None) == (checkpoint is None):
        raise RigoptError("give --ref (a packed model, with --model and --seed) or --checkpoint (a checkpoint file), "
                          "one of the two")
    size = parse_image_size(image_size) if image_size is not None else SYNTHETIC_IMAGE_SIZE
    if checkpoint is not None:
        existing_file(checkpoint, "checkpoint file (checkpoint.pt of rigopt bench train, or a pack's seed<k>.pt)",
                      option="--checkpoint")
    else:
        packed = shipped_detector(model, reference_rig(ref, detectors).name, detectors)
        if seed not in packed.seeds:
            raise RigoptError(f"--seed {seed}: the pack {packed.folder} holds seeds {', '.join(map(str, packed.seeds))}")
        checkpoint = packed.checkpoint(seed)
        size = parse_image_size(image_size) if image_size is not None else tuple(packed.card["test_data"]["image_size"])
    with status_console.status(f"tracing {checkpoint}"):
        card = export_torchscript(checkpoint, out, size)
    console.print(f"wrote {out}: {card['name']}, {card['image_size'][0]}x{card['image_size'][1]} px, batches of "
                  f"{card['batch_size']}")
    print_next(f"rigopt validate RIG --ref {card['trained_on']} --detector {out} (a rig's drop with it)")
