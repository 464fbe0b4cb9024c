"""The continuous stage: move the MILP's cameras off the sampling grid (casadi + IPOPT).

With the matching to the reference and the sector duties fixed, each camera k may slide in the tangent
plane of its mount point (offsets u, v within ``radius`` m), turn (yaw, pitch within the pitch limits) and,
for a continuous lens range, change its FOV (a benchmark pinhole only: a catalogue camera with a real lens
keeps its lens, intrinsics and distortion). The objective is the calibrated matching cost of the fixed
matching, smoothed (``sqrt(. + eps)``) where the distances have kinks. Each sector point a camera is on
duty for must stay inside its frustum by a margin (a smooth stand-in for coverage; the body's occlusion is
not modelled here). The result is projected back onto the body's surface and kept only when it passes the
mount checks, still meets every coverage requirement, and lowers the calibrated RigCD.

Steps follow the usual Opti shape: build, solve (solver output silenced, status checked), extract.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigopt.camera import CameraModel, camera_frame_points, pinhole_half_tangents
from rigopt.mounting.records import MountRules
from rigopt.mounting.shapes import surface_frame
from rigopt.geometry import rotation_from_yaw_pitch_roll, symbolic_rotation_angle, symbolic_rotation_from_yaw_pitch
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.symmetry import mirror_points

#: Smoothing of norms and angles at zero (m^2 and rad^2).
SMOOTHING = 1e-6
#: Duty points must stay this fraction of the half-angle tangent inside the frustum.
FRUSTUM_INSET = 0.03
#: Half-angle cap (deg) of the tangent box that stands in for a real lens's view (tangents grow without
#: bound towards 90 degrees, and a fisheye sees beyond).
MAX_DUTY_HALF_ANGLE_DEG = 75.0


def lens_half_tangents(camera: Camera) -> tuple[float, float]:
    """(tan_h, tan_v) of the box of directions (1, a, b), |a| <= tan_h, |b| <= tan_v, that a camera with a real
    lens keeps its duty points in: the smaller of its left/right and top/bottom edge-midpoint angles
    (:meth:`rigopt.camera.CameraModel.edge_angles`), capped at MAX_DUTY_HALF_ANGLE_DEG. A stand-in for the
    lens's view like the pinhole's; the refined rig's coverage is recomputed exactly."""
    left, right, up, down = (float(a) for a in CameraModel.of_camera(camera).edge_angles())
    cap = np.deg2rad(MAX_DUTY_HALF_ANGLE_DEG)
    return float(np.tan(min(left, right, cap))), float(np.tan(min(up, down, cap)))


@dataclass(frozen=True)
class RefineProblem:
    """Inputs of the refinement.

    design : the MILP's rig; matched : (k,) int reference camera of each design camera (-1 none);
    normals : (k, 3) outward normals at the design cameras' mount points; duties : (k, q) bool sector points
    each camera must keep in view; points : (q, 3) m sector points; weights: ``alpha``, ``lambdas``;
    ``pitch_range`` (rad); ``fov_range`` (deg) or None to keep each camera's FOV; ``radius`` (m), how far
    each camera may slide: one for all or (k,) per camera (see :func:`free_radii`);
    ``mirror`` (k,) int the camera at each one's mirror image across y = 0 (itself on the centreline, -1
    none), or None: pairs move as mirror images (the same tangent move reflected, yaw negated, pitch and FOV
    shared) and a centreline camera stays on y = 0 facing ahead or back.
    """

    design: Rig
    reference: Rig
    matched: np.ndarray
    normals: np.ndarray
    duties: np.ndarray
    points: np.ndarray
    alpha: float
    lambdas: tuple[float, float, float]
    pitch_range: tuple[float, float]
    fov_range: tuple[float, float] | None
    radius: float | np.ndarray
    mirror: np.ndarray | None = None


@dataclass(frozen=True)
class RefineOutcome:
    """IPOPT's ``status`` and the refined (not yet validated) ``rig``: the solution, or the last iterate when
    IPOPT stopped early; None when it produced no finite values."""

    status: str
    rig: Rig | None


def refine(problem: RefineProblem, max_iter: int = 200) -> RefineOutcome:
    """Solve the continuous problem from the MILP design; see the module docstring."""
    import casadi as ca

    design, reference = problem.design, problem.reference
    lt, lr, lf = problem.lambdas
    n = len(design)
    forward = design.rotations[:, :, 0]
    yaw0 = np.arctan2(forward[:, 1], forward[:, 0])
    pitch0 = np.arcsin(np.clip(forward[:, 2], -1.0, 1.0))

    # Build.
    opti = ca.Opti()
    u, v = opti.variable(n), opti.variable(n)
    yaw, pitch = opti.variable(n), opti.variable(n)
    fov = opti.variable(n) if problem.fov_range else None
    cost = 0
    for k, camera in enumerate(design.cameras):
        frame = ca.DM(surface_frame(problem.normals[k], camera.forward))
        position = ca.DM(camera.position) + frame[:, 0] * u[k] + frame[:, 1] * v[k]
        rotation = symbolic_rotation_from_yaw_pitch(ca, yaw[k], pitch[k])
        hfov = fov[k] if fov is not None and camera.lens.is_ideal_pinhole else camera.fov
        r = problem.matched[k]
        if r >= 0:
            target = reference.cameras[r]
            offset = position - ca.DM(target.position)
            angle = symbolic_rotation_angle(ca, ca.mtimes(ca.DM(target.rotation.T), rotation), SMOOTHING)
            cost += lt * ca.sqrt(ca.sumsqr(offset) + SMOOTHING) + lr * angle + lf * ca.sqrt((hfov - target.fov) ** 2
                                                                                           + SMOOTHING)
        tangents = (pinhole_half_tangents(hfov, *camera.image_size, tan=ca.tan) if camera.lens.is_ideal_pinhole
                    else lens_half_tangents(camera))
        tan_h, tan_v = (t * (1 - FRUSTUM_INSET) for t in tangents)
        for q in np.flatnonzero(problem.duties[k]):
            local = ca.mtimes(rotation.T, ca.DM(problem.points[q]) - position)
            opti.subject_to(local[0] >= 0.1)
            opti.subject_to(opti.bounded(-local[0] * tan_h, local[1], local[0] * tan_h))
            opti.subject_to(opti.bounded(-local[0] * tan_v, local[2], local[0] * tan_v))
        opti.subject_to(u[k] ** 2 + v[k] ** 2 <= float(np.broadcast_to(problem.radius, (n,))[k]) ** 2)
    if problem.mirror is not None:
        _keep_pairs(opti, problem, design, u, v, yaw, pitch, fov, yaw0)
    opti.subject_to(opti.bounded(problem.pitch_range[0], pitch, problem.pitch_range[1]))
    if fov is not None:
        opti.subject_to(opti.bounded(problem.fov_range[0], fov, problem.fov_range[1]))
        opti.set_initial(fov, design.fovs)
    matched = problem.matched >= 0
    m_count = max(int(matched.sum()), 1)
    opti.minimize(problem.alpha / m_count * cost)
    opti.set_initial(u, 0)
    opti.set_initial(v, 0)
    opti.set_initial(yaw, yaw0)
    opti.set_initial(pitch, pitch0)

    # Solve.
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "sb": "yes", "max_iter": max_iter})
    try:
        solution = opti.solve()
    except RuntimeError:  # not converged: the last iterate may still be a better, valid rig (validated later)
        solution = opti.debug
    status = str(opti.stats().get("return_status", "unknown"))

    # Extract.
    values = [np.atleast_1d(solution.value(x)) for x in (u, v, yaw, pitch)]
    fovs = np.atleast_1d(solution.value(fov)) if fov is not None else design.fovs
    if not all(np.all(np.isfinite(x)) for x in (*values, fovs)):
        return RefineOutcome(status, None)
    cameras = []
    for k, camera in enumerate(design.cameras):
        frame = surface_frame(problem.normals[k], camera.forward)
        position = camera.position + frame[:, 0] * values[0][k] + frame[:, 1] * values[1][k]
        rotation = rotation_from_yaw_pitch_roll(values[2][k], values[3][k], 0.0)
        cameras.append(_moved(camera, position, rotation, float(fovs[k])))
    return RefineOutcome(status, Rig(design.name, design.vehicle, tuple(cameras)))


def _keep_pairs(opti, problem: RefineProblem, design: Rig, u, v, yaw, pitch, fov, yaw0) -> None:
    """Constrain mirrored pairs to move as mirror images and centreline cameras to stay on it (see
    RefineProblem.mirror). The tangent move (u, v) of camera k maps to its mirror j's tangent frame through
    F_j^T M F_k (2 x 2; exact for mirrored frames, the nearest move on a slightly asymmetric body)."""
    frames = [surface_frame(problem.normals[k], c.forward)[:, :2] for k, c in enumerate(design.cameras)]
    for k, j in enumerate(problem.mirror):
        if j < 0 or j < k:
            continue
        if j == k:  # on the centreline: no lateral move, facing straight ahead or back
            opti.subject_to(frames[k][1, 0] * u[k] + frames[k][1, 1] * v[k] == 0)
            opti.subject_to(yaw[k] == yaw0[k])
            continue
        b = frames[j].T @ mirror_points(frames[k].T).T  # (2, 2): F_j^T M F_k
        opti.subject_to(u[j] == b[0, 0] * u[k] + b[0, 1] * v[k])
        opti.subject_to(v[j] == b[1, 0] * u[k] + b[1, 1] * v[k])
        opti.subject_to(yaw[j] + yaw[k] == yaw0[j] + yaw0[k])  # yaw_j = -yaw_k, up to the 2 pi of the start
        opti.subject_to(pitch[j] == pitch[k])
        if fov is not None:
            opti.subject_to(fov[j] == fov[k])


def _moved(camera: Camera, position, rotation, fov: float) -> Camera:
    """``camera`` at a new pose: a benchmark pinhole with FOV ``fov`` (deg), a real lens unchanged."""
    if not camera.lens.is_ideal_pinhole:
        return Camera(camera.id, position, rotation, camera.lens, camera.zone, role=camera.role)
    return Camera.pinhole(camera.id, position, rotation, fov, camera.image_size, camera.zone, role=camera.role)


def project_to_surface(rig: Rig, vehicle: Vehicle, rules: MountRules = MountRules()) -> Rig:
    """Each lens moved to half a housing depth off its nearest surface point (the tangent-plane moves of the
    refinement leave it slightly off a curved surface)."""
    surface = vehicle.surface(rig.positions)
    offset = rules.housing[2] / 2.0
    cameras = [_moved(c, surface.foot[k] + surface.normal[k] * offset, c.rotation, c.fov)
               for k, c in enumerate(rig.cameras)]
    return Rig(rig.name, rig.vehicle, tuple(cameras))


#: Directions and radii (fractions of the largest) of the disc samples that bound a camera's free slide.
DISC_DIRECTIONS = 16
DISC_STEPS = 8


def free_radii(rig: Rig, normals: np.ndarray, vehicle: Vehicle, radius: float,
               rules: MountRules = MountRules()) -> np.ndarray:
    """(k,) float m: how far each camera of ``rig`` may slide in its tangent plane (``normals`` (k, 3)) and stay
    mountable: the largest radius up to ``radius`` whose disc, sampled every radius / DISC_STEPS in
    DISC_DIRECTIONS directions and projected onto the body, stays in the camera's zone and where mounting
    practice allows a lens (off the wheels, high enough, out of the keep-outs). 0 where even the first ring
    leaves it."""
    from rigopt.mounting.practice import practical

    angles = np.linspace(0.0, 2 * np.pi, DISC_DIRECTIONS, endpoint=False)
    steps = np.arange(1, DISC_STEPS + 1) * radius / DISC_STEPS
    offset = rules.housing[2] / 2.0
    out = np.zeros(len(rig))
    for k, camera in enumerate(rig.cameras):
        frame = surface_frame(normals[k], camera.forward)
        moves = steps[:, None, None] * (np.cos(angles)[None, :, None] * frame[:, 0] + np.sin(angles)[None, :, None]
                                        * frame[:, 1])  # (steps, directions, 3)
        points = (camera.position + moves).reshape(-1, 3)
        surface = vehicle.surface(points)
        lens = surface.foot + surface.normal * offset
        fine = np.array(vehicle.zone_names(surface.foot, surface.normal)) == camera.zone
        fine &= practical(vehicle, lens, rules.practice)
        bad = np.flatnonzero(~fine.reshape(len(steps), len(angles)).all(axis=1))
        out[k] = radius if len(bad) == 0 else steps[bad[0] - 1] if bad[0] > 0 else 0.0
    return out


def duty_points(sees: np.ndarray, needed: np.ndarray, margins: np.ndarray, points: np.ndarray | None = None
                ) -> np.ndarray:
    """(k, q) bool: for each required point, the ``needed`` cameras that see it deepest inside their frustum
    (``margins`` (k, q), larger is deeper) keep it in view. With the ``points`` (q, 3) m, a camera keeps only
    the corners of the convex hull of its duty points: its frustum is a convex cone, so the hull's corners
    inside it keep every duty point inside (a regulation field's hundreds of points become a few)."""
    duties = np.zeros_like(sees)
    for q in np.flatnonzero(needed > 0):
        seeing = np.flatnonzero(sees[:, q])
        chosen = seeing[np.argsort(-margins[seeing, q], kind="stable")[:needed[q]]]
        duties[chosen, q] = True
    if points is not None:
        for k in range(len(duties)):
            duties[k] = np.isin(np.arange(duties.shape[1]), hull_corners(points, np.flatnonzero(duties[k])))
    return duties


def hull_corners(points: np.ndarray, index: np.ndarray) -> np.ndarray:
    """(h,) int: those of ``index`` that are corners of the convex hull of ``points[index]`` (all of them when
    the hull is flat or too small to compute)."""
    from scipy.spatial import ConvexHull, QhullError

    if len(index) <= 4:
        return index
    try:
        return index[ConvexHull(points[index]).vertices]
    except QhullError:  # flat (e.g. every duty point at one height): the 2-D hull of the ground coordinates
        try:
            return index[ConvexHull(points[index][:, :2]).vertices] if np.ptp(points[index][:, 2]) == 0 else index
        except QhullError:
            return index


def frustum_margins(rig: Rig, points: np.ndarray) -> np.ndarray:
    """(k, q) float: how deep each point lies inside each camera's view (:meth:`CameraModel.view_margin`: for
    a pinhole the smallest of 1 - |y| / (x tan h) and 1 - |z| / (x tan v); negative outside)."""
    return CameraModel.of_cameras(rig.cameras).view_margin(camera_frame_points(rig.positions, rig.rotations, points))
