"""Mounting practice: places a camera could physically sit but that no engineer would mount it.

Besides the geometric mount rules (:mod:`rigopt.mounting.rules`) a lens may not be

  - on a wheel, tyre or wheel arch: inside a wheel's *keep-out*, the disc of radius ``wheel radius +
    wheel_clearance`` around the axle (in x and z) from the wheel's inner face outwards (so the tyre's
    sidewall and the arch around it are covered, however far the body sticks out);
  - lower than the minimum lens height (tyre spray, kerbs, car washes): ``MountPractice.min_height``, else
    the vehicle's ``min_lens_height``, else 0.5 m;
  - inside one of the vehicle's keep-out boxes (``[[keep_out]]`` in its spec: roll-up locker doors, a
    coupled semi-trailer), unless that keep-out is optional and lifted by name.

Frames: ISO 8855 vehicle frame, metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigopt.vehicle.model import Vehicle

#: The lowest lens height (m) when neither the rules nor the vehicle say otherwise.
DEFAULT_MIN_HEIGHT = 0.5


@dataclass(frozen=True)
class MountPractice:
    """The practice rules' settings: ``min_height`` m (None: the vehicle's, else DEFAULT_MIN_HEIGHT),
    ``enabled`` False switches every practice rule off (to measure what practice costs); ``wheel_clearance`` m
    around each tyre (its arch lip; a fender camera above the arch, as on the benchmark's
    cars 8-17 cm from the tread, stays allowed), ``lifted`` names of optional keep-outs
    switched off (e.g. ``("trailer",)`` for a tractor unit driven solo)."""

    min_height: float | None = None
    wheel_clearance: float = 0.05
    lifted: tuple[str, ...] = ()
    enabled: bool = True

    def height_floor(self, vehicle: Vehicle) -> float:
        """The minimum lens height (m) on ``vehicle``."""
        if self.min_height is not None:
            return self.min_height
        given = vehicle.spec.min_lens_height
        return DEFAULT_MIN_HEIGHT if given is None else given


def on_wheels(vehicle: Vehicle, points, clearance: float) -> list[list[str]]:
    """For each point (n, 3) m: the wheels ('front-left wheel', ...) whose keep-out it is in."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    found: list[list[str]] = [[] for _ in range(len(points))]
    axles = vehicle.axles
    for centre, radius, width in vehicle.wheels:
        side = np.sign(centre[1]) or 1.0
        outboard = side * points[:, 1] >= abs(centre[1]) - width / 2.0 - 0.02
        near = np.hypot(points[:, 0] - centre[0], points[:, 2] - centre[2]) <= radius + clearance
        position = "front" if len(axles) > 1 and centre[0] == axles[0] else (
            "rear" if len(axles) > 1 and centre[0] == axles[-1] else f"x {centre[0]:.2f} m")
        name = f"{position}-{'left' if side > 0 else 'right'} wheel"
        for k in np.flatnonzero(outboard & near):
            found[k].append(name)
    return found


def keep_out_boxes(vehicle: Vehicle, lifted=(), occluding_only: bool = False) -> list[tuple[np.ndarray, np.ndarray, str]]:
    """The vehicle's keep-out boxes in force: (low (3,), high (3,), 'name (reason)'), mirrored copies
    expanded, lifted optional ones left out; with ``occluding_only`` only those that block views."""
    flip = np.array([1.0, -1.0, 1.0])
    out = []
    for box in vehicle.spec.keep_outs:
        if (box.optional and box.name in lifted) or (occluding_only and not box.occludes):
            continue
        label = f"{box.name} ({box.reason})"
        out.append((box.min, box.max, label))
        if box.mirrored:
            out.append((np.minimum(box.min * flip, box.max * flip), np.maximum(box.min * flip, box.max * flip), label))
    return out


def in_keep_outs(vehicle: Vehicle, points, lifted=()) -> list[list[str]]:
    """For each point (n, 3) m: the keep-out boxes ('name (reason)') it is in (lifted ones skipped)."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    found: list[list[str]] = [[] for _ in range(len(points))]
    for low, high, label in keep_out_boxes(vehicle, lifted):
        for k in np.flatnonzero(np.all((points >= low) & (points <= high), axis=1)):
            if label not in found[k]:
                found[k].append(label)
    return found


def segments_hit_boxes(starts, directions, length: float, boxes) -> np.ndarray:
    """(n,) bool: segments ``starts + s directions``, s in [0, length] (starts, directions (n, 3)), that
    meet any of ``boxes`` [(low (3,), high (3,), label), ...] (the slab test)."""
    starts, directions = np.asarray(starts, dtype=float), np.asarray(directions, dtype=float)
    hit = np.zeros(len(starts), dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse = 1.0 / directions
        for low, high, _ in boxes:
            a, b = (low - starts) * inverse, (high - starts) * inverse
            near = np.nanmax(np.where(np.isnan(a), -np.inf, np.minimum(a, b)), axis=1)
            far = np.nanmin(np.where(np.isnan(a), np.inf, np.maximum(a, b)), axis=1)
            hit |= (near <= far) & (far >= 0.0) & (near <= length)
    return hit


def practice_problems(vehicle: Vehicle, points, practice: MountPractice = MountPractice()) -> list[list[str]]:
    """For each lens position (n, 3) m: what mounting practice forbids there (empty lists where nothing)."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    if not practice.enabled:
        return [[] for _ in range(len(points))]
    floor = practice.height_floor(vehicle)
    wheels = on_wheels(vehicle, points, practice.wheel_clearance)
    boxes = in_keep_outs(vehicle, points, practice.lifted)
    problems = []
    for k, point in enumerate(points):
        mine = []
        if point[2] < floor - 1e-9:
            mine.append(f"lens {point[2]:.2f} m above the ground (at least {floor:.2f} m: spray and kerbs)")
        if wheels[k]:
            mine.append(f"on the {' and '.join(wheels[k])}: tyre or wheel arch")
        if boxes[k]:
            mine.append(f"in the keep-out {', '.join(boxes[k])}")
        problems.append(mine)
    return problems


def practical(vehicle: Vehicle, points, practice: MountPractice = MountPractice()) -> np.ndarray:
    """(n,) bool: lens positions mounting practice allows."""
    return np.array([not p for p in practice_problems(vehicle, points, practice)], dtype=bool)


#: Spray from a tyre reaches about this far (m) around it, fore and aft and above its top.
SPRAY_REACH_M = 0.6


def spray_exposure(vehicle: Vehicle, points) -> list[str]:
    """For each lens position (n, 3) m: "high" where tyre spray and road dirt reach it (outboard, within
    SPRAY_REACH_M of a tyre's tread in x and z), else "low". A soft attribute shown in reports."""
    return ["high" if wheels else "low" for wheels in on_wheels(vehicle, points, SPRAY_REACH_M)]


#: Extra mounting cost of a lens in tyre spray (it needs a washer and is cleaned more often), in units of an
#: ordinary body panel's cost (1).
SPRAY_COST = 0.5


def mounting_costs(vehicle: Vehicle, zones, points) -> np.ndarray:
    """(n,) float: the relative cost of mounting a lens at each of ``points`` (n, 3) m in ``zones`` (n,) zone
    names: the zone's ``cost`` (1 an ordinary body panel; 1 for an unknown zone) plus SPRAY_COST where tyre
    spray reaches the lens (:func:`spray_exposure`)."""
    cost = {z.name: z.cost for z in vehicle.zones}
    spray = np.array([s == "high" for s in spray_exposure(vehicle, points)], dtype=bool)
    return np.array([cost.get(z, 1.0) for z in zones], dtype=float) + SPRAY_COST * spray
