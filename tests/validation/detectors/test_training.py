"""Training: it learns (overfits a tiny set), it resumes exactly, and it refuses checkpoints that do not fit.

Oracles: the overfit tests compare the run's own logged loss, first steps against last steps; the
resumability tests compare a resumed run with an uninterrupted run of the same seed, which must take the
very same steps (same sample order, learning rates and weights), so weights agree to float rounding.
"""

from __future__ import annotations

import csv
import math

import pytest

torch = pytest.importorskip("torch")

from rigopt.validation.detectors import training  # noqa: E402
from rigopt.validation.detectors.config import model_config  # noqa: E402
from rigopt.validation.detectors.data import RigSplit  # noqa: E402
from rigopt.validation.detectors.models import load_checkpoint, model_from_checkpoint, save_checkpoint  # noqa: E402
from rigopt.validation.detectors.training import train  # noqa: E402
from rigopt.errors import DataError  # noqa: E402


def read_log(folder) -> list[dict]:
    with open(folder / "train_log.csv", newline="") as handle:
        return list(csv.DictReader(handle))


def assert_same_state(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for name in a:
        torch.testing.assert_close(a[name], b[name], rtol=0, atol=1e-6, msg=f"{name} differs")


def assert_same_optimizer(a: dict, b: dict) -> None:
    assert a["param_groups"] == b["param_groups"]
    assert a["state"].keys() == b["state"].keys()
    for key in a["state"]:
        for name, value in a["state"][key].items():
            torch.testing.assert_close(value, b["state"][key][name], rtol=0, atol=1e-6)


@pytest.fixture(scope="module")
def r5_train(tiny_data):
    return RigSplit(tiny_data, "R5", "train")


@pytest.fixture(scope="module")
def lss_run(tiny_data, tmp_path_factory):
    """A finished 1-epoch tiny LSS run on R5 (4 cameras)."""
    folder = tmp_path_factory.mktemp("lss_r5")
    train(RigSplit(tiny_data, "R5", "train"), model_config("lss", "tiny", epochs=1), folder)
    return folder


# ---------------------------------------------------------------- learning


@pytest.mark.slow
@pytest.mark.parametrize("family", ["lss", "petr"])
def test_training_overfits_a_tiny_set(r5_train, tmp_path, family):
    """60 steps on the same 4 samples (one batch) cut the loss to well under half."""
    steps = 60
    config = model_config(family, "tiny", lr=1e-2, weight_decay=0.0, batch_size=len(r5_train), epochs=steps)
    seen = []
    run = train(r5_train, config, tmp_path, progress=lambda epoch, step, total, loss: seen.append((step, total, loss)))
    rows = read_log(tmp_path)
    losses = [float(r["loss"]) for r in rows]
    assert len(losses) == steps and all(math.isfinite(v) for v in losses)
    first, last = sum(losses[:5]) / 5, sum(losses[-5:]) / 5
    assert last < 0.5 * first, f"{family}: loss went from {first:.3f} to {last:.3f}"
    assert min(losses[-10:]) < min(losses[:10])
    # the run's report and the progress callback agree with the log
    assert run.epochs == steps and run.steps_now == steps and run.checkpoint.is_file()
    assert run.final_loss == pytest.approx(losses[-1], rel=1e-5)
    assert [s for s, _, _ in seen] == list(range(1, steps + 1)) and {t for _, t, _ in seen} == {steps}
    assert [loss for _, _, loss in seen] == pytest.approx(losses, rel=1e-5)
    # learning rate: linear warm-up (step k of 50 -> k / 50 of lr), then decaying
    rates = [float(r["lr"]) for r in rows]
    assert rates[0] == pytest.approx(config.lr / training.WARMUP_STEPS) and rates[49] == pytest.approx(config.lr)
    assert rates[50] == pytest.approx(config.lr) and all(x > y for x, y in zip(rates[50:], rates[51:]))
    assert rates[-1] >= 0.05 * config.lr


# ---------------------------------------------------------------- resuming


class Interrupted(Exception):
    pass


def test_an_interrupted_run_resumes_to_the_same_weights_and_log(r5_train, tmp_path, monkeypatch):
    """3 epochs of 2 steps, killed in the middle of epoch 3 (after step 5; checkpoint at step 4), resumed:
    same weights, optimizer state and per-step losses as the run that was never stopped. The warm-up is
    shortened so that the cosine part of the schedule is exercised too."""
    monkeypatch.setattr(training, "WARMUP_STEPS", 2)
    config = model_config("lss", "tiny", epochs=3, batch_size=2)
    straight, resumed = tmp_path / "straight", tmp_path / "resumed"
    train(r5_train, config, straight, seed=3)

    def stop_after_step_5(epoch, step, total, loss):
        if step == 5:
            raise Interrupted

    with pytest.raises(Interrupted):
        train(r5_train, config, resumed, seed=3, progress=stop_after_step_5)
    assert load_checkpoint(resumed / "checkpoint.pt")["step"] == 4
    assert [int(r["step"]) for r in read_log(resumed)] == [1, 2, 3, 4, 5]  # step 5 is past the checkpoint
    run = train(r5_train, config, resumed, seed=3)
    assert run.epochs == 3 and run.steps_now == 2

    a, b = load_checkpoint(straight / "checkpoint.pt"), load_checkpoint(resumed / "checkpoint.pt")
    assert (a["epoch"], a["step"]) == (b["epoch"], b["step"]) == (3, 6)
    assert_same_state(a["model"], b["model"])
    assert_same_optimizer(a["optimizer"], b["optimizer"])
    log_a, log_b = read_log(straight), read_log(resumed)
    assert [int(r["step"]) for r in log_b] == [1, 2, 3, 4, 5, 6]
    assert [int(r["epoch"]) for r in log_b] == [0, 0, 1, 1, 2, 2]
    for row_a, row_b in zip(log_a, log_b):
        assert float(row_a["loss"]) == pytest.approx(float(row_b["loss"]), rel=1e-5)
        assert row_a["lr"] == row_b["lr"]


def test_one_epoch_then_two_equals_two_straight(r5_train, tmp_path):
    """Training 1 epoch, then asking for 2, ends where 2 straight epochs end. (The 4 steps lie within the
    50-step warm-up, whose rates do not depend on the epoch count; past it the cosine decay is spread over
    the epochs asked for, so a run extended to more epochs has taken its earlier steps at other rates.)"""
    straight, extended = tmp_path / "straight", tmp_path / "extended"
    one, two = model_config("lss", "tiny", epochs=1), model_config("lss", "tiny", epochs=2)
    train(r5_train, two, straight)
    first = train(r5_train, one, extended)
    assert (first.epochs, first.steps_now) == (1, 2)
    assert [int(r["step"]) for r in read_log(extended)] == [1, 2]
    second = train(r5_train, two, extended)
    assert (second.epochs, second.steps_now) == (2, 2)

    a, b = load_checkpoint(straight / "checkpoint.pt"), load_checkpoint(extended / "checkpoint.pt")
    assert (b["epoch"], b["step"]) == (2, 4)
    assert_same_state(a["model"], b["model"])
    assert_same_optimizer(a["optimizer"], b["optimizer"])
    rows = read_log(extended)
    steps = [int(r["step"]) for r in rows]
    assert steps == [1, 2, 3, 4] and len(set(steps)) == len(steps)
    assert [int(r["epoch"]) for r in rows] == [0, 0, 1, 1]
    assert [r["loss"] for r in rows] == [r["loss"] for r in read_log(straight)]
    with open(extended / "train_log.csv") as handle:
        assert handle.read().count("epoch,step,loss") == 1  # one header

    # a finished run asked again does nothing and leaves its checkpoint alone
    before = (extended / "checkpoint.pt").read_bytes()
    again = train(r5_train, two, extended)
    assert again.steps_now == 0 and again.epochs == 2 and math.isnan(again.final_loss)
    assert (extended / "checkpoint.pt").read_bytes() == before
    assert len(read_log(extended)) == 4


def test_seeds_decide_the_weights(r5_train, tmp_path):
    config = model_config("lss", "tiny", epochs=1)
    for name, seed in (("a", 0), ("b", 0), ("c", 1)):
        train(r5_train, config, tmp_path / name, seed=seed)
    a, b, c = (load_checkpoint(tmp_path / n / "checkpoint.pt")["model"] for n in "abc")
    assert_same_state(a, b)
    assert not torch.allclose(a["encoder.stage1.0.0.weight"], c["encoder.stage1.0.0.weight"])


def test_a_checkpoint_reloads_into_the_same_model(lss_run, r5_train):
    state = load_checkpoint(lss_run / "checkpoint.pt", family="lss")
    assert state["rig"] == "R5" and state["channels"] == list(r5_train.channels) and state["epoch"] == 1
    model, config = model_from_checkpoint(state)
    assert config == model_config("lss", "tiny", epochs=1)
    assert_same_state(model.state_dict(), state["model"])
    again, _ = model_from_checkpoint(load_checkpoint(lss_run / "checkpoint.pt"))
    batch = r5_train.batch([0])
    with torch.no_grad():
        torch.testing.assert_close(model.eval()(batch)["heatmap"], again.eval()(batch)["heatmap"])


# ---------------------------------------------------------------- bad input


def test_checkpoint_of_another_family_is_refused(lss_run):
    with pytest.raises(DataError) as caught:
        load_checkpoint(lss_run / "checkpoint.pt", family="petr")
    assert "lss" in str(caught.value) and "petr" in str(caught.value)


def test_resuming_on_a_rig_with_another_camera_count_is_refused(lss_run, tiny_data):
    before = (lss_run / "checkpoint.pt").read_bytes()
    log_before = (lss_run / "train_log.csv").read_text()
    r1 = RigSplit(tiny_data, "R1", "train")
    assert r1.n_cameras == 8
    with pytest.raises(DataError) as caught:
        train(r1, model_config("lss", "tiny", epochs=2), lss_run)
    message = str(caught.value)
    assert "R5" in message and "4 cameras" in message and "8 cameras" in message
    assert (lss_run / "checkpoint.pt").read_bytes() == before  # nothing overwritten
    assert (lss_run / "train_log.csv").read_text() == log_before


def test_resuming_with_another_family_or_architecture_is_refused(lss_run, r5_train):
    with pytest.raises(DataError, match="lss"):
        train(r5_train, model_config("petr", "tiny", epochs=2), lss_run)
    with pytest.raises(DataError, match="width"):
        train(r5_train, model_config("lss", "tiny", width=16, epochs=2), lss_run)


def test_damaged_or_foreign_checkpoints_are_data_errors(tmp_path):
    with pytest.raises(DataError, match="no such checkpoint"):
        load_checkpoint(tmp_path / "missing.pt")
    garbage = tmp_path / "garbage.pt"
    garbage.write_bytes(b"\x00not a torch file" * 10)
    with pytest.raises(DataError, match="not a readable"):
        load_checkpoint(garbage)
    foreign = tmp_path / "foreign.pt"
    save_checkpoint(foreign, {"weights": torch.zeros(3)})
    with pytest.raises(DataError, match="lacks"):
        load_checkpoint(foreign)
