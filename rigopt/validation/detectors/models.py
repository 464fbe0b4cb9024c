"""Building detectors and saving, loading and checking their checkpoints.

A checkpoint (``checkpoint.pt``) holds: family, config (ModelConfig as a dict), rig (name trained on),
channels (its camera channels), epoch (finished epochs), step, model and optimizer state dicts, seed.
"""

from __future__ import annotations

from pathlib import Path

import torch

from rigopt.validation.detectors.config import ModelConfig
from rigopt.validation.detectors.families import DETECTORS, Detector
from rigopt.errors import DataError, RigoptError

#: The settings that shape a model's weights; a checkpoint only loads into a model with the same ones.
ARCHITECTURE = ("family", "width", "bev_channels", "bev_range", "bev_cell", "depth_min", "depth_max", "depth_bins",
                "queries", "decoder_layers", "heads", "position_depths")


def build_model(config: ModelConfig) -> Detector:
    """A freshly initialised detector of ``config.family`` (seed torch first for reproducible weights)."""
    return DETECTORS[config.family](config)


def resolve_device(name: str) -> torch.device:
    """``cpu``, ``cuda`` or ``cuda:K``, checked against what this torch build can reach."""
    text = str(name).lower()
    if text == "cpu":
        return torch.device("cpu")
    if text.startswith("cuda"):
        if not torch.cuda.is_available():
            raise RigoptError(f"--device {name}: this machine has no CUDA device that torch {torch.__version__} can "
                              "use; train with --device cpu")
        device = torch.device(text)
        if device.index is not None and device.index >= torch.cuda.device_count():
            raise RigoptError(f"--device {name}: only {torch.cuda.device_count()} CUDA device(s) here (cuda:0 ...)")
        return device
    raise RigoptError(f"--device {name!r}: use cpu, cuda or cuda:K")


def save_checkpoint(path: Path, state: dict) -> None:
    """Write ``state`` atomically (a crash leaves the previous checkpoint whole)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_suffix(".tmp")
    torch.save(state, temporary)
    temporary.replace(path)


def load_checkpoint(path, family: str | None = None) -> dict:
    """A checkpoint's state (tensors on the CPU); ``family`` if given must be the one it was trained as."""
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: no such checkpoint; train one with rigopt bench train")
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)  # tensors and plain data only
    except Exception as error:  # torch raises many kinds for a damaged file
        raise DataError(f"{path}: not a readable rigopt checkpoint (torch cannot load it: {type(error).__name__}); "
                        "train one with rigopt bench train or pass another --checkpoint") from None
    if not isinstance(state, dict) or not {"family", "config", "model", "rig"} <= state.keys():
        raise DataError(f"{path}: not a rigopt detector checkpoint (it lacks family, config, model or rig)")
    if family is not None and state["family"] != family:
        raise DataError(f"{path}: a {state['family']} checkpoint, not {family}; pass --model {state['family']} "
                        "or another checkpoint")
    return state


def model_from_checkpoint(state: dict) -> tuple[Detector, ModelConfig]:
    """The detector a checkpoint ``state`` holds (its family's class from the registry, its weights) and its
    settings."""
    config = ModelConfig.from_dict(state["config"])
    if config.family not in DETECTORS:
        raise DataError(f"a checkpoint of detector family {config.family!r}, which this rigopt does not have "
                        f"(families: {', '.join(DETECTORS)})")
    model = build_model(config)
    model.load_state_dict(state["model"])
    return model, config


def check_compatible(state: dict, config: ModelConfig, rig: str, channels: tuple, path) -> None:
    """Raise if a checkpoint cannot be resumed as training ``config`` on ``rig`` with ``channels``."""
    saved = ModelConfig.from_dict(state["config"])
    if state["family"] != config.family:
        raise DataError(f"{path}: holds a {state['family']} model, not {config.family}; use another --runs folder")
    if state["rig"] != rig or list(state["channels"]) != list(channels):
        raise DataError(f"{path}: trained on {state['rig']} ({len(state['channels'])} cameras: "
                        f"{', '.join(state['channels'])}), not {rig} ({len(channels)} cameras: {', '.join(channels)}); "
                        "use another --runs folder")
    different = [name for name in ARCHITECTURE if getattr(saved, name) != getattr(config, name)]
    if different:
        raise DataError(f"{path}: trained with other settings ({', '.join(f'{n}={getattr(saved, n)}' for n in different)}"
                        "); resume with the same --size, or use another --runs folder")
