"""The mount rules: where a camera may go on a vehicle, checked with python-fcl (the solids are in
:mod:`rigopt.mounting.shapes`; the rules' settings, :class:`MountRules`, and what a check finds, :class:`RigCheck`,
in :mod:`rigopt.mounting.records`).

A camera is valid on a vehicle when
  1. its lens is outside the body and at most ``max_distance`` from the surface;
  2. its housing, a box ``housing`` (width along the horizontal tangent, height, depth along the outward
     normal) whose back face lies on the surface at the lens's foot point, penetrates the body by no more
     than ``penetration_tolerance``;
  3. its near view frustum (from ``near`` to ``frustum_range`` metres, the image shrunk by
     ``frustum_margin`` of each half-angle; a near_field camera's central 60-degree cone, since a surround-view
     fisheye sees its own body at its edges) does not intersect the body, a solid: neither its surface (fcl)
     nor its inside, which the frustum's probe rays find from the lens (a lens facing into the body from its
     skin has its whole frustum inside it, where fcl's surface mesh meets nothing);
  4. its foot point and surface normal lie in one of the vehicle's zones;
  5. its housing does not collide with another camera's housing (cameras of one module, ``Camera.module``,
     share a housing and do not clash with each other);
  6. mounting practice allows its lens position (:mod:`rigopt.mounting.practice`: not on a wheel, tyre or
     arch, not below the minimum lens height, not in a keep-out such as locker doors or a coupled trailer, not
     on a step, a door frame or hinge line, a rail, ladder, light bar or rack, an arch lip, in a tyre's spray,
     beyond the legal width, in the tilt-cab arc or the trailer's swing, nor on the windscreen outside the
     wiped area: :mod:`rigopt.mounting.features`), and no keep-out that blocks views (a coupled trailer) nor
     a trailer's swing is in its near view;
  7. it does not duplicate another camera of the rig (the same lens, close by, looking the same way).
The lens sits at the housing's centre, so a well-mounted camera is ``housing[2] / 2`` off the surface.

Raised mounts: a zone with ``raised_max`` > 0 (a roof rack, sensor pod or mast) lets a camera sit up to
that far above the surface. A camera further than ``max_distance`` from the surface is on a raised mount
when the line from its lens against the zone's ``normal`` (the post's axis) meets the surface within
``raised_max`` at a point of that zone. Its housing is then centred on the lens, oriented by the post's
axis, and a *post* stands under it: a box of the housing's footprint (width x height) from the surface to
the housing's back face. Rules 2-5 apply with the housing where the camera is; the post counts as part of
the body for every camera's view frustum (its own included) and housing (rules 3 and 5); it is not tested
against the body it stands on.

The keep-outs, a trailer's swing and the posts are fcl boxes and cylinders, solids: a frustum wholly inside one
collides with it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from rigopt.mounting.features import WINDSCREEN_VIEW_DEG, off_windscreen_view, trailer_swings
from rigopt.mounting.practice import duplicates, keep_out_boxes, practice_problems, separate_housings
from rigopt.mounting.records import CameraCheck, MountRules, RaisedMount, RigCheck
from rigopt.mounting.shapes import (box_object, collides, frustum_object, housing_object, post_object, probe_rays,
                                    swing_object)
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.model import Vehicle


def housing_fits(vehicle: Vehicle, feet, normals, rules: MountRules = MountRules()) -> np.ndarray:
    """(n,) bool: a housing with its back face at each foot point (n, 3) on a surface of normal (n, 3) sinks
    no deeper than ``rules.penetration_tolerance`` into the body (the housing rule, for mount points). A foot on a
    degenerate face (a zero normal: meshes carry a few zero-area faces) has no surface to sit on: it does not fit."""
    body = vehicle.collision_object
    feet, normals = np.atleast_2d(feet), np.atleast_2d(normals)
    forward = np.array([1.0, 0.0, 0.0])
    return np.array([bool(np.linalg.norm(normal) > 0.5) and not collides(
        housing_object(foot, normal, forward, rules.housing, rules.penetration_tolerance), body)
        for foot, normal in zip(feet, normals)], dtype=bool)


def raised_mounts(vehicle: Vehicle, positions) -> list[RaisedMount | None]:
    """For each lens position (n, 3) m: the raised zone whose post can carry it (first in zone order), or
    None: the line against the zone's normal meets the body within ``raised_max`` in that zone."""
    positions = np.atleast_2d(positions)
    found: list[RaisedMount | None] = [None] * len(positions)
    for zone in (z for z in vehicle.zones if z.raised):
        hits = vehicle.ray_caster.first_hits(positions, np.broadcast_to(-zone.normal, positions.shape))
        normals = vehicle.mesh.face_normals[np.maximum(hits.face, 0)]
        ok = (hits.distance <= zone.raised_max) & (hits.face >= 0)
        for k in np.flatnonzero(ok):
            if found[k] is None and zone.contains(hits.location[k], normals[k])[0]:
                found[k] = RaisedMount(zone, hits.location[k], zone.normal, float(hits.distance[k]))
    return found


def check_unassembled(rig: Rig, vehicle: Vehicle, rules: MountRules = MountRules()) -> RigCheck:
    """:func:`check_rig` of a design's cameras while they are being placed: every rule but the module rule, which
    the design meets once placed (its lenses closer than a module's size become one module,
    :func:`rigopt.mounting.practice.as_modules`, and the assembled rig is checked whole)."""
    return check_rig(rig, vehicle, replace(rules, practice=replace(rules.practice, module_distance=0.0)))


def check_rig(rig: Rig, vehicle: Vehicle, rules: MountRules = MountRules()) -> RigCheck:
    """Apply every mount rule to every camera of ``rig`` on ``vehicle`` (raised mounts: see the module doc)."""
    body = vehicle.collision_object
    surface = vehicle.surface(rig.positions)
    zones = vehicle.zone_names(surface.foot, surface.normal)
    mounts = _raised_mounts_of(rig, vehicle, surface, rules)
    housings = _Housings.of(rig, surface, mounts, rules)
    practice = practice_problems(vehicle, rig.positions, rules.practice, rules.housing, surface)
    blockers = _view_blockers(vehicle, rules)
    duplicated = duplicates(rig, rules.practice)
    crowded = separate_housings(rig, rules.practice)
    checks = []
    for k, camera in enumerate(rig.cameras):
        distance, mount = float(surface.distance[k]), mounts[k]
        problems = list(practice[k]) + _surface_problems(distance, mount, vehicle, rules)
        sunk = housing_object(housings.feet[k], housings.axes[k], camera.forward, rules.housing,
                              rules.penetration_tolerance)
        if distance >= 0 and collides(sunk, body):
            problems.append(f"housing penetrates the body by more than {rules.penetration_tolerance * 100:.0f} cm")
        problems += _view_problems(camera, rig, vehicle, body, blockers, housings.posts, rules)
        zone = mount.zone.name if mount is not None else zones[k]
        if zone is None:
            problems.append("outside every mounting zone")
        elif rules.practice.feature_rules and off_windscreen_view([zone], camera.forward)[0]:
            problems.append(f"on the windscreen looking aside: a windscreen camera sits behind the glass and looks out "
                            f"through it, within {WINDSCREEN_VIEW_DEG:g} deg of straight ahead; one looking aside is a "
                            "housing on the glass's outside")
        problems += _clash_problems(k, rig, housings)
        problems += [reason for reason in (duplicated[k], crowded[k]) if reason is not None]
        checks.append(CameraCheck(camera.id, not problems, distance, zone, tuple(problems)))
    return RigCheck(rig.name, vehicle.name, tuple(checks))


def _raised_mounts_of(rig: Rig, vehicle: Vehicle, surface, rules: MountRules) -> list[RaisedMount | None]:
    """For each camera: the raised zone's post carrying it when its lens stands further than ``max_distance`` off
    the surface (:func:`raised_mounts`), else None."""
    far = surface.distance > rules.max_distance
    raised = raised_mounts(vehicle, rig.positions[far]) if far.any() and any(z.raised for z in vehicle.zones) else []
    mounts: list[RaisedMount | None] = [None] * len(rig.cameras)
    for k, mount in zip(np.flatnonzero(far), raised):
        mounts[k] = mount
    return mounts


@dataclass(frozen=True)
class _Housings:
    """Where each camera's housing sits: ``feet`` (n,) of (3,) m and ``axes`` (n,) of (3,) (its back face on the
    surface, or centred on a raised camera's lens along its post), the fcl ``objects`` (n,), and the ``posts``
    {camera index: fcl object} of raised cameras."""

    feet: list
    axes: list
    objects: list
    posts: dict

    @classmethod
    def of(cls, rig: Rig, surface, mounts: list, rules: MountRules) -> _Housings:
        feet = [surface.foot[k] if m is None else rig.positions[k] - m.axis * rules.housing[2] / 2.0
                for k, m in enumerate(mounts)]
        axes = [surface.normal[k] if m is None else m.axis for k, m in enumerate(mounts)]
        objects = [housing_object(feet[k], axes[k], c.forward, rules.housing) for k, c in enumerate(rig.cameras)]
        posts = {k: post_object(m, c.forward, rules) for k, (m, c) in enumerate(zip(mounts, rig.cameras))
                 if m is not None}
        return cls(feet, axes, objects, {k: p for k, p in posts.items() if p is not None})


def _view_blockers(vehicle: Vehicle, rules: MountRules) -> list[tuple]:
    """(fcl object, label) of what blocks a view besides the body: the keep-outs in force that occlude (a coupled
    trailer), by label, and the space a trailer's front swings through."""
    in_force = keep_out_boxes(vehicle, rules.practice.lifted, occluding_only=True) if rules.practice.enabled else []
    blockers = [(box_object(low, high), label) for low, high, label in sorted(in_force, key=lambda b: b[2])]
    swings = trailer_swings(vehicle, rules.practice.lifted) if rules.practice.feature_rules else []
    return blockers + [(swing_object(swing), swing.describe()) for swing in swings]


def _surface_problems(distance: float, mount: RaisedMount | None, vehicle: Vehicle, rules: MountRules) -> list[str]:
    """A lens inside the body, or too far off its surface without a raised zone's post to carry it."""
    if distance < 0:
        return [f"inside the body ({-distance * 100:.1f} cm deep)"]
    if distance > rules.max_distance and mount is None:
        raised_zones = ", ".join(f"{z.name} {z.raised_max * 100:.0f} cm" for z in
                                 {z.name: z for z in vehicle.zones if z.raised}.values())
        return [f"{distance * 100:.1f} cm off the surface (at most {rules.max_distance * 100:.0f} cm"
                + (f"; on a post over a raised zone: {raised_zones}" if raised_zones else "") + ")"]
    return []


def _view_problems(camera: Camera, rig: Rig, vehicle: Vehicle, body, blockers: list, posts: dict,
                   rules: MountRules) -> list[str]:
    """What is in the camera's checked frustum within ``frustum_range``: the body, a keep-out or swing, a post."""
    problems = []
    frustum = frustum_object(camera, rules)
    if collides(frustum, body) or _body_blocks_probes(vehicle, camera, rules):
        problems.append(f"the body is in its view within {rules.frustum_range:g} m")
    for label in dict.fromkeys(label for box, label in blockers if collides(frustum, box)):
        what = label if label.startswith("the ") else f"the keep-out {label}"
        problems.append(f"{what} is in its view within {rules.frustum_range:g} m")
    seen_posts = [j for j, post in posts.items() if collides(frustum, post)]
    if seen_posts:
        problems.append(f"the post of {', '.join(rig.cameras[j].id for j in seen_posts)} is in its view within "
                        f"{rules.frustum_range:g} m")
    return problems


def _clash_problems(k: int, rig: Rig, housings: _Housings) -> list[str]:
    """Camera k's housing against the other cameras' housings and posts (cameras of one module never clash)."""
    camera, own = rig.cameras[k], housings.objects[k]
    clashes = [other.id for j, other in enumerate(rig.cameras) if j != k and not _one_module(camera, other) and
               (collides(own, housings.objects[j]) or (j in housings.posts and collides(own, housings.posts[j])))]
    return [f"housing collides with {', '.join(clashes)}"] if clashes else []


def _body_blocks_probes(vehicle: Vehicle, camera: Camera, rules: MountRules) -> bool:
    """True when the body, a solid, blocks a probe ray of the camera's checked frustum within
    ``rules.frustum_range`` m of its lens (:meth:`rigopt.raycast.RayCaster.blocked_distance`)."""
    rays = probe_rays(camera, rules)
    origins = np.broadcast_to(camera.position, rays.shape)
    return bool((vehicle.ray_caster.blocked_distance(origins, rays) <= rules.frustum_range).any())


def _one_module(a: Camera, b: Camera) -> bool:
    """True when two cameras share a module (one housing: a roof cluster, a stereo pair)."""
    return a.module is not None and a.module == b.module
