"""One rig's split as torch tensors: camera images, their calibration, and boxes in the ego frame.

A batch holds B samples of one rig with N cameras (every sample of a rig has the same cameras, in the
order of their sorted channel names)::

    images      (B, N, 3, H, W) float32, RGB scaled to [0, 1]
    intrinsics  (B, N, 3, 3)    float32, pixels of the (possibly resized) images
    cam_to_ego  (B, N, 4, 4)    float32, camera optical frame (x right, y down, z forward) -> ego, metres
    boxes       list of B BoxTargets (ego frame, ISO 8855: x forward, y left, z up), the boxes the rig sees
    depths      (B, N, H, W)    float32 renderer depth along the optical axis, m (0: no surface), or None
                                when the dataset has no depth maps
    lenses      CameraModel (N,) of the images as they are (size, intrinsics, distortion), or None when
                                every camera is a pinhole of its intrinsics (the split records no distortion)
    rays        (B, N, H, W, 3) float32 optical-frame ray of each pixel centre at unit depth (0 where none in
                                front of the lens), or None: the detector contract's form of the lenses
                                (``external.pixel_ray_maps``); where given, a detector's rays come from it

Images are decoded once and kept as uint8 in memory (a 480-sample, 8-camera split at 160 x 90 is 170 MB).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from rigopt.validation.synthetic.dataset import TrainingSample, read_dataset
from rigopt.validation.synthetic.generate import DEPTH_SCALE
from rigopt.camera import CameraModel, Lens
from rigopt.errors import DataError, RigoptError
from rigopt.geometry import rot_z


@dataclass(frozen=True)
class BoxTargets:
    """n boxes of one sample in the ego frame: centers (n, 3) m, sizes (n, 3) (length, width, height) m,
    yaws (n,) rad, classes (n,) int64 into CLASSES."""

    centers: torch.Tensor
    sizes: torch.Tensor
    yaws: torch.Tensor
    classes: torch.Tensor

    def to(self, device) -> BoxTargets:
        return BoxTargets(*(getattr(self, f).to(device) for f in ("centers", "sizes", "yaws", "classes")))


@dataclass(frozen=True)
class Batch:
    """B samples of one rig (shapes in the module docstring); ``tokens`` (B,) sample ids."""

    images: torch.Tensor
    intrinsics: torch.Tensor
    cam_to_ego: torch.Tensor
    boxes: list
    tokens: list
    depths: torch.Tensor | None = None
    lenses: CameraModel | None = None
    rays: torch.Tensor | None = None

    def to(self, device) -> Batch:
        return Batch(self.images.to(device), self.intrinsics.to(device), self.cam_to_ego.to(device),
                     [b.to(device) for b in self.boxes], self.tokens,
                     None if self.depths is None else self.depths.to(device), self.lenses,
                     None if self.rays is None else self.rays.to(device))

    @property
    def n_cameras(self) -> int:
        return self.images.shape[1]


def split_root(data, rig: str, split: str) -> Path:
    """``<data>/<rig>/<split>``, checked; the error lists the rigs that ``data`` does hold."""
    data = Path(data)
    root = data / rig / split
    if root.is_dir():
        return root
    if not data.is_dir():
        raise DataError(f"{data}: no such data folder; make one with rigopt bench generate --out {data}")
    held = sorted(p.parent.name for p in data.glob(f"*/{split}") if p.is_dir())
    raise DataError(f"{data}: no {split} split for rig {rig!r} (it holds {', '.join(held) or 'no ' + split + ' split'}); "
                    f"render it with rigopt bench generate --rigs {rig} --split {split} --out {data}")


class RigSplit:
    """The samples of ``<data>/<rig>/<split>``, images resized to ``image_size`` (width, height) if given;
    batches carry the depth maps where every sample has them, unless ``depths`` is False (inference and
    training without depth supervision need none, and skip decoding them), and the cameras' lens models
    (``lenses``) where some camera's calibration records a distortion."""

    def __init__(self, data, rig: str, split: str, image_size: tuple[int, int] | None = None,
                 max_range: float = np.inf, depths: bool = True):
        self.root = split_root(data, rig, split)
        self.rig, self.split = rig, split
        self.samples: list[TrainingSample] = read_dataset(self.root)
        if not self.samples:
            raise DataError(f"{self.root}: the split has no samples")
        self.channels = tuple(sorted(self.samples[0].images))
        for sample in self.samples:
            if tuple(sorted(sample.images)) != self.channels:
                raise DataError(f"{self.root}: sample {sample.token} has cameras {sorted(sample.images)}, "
                                f"others {list(self.channels)}; one split must hold one rig")
        first = self.samples[0]
        self.native_size = _image_size(first.images[self.channels[0]])
        self.image_size = tuple(image_size) if image_size else self.native_size
        scale = np.diag([self.image_size[0] / self.native_size[0], self.image_size[1] / self.native_size[1], 1.0])
        self.intrinsics = torch.tensor(np.stack([scale @ first.intrinsics[c] for c in self.channels]),
                                       dtype=torch.float32)
        self.cam_to_ego = torch.tensor(np.stack([first.T_ego_cam[c] for c in self.channels]), dtype=torch.float32)
        self.lenses = _lens_models(first, self.channels, self.native_size, self.image_size, self.root)
        self.max_range = max_range
        self.has_depth = depths and all(sample.depths for sample in self.samples)
        self._images: dict[int, np.ndarray] = {}
        self._depths: dict[int, np.ndarray] = {}

    def __len__(self) -> int:
        return len(self.samples)

    @property
    def n_cameras(self) -> int:
        return len(self.channels)

    def images(self, index: int) -> np.ndarray:
        """(N, H, W, 3) uint8 images of sample ``index``."""
        if index not in self._images:
            self._images[index] = np.stack([_read_image(self.samples[index].images[c], self.image_size, "RGB")
                                            for c in self.channels])
        return self._images[index]

    def depths(self, index: int) -> np.ndarray:
        """(N, H, W) uint16 depth maps of sample ``index`` (units of 1 / ``DEPTH_SCALE`` m, 0: none), resized
        by nearest neighbour."""
        if index not in self._depths:
            self._depths[index] = np.stack([_read_image(self.samples[index].depths[c], self.image_size, "I;16")
                                            for c in self.channels])
        return self._depths[index]

    def targets(self, index: int) -> BoxTargets:
        """The training targets of sample ``index``: its annotated boxes of evaluated classes within
        ``max_range`` m of the ego that some camera of the rig sees (``TrainingSample.visible``). Objects
        in the rig's blind zones are annotated (evaluation counts them) but not taught: no image shows them."""
        s = self.samples[index]
        keep = (s.classes >= 0) & (np.hypot(s.centers[:, 0], s.centers[:, 1]) <= self.max_range) & s.visible
        return BoxTargets(torch.tensor(s.centers[keep], dtype=torch.float32),
                          torch.tensor(s.sizes[keep], dtype=torch.float32),
                          torch.tensor(s.yaws[keep], dtype=torch.float32),
                          torch.tensor(s.classes[keep], dtype=torch.int64))

    def batch(self, indices) -> Batch:
        indices = [int(i) for i in indices]
        images = torch.from_numpy(np.stack([self.images(i) for i in indices])).permute(0, 1, 4, 2, 3)
        b = len(indices)
        depths = None
        if self.has_depth:
            depths = torch.from_numpy(np.stack([self.depths(i) for i in indices]).astype(np.float32)) / DEPTH_SCALE
        return Batch(images.float().div_(255.0), self.intrinsics.expand(b, -1, -1, -1).clone(),
                     self.cam_to_ego.expand(b, -1, -1, -1).clone(), [self.targets(i) for i in indices],
                     [self.samples[i].token for i in indices], depths, self.lenses)

    def batches(self, batch_size: int, order=None):
        """Batches of ``batch_size`` samples in ``order`` (default: the split's order)."""
        order = np.arange(len(self)) if order is None else np.asarray(order)
        for start in range(0, len(order), batch_size):
            yield self.batch(order[start:start + batch_size])


def augment(batch: Batch, rng: np.random.Generator, max_yaw: float = np.pi / 8) -> Batch:
    """``batch`` seen by a rotated and mirrored ego frame (BEVDet's bird's-eye augmentation), per sample: a
    turn by U(-max_yaw, max_yaw) rad about z after mirroring x and y each with probability 1/2. The
    calibration (cam_to_ego) and the boxes move together, so every image still shows its boxes where the
    calibration says; the images, depth maps and lenses are unchanged."""
    cam_to_ego, boxes = batch.cam_to_ego.clone(), []
    for b, targets in enumerate(batch.boxes):
        angle = rng.uniform(-max_yaw, max_yaw)
        mirror = np.diag([rng.choice([-1.0, 1.0]), rng.choice([-1.0, 1.0]), 1.0])
        A = torch.tensor(rot_z(angle) @ mirror, dtype=cam_to_ego.dtype, device=cam_to_ego.device)
        cam_to_ego[b, :, :3, :] = A @ cam_to_ego[b, :, :3, :]
        heading = torch.stack([torch.cos(targets.yaws), torch.sin(targets.yaws), torch.zeros_like(targets.yaws)], 1)
        heading = heading @ A.T
        boxes.append(BoxTargets(targets.centers @ A.T, targets.sizes, torch.atan2(heading[:, 1], heading[:, 0]),
                                targets.classes))
    return Batch(batch.images, batch.intrinsics, cam_to_ego, boxes, batch.tokens, batch.depths, batch.lenses,
                 batch.rays)


def _lens_models(sample: TrainingSample, channels, native_size, image_size, root) -> CameraModel | None:
    """(N,) models of the cameras ``channels`` of ``sample`` (its intrinsics at ``native_size``, its recorded
    distortions) seeing images of ``image_size``; None when no camera records a distortion."""
    if not sample.distortions:
        return None
    lenses = []
    for channel in channels:
        k = sample.intrinsics[channel]
        distortion, coefficients = sample.distortions.get(channel, ("none", ()))
        try:
            lenses.append(Lens(*native_size, k[0, 0], k[1, 1], k[0, 2], k[1, 2], distortion, coefficients))
        except RigoptError as error:
            raise DataError(f"{root}: camera {channel}: {error}") from None
    return CameraModel.of_lenses(lenses).resized(image_size)


def _read_image(path, size: tuple[int, int], mode: str) -> np.ndarray:
    """An image file as an array at ``size`` (width, height): ``mode`` "RGB" (H, W, 3) uint8, resized
    bilinearly, or "I;16" (H, W) uint16 (a depth map), resized by nearest neighbour."""
    from PIL import Image

    try:
        image = Image.open(path)
        image = image.convert("RGB") if mode == "RGB" else image
    except OSError as error:
        raise DataError(f"{path}: cannot read the image ({error})") from None
    if image.size != tuple(size):
        image = image.resize(tuple(size), Image.BILINEAR if mode == "RGB" else Image.NEAREST)
    array = np.asarray(image)
    return array if mode == "RGB" else array.astype(np.uint16)


def _image_size(path) -> tuple[int, int]:
    from PIL import Image

    try:
        with Image.open(path) as image:
            return image.size
    except OSError as error:
        raise DataError(f"{path}: cannot read the image ({error})") from None
