"""Shared set-up of the detector tests: a tiny rendered benchmark and single-threaded torch.

The benchmark is rendered once per session with the library itself (as ``rigopt bench generate`` does):
rigs R1 (8 cameras) and R5 (4 cameras), one scene of 4 frames in each of the train and test splits, at
64 x 36 pixels, without the ego body (faster; no self-occlusion is needed here).

Torch runs on one thread during these tests: the models are so small that thread start-up dominates, and
on a shared 2-core machine OpenMP's spinning threads made a tiny forward pass ~200x slower than one thread.
"""

from __future__ import annotations

import pytest

TINY_RIGS = {"R1": 8, "R5": 4}  # rig -> camera count
TINY_SIZE = (64, 36)  # width, height
TINY_FRAMES = 4
#: The packed tiny models' test split (:func:`packed`): one scene of 4 frames at 64 x 36 px.
PACKED_SIZE, PACKED_FRAMES = (64, 36), 4


@pytest.fixture(scope="session", autouse=True)
def single_threaded_torch():
    try:
        import torch
    except ImportError:  # the torch-free tests (evaluation) still run
        yield
        return
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


@pytest.fixture(scope="session")
def tiny_data(tmp_path_factory):
    """``<data>/<rig>/<split>/`` for rigs R1 and R5, splits train and test (4 samples each)."""
    from rigopt.validation.synthetic.generate import generate_split
    from rigopt.validation.synthetic.render import render_rig
    from rigopt.validation.synthetic.scenes import split_scenes
    from rigopt.rig.library import load_rig

    out = tmp_path_factory.mktemp("tiny_bench")
    rigs = [load_rig(name) for name in TINY_RIGS]
    assert [len(rig) for rig in rigs] == list(TINY_RIGS.values())
    for split in ("train", "test"):
        scenes = split_scenes(split, 1, TINY_FRAMES)
        generate_split(rigs, scenes, out, TINY_SIZE, render_rig, lambda rig: None)
    return out


@pytest.fixture
def tiny_lss():
    from rigopt.validation.detectors.config import model_config

    return model_config("lss", "tiny")


@pytest.fixture
def tiny_petr():
    from rigopt.validation.detectors.config import model_config

    return model_config("petr", "tiny")


@pytest.fixture(scope="session")
def packed(tmp_path_factory):
    """(data, detectors root): R1's test split (one scene of 4 frames, ego body rendered) and tiny lss models of
    seeds 0 and 1 fitted to it (60 steps on its one batch, so that their own mAP is above 0), packed into
    <root>/lss-R1."""
    from rigopt.rig.library import load_rig
    from rigopt.validation.detectors import shipped
    from rigopt.validation.detectors.config import model_config
    from rigopt.validation.detectors.data import RigSplit
    from rigopt.validation.detectors.training import train
    from rigopt.validation.synthetic.generate import ego_body_lookup, generate_split
    from rigopt.validation.synthetic.render import render_rig
    from rigopt.validation.synthetic.scenes import split_scenes

    base = tmp_path_factory.mktemp("shipped")
    data = base / "data"
    generate_split([load_rig("R1")], split_scenes("test", 1, PACKED_FRAMES), data, PACKED_SIZE, render_rig, ego_body_lookup())
    config = model_config("lss", "tiny", lr=1e-2, weight_decay=0.0, batch_size=PACKED_FRAMES, epochs=60)
    runs = {seed: base / f"run{seed}" for seed in (0, 1)}
    for seed, folder in runs.items():
        train(RigSplit(data, "R1", "test"), config, folder, seed=seed)
    root = base / "detectors"
    shipped.pack(runs, data, root / "lss-R1", {"preset": "tiny", "epochs": 60}, {"split": "test", "scenes": 1},
                 resamples=200)
    return data, root


@pytest.fixture
def use_packed(packed, monkeypatch):
    monkeypatch.setenv("RIGOPT_DETECTORS", str(packed[1]))
    return packed
