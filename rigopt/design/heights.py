"""The height search: each perception camera moved to the valid mount nearest its reference camera's height.

The MILP chooses mounts on a grid about 0.1 m apart (``default_spacing``), coarser than the default height
tolerance of 0.05 m: where no grid point lies within it, a camera keeps the nearest grid height (the fire
truck's rear camera 0.15 m above R1's). After the MILP (and the refinement), with a height tolerance and
freely placed perception cameras, each perception camera in turn moves to the mount point of a finer grid
(``HEIGHT_SEARCH_SPACING``) within ``settings.height_search_m`` of its mount whose height above the ground is
nearest its matched reference camera's, keeping its direction and lens; heights within ``HEIGHT_STEP_M`` of
each other count as equal and the shorter move wins. A move is kept only when the whole rig still passes the
mount checks, the camera shows no more of the body than the candidates may, and the rig still meets its
coverage requirements; at most ``MAX_TRIES`` points are tried per camera (a work limit, never a clock).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from rigopt.camera import CameraModel
from rigopt.design.naming import mount_name, unique
from rigopt.design.settings import DesignSettings
from rigopt.mounting.candidates import body_fraction
from rigopt.mounting.rules import check_unassembled
from rigopt.mounting.sampling import sample_zone_points
from rigopt.rig.model import Rig
from rigopt.vehicle.model import Vehicle

#: Spacing (m) of the fine mount grid the search moves cameras to.
HEIGHT_SEARCH_SPACING = 0.03
#: Heights (m) closer than this count as equal; a move must bring a camera at least this much nearer.
HEIGHT_STEP_M = 0.01
#: Mount points tried per camera, nearest height first.
MAX_TRIES = 40


@dataclass(frozen=True)
class HeightMove:
    """One camera's move: its id, its matched reference camera's id and height (m above the ground), its
    height before and after (m) and how far its lens moved (m)."""

    camera: str
    reference: str
    reference_m: float
    from_m: float
    to_m: float
    moved_m: float

    def to_dict(self) -> dict:
        return {"camera": self.camera, "reference": self.reference, "reference_m": self.reference_m,
                "from_m": self.from_m, "to_m": self.to_m, "moved_m": self.moved_m}


def search_heights(rig: Rig, matched: np.ndarray, reference: Rig, vehicle: Vehicle, radius: float,
                   settings: DesignSettings,
                   meets_requirements: Callable[[Rig], bool]) -> tuple[Rig, tuple[HeightMove, ...]]:
    """``rig`` with its first ``len(matched)`` cameras (the perception cameras, camera k matched to reference
    camera ``matched[k]``; positions in ``vehicle``'s centre frame, ground at z = 0) moved as the module says,
    within ``radius`` m, under ``settings``' zones, mount rules and body share; ``meets_requirements(rig)``
    says whether a moved rig still meets the design's coverage requirements. Returns the rig, its moved cameras
    renamed after their new mounts (:mod:`rigopt.design.naming`), and the moves."""
    points, _, zones = sample_zone_points(vehicle, HEIGHT_SEARCH_SPACING, settings.zones, rules=settings.rules,
                                          near=(rig.positions[:len(matched)], radius))
    cameras, moves = list(rig.cameras), []
    for k, r in enumerate(np.asarray(matched, dtype=int)):
        camera, target = cameras[k], float(reference.cameras[r].position[2])
        gap = abs(float(camera.position[2]) - target)
        distance = np.linalg.norm(points - camera.position, axis=1)
        steps = np.floor(np.abs(points[:, 2] - target) / HEIGHT_STEP_M)
        nearer = np.flatnonzero((distance <= radius) & (steps < np.floor(gap / HEIGHT_STEP_M)))
        for i in nearer[np.lexsort((distance[nearer], steps[nearer]))][:MAX_TRIES]:
            moved = replace(camera, position=points[i].copy(), zone=str(zones[i]))
            trial = Rig(rig.name, rig.vehicle, tuple(cameras[:k] + [moved] + cameras[k + 1:]))
            if settings.max_body_fraction is not None and body_fraction(
                    vehicle, moved.position[None], moved.rotation[None],
                    CameraModel.of_cameras([moved]))[0] > settings.max_body_fraction:
                continue
            if check_unassembled(trial, vehicle, settings.rules).valid and meets_requirements(trial):
                cameras[k] = moved
                moves.append((k, HeightMove(camera.id, reference.cameras[r].id, target, float(camera.position[2]),
                                            float(moved.position[2]), float(distance[i]))))
                break
    if not moves:
        return rig, ()
    n = len(matched)
    names = unique([mount_name(c.zone, c.position, c.forward) for c in cameras[:n]])
    cameras[:n] = [replace(c, id=name) for c, name in zip(cameras[:n], names)]
    return (Rig(rig.name, rig.vehicle, tuple(cameras)),
            tuple(replace(move, camera=cameras[k].id) for k, move in moves))
