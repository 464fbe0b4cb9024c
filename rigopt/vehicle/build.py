"""Build a vehicle spec's solids into one watertight triangle mesh (manifold3d booleans, trimesh out)."""

from __future__ import annotations

import numpy as np
import trimesh

from rigopt.errors import DataError
from rigopt.vehicle.spec import Box, MeshSolid, Prism, VehicleSpec, Wheels

#: Segments of a wheel's circle.
WHEEL_SEGMENTS = 48
#: Extrusions reach this far past the vehicle in every direction (m) before they are intersected.
_REACH = 20.0


def _manifold():
    import manifold3d

    return manifold3d


def _prism(solid: Prism):
    m3d = _manifold()
    even_odd = m3d.FillRule.EvenOdd
    side = m3d.CrossSection([solid.side], even_odd)
    # Side profile in (x, z): extrude along local z, centre it, then rotate +90 deg about x: (X, Y, Z) -> (X, -Z, Y).
    slab = m3d.Manifold.extrude(side, 2 * _REACH).translate((0.0, 0.0, -_REACH)).rotate((90.0, 0.0, 0.0))
    half = solid.plan
    outline = np.concatenate([half, half[::-1] * np.array([1.0, -1.0])])
    centre = np.array([outline[:, 0].mean(), 0.0])
    plan = m3d.CrossSection([outline - centre], even_odd)
    zmin, zmax = float(solid.side[:, 1].min()) - 0.01, float(solid.side[:, 1].max()) + 0.01
    column = m3d.Manifold.extrude(plan, zmax - zmin, scale_top=solid.taper).translate((centre[0], 0.0, zmin))
    return slab ^ column


def _wheels(solid: Wheels):
    m3d = _manifold()
    parts = []
    for x in solid.axles:
        for y in (solid.track / 2, -solid.track / 2):
            wheel = m3d.Manifold.cylinder(solid.width, solid.radius, solid.radius, WHEEL_SEGMENTS, True)
            parts.append(wheel.rotate((90.0, 0.0, 0.0)).translate((x, y, solid.radius)))
    return m3d.Manifold.batch_boolean(parts, m3d.OpType.Add)


def _box(solid: Box):
    m3d = _manifold()
    parts = [m3d.Manifold.cube(tuple(solid.size), True).translate(tuple(solid.center))]
    if solid.mirrored:
        parts.append(m3d.Manifold.cube(tuple(solid.size), True).translate(tuple(solid.center * [1, -1, 1])))
    return m3d.Manifold.batch_boolean(parts, m3d.OpType.Add)


def _mesh_solid(solid: MeshSolid):
    m3d = _manifold()
    try:
        mesh = trimesh.load_mesh(solid.path, process=True)
    except (OSError, ValueError) as error:
        raise DataError(f"{solid.path}: cannot read the vehicle's mesh file ({error})") from None
    return m3d.Manifold(m3d.Mesh(np.asarray(mesh.vertices, dtype=np.float32), np.asarray(mesh.faces, dtype=np.uint32)))


def build_mesh(spec: VehicleSpec) -> trimesh.Trimesh:
    """The union of the spec's solids as one watertight mesh, ISO vehicle frame, metres."""
    m3d = _manifold()
    builders = {Prism: _prism, Wheels: _wheels, Box: _box, MeshSolid: _mesh_solid}
    parts = [builders[type(solid)](solid) for solid in spec.solids]
    body = m3d.Manifold.batch_boolean(parts, m3d.OpType.Add) if len(parts) > 1 else parts[0]
    if body.is_empty():
        raise DataError(f"{spec.source}: the solids build an empty body; check the profiles and outlines")
    mesh = body.to_mesh()
    result = trimesh.Trimesh(np.asarray(mesh.vert_properties[:, :3], dtype=float), np.asarray(mesh.tri_verts),
                             process=False)
    if not result.is_watertight:
        raise DataError(f"{spec.source}: the built body is not watertight")
    return result
