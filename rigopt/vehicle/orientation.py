"""Units, orientation and size of a user's mesh: the flags that bring it into the ISO frame, and the checks
(fast, on the raw mesh, before it is closed) that tell which flag fixes a mesh that is not.

Flags (``rigopt vehicle add``): ``--scale S`` multiplies every coordinate (0.01: centimetres, 0.001:
millimetres, 0.0254: inches; ``--length L`` sets it from the real length, :mod:`rigopt.vehicle.user`);
``--forward A`` names the file's axis that points to the vehicle's front and
``--up A`` the file's axis that points up (A one of +x -x +y -y +z -z; defaults +x and +z). They give the
rotation whose rows are the ISO axes in file coordinates: x_iso = forward, z_iso = up, y_iso = up x forward
(left); e.g. ``--forward -y --up +z`` is a 90-degree turn about z taking file -y to ISO +x.

Checks, each raising a :class:`PoseError` whose message ends with the flags that fix it and whose ``fix``
holds them (:func:`check_pose`):

1. units: a length (longest extent) outside 2.5-25 m, or a size no road vehicle has that a scale outside
   0.5-2 explains; the scale is inferred from the size (:func:`scale_candidates`: any factor, a common unit or
   a round number preferred), and the hint carries the flags the scaled mesh needs next (the checks below
   run on it): "looks like inches: add --scale 0.0254 --forward -y, or --length L ...";
2. up (when ``--up`` is not given): the height axis is found as the short axis whose ends differ most in
   horizontal area near them (the roof is broad, the tyres touch the ground in small patches); when it is
   clearly not z: "add --up +y";
3. long axis: x must be longer than y and z: "add --forward +y or -y";
4. front (when ``--forward`` is not given): the front is judged from the shape (:func:`front_sign`): a
   tandem axle group marks the rear; otherwise the end whose top is lower over the outer 20 % of the
   length (hood, cab, windshield rake) is the front. A mesh that seems to face -x is refused ("add
   --forward -x"), as is one whose ends look alike ("confirm with --forward +x"); an explicit ``--forward``
   is always believed;
5. size: length 2.5-25 m, width 1.4-3.0 m (without mirrors; the mesh's width with them may exceed it),
   height 1.0-4.5 m; outside: an error naming the dimension and its limits, a warning with ``--allow-size``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from rigopt.errors import DataError, RigoptError
from rigopt.geometry import rot_z

AXES = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1), "-z": (0, 0, -1)}
#: Road-vehicle limits (m): length, width (without mirrors), height.
SIZE_LIMITS = {"length": (2.5, 25.0), "width": (1.4, 3.0), "height": (1.0, 4.5)}
#: The widest a mesh may be with its mirrors (m) and still be a road vehicle: a 2.55 m body with mirrors reaching
#: 0.5 m out each side. A unit is judged on this width, since a mesh's box holds its mirrors.
WIDTH_WITH_MIRRORS = 3.6
#: Typical road vehicles (length, width, height m) whose proportions a mesh's size is fitted to, to infer its scale.
REFERENCE_SIZES = {"car": (4.6, 1.8, 1.5), "van": (5.2, 2.0, 2.0), "truck": (8.5, 2.5, 3.5), "bus": (12.0, 2.55, 3.2)}
#: Common units (m per file unit).
UNITS = ((0.001, "millimetres"), (0.01, "centimetres"), (0.0254, "inches"), (0.1, "decimetres"), (0.3048, "feet"),
         (1.0, "metres"))
#: A common unit is preferred over another scale by this much of the fit (root mean square log ratio).
UNIT_PREFERENCE = 0.08
#: Other scales offered: these x 10^k, preferred by this much over the fitted scale itself.
NICE_PREFERENCE = 0.03
NICE_NUMBERS = (1.0, 1.2, 1.25, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 7.5, 8.0)
#: Even with --allow-size, a length outside these bounds (m) is refused as a unit error.
HARD_LENGTH = (1.0, 40.0)
#: Top heights of the two ends must differ by this share of the height to tell the front.
FRONT_MARGIN = 0.05
#: The roof end's area near it must exceed the ground end's by this factor to tell up.
UP_RATIO = 1.6


def axis_name(vector) -> str:
    for name, axis in AXES.items():
        if np.allclose(vector, axis):
            return name
    raise ValueError(f"not an axis: {vector}")


def frame_rotation(forward: str = "+x", up: str = "+z") -> np.ndarray:
    """(3, 3) rotation taking file coordinates to ISO: rows forward, up x forward, up (file axes)."""
    for flag, value in (("--forward", forward), ("--up", up)):
        if value not in AXES:
            raise RigoptError(f"{flag} must be one of {', '.join(AXES)}, got {value!r}")
    f, u = np.array(AXES[forward], float), np.array(AXES[up], float)
    if abs(f @ u) > 0.5:
        raise RigoptError(f"--forward {forward} and --up {up} must name different axes")
    return np.stack([f, np.cross(u, f), u])


def _end_areas(mesh: trimesh.Trimesh, axis: int) -> tuple[float, float]:
    """Area of the mesh projected along ``axis`` within 4 % of its extent from the low and the high end."""
    low, high = mesh.bounds[:, axis]
    band = 0.04 * (high - low)
    centre = mesh.triangles_center[:, axis]
    projected = np.abs(mesh.face_normals[:, axis]) * mesh.area_faces
    return float(projected[centre <= low + band].sum()), float(projected[centre >= high - band].sum())


def mirror_asymmetry(mesh: trimesh.Trimesh, axis: int, samples: int = 3000) -> float:
    """Mean distance (m) from surface samples reflected about their median plane across ``axis`` to the nearest
    unreflected sample: near 0 across a vehicle's width, large across its height."""
    from scipy.spatial import cKDTree

    points, _ = trimesh.sample.sample_surface(mesh, samples, seed=1)
    reflected = points.copy()
    reflected[:, axis] = 2 * np.median(points[:, axis]) - reflected[:, axis]  # a protrusion leaves the median
    return float(cKDTree(points).query(reflected)[0].mean())


def guess_up(mesh: trimesh.Trimesh) -> np.ndarray | None:
    """(3,) unit axis (mesh frame) that seems to point up, or None when the shape does not tell. Of the two
    axes other than the longest, the width is mirror-symmetric and the height is not (by twice as much);
    up points to the height's end that is broader near it (roof vs tyres, by UP_RATIO)."""
    extents = np.ptp(mesh.bounds, axis=0)
    short = [a for a in range(3) if a != int(np.argmax(extents))]
    asymmetry = [mirror_asymmetry(mesh, a) for a in short]
    width_k = int(np.argmin(asymmetry))
    height_axis = short[1 - width_k]
    if asymmetry[1 - width_k] < max(2 * asymmetry[width_k], 0.005 * np.linalg.norm(extents)):
        return None
    low, high = _end_areas(mesh, height_axis)
    if max(low, high) < UP_RATIO * min(low, high):
        return None
    return np.eye(3)[height_axis] * (1 if high > low else -1)


def front_sign(mesh: trimesh.Trimesh, axles=()) -> tuple[int, str]:
    """+1 when the mesh (ISO frame, z up) seems to face +x, -1 when -x, 0 when its shape does not tell;
    and the reason. ``axles``: x of its axles (m), front or rear first."""
    axles = sorted(axles)
    if len(axles) >= 3:
        gaps = np.diff(axles)
        if gaps[0] < 0.6 * gaps[-1]:
            return 1, "a tandem axle group at the other end"
        if gaps[-1] < 0.6 * gaps[0]:
            return -1, "a tandem axle group at the other end"
    (x0, _, z0), (x1, _, z1) = mesh.bounds
    points, _ = trimesh.sample.sample_surface(mesh, 20000, seed=0)
    bins = np.clip(((points[:, 0] - x0) / (x1 - x0) * 20).astype(int), 0, 19)
    top = np.array([points[bins == b, 2].max() if np.any(bins == b) else z0 for b in range(20)])
    rear, front = top[:4].mean(), top[-4:].mean()
    score = (rear - front) / (z1 - z0)
    if score > FRONT_MARGIN:
        return 1, "that end is lower: hood or cab"
    if score < -FRONT_MARGIN:
        return -1, "that end is lower: hood or cab"
    return 0, "both ends are of about the same height"


@dataclass(frozen=True)
class ScaleGuess:
    """The scale (file unit -> m) that makes a mesh's size a plausible road vehicle: ``scale``, ``unit`` (its
    name when it is a common unit, else None), ``kind`` (the typical vehicle whose proportions fit best)."""

    scale: float
    unit: str | None
    kind: str

    def describe(self) -> str:
        return self.unit if self.unit else f"a {self.kind} in units of {self.scale:g} m"


def plausible(size) -> bool:
    """Whether ``size`` (3,) m, in any order, can be a road vehicle's length, width (mirrors included: up to
    WIDTH_WITH_MIRRORS) and height (SIZE_LIMITS)."""
    length, a, b = np.sort(np.asarray(size, float))[::-1]
    (l0, l1), (w0, _), (h0, h1) = SIZE_LIMITS.values()
    w1 = WIDTH_WITH_MIRRORS
    return l0 <= length <= l1 and ((w0 <= a <= w1 and h0 <= b <= h1) or (w0 <= b <= w1 and h0 <= a <= h1))


def _fit(size: np.ndarray) -> tuple[float, str]:
    """(root mean square log ratio, kind): how far ``size`` (sorted, m) is from the nearest of REFERENCE_SIZES."""
    return min((float(np.sqrt(np.mean((np.log(np.sort(reference)[::-1]) - np.log(size)) ** 2))), kind)
               for kind, reference in REFERENCE_SIZES.items())


def scale_candidates(size) -> list[ScaleGuess]:
    """The scales that make ``size`` (3,) (file units, any order) a plausible road vehicle, best first.

    Candidates: the common UNITS, and NICE_NUMBERS x 10^k near the scale that fits each of REFERENCE_SIZES
    (least squares in log), with its 3-digit value. Those that make the size plausible (:func:`plausible`) are
    ranked by how near their scaled size is to a reference (root mean square log ratio), a unit preferred by
    UNIT_PREFERENCE and a round number by NICE_PREFERENCE (a car drawn in decimetres is told 0.1, one drawn at
    0.06 m per unit 0.06)."""
    size = np.sort(np.asarray(size, float))[::-1]
    if not np.all(size > 0):
        return []
    candidates = {value: (name, UNIT_PREFERENCE) for value, name in UNITS}
    for reference in REFERENCE_SIZES.values():
        estimate = float(np.exp(np.mean(np.log(np.sort(reference)[::-1]) - np.log(size))))
        decade = 10.0 ** np.floor(np.log10(estimate))
        for value in [n * decade * f for n in NICE_NUMBERS for f in (0.1, 1.0, 10.0)]:
            if abs(np.log(value / estimate)) < np.log(1.5):
                candidates.setdefault(float(f"{value:.6g}"), (None, NICE_PREFERENCE))
        candidates.setdefault(float(f"{estimate:.3g}"), (None, 0.0))
    scored = []
    for value, (unit, preference) in candidates.items():
        if plausible(size * value):
            distance, kind = _fit(size * value)
            scored.append((distance - preference, value, unit, kind))
    return [ScaleGuess(value, unit, kind) for _, value, unit, kind in sorted(scored)]


def infer_scale(size) -> ScaleGuess | None:
    """The best of :func:`scale_candidates`, or None."""
    ranked = scale_candidates(size)
    return ranked[0] if ranked else None


class PoseError(DataError):
    """A pose check that failed: the message, and ``fix`` {flag: value} (e.g. {"--scale": "0.01"}) that fixes it."""

    def __init__(self, message: str, fix: dict[str, str] | None = None):
        super().__init__(message)
        self.fix = dict(fix or {})


def _flags(fix: dict[str, str]) -> str:
    return " ".join(f"{flag} {value}".strip() for flag, value in fix.items())


def check_pose(mesh: trimesh.Trimesh, source: str, *, scale: float = 1.0, forward: str | None = None,
               up: str | None = None, allow_size: bool = False, axles=()) -> list[str]:
    """Check a mesh already brought into the ISO frame by the flags (``forward``/``up`` None: not given,
    the defaults were used; ``scale`` the scale applied); raise
    PoseError naming the fixing flags, or return warnings (see module doc). A unit problem's hint also carries
    the flags the scaled mesh needs next, so that one retry with all of them gets past every pose check."""
    size = np.ptp(mesh.bounds, axis=0)
    described = f"{size[0]:.3g} x {size[1]:.3g} x {size[2]:.3g}"
    rotation = frame_rotation(forward or "+x", up or "+z")

    def file_axis(iso_vector) -> str:
        return axis_name(rotation.T @ np.asarray(iso_vector, float))

    length = size.max()
    low, high = SIZE_LIMITS["length"]
    units = "units" if scale == 1.0 else f"m with --scale {scale:g}"
    ranked = scale_candidates(size)
    relative = ranked[0].scale if ranked else 1.0
    unit_error = not low <= length <= high or (not plausible(size) and not 0.5 <= relative <= 2.0)
    if unit_error and ranked and (not allow_size or not HARD_LENGTH[0] <= length <= HARD_LENGTH[1]):
        # the best candidate whose scaled mesh passes the size check once oriented, and what it needs next
        for guess in ranked:
            fix, then = {"--scale": f"{scale * guess.scale:.6g}"}, ""
            scaled = trimesh.Trimesh(mesh.vertices * guess.scale, mesh.faces, process=False)
            try:
                check_pose(scaled, source, scale=scale * guess.scale, forward=forward, up=up, allow_size=allow_size,
                           axles=[x * guess.scale for x in axles])
            except PoseError as error:
                if "--allow-size" in error.fix and guess is not ranked[-1]:
                    continue
                extra = {k: v for k, v in error.fix.items() if k not in ("--scale", "--allow-size")}
                fix.update(extra)
                reason = str(error)[len(source) + 2:].rsplit(": add ", 1)[0]
                then = f"; scaled by it, {reason}" if extra else ""
            break
        other = next((g for g in ranked if g.unit and g is not guess), None) if not guess.unit else None
        also = (f" or {other.describe()}, {scale * other.scale:.6g} m per unit ({length * other.scale:.3g} m long): "
                "the shape cannot tell which, the real length can") if other is not None else ""
        raise PoseError(f"{source}: the mesh is {described} {units} (x, y, z), which looks like {guess.describe()}"
                        f" ({length * guess.scale:.3g} m long){also}{then}: add {_flags(fix)}, or --length L with "
                        "its real length L in metres", fix)
    if not low <= length <= high and (not allow_size or not HARD_LENGTH[0] <= length <= HARD_LENGTH[1]):
        raise DataError(f"{source}: the mesh is {described} {units} (x, y, z): its length {length:.3g} m is outside a "
                        f"road vehicle's {low:g}-{high:g} m and no unit makes it one; give its real length with "
                        "--length L (metres) or its unit with --scale" +
                        ("" if allow_size else ", or add --allow-size if it really is that long"))
    if up is None:
        guessed = guess_up(mesh)
        if guessed is not None and not np.allclose(guessed, [0, 0, 1]):
            fix = {"--up": file_axis(guessed)}
            fix.update(_forward_fix(mesh, guessed, rotation, forward))
            alternative = f" (or --forward {_opposite(fix['--forward'])}; whichever way its front faces)" \
                if "--forward" in fix else ""
            raise PoseError(f"{source}: z does not seem to be up: the mesh ({described} m, x, y, z) is broad at its "
                            f"{axis_name(guessed)} end and touches the ground in small patches at the other: "
                            f"add {_flags(fix)}{alternative}", fix)
    if size[2] > size[0] or size[1] > size[0]:
        if size[2] > size[1]:
            raise PoseError(f"{source}: the mesh is longest along z ({described} m for x, y, z): it is on its side "
                            "or standing on end; name the file's axis that points up with --up (e.g. --up +y)")
        sign, reason = front_sign(_turned(mesh, 1), axles=())
        plus, minus = file_axis([0, 1, 0]), file_axis([0, -1, 0])
        if sign == 0:
            raise PoseError(f"{source}: the mesh is longest along y ({described} m for x, y, z), not x (forward): it "
                            f"is turned by 90 degrees; add --forward {plus} or --forward {minus} (whichever way its "
                            "front faces)", {"--forward": plus})
        facing = plus if sign > 0 else minus
        raise PoseError(f"{source}: the mesh is longest along y ({described} m for x, y, z), not x (forward): it is "
                        f"turned by 90 degrees; its front seems to face {facing} ({reason}): add --forward {facing}",
                        {"--forward": facing})
    if forward is None:
        sign, reason = front_sign(mesh, axles)
        if sign < 0:
            raise PoseError(f"{source}: the mesh seems to face {file_axis([-1, 0, 0])} ({reason}): add --forward "
                            f"{file_axis([-1, 0, 0])}, or --forward {file_axis([1, 0, 0])} if its front really is "
                            f"at {file_axis([1, 0, 0])}", {"--forward": file_axis([-1, 0, 0])})
        if sign == 0:
            raise PoseError(f"{source}: cannot tell the mesh's front from its shape ({reason}): confirm it with "
                            f"--forward {file_axis([1, 0, 0])}, or give --forward {file_axis([-1, 0, 0])} if it "
                            "faces the other way: add --forward " + file_axis([1, 0, 0]),
                            {"--forward": file_axis([1, 0, 0])})
    warnings = []
    for value, (dimension, (low, high)) in zip(size, SIZE_LIMITS.items()):
        if not low <= value <= high:
            message = (f"its {dimension} {value:.2f} m is outside a road vehicle's {low:g}-{high:g} m"
                       + (" (without mirrors)" if dimension == "width" else ""))
            if not allow_size:
                raise PoseError(f"{source}: {message}; check --scale (or give --length L), or add --allow-size if the "
                                "size is right", {"--allow-size": ""})
            warnings.append(f"{message} (accepted with --allow-size)")
    return warnings


def _opposite(axis: str) -> str:
    return ("-" if axis[0] == "+" else "+") + axis[1]


def _turned(mesh: trimesh.Trimesh, quarter_turns: int) -> trimesh.Trimesh:
    """The mesh turned about z by ``quarter_turns`` x 90 degrees so that its +y axis becomes +x."""
    turned, transform = mesh.copy(), np.eye(4)
    transform[:3, :3] = rot_z(-np.pi / 2 * quarter_turns)
    turned.apply_transform(transform)
    return turned


def _forward_fix(mesh, up_iso, rotation, forward) -> dict[str, str]:
    """{"--forward": A} when, with the guessed up, the long axis is not the current forward (A: the end the
    shape says is the front, else the long axis's + end); {} otherwise."""
    length_axis = np.eye(3)[int(np.argmax(np.ptp(mesh.bounds, axis=0)))]
    if abs(length_axis @ np.array([1.0, 0.0, 0.0])) > 0.5 or forward is not None:
        return {}
    # turn the mesh so that the guessed up is z and the long axis x, and ask its shape which end is the front
    side = np.cross(up_iso, length_axis)
    turned = trimesh.Trimesh(mesh.vertices @ np.stack([length_axis, side, up_iso]).T, mesh.faces, process=False)
    sign, _ = front_sign(turned)
    front = length_axis * (sign if sign != 0 else 1)
    return {"--forward": axis_name(rotation.T @ front)}
