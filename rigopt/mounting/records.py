"""The mounting's plain records: the settings of the mount rules (:class:`MountRules`, its
:class:`MountPractice`) and what a check finds (:class:`RaisedMount`, :class:`CameraCheck`, :class:`RigCheck`).

The other modules of :mod:`rigopt.mounting` import these records and this module imports none of those modules,
so the package's modules form no cycle, not even through their annotations.

Frames and units: ISO 8855 vehicle frame, metres.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rigopt.vehicle.model import Vehicle, Zone

#: The lowest lens height (m) when neither the rules nor the vehicle say otherwise.
DEFAULT_MIN_HEIGHT = 0.5
#: A camera housing (m): width along the surface's horizontal tangent, height, depth along its outward normal.
DEFAULT_HOUSING = (0.08, 0.06, 0.06)


@dataclass(frozen=True)
class MountPractice:
    """The practice rules' settings: ``min_height`` m (None: the vehicle's, else DEFAULT_MIN_HEIGHT),
    ``enabled`` False switches every practice rule off (to measure what practice costs); ``wheel_clearance`` m
    around each tyre (a fender camera above the arch, as on the benchmark's cars 8-17 cm from the tread, stays
    allowed), ``lifted`` names of optional keep-outs switched off (e.g. ``("trailer",)`` for a tractor unit
    driven solo, which lifts the trailer's swing too).

    The body features (:mod:`rigopt.mounting.features`): ``feature_margin`` m, how close to a step's, a
    fixture's or a door's box a lens counts as on it (a housing's lens sits 3 cm off the surface);
    ``hinge_band`` m either side of a door's hinged edge; ``lip_band`` m beyond a wheel arch's edge (the
    housing reaches 3-4 cm towards it, the lip's flange 1-2 cm more); the tyre-spray cone's
    ``spray_elevation_deg`` (its axis above backwards), ``spray_half_angle_deg`` and ``spray_length`` m;
    ``width_exempt_zones`` zones whose cameras do not count in the legal width (mirrors) and
    ``width_allowance`` m how far other cameras may stick out beyond it (Regulation (EU) 1230/2012, Annex I,
    Appendix 1, point 1(c): devices on the sides other than mirrors, up to 100 mm in total, are not counted in
    the width; 0 refuses any protrusion); two cameras
    duplicate each other within ``duplicate_distance`` m and ``duplicate_angle_deg``; housings whose lenses lie
    closer than ``module_distance`` m are one module (a shared housing) or refused; ``features`` False switches
    the body-feature rules, the trailer's swing, the duplicate and the module rule off (the rules before them)."""

    min_height: float | None = None
    wheel_clearance: float = 0.05
    lifted: tuple[str, ...] = ()
    enabled: bool = True
    feature_margin: float = 0.05
    hinge_band: float = 0.10
    lip_band: float = 0.05
    spray_elevation_deg: float = 15.0
    spray_half_angle_deg: float = 15.0
    spray_length: float = 2.0
    width_exempt_zones: tuple[str, ...] = ("mirror",)
    width_allowance: float = 0.10
    duplicate_distance: float = 0.5
    duplicate_angle_deg: float = 10.0
    module_distance: float = 0.25
    features: bool = True

    @property
    def feature_rules(self) -> bool:
        """Whether the body-feature rules, the trailer's swing and the duplicate rule apply."""
        return self.enabled and self.features

    def height_floor(self, vehicle: Vehicle) -> float:
        """The minimum lens height (m) on ``vehicle``."""
        if self.min_height is not None:
            return self.min_height
        given = vehicle.spec.min_lens_height
        return DEFAULT_MIN_HEIGHT if given is None else given


@dataclass(frozen=True)
class MountRules:
    """Tolerances of the mount checks; lengths in metres, ``frustum_margin`` a fraction of each half-angle."""

    housing: tuple[float, float, float] = DEFAULT_HOUSING
    max_distance: float = 0.05
    penetration_tolerance: float = 0.01
    near: float = 0.02
    frustum_range: float = 1.0
    frustum_margin: float = 0.5
    practice: MountPractice = MountPractice()


@dataclass(frozen=True)
class RaisedMount:
    """A camera on a raised zone's post: ``zone``, ``foot`` (3,) m where the post meets the surface,
    ``axis`` (3,) the post's unit direction (the zone's normal), ``height`` m from the foot to the lens."""

    zone: Zone
    foot: np.ndarray
    axis: np.ndarray
    height: float


@dataclass(frozen=True)
class CameraCheck:
    """Outcome for one camera: ``distance_to_surface`` m (> 0 outside), ``zone`` (None outside every
    zone), ``problems`` (empty when valid)."""

    id: str
    valid: bool
    distance_to_surface: float
    zone: str | None
    problems: tuple[str, ...] = field(default_factory=tuple)


@dataclass(frozen=True)
class RigCheck:
    """Outcome for a rig on a vehicle; ``valid`` when every camera is."""

    rig: str
    vehicle: str
    cameras: tuple[CameraCheck, ...]

    @property
    def valid(self) -> bool:
        return all(c.valid for c in self.cameras)
