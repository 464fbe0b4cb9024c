"""The grid that closes a mesh: exact ray crossings along grid lines, the inside votes, and the level surface.

A grid is ``origin`` (3,) m, ``pitch`` m and ``shape`` (nx, ny, nz); node ``(i, j, k)`` lies at
``origin + pitch * (i, j, k)``. Every function works in the mesh's own units (metres in rigopt) and frame.

- :func:`axis_crossings`: where the triangles cross each grid line along an axis (exact: the triangles are
  rasterised onto the lines), as flat arrays.
- :func:`inside_votes`: per node and axis direction, whether a ray from the node crosses the surface so that
  the node looks inside (signed count non-zero or an odd number of crossings).
- :func:`hit_votes`: per node, in how many of the 6 axis directions a ray meets a solid of the grid.
- :func:`marching_tetrahedra`: the level surface of a field, closed and 2-manifold.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

#: Pairs (triangle, grid line) rasterised per chunk (memory bound).
CHUNK_PAIRS = 2_000_000


@dataclass(frozen=True)
class Grid:
    """Nodes ``origin + pitch * index`` for index in ``shape``: origin (3,) m, pitch m, shape (3,) int."""

    origin: np.ndarray
    pitch: float
    shape: tuple[int, int, int]

    @classmethod
    def around(cls, mesh: trimesh.Trimesh, pitch: float, margin: int = 3) -> "Grid":
        """A grid covering ``mesh`` with ``margin`` nodes to spare on every side; shifted by a small odd fraction
        of the pitch so that no grid line runs exactly through the edges of axis-aligned meshes."""
        low, high = mesh.bounds
        origin = low - margin * pitch + pitch * np.array([0.01237, 0.01711, 0.01093])
        shape = tuple(int(n) for n in np.ceil((high - origin) / pitch) + margin + 1)
        return cls(origin, float(pitch), shape)

    @property
    def size(self) -> int:
        return int(np.prod(self.shape))

    def nodes(self, index) -> np.ndarray:
        """(n, 3) m: the positions of node indices (n, 3)."""
        return self.origin + self.pitch * np.asarray(index, dtype=float)

    def nearest(self, points) -> np.ndarray:
        """(n, 3) int: the index of the node nearest each point (n, 3), clipped to the grid."""
        index = np.rint((np.asarray(points, dtype=float) - self.origin) / self.pitch).astype(int)
        return np.clip(index, 0, np.array(self.shape) - 1)


def axis_crossings(mesh: trimesh.Trimesh, grid: Grid, axis: int):
    """Where the surface crosses the grid lines along ``axis``: ``(ju, jv, where, sign)``, flat arrays over the
    crossings: the line's indices on the two other axes (in increasing axis order), the crossing's
    coordinate along ``axis`` (m) and the sign of the crossed face's normal along ``axis`` (+1 leaving through
    an outward face when travelling along +axis)."""
    u, v = [a for a in range(3) if a != axis]
    origin, pitch, shape = grid.origin, grid.pitch, grid.shape
    triangles = mesh.triangles
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    keep = np.abs(normals[:, axis]) > 1e-12  # triangles parallel to the lines are grazed, never crossed
    triangles, normals = triangles[keep], normals[keep]
    low = np.ceil((triangles[:, :, [u, v]].min(axis=1) - origin[[u, v]]) / pitch).astype(int)
    high = np.floor((triangles[:, :, [u, v]].max(axis=1) - origin[[u, v]]) / pitch).astype(int)
    low = np.maximum(low, 0)
    high = np.minimum(high, np.array([shape[u], shape[v]]) - 1)
    counts = np.maximum(high - low + 1, 0)
    per_triangle = counts[:, 0] * counts[:, 1]
    out = ([], [], [], [])
    for chunk in np.array_split(np.arange(len(triangles)), int(per_triangle.sum() // CHUNK_PAIRS) + 1):
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
        out[0].append(ju[hit])
        out[1].append(jv[hit])
        out[2].append(a[hit, axis] + s[hit] * (b[hit, axis] - a[hit, axis]) + t[hit] * (c[hit, axis] - a[hit, axis]))
        out[3].append(np.sign(normals[which[hit], axis]).astype(np.int32))
    if not out[0]:
        return np.zeros(0, int), np.zeros(0, int), np.zeros(0), np.zeros(0, np.int32)
    return tuple(np.concatenate(part) for part in out)


def inside_votes(mesh: trimesh.Trimesh, grid: Grid) -> np.ndarray:
    """(nx, ny, nz) int8: in how many of the 6 axis directions a ray from each node crosses the surface so that
    the node looks inside: the crossings' signed count is non-zero or their number is odd."""
    votes = np.zeros(grid.shape, dtype=np.int8)
    for axis in range(3):
        u, v = [a for a in range(3) if a != axis]
        ju, jv, where, sign = axis_crossings(mesh, grid, axis)
        n = grid.shape[axis]
        # a crossing at `where` lies above the nodes up to its slot - 1 and below the nodes from its slot on
        slot = np.clip(np.floor((where - grid.origin[axis]) / grid.pitch).astype(int) + 1, 0, n)
        crossing = np.zeros((n + 1, grid.shape[u], grid.shape[v]), dtype=np.int32)
        signed = np.zeros_like(crossing)
        np.add.at(crossing, (slot, ju, jv), 1)
        np.add.at(signed, (slot, ju, jv), sign)
        below_count = np.cumsum(crossing, axis=0)[:-1]
        below_signed = np.cumsum(signed, axis=0)[:-1]
        above_count = crossing.sum(axis=0) - below_count
        above_signed = signed.sum(axis=0) - below_signed
        forward = (above_signed != 0) | (above_count % 2 == 1)
        backward = (below_signed != 0) | (below_count % 2 == 1)
        votes += np.moveaxis(forward.astype(np.int8) + backward.astype(np.int8), 0, axis)
    return votes


def hit_votes(solid: np.ndarray) -> np.ndarray:
    """(nx, ny, nz) int8: in how many of the 6 axis directions a ray from each node meets a node of ``solid``
    (bool, same shape), the node itself included."""
    votes = np.zeros(solid.shape, dtype=np.int8)
    for axis in range(3):
        ahead = np.flip(np.logical_or.accumulate(np.flip(solid, axis), axis=axis), axis)
        behind = np.logical_or.accumulate(solid, axis=axis)
        votes += ahead.astype(np.int8) + behind.astype(np.int8)
    return votes


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
    corners = np.stack([inside[dx:nx - 1 + dx, dy:ny - 1 + dy, dz:nz - 1 + dz]
                        for dx in (0, 1) for dy in (0, 1) for dz in (0, 1)])
    mixed = np.argwhere(corners.any(axis=0) & ~corners.all(axis=0))  # (c, 3) cubes with corners on both sides
    tets = (mixed[:, None, None, :] + _TETRAHEDRA[None]).reshape(-1, 4, 3)
    flat = np.ravel_multi_index(tets.reshape(-1, 3).T, field.shape).reshape(-1, 4)
    values = field.reshape(-1)[flat]
    is_in = values > level
    count = is_in.sum(axis=1)
    order = np.argsort(~is_in, axis=1, kind="stable")  # each tetrahedron's inside corners first
    flat = np.take_along_axis(flat, order, axis=1)
    values = np.take_along_axis(values, order, axis=1)
    inner_parts, outer_parts, inner_values, outer_values = [], [], [], []
    for n_in, pattern in ((1, [[(0, 1), (0, 2), (0, 3)]]), (3, [[(0, 3), (1, 3), (2, 3)]]),
                          (2, [[(0, 2), (0, 3), (1, 3)], [(0, 2), (1, 3), (1, 2)]])):
        rows = np.flatnonzero(count == n_in)
        for triangle in pattern:
            inner_parts.append(np.stack([flat[rows, i] for i, _ in triangle], axis=1))
            outer_parts.append(np.stack([flat[rows, o] for _, o in triangle], axis=1))
            inner_values.append(np.stack([values[rows, i] for i, _ in triangle], axis=1))
            outer_values.append(np.stack([values[rows, o] for _, o in triangle], axis=1))
    inner, outer = np.concatenate(inner_parts), np.concatenate(outer_parts)  # (t, 3) grid points per corner
    inner_value, outer_value = np.concatenate(inner_values), np.concatenate(outer_values)
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
    outward = b_point[index[:, 0]] - a_point[index[:, 0]]
    flip = np.einsum("ij,ij->i", normal, outward) < 0
    index[flip] = index[flip][:, ::-1]
    return vertices, index
