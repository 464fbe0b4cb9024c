"""The study's transfer matrix in one pass on a machine with a GPU and many cores (rendering overlaps training).

The same data, training runs and results as ``run.py --steps data matrix``, scheduled for one short lease:
  1. render the train split of every matrix rig in a pool of processes, rig after rig, and start each rig's
     training (``rigopt bench train --device cuda``, a few at once on the one GPU) as soon as its split is whole;
  2. render every rig's test split in the same pool while those train;
  3. test every trained model on every rig, one job per test rig (``protocol.matrix_rows``; with ``--deadline``
     the trainings unfinished by then are stopped and left out);
  4. pack: the results, the training logs and the timings (seconds per phase, training throughput) into one
     archive, ``--pack``/matrix.tar.gz (``--pack-only`` packs what an interrupted run left).
Rendering and training resume as ``run.py``'s do. Usage:
  python studies/baselines/gpu_matrix.py --data DIR --pack DIR [--train-scenes 28] [--test-scenes 14]
         [--frames 20] [--epochs 12] [--render-workers 14] [--train-jobs 4] [--eval-workers 8] [--device cuda]
         [--deadline SECONDS] [--pack-only]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tarfile
import time
from pathlib import Path

from rigopt.output import write_text_atomic

sys.path.insert(0, str(Path(__file__).resolve().parent))
from run import MATRIX, RESULTS, TRANSFER, rig_name  # noqa: E402

FAMILY = "lss"


def render_and_train(args, timings: dict) -> list[str]:
    """Phases 1 and 2: one render pool for every (rig, split, scene); each rig's training starts once its
    train split is assembled. Returns the rigs whose training finished (by ``--deadline`` s if given)."""
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    import multiprocessing

    from rigopt.bench.generate import assemble, ego_mesh_lookup, in_vehicle_frame, render_scene
    from rigopt.bench.render import render_rig
    from rigopt.bench.scenes import split_scenes
    from rigopt.rig.library import load_rig

    size = (160, 90)
    rigs = [in_vehicle_frame(load_rig(rig))[0] for rig in args.rigs]
    ego_mesh_of = ego_mesh_lookup(print)
    splits = {"train": split_scenes("train", args.train_scenes, args.frames),
              "test": split_scenes("test", args.test_scenes, args.frames)}
    jobs = [(rig, split, scene) for split in ("train", "test") for rig in rigs for scene in splits[split]]
    left = {(rig.name, split): 0 for rig in rigs for split in splits}
    started = time.perf_counter()
    training: list[tuple[str, subprocess.Popen]] = []
    queue: list[str] = []

    def root(rig, split) -> Path:
        return args.data / rig.name / split

    def finished(rig, split) -> None:
        assemble(root(rig, split), rig, split, size)
        timings.setdefault("split_ready_s", {})[f"{rig.name}/{split}"] = round(time.perf_counter() - started, 1)
        save(args, timings)
        print(f"[{time.perf_counter() - started:6.0f} s] {rig.name} {split}: split whole", flush=True)
        if split == "train":
            queue.append(rig.name)

    def start_training() -> None:
        while queue and sum(p.poll() is None for _, p in training) < args.train_jobs:
            rig = queue.pop(0)
            # rigopt bench train's own call, in a process the deadline can stop
            command = [sys.executable, "-c", "import sys; from rigopt.baselines.config import model_config; "
                       "from rigopt.baselines.protocol import train_on; "
                       "train_on(sys.argv[1], sys.argv[2], model_config('lss', epochs=int(sys.argv[3])), "
                       "sys.argv[1] + '/runs', sys.argv[4])", str(args.data), rig, str(args.epochs), args.device]
            log = open(args.data / f"train-{rig}.log", "w")
            training.append((rig, subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT)))

    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=args.render_workers, mp_context=context) as pool:
        pending = {}
        for rig, split, scene in jobs:
            if (root(rig, split) / ".parts" / f"{scene.name}.json").is_file():
                continue
            left[(rig.name, split)] += 1
            future = pool.submit(render_scene, scene, rig, root(rig, split), size, render_rig, ego_mesh_of(rig))
            pending[future] = (rig, split)
        for rig in rigs:  # splits rendered before
            for split in splits:
                if not left[(rig.name, split)]:
                    finished(rig, split)
        start_training()
        while pending:
            done, _ = wait(pending, timeout=5, return_when=FIRST_COMPLETED)
            for future in done:
                rig, split = pending.pop(future)
                future.result()
                left[(rig.name, split)] -= 1
                if not left[(rig.name, split)]:
                    finished(rig, split)
            start_training()
    timings["render_s"] = round(time.perf_counter() - started, 1)
    timings["render_pairs"] = len(jobs)
    timings["render_camera_frames"] = sum(len(rig) * len(scene.frames) for rig, _, scene in jobs)
    save(args, timings)
    while (queue or any(p.poll() is None for _, p in training)) and not past(args.deadline, started):
        start_training()
        time.sleep(2)
    for rig, process in training:
        if process.poll() is None:
            print(f"{rig}: training stopped at the deadline", flush=True)
            process.kill()
            process.wait()
    timings["train_wall_s"] = round(time.perf_counter() - started, 1)
    save(args, timings)
    return [rig for rig, process in training if process.returncode == 0]


def past(deadline: float | None, started: float) -> bool:
    return deadline is not None and time.perf_counter() - started > deadline


def evaluate(args, trained: list[str], timings: dict) -> None:
    """Phase 3: every finished model on every rig, one job per test rig (``protocol.matrix_rows``)."""
    from rigopt.baselines.protocol import matrix_rows, write_results

    started = time.perf_counter()
    rows = matrix_rows(args.data, trained, list(map(rig_name, args.rigs)), FAMILY, args.data / "runs", args.device,
                       workers=args.eval_workers)
    for row in rows:
        write_results(args.transfer, row)
    timings["matrix_s"] = round(time.perf_counter() - started, 1)
    timings["trained"] = trained
    save(args, timings)


def save(args, timings: dict) -> None:
    write_text_atomic(args.results / "gpu_matrix_timings.json", json.dumps(timings, indent=1) + "\n")


def training_throughput(data: Path) -> list[dict]:
    """Per training run: steps, seconds, samples/s (batch 4), from its train_log.csv."""
    import csv

    rows = []
    for log in sorted((data / "runs" / FAMILY).glob("*/train_log.csv")):
        steps = list(csv.DictReader(log.open()))
        if steps:
            seconds = float(steps[-1]["seconds"])
            rows.append({"rig": log.parent.name, "steps": len(steps), "seconds": seconds,
                         "samples_per_s": round(4 * len(steps) / seconds, 1) if seconds else None})
    return rows


def pack(args, timings: dict) -> Path:
    """The results, the logs (copied to results/logs) and the timings in ``<pack>/matrix.tar.gz``."""
    import shutil

    logs = args.results / "logs" / FAMILY
    logs.mkdir(parents=True, exist_ok=True)
    for log in (args.data / "runs" / FAMILY).glob("*/train_log.csv"):
        shutil.copy(log, logs / f"{log.parent.name}.csv")
    timings["training"] = training_throughput(args.data)
    timings["settings"] = {k: v for k, v in vars(args).items() if k not in ("data", "pack", "transfer", "results")}
    timings["settings"]["rigs"] = list(map(rig_name, args.rigs))
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
    parser.add_argument("--test-scenes", type=int, default=14)
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--epochs", type=int, default=12)
    parser.add_argument("--render-workers", type=int, default=14)
    parser.add_argument("--train-jobs", type=int, default=4)
    parser.add_argument("--eval-workers", type=int, default=8)
    parser.add_argument("--deadline", type=float, help="seconds after which unfinished trainings are stopped")
    parser.add_argument("--device", default="cuda")
    parser.add_argument("--pack-only", action="store_true")
    parser.add_argument("--rigs", nargs="+", default=MATRIX, help="default: run.py's matrix rigs")
    parser.add_argument("--transfer", type=Path, default=TRANSFER, help="results folder (default: baselines/transfer)")
    parser.add_argument("--results", type=Path, default=RESULTS, help="readings folder (default: the study's results)")
    args = parser.parse_args()
    args.data.mkdir(parents=True, exist_ok=True)
    stored = args.results / "gpu_matrix_timings.json"
    timings = json.loads(stored.read_text()) if args.pack_only and stored.is_file() else {}
    started = time.perf_counter()
    if not args.pack_only:
        trained = render_and_train(args, timings)
        evaluate(args, trained, timings)
        timings["total_s"] = round(time.perf_counter() - started, 1)
    print("packed", pack(args, timings))


if __name__ == "__main__":
    main()
