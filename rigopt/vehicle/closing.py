"""Closing a vehicle mesh as it comes from a simulator or a CAD export: open, multi-part, non-manifold, thin.

A mesh that manifold3d accepts as it is (each part a closed 2-manifold), or after trimesh has filled its
small holes, is kept exactly, its parts joined by a boolean union. Any other mesh is closed on a grid of
nodes ``pitch`` m apart (:mod:`rigopt.vehicle.voxel_grid`); ``pitch`` = length / 200 clamped to [1, 4] cm
(:func:`closing_pitch`) unless given. Two methods (``CLOSING_METHODS``; measured against each other by
``studies/vehicles/closing_methods.py``):

``distance`` (the default): a signed distance field whose zero level is the closed surface.

1. Inside: a node is inside when at least 4 of the 6 axis rays from it cross the surface with a non-zero
   signed count or an odd number of times (exact crossings; a point in a body without a floor sees the body
   in 5 directions, a point under it between the wheels in 1; overlapping parts count 2).
2. Thin parts: the surface is sampled (spacing half a pitch); a sample with no inside node at the 8 corners
   of its grid cell is *thin* (an open panel, a sheet, a rail, a ladder, a bar: no volume the grid can see).
   Thin parts are thickened into a shell: nodes closer than ``SHELL_PITCHES`` pitches to a thin sample.
3. Enclosed: a node that sees the inside or the shell in at least 5 of the 6 axis directions is filled (the
   inside of a truck body built of thin open panels, missing its floor), and so are cavities.
4. The field: near the surface the distance to the nearest sample, negative inside, (the distance to the
   nearest thin sample - the shell's half-thickness) for the shell; far from it +-the band. Its zero level
   is extracted by marching tetrahedra (closed and 2-manifold by construction), simplified by manifold3d to
   within a quarter pitch. Closed parts keep their surface (to the sampling's accuracy, a few mm); thin parts
   grow by the shell's half-thickness on each side.

``winding``: as ``distance``, with step 1's inside test replaced by the generalised winding number (at least
1/2; libigl's fast winding number, ``pip install libigl``), for the comparison.

``smooth`` (the first closing, kept for the comparison): the inside nodes of step 1 with cavities filled, the
0/1 field smoothed (Gaussian, sigma one pitch) and its 0.5 level extracted. Thin parts thinner than about
two pitches vanish.

The closing error is measured for both: the distances (m) from points sampled evenly on the original surface
to the closed surface; :data:`CLOSING_P95_LIMIT` bounds their 95th percentile, and a refusal names the finer
``--pitch`` that fixes it. Surface inside the closed body on both sides (inner skins, faces between
overlapping parts) is left out and its share reported.

Frames and units: whatever the input's, metres expected (the pitch is in the mesh's units).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import trimesh
from scipy import ndimage
from scipy.spatial import cKDTree

from rigopt.raycast import RayCaster
from rigopt.errors import DataError
from rigopt.vehicle.voxel_grid import Grid, hit_votes, inside_votes, marching_tetrahedra

#: Closing methods (module doc), the default first.
CLOSING_METHODS = ("distance", "smooth", "winding")
#: Grid pitch of the closing: length / PITCH_DIVISIONS, clamped to [PITCH_MIN, PITCH_MAX] m.
PITCH_DIVISIONS = 200
PITCH_MIN, PITCH_MAX = 0.01, 0.04
#: The finest pitch a refusal suggests (m), and the most grid nodes a closing may use.
PITCH_FLOOR = 0.005
MAX_NODES = 60_000_000
#: A closed mesh is refused when the 95th percentile of its closing error exceeds this (m): the mount rules
#: allow a lens at most 5 cm from the surface, so a surface moved further would misjudge every mount.
CLOSING_P95_LIMIT = 0.05
#: Surface samples of the original mesh for the error measure.
ERROR_SAMPLES = 4000
#: Of the 6 axis directions, this many must see the point inside the body (step 1) ...
INSIDE_VOTES = 4
#: ... and this many must meet the inside or the shell for a point to be enclosed (step 3).
ENCLOSED_VOTES = 5
#: Thin parts are thickened by this many pitches on each side (enough for the grid to catch a sheet or a
#: bar wherever it lies between the nodes).
SHELL_PITCHES = 0.75
#: Surface samples for the distance field, per square pitch; at most MAX_SAMPLES.
SAMPLES_PER_PITCH2 = 4
MAX_SAMPLES = 4_000_000


@dataclass(frozen=True)
class ClosingReport:
    """How a mesh was closed: ``method`` "exact" (parts were closed already), "distance" or "smooth";
    ``pitch`` m (0 for exact); closing error (m) from original surface samples to the closed surface:
    ``max_error``, ``p95_error``, and ``worst_point`` (3,) m, the sample farthest away; ``buried`` the share of
    the original surface inside the closed body (left out of the error); ``thin`` the share of the original
    surface that was thin (open on both sides, thickened); ``seconds`` spent."""

    method: str
    pitch: float
    max_error: float
    p95_error: float
    worst_point: tuple[float, float, float]
    buried: float
    seconds: float
    thin: float = 0.0

    def describe(self) -> str:
        if self.method == "exact":
            how = "parts were closed; joined exactly"
        else:
            how = f"closed on a {self.pitch * 100:.1f} cm grid ({self.method})"
            if self.thin >= 0.005:
                how += f", {self.thin:.0%} of the surface thin (thickened by {SHELL_PITCHES * self.pitch * 100:.1f} cm)"
        return (f"{how}; closing error max {self.max_error * 100:.1f} cm, 95th percentile "
                f"{self.p95_error * 100:.1f} cm; {self.buried:.0%} of the surface was inside the body "
                f"({self.seconds:.1f} s)")


def closing_pitch(mesh: trimesh.Trimesh) -> float:
    """Grid pitch (m) for ``mesh``: its longest extent / PITCH_DIVISIONS, clamped to [PITCH_MIN, PITCH_MAX]."""
    return float(np.clip(np.ptp(mesh.bounds, axis=0).max() / PITCH_DIVISIONS, PITCH_MIN, PITCH_MAX))


def close_mesh(mesh: trimesh.Trimesh, source: str = "<mesh>", *, method: str = "distance",
               pitch: float | None = None) -> tuple[trimesh.Trimesh, ClosingReport]:
    """The closed 2-manifold body of ``mesh`` and the report of how it was closed (see the module doc).
    ``method`` one of CLOSING_METHODS for a mesh that is not closed already; ``pitch`` m, default
    :func:`closing_pitch`."""
    if method not in CLOSING_METHODS:
        raise DataError(f"closing method must be one of {', '.join(CLOSING_METHODS)}, got {method!r}")
    if pitch is not None and not (np.isfinite(pitch) and PITCH_FLOOR <= pitch <= 0.2):
        raise DataError(f"--pitch is the closing grid's spacing in metres, in [{PITCH_FLOOR:g}, 0.2], got {pitch}")
    start = time.perf_counter()
    exact = _exact_union(mesh)
    if exact is None:  # a few missing triangles: fill the holes and try again
        repaired = mesh.copy()
        repaired.merge_vertices()
        trimesh.repair.fill_holes(repaired)
        trimesh.repair.fix_normals(repaired)
        exact = _exact_union(repaired)
    thin = 0.0
    if exact is not None:
        closed, method, pitch = exact, "exact", 0.0
    else:
        pitch = float(pitch) if pitch is not None else closing_pitch(mesh)
        nodes = Grid.around(mesh, pitch, margin=4).size
        if nodes > MAX_NODES:
            coarser = pitch * (nodes / MAX_NODES) ** (1 / 3)
            raise DataError(f"{source}: a closing grid of {pitch * 100:.1f} cm needs {nodes / 1e6:.0f} million nodes "
                            f"(at most {MAX_NODES / 1e6:.0f} million); give --pitch {np.ceil(coarser * 1000) / 1000:g} "
                            "or more")
        if method in ("distance", "winding"):
            closed, thin = distance_close(mesh, pitch, source, winding=method == "winding")
        else:
            closed = smooth_close(mesh, pitch, source)
    if closed.volume <= 0:
        raise DataError(f"{source}: the mesh encloses no volume: its faces seem turned inside out; export it with "
                        "outward-facing normals")
    errors, samples, buried = closing_errors(mesh, closed, max(2 * pitch, 0.005))
    worst = samples[int(np.argmax(errors))] if len(errors) else np.zeros(3)
    p95 = float(np.percentile(errors, 95)) if len(errors) else 0.0
    report = ClosingReport(method, pitch, float(errors.max(initial=0.0)), p95, tuple(float(v) for v in worst), buried,
                           time.perf_counter() - start, thin)
    if report.p95_error > CLOSING_P95_LIMIT:
        finer = np.floor(pitch / 2 * 1000) / 1000
        fix = (f"add --pitch {finer:g} (a finer closing grid)" if method != "exact" and finer >= PITCH_FLOOR else
               "export it with closed parts (each part a closed surface)")
        raise DataError(f"{source}: closing the mesh moved its surface too far ({report.describe()}; the 95th "
                        f"percentile must stay within {CLOSING_P95_LIMIT * 100:.0f} cm; the worst point is at "
                        f"{np.round(worst, 2).tolist()} m): {fix}")
    return closed, report


def _exact_union(mesh: trimesh.Trimesh) -> trimesh.Trimesh | None:
    """The union of the mesh's parts when manifold3d accepts them (coincident vertices merged, as STL files
    need), else None."""
    import manifold3d

    raw = manifold3d.Mesh(np.asarray(mesh.vertices, dtype=np.float32), np.asarray(mesh.faces, dtype=np.uint32))
    raw.merge()
    body = manifold3d.Manifold(raw)
    if body.status() != manifold3d.Error.NoError or body.is_empty():
        return None
    parts = body.decompose()
    if len(parts) > 1:
        body = manifold3d.Manifold.batch_boolean(parts, manifold3d.OpType.Add)
    return _to_trimesh(body)


def _to_trimesh(body) -> trimesh.Trimesh:
    out = body.to_mesh()
    return trimesh.Trimesh(np.asarray(out.vert_properties[:, :3], dtype=float), np.asarray(out.tri_verts),
                           process=False)


def _level_body(field: np.ndarray, grid: Grid, source: str, speck: float) -> trimesh.Trimesh:
    """The closed body where ``field`` (grid shape) > 0: marching tetrahedra, simplified to a quarter pitch,
    parts smaller than ``speck`` m^3 dropped."""
    import manifold3d

    vertices, faces = marching_tetrahedra(field, 0.0)
    body = manifold3d.Manifold(manifold3d.Mesh(np.asarray(grid.origin + vertices * grid.pitch, dtype=np.float32),
                                               np.asarray(faces, dtype=np.uint32)))
    if body.status() != manifold3d.Error.NoError or body.is_empty():
        raise DataError(f"{source}: closing the mesh failed ({body.status()}); export it with closed parts")
    body = body.simplify(grid.pitch / 4)
    parts = sorted(body.decompose(), key=lambda part: -part.volume())
    keep = [p for p in parts if p.volume() > speck] or parts[:1]
    return _to_trimesh(manifold3d.Manifold.batch_boolean(keep, manifold3d.OpType.Add) if len(keep) > 1 else keep[0])


# --- the distance closing ------------------------------------------------------------------------------------------


def distance_close(mesh: trimesh.Trimesh, pitch: float, source: str = "<mesh>",
                   winding: bool = False) -> tuple[trimesh.Trimesh, float]:
    """The closed body of ``mesh`` by the ``distance`` method (module doc) on a grid of ``pitch`` m, and the
    share of its surface that was thin; ``winding``: the ``winding`` method's inside test."""
    grid = Grid.around(mesh, pitch, margin=4)
    inside = _winding_inside(mesh, grid) if winding else inside_votes(mesh, grid) >= INSIDE_VOTES
    count = int(min(MAX_SAMPLES, max(20000, SAMPLES_PER_PITCH2 * mesh.area / pitch**2)))
    samples, face = trimesh.sample.sample_surface(mesh, count, seed=0)
    normals = mesh.face_normals[face]
    # thin: no inside node at the 8 corners of the grid cell holding the sample (a closed part's faces, edges
    # and corners all have one; an open panel, a sheet or a bar thinner than the pitch has none)
    nx, ny, nz = grid.shape
    cell_inside = np.zeros((nx - 1, ny - 1, nz - 1), dtype=bool)
    for dx, dy, dz in np.ndindex(2, 2, 2):
        cell_inside |= inside[dx:nx - 1 + dx, dy:ny - 1 + dy, dz:nz - 1 + dz]
    cell = np.clip(np.floor((samples - grid.origin) / pitch).astype(int), 0, np.array(grid.shape) - 2)
    thin = ~cell_inside[tuple(cell.T)]
    shell = SHELL_PITCHES * pitch
    band = shell + 1.5 * pitch
    reach = int(np.ceil(band / pitch))
    near = _near(grid, samples, reach)
    nodes = grid.nodes(np.argwhere(near))
    spacing = np.sqrt(mesh.area / count)
    distance = _surface_distance(samples, normals, nodes, band, spacing)
    thin_distance = np.full(len(nodes), band)
    if thin.any():
        close_to_thin = _near(grid, samples[thin], reach)[near]
        thin_distance[close_to_thin] = _surface_distance(samples[thin], normals[thin], nodes[close_to_thin], band,
                                                         spacing)
    in_shell = np.zeros(grid.shape, dtype=bool)
    in_shell[near] = thin_distance < shell
    solid = inside | in_shell
    solid |= hit_votes(solid) >= ENCLOSED_VOTES
    solid = ndimage.binary_fill_holes(solid)
    if not solid.any():
        raise DataError(f"{source}: no part of the mesh encloses a volume, even after closing: give a finer --pitch, "
                        "or export the body as closed parts")
    # -phi: positive inside; near the surface the signed distances of the three kinds of solid, united (max)
    field = np.where(solid, band, -band).astype(np.float32)
    signed = np.where(inside[near], np.maximum(distance, 1e-6), -distance)
    filled = np.where(solid[near] & ~inside[near] & ~in_shell[near], band, -band)
    field[near] = np.maximum(np.maximum(signed, shell - thin_distance), filled)
    return _level_body(field, grid, source, 8 * pitch**3), float(thin.mean())


def _winding_inside(mesh: trimesh.Trimesh, grid: Grid) -> np.ndarray:
    """(grid shape) bool: nodes whose generalised winding number with respect to ``mesh`` is at least 1/2."""
    try:
        import igl
    except ImportError:
        raise DataError("the winding closing needs libigl: pip install libigl") from None
    nodes = grid.nodes(np.stack(np.unravel_index(np.arange(grid.size), grid.shape), axis=1))
    number = igl.fast_winding_number(np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int64), nodes)
    return (np.asarray(number) >= 0.5).reshape(grid.shape)


def _surface_distance(samples, normals, points, cap: float, spacing: float) -> np.ndarray:
    """(n,) m: distance from ``points`` (n, 3) to the surface sampled by ``samples`` (k, 3) with face
    ``normals`` (k, 3) about ``spacing`` m apart, at most ``cap``: the distance to the nearest sample's tangent
    plane, exact on a face, and beyond the sampled surface's edge (a lateral offset over ``spacing``) the offset
    past it added in quadrature."""
    _, nearest = cKDTree(samples).query(points, distance_upper_bound=cap + spacing)
    found = nearest < len(samples)
    out = np.full(len(points), cap)
    offset = points[found] - samples[nearest[found]]
    across = np.abs(np.einsum("ij,ij->i", offset, normals[nearest[found]]))
    lateral = np.sqrt(np.maximum(np.einsum("ij,ij->i", offset, offset) - across**2, 0.0))
    out[found] = np.minimum(np.hypot(across, np.maximum(lateral - spacing, 0.0)), cap)
    return out


def _near(grid: Grid, points: np.ndarray, reach: int) -> np.ndarray:
    """(grid shape) bool: nodes within ``reach`` nodes (in each axis) of a node nearest one of ``points``."""
    marked = np.zeros(grid.shape, dtype=bool)
    marked[tuple(grid.nearest(points).T)] = True
    return ndimage.maximum_filter(marked, size=2 * reach + 1, mode="constant")


# --- the smooth closing --------------------------------------------------------------------------------------------


def smooth_close(mesh: trimesh.Trimesh, pitch: float, source: str = "<mesh>") -> trimesh.Trimesh:
    """The closed body of ``mesh`` by the ``smooth`` method (module doc) on a grid of ``pitch`` m."""
    grid = Grid.around(mesh, pitch)
    solid = ndimage.binary_fill_holes(inside_votes(mesh, grid) >= INSIDE_VOTES)
    if not solid.any():
        raise DataError(f"{source}: no part of the mesh encloses a volume, even after closing: give a finer --pitch, "
                        "or export the body as closed parts")
    field = ndimage.gaussian_filter(solid.astype(float), sigma=1.0, mode="constant") - 0.5
    return _level_body(field, grid, source, 27 * pitch**3)


# --- closing error --------------------------------------------------------------------------------------------------


def closing_errors(original: trimesh.Trimesh, closed: trimesh.Trimesh, buried_step: float,
                   count: int = ERROR_SAMPLES, seed: int = 0) -> tuple[np.ndarray, np.ndarray, float]:
    """Distances (n,) m from points sampled evenly on ``original``'s surface to ``closed``'s, the samples
    (n, 3), and the share of the ``count`` samples left out as buried: inside the closed body on both sides
    (``buried_step`` m along the normal either way), as inner skins and faces between overlapping parts are."""
    if original.area <= 0:
        return np.zeros(0), np.zeros((0, 3)), 0.0
    samples, face = trimesh.sample.sample_surface(original, count, seed=seed)
    normal = original.face_normals[face]
    step = max(buried_step, 1e-3)
    caster = RayCaster(closed)
    buried = caster.inside(samples + step * normal) & caster.inside(samples - step * normal)
    samples = samples[~buried]
    if len(samples) == 0:
        return np.zeros(0), np.zeros((0, 3)), 1.0
    _, distance, _ = trimesh.proximity.closest_point(closed, samples)
    return np.asarray(distance), samples, float(buried.mean())
