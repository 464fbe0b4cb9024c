"""The default designs from R1 against a packaging check that does not read rigopt's zones (issue 43's acceptance).

Each check below is computed here from the body mesh, the wheels and the spec's named parts, in this module's own
code, not through rigopt's mount rules:

- the wheels' envelope: no lens inside a tyre (a cylinder across y) raised by up to 0.12 m of bump, a front tyre
  turned to any whole degree within 40 either way (membership tested directly, every 1 deg and 1 cm);
- no lens on a step tread: its nearest body face faces up (normal z > 0.9) below 1.0 m;
- no lens within 5 cm of a light bar (the spec's ``light_bar`` fixtures) or a mud flap (the mesh's ``mud_flap``
  parts), nor of a door opening's edge in the door's plane (the spec's ``door_frames``);
- trucks, buses and vans use a mirror mount (a lens outboard of the body's width without mirrors) or a roof edge
  (a lens within 0.35 m of the roof's top and of the body's plan outline);
- no two lenses closer than 0.25 m unless they share a module.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely
import trimesh

from rigopt.vehicle.category import body_width
from rigopt.vehicle.placement import to_vehicle_centre

pytestmark = pytest.mark.slow

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
BUMP_M, LOCK_DEG, NEAR_M = 0.12, 40, 0.05
#: The user meshes added as in the README: (name, mesh, vehicle add's flags).
USER_MESHES = {"citybus": ("raw_bus.obj", {"forward": "+x", "allow_size": True}),
               "van": ("raw_van.obj", {"scale": 0.001})}
VEHICLES = ["firetruck", "hgv", "hgv --no-trailer", "tt", "etron", "chrysler_pacifica_hybrid", "ford_fusion_hybrid",
            "renault_zoe", "citybus", "van"]
#: Vehicles that must use a mirror or roof-edge mount.
HEAVY_OR_BOXY = {"firetruck", "hgv", "hgv --no-trailer", "citybus", "van"}


@pytest.fixture(scope="module")
def home(tmp_path_factory):
    """A RIGOPT_HOME holding the city bus and the van, added from the example meshes."""
    from rigopt.vehicle.user import add_user_vehicle

    folder = tmp_path_factory.mktemp("home")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("RIGOPT_HOME", str(folder))
        for name, (mesh, flags) in USER_MESHES.items():
            add_user_vehicle(name, EXAMPLES / mesh, **flags)
        yield folder


def _inside_wheels(vehicle, points) -> np.ndarray:
    """(n,) bool: points inside a tyre anywhere in its bump travel and, on the front axle, its steer range."""
    front = max(vehicle.axles)
    inside = np.zeros(len(points), dtype=bool)
    for centre, radius, width in vehicle.wheels:
        angles = np.deg2rad(np.arange(-LOCK_DEG, LOCK_DEG + 1)) if abs(centre[0] - front) < 1e-6 else [0.0]
        for bump in np.arange(0.0, BUMP_M + 1e-9, 0.01):
            d = points - (centre + [0.0, 0.0, bump])
            for a in angles:
                along = d[:, 0] * np.cos(a) + d[:, 1] * np.sin(a)
                across = -d[:, 0] * np.sin(a) + d[:, 1] * np.cos(a)
                inside |= (np.abs(across) <= width / 2) & (np.hypot(along, d[:, 2]) <= radius)
    return inside


def _near_box(points, low, high, margin=NEAR_M) -> np.ndarray:
    return np.all((points >= np.asarray(low) - margin) & (points <= np.asarray(high) + margin), axis=1)


def _boxes(entries):
    """(low, high) of each spec box (FeatureBox, DoorFrameSpec), their -y copies included."""
    for entry in entries:
        yield entry.min, entry.max
        if entry.mirrored:
            flip = np.array([1.0, -1.0, 1.0])
            yield np.minimum(entry.min * flip, entry.max * flip), np.maximum(entry.min * flip, entry.max * flip)


def _on_door_edges(points, low, high) -> np.ndarray:
    """Within NEAR_M of a door opening's edges, in the door's plane (its thinnest axis), within 0.15 m of it."""
    low, high = np.asarray(low), np.asarray(high)
    across = int(np.argmin(high - low))
    plane = [k for k in range(3) if k != across]
    near_plane = np.abs(points[:, across] - (low[across] + high[across]) / 2) <= 0.15
    inner = np.all((points[:, plane] >= low[plane] + NEAR_M) & (points[:, plane] <= high[plane] - NEAR_M), axis=1)
    outer = np.all((points[:, plane] >= low[plane] - NEAR_M) & (points[:, plane] <= high[plane] + NEAR_M), axis=1)
    return near_plane & outer & ~inner


def _mud_flaps(vehicle):
    for solid in vehicle.spec.solids:
        if "mud_flap" in solid.name and hasattr(solid, "center"):
            half = np.asarray(solid.size) / 2
            yield solid.center - half, solid.center + half
            if solid.mirrored:
                centre = solid.center * [1.0, -1.0, 1.0]
                yield centre - half, centre + half


@pytest.mark.parametrize("name", VEHICLES)
def test_the_default_design_passes_a_packaging_check_that_reads_no_zones(home, name):
    from rigopt.design import DesignSettings, design_rig
    from rigopt.mounting.records import MountPractice, MountRules

    vehicle_name, _, flag = name.partition(" ")
    lifted = ("trailer",) if flag == "--no-trailer" else ()  # a tractor driven solo: its mud flaps exposed
    result = design_rig(vehicle_name, "R1", settings=DesignSettings.preset(rules=MountRules(
        practice=MountPractice(lifted=lifted))))
    vehicle = result.vehicle
    rig, _ = to_vehicle_centre(result.design.rig, vehicle)
    points, ids = rig.positions, [c.id for c in rig.cameras]

    inside = _inside_wheels(vehicle, points)
    assert not inside.any(), [i for i, bad in zip(ids, inside) if bad]

    _, _, faces = trimesh.proximity.closest_point(vehicle.mesh, points)
    normals = vehicle.mesh.face_normals[faces]
    gap = trimesh.proximity.closest_point(vehicle.mesh, points)[1]
    tread = (normals[:, 2] > 0.9) & (points[:, 2] < 1.0) & (gap < 0.15)
    assert not tread.any(), [i for i, bad in zip(ids, tread) if bad]

    light_bars = [b for b in vehicle.spec.fixtures if b.kind == "light_bar"]
    for low, high in [*_boxes(light_bars), *_mud_flaps(vehicle)]:
        near = _near_box(points, low, high)
        assert not near.any(), (low, high, [i for i, bad in zip(ids, near) if bad])
    for low, high in _boxes(vehicle.spec.door_frames):
        edge = _on_door_edges(points, low, high)
        assert not edge.any(), (low, high, [i for i, bad in zip(ids, edge) if bad])

    apart = np.linalg.norm(points[:, None] - points[None], axis=-1)
    for a, b in zip(*np.nonzero(np.triu(apart < 0.25, k=1))):
        assert rig.cameras[a].module is not None and rig.cameras[a].module == rig.cameras[b].module, (ids[a], ids[b])

    if name in HEAVY_OR_BOXY:
        half_width = body_width(vehicle) / 2
        mirror = np.abs(points[:, 1]) > half_width + NEAR_M
        outline = shapely.MultiPoint(vehicle.mesh.vertices[:, :2]).convex_hull.exterior
        to_edge = shapely.distance(outline, shapely.points(points[:, :2]))
        roof = vehicle.mesh.bounds[1][2]
        roof_edge = (points[:, 2] >= roof - 0.35) & (to_edge <= 0.35)
        assert (mirror | roof_edge).any(), list(zip(ids, np.round(points, 2).tolist()))
