"""Closing a vehicle mesh as it comes from a simulator or a CAD export: open, multi-part, non-manifold.

A mesh that manifold3d accepts as it is (each part a closed 2-manifold), or after trimesh has filled
its small holes, is kept exactly, its parts joined by a boolean union. Any other mesh is closed on a voxel grid:

1. Grid: points ``pitch`` m apart over the mesh's box plus a margin; ``pitch`` = length / 200 clamped to
   [1, 4] cm (:func:`closing_pitch`).
2. Inside test: for each grid point and each of the 6 axis directions, the triangles a ray from the point
   crosses (exact, by rasterising the triangles onto the grid's lines). A direction votes *inside* when its
   crossings' signed count (+1 leaving through an outward face, -1 entering) is non-zero or their number is
   odd, so that overlapping closed parts (count 2) and parts with flipped faces (odd number) both count as
   solid. A point is inside when at least 4 of the 6 directions say so: a point inside a body without a
   floor sees the body in 5 directions, a point under such a body (between the wheels) in 1.
3. Cavities (inside a shell with an inner skin) are filled; the 0/1 field is smoothed (Gaussian, sigma =
   one voxel) so that sloped surfaces keep their normals; its 0.5 level set is extracted by marching
   tetrahedra on the grid (closed and 2-manifold by construction) and simplified by manifold3d to within
   a quarter pitch.
4. The closing error is measured: the distances (cm) from points sampled evenly on the original surface
   to the closed surface; :data:`CLOSING_P95_LIMIT` bounds their 95th percentile. Surface inside the closed
   body on both sides (inner skins, faces between overlapping parts) is left out and its share reported.

Frames and units: whatever the input's, metres expected (the pitch is in the mesh's units).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import trimesh
from scipy import ndimage

from rigopt import raycast
from rigopt.errors import DataError

#: Grid pitch of the voxel closing: length / PITCH_DIVISIONS, clamped to [PITCH_MIN, PITCH_MAX] m.
PITCH_DIVISIONS = 200
PITCH_MIN, PITCH_MAX = 0.01, 0.04
#: A closed mesh is refused when the 95th percentile of its closing error exceeds this (m): the mount rules
#: allow a lens at most 5 cm from the surface, so a surface moved further would misjudge every mount.
CLOSING_P95_LIMIT = 0.05
#: Surface samples of the original mesh for the error measure.
ERROR_SAMPLES = 4000
#: Of the 6 axis directions, this many must see the point inside the body.
INSIDE_VOTES = 4


@dataclass(frozen=True)
class ClosingReport:
    """How a mesh was closed: ``method`` "exact" (parts were closed already) or "voxel"; ``pitch`` m (0 for
    exact); closing error (m) from original surface samples to the closed surface: ``max_error``,
    ``p95_error``, and ``worst_point`` (3,) m, the sample farthest away; ``buried`` the share of the original
    surface inside the closed body (left out of the error); ``seconds`` spent."""

    method: str
    pitch: float
    max_error: float
    p95_error: float
    worst_point: tuple[float, float, float]
    buried: float
    seconds: float

    def describe(self) -> str:
        how = "parts were closed; joined exactly" if self.method == "exact" else \
            f"closed on a {self.pitch * 100:.1f} cm voxel grid"
        return (f"{how}; closing error max {self.max_error * 100:.1f} cm, 95th percentile "
                f"{self.p95_error * 100:.1f} cm; {self.buried:.0%} of the surface was inside the body "
                f"({self.seconds:.1f} s)")


def closing_pitch(mesh: trimesh.Trimesh) -> float:
    """Voxel pitch (m) for ``mesh``: its longest extent / PITCH_DIVISIONS, clamped to [PITCH_MIN, PITCH_MAX]."""
    return float(np.clip(np.ptp(mesh.bounds, axis=0).max() / PITCH_DIVISIONS, PITCH_MIN, PITCH_MAX))


def close_mesh(mesh: trimesh.Trimesh, source: str = "<mesh>") -> tuple[trimesh.Trimesh, ClosingReport]:
    """The closed 2-manifold body of ``mesh`` and the report of how it was closed (see the module doc)."""
    start = time.perf_counter()
    exact = _exact_union(mesh)
    if exact is None:  # a few missing triangles: fill the holes and try again
        repaired = mesh.copy()
        repaired.merge_vertices()
        trimesh.repair.fill_holes(repaired)
        trimesh.repair.fix_normals(repaired)
        exact = _exact_union(repaired)
    if exact is not None:
        closed, method, pitch = exact, "exact", 0.0
    else:
        pitch = closing_pitch(mesh)
        closed, method = voxel_close(mesh, pitch, source), "voxel"
    if closed.volume <= 0:
        raise DataError(f"{source}: the mesh encloses no volume (are its faces turned inside out?)")
    errors, samples, buried = closing_errors(mesh, closed, max(2 * pitch, 0.005))
    worst = samples[int(np.argmax(errors))] if len(errors) else np.zeros(3)
    report = ClosingReport(method, pitch, float(errors.max(initial=0.0)), float(np.percentile(errors, 95)) if len(errors)
                           else 0.0, tuple(float(v) for v in worst), buried, time.perf_counter() - start)
    if report.p95_error > CLOSING_P95_LIMIT:
        raise DataError(f"{source}: closing the mesh moved its surface too far ({report.describe()}; the 95th "
                        f"percentile must stay within {CLOSING_P95_LIMIT * 100:.0f} cm): it is open or thin in too "
                        "many places; export it with closed parts")
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


# --- voxel closing ------------------------------------------------------------------------------------------------


def voxel_close(mesh: trimesh.Trimesh, pitch: float, source: str = "<mesh>") -> trimesh.Trimesh:
    """The closed body of ``mesh`` on a grid of ``pitch`` m (steps 1-3 of the module doc)."""
    import manifold3d

    origin, shape = _grid(mesh, pitch)
    solid = inside_grid(mesh, origin, pitch, shape)
    solid = ndimage.binary_fill_holes(solid)
    if not solid.any():
        raise DataError(f"{source}: no part of the mesh encloses a volume, even after closing; is it a flat or "
                        "single-sided surface?")
    field = ndimage.gaussian_filter(solid.astype(float), sigma=1.0, mode="constant")
    vertices, faces = marching_tetrahedra(field, 0.5)
    body = manifold3d.Manifold(manifold3d.Mesh(np.asarray(origin + vertices * pitch, dtype=np.float32),
                                               np.asarray(faces, dtype=np.uint32)))
    if body.status() != manifold3d.Error.NoError or body.is_empty():
        raise DataError(f"{source}: closing the mesh failed ({body.status()}); export it with closed parts")
    body = body.simplify(pitch / 4)
    # One body: drop specks (parts smaller than a few voxels) that the smoothing left behind.
    parts = sorted(body.decompose(), key=lambda part: -part.volume())
    keep = [p for p in parts if p.volume() > 27 * pitch**3]
    return _to_trimesh(manifold3d.Manifold.batch_boolean(keep, manifold3d.OpType.Add) if len(keep) > 1 else keep[0])


def _grid(mesh: trimesh.Trimesh, pitch: float) -> tuple[np.ndarray, tuple[int, int, int]]:
    """Origin (3,) and shape of a grid covering the mesh with a 3-pitch margin; shifted by a small odd
    fraction of the pitch so that no grid line runs exactly through the edges of axis-aligned meshes."""
    low, high = mesh.bounds
    origin = low - 3 * pitch + pitch * np.array([0.01237, 0.01711, 0.01093])
    shape = tuple(int(n) for n in np.ceil((high - origin) / pitch) + 4)
    return origin, shape


def inside_grid(mesh: trimesh.Trimesh, origin: np.ndarray, pitch: float, shape) -> np.ndarray:
    """(nx, ny, nz) bool: grid points ``origin + pitch * index`` inside the mesh by the 6-direction vote."""
    votes = np.zeros(shape, dtype=np.int8)
    for axis in range(3):
        forward, backward = _axis_winding(mesh, origin, pitch, shape, axis)
        votes += forward
        votes += backward
    return votes >= INSIDE_VOTES


def _axis_winding(mesh, origin, pitch, shape, axis):
    """(shape) bool twice: rays from each grid point along +axis and along -axis cross the mesh so that the
    point looks inside (signed count non-zero or an odd number of crossings)."""
    u, v = [a for a in range(3) if a != axis]
    triangles = mesh.triangles
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    keep = np.abs(normals[:, axis]) > 1e-12  # triangles parallel to the rays are grazed, never crossed
    triangles, normals = triangles[keep], normals[keep]
    # grid-line indices of each triangle's bounding box in the (u, v) plane
    low = np.ceil((triangles[:, :, [u, v]].min(axis=1) - origin[[u, v]]) / pitch).astype(int)
    high = np.floor((triangles[:, :, [u, v]].max(axis=1) - origin[[u, v]]) / pitch).astype(int)
    low = np.maximum(low, 0)
    high = np.minimum(high, np.array([shape[u], shape[v]]) - 1)
    counts = np.maximum(high - low + 1, 0)
    per_triangle = counts[:, 0] * counts[:, 1]
    crossing = np.zeros((shape[axis] + 1, shape[u], shape[v]), dtype=np.int32)
    signed = np.zeros_like(crossing)
    for chunk in np.array_split(np.arange(len(triangles)), max(1, int(per_triangle.sum() // 2_000_000) + 1)):
        which = np.repeat(chunk, per_triangle[chunk])
        if len(which) == 0:
            continue
        offset = np.arange(len(which)) - np.repeat(np.cumsum(per_triangle[chunk]) - per_triangle[chunk],
                                                   per_triangle[chunk])
        ju = low[which, 0] + offset // np.maximum(counts[which, 1], 1)
        jv = low[which, 1] + offset % np.maximum(counts[which, 1], 1)
        pu, pv = origin[u] + ju * pitch, origin[v] + jv * pitch
        a, b, c = triangles[which, 0], triangles[which, 1], triangles[which, 2]
        # barycentric coordinates of the line's foot in the triangle's (u, v) projection
        d1u, d1v, d2u, d2v = b[:, u] - a[:, u], b[:, v] - a[:, v], c[:, u] - a[:, u], c[:, v] - a[:, v]
        det = d1u * d2v - d2u * d1v
        qu, qv = pu - a[:, u], pv - a[:, v]
        s = (qu * d2v - d2u * qv) / det
        t = (d1u * qv - qu * d1v) / det
        hit = (s >= 0) & (t >= 0) & (s + t <= 1)
        where = a[hit, axis] + s[hit] * (b[hit, axis] - a[hit, axis]) + t[hit] * (c[hit, axis] - a[hit, axis])
        # crossing at coordinate `where`: grid points above it see it in -axis rays, those below in +axis rays
        slot = np.clip(np.floor((where - origin[axis]) / pitch).astype(int) + 1, 0, shape[axis])
        np.add.at(crossing, (slot, ju[hit], jv[hit]), 1)
        np.add.at(signed, (slot, ju[hit], jv[hit]), np.sign(normals[which[hit], axis]).astype(np.int32))
    below_count = np.cumsum(crossing, axis=0)[:-1]  # crossings below each grid point
    below_signed = np.cumsum(signed, axis=0)[:-1]
    above_count = crossing.sum(axis=0) - below_count
    above_signed = signed.sum(axis=0) - below_signed
    forward = (above_signed != 0) | (above_count % 2 == 1)
    backward = (below_signed != 0) | (below_count % 2 == 1)
    return np.moveaxis(forward, 0, axis), np.moveaxis(backward, 0, axis)


# Freudenthal split of the unit cube into 6 tetrahedra along its diagonal: corner offsets (dx, dy, dz).
_TETRAHEDRA = np.array([[[0, 0, 0], e1, np.add(e1, e2), [1, 1, 1]]
                        for e1, e2 in [([1, 0, 0], [0, 1, 0]), ([1, 0, 0], [0, 0, 1]), ([0, 1, 0], [1, 0, 0]),
                                       ([0, 1, 0], [0, 0, 1]), ([0, 0, 1], [1, 0, 0]), ([0, 0, 1], [0, 1, 0])]])


def marching_tetrahedra(field: np.ndarray, level: float) -> tuple[np.ndarray, np.ndarray]:
    """The ``level`` surface of ``field`` (nx, ny, nz), ``field > level`` inside: vertices (n, 3) in grid
    units and faces (m, 3), outward-wound; closed and 2-manifold when the field is ``<= level`` on the border
    (a vertex per crossed grid edge, shared by every tetrahedron around that edge)."""
    field = np.where(field == level, level - 1e-9, field)  # no grid value exactly on the level
    nx, ny, nz = field.shape
    inside = field > level
    # cubes with corners on both sides
    corners = np.stack([inside[dx:nx - 1 + dx, dy:ny - 1 + dy, dz:nz - 1 + dz]
                        for dx in (0, 1) for dy in (0, 1) for dz in (0, 1)])
    mixed = np.argwhere(corners.any(axis=0) & ~corners.all(axis=0))  # (c, 3) cube indices
    tets = mixed[:, None, None, :] + _TETRAHEDRA[None]  # (c, 6, 4, 3) grid points
    tets = tets.reshape(-1, 4, 3)
    flat = np.ravel_multi_index(tets.reshape(-1, 3).T, field.shape).reshape(-1, 4)
    values = field.reshape(-1)[flat]
    is_in = values > level
    count = is_in.sum(axis=1)
    # order each tetrahedron's corners inside first
    order = np.argsort(~is_in, axis=1, kind="stable")
    flat = np.take_along_axis(flat, order, axis=1)
    values = np.take_along_axis(values, order, axis=1)
    edge_a, edge_b, triangles = [], [], []
    for n_in, pattern in ((1, [[(0, 1), (0, 2), (0, 3)]]), (3, [[(0, 3), (1, 3), (2, 3)]]),
                          (2, [[(0, 2), (0, 3), (1, 3)], [(0, 2), (1, 3), (1, 2)]])):
        rows = np.flatnonzero(count == n_in)
        for triangle in pattern:
            edge_a.append(np.stack([flat[rows, i] for i, _ in triangle], axis=1))
            edge_b.append(np.stack([flat[rows, o] for _, o in triangle], axis=1))
            triangles.append(np.stack([values[rows, i] for i, _ in triangle], axis=1))
            triangles[-1] = (triangles[-1], np.stack([values[rows, o] for _, o in triangle], axis=1))
    inner = np.concatenate(edge_a)  # (t, 3) grid point inside, per triangle corner
    outer = np.concatenate(edge_b)  # (t, 3) grid point outside
    inner_value = np.concatenate([t[0] for t in triangles])
    outer_value = np.concatenate([t[1] for t in triangles])
    keys, index = np.unique(inner.astype(np.int64) * field.size + outer, return_inverse=True)
    index = index.reshape(-1, 3)
    # one vertex per crossed edge, where the field crosses the level linearly
    first = np.zeros(len(keys), dtype=np.int64)
    first[index.ravel()] = np.arange(index.size)
    a_point = np.stack(np.unravel_index(inner.ravel()[first], field.shape), axis=1).astype(float)
    b_point = np.stack(np.unravel_index(outer.ravel()[first], field.shape), axis=1).astype(float)
    fa, fb = inner_value.ravel()[first], outer_value.ravel()[first]
    vertices = a_point + ((level - fa) / (fb - fa))[:, None] * (b_point - a_point)
    # wind every triangle so that its normal points from the inside corner to the outside corner
    tri = vertices[index]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    outward = (b_point[index[:, 0]] - a_point[index[:, 0]])
    flip = np.einsum("ij,ij->i", normal, outward) < 0
    index[flip] = index[flip][:, ::-1]
    return vertices, index


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
    buried = raycast.inside(closed, samples + step * normal) & raycast.inside(closed, samples - step * normal)
    samples = samples[~buried]
    if len(samples) == 0:
        return np.zeros(0), np.zeros((0, 3)), 1.0
    _, distance, _ = trimesh.proximity.closest_point(closed, samples)
    return np.asarray(distance), samples, float(buried.mean())
