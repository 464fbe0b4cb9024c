"""A camera's bracket sheet: how it is fixed to the body and what moves or gets dirty around it.

What a packaging engineer needs beside the packaging sheet (:mod:`rigopt.coverage.packaging`) to draw the bracket
and route the cable. Inputs in the vehicle's mesh frame: ISO 8855 (x forward, y left, z up), metres, origin at
the vehicle's centre on the ground; reports shift positions to :func:`rigopt.coverage.packaging.report_origin`.

Definitions (one camera; its mount point and outward normal n are the body surface's nearest the lens):

- bracket angles (deg): the camera's yaw, pitch and roll (ISO 8855's order, as a rig's) relative to a bracket
  that looks straight out of the surface with its up along the surface's up: the bracket frame's x is n, its
  z the surface's up (:func:`rigopt.mounting.shapes.surface_frame`'s height axis, taken with the vehicle's
  forward on a level surface), its y their cross product. (0, 0, 0): the camera looks straight out;
- housing (m): the housing's width, height and depth (the mount rules' box), and the depth available behind the
  skin: how far the body, a solid, reaches inward along -n from the mount point before its other side (None
  when the ray leaves through no face, on an open mesh), at most DEPTH_CAP_M;
- clearances (m, 0 where the lens is inside): to the nearest door opening (a door's box) and whether the lens
  is in the door's swing (the quarter cylinder the door sweeps outside its opening about its hinge line, radius
  the door's width across the hinge); to the wheels' envelope (each tyre up to its bump travel, a steered one
  turned to its lock either way: :func:`rigopt.mounting.features.wheel_envelope_distances`; a mount rule keeps
  lenses out of it); whether the tilting cab sweeps the lens; for a lens on the wiped area's zone, how far it
  lies outside the wipers' sweep (seen from the front);
- harness: the ECU's place (``[ecu]`` is not a spec key: rigopt assumes the centreline halfway between the
  first and last axle, or the vehicle's centre, ECU_HEIGHT_M up, under the floor or a seat) and the cable's
  length along the vehicle's axes (|dx| + |dy| + |dz|, as a harness runs along rails and pillars) plus a
  SERVICE_LOOP_M service loop: an estimate to start the routing from;
- exposure: stone chips "high" for a lens looking within FORWARD_CONE_DEG of ahead in the front half of the
  body, lower than LOW_LENS_M, "medium" for such a lens higher up, else "low"; soiling "high" where tyre spray
  reaches (:func:`rigopt.mounting.practice.spray_exposure`) or for a lens looking within FORWARD_CONE_DEG of
  straight back lower than LOW_LENS_M (the wake's dirt), else "low"; a washer is advised where either is high.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigopt.geometry import yaw_pitch_roll_from_rotation
from rigopt.mounting import features
from rigopt.mounting.practice import spray_exposure
from rigopt.mounting.records import DEFAULT_HOUSING
from rigopt.mounting.shapes import surface_frame
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.placement import to_vehicle_centre
from rigopt.vehicle.spec import HINGE_EDGES

#: Deepest (m) the depth behind the skin is measured to.
DEPTH_CAP_M = 1.0
#: The assumed ECU's height above the ground (m).
ECU_HEIGHT_M = 0.5
#: Cable kept for service at the camera (m).
SERVICE_LOOP_M = 0.3
#: A lens looks ahead (or back) when its axis is within this angle (deg) of the vehicle's forward (backward).
FORWARD_CONE_DEG = 60.0
#: Lenses lower than this (m) sit in the stones and dirt the road throws up.
LOW_LENS_M = 1.2


@dataclass(frozen=True)
class BracketSheet:
    """One camera's bracket sheet (module docstring); positions (3,) m in the vehicle-centre frame."""

    camera: str
    bracket_ypr_deg: tuple[float, float, float]
    housing_m: tuple[float, float, float]
    depth_behind_skin_m: float | None
    door_m: float | None
    door_swing: str | None
    wheel_envelope_m: float | None
    tilt_cab_sweep: bool | None
    outside_wiped_area_m: float | None
    ecu: np.ndarray
    harness_m: float
    stone_chip: str
    soiling: str

    @property
    def washer(self) -> bool:
        """Whether a washer is advised: stones or dirt reach the lens (either exposure "high")."""
        return "high" in (self.stone_chip, self.soiling)

    def to_dict(self, origin=None) -> dict:
        """Plain JSON values, the ECU measured from ``origin`` (3,) m (vehicle-centre frame; default its centre)."""
        origin = np.zeros(3) if origin is None else np.asarray(origin, dtype=float)
        return {"bracket_ypr_deg": list(self.bracket_ypr_deg), "housing_m": list(self.housing_m),
                "depth_behind_skin_m": self.depth_behind_skin_m,
                "clearance_m": {"door": self.door_m, "wheel_envelope": self.wheel_envelope_m},
                "door_swing": self.door_swing, "tilt_cab_sweep": self.tilt_cab_sweep,
                "outside_wiped_area_m": self.outside_wiped_area_m, "ecu_m": (self.ecu - origin).tolist(),
                "harness_m": self.harness_m, "stone_chip": self.stone_chip, "soiling": self.soiling,
                "washer": self.washer}


def bracket_angles(camera: Camera, normal) -> tuple[float, float, float]:
    """(yaw, pitch, roll) deg of ``camera`` relative to a bracket looking straight out of a surface of outward
    ``normal`` (3,) with its up along the surface's up (module docstring)."""
    width, up, out = surface_frame(np.asarray(normal, dtype=float), np.array([1.0, 0.0, 0.0])).T
    bracket = np.column_stack([out, width, up])  # x out of the surface, y along it, z its up: right-handed
    yaw, pitch, roll = (float(np.rad2deg(a)) for a in np.ravel(yaw_pitch_roll_from_rotation(bracket.T @ camera.rotation)))
    return yaw, pitch, roll


def depth_behind_skin(vehicle: Vehicle, mount_point, normal) -> float | None:
    """How far (m, at most DEPTH_CAP_M) the body reaches inward from ``mount_point`` (3,) along -``normal``; None
    when the ray meets no face."""
    inward = -np.asarray(normal, dtype=float)
    start = np.asarray(mount_point, dtype=float) + inward * 1e-4  # just inside the skin
    distance = float(vehicle.ray_caster.first_hits(start[None], inward[None]).distance[0])
    return None if not np.isfinite(distance) else min(distance + 1e-4, DEPTH_CAP_M)


def door_clearance(vehicle: Vehicle, point) -> tuple[float | None, str | None]:
    """(distance m to the nearest door opening's box, 0 inside; the door whose swing holds ``point`` (3,) or
    None); (None, None) for a vehicle without door frames."""
    point = np.asarray(point, dtype=float)
    nearest, swing = None, None
    for door, low, high in features.feature_boxes(vehicle.spec.door_frames):
        gap = float(np.linalg.norm(np.maximum(np.maximum(low - point, point - high), 0.0)))
        nearest = gap if nearest is None else min(nearest, gap)
        if door.hinge is not None and swing is None and _in_swing(point, door.hinge, low, high):
            swing = door.name
    return nearest, swing


def _in_swing(point, hinge: str, low, high) -> bool:
    """Whether ``point`` lies in the quarter cylinder a door of box [low, high] sweeps outside its opening about
    its ``hinge`` edge (a HINGE_EDGES key)."""
    normal = int(np.argmin(high - low))  # across the door
    axis, side = HINGE_EDGES[hinge]  # the hinge line lies at this axis's high (side > 0) or low end
    along = next(a for a in range(3) if a not in (normal, axis))
    centre = (low + high) / 2.0
    outward = 1.0 if centre[normal] >= 0 else -1.0  # the door opens away from the vehicle's centre
    face = high[normal] if outward > 0 else low[normal]
    line = high[axis] if side > 0 else low[axis]
    radius = float(high[axis] - low[axis])
    outside = (point[normal] - face) * outward >= 0.0
    beside = low[along] <= point[along] <= high[along]
    within = np.hypot(point[axis] - line, point[normal] - face) <= radius
    towards = (point[axis] - line) * side <= 0.0  # on the door's side of its hinge line
    return bool(outside and beside and within and towards)


def wheel_envelope_distance(vehicle: Vehicle, point) -> float | None:
    """Distance (m, 0 inside) from ``point`` (3,) to the nearest wheel's envelope
    (:func:`rigopt.mounting.features.wheel_envelope_distances`); None for a vehicle whose wheels are unknown."""
    distance = features.wheel_envelope_distances(vehicle, point)
    return None if distance is None else float(distance[0])


def assumed_ecu(vehicle: Vehicle) -> np.ndarray:
    """(3,) m: where the sheet assumes the ECU (module docstring), vehicle-centre frame."""
    x = (max(vehicle.axles) + min(vehicle.axles)) / 2.0 if vehicle.axles else 0.0
    return np.array([x, 0.0, ECU_HEIGHT_M])


def exposure(camera: Camera, vehicle: Vehicle) -> tuple[str, str]:
    """(stone chip, soiling): "high", "medium" or "low" each (module docstring)."""
    cone = np.cos(np.deg2rad(FORWARD_CONE_DEG))
    ahead, behind = camera.forward[0] >= cone, camera.forward[0] <= -cone
    low = camera.position[2] < LOW_LENS_M
    front_half = camera.position[0] > 0.0
    stone = "high" if ahead and front_half and low else "medium" if ahead and front_half else "low"
    sprayed = spray_exposure(vehicle, camera.position[None])[0] == "high"
    soiling = "high" if sprayed or (behind and low) else "low"
    return stone, soiling


def bracket_sheet(camera: Camera, vehicle: Vehicle, housing=DEFAULT_HOUSING) -> BracketSheet:
    """The bracket sheet of ``camera`` (position in ``vehicle``'s centre frame) with a housing of ``housing``
    (w, h, d) m."""
    surface = vehicle.surface(camera.position[None])
    mount_point, normal = surface.foot[0], surface.normal[0] / np.linalg.norm(surface.normal[0])
    door_m, swing = door_clearance(vehicle, camera.position)
    cab = vehicle.spec.tilt_cab
    tilt = bool(features.in_tilt_arc(vehicle, camera.position[None], 0.0)[0]) if cab is not None else None
    wiped = vehicle.spec.wiped_area
    outside = None
    if wiped is not None and vehicle.zone_names(mount_point[None], normal[None])[0] == wiped.zone:
        outside = float(features.outside_wiped_area(vehicle, mount_point[None], [wiped.zone])[0])
    ecu = assumed_ecu(vehicle)
    harness = float(np.abs(camera.position - ecu).sum()) + SERVICE_LOOP_M
    stone, soiling = exposure(camera, vehicle)
    return BracketSheet(camera.id, bracket_angles(camera, normal), tuple(float(v) for v in housing),
                        depth_behind_skin(vehicle, mount_point, normal), door_m, swing,
                        wheel_envelope_distance(vehicle, camera.position), tilt, outside, ecu, harness, stone, soiling)


def rig_brackets(rig: Rig, vehicle: Vehicle, housing=DEFAULT_HOUSING) -> tuple[BracketSheet, ...]:
    """The bracket sheet of every camera of ``rig`` (placed on ``vehicle`` from whatever origin it is measured
    from), in camera order."""
    placed, _ = to_vehicle_centre(rig, vehicle)
    return tuple(bracket_sheet(camera, vehicle, housing) for camera in placed.cameras)
