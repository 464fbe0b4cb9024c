"""The detector families: the interface every family's detector satisfies, and the registry by name.

A family is one module with one ``torch.nn.Module`` subclass that satisfies :class:`Detector`, plus an
entry in :data:`DETECTORS` (its settings' defaults, plain data, in ``config.FAMILY_DEFAULTS``). Everything else (building, checkpoints, training, inference, evaluation, the
command line's ``--model``) reaches the family only through this registry and this interface: a third
family is its module, its line here and its defaults in ``config.FAMILY_DEFAULTS``.
"""

from __future__ import annotations

from typing import Mapping, Protocol, runtime_checkable

import torch

from rigopt.validation.detectors.config import EXTERNAL_FAMILY, ModelConfig
from rigopt.validation.detectors.data import Batch
from rigopt.validation.detectors.lss import LSSDetector
from rigopt.validation.detectors.petr import PETRDetector


@runtime_checkable
class Detector(Protocol):
    """A camera-rig 3D detector of one family (a ``torch.nn.Module``; ``parameters``, ``state_dict``, ``to``,
    ``train`` and ``eval`` come from there).

    The class is built from its settings alone, ``cls(config: ModelConfig)``, and must work for any camera
    count: the rig's calibration arrives with every batch. Frames and units: boxes and detections are in
    the ego frame (ISO 8855: x forward, y left, z up), metres and radians.

    Class attributes:

    - ``family`` : str, the registry key (saved in checkpoints and results);
    - ``config_defaults`` : mapping of ``ModelConfig`` fields this family starts from before the size
      preset and the user's overrides (e.g. its learning rate);
    - ``takes_lenses`` (optional, default False): True when the family computes each camera's rays through
      its lens model where the batch carries one (``Batch.lenses``: distorted cameras, fisheyes included);
      a family without it takes pinholes only (:func:`takes_lenses`).
    """

    family: str
    config_defaults: Mapping[str, object]
    config: ModelConfig

    def __call__(self, batch: Batch) -> dict:
        """The forward pass of a batch (B samples of N cameras): the family's raw outputs, a dict of tensors
        that only its own ``loss`` and ``detections`` read."""
        ...

    def loss(self, outputs: dict, batch: Batch) -> tuple[torch.Tensor, dict[str, float]]:
        """The training loss of ``outputs`` against ``batch.boxes``: a scalar tensor to back-propagate and
        its named terms as floats (the same names at every step: they are the training log's columns)."""
        ...

    def detections(self, outputs: dict, top_k: int = 100) -> list[dict]:
        """Per sample of the batch the ``top_k`` best detections, CPU tensors: ``centers`` (k, 3) m,
        ``sizes`` (k, 3) m (length, width, height), ``yaws`` (k,) rad, ``classes`` (k,) int index into
        ``bench.scene_model.CLASSES``, ``scores`` (k,) float in [0, 1]."""
        ...


#: Family name -> its detector class.
DETECTORS: dict[str, type[Detector]] = {
    "lss": LSSDetector,
    "petr": PETRDetector,
}


def takes_lenses(family: str) -> bool:
    """True when the detectors of ``family`` take distorted cameras (``Detector.takes_lenses``; the contract's
    detectors, :data:`EXTERNAL_FAMILY`, do)."""
    return family == EXTERNAL_FAMILY or bool(getattr(DETECTORS[family], "takes_lenses", False))
