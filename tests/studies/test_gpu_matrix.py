"""studies/detectors/gpu_matrix.py end to end on the CPU at toy size: it renders, trains (in processes it can
stop), tests by test rig and packs; the rows are the benchmark's results layout and the archive holds them.
The packed weights, tested elsewhere (--models-from), give the same rows."""

from __future__ import annotations

import json
import subprocess
import sys
import tarfile
from pathlib import Path

import pytest

pytest.importorskip("torch")

SCRIPT = Path(__file__).resolve().parents[2] / "studies" / "detectors" / "gpu_matrix.py"


def one_pass(tmp_path, name: str, *extra: str) -> subprocess.CompletedProcess:
    folder = tmp_path / name
    return subprocess.run([sys.executable, str(SCRIPT), "--data", str(folder / "data"), "--pack", str(folder / "pack"),
                           "--rigs", "R5", "R1-c6", "--train-scenes", "1", "--test-scenes", "1", "--frames", "2",
                           "--test-frames", "1",
                           "--epochs", "1", "--batch", "2", "--render-workers", "2", "--train-jobs", "2",
                           "--eval-workers", "1", "--device", "cpu", "--transfer", str(folder / "transfer"),
                           "--results", str(folder / "results"), *extra], capture_output=True, text=True, timeout=600)


@pytest.mark.slow
def test_one_pass_on_two_rigs(tmp_path):
    done = one_pass(tmp_path, "lease")
    transfer, results, pack = (tmp_path / "lease" / name for name in ("transfer", "results", "pack"))
    assert done.returncode == 0, done.stderr[-2000:]
    for rig in ("R5", "R1-c6"):
        row = json.loads((transfer / "lss" / f"trained_on_{rig}.json").read_text())
        assert row["trained_on"] == rig and set(row["results"]) == {"R5", "R1-c6"}
        assert row["training"]["epochs"] == 1 and row["training"]["config"]["batch_size"] == 2
        assert 0.0 <= row["results"][rig]["metrics"]["mAP"] <= 1.0
    timings = json.loads((results / "gpu_matrix_timings.json").read_text())
    assert sorted(timings["trained"]) == ["R1-c6", "R5"]
    assert timings["render_camera_images"] == (4 + 6) * (2 + 1)  # cameras x (train frames + test frames)
    assert {r["rig"] for r in timings["training"]} == {"R5", "R1-c6"}
    with tarfile.open(pack / "matrix.tar.gz") as archive:
        names = set(archive.getnames())
    assert {"transfer/trained_on_R5.json", "logs/R1-c6.csv", "gpu_matrix_timings.json"} <= names
    with tarfile.open(pack / "models-0.tar") as archive:
        assert sorted(archive.getnames()) == ["R1-c6.pt", "R5.pt"]
    elsewhere = one_pass(tmp_path, "elsewhere", "--models-from", str(pack))
    assert elsewhere.returncode == 0, elsewhere.stderr[-2000:]
    assert not (tmp_path / "elsewhere" / "data" / "R5" / "train").exists()  # the test split only
    for rig in ("R5", "R1-c6"):
        ours = json.loads((tmp_path / "elsewhere" / "transfer" / "lss" / f"trained_on_{rig}.json").read_text())
        theirs = json.loads((transfer / "lss" / f"trained_on_{rig}.json").read_text())
        assert ours == theirs
