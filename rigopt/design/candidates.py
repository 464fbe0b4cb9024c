"""The designer's discrete candidate cameras: valid mount points x clear orientations x catalogue cameras.

Mount points come from :func:`rigopt.mounting.sampling.sample_zone_points`; for every camera of the
catalogue (:class:`rigopt.design.settings.CatalogueCamera`: its real lens), the (pitch, yaw) grid
directions whose checked frustum is clear of the body (:func:`rigopt.mounting.candidates.clear_directions`)
become candidates. Angles in radians, ISO frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigopt.camera import CameraModel
from rigopt.design.settings import CatalogueCamera, catalogue_of
from rigopt.mounting.rules import MountRules
from rigopt.errors import RigoptError
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.mounting.candidates import body_fraction, clear_directions
from rigopt.mounting.sampling import sample_zone_points
from rigopt.vehicle.model import Vehicle


@dataclass(frozen=True)
class CandidateSet:
    """n candidate cameras on m mount points.

    positions (n, 3) m lens positions; rotations (n, 3, 3) R_vehicle_cam; fovs (n,) deg (the catalogue
    cameras' FOVs); yaws, pitches (n,) rad; mount (n,) int index into mount_points (m, 3) m, mount_normals
    (m, 3) and mount_zones (m,) str; lens (n,) int index into catalogue, the cameras they use.
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
    lens: np.ndarray
    catalogue: tuple[CatalogueCamera, ...]

    def __len__(self) -> int:
        return len(self.fovs)

    def subset(self, index) -> "CandidateSet":
        """The candidates ``index`` (k,) int, with the same mount point arrays."""
        index = np.asarray(index, dtype=int)
        return CandidateSet(self.positions[index], self.rotations[index], self.fovs[index], self.yaws[index],
                            self.pitches[index], self.mount[index], self.mount_points, self.mount_normals,
                            self.mount_zones, self.lens[index], self.catalogue)

    def model(self, index=slice(None)) -> CameraModel:
        """The CameraModel (batch (k,)) of the candidates ``index`` (default all): their lenses."""
        catalogue = CameraModel.of_lenses([c.lens for c in self.catalogue])
        chosen = self.lens[index]
        return CameraModel(*(getattr(catalogue, n)[chosen] for n in ("width", "height", "fx", "fy", "cx", "cy",
                                                                      "distortion", "coefficients")))

    def camera(self, k: int, id: str, with_zone: bool = True):
        """Candidate ``k`` as a rig camera named ``id``, with its catalogue camera's lens (and its mount
        point's zone unless ``with_zone`` is False)."""
        zone = str(self.mount_zones[self.mount[k]]) if with_zone else None
        return self.catalogue[self.lens[k]].camera(id, self.positions[k], self.rotations[k], zone)


def build_candidates(vehicle: Vehicle, lenses, spacing: float, yaws_deg, pitches_deg, zones=None,
                     rules: MountRules = MountRules(), max_body_fraction: float | None = None) -> CandidateSet:
    """Every clear (mount point, pitch, yaw, catalogue camera) combination as a candidate camera.

    lenses : the catalogue: CatalogueCameras, Lenses or FOVs (deg, benchmark pinholes), taken once each in
    the order of their FOVs (cameras of equal FOV in the given order); max_body_fraction : drop candidates
    whose image shows more of the ego body than this share (:func:`mounting.candidates.body_fraction`)."""
    unique = list(dict.fromkeys(catalogue_of(lenses)))
    catalogue = tuple(sorted(unique, key=lambda c: c.fov))
    points, normals, names = sample_zone_points(vehicle, spacing, zones, rules=rules)
    yaws = np.deg2rad(np.asarray(yaws_deg, dtype=float))
    pitches = np.deg2rad(np.asarray(pitches_deg, dtype=float))
    parts = []
    for index, entry in enumerate(catalogue):
        clear = clear_directions(vehicle, points, yaws, pitches, entry.lens, rules)  # (m, k, j)
        mount, pitch_index, yaw_index = np.nonzero(clear)
        parts.append((mount, pitches[pitch_index], yaws[yaw_index], np.full(len(mount), entry.fov),
                      np.full(len(mount), index)))
    mount, pitch, yaw, fov, lens = (np.concatenate(column) for column in zip(*parts))
    if len(mount) == 0:
        raise RigoptError(f"no mount point of {vehicle.name} has a clear view in any direction of the grid; "
                          "allow more zones or pitch angles")
    rotations = rotation_from_yaw_pitch_roll(yaw, pitch, np.zeros_like(yaw))
    candidates = CandidateSet(points[mount], rotations, fov, yaw, pitch, mount, points, normals, names, lens, catalogue)
    if max_body_fraction is None:
        return candidates
    keep = body_fraction(vehicle, candidates.positions, rotations, candidates.model()) <= max_body_fraction
    if not keep.any():
        raise RigoptError(f"every candidate camera of {vehicle.name} sees more than {max_body_fraction:.0%} of its "
                          "own body; allow more zones or pitch angles, or raise the body share allowed")
    mount, pitch, yaw, fov, lens, rotations = mount[keep], pitch[keep], yaw[keep], fov[keep], lens[keep], rotations[keep]
    return CandidateSet(points[mount], rotations, fov, yaw, pitch, mount, points, normals, names, lens, catalogue)
