"""Detector settings: ``ModelConfig``, each family's own defaults (``FAMILY_DEFAULTS``, which its detector class
carries as ``config_defaults``) and the size presets. Plain data: building a config needs no torch.

Sizes: ``tiny`` for tests (seconds on a CPU), ``small`` for the 2-core CPU studies, ``base`` for a GPU.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace

from rigopt.errors import RigoptError, unknown_name

SIZES = ("tiny", "small", "base")
#: The family name of a detector of the user's behind the detector contract (``external.py``), which takes every
#: lens through its pixel ray maps.
EXTERNAL_FAMILY = "external"

#: Family name -> the ``ModelConfig`` fields it starts from before the size preset and the user's overrides
#: (its learning rate); the registry ``families.DETECTORS`` has the same names (tested).
FAMILY_DEFAULTS: dict[str, dict[str, object]] = {
    "lss": {"lr": 1e-3},
    "petr": {"lr": 4e-4},
}


@dataclass(frozen=True)
class ModelConfig:
    """One detector's architecture and training settings.

    bev_range : half-width (m) of the square bird's-eye area both families detect in, centred on the ego;
    bev_cell : LSS grid cell (m); depth_min, depth_max, depth_bins : LSS depth distribution (m, along the
    optical axis); position_depths : points per pixel ray in PETR's 3D position embedding; dn_groups : PETR's groups of
    denoising queries in training (0: none); azimuth_prior : PETR's cross-attention favours the tokens whose rays
    pass over each query's reference point; token_supervision : PETR's auxiliary loss on its image tokens
    (object centre and depth); depth_weight : weight of LSS's depth supervision from the renderer's depth maps
    (0: none; used only where the data holds depth maps); bev_augment : train on randomly turned and mirrored
    ego frames (``data.augment``); feature_stride : pixels per image feature cell, 8 or 4 (LSS lifts along
    each cell's ray: 4 gives rays twice as fine in each direction); image_size :
    (width, height) pixels the images are resized to, None to keep them as stored.
    """

    family: str
    size: str = "small"
    width: int = 32
    bev_channels: int = 48
    bev_range: float = 51.2
    bev_cell: float = 1.6
    depth_min: float = 1.0
    depth_max: float = 61.0
    depth_bins: int = 30
    queries: int = 96
    decoder_layers: int = 3
    heads: int = 4
    position_depths: int = 16
    dn_groups: int = 3
    azimuth_prior: bool = True
    token_supervision: bool = True
    depth_weight: float = 0.0
    bev_augment: bool = False
    feature_stride: int = 8
    image_size: tuple | None = None
    lr: float = 1e-3
    weight_decay: float = 1e-2
    batch_size: int = 4
    epochs: int = 24

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, values: dict) -> ModelConfig:
        known = {f.name for f in fields(cls)}
        config = cls(**{k: v for k, v in values.items() if k in known})
        return replace(config, image_size=tuple(config.image_size) if config.image_size else None)


_PRESETS = {
    "tiny": dict(width=8, bev_channels=8, bev_cell=6.4, depth_bins=6, queries=12, decoder_layers=1, heads=2,
                 position_depths=4, dn_groups=1, batch_size=2, epochs=2),
    "small": dict(bev_augment=True),
    "base": dict(bev_augment=True, width=64, bev_channels=96, bev_cell=0.8, depth_bins=60, queries=200,
                 decoder_layers=6, heads=8, position_depths=32, batch_size=8, epochs=36),
}


def model_config(family: str, size: str = "small", **overrides) -> ModelConfig:
    """The preset ``size`` of detector ``family`` (a key of ``FAMILY_DEFAULTS``) with ``overrides`` (None
    values ignored): the family's defaults, then the size preset, then the overrides."""
    family, size = str(family).lower(), str(size).lower()
    if family not in FAMILY_DEFAULTS:
        raise unknown_name("model family", family, tuple(FAMILY_DEFAULTS))
    if size not in SIZES:
        raise unknown_name("model size", size, SIZES)
    values = {**FAMILY_DEFAULTS[family], **_PRESETS[size],
              **{k: v for k, v in overrides.items() if v is not None}}
    config = ModelConfig(family=family, size=size, **values)
    for name in ("width", "bev_channels", "depth_bins", "queries", "decoder_layers", "heads", "position_depths",
                 "batch_size", "epochs"):
        if getattr(config, name) < 1:
            raise RigoptError(f"model setting {name} must be at least 1, got {getattr(config, name)}")
    if config.feature_stride not in (4, 8):
        raise RigoptError(f"model setting feature_stride is 4 or 8 (pixels per feature cell), got {config.feature_stride}")
    if config.dn_groups < 0:
        raise RigoptError(f"model setting dn_groups must be 0 (no denoising queries) or more, got {config.dn_groups}")
    if not (config.bev_range > 0 and 0 < config.bev_cell <= config.bev_range and 0 < config.depth_min
            < config.depth_max and config.lr > 0):
        raise RigoptError(f"model ranges must be positive and ordered: bev_range {config.bev_range}, bev_cell "
                          f"{config.bev_cell}, depth {config.depth_min}..{config.depth_max}, lr {config.lr}")
    if (2 * config.width) % config.heads:
        raise RigoptError(f"2 x width ({2 * config.width}, the feature size) must be a multiple of heads {config.heads}")
    return config
