"""Mirror symmetry of a body across its centre plane y = 0 (ISO vehicle frame, metres).

A vehicle counts as mirror-symmetric when its surface reflected across y = 0 lies within
``SYMMETRY_TOLERANCE_M`` of itself almost everywhere (the 99th percentile of the distances of reflected
surface samples to the body). The tolerance admits what real bodies carry on one side only (a truck's
lockers, mirror heads: the firetruck's right side stands 4-6 cm further out than its left) and rejects a
body that is not symmetric at all. Designs on a symmetric vehicle place cameras in mirrored pairs or on the
centreline (:mod:`rigopt.design.selection`); each camera of a pair sits on its own side's surface, so the
pair mirrors exactly in x, z, yaw, pitch and lens, and in |y| to within the body's own asymmetry.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from rigopt.geometry import geodesic_distance
from rigopt.quiet import quiet_trimesh

#: Largest 99th-percentile mirror distance (m) of a body that counts as symmetric (about a housing's width).
SYMMETRY_TOLERANCE_M = 0.10
#: Surface samples used to measure the mirror distance.
SYMMETRY_SAMPLES = 4000

#: The reflection across the centre plane y = 0.
MIRROR = np.diag([1.0, -1.0, 1.0])


@dataclass(frozen=True)
class MirrorSymmetry:
    """How far the body reflected across y = 0 lies from itself: ``p99`` and ``max`` (m) over surface
    samples, and ``symmetric``: p99 within SYMMETRY_TOLERANCE_M."""

    p99: float
    max: float

    @property
    def symmetric(self) -> bool:
        return self.p99 <= SYMMETRY_TOLERANCE_M

    def describe(self) -> str:
        verdict = "mirror-symmetric" if self.symmetric else "not mirror-symmetric"
        return (f"{verdict} across y = 0 (reflected surface within {self.p99 * 100:.1f} cm of the body for 99 % "
                f"of it, at most {self.max * 100:.1f} cm; tolerance {SYMMETRY_TOLERANCE_M * 100:.0f} cm)")


def mirror_symmetry(mesh: trimesh.Trimesh, samples: int = SYMMETRY_SAMPLES, seed: int = 1) -> MirrorSymmetry:
    """Measure the mirror symmetry of ``mesh`` (vehicle frame, m) across y = 0."""
    with quiet_trimesh():  # fewer than ``samples`` evenly spread points is fine
        points, _ = trimesh.sample.sample_surface_even(mesh, samples, seed=seed)
    distance = trimesh.proximity.closest_point(mesh, points @ MIRROR)[1]
    return MirrorSymmetry(float(np.percentile(distance, 99)), float(distance.max()))


def mirror_points(points) -> np.ndarray:
    """(n, 3) float: ``points`` (n, 3) reflected across y = 0 (also for directions and normals)."""
    return np.asarray(points, dtype=float) @ MIRROR


def mirror_rotations(rotations) -> np.ndarray:
    """(n, 3, 3) float: camera rotations R_vehicle_cam reflected across y = 0, kept right-handed (the camera's
    left axis flips back): yaw -> -yaw, pitch kept, roll -> -roll."""
    mirrored = MIRROR @ np.asarray(rotations, dtype=float)
    return mirrored @ MIRROR


def camera_mirrors(positions, rotations, fovs, position_tolerance: float = SYMMETRY_TOLERANCE_M,
                   angle_tolerance_deg: float = 0.5) -> np.ndarray:
    """(k,) int: for each camera the index of the camera at its mirror image across y = 0 (itself on the
    centreline facing straight ahead or back), or -1 when there is none.

    positions (k, 3) m, rotations (k, 3, 3) R_vehicle_cam, fovs (k,) deg. A mirror image has the same FOV,
    its rotation within ``angle_tolerance_deg`` of the reflected one and its lens within
    ``position_tolerance`` m of the reflected lens (bodies asymmetric by a few centimetres carry their pairs
    at slightly different |y|)."""
    positions, rotations, fovs = (np.asarray(a, dtype=float) for a in (positions, rotations, fovs))
    reflected, turned = mirror_points(positions), mirror_rotations(rotations)
    mirror = np.full(len(positions), -1, dtype=int)
    for i in range(len(positions)):
        distance = np.linalg.norm(positions - reflected[i], axis=1)
        angle = np.degrees(geodesic_distance(turned[i][None], rotations))
        fits = (distance <= position_tolerance) & (angle <= angle_tolerance_deg) & np.isclose(fovs, fovs[i])
        if fits.any():
            mirror[i] = int(np.flatnonzero(fits)[np.argmin(distance[fits])])
    return mirror


@dataclass(frozen=True)
class RigSymmetry:
    """A rig's cameras by mirror symmetry: ``pairs`` ((left id, right id), ...), ``centreline`` ids, ``unpaired``
    ids, and ``largest_offset`` (m), the largest distance of a camera from its partner's reflection."""

    pairs: tuple[tuple[str, str], ...]
    centreline: tuple[str, ...]
    unpaired: tuple[str, ...]
    largest_offset: float

    @property
    def symmetric(self) -> bool:
        return not self.unpaired

    def describe(self) -> str:
        if not self.symmetric:
            return (f"not symmetric: {len(self.unpaired)} camera(s) without a mirror image "
                    f"({', '.join(self.unpaired)})")
        return (f"symmetric: {len(self.pairs)} mirrored pair(s) and {len(self.centreline)} camera(s) on the "
                f"centreline; pairs mirror within {self.largest_offset * 100:.1f} cm")

    def to_dict(self) -> dict:
        return {"symmetric": self.symmetric, "pairs": [list(p) for p in self.pairs],
                "centreline": list(self.centreline), "unpaired": list(self.unpaired),
                "largest_pair_offset_m": self.largest_offset}


def rig_symmetry(rig) -> RigSymmetry:
    """How the cameras of ``rig`` (vehicle frame) pair up across y = 0 (:func:`camera_mirrors`)."""
    mirror = camera_mirrors(rig.positions, rig.rotations, rig.fovs)
    ids = [c.id for c in rig.cameras]
    reflected = mirror_points(rig.positions)
    pairs, centre, unpaired, largest = [], [], [], 0.0
    for k, m in enumerate(mirror):
        if m < 0 or mirror[m] != k:
            unpaired.append(ids[k])
            continue
        largest = max(largest, float(np.linalg.norm(rig.positions[m] - reflected[k])))
        if m == k:
            centre.append(ids[k])
        elif rig.positions[k, 1] > rig.positions[m, 1]:
            pairs.append((ids[k], ids[m]))
    return RigSymmetry(tuple(pairs), tuple(centre), tuple(unpaired), largest)
