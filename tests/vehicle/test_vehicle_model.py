"""Vehicle surface queries and zones on the box car [-2, 2] x [-0.9, 0.9] x [0.3, 1.5]."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.vehicle.model import ZONE_QUERY_EDGE


def test_point_in_front_of_the_front_face_is_3cm_outside(box_car):
    query = box_car.surface([[2.03, 0.1, 1.0]])
    assert query.distance[0] == pytest.approx(0.03, abs=1e-6)


def test_point_inside_is_negative(box_car):
    query = box_car.surface([[1.9, 0.1, 1.0]])
    assert query.distance[0] == pytest.approx(-0.1, abs=1e-6)


def test_foot_is_the_nearest_surface_point(box_car):
    query = box_car.surface([[2.03, 0.1, 1.0], [1.9, 0.1, 1.0], [0.5, 0.95, 0.8]])
    np.testing.assert_allclose(query.foot, [[2.0, 0.1, 1.0], [2.0, 0.1, 1.0], [0.5, 0.9, 0.8]], atol=1e-6)


def test_normal_points_outward(box_car):
    query = box_car.surface([[2.03, 0.1, 1.0], [1.9, 0.1, 1.0], [0.5, -0.95, 0.8], [0.0, 0.1, 1.6]])
    np.testing.assert_allclose(query.normal, [[1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 0, 1]], atol=1e-9)


def test_face_indexes_the_mesh(box_car):
    query = box_car.surface([[2.03, 0.1, 1.0]])
    np.testing.assert_allclose(box_car.mesh.face_normals[query.face[0]], [1, 0, 0], atol=1e-9)


def test_zone_picked_by_position(box_car):
    names = box_car.zone_names([[2.0, 0.0, 1.0], [-2.0, 0.0, 1.0]], [[1, 0, 0], [1, 0, 0]])
    assert names == ["front", None]


def test_zone_requires_the_normal_in_its_cone(box_car):
    # on the front face, but with a sideways normal: outside the 45 deg cone around +x
    assert box_car.zone_names([[2.0, 0.0, 1.0]], [[0.0, 1.0, 0.0]]) == [None]


def test_zone_cone_edge(box_car):
    inside = [np.cos(np.deg2rad(44)), np.sin(np.deg2rad(44)), 0.0]
    outside = [np.cos(np.deg2rad(46)), np.sin(np.deg2rad(46)), 0.0]
    assert box_car.zone_names([[2.0, 0.0, 1.0]] * 2, [inside, outside]) == ["front", None]


def test_mirrored_zone_covers_both_sides_under_one_name(box_car):
    names = box_car.zone_names([[0.0, 0.9, 1.0], [0.0, -0.9, 1.0]], [[0, 1, 0], [0, -1, 0]])
    assert names == ["side", "side"]


def test_mirrored_zone_keeps_its_normal_per_side(box_car):
    # the right-hand copy wants -y normals: a +y normal at y = -0.9 is in neither copy
    assert box_car.zone_names([[0.0, -0.9, 1.0]], [[0, 1, 0]]) == [None]


def test_mirrored_zone_expands_to_two_zones(box_car):
    assert [z.name for z in box_car.zones] == ["front", "side", "side"]


def test_unmirrored_zone_covers_one_side(build_vehicle, make_spec_text, box_zones):
    car = build_vehicle(make_spec_text(zones=box_zones.replace("mirrored = true", "mirrored = false")))
    names = car.zone_names([[0.0, 0.9, 1.0], [0.0, -0.9, 1.0]], [[0, 1, 0], [0, -1, 0]])
    assert names == ["side", None]


def test_fine_mesh_edges_are_short(box_car):
    lengths = box_car.fine_mesh.edges_unique_length
    assert lengths.max() <= ZONE_QUERY_EDGE + 1e-9


def test_fine_mesh_keeps_the_surface(box_car):
    assert box_car.fine_mesh.area == pytest.approx(box_car.mesh.area, rel=1e-9)


# --- the fine mesh and its zones, against trimesh and the plain per-zone loop ------------------------------------

@pytest.mark.parametrize("max_edge", [0.05, 0.3, 0.7])
def test_subdivision_is_trimeshs(box_car, max_edge):
    """The fine mesh is trimesh's subdivide_to_size, vertex for vertex and face for face (its faces' order
    decides the zone samples), also where one face gets one, two or three of its edges split in a round."""
    import trimesh

    from rigopt.vehicle.model import subdivide_to_size

    sheared = box_car.mesh.vertices * [1.0, 1.0, 1.0] + box_car.mesh.vertices[:, [1]] * [0.37, 0.0, 0.11]
    for vertices in (box_car.mesh.vertices, sheared):
        expected = trimesh.remesh.subdivide_to_size(vertices, box_car.mesh.faces, max_edge)
        got = subdivide_to_size(vertices, box_car.mesh.faces, max_edge)
        np.testing.assert_array_equal(got[0], expected[0])
        np.testing.assert_array_equal(got[1], expected[1])
        edges = got[0][got[1]] - got[0][got[1][:, [1, 2, 0]]]
        assert np.linalg.norm(edges, axis=2).max() <= max_edge
        assert len(got[1]) > 4 * len(box_car.mesh.faces)  # it did subdivide


def test_subdivision_stops_at_max_iter(box_car):
    from rigopt.vehicle.model import subdivide_to_size

    with pytest.raises(ValueError, match="max_iter"):
        subdivide_to_size(box_car.mesh.vertices, box_car.mesh.faces, 0.05, max_iter=2)


def test_fine_face_zones_are_the_first_zone_of_each_face(box_car):
    fine = box_car.fine_mesh
    expected = [None] * len(fine.faces)
    for zone in box_car.zones:  # the definition: the first zone whose box and cone hold the face's centre and normal
        for k in np.flatnonzero(zone.contains(fine.triangles_center, fine.face_normals)):
            expected[k] = expected[k] or zone.name
    assert box_car.fine_face_zones.tolist() == expected
    assert len({name for name in expected if name}) >= 2 and None in expected


def test_a_pickled_vehicle_is_its_spec_and_mesh(box_car):
    """To a worker process a vehicle travels as its spec and mesh (no caches: a mesh's spatial index does not
    survive pickling) and answers there as here."""
    import pickle

    box_car.fine_face_zones, box_car.ray_caster  # derived data built here first
    copy = pickle.loads(pickle.dumps(box_car))
    assert copy.name == box_car.name and [z.name for z in copy.zones] == [z.name for z in box_car.zones]
    assert "fine_mesh" not in copy.__dict__ and "ray_caster" not in copy.__dict__
    np.testing.assert_array_equal(copy.mesh.vertices, box_car.mesh.vertices)
    np.testing.assert_array_equal(copy.mesh.faces, box_car.mesh.faces)
    np.testing.assert_array_equal(copy.mesh.face_normals, box_car.mesh.face_normals)
    points = [[2.03, 0.1, 1.0], [1.9, 0.1, 1.0], [0.5, -0.95, 0.8]]
    np.testing.assert_array_equal(copy.surface(points).distance, box_car.surface(points).distance)
    assert copy.fine_face_zones.tolist() == box_car.fine_face_zones.tolist()


def test_a_point_nearest_a_zero_area_face_gets_a_unit_normal():
    """Built-in meshes hold zero-area faces (the ford_fusion_hybrid 20), whose trimesh normal is 0; a point nearest
    one gets its corners' normal, so that the checks built on it (zones, housing frames, the width limit) never see
    a zero or NaN normal (the width check passed such a point silently: NaN compares false)."""
    import numpy as np

    from rigopt.mounting import features
    from rigopt.vehicle.library import load_vehicle

    vehicle = load_vehicle("ford_fusion_hybrid")
    mesh = vehicle.mesh
    flat = np.flatnonzero(np.linalg.norm(mesh.face_normals, axis=1) < 0.5)
    assert len(flat) > 0
    points = mesh.triangles_center[flat] + 1e-4  # on (next to) each zero-area face
    surface = vehicle.surface(points)
    assert np.allclose(np.linalg.norm(surface.normal, axis=1), 1.0)
    protrusion, limit = features.width_protrusion(vehicle, surface.foot, surface.normal, [None] * len(points),
                                                  (0.06, 0.05, 0.04))
    assert np.isfinite(protrusion).all() and np.isfinite(limit).all()
