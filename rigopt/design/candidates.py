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
from rigopt.mounting.features import WINDSCREEN_ZONE, off_windscreen_view
from rigopt.mounting.records import MountRules
from rigopt.errors import RigoptError
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.mounting.candidates import body_fraction, clear_directions
from rigopt.mounting.sampling import sample_symmetric_zone_points, sample_zone_points
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
    mirror: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.fovs)

    def subset(self, index) -> "CandidateSet":
        """The candidates ``index`` (k,) int, with the same mount point arrays."""
        index = np.asarray(index, dtype=int)
        return CandidateSet(self.positions[index], self.rotations[index], self.fovs[index], self.yaws[index],
                            self.pitches[index], self.mount[index], self.mount_points, self.mount_normals,
                            self.mount_zones, self.lens[index], self.catalogue)

    def mirror_closed(self, index) -> np.ndarray:
        """(k,) int: the sorted candidates ``index`` together with their mirrors (``index`` itself, sorted,
        for a set without mirrors)."""
        index = np.asarray(index, dtype=int)
        return np.union1d(index, self.mirror[index]) if self.mirror is not None else np.unique(index)

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


def windscreen_aside(names, yaws) -> np.ndarray:
    """(m, j) bool: mount points in the windscreen's zone (``names`` (m,)) with the yaws (j,) rad that look aside
    (:func:`rigopt.mounting.features.off_windscreen_view`, for a level axis)."""
    forwards = np.column_stack([np.cos(yaws), np.sin(yaws), np.zeros(len(yaws))])
    on_glass = np.asarray([name == WINDSCREEN_ZONE for name in names], dtype=bool)
    return on_glass[:, None] & off_windscreen_view([WINDSCREEN_ZONE] * len(yaws), forwards)[None, :]


def build_candidates(vehicle: Vehicle, lenses, spacing: float, yaws_deg, pitches_deg, zones=None,
                     rules: MountRules = MountRules(), max_body_fraction: float | None = None,
                     symmetric: bool = False, clear_lens=None) -> CandidateSet:
    """Every clear (mount point, pitch, yaw, catalogue camera) combination as a candidate camera.

    lenses : the catalogue: CatalogueCameras, Lenses or FOVs (deg, benchmark pinholes), taken once each in
    the order of their FOVs (cameras of equal FOV in the given order); max_body_fraction : drop candidates
    whose image shows more of the ego body than this share (:func:`mounting.candidates.body_fraction`);
    symmetric : mount points in mirrored pairs (:func:`rigopt.mounting.sampling.sample_symmetric_zone_points`)
    and only candidates whose mirror image is a candidate too (``CandidateSet.mirror``); clear_lens : the Lens
    whose checked frustum must be clear of the body, None for each catalogue camera's own
    (a surround-view fisheye sees its own body at its edges: its central cone is checked instead)."""
    unique = list(dict.fromkeys(catalogue_of(lenses)))
    catalogue = tuple(sorted(unique, key=lambda c: c.fov))
    if symmetric:
        points, normals, names, mirror_mount = sample_symmetric_zone_points(vehicle, spacing, zones, rules=rules)
    else:
        (points, normals, names), mirror_mount = sample_zone_points(vehicle, spacing, zones, rules=rules), None
    yaws = np.deg2rad(np.asarray(yaws_deg, dtype=float))
    pitches = np.deg2rad(np.asarray(pitches_deg, dtype=float))
    parts = []
    for index, entry in enumerate(catalogue):
        clear = clear_directions(vehicle, points, yaws, pitches, entry.lens if clear_lens is None else clear_lens,
                                 rules)  # (m, k, j)
        if rules.practice.feature_rules:  # a windscreen camera looks out through the glass
            clear &= ~windscreen_aside(names, yaws)[:, None, :]
        mount, pitch_index, yaw_index = np.nonzero(clear)
        parts.append((mount, pitch_index, yaw_index, np.full(len(mount), index)))
    mount, pitch_index, yaw_index, lens = (np.concatenate(column) for column in zip(*parts))
    keep = np.ones(len(mount), dtype=bool)
    if len(mount) and max_body_fraction is not None:
        rotations = rotation_from_yaw_pitch_roll(yaws[yaw_index], pitches[pitch_index], np.zeros(len(mount)))
        model = CandidateSet(points[mount], rotations, np.zeros(len(mount)), yaws[yaw_index], pitches[pitch_index],
                             mount, points, normals, names, lens, catalogue).model()
        keep = body_fraction(vehicle, points[mount], rotations, model) <= max_body_fraction
        if not keep.any():
            raise RigoptError(f"every candidate camera of {vehicle.name} sees more than {max_body_fraction:.0%} of "
                              "its own body; allow more zones or pitch angles, or raise the body share allowed")
    mirror = None
    if symmetric:
        keep, mirror = _mirror_pairs(keep, mount, pitch_index, yaw_index, lens, mirror_mount, yaws_deg)
    if not keep.any():
        raise RigoptError(f"no mount point of {vehicle.name} has a clear view in any direction of the grid"
                          f"{' in mirrored pairs (try --asymmetric)' if symmetric else ''}; allow more zones or "
                          "pitch angles")
    mount, pitch, yaw, lens = mount[keep], pitches[pitch_index[keep]], yaws[yaw_index[keep]], lens[keep]
    rotations = rotation_from_yaw_pitch_roll(yaw, pitch, np.zeros_like(yaw))
    fov = np.array([c.fov for c in catalogue])[lens]
    return CandidateSet(points[mount], rotations, fov, yaw, pitch, mount, points, normals, names, lens, catalogue,
                        mirror)


def _mirror_pairs(keep, mount, pitch_index, yaw_index, lens, mirror_mount, yaws_deg):
    """The candidates ``keep`` (n,) bool whose mirror image (mirrored mount point, same pitch and lens, yaw
    negated) is kept too, and each kept one's mirror as an index among the kept: (keep (n,) bool, mirror (k,) int)."""
    yaws = np.asarray(yaws_deg, dtype=float)
    wrapped = (-yaws + 180.0) % 360.0 - 180.0
    yaw_mirror = np.array([int(np.flatnonzero(np.isclose(yaws, w, atol=1e-9))[0])
                           if np.isclose(yaws, w, atol=1e-9).any() else -1 for w in wrapped])
    shape = (int(mount.max(initial=0)) + 1, int(pitch_index.max(initial=0)) + 1, len(yaws), int(lens.max(initial=0)) + 1)
    slot = np.full(shape, -1, dtype=int)
    slot[mount[keep], pitch_index[keep], yaw_index[keep], lens[keep]] = np.flatnonzero(keep)
    partner_yaw = yaw_mirror[yaw_index]
    partner = np.where(partner_yaw >= 0, slot[mirror_mount[mount], pitch_index, np.maximum(partner_yaw, 0), lens], -1)
    keep = keep & (partner >= 0)
    keep &= keep[np.maximum(partner, 0)]
    new_index = np.cumsum(keep) - 1
    return keep, new_index[partner[keep]]
