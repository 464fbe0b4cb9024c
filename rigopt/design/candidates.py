"""The designer's discrete candidate cameras: valid mount points x clear orientations x catalogue lenses.

Mount points come from :func:`rigopt.mounting.sampling.sample_zone_points`; for every lens of the
catalogue, the (pitch, yaw) grid directions whose checked frustum is clear of the body
(:func:`rigopt.mounting.candidates.clear_directions`) become candidates. Angles in radians, ISO frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigopt.mounting.rules import MountRules
from rigopt.errors import RigoptError
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.mounting.candidates import clear_directions
from rigopt.mounting.sampling import sample_zone_points
from rigopt.vehicle.model import Vehicle


@dataclass(frozen=True)
class CandidateSet:
    """n candidate cameras on m mount points.

    positions (n, 3) m lens positions; rotations (n, 3, 3) R_vehicle_cam; fovs (n,) deg; yaws, pitches (n,)
    rad; mount (n,) int index into mount_points (m, 3) m, mount_normals (m, 3) and mount_zones (m,) str.
    """

    positions: np.ndarray
    rotations: np.ndarray
    fovs: np.ndarray
    yaws: np.ndarray
    pitches: np.ndarray
    mount: np.ndarray
    mount_points: np.ndarray
    mount_normals: np.ndarray
    mount_zones: np.ndarray

    def __len__(self) -> int:
        return len(self.fovs)

    def subset(self, index) -> "CandidateSet":
        """The candidates ``index`` (k,) int, with the same mount point arrays."""
        index = np.asarray(index, dtype=int)
        return CandidateSet(self.positions[index], self.rotations[index], self.fovs[index], self.yaws[index],
                            self.pitches[index], self.mount[index], self.mount_points, self.mount_normals,
                            self.mount_zones)


def build_candidates(vehicle: Vehicle, lenses, spacing: float, yaws_deg, pitches_deg, zones=None,
                     rules: MountRules = MountRules()) -> CandidateSet:
    """Every clear (mount point, pitch, yaw, lens) combination as a candidate camera."""
    lenses = np.asarray(sorted(set(float(f) for f in lenses)), dtype=float)
    if len(lenses) == 0 or np.any(lenses <= 0) or np.any(lenses >= 180):
        raise RigoptError(f"lens FOVs must be in (0, 180) degrees, got {lenses.tolist()}")
    points, normals, names = sample_zone_points(vehicle, spacing, zones, rules=rules)
    yaws = np.deg2rad(np.asarray(yaws_deg, dtype=float))
    pitches = np.deg2rad(np.asarray(pitches_deg, dtype=float))
    parts = []
    for fov in lenses:
        clear = clear_directions(vehicle, points, yaws, pitches, fov, rules)  # (m, k, j)
        mount, pitch_index, yaw_index = np.nonzero(clear)
        parts.append((mount, pitches[pitch_index], yaws[yaw_index], np.full(len(mount), fov)))
    mount, pitch, yaw, fov = (np.concatenate(column) for column in zip(*parts))
    if len(mount) == 0:
        raise RigoptError(f"no mount point of {vehicle.name} has a clear view in any direction of the grid; "
                          "allow more zones or pitch angles")
    rotations = rotation_from_yaw_pitch_roll(yaw, pitch, np.zeros_like(yaw))
    return CandidateSet(points[mount], rotations, fov, yaw, pitch, mount, points, normals, names)
