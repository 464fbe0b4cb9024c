"""What ``design_rig`` returns: the design, each stage's facts (MILP, refinement) and the comparisons, in
one ``DesignResult`` from which the report writers and the command line take everything they show."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

from rigopt.mounting.candidates import rig_body_share
from rigopt.mounting.records import RigCheck
from rigopt.design.problem import ReferenceRig
from rigopt.design.selection import Selection
from rigopt.design.settings import DesignSettings
from rigopt.metrics.calibration import Calibration
from rigopt.metrics.drop_model import DropModel
from rigopt.metrics.ranking import TransferPrediction, predict_transfer
from rigopt.rig.model import Rig
from rigopt.vehicle.model import Vehicle


@dataclass(frozen=True)
class RigSummary:
    """A rig judged against the reference(s): predicted transfer from each, coverage (fraction of sector
    points seen), and whether it meets the design's coverage requirements; ``check``: its mount checks when
    they were run."""

    rig: Rig
    predictions: tuple[TransferPrediction, ...]
    coverage: float
    meets_requirements: bool
    check: RigCheck | None = None

    @property
    def prediction(self) -> TransferPrediction:
        """The worst (largest predicted drop) of the predictions: the single one without a fleet."""
        return max(self.predictions, key=lambda p: p.predicted_drop)


@dataclass(frozen=True)
class MilpStage:
    """The discrete stage's outcome: ``rig``, the selected cameras (they pass the mount ``check``);
    ``selection``, the final MILP's answer (status, relative gap, objective, seconds); ``n_candidates``
    valid candidates in all, ``n_offered`` of them offered to the MILP after pruning; ``repairs``, the
    re-solves after removing cameras that failed the mount checks."""

    rig: Rig
    check: RigCheck
    selection: Selection
    n_candidates: int
    n_offered: int
    repairs: int

    @property
    def status(self) -> str:
        """The final MILP's solver status (``optimal``, or how it stopped)."""
        return self.selection.status

    @property
    def gap(self) -> float:
        """The final MILP's relative optimality gap."""
        return self.selection.gap


@dataclass(frozen=True)
class RefinementReport:
    """What the continuous stage did. ``status``: one line saying it ("off", "off (fleet design)",
    "accepted: IPOPT ..., k of n cameras moved, RigCD a -> b", "rejected: IPOPT ..., why");
    ``accepted``: the refined rig replaced the MILP's; ``solver_status``: IPOPT's return status (None when
    it did not run); ``cameras_moved``: cameras of the refined rig off their MILP pose; ``refined``: the
    refined rig's summary when it was built and passed the mount checks (accepted or not)."""

    status: str
    accepted: bool = False
    solver_status: str | None = None
    cameras_moved: int = 0
    refined: RigSummary | None = None


@dataclass(frozen=True)
class Comparisons:
    """The design's yardsticks, judged like the design: ``naive_transfer``, each reference camera moved to
    the nearest mount point facing its way (None when some camera finds none), then refined as the design
    is; ``rigs``, the rigs the caller asked to compare with (by default the library's hand-designed rigs for
    the vehicle)."""

    naive_transfer: RigSummary | None
    rigs: tuple[RigSummary, ...]
    naive_refinement: str = "off"
    """The naive transfer's continuous stage, as the design's (``refine_comparison``): its status line."""

    @property
    def best_rig(self) -> RigSummary | None:
        """The compared rig with the smallest predicted drop; None without any."""
        return min(self.rigs, key=lambda s: s.prediction.predicted_drop, default=None)


@dataclass(frozen=True)
class DesignResult:
    """A design and everything about how it was reached: the ``design`` (the MILP's rig, ``milp.rig``, or
    the accepted refinement), the MILP stage, the refinement report, the comparisons, the first
    reference's own coverage (fraction of sector points it sees on its vehicle), the inputs (``vehicle``,
    ``references`` on their vehicles, ``calibration``, ``settings``) and the design stages' wall time
    ``seconds``."""

    design: RigSummary
    milp: MilpStage
    refinement: RefinementReport
    comparisons: Comparisons
    reference_coverage: float
    vehicle: Vehicle
    references: tuple[ReferenceRig, ...]
    calibration: Calibration
    settings: DesignSettings
    seconds: float
    symmetry_fallback: str | None = None
    regions: tuple = ()
    """The design's dense coverage (RegionCoverage each) of the required regulation fields, or, when none
    is required, of the vehicle category's default fields (reported only)."""
    fields_fallback: str | None = None
    """Why the vehicle category's fields, required by default, were dropped (None when they were not)."""
    near_field: object = None
    """The near-field stage (:class:`rigopt.design.near_field.NearFieldDesign`) of a two-role design, else None
    (the fields ``settings.require`` names are then required of its cameras, not of the perception cameras)."""
    tolerance_widened: tuple[tuple[str, float], ...] = ()
    """(reference camera id, factor): the reference cameras no mount keeps within the pose tolerance, with the
    factor their tolerance was widened by (inf: matched without it)."""
    near_field_mirrored: bool = False
    """Whether the near-field cameras were placed in mirrored pairs (with the perception cameras or, under
    ``perception_symmetric=False``, without them)."""
    height_moves: tuple = ()
    """The height search's moves (:class:`rigopt.design.heights.HeightMove`), in camera order."""
    drop_model: DropModel | None = None
    """The drop model whose predictions the summaries carry (:func:`predicted_by`), None for RigCD's."""
    stand_ins: tuple[tuple[str, str], ...] = ()
    """(perception camera id, reference camera id): the first reference's camera each perception camera was
    designed for (the MILP's matching, its pose kept near that camera's under the pose tolerance), in camera order.
    RigCD's own matching of the final rig (the report's ``matched_reference_camera``) may pair them otherwise."""


def repredicted(summary: RigSummary | None, references: Sequence[Rig], calibration: Calibration,
                model: DropModel) -> RigSummary | None:
    """``summary`` with its prediction from each reference that ``model`` was fitted from made by the model (the
    others kept: RigCD's under ``calibration``); None stays None."""
    if summary is None:
        return None
    return replace(summary, predictions=tuple(
        predict_transfer(reference, [summary.rig.perception()], calibration, model, rig_body_share)[0]
        if model.applies_to(reference)
        else kept for reference, kept in zip(references, summary.predictions)))


def predicted_by(result: DesignResult, model: DropModel | None) -> DesignResult:
    """``result`` with every rig's predicted drop (design, refinement, comparisons) that of the drop ``model`` from
    each reference it was fitted from, RigCD's under the result's calibration from the others
    (:func:`repredicted`); the design itself, chosen before, does not change. ``model`` None: ``result`` as it is."""
    if model is None:
        return result
    references = [r.rig for r in result.references]

    def again(summary: RigSummary | None) -> RigSummary | None:
        return repredicted(summary, references, result.calibration, model)

    comparisons = replace(result.comparisons, naive_transfer=again(result.comparisons.naive_transfer),
                          rigs=tuple(map(again, result.comparisons.rigs)))
    refinement = replace(result.refinement, refined=again(result.refinement.refined))
    return replace(result, design=again(result.design), comparisons=comparisons, refinement=refinement,
                   drop_model=model)
