"""Mounting practice: places a camera could physically sit but that no engineer would mount it.

Besides the geometric mount rules (:mod:`rigopt.mounting.rules`) a lens may not be

  - on a wheel, tyre or wheel arch: inside a wheel's *keep-out*, the disc of radius ``wheel radius +
    wheel_clearance`` around the axle (in x and z) from the wheel's inner face outwards (so the tyre's
    sidewall and the arch around it are covered, however far the body sticks out);
  - lower than the minimum lens height (tyre spray, kerbs, car washes): ``MountPractice.min_height``, else
    the vehicle's ``min_lens_height``, else 0.5 m;
  - inside one of the vehicle's keep-out boxes (``[[keep_out]]`` in its spec: roll-up locker doors, a
    coupled semi-trailer), unless that keep-out is optional and lifted by name;
  - on the body features of :mod:`rigopt.mounting.features`: steps and tailboards, door frames and hinge
    lines, rails, ladders, light bars and racks, wheel-arch lips, tyre-spray cones, the wheels' envelope (steer
    and bump), beyond the legal width, in the tilt-cab arc or the trailer's swing, on the windscreen outside
    the wiped area.

And, for a whole rig (:func:`duplicates`): no two cameras duplicate each other (the same lens, lenses within
``duplicate_distance`` m, optical axes within ``duplicate_angle_deg``), unless they share a module (a stereo
pair is one on purpose); no two lenses closer than ``module_distance`` m sit in housings of their own
(:func:`separate_housings`; :func:`as_modules` makes them one module).

Its settings are :class:`rigopt.mounting.records.MountPractice`. Frames: ISO 8855 vehicle frame, metres.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from rigopt.mounting import features
from rigopt.mounting.records import DEFAULT_HOUSING, MountPractice
from rigopt.rig.model import Rig
from rigopt.vehicle.arches import wheel_name
from rigopt.vehicle.model import SurfaceQuery, Vehicle

def on_wheels(vehicle: Vehicle, points, clearance: float) -> list[list[str]]:
    """For each point (n, 3) m: the wheels ('front-left wheel', ...) whose keep-out it is in."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    found: list[list[str]] = [[] for _ in range(len(points))]
    for centre, radius, width in vehicle.wheels:
        side = np.sign(centre[1]) or 1.0
        outboard = side * points[:, 1] >= abs(centre[1]) - width / 2.0 - 0.02
        near = np.hypot(points[:, 0] - centre[0], points[:, 2] - centre[2]) <= radius + clearance
        for k in np.flatnonzero(outboard & near):
            found[k].append(wheel_name(vehicle.axles, centre))
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


def practice_problems(vehicle: Vehicle, points, practice: MountPractice = MountPractice(),
                      housing=DEFAULT_HOUSING, surface: SurfaceQuery | None = None) -> list[list[str]]:
    """For each lens position (n, 3) m: what mounting practice forbids there (empty lists where nothing).

    ``housing`` (w, h, d) m is the camera's (the legal width counts its outer face); ``surface`` the nearest
    body surface of ``points`` when the caller has it (else it is queried)."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    if not practice.enabled:
        return [[] for _ in range(len(points))]
    floor = practice.height_floor(vehicle)
    wheels = on_wheels(vehicle, points, practice.wheel_clearance)
    boxes = in_keep_outs(vehicle, points, practice.lifted)
    if not practice.features:
        return [_basic_problems(point, floor, wheels[k], boxes[k]) for k, point in enumerate(points)]
    surface = vehicle.surface(points) if surface is None else surface
    zones = vehicle.zone_names(surface.foot, surface.normal)
    margin = practice.feature_margin
    listed = [features.on_steps(vehicle, points, margin),
              features.in_door_frames(vehicle, points, margin, practice.hinge_band),
              features.on_fixtures(vehicle, points, margin),
              features.on_arch_lips(vehicle, points, practice.lip_band, practice.wheel_clearance),
              features.in_spray_cones(vehicle, points, practice),
              features.in_wheel_envelopes(vehicle, points)]
    protrusion, limit = features.width_protrusion(vehicle, points, surface.normal, zones, housing,
                                                  practice.width_exempt_zones)
    tilted = features.in_tilt_arc(vehicle, points, margin)
    swings = [(swing, *swing.holds(points)) for swing in features.trailer_swings(vehicle, practice.lifted)]
    # a lens on a post (a raised zone) looks through no windscreen
    on_surface = surface.distance <= housing[2] / 2.0 + margin
    unwiped = np.where(on_surface, features.outside_wiped_area(vehicle, surface.foot, zones), 0.0)
    problems = []
    for k, point in enumerate(points):
        mine = _basic_problems(point, floor, wheels[k], boxes[k])
        for found in listed:
            mine += found[k]
        if protrusion[k] > practice.width_allowance:
            legal, allowed = vehicle.legal_width, f"side devices may add {practice.width_allowance:.2f} m"
            mine.append(f"protrudes {protrusion[k]:.2f} m beyond the legal width {legal:.2f} m ({allowed})"
                        if limit[k] <= legal / 2.0 + 1e-9 else
                        f"protrudes {protrusion[k]:.2f} m beyond the body's side ({limit[k]:.2f} m from the "
                        f"centreline: the body is wider than the legal {legal:.2f} m; {allowed})")
        if tilted[k]:
            cab = vehicle.spec.tilt_cab
            mine.append(f"in the tilt-cab arc (the cab sweeps it tilting up to {cab.angle_deg:.0f} deg about "
                        f"x {cab.pivot[0]:.2f} m, z {cab.pivot[1]:.2f} m)")
        for swing, inside, depth in swings:
            if inside[k] and not any(swing.name in label for label in boxes[k]):
                mine.append(f"in {swing.describe()}: {depth[k]:.2f} m inside")
        if unwiped[k] > 1e-3:
            mine.append(f"on the windscreen outside the wiped area ({unwiped[k]:.2f} m from it)")
        problems.append(mine)
    return problems


def _basic_problems(point, floor: float, wheels: list[str], boxes: list[str]) -> list[str]:
    """A lens's problems with the rules before the body features: height, wheels, keep-outs."""
    mine = []
    if point[2] < floor - 1e-9:
        mine.append(f"lens {point[2]:.2f} m above the ground (at least {floor:.2f} m: spray and kerbs)")
    if wheels:
        mine.append(f"on the {' and '.join(wheels)}: tyre or wheel arch")
    if boxes:
        mine.append(f"in the keep-out {', '.join(boxes)}")
    return mine


def practical(vehicle: Vehicle, points, practice: MountPractice = MountPractice(), housing=DEFAULT_HOUSING,
              surface: SurfaceQuery | None = None) -> np.ndarray:
    """(n,) bool: lens positions mounting practice allows (see :func:`practice_problems`)."""
    return np.array([not p for p in practice_problems(vehicle, points, practice, housing, surface)], dtype=bool)


def duplicates(rig: Rig, practice: MountPractice = MountPractice()) -> list[str | None]:
    """For each camera of ``rig``: the reason it duplicates an earlier camera ('duplicates CAM_X: same lens,
    0.31 m apart, 4 deg apart'), or None. Two cameras duplicate each other when they have the same lens (the
    same FOV and real lens), their lenses lie within ``duplicate_distance`` m and their optical axes within
    ``duplicate_angle_deg``; cameras of one module (a stereo pair) never do. Only the later camera of a pair is
    named, so removing it leaves the rig without duplicates."""
    found: list[str | None] = [None] * len(rig.cameras)
    if not practice.feature_rules:
        return found
    cameras = rig.cameras
    for j, later in enumerate(cameras):
        for earlier in cameras[:j]:
            if later.module is not None and later.module == earlier.module:
                continue
            twin = _twins(later, earlier, practice)
            if twin is not None:
                found[j] = f"duplicates {earlier.id}: same lens, {twin[0]:.2f} m apart, {twin[1]:.0f} deg apart"
                break
    return found


def _twins(a, b, practice: MountPractice) -> tuple[float, float] | None:
    """(m apart, deg apart) when cameras ``a`` and ``b`` duplicate each other (the same lens, lenses within
    ``duplicate_distance`` m and optical axes within ``duplicate_angle_deg``), else None."""
    if a.lens != b.lens:
        return None
    apart = float(np.linalg.norm(a.position - b.position))
    angle = float(np.rad2deg(np.arccos(np.clip(a.forward @ b.forward, -1.0, 1.0))))
    return (apart, angle) if apart <= practice.duplicate_distance and angle <= practice.duplicate_angle_deg else None


def separate_housings(rig: Rig, practice: MountPractice = MountPractice()) -> list[str | None]:
    """For each camera of ``rig``: why its housing is too close to an earlier camera's ('0.173 m from CAM_X in a
    housing of its own: ...'), or None. Lenses closer than ``practice.module_distance`` m cannot sit in housings
    of their own: they are one module (the same ``Camera.module``, :func:`as_modules`) or stand farther apart.
    Only the later camera of a pair is named."""
    found: list[str | None] = [None] * len(rig.cameras)
    if not practice.feature_rules:
        return found
    for j, later in enumerate(rig.cameras):
        for earlier in rig.cameras[:j]:
            apart = float(np.linalg.norm(later.position - earlier.position))
            if apart < practice.module_distance and (later.module is None or later.module != earlier.module):
                found[j] = (f"{apart:.3f} m from {earlier.id} in a housing of its own: housings closer than "
                            f"{practice.module_distance:g} m are one module (give both the same module) or stand "
                            "farther apart")
                break
    return found


def as_modules(rig: Rig, practice: MountPractice = MountPractice()) -> Rig:
    """``rig`` with each group of cameras whose lenses lie closer than ``practice.module_distance`` m to one another
    (chained) in one module: the module a member has already (the first in camera order), else
    '<first member's id>_MODULE'. Two cameras that duplicate each other are not grouped (a module is no licence for
    an unplanned stereo pair: :func:`duplicates` still names them). Positions and lenses are unchanged; ``rig``
    itself when nothing is grouped."""
    cameras = list(rig.cameras)
    if not practice.feature_rules or len(cameras) < 2:
        return rig
    group = list(range(len(cameras)))  # each camera's group: the lowest index it is chained to

    def root(k: int) -> int:
        while group[k] != k:
            k = group[k]
        return k

    for j in range(len(cameras)):
        for i in range(j):
            close = float(np.linalg.norm(cameras[j].position - cameras[i].position)) < practice.module_distance
            if close and _twins(cameras[i], cameras[j], practice) is None:
                a, b = sorted((root(i), root(j)))
                group[b] = a
    members: dict[int, list[int]] = {}
    for k in range(len(cameras)):
        members.setdefault(root(k), []).append(k)
    changed = False
    for first, ks in members.items():
        if len(ks) < 2:
            continue
        module = next((cameras[k].module for k in ks if cameras[k].module), f"{cameras[first].id}_MODULE")
        for k in ks:
            if cameras[k].module != module:
                cameras[k], changed = replace(cameras[k], module=module), True
    return replace(rig, cameras=tuple(cameras)) if changed else rig


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
