"""The detector-family interface and registry: both torch families satisfy it, and a third family is one
class plus one registry entry (here a minimal one, registered for the test only, that is trained,
checkpointed, reloaded and evaluated through the same code as the real families)."""

from __future__ import annotations

import math

import pytest

torch = pytest.importorskip("torch")

from rigopt.validation.detectors.config import FAMILY_DEFAULTS, model_config  # noqa: E402
from rigopt.validation.detectors.families import DETECTORS, Detector  # noqa: E402
from rigopt.validation.detectors.models import build_model, load_checkpoint, model_from_checkpoint  # noqa: E402
from rigopt.validation.detectors.protocol import evaluate_on, train_on  # noqa: E402
from rigopt.validation.synthetic.scene_model import CLASSES  # noqa: E402
from rigopt.errors import DataError  # noqa: E402


class MeanBoxDetector(torch.nn.Module):
    """A third family, as small as the interface allows: it learns one bird's-eye point (the mean box
    centre of what it was shown) and detects a car there in every sample."""

    family = "meanbox"
    config_defaults = {"lr": 0.05}

    def __init__(self, config):
        super().__init__()
        self.config = config
        self.center = torch.nn.Parameter(torch.zeros(2))

    def forward(self, batch) -> dict:
        return {"center": self.center.expand(len(batch.tokens), 2)}

    def loss(self, outputs: dict, batch) -> tuple[torch.Tensor, dict[str, float]]:
        targets = [b.centers[:, :2].mean(dim=0) for b in batch.boxes if len(b.centers)]
        if not targets:
            loss = outputs["center"].sum() * 0.0
        else:
            loss = (outputs["center"][:1] - torch.stack(targets).mean(dim=0)).abs().sum()
        return loss, {"center": float(loss.detach())}

    def detections(self, outputs: dict, top_k: int = 100) -> list[dict]:
        found = []
        for center in outputs["center"].detach().cpu():
            found.append({"centers": torch.cat([center, torch.zeros(1)])[None], "sizes": torch.ones(1, 3),
                          "yaws": torch.zeros(1), "classes": torch.zeros(1, dtype=torch.int64),
                          "scores": torch.full((1,), 0.5)})
        return found


@pytest.mark.parametrize("family", sorted(DETECTORS))
def test_each_registered_family_satisfies_the_interface(family):
    cls = DETECTORS[family]
    assert cls.family == family
    config = model_config(family, "tiny")
    assert {k: getattr(config, k) for k in cls.config_defaults} == dict(cls.config_defaults)
    model = build_model(config)
    assert isinstance(model, Detector) and isinstance(model, torch.nn.Module)
    assert type(model) is cls and model.config == config


def test_a_family_default_gives_way_to_an_override():
    assert model_config("petr", "tiny").lr == DETECTORS["petr"].config_defaults["lr"]
    assert model_config("petr", "tiny", lr=0.123).lr == 0.123


def test_every_family_s_defaults_are_its_class_s():
    assert set(FAMILY_DEFAULTS) == set(DETECTORS)
    assert all(DETECTORS[name].config_defaults == FAMILY_DEFAULTS[name] for name in DETECTORS)


def test_a_third_family_is_one_class_with_its_registry_and_defaults_entries(tiny_data, tmp_path, monkeypatch):
    monkeypatch.setitem(DETECTORS, "meanbox", MeanBoxDetector)
    monkeypatch.setitem(FAMILY_DEFAULTS, "meanbox", MeanBoxDetector.config_defaults)
    config = model_config("meanbox", "tiny", epochs=2)
    assert config.family == "meanbox" and config.lr == 0.05
    assert isinstance(build_model(config), Detector)

    run = train_on(tiny_data, "R5", config, tmp_path / "runs", "cpu", 0)
    assert run.epochs == 2 and math.isfinite(run.final_loss)
    state = load_checkpoint(run.checkpoint, "meanbox")
    model, saved = model_from_checkpoint(state)
    assert type(model) is MeanBoxDetector and saved == config
    assert float(model.center.detach().abs().sum()) > 0  # it learned something, and the weights came back

    metrics = evaluate_on(run.checkpoint, tiny_data, "R1", "cpu", "meanbox")
    assert set(metrics) >= {"mAP", "raw"}
    assert len(metrics["raw"]) == 4 * len(CLASSES)


def test_a_checkpoint_of_an_unregistered_family_is_a_clear_error(tiny_data, tmp_path, monkeypatch):
    monkeypatch.setitem(DETECTORS, "meanbox", MeanBoxDetector)
    monkeypatch.setitem(FAMILY_DEFAULTS, "meanbox", MeanBoxDetector.config_defaults)
    run = train_on(tiny_data, "R5", model_config("meanbox", "tiny", epochs=1), tmp_path / "runs", "cpu", 0)
    monkeypatch.delitem(DETECTORS, "meanbox")
    with pytest.raises(DataError, match="meanbox.*families: lss, petr"):
        model_from_checkpoint(load_checkpoint(run.checkpoint))
