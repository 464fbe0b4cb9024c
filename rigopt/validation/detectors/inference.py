"""Running a trained detector on a rig's split and scoring it with the benchmark's centre-distance mAP
(``rigopt.validation.synthetic.evaluation``).

Both ground truth and detections are kept within ``EVAL_RANGE`` m (bird's-eye distance) of the ego, as
nuScenes' evaluation keeps each class within its range; the detectors' bird's-eye square covers it. The
ground truth is every annotated object with its visibility under the split's rig, so that one matching
gives both the fixed-set and the visible-only score.
"""

from __future__ import annotations

import torch

from rigopt.validation.detectors.data import RigSplit
from rigopt.validation.detectors.families import Detector
from rigopt.validation.detectors.models import resolve_device
from rigopt.validation.synthetic.evaluation import (EVAL_RANGE, Detections, GroundTruth, MatchedDetections,
                                     SamplePrediction, match)

#: Detections per sample evaluated (the highest-scoring).
TOP_K = 100


@torch.no_grad()
def predict(model: Detector, split: RigSplit, device: str = "cpu", batch_size: int = 16,
            top_k: int = TOP_K, progress=lambda done, total: None) -> list[SamplePrediction]:
    """The ``top_k`` highest-scoring detections of every sample of ``split``, within EVAL_RANGE."""
    target = resolve_device(device)
    model = model.to(target).eval()
    predictions = []
    for batch in split.batches(batch_size):
        for token, found in zip(batch.tokens, model.detections(model(batch.to(target)), top_k)):
            predictions.append(SamplePrediction(token, found["centers"].numpy().astype(float), found["classes"].numpy(),
                                                found["scores"].numpy().astype(float)).within(EVAL_RANGE))
        progress(len(predictions), len(split))
    return predictions


def match_split(model: Detector, split: RigSplit, device: str = "cpu", batch_size: int = 16,
                progress=lambda done, total: None) -> MatchedDetections:
    """``model``'s detections on ``split`` matched to its ground truth (within EVAL_RANGE), indexed by the
    split's sample tokens in split order."""
    predictions = predict(model, split, device, batch_size, progress=progress)
    truth = GroundTruth.from_samples(split.samples).within(EVAL_RANGE)
    return match(Detections.from_predictions(predictions), truth, samples=[s.token for s in split.samples])
