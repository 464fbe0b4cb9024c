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
