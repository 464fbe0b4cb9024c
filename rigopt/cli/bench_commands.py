"""``rigopt bench generate``: the synthetic multi-rig benchmark in the nuScenes layout."""

from __future__ import annotations

from pathlib import Path
from typing import List

import typer

from rigopt.cli.app import app, console
from rigopt.errors import RigoptError

bench_app = typer.Typer(help="The synthetic multi-rig benchmark: identical scenes under any rig.", no_args_is_help=True)
app.add_typer(bench_app, name="bench")


@bench_app.command("generate")
def generate_command(
    rigs: List[str] = typer.Option(..., "--rigs", help="Rigs to render: library names or rig files; more may follow "
                                                       "as arguments (--rigs R1 R1-f design.json) or commas."),
    more: List[str] = typer.Argument(None, hidden=True),
    split: str = typer.Option("mini", help="Split: train, val, test or mini (scenes never shared between splits)."),
    scenes: int = typer.Option(2, help="Number of scenes."),
    out: Path = typer.Option(..., "--out", help="Output folder: <out>/<rig>/<split>/ per rig."),
    size: str = typer.Option("160x90", help="Image size WIDTHxHEIGHT in pixels."),
    frames: int = typer.Option(40, help="Samples per scene (2 Hz)."),
    seed: int = typer.Option(0, help="Seed offset of the scenes."),
):
    """Render the same scenes under every rig and write images and nuScenes tables (resumable)."""
    from rich.progress import Progress

    from rigopt.bench.generate import ego_mesh_lookup, generate_split
    from rigopt.bench.render import render_rig
    from rigopt.bench.scenes import split_scenes
    from rigopt.cli.rig_commands import parse_image_size
    from rigopt.rig.library import load_rig

    if scenes < 1 or frames < 1:
        raise RigoptError(f"--scenes and --frames must be at least 1, got {scenes} and {frames}")
    names = [n.strip() for text in [*rigs, *(more or [])] for n in text.split(",") if n.strip()]
    loaded = [load_rig(name) for name in names]
    width_height = parse_image_size(size)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise RigoptError(f"{out}: cannot create the output folder ({error.strerror})") from None

    ego_mesh_of = ego_mesh_lookup(lambda message: console.print(f"[yellow]warning:[/] {message}"))

    scene_list = split_scenes(split, scenes, frames, seed)
    with Progress(console=console, transient=True) as progress:
        task = progress.add_task("rendering", total=len(loaded) * len(scene_list))

        def step(message: str) -> None:
            progress.update(task, description=message)
            if "rendering" in message or "skipped" in message:
                progress.advance(task)

        roots = generate_split(loaded, scene_list, out, width_height, render_rig, ego_mesh_of, step)
    console.print("wrote " + ", ".join(str(r) for r in roots))


@bench_app.command("show")
def show_command(
    data: Path = typer.Argument(..., help="A generated benchmark folder (<out>) or one rig's split root."),
    rig: str = typer.Option(..., "--rig", help="Rig name (the folder under <out>)."),
    sample: int = typer.Option(0, "--sample", help="Sample index, in scene and time order."),
    split: str = typer.Option("mini", help="Split folder under the rig."),
    out: Path = typer.Option(..., "--out", help="PNG file to write."),
):
    """Tile a sample's camera images with its projected boxes, and a bird's-eye view of the boxes."""
    from rigopt.bench.dataset import read_dataset
    from rigopt.report.bench_figures import write_sample_figure

    root = data / rig / split
    if not root.is_dir():
        raise RigoptError(f"{root}: no such rig/split folder; generate it with rigopt bench generate")
    samples = read_dataset(root)
    if not 0 <= sample < len(samples):
        raise RigoptError(f"--sample must be in 0..{len(samples) - 1} for {root}, got {sample}")
    path = write_sample_figure(samples[sample], out, f"{rig}: {samples[sample].scene}, sample {sample}")
    console.print(f"wrote {path}")
