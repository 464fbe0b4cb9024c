"""``rigopt bench generate``: the synthetic multi-rig benchmark in the nuScenes layout."""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer

from rigopt.benchmark import SYNTHETIC_IMAGE_SIZE
from rigopt.cli.app import PICTURE_SUFFIXES, app, console, note, print_next, resumable, status_console
from rigopt.cli.parsing import image_size_text, parse_image_size
from rigopt.errors import RigoptError

#: Largest image side ``bench generate`` renders (px); larger sizes are refused with a memory estimate.
MAX_SIDE = 8192
#: A lower bound of the bytes the renderer holds per pixel of one image: eight float64 values (ray direction,
#: hit point, depth, object id) while the image is rendered.
BYTES_PER_PIXEL = 64


def render_size(text: str) -> tuple[int, int]:
    """``--size`` as (width, height), refused beyond MAX_SIDE with the memory one image would take."""

    width, height = parse_image_size(text, "--size", smallest=1)  # a rendering size (tests render tiny images)
    if max(width, height) > MAX_SIDE:
        gib = width * height * BYTES_PER_PIXEL / 2**30
        raise RigoptError(f"--size {text}: rendering one {width}x{height} image needs at least {gib:,.0f} GiB "
                          f"of memory; use at most {MAX_SIDE} pixels a side (e.g. 1600x900)")
    return width, height


bench_app = typer.Typer(help="The synthetic multi-rig benchmark: identical scenes under any rig.", no_args_is_help=True)
app.add_typer(bench_app, name="bench")


@bench_app.command("generate")
def generate_command(
    rigs: List[str] = typer.Option(..., "--rigs", help="Rigs to render: library names or rig files; more may follow "
                                                       "as arguments (--rigs R1 R1-f design.json) or commas."),
    more: List[str] = typer.Argument(None, hidden=True),
    split: str = typer.Option("mini", help="Split: train, val, test or mini (scenes never shared between splits)."),
    scenes: int = typer.Option(2, min=1, help="Number of scenes."),
    out: Path = typer.Option(..., "--out", help="Output folder: <out>/<rig>/<split>/ per rig (resumable: a rerun "
                                                "renders only the scenes not finished)."),
    size: str = typer.Option(image_size_text(SYNTHETIC_IMAGE_SIZE),
                             help=f"Image size WIDTHxHEIGHT in pixels (at most {MAX_SIDE} a side)."),
    frames: int = typer.Option(40, min=1, help="Samples per scene (2 Hz)."),
    seed: int = typer.Option(0, min=0, help="Seed offset of the scenes (0 or more)."),
    ray: Optional[str] = typer.Option(None, "--ray", help="Render each (rig, scene) pair as a task on the Ray cluster "
                                                          "at this address ('local' starts one here); --out must "
                                                          "be on storage every node sees."),
    workers: int = typer.Option(1, "--workers", min=1, help="Render the (rig, scene) pairs in this many processes "
                                                           "on this machine (one per core)."),
):
    """Render the same scenes under every rig and write images and nuScenes tables (resumable)."""
    from rich.progress import Progress

    from rigopt.validation.synthetic.generate import ego_body_lookup, generate_split
    from rigopt.validation.synthetic.render import render_rig
    from rigopt.validation.synthetic.scenes import split_scenes
    from rigopt.rig.library import load_rig

    from rigopt.output import check_out_folder

    check_out_folder(out, resume=True)
    width_height = render_size(size)
    names = [n.strip() for text in [*rigs, *(more or [])] for n in text.split(",") if n.strip()]
    loaded = [load_rig(name) for name in names]
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise RigoptError(f"--out {out}: cannot create the output folder ({error.strerror})") from None

    ego_body_of = ego_body_lookup(lambda message: status_console.print(f"[yellow]warning:[/] {message}"))

    scene_list = split_scenes(split, scenes, frames, seed)
    resumable(f"rerun the same command: the scenes rendered so far in {out} are kept and skipped")
    kept = []
    with Progress(console=status_console, transient=True) as progress:
        task = progress.add_task("rendering", total=len(loaded) * len(scene_list))

        def step(message: str) -> None:
            progress.update(task, description=message)
            if "rendering " in message or "skipped" in message or message.endswith("rendered"):
                progress.advance(task)
            if "skipped" in message:
                kept.append(message)

        roots = generate_split(loaded, scene_list, out, width_height, render_rig, ego_body_of, step,
                               lambda message: status_console.print(f"rigopt: note: {message}", markup=False,
                                                                    highlight=False, soft_wrap=True), ray, workers)
    if kept:
        note(f"resumed: {len(kept)} of the {len(loaded) * len(scene_list)} (rig, scene) pairs were rendered before "
             "and kept")
    console.print("wrote " + ", ".join(str(r) for r in roots))
    print_next(f"rigopt bench show {out} --rig {roots[0].parent.name} --split {split} --out sample.png (a sample's "
               "images with their boxes)",
               f"rigopt bench train --data {out} --rig {roots[0].parent.name} --model lss (a detector on it; a train "
               "split: --split train)")


@bench_app.command("show")
def show_command(
    data: Path = typer.Argument(..., help="A generated benchmark folder (<out>) or one rig's split root."),
    rig: str = typer.Option(..., "--rig", help="Rig name (the folder under <out>)."),
    sample: int = typer.Option(0, "--sample", help="Sample index, in scene and time order."),
    split: str = typer.Option("mini", help="Split folder under the rig."),
    out: Path = typer.Option(..., "--out", help="Picture to write: .png (or .pdf, .svg, .jpg)."),
):
    """Tile a sample's camera images with its projected boxes, and a bird's-eye view of the boxes."""
    from rigopt.validation.synthetic.dataset import read_dataset
    from rigopt.output import atomic_file, check_out_file, existing_folder
    from rigopt.report.bench_figures import write_sample_figure

    out = check_out_file(out, suffixes=PICTURE_SUFFIXES)
    existing_folder(data, "the benchmark's rig folders (<data>/<rig>/<split>, made by rigopt bench generate --out)")

    root = data / rig / split
    if not root.is_dir():
        raise RigoptError(f"{root}: no such rig/split folder; generate it with rigopt bench generate")
    samples = read_dataset(root)
    if not 0 <= sample < len(samples):
        raise RigoptError(f"--sample must be in 0..{len(samples) - 1} for {root}, got {sample}")
    missing = [str(p) for p in samples[sample].images.values() if not Path(p).is_file()]
    if missing:
        raise RigoptError(f"{root}: sample {sample} lacks its image {missing[0]}; remove the rig's folder and generate "
                          "it again with rigopt bench generate")
    with atomic_file(out) as work:
        write_sample_figure(samples[sample], work, f"{rig}: {samples[sample].scene}, sample {sample}")
    console.print(f"wrote {out}")
