"""Your own detector in rigopt's evaluation: the detector contract, loading a detector that keeps it (a
TorchScript file or a Python entry point), running it on a rendered split with its answers checked, and
exporting a rigopt checkpoint to it.

The contract (version 1). rigopt calls the detector on batches of B samples of one rig with N cameras (any
N: the calibration arrives with every batch), in torch tensors on the chosen device::

    boxes, scores, labels = detector(images, intrinsics, cam_to_ego, rays)

    images      (B, N, 3, H, W) float32  RGB in [0, 1], rendered at the detector's declared size (W, H)
    intrinsics  (B, N, 3, 3)    float32  pixels of those images (a distorted lens: the K of its distorted
                                         normalised coordinates, as the benchmark's calibration records it)
    cam_to_ego  (B, N, 4, 4)    float32  camera optical frame (x right, y down, z forward) -> ego frame, m
    rays        (B, N, H, W, 3) float32  the ray of each pixel's centre (u + 0.5, v + 0.5) in the optical frame
                                         at unit depth (z = 1), through the lens's distortion: the distortion
                                         in a form no detector has to re-implement; (0, 0, 0) for a pixel that
                                         sees nothing in front of its lens (a fisheye beyond 90 degrees)
    boxes       (B, K, 7)  float  centre x, y, z (m), length, width, height (m), yaw (rad about z, 0 along +x)
    scores      (B, K)     float  in [0, 1]
    labels      (B, K)     int    index into the card's ``classes``; -1 marks padding (its box is not read)

The ego frame is the benchmark's: ISO 8855 (x forward, y left, z up), origin on the ground below the vehicle's
centre. rigopt keeps each sample's ``TOP_K`` best detections within ``EVAL_RANGE`` and scores them with the
benchmark's centre-distance mAP, exactly as it scores its own models.

The card (a dict) declares ``contract`` (1), ``image_size`` ([W, H] px), ``classes`` (names, each one of
``CLASSES``: car, truck, bus, motorcycle, bicycle, adult, child, traffic_sign, traffic_light), and optionally
``batch_size`` (default 1) and ``name``. A TorchScript file carries it as the extra file ``rigopt.json``
(``torch.jit.save(module, path, _extra_files={"rigopt.json": json.dumps(card)})``); an entry point
``package.module:factory`` is a function of no arguments returning ``(detector, card)``.

What a detector returns is checked batch by batch: shapes, finite values, scores in [0, 1], labels in range,
positive sizes, and, over the split, that the boxes stand where ego-frame objects do (a median centre height
within ``HEIGHTS``, which boxes in a camera's frame, z forward, miss). A breach is one DataError that names
what came back and what the contract expects.
"""

from __future__ import annotations

import hashlib
import importlib
import json
import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
import torch

from rigopt.errors import DataError
from rigopt.validation.detectors.data import Batch, RigSplit
from rigopt.validation.detectors.inference import TOP_K
from rigopt.validation.detectors.layers import lens_cells, pinhole_rays
from rigopt.validation.detectors.models import resolve_device
from rigopt.validation.synthetic.evaluation import (EVAL_RANGE, Detections, GroundTruth, MatchedDetections,
                                                   SamplePrediction, match)
from rigopt.validation.synthetic.scene_model import CLASSES

CONTRACT = 1
CARD_FILE = "rigopt.json"
#: m: the range the median centre height of a split's detections must lie in (ego-frame objects stand on the
#: ground; in a camera's frame, z is the distance ahead).
HEIGHTS = (-2.0, 6.0)
ENTRY_POINT = re.compile(r"[A-Za-z_][\w.]*:[A-Za-z_]\w*")


@dataclass(frozen=True)
class ExternalDetector:
    """A detector that keeps the contract: ``source`` (a TorchScript file's path or ``package.module:factory``),
    its ``card`` (the contract's declaration) and ``digest`` (16 hex digits of a file's bytes, which name its kept
    scores; None for an entry point, whose weights may change behind the same name: it is scored afresh each
    time). Picklable: the model is loaded in each process that runs it (:func:`loaded`)."""

    source: str
    card: dict
    digest: str | None

    @property
    def name(self) -> str:
        return str(self.card.get("name") or Path(self.source.split(":")[0]).stem)

    @property
    def image_size(self) -> tuple[int, int]:
        return tuple(int(v) for v in self.card["image_size"])

    @property
    def batch_size(self) -> int:
        return int(self.card.get("batch_size", 1))

    def match(self, split: RigSplit, device: str = "cpu") -> MatchedDetections:
        """Its detections on ``split`` matched to the split's ground truth within EVAL_RANGE (as
        ``inference.match_split`` for rigopt's own models)."""
        predictions = predict(self, split, device)
        truth = GroundTruth.from_samples(split.samples).within(EVAL_RANGE)
        return match(Detections.from_predictions(predictions), truth, samples=[s.token for s in split.samples])


def load_detector(source: str) -> ExternalDetector:
    """The detector at ``source``: a TorchScript file (``.pt``, ``.ts``, ``.torchscript``) or an entry point
    ``package.module:factory``, its card checked. A DataError says what is wrong and what the contract asks."""
    text = str(source)
    path = Path(text)
    if path.is_file():
        if path.suffix.lower() == ".onnx":
            raise DataError(f"--detector {text}: ONNX files are not read; export the model as TorchScript with its "
                            f"card as the extra file {CARD_FILE}, or wrap an ONNX runtime session in an entry point "
                            "(package.module:factory, docs/detectors.md)")
        card = _card(_torchscript(path)[1], text)
        return ExternalDetector(text, card, hashlib.sha256(path.read_bytes()).hexdigest()[:16])
    if ENTRY_POINT.fullmatch(text):
        return ExternalDetector(text, _entry_point(text)[1], None)
    raise DataError(f"--detector {text}: no such file, nor an entry point package.module:factory; give a TorchScript "
                    "file (rigopt detectors export makes one from a rigopt model) or an importable factory")


@lru_cache(maxsize=4)
def loaded(source: str):
    """The callable detector at ``source``, loaded once per process."""
    if ENTRY_POINT.fullmatch(source) and not Path(source).is_file():
        return _entry_point(source)[0]
    return _torchscript(Path(source))[0]


def _torchscript(path: Path) -> tuple[object, bytes | None]:
    """A TorchScript file's module (on the CPU) and its card's bytes (None when it has none)."""
    extra = {CARD_FILE: ""}
    try:
        module = torch.jit.load(str(path), map_location="cpu", _extra_files=extra)
    except Exception as error:  # torch raises many kinds for a file that is not TorchScript
        raise DataError(f"--detector {path}: not a TorchScript file torch can load ({type(error).__name__}); export "
                        "the model with torch.jit.trace or torch.jit.script and torch.jit.save") from None
    return module.eval(), extra[CARD_FILE] or None


def _entry_point(text: str) -> tuple[object, dict]:
    """The detector and card an entry point's factory returns."""
    module_name, function = text.split(":")
    try:
        factory = getattr(importlib.import_module(module_name), function)
    except (ImportError, AttributeError) as error:
        raise DataError(f"--detector {text}: cannot import it ({type(error).__name__}: {error}); the package must be "
                        "importable here (pip install it, or put it on PYTHONPATH)") from None
    made = factory()
    if not (isinstance(made, tuple) and len(made) == 2 and callable(made[0]) and isinstance(made[1], dict)):
        raise DataError(f"--detector {text}: the factory returned {type(made).__name__}; the contract expects a "
                        "(detector, card) pair: a callable and a dict")
    return made[0], _card(made[1], text)


def _card(card, source: str) -> dict:
    """The card, checked against the contract; ``card`` a dict or its JSON text (None: the file has none)."""
    if card is None:
        raise DataError(f"--detector {source}: the TorchScript file carries no {CARD_FILE}; save it with "
                        f"_extra_files={{'{CARD_FILE}': json.dumps(card)}} (docs/detectors.md, the detector contract)")
    if isinstance(card, (str, bytes)):
        try:
            card = json.loads(card)
        except (json.JSONDecodeError, UnicodeDecodeError) as error:
            raise DataError(f"--detector {source}: its {CARD_FILE} is not JSON text ({error})") from None
    if not isinstance(card, dict) or card.get("contract") != CONTRACT:
        raise DataError(f"--detector {source}: its card says contract {card.get('contract') if isinstance(card, dict) else card!r}; "
                        f"this rigopt reads contract {CONTRACT} (a dict with contract, image_size, classes)")
    size = card.get("image_size")
    if not (isinstance(size, list) and len(size) == 2 and all(isinstance(v, int) and 16 <= v <= 8192 for v in size)):
        raise DataError(f"--detector {source}: image_size {size!r}; the contract expects [width, height], whole "
                        "pixels from 16 to 8192")
    classes = card.get("classes")
    if not (isinstance(classes, list) and classes and all(name in CLASSES for name in classes)):
        raise DataError(f"--detector {source}: classes {classes!r}; the contract expects a list of names from "
                        f"{', '.join(CLASSES)}")
    batch = card.get("batch_size", 1)
    if not (isinstance(batch, int) and batch >= 1):
        raise DataError(f"--detector {source}: batch_size {batch!r}; the contract expects a whole number from 1")
    return card


def pixel_ray_maps(batch: Batch) -> torch.Tensor:
    """(B, N, H, W, 3) float32: the contract's ``rays`` of a batch, each pixel centre's optical-frame ray at unit
    depth. Pinholes: from the intrinsics (``layers.pinhole_rays``, as the detectors compute theirs: the same numbers);
    distorted lenses: through ``batch.lenses`` (``layers.lens_cells``), (0, 0, 0) where no ray is in front."""
    b, n, _, h, w = batch.images.shape
    if batch.lenses is not None:
        rays, _ = lens_cells(batch.lenses, (h, w), 1, torch.float32)
        return rays.expand(b, n, h, w, 3).clone()
    return pinhole_rays(batch.intrinsics, (h, w), 1)


@torch.no_grad()
def predict(detector: ExternalDetector, split: RigSplit, device: str = "cpu") -> list[SamplePrediction]:
    """Each sample's ``TOP_K`` best detections within EVAL_RANGE, rigopt's class indices; the detector's answers
    checked against the contract (a DataError at the first breach)."""
    if tuple(split.image_size) != detector.image_size:
        raise DataError(f"{split.root}: images of {split.image_size[0]}x{split.image_size[1]} px, the detector "
                        f"{detector.name} declares {detector.image_size[0]}x{detector.image_size[1]}")
    target = resolve_device(device)
    model = loaded(detector.source)
    if isinstance(model, torch.nn.Module):
        model = model.to(target)
    to_rigopt = np.array([CLASSES.index(name) for name in detector.card["classes"]])
    predictions = []
    for batch in split.batches(detector.batch_size):
        inputs = (batch.images, batch.intrinsics, batch.cam_to_ego, pixel_ray_maps(batch))
        returned = model(*(tensor.to(target) for tensor in inputs))
        boxes, scores, labels = checked_answer(returned, len(batch.tokens), len(to_rigopt), detector.name)
        for token, box, score, label in zip(batch.tokens, boxes, scores, labels):
            real = np.flatnonzero(label >= 0)
            best = real[np.argsort(-score[real], kind="stable")[:TOP_K]] if len(real) > TOP_K else real
            predictions.append(SamplePrediction(token, box[best, :3], to_rigopt[label[best]], score[best])
                               .within(EVAL_RANGE))
    check_frame(predictions, detector.name)
    return predictions


def checked_answer(returned, samples: int, n_classes: int, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A detector's answer to a batch of ``samples`` as numpy (boxes (B, K, 7) float, scores (B, K) float,
    labels (B, K) int), or a DataError naming the breach of the contract."""
    expected = f"(boxes (B, K, 7), scores (B, K), labels (B, K)) with B = {samples}"
    if not (isinstance(returned, (tuple, list)) and len(returned) == 3
            and all(isinstance(t, torch.Tensor) for t in returned)):
        raise DataError(f"detector {name} returned {_described(returned)}; the contract expects three tensors {expected}")
    boxes, scores, labels = (t.detach().cpu() for t in returned)
    shapes = tuple(tuple(t.shape) for t in (boxes, scores, labels))
    if not (boxes.ndim == 3 and boxes.shape[0] == samples and boxes.shape[2] == 7
            and scores.shape == labels.shape == boxes.shape[:2]):
        raise DataError(f"detector {name} returned shapes {shapes}; the contract expects {expected}")
    if labels.is_floating_point() or labels.is_complex() or labels.dtype == torch.bool:
        raise DataError(f"detector {name} returned labels of {labels.dtype}; the contract expects whole numbers")
    boxes, scores, labels = boxes.double().numpy(), scores.double().numpy(), labels.long().numpy()
    real = labels >= 0
    if (labels >= n_classes).any() or (labels < -1).any():
        raise DataError(f"detector {name} returned label {int(labels[(labels >= n_classes) | (labels < -1)][0])}; "
                        f"its card names {n_classes} classes (labels 0 to {n_classes - 1}, -1 for padding)")
    if not (np.isfinite(boxes[real]).all() and np.isfinite(scores[real]).all()):
        raise DataError(f"detector {name} returned NaN or infinite boxes or scores; the contract expects finite "
                        "values for every detection (label -1 marks padding)")
    if ((scores[real] < 0) | (scores[real] > 1)).any():
        bad = scores[real][(scores[real] < 0) | (scores[real] > 1)][0]
        raise DataError(f"detector {name} returned score {bad:.4g}; the contract expects scores in [0, 1] "
                        "(probabilities, e.g. a sigmoid)")
    if (boxes[real][:, 3:6] <= 0).any():
        raise DataError(f"detector {name} returned a box with a size <= 0; the contract expects length, width and "
                        "height in metres, above 0")
    return boxes, scores, labels


def check_frame(predictions: list[SamplePrediction], name: str) -> None:
    """A DataError when the detections' median centre height lies outside HEIGHTS: not ego-frame boxes."""
    heights = np.concatenate([p.centers[:, 2] for p in predictions]) if predictions else np.zeros(0)
    if len(heights) and not HEIGHTS[0] <= np.median(heights) <= HEIGHTS[1]:
        raise DataError(f"detector {name} returned boxes at a median height of {np.median(heights):.1f} m; the "
                        "contract expects the ego frame (ISO 8855: x forward, y left, z up, origin on the ground), "
                        "where objects stand within a few metres of the ground: boxes in a camera's frame?")


def _described(value) -> str:
    if isinstance(value, (tuple, list)):
        return f"a {type(value).__name__} of {len(value)} ({', '.join(type(v).__name__ for v in value)})"
    return f"a {type(value).__name__}"


class ContractModule(torch.nn.Module):
    """A rigopt detector behind the contract: ``(images, intrinsics, cam_to_ego, rays) -> (boxes, scores,
    labels)``, its ``top_k`` best heatmap peaks per sample (labels index ``CLASSES``), for tracing."""

    def __init__(self, model, top_k: int = TOP_K):
        super().__init__()
        self.model, self.top_k = model, top_k

    def forward(self, images, intrinsics, cam_to_ego, rays):
        batch = Batch(images, intrinsics, cam_to_ego, [], [], rays=rays)
        found = self.model.head.decode_batch(self.model(batch), self.top_k)
        boxes = torch.cat([found["centers"], found["sizes"], found["yaws"][..., None]], dim=-1)
        return boxes, found["scores"], found["classes"]


def export_torchscript(checkpoint: Path, out: Path, image_size: tuple[int, int], batch_size: int = 16,
                       name: str | None = None) -> dict:
    """Trace the lss model of a rigopt checkpoint (a run's or a shipped pack's) behind the contract and write it
    to ``out`` (TorchScript, its card inside; whole or not at all); returns the card. ``batch_size``: the batch
    the card asks rigopt to call it with (rigopt's own scoring uses 16: the same numbers)."""
    from rigopt.output import atomic_file
    from rigopt.validation.detectors.models import load_checkpoint, model_from_checkpoint

    state = load_checkpoint(checkpoint)
    if state["family"] != "lss":
        raise DataError(f"{checkpoint}: a {state['family']} model; rigopt exports lss models (the shipped family) only")
    model = model_from_checkpoint(state)[0].float().eval()
    width, height = image_size
    example = Batch(torch.rand(2, 3, 3, height, width), torch.eye(3).repeat(2, 3, 1, 1), torch.eye(4).repeat(2, 3, 1, 1),
                    [], [])
    example.intrinsics[..., 0, 0] = example.intrinsics[..., 1, 1] = width / 2
    example.intrinsics[..., 0, 2], example.intrinsics[..., 1, 2] = width / 2, height / 2
    inputs = (example.images, example.intrinsics, example.cam_to_ego, pixel_ray_maps(example))
    import warnings

    with warnings.catch_warnings():  # the tracer's notes on Python ints taken from shapes, checked by the tests
        warnings.simplefilter("ignore")
        traced = torch.jit.trace(ContractModule(model), inputs, check_trace=False)
    card = {"contract": CONTRACT, "name": name or f"{state['family']}-{state['rig']}-seed{state.get('seed', 0)}",
            "image_size": [width, height], "classes": list(CLASSES), "batch_size": batch_size,
            "trained_on": state["rig"]}
    with atomic_file(out) as work:
        torch.jit.save(traced, str(work), _extra_files={CARD_FILE: json.dumps(card)})
    return card
