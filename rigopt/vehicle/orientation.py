"""Units, orientation and size of a user's mesh: the flags that bring it into the ISO frame, and the checks
(fast, on the raw mesh, before it is closed) that tell which flag fixes a mesh that is not.

Flags (``rigopt vehicle add``): ``--scale S`` multiplies every coordinate (0.01: centimetres, 0.001:
millimetres, 0.0254: inches); ``--forward A`` names the file's axis that points to the vehicle's front and
``--up A`` the file's axis that points up (A one of +x -x +y -y +z -z; defaults +x and +z). They give the
rotation whose rows are the ISO axes in file coordinates: x_iso = forward, z_iso = up, y_iso = up x forward
(left); e.g. ``--forward -y --up +z`` is a 90-degree turn about z taking file -y to ISO +x.

Checks, each naming the flag that fixes it (:func:`check_pose`):

1. units: a length (longest extent) outside 2.5-25 m that a common unit explains (x 0.01, 0.001 or
   0.0254 puts every dimension within the size limits): "looks like centimetres: add --scale 0.01";
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

import numpy as np
import trimesh

from rigopt.errors import DataError, RigoptError

AXES = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1), "-z": (0, 0, -1)}
#: Road-vehicle limits (m): length, width (without mirrors), height.
SIZE_LIMITS = {"length": (2.5, 25.0), "width": (1.4, 3.0), "height": (1.0, 4.5)}
#: Scales tried when the size looks like another unit, with the unit's name.
UNIT_GUESSES = ((0.01, "centimetres"), (0.001, "millimetres"), (0.0254, "inches"))
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


def unit_guess(size: np.ndarray) -> tuple[float, str] | None:
    """(scale, unit name) that makes ``size`` (length, width, height) a plausible road vehicle, or None."""
    for scale, unit in UNIT_GUESSES:
        scaled = np.sort(size * scale)[::-1]
        length, rest = scaled[0], scaled[1:]
        if SIZE_LIMITS["length"][0] <= length <= SIZE_LIMITS["length"][1] and \
                np.all(rest >= SIZE_LIMITS["width"][0] * 0.7) and np.all(rest <= SIZE_LIMITS["height"][1]):
            return scale, unit
    return None


def check_pose(mesh: trimesh.Trimesh, source: str, *, scale: float = 1.0, forward: str | None = None,
               up: str | None = None, allow_size: bool = False, axles=()) -> list[str]:
    """Check a mesh already brought into the ISO frame by the flags (``forward``/``up`` None: not given,
    the defaults were used); raise DataError naming the fixing flag, or return warnings (see module doc)."""
    size = np.ptp(mesh.bounds, axis=0)
    described = f"{size[0]:.3g} x {size[1]:.3g} x {size[2]:.3g}"
    rotation = frame_rotation(forward or "+x", up or "+z")

    def file_axis(iso_vector) -> str:
        return axis_name(rotation.T @ np.asarray(iso_vector, float))

    length = size.max()
    low, high = SIZE_LIMITS["length"]
    if not low <= length <= high:
        guess = unit_guess(size)
        units = "units" if scale == 1.0 else f"m with --scale {scale:g}"
        if guess and (not allow_size or not HARD_LENGTH[0] <= length <= HARD_LENGTH[1]):
            raise DataError(f"{source}: the mesh is {described} {units} (x, y, z), which looks like {guess[1]}: "
                            f"add --scale {scale * guess[0]:g}")
        if not allow_size or not HARD_LENGTH[0] <= length <= HARD_LENGTH[1]:
            raise DataError(f"{source}: the mesh is {described} {units} (x, y, z): its length {length:.3g} m is "
                            f"outside a road vehicle's {low:g}-{high:g} m; give its unit with --scale (0.01 for "
                            "centimetres, 0.001 for millimetres, 0.0254 for inches)" +
                            ("" if allow_size else ", or add --allow-size if it really is that long"))
    if up is None:
        guessed = guess_up(mesh)
        if guessed is not None and not np.allclose(guessed, [0, 0, 1]):
            fix = f"--up {file_axis(guessed)}"
            raise DataError(f"{source}: z does not seem to be up: the mesh ({described} m, x, y, z) is broad at its "
                            f"{axis_name(guessed)} end and touches the ground in small patches at the other: "
                            f"add {fix}" + _forward_hint(mesh, guessed, rotation, forward))
    if size[2] > size[0] or size[1] > size[0]:
        if size[2] > size[1]:
            raise DataError(f"{source}: the mesh is longest along z ({described} m for x, y, z): it is on its side "
                            "or standing on end; name the file's axis that points up with --up (e.g. --up +y)")
        sign, reason = front_sign(_turned(mesh, 1), axles=())
        plus, minus = file_axis([0, 1, 0]), file_axis([0, -1, 0])
        if sign == 0:
            fix = f"add --forward {plus} or --forward {minus} (whichever way its front faces)"
        else:
            fix = f"its front seems to face {plus if sign > 0 else minus} ({reason}): add --forward " \
                  f"{plus if sign > 0 else minus}"
        raise DataError(f"{source}: the mesh is longest along y ({described} m for x, y, z), not x (forward): "
                        f"it is turned by 90 degrees; {fix}")
    if forward is None:
        sign, reason = front_sign(mesh, axles)
        if sign < 0:
            raise DataError(f"{source}: the mesh seems to face {file_axis([-1, 0, 0])} ({reason}): add --forward "
                            f"{file_axis([-1, 0, 0])}, or --forward {file_axis([1, 0, 0])} if its front really is "
                            f"at {file_axis([1, 0, 0])}")
        if sign == 0:
            raise DataError(f"{source}: cannot tell the mesh's front from its shape ({reason}): confirm it with "
                            f"--forward {file_axis([1, 0, 0])}, or give --forward {file_axis([-1, 0, 0])} if it "
                            "faces the other way")
    warnings = []
    for value, (dimension, (low, high)) in zip(size, SIZE_LIMITS.items()):
        if not low <= value <= high:
            message = (f"its {dimension} {value:.2f} m is outside a road vehicle's {low:g}-{high:g} m"
                       + (" (without mirrors)" if dimension == "width" else ""))
            if not allow_size:
                raise DataError(f"{source}: {message}; check --scale, or add --allow-size if the size is right")
            warnings.append(f"{message} (accepted with --allow-size)")
    return warnings


def _turned(mesh: trimesh.Trimesh, quarter_turns: int) -> trimesh.Trimesh:
    """The mesh turned about z by ``quarter_turns`` x 90 degrees so that its +y axis becomes +x."""
    turned = mesh.copy()
    turned.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2 * quarter_turns, [0, 0, 1]))
    return turned


def _forward_hint(mesh, up_iso, rotation, forward) -> str:
    """' --forward A' when, with the guessed up, the long axis is not the current forward."""
    length_axis = np.eye(3)[int(np.argmax(np.ptp(mesh.bounds, axis=0)))]
    current = np.array([1.0, 0.0, 0.0])
    if abs(length_axis @ current) > 0.5 or forward is not None:
        return ""
    return f" --forward {axis_name(rotation.T @ length_axis)} (or {axis_name(-rotation.T @ length_axis)}; " \
           "whichever way its front faces)"
