"""The study's transfer matrix in one pass on a machine with a GPU and many cores, for one short lease.

The same kind of data, training runs and results as ``run.py --steps data matrix``, in three phases that
each keep every core busy:
  1. render: every (rig, split, scene) of the matrix rigs in a pool of ``--render-workers`` processes
     (``generate_split``, as ``rigopt bench generate --workers``);
  2. train: every rig, ``--train-jobs`` runs at once on the one GPU (a run of this small model is bound by
     its Python side, one core each, so many runs share the GPU); with ``--deadline`` the runs
     unfinished by then are stopped and tested from their last finished epoch (their rows record how many);
  3. test: every trained model on every rig, one job per test rig (``protocol.matrix_rows``); rows written
     to ``--transfer`` in the benchmark's layout;
then pack the results, the training logs and the timings (seconds per phase, throughput) into one archive,
``--pack``/matrix.tar.gz (``--pack-only`` packs what an interrupted run left), and the trained weights (without
optimiser state, 2.5 MB a rig) into ``--pack``/models-<k>.tar, five rigs each (a lease returns files of 16 MiB
at most). Where a lease ends before the test phase, ``--models-from PACK`` tests those weights elsewhere: it
renders the test split only, unpacks the models into ``--data``/runs and runs phase 3.

Measured on an H200 with 16 cores (docs/detectors_study.md): rendering alone ran 125,000 camera images in
155 s with 13 workers; overlapping rendering and training (an earlier version of this script) starved
both. Batches of 16 lose 0.04 mAP against 4 at the same epochs (``recipe.py`` g4, g16), so 4 stays the
default. Rendering and training resume as ``run.py``'s do. Usage:
  python studies/detectors/gpu_matrix.py --data DIR --pack DIR [--train-scenes 28] [--test-scenes 16]
         [--frames 20] [--test-frames N] [--epochs 12] [--batch 4] [--render-workers 16] [--train-jobs 16] [--eval-workers 20]
         [--device cuda] [--deadline SECONDS] [--pack-only] [--models-from PACK]
(``--train-jobs 20`` trains every rig at once: about 3.4 GB of GPU memory each, so an H200's 139 GB.)
On a CPU (``--device cpu``, one thread per process: ``OMP_NUM_THREADS=1``, ``--train-jobs`` = cores) the same
script runs a smaller recipe; the committed matrix's (docs/detectors_study.md) took 24 train scenes of 16
samples, 8 test scenes of 8 and 6 epochs on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tarfile
import time
from pathlib import Path

from rigopt.benchmark import SYNTHETIC_IMAGE_SIZE
from rigopt.output import write_text_atomic

sys.path.insert(0, str(Path(__file__).resolve().parent))
from run import MATRIX, RESULTS, TRANSFER, rig_name  # noqa: E402

FAMILY = "lss"
SIZE = SYNTHETIC_IMAGE_SIZE
#: A training run in its own process (so that the deadline can stop it): rigopt bench train's own call.
TRAIN_CALL = ("import sys; from rigopt.validation.detectors.config import model_config; "
              "from rigopt.validation.detectors.protocol import train_on; "
              "batch = int(sys.argv[5]); "
              "config = model_config('lss', epochs=int(sys.argv[3]), batch_size=batch, lr=1e-3 * (batch / 4) ** 0.5); "
              "train_on(sys.argv[1], sys.argv[2], config, sys.argv[1] + '/runs', sys.argv[4])")


def render(args, timings: dict) -> None:
    """Phase 1: every (rig, split, scene) not rendered yet in one pool (``generate_split``), then the tables."""
    from rigopt.validation.synthetic.generate import ego_body_lookup, generate_split
    from rigopt.validation.synthetic.render import render_rig
    from rigopt.validation.synthetic.scenes import split_scenes
    from rigopt.rig.library import load_rig

    started = time.perf_counter()
    rigs = [load_rig(rig) for rig in args.rigs]
    scenes = [] if args.models_from else split_scenes("train", args.train_scenes, args.frames)
    scenes += split_scenes("test", args.test_scenes, args.test_frames or args.frames)
    cameras, frames = {rig.name: len(rig) for rig in rigs}, {scene.name: len(scene.frames) for scene in scenes}
    rendered = []

    def progress(message: str) -> None:
        if message.endswith(": rendered"):
            rig, scene = message.removesuffix(": rendered").split(" / ")
            rendered.append(cameras[rig] * frames[scene])
            if len(rendered) % 100 == 0:
                print(f"[{time.perf_counter() - started:6.0f} s] rendered {len(rendered)} pairs", flush=True)

    generate_split(rigs, scenes, args.data, SIZE, render_rig, ego_body_lookup(print), progress, print,
                   workers=args.render_workers)
    timings["render_s"] = round(time.perf_counter() - started, 1)
    timings["render_camera_images"] = sum(rendered)
    save(args, timings)


def train(args, timings: dict) -> list[str]:
    """Phase 2: every rig's training, ``--train-jobs`` at once; returns the rigs whose run finished."""
    started = sampled = time.perf_counter()
    queue, running, finished = list(map(rig_name, args.rigs)), [], []
    while queue or running:
        while queue and len(running) < args.train_jobs:
            rig = queue.pop(0)
            log = open(args.data / f"train-{rig}.log", "w")
            command = [sys.executable, "-c", TRAIN_CALL, str(args.data), rig, str(args.epochs), args.device,
                       str(args.batch)]
            running.append((rig, subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT)))
        for rig, process in [r for r in running if r[1].poll() is not None]:
            running.remove((rig, process))
            (finished.append(rig) if process.returncode == 0 else print(f"{rig}: training failed", flush=True))
        if past(args.deadline, args.started) and running:
            stopped = timings.setdefault("stopped_at_deadline", {})
            for rig, process in running:
                process.kill()
                process.wait()
                epochs = finished_epochs(args.data, rig)
                print(f"{rig}: training stopped at the deadline after {epochs} epochs", flush=True)
                stopped[rig] = epochs
                if epochs:  # tested from its last epoch's checkpoint; its row records the epochs it had
                    finished.append(rig)
            break
        if time.perf_counter() - sampled > 15:
            sample, sampled = gpu_sample(time.perf_counter() - started), time.perf_counter()
            if sample:
                timings.setdefault("gpu_samples", []).append(sample)
        time.sleep(1)
    timings["train_s"] = round(time.perf_counter() - started, 1)
    timings["trained"] = finished
    save(args, timings)
    return finished


def finished_epochs(data: Path, rig: str) -> int:
    """Epochs in a run's checkpoint (0 without one)."""
    from rigopt.validation.detectors.models import load_checkpoint
    from rigopt.validation.detectors.protocol import run_folder

    checkpoint = run_folder(data / "runs", FAMILY, rig) / "checkpoint.pt"
    return int(load_checkpoint(checkpoint, FAMILY)["epoch"]) if checkpoint.is_file() else 0


def gpu_sample(seconds: float) -> dict:
    """GPU memory in use (MiB) and utilisation (%) now, by nvidia-smi; empty where there is none."""
    try:
        query = ["nvidia-smi", "--query-gpu=memory.used,utilization.gpu", "--format=csv,noheader,nounits"]
        line = subprocess.run(query, capture_output=True, text=True, timeout=10).stdout.split("\n")[0]
        memory, utilisation = (float(v) for v in line.split(","))
    except (OSError, ValueError, subprocess.SubprocessError):
        return {}
    return {"s": round(seconds), "memory_mib": memory, "utilisation_pct": utilisation}


def past(deadline: float | None, started: float) -> bool:
    return deadline is not None and time.perf_counter() - started > deadline


def evaluate(args, trained: list[str], timings: dict) -> None:
    """Phase 3: every finished model on every rig, one job per test rig (``protocol.matrix_rows``)."""
    from rigopt.validation.detectors.protocol import matrix_rows, write_results

    started = time.perf_counter()
    rows = matrix_rows(args.data, trained, list(map(rig_name, args.rigs)), FAMILY, args.data / "runs", args.device,
                       workers=args.eval_workers)
    for row in rows:
        write_results(args.transfer, row)
    timings["test_s"] = round(time.perf_counter() - started, 1)
    save(args, timings)


def save(args, timings: dict) -> None:
    write_text_atomic(args.results / "gpu_matrix_timings.json", json.dumps(timings, indent=1) + "\n")


def training_throughput(data: Path, batch: int) -> list[dict]:
    """Per training run: steps, seconds, samples/s, from its train_log.csv."""
    import csv

    rows = []
    for log in sorted((data / "runs" / FAMILY).glob("*/train_log.csv")):
        steps = list(csv.DictReader(log.open()))
        if steps:
            seconds = float(steps[-1]["seconds"])
            rows.append({"rig": log.parent.name, "steps": len(steps), "seconds": seconds,
                         "samples_per_s": round(batch * len(steps) / seconds, 1) if seconds else None})
    return rows


MODELS_PER_ARCHIVE = 5


def pack_models(args) -> list[Path]:
    """Every run's weights (its checkpoint without the optimiser state) as ``<rig>.pt`` in
    ``--pack``/models-<k>.tar, MODELS_PER_ARCHIVE rigs each."""
    import io

    import torch

    from rigopt.validation.detectors.models import load_checkpoint
    from rigopt.validation.detectors.protocol import run_folder

    runs = args.data / "runs"
    checkpoints = {rig: run_folder(runs, FAMILY, rig) / "checkpoint.pt" for rig in map(rig_name, args.rigs)}
    rigs = [rig for rig, checkpoint in checkpoints.items() if checkpoint.is_file()]
    archives = []
    for k in range(0, len(rigs), MODELS_PER_ARCHIVE):
        archive = args.pack / f"models-{k // MODELS_PER_ARCHIVE}.tar"
        with tarfile.open(archive, "w") as tar:
            for rig in rigs[k:k + MODELS_PER_ARCHIVE]:
                state = load_checkpoint(checkpoints[rig], FAMILY)
                state.pop("optimizer", None)
                buffer = io.BytesIO()
                torch.save(state, buffer)
                info = tarfile.TarInfo(f"{rig}.pt")
                info.size = buffer.tell()
                buffer.seek(0)
                tar.addfile(info, buffer)
        archives.append(archive)
    return archives


def unpack_models(args) -> list[str]:
    """The weights of ``--models-from``/models-*.tar as ``--data``/runs/<family>/<rig>/checkpoint.pt; returns the
    rigs, in ``--rigs`` order, that have one."""
    from rigopt.validation.detectors.protocol import run_folder

    archives = sorted(args.models_from.glob("models-*.tar"))
    if not archives:
        raise SystemExit(f"--models-from {args.models_from}: no models-*.tar there (gpu_matrix.py packs them)")
    unpacked = set()
    for archive in archives:
        with tarfile.open(archive) as tar:
            for member in tar.getmembers():
                rig = Path(member.name).stem
                if member.isfile() and member.name == f"{rig}.pt":
                    folder = run_folder(args.data / "runs", FAMILY, rig)
                    folder.mkdir(parents=True, exist_ok=True)
                    (folder / "checkpoint.pt").write_bytes(tar.extractfile(member).read())
                    unpacked.add(rig)
    return [rig for rig in map(rig_name, args.rigs) if rig in unpacked]


def pack(args, timings: dict) -> Path:
    """The results, the logs (copied to results/logs) and the timings in ``<pack>/matrix.tar.gz``."""
    import shutil

    logs = args.results / "logs" / FAMILY
    logs.mkdir(parents=True, exist_ok=True)
    for log in (args.data / "runs" / FAMILY).glob("*/train_log.csv"):
        shutil.copy(log, logs / f"{log.parent.name}.csv")
    timings["training"] = training_throughput(args.data, args.batch)
    save(args, timings)
    args.pack.mkdir(parents=True, exist_ok=True)
    archive = args.pack / "matrix.tar.gz"
    with tarfile.open(archive, "w:gz") as tar:
        for name, path in (("transfer", args.transfer / FAMILY), ("logs", logs),
                           ("gpu_matrix_timings.json", args.results / "gpu_matrix_timings.json")):
            if path.exists():
                tar.add(path, arcname=name)
    return archive


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--pack", type=Path, required=True)
    parser.add_argument("--train-scenes", type=int, default=28)
    parser.add_argument("--test-scenes", type=int, default=16)
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--test-frames", type=int, help="frames per test scene (default: --frames)")
    parser.add_argument("--epochs", type=int, default=12)
    parser.add_argument("--batch", type=int, default=4, help="batch size (learning rate 1e-3 x sqrt(batch / 4))")
    parser.add_argument("--render-workers", type=int, default=16)
    parser.add_argument("--train-jobs", type=int, default=16)
    parser.add_argument("--eval-workers", type=int, default=20)
    parser.add_argument("--device", default="cuda")
    parser.add_argument("--deadline", type=float, help="seconds from the start after which trainings are stopped")
    parser.add_argument("--pack-only", action="store_true")
    parser.add_argument("--models-from", type=Path, help="test the weights a lease packed there (models-*.tar)")
    parser.add_argument("--rigs", nargs="+", default=MATRIX, help="default: run.py's matrix rigs")
    parser.add_argument("--transfer", type=Path, default=TRANSFER, help="results folder (default: measurements/transfer)")
    parser.add_argument("--results", type=Path, default=RESULTS, help="readings folder (default: the study's results)")
    args = parser.parse_args()
    args.started = time.perf_counter()
    args.data.mkdir(parents=True, exist_ok=True)
    stored = args.results / "gpu_matrix_timings.json"
    timings = json.loads(stored.read_text()) if args.pack_only and stored.is_file() else {}
    if not args.pack_only:
        timings["settings"] = {k: v for k, v in vars(args).items() if k not in (
            "data", "pack", "transfer", "results", "rigs", "started", "pack_only", "models_from")}
        timings["settings"]["rigs"] = list(map(rig_name, args.rigs))
        timings["settings"]["models_from"] = str(args.models_from) if args.models_from else None
        render(args, timings)
        evaluate(args, unpack_models(args) if args.models_from else train(args, timings), timings)
        timings["total_s"] = round(time.perf_counter() - args.started, 1)
    print("packed", pack(args, timings))
    if not args.models_from:
        print("packed", *pack_models(args))


if __name__ == "__main__":
    main()
