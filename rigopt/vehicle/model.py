"""Vehicle: a body mesh with named mounting zones, and the surface queries every other part asks of it."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import trimesh

from rigopt.errors import DataError
from rigopt.raycast import RayCaster, resolve_backend
from rigopt.vehicle.arches import WheelArch, trace_arches
from rigopt.vehicle.build import build_mesh
from rigopt.vehicle.footprint import Footprint
from rigopt.vehicle.spec import VehicleSpec, Wheels, ZoneSpec
from rigopt.vehicle.symmetry import MirrorSymmetry, mirror_symmetry


#: Longest edge (m) of the subdivided mesh used for per-face zone queries.
ZONE_QUERY_EDGE = 0.05
#: How far (m) beyond its half-diagonal a feature box's centre may lie from the body's surface.
FEATURE_REACH = 0.10

def subdivide_to_size(vertices, faces, max_edge: float, max_iter: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """``trimesh.remesh.subdivide_to_size`` (every edge longer than ``max_edge`` m bisected at one shared midpoint,
    until none is), the same vertices (j, 3) float and faces (q, 3) int in the same order, faster: each round
    looks only at the faces the last round made (a face with no long edge is final, and its place in trimesh's
    order is fixed: after the faces finished before it) and sorts only the long edges. vertices (n, 3) float m,
    faces (m, 3) int."""
    vertices = np.array(vertices, dtype=np.float64, copy=True)
    active = np.array(faces, dtype=np.int64, copy=True)
    done = []
    for i in range(max_iter + 1):
        corners = vertices[active]  # (f, 3, 3); edge k runs from corner k to corner k + 1 (either way: same length)
        lengths = ((corners - corners[:, [1, 2, 0]]) ** 2).sum(axis=2) ** 0.5
        long_edge = lengths > max_edge
        if not long_edge.any():
            break
        if i >= max_iter:
            raise ValueError("max_iter exceeded!")
        # trimesh numbers the midpoints in the order of its edge keys (b << 32 | a for a sorted edge (a, b))
        edges = np.sort(np.stack([active, active[:, [1, 2, 0]]], axis=2)[long_edge], axis=1)
        unique, first, inverse = np.unique((edges[:, 1] << 32) | edges[:, 0], return_index=True, return_inverse=True)
        face_mid = np.full(active.shape, -1, dtype=np.int64)
        face_mid[long_edge] = inverse.reshape(-1) + len(vertices)
        vertices = np.vstack((vertices, vertices[edges[first]].mean(axis=1)))
        split = face_mid >= 0
        count = split.sum(axis=1)
        done.append(active[count == 0])
        # the splits as trimesh makes them: one long edge, two, three
        one = count == 1
        j = np.argmax(split[one], axis=1)
        r = np.arange(len(j))
        f1, mid1 = active[one], face_mid[one]
        a, b, c = f1[r, j], f1[r, (j + 1) % 3], f1[r, (j + 2) % 3]
        p = mid1[r, j]
        faces_one = np.column_stack((a, p, c, p, b, c)).reshape((-1, 3))
        two = count == 2
        j = (np.argmin(split[two], axis=1) + 1) % 3
        r = np.arange(len(j))
        f2, mid2 = active[two], face_mid[two]
        a, b, c = f2[r, j], f2[r, (j + 1) % 3], f2[r, (j + 2) % 3]
        p, q = mid2[r, j], mid2[r, (j + 1) % 3]
        use_aq = (((vertices[a, :3] - vertices[q, :3]) ** 2).sum(axis=1)
                  <= ((vertices[p, :3] - vertices[c, :3]) ** 2).sum(axis=1))[:, None]
        corner = np.column_stack((p, b, q))
        quad_a = np.where(use_aq, np.column_stack((a, p, q)), np.column_stack((a, p, c)))
        quad_b = np.where(use_aq, np.column_stack((a, q, c)), np.column_stack((p, q, c)))
        faces_two = np.vstack((corner, quad_a, quad_b))
        three = count == 3
        f3, mid3 = active[three], face_mid[three]
        v0, v1, v2 = f3.T
        m0, m1, m2 = mid3.T
        faces_three = np.column_stack((v0, m0, m2, m0, v1, m1, m2, m1, v2, m0, m1, m2)).reshape((-1, 3))
        active = np.vstack((faces_one, faces_two, faces_three)).astype(np.int64)
    return vertices, np.vstack(done + [active])


@dataclass(frozen=True)
class Zone:
    """One mounting region: box [``min``, ``max``] (3,) m and outward-normal cone around ``normal`` (3,);
    ``raised_max`` m > 0 makes it a raised zone (a camera may sit that far above it on a post along
    ``normal``); ``cost`` its relative mounting cost (1 an ordinary body panel)."""

    name: str
    min: np.ndarray
    max: np.ndarray
    normal: np.ndarray
    cone_deg: float
    raised_max: float = 0.0
    cost: float = 1.0

    @property
    def raised(self) -> bool:
        return self.raised_max > 0

    def contains(self, points, normals) -> np.ndarray:
        """(n,) bool: surface points (n, 3) m with outward normals (n, 3) inside the zone."""
        points, normals = np.atleast_2d(points), np.atleast_2d(normals)
        inside = (points[:, 0] >= self.min[0]) & (points[:, 0] <= self.max[0])
        for axis in (1, 2):
            inside &= (points[:, axis] >= self.min[axis]) & (points[:, axis] <= self.max[axis])
        return inside & (normals @ self.normal >= np.cos(np.deg2rad(self.cone_deg)) - 1e-12)


def expand_zones(specs: tuple[ZoneSpec, ...]) -> tuple[Zone, ...]:
    zones = []
    flip = np.array([1.0, -1.0, 1.0])
    for z in specs:
        zones.append(Zone(z.name, z.min, z.max, z.normal, z.cone_deg, z.raised_max, z.cost))
        if z.mirrored:
            low, high = z.min * flip, z.max * flip
            zones.append(Zone(z.name, np.minimum(low, high), np.maximum(low, high), z.normal * flip, z.cone_deg,
                              z.raised_max, z.cost))
    return tuple(zones)


@dataclass(frozen=True)
class SurfaceQuery:
    """Nearest body surface of query points: ``foot`` (n, 3) m, ``distance`` (n,) m signed (> 0 outside
    the body, < 0 inside), ``normal`` (n, 3) outward unit normal at the foot, ``face`` (n,) int."""

    foot: np.ndarray
    distance: np.ndarray
    normal: np.ndarray
    face: np.ndarray


@dataclass(frozen=True, eq=False)
class Vehicle:
    """A vehicle built from its spec: ``mesh`` is watertight, ISO vehicle frame, metres."""

    spec: VehicleSpec
    mesh: trimesh.Trimesh

    @classmethod
    def from_spec(cls, spec: VehicleSpec) -> "Vehicle":
        """The vehicle of ``spec``, its mesh built; a feature box off the body is an error (:meth:`check_features`)."""
        vehicle = cls(spec, build_mesh(spec))
        vehicle.check_features()
        return vehicle

    def check_features(self) -> None:
        """Every ``[[steps]]``, ``[[fixtures]]`` and ``[[door_frames]]`` box of the spec meets the body: the mesh's
        surface comes within FEATURE_REACH m of the box's half-diagonal from its centre. A box off the body
        contradicts the mesh (a step 5 m beside a van), and DataError says which and how far."""
        entries = [(kind, entry) for kind, group in (("steps", self.spec.steps), ("fixtures", self.spec.fixtures),
                                                     ("door_frames", self.spec.door_frames)) for entry in group]
        if not entries:
            return
        low, high = np.array([e.min for _, e in entries]), np.array([e.max for _, e in entries])
        _, distance, _ = trimesh.proximity.closest_point(self.mesh, (low + high) / 2)
        gap = distance - np.linalg.norm(high - low, axis=1) / 2
        for (kind, entry), off in zip(entries, gap):
            if off > FEATURE_REACH:
                raise DataError(f"{self.spec.source}: [[{kind}]] {entry.name!r} (box {np.round(entry.min, 2).tolist()}.."
                                f"{np.round(entry.max, 2).tolist()} m) lies {off:.2f} m off the body's surface: it "
                                "contradicts the mesh; move the box onto the body (ISO frame, metres from the "
                                "vehicle's centre) or remove it")

    def __getstate__(self) -> dict:
        """A pickled vehicle (to a worker process) is its spec and its mesh's vertices and faces: its derived data,
        and the mesh's own caches (a spatial index does not survive pickling), are built again where needed."""
        return {"spec": self.spec, "vertices": np.asarray(self.mesh.vertices), "faces": np.asarray(self.mesh.faces)}

    def __setstate__(self, state: dict) -> None:
        object.__setattr__(self, "spec", state["spec"])
        object.__setattr__(self, "mesh", trimesh.Trimesh(state["vertices"], state["faces"], process=False))

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def blueprint(self) -> str:
        return self.spec.blueprint

    @property
    def category(self) -> str:
        """UN vehicle category (M1, M2, M3, N1, N2, N3): the spec's ``category``, else the one its shape suggests
        (:attr:`category_guess`)."""
        return self.spec.category or self.category_guess.category

    @cached_property
    def category_guess(self):
        """:func:`rigopt.vehicle.category.guess_category` of this vehicle: the category its shape suggests and why."""
        from rigopt.vehicle.category import guess_category

        return guess_category(self)

    @cached_property
    def zones(self) -> tuple[Zone, ...]:
        """Zones with mirrored copies expanded (a mirrored zone appears twice under one name)."""
        return expand_zones(self.spec.zones)

    @cached_property
    def fine_mesh(self) -> trimesh.Trimesh:
        """The body subdivided to edges of at most ZONE_QUERY_EDGE m: zone membership is decided per face
        (centre and normal), so large flat faces of the built mesh are split first."""
        vertices, faces = subdivide_to_size(self.mesh.vertices, self.mesh.faces, ZONE_QUERY_EDGE)
        return trimesh.Trimesh(vertices, faces, process=False)

    @cached_property
    def fine_face_zones(self) -> np.ndarray:
        """(F,) object: the zone name of each face of ``fine_mesh`` (first matching zone), None outside all."""
        fine = self.fine_mesh
        names = np.array([z.name for z in self.zones] + [None], dtype=object)
        return names[self.zone_indices(fine.triangles_center, fine.face_normals)]

    @cached_property
    def axles(self) -> tuple[float, ...]:
        """x (m) of each axle, front first: the spec's ``axles``, else those of its wheels (solids or
        ``[[wheels]]`` tables); () when the vehicle has none."""
        given = self.spec.axles or tuple(x for s in self.wheel_sets for x in s.axles)
        return tuple(sorted(given, reverse=True))

    @cached_property
    def wheel_sets(self) -> tuple[Wheels, ...]:
        """The vehicle's wheels as ``Wheels`` (axles x, radius, width, track; m): its wheels solids, and the
        ``[[wheels]]`` tables of a user vehicle whose mesh holds them; () when unknown."""
        return tuple(s for s in self.spec.solids if isinstance(s, Wheels)) + tuple(self.spec.wheels)

    @cached_property
    def wheels(self) -> tuple[tuple[np.ndarray, float, float], ...]:
        """Each wheel as (centre (3,) m, radius m, width m): one per axle and side, front first, left first."""
        out = []
        for wheel_set in self.wheel_sets:
            for x in wheel_set.axles:
                for y in (wheel_set.track / 2, -wheel_set.track / 2):
                    out.append((np.array([x, y, wheel_set.radius]), wheel_set.radius, wheel_set.width))
        return tuple(sorted(out, key=lambda w: (-w[0][0], -w[0][1])))

    @cached_property
    def wheel_arches(self) -> tuple[WheelArch, ...]:
        """Each wheel's arch traced on the mesh (:mod:`rigopt.vehicle.arches`), in the order of ``wheels``."""
        return trace_arches(self.ray_caster, self.wheels, self.axles)

    @property
    def legal_width(self) -> float:
        """The width (m) no camera may stick out beyond: the spec's ``legal_width`` (2.55, or 2.60 refrigerated)."""
        return self.spec.legal_width

    def body_features(self) -> list[dict]:
        """The body features of the spec that the mount rules read, one row each: ``kind`` (mirror zone, step or a
        fixture kind, door, wiped area, tilt cab, keep-out), ``name``, ``note`` (a door's hinge, a keep-out's
        reason, the wiped area's zone) and the box ``min``, ``max`` (3,) m, vehicle-centre frame (a mirrored
        entry gives its +y box; None for the wiped area, an outline on the glass)."""
        spec = self.spec
        rows = [{"kind": "mirror zone", "name": z.name, "note": "mounting zone" + (", mirrored" if z.mirrored else ""),
                 "min": z.min, "max": z.max} for z in spec.zones if z.name.startswith("mirror")]
        rows += [{"kind": f.kind, "name": f.name, "note": "mirrored" if f.mirrored else "", "min": f.min,
                  "max": f.max} for f in (*spec.steps, *spec.fixtures)]
        rows += [{"kind": "door", "name": d.name, "note": f"hinged {d.hinge}" if d.hinge else "sliding or unknown",
                  "min": d.min, "max": d.max} for d in spec.door_frames]
        if spec.wiped_area is not None:
            rows.append({"kind": "wiped area", "name": "windscreen", "note": f"on zone {spec.wiped_area.zone}",
                         "min": None, "max": None})
        if spec.tilt_cab is not None:
            rows.append({"kind": "tilt cab", "name": "cab", "note": f"tilts up to {spec.tilt_cab.angle_deg:g} deg",
                         "min": spec.tilt_cab.min, "max": spec.tilt_cab.max})
        rows += [{"kind": "keep-out", "name": k.name, "note": k.reason, "min": k.min, "max": k.max}
                 for k in spec.keep_outs]
        return rows

    @property
    def rear_axle(self) -> np.ndarray | None:
        """(3,) float m: the point on the ground (z = 0) below the centre of the rear axle, rigopt's rear-axle
        origin (that of imported nuScenes, Argoverse 2, Waymo and DDAD rigs); with a rear axle group (a
        tandem: every axle behind the middle of the wheelbase) the group's midpoint. None when the vehicle's
        axles are unknown."""
        axles = self.axles
        if not axles:
            return None
        middle = 0.5 * (axles[0] + axles[-1])
        rear = [x for x in axles if x < middle] or [axles[-1]]
        return np.array([0.5 * (max(rear) + min(rear)), 0.0, 0.0])

    @cached_property
    def symmetry(self) -> MirrorSymmetry:
        """How mirror-symmetric the body is across y = 0 (:mod:`rigopt.vehicle.symmetry`)."""
        return mirror_symmetry(self.mesh)

    @cached_property
    def ray_caster(self) -> RayCaster:
        """The body's ray caster (:class:`rigopt.raycast.RayCaster`, the "auto" backend), built once."""
        return RayCaster(self.mesh)

    def caster(self, backend: str = "auto") -> RayCaster:
        """The body's ray caster for ``backend``: :attr:`ray_caster` when the backend is the one "auto" picks,
        else a caster of its own (built each call: another backend is for comparing backends)."""
        if resolve_backend(backend) == self.ray_caster.backend:
            return self.ray_caster
        return RayCaster(self.mesh, backend)

    @cached_property
    def footprint(self) -> Footprint:
        """The body's convex footprint on the ground (:class:`rigopt.vehicle.footprint.Footprint`)."""
        return Footprint.of_mesh(self.mesh)

    @cached_property
    def collision_object(self):
        """The body as a python-fcl BVH collision object (mesh triangles, vehicle frame), built once."""
        import fcl

        model = fcl.BVHModel()
        model.beginModel(len(self.mesh.vertices), len(self.mesh.faces))
        model.addSubModel(np.asarray(self.mesh.vertices, dtype=float), np.asarray(self.mesh.faces, dtype=np.int32))
        model.endModel()
        return fcl.CollisionObject(model, fcl.Transform())

    @cached_property
    def size(self) -> np.ndarray:
        """(3,) float: the mesh's extent (length, width, height) in metres."""
        return np.ptp(self.mesh.bounds, axis=0)

    def surface(self, points) -> SurfaceQuery:
        """Nearest surface of ``points`` (n, 3) m; the sign of the distance comes from containment."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        foot, unsigned, face = trimesh.proximity.closest_point(self.mesh, points)
        inside = self.ray_caster.inside(points)
        normal = np.array(self.mesh.face_normals[face])
        flat = np.linalg.norm(normal, axis=1) < 0.5  # a zero-area face has no normal (trimesh gives 0): its corners'
        if flat.any():
            corners = np.asarray(self.mesh.vertex_normals)[np.asarray(self.mesh.faces)[face[flat]]].sum(axis=1)
            normal[flat] = corners / np.linalg.norm(corners, axis=1, keepdims=True)
        return SurfaceQuery(foot, np.where(inside, -unsigned, unsigned), normal, face)

    def zone_indices(self, points, normals) -> np.ndarray:
        """(n,) int: the index in ``zones`` of the first zone containing each surface point (n, 3) with normal
        (n, 3); -1 where none does."""
        points, normals = np.atleast_2d(points), np.atleast_2d(normals)
        order = np.argsort(points[:, 0], kind="stable")  # sorted by x, each zone tests the slice in its x range
        points, normals = points[order], normals[order]
        index = np.full(len(points), -1)
        for k, zone in reversed(list(enumerate(self.zones))):  # the first zone is written last
            near = slice(np.searchsorted(points[:, 0], zone.min[0], "left"),
                         np.searchsorted(points[:, 0], zone.max[0], "right"))
            index[near][zone.contains(points[near], normals[near])] = k
        unsorted = np.empty_like(index)
        unsorted[order] = index
        return unsorted

    def zone_names(self, points, normals) -> list[str | None]:
        """Name of the first zone containing each surface point (n, 3) with normal (n, 3); None if none."""
        names = [z.name for z in self.zones] + [None]
        return [names[k] for k in self.zone_indices(points, normals)]
