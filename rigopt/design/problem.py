"""What a design starts from besides the target vehicle and the settings: the reference rigs, each on the
vehicle it was designed on, and the rigs to compare the design with; and the default ways to build them.

The designer looks nothing up by name: the caller (the command line, a study) builds these, usually with
``ReferenceRig.on_own_vehicle`` and ``benchmark_rigs``, and passes them in.
"""

from __future__ import annotations

from dataclasses import dataclass

from rigopt.rig.model import Rig
from rigopt.vehicle.model import Vehicle


@dataclass(frozen=True)
class ReferenceRig:
    """A rig a detector was trained on, and ``vehicle``, the vehicle it was mounted on there: what the rig
    sees around that vehicle is the coverage a design must keep."""

    rig: Rig
    vehicle: Vehicle

    @classmethod
    def on_own_vehicle(cls, rig: Rig) -> "ReferenceRig":
        """``rig`` on the built-in or user vehicle its ``vehicle`` field names (blueprint, name or alias), its
        positions converted to the vehicle's centre; cameras inside the body are refused."""
        from rigopt.vehicle.placement import rig_on_vehicle

        placed, vehicle, _ = rig_on_vehicle(rig, None)
        return cls(placed, vehicle)

    @classmethod
    def on_vehicle(cls, rig: Rig, vehicle: Vehicle) -> "ReferenceRig":
        """``rig`` placed on ``vehicle`` (:func:`rigopt.vehicle.placement.place_rig`): for imported rigs, whose
        own vehicle rigopt does not know."""
        from rigopt.vehicle.placement import place_rig

        placed, _ = place_rig(rig, vehicle)
        return cls(placed, vehicle)


def benchmark_rigs(vehicle: Vehicle) -> tuple[Rig, ...]:
    """The library's hand-designed rigs for ``vehicle`` (R6 on the firetruck, R9 on the hgv, ...): the
    default rigs a design is compared with."""
    from rigopt.rig.library import library_rig, rig_names

    rigs = [library_rig(name) for name in rig_names()]
    return tuple(rig for rig in rigs if rig.vehicle.lower() == vehicle.blueprint.lower())
