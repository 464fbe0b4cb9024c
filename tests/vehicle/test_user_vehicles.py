"""User vehicles: a mesh file checked, brought into the ISO frame, given zones and stored under RIGOPT_HOME.

Every test runs with ``rigopt_home`` (conftest): RIGOPT_HOME in a tmp folder and the built-in vehicles
replaced by one fake built-in "etron", so that no real home or built-in spec is read or written.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from rigopt.errors import DataError, RigoptError
from rigopt.vehicle.library import broken_user_vehicles, find_spec, load_vehicle, user_vehicles_dir, vehicle_names
from rigopt.vehicle import user
from rigopt.vehicle.user import carla_mesh_to_iso, load_user_mesh

pytestmark = pytest.mark.usefixtures("rigopt_home")

def add_user_vehicle(*args, **kwargs):
    """``user.add_user_vehicle`` returning the spec's path; the box cars' ends look alike, so their front is
    confirmed with forward="+x"."""
    kwargs.setdefault("forward", "+x")
    return user.add_user_vehicle(*args, **kwargs).path


BOX_BOUNDS = [[-2, -0.9, 0.3], [2, 0.9, 1.5]]
BOX_VOLUME = 4 * 1.8 * 1.2


@pytest.fixture
def export(tmp_path):
    """Factory: write a mesh to ``tmp_path/<name>`` and return its path."""

    def write(mesh: trimesh.Trimesh, name: str = "car.stl"):
        path = tmp_path / name
        mesh.export(path)
        return path

    return write


@pytest.fixture
def box_stl(box_car, export):
    return export(box_car.mesh, "box.stl")


def centred(bounds) -> np.ndarray:
    """(2, 3) ``bounds`` moved so that the footprint box's centre is at x = y = 0 (z kept): the vehicle frame."""
    bounds = np.asarray(bounds, float)
    return bounds - [0.5 * (bounds[0, 0] + bounds[1, 0]), 0.5 * (bounds[0, 1] + bounds[1, 1]), 0.0]


def transformed(mesh: trimesh.Trimesh, matrix) -> trimesh.Trimesh:
    out = mesh.copy()
    out.apply_transform(matrix)
    return out


# --- round trip -------------------------------------------------------------------------------------------


def test_added_vehicle_is_stored_under_rigopt_home(box_stl, rigopt_home):
    path = add_user_vehicle("mycar", box_stl)
    assert path == rigopt_home / "vehicles" / "mycar" / "vehicle.toml"
    assert path.is_file() and (path.parent / "body.ply").is_file()
    assert user_vehicles_dir() == rigopt_home / "vehicles"


def test_round_trip_keeps_the_bounds(box_stl):
    add_user_vehicle("mycar", box_stl)
    np.testing.assert_allclose(load_vehicle("mycar").mesh.bounds, BOX_BOUNDS, atol=1e-4)


def test_round_trip_keeps_the_volume(box_stl):
    add_user_vehicle("mycar", box_stl)
    mesh = load_vehicle("mycar").mesh
    assert mesh.is_watertight
    assert mesh.volume == pytest.approx(BOX_VOLUME, abs=1e-4)


def test_added_vehicle_is_listed_and_found(box_stl):
    add_user_vehicle("mycar", box_stl)
    assert "mycar" in vehicle_names()
    assert find_spec("MyCar").name == "mycar"


def test_carla_frame_is_reflected_back(asymmetric_car, export):
    mirrored = carla_mesh_to_iso(asymmetric_car.mesh)  # the same reflection takes ISO to CARLA
    np.testing.assert_allclose(mirrored.bounds[:, 1], [-1.15, 0.9], atol=1e-5)  # it really is different
    add_user_vehicle("carlacar", export(mirrored, "carla.ply"), frame="carla")
    loaded = load_vehicle("carlacar").mesh
    np.testing.assert_allclose(loaded.bounds, centred(asymmetric_car.mesh.bounds), atol=1e-4)
    assert loaded.volume == pytest.approx(asymmetric_car.mesh.volume, abs=1e-4)


def test_iso_frame_is_kept(asymmetric_car, export):
    add_user_vehicle("isocar", export(asymmetric_car.mesh, "iso.ply"))
    np.testing.assert_allclose(load_vehicle("isocar").mesh.bounds, centred(asymmetric_car.mesh.bounds), atol=1e-4)


def test_carla_reflection_keeps_normals_outward(asymmetric_car):
    mirrored = carla_mesh_to_iso(asymmetric_car.mesh)
    assert mirrored.volume == pytest.approx(asymmetric_car.mesh.volume, rel=1e-9)


def test_unknown_frame_raises(box_stl):
    with pytest.raises(RigoptError, match="frame"):
        load_user_mesh(box_stl, frame="unreal")


# --- rejected meshes ------------------------------------------------------------------------------------------


def test_millimetre_mesh_raises(box_car, export):
    path = export(transformed(box_car.mesh, np.diag([1000.0, 1000.0, 1000.0, 1.0])), "mm.stl")
    with pytest.raises(DataError, match="millimetres"):
        add_user_vehicle("mmcar", path)


def test_mesh_on_its_side_raises(box_car, export):
    standing = transformed(box_car.mesh, trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
    standing.apply_translation([0, 0, -standing.bounds[0, 2]])
    assert np.argmax(np.ptp(standing.bounds, axis=0)) == 2
    with pytest.raises(DataError, match="side"):
        add_user_vehicle("standing", export(standing, "standing.stl"))


def test_lifted_mesh_raises(box_car, export):
    lifted = transformed(box_car.mesh, trimesh.transformations.translation_matrix([0, 0, 2.0]))
    with pytest.raises(DataError, match=r"z = 0|lowest point"):
        add_user_vehicle("lifted", export(lifted, "lifted.stl"))


@pytest.mark.slow
def test_open_mesh_is_closed(box_car, export):
    fine = box_car.fine_mesh
    keep = fine.triangles_center[:, 0] < 2.0 - 1e-6  # the whole front face is missing
    open_mesh = trimesh.Trimesh(fine.vertices, fine.faces[keep], process=False)
    assert not open_mesh.is_watertight
    add_user_vehicle("opencar", export(open_mesh, "open.ply"))
    mesh = load_vehicle("opencar").mesh
    assert mesh.is_watertight
    np.testing.assert_allclose(mesh.bounds, BOX_BOUNDS, atol=0.03)  # within a voxel pitch (2 cm) and smoothing
    assert mesh.volume == pytest.approx(BOX_VOLUME, rel=0.03)


def test_mesh_with_one_missing_triangle_is_repaired(box_car, export):
    mesh = box_car.mesh
    holed = trimesh.Trimesh(mesh.vertices, mesh.faces[1:], process=False)
    add_user_vehicle("holed", export(holed, "holed.ply"))
    assert load_vehicle("holed").mesh.volume == pytest.approx(BOX_VOLUME, abs=1e-4)


def test_unreadable_file_raises(tmp_path):
    path = tmp_path / "junk.ply"
    path.write_bytes(b"\x00 this is not a mesh \xff" * 50)
    with pytest.raises(DataError, match="junk.ply"):
        add_user_vehicle("junk", path)


def test_missing_file_raises(tmp_path):
    with pytest.raises(DataError, match="no such mesh file"):
        add_user_vehicle("nothing", tmp_path / "nothing.stl")


def test_failed_add_writes_nothing(box_car, export, rigopt_home):
    lifted = transformed(box_car.mesh, trimesh.transformations.translation_matrix([0, 0, 2.0]))
    with pytest.raises(DataError):
        add_user_vehicle("lifted", export(lifted, "lifted.stl"))
    assert not (rigopt_home / "vehicles" / "lifted").exists()


# --- zones -------------------------------------------------------------------------------------------------------


def test_zone_that_selects_no_surface_raises(box_stl, tmp_path):
    zones = tmp_path / "zones.toml"
    zones.write_text('[[zones]]\nname = "nowhere"\nmin = [10, 10, 10]\nmax = [11, 11, 11]\nnormal = [1, 0, 0]\n'
                     'cone_deg = 30\n')
    with pytest.raises(DataError, match="selects no surface") as caught:
        add_user_vehicle("zoned", box_stl, zones)
    assert str(caught.value).startswith(f"{zones}:")  # the user's file, not the copy in the store


def test_zones_file_is_used(box_stl, tmp_path):
    zones = tmp_path / "zones.toml"
    zones.write_text('[[zones]]\nname = "nose"\nmin = [1.9, -1, 0.2]\nmax = [2.1, 1, 1.6]\nnormal = [1, 0, 0]\n'
                     'cone_deg = 30\n')
    add_user_vehicle("zoned", box_stl, zones)
    vehicle = load_vehicle("zoned")
    assert [z.name for z in vehicle.zones] == ["nose"]
    assert vehicle.zone_names([[2.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]]) == ["nose"]


def test_zones_file_without_zones_raises(box_stl, tmp_path):
    zones = tmp_path / "zones.toml"
    zones.write_text('name = "nothing here"\n')
    with pytest.raises(DataError, match="zones"):
        add_user_vehicle("zoned", box_stl, zones)


def test_default_zones(box_stl):
    add_user_vehicle("mycar", box_stl)
    names = {z.name for z in load_vehicle("mycar").zones}
    assert {"bumper_front", "roof_front", "b_pillar"} <= names


def test_default_zones_select_the_right_faces(box_stl):
    add_user_vehicle("mycar", box_stl)
    vehicle = load_vehicle("mycar")
    points = [[2.0, 0.0, 0.5], [-2.0, 0.0, 0.5], [1.0, 0.0, 1.5], [0.0, 0.9, 1.3], [0.0, -0.9, 1.3]]
    normals = [[1, 0, 0], [-1, 0, 0], [0, 0, 1], [0, 1, 0], [0, -1, 0]]
    assert vehicle.zone_names(points, normals) == ["bumper_front", "bumper_rear", "roof_front", "b_pillar",
                                                   "b_pillar"]


# --- names -------------------------------------------------------------------------------------------------------


def test_builtin_name_raises(box_stl):
    with pytest.raises(RigoptError, match="built-in"):
        add_user_vehicle("etron", box_stl)


def test_builtin_alias_raises(box_stl):
    with pytest.raises(RigoptError, match="built-in"):
        add_user_vehicle("suv", box_stl)


def test_bad_name_raises(box_stl, rigopt_home):
    with pytest.raises(RigoptError, match="name"):
        add_user_vehicle("my car!", box_stl)
    assert not (rigopt_home / "vehicles").exists()


def test_user_vehicle_can_be_replaced(box_car, asymmetric_car, export):
    add_user_vehicle("mycar", export(box_car.mesh, "a.stl"))
    add_user_vehicle("mycar", export(asymmetric_car.mesh, "b.stl"), force=True)
    assert vehicle_names().count("mycar") == 1
    np.testing.assert_allclose(find_spec("mycar").box, np.ptp(asymmetric_car.mesh.bounds, axis=0), atol=1e-4)


def test_replaced_vehicle_is_reloaded(box_car, asymmetric_car, export):
    add_user_vehicle("mycar", export(box_car.mesh, "a.stl"))
    np.testing.assert_allclose(load_vehicle("mycar").mesh.bounds, BOX_BOUNDS, atol=1e-4)
    add_user_vehicle("mycar", export(asymmetric_car.mesh, "b.stl"), force=True)
    np.testing.assert_allclose(load_vehicle("mycar").mesh.bounds, centred(asymmetric_car.mesh.bounds), atol=1e-4)


def test_zones_file_errors_name_the_users_file(box_stl, tmp_path):
    zones = tmp_path / "zones.toml"
    zones.write_text('[[zones]]\nname = "nose"\nmin = [1.9, -1, 0.2]\nnormal = [1, 0, 0]\ncone_deg = 30\n')
    with pytest.raises(DataError) as caught:
        add_user_vehicle("zoned", box_stl, zones)
    assert str(zones) in str(caught.value) and "vehicles" not in str(caught.value)


def test_re_adding_a_name_needs_force(box_car, asymmetric_car, export):
    add_user_vehicle("mycar", export(box_car.mesh, "a.stl"))
    with pytest.raises(RigoptError, match="--force"):
        add_user_vehicle("mycar", export(asymmetric_car.mesh, "b.stl"))
    np.testing.assert_allclose(load_vehicle("mycar").mesh.bounds, BOX_BOUNDS, atol=1e-4)  # unchanged


def test_names_are_unique_without_regard_to_case(box_car, asymmetric_car, export, rigopt_home):
    add_user_vehicle("mycar", export(box_car.mesh, "a.stl"))
    with pytest.raises(RigoptError, match="'mycar' exists"):
        add_user_vehicle("MYCAR", export(asymmetric_car.mesh, "b.stl"))
    assert [n for n in vehicle_names() if n.lower() == "mycar"] == ["mycar"]
    add_user_vehicle("MYCAR", export(asymmetric_car.mesh, "b.stl"), force=True)  # replaces it, under the new case
    assert [n for n in vehicle_names() if n.lower() == "mycar"] == ["MYCAR"]
    assert [p.name for p in (rigopt_home / "vehicles").iterdir()] == ["MYCAR"]
    np.testing.assert_allclose(load_vehicle("mycar").mesh.bounds, centred(asymmetric_car.mesh.bounds), atol=1e-4)


@pytest.fixture
def broken(rigopt_home):
    """A user vehicle "wreck" whose vehicle.toml is not TOML."""
    folder = rigopt_home / "vehicles" / "wreck"
    folder.mkdir(parents=True)
    (folder / "vehicle.toml").write_text("name = [unclosed\n")
    return folder


def test_a_broken_user_vehicle_is_skipped(broken, box_stl):
    add_user_vehicle("mycar", box_stl)
    assert "wreck" not in vehicle_names()
    assert {"etron", "mycar"} <= set(vehicle_names())
    assert find_spec("suv").name == "etron"  # built-ins are still found
    assert load_vehicle("mycar").name == "mycar"
    assert set(broken_user_vehicles()) == {"wreck"}
    assert "not valid TOML" in broken_user_vehicles()["wreck"]


def test_a_broken_user_vehicle_is_reported_by_name(broken):
    with pytest.raises(RigoptError, match=r"user vehicle 'wreck' cannot be read: .*not valid TOML.*--force"):
        find_spec("WRECK")


def test_a_broken_user_vehicle_is_replaced_only_with_force(broken, box_stl):
    with pytest.raises(RigoptError, match="--force"):
        add_user_vehicle("wreck", box_stl)
    add_user_vehicle("wreck", box_stl, force=True)
    assert broken_user_vehicles() == {}
    assert load_vehicle("wreck").name == "wreck"


def test_a_user_vehicle_missing_its_body_is_skipped_by_the_listing(box_stl, rigopt_home):
    import json

    from in_process import run_rigopt

    add_user_vehicle("mycar", box_stl)
    add_user_vehicle("lost", box_stl)
    (rigopt_home / "vehicles" / "lost" / "body.ply").unlink()
    listed = run_rigopt("vehicles", "--json", env={"RIGOPT_HOME": str(rigopt_home)})
    assert listed.returncode == 0, listed.stderr
    names = {row["vehicle"] for row in json.loads(listed.stdout)}
    assert "mycar" in names and "lost" not in names
    assert "user vehicle 'lost' skipped" in listed.stderr and "--force" in listed.stderr


def test_the_zones_option_is_described_with_its_tables():
    from in_process import run_rigopt

    shown = run_rigopt("vehicle", "add", "--help")
    assert shown.returncode == 0
    assert "TOML file of [[zones]] tables" in " ".join(shown.stdout.split())


def test_names_are_letters_of_any_script_digits_and_three_marks(box_stl):
    """'ü' is a letter (the message used to say letters and refuse it); spaces, slashes and marks are not."""
    assert add_user_vehicle("müllwagen_2.0-b", box_stl).parent.name == "müllwagen_2.0-b"
    for bad in ("my car", "a/b", "_lead", "x!", "..", ""):
        with pytest.raises(RigoptError, match="letters, digits"):
            add_user_vehicle(bad, box_stl)


# --- category ----------------------------------------------------------------------------------------------


def a_bus_mesh() -> trimesh.Trimesh:
    """A 12 m box bus on four wheels, its front axle 3 m behind its front face."""
    body = trimesh.creation.box(extents=[12.0, 2.5, 2.6], transform=trimesh.transformations.translation_matrix(
        [0.0, 0.0, 1.6]))
    wheels = []
    for x in (3.0, -3.5):
        for y in (1.0, -1.0):
            wheel = trimesh.creation.cylinder(radius=0.5, height=0.3, sections=24,
                                              transform=trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
            wheel.apply_translation([x, y, 0.5])
            wheels.append(wheel)
    return trimesh.util.concatenate([body, *wheels])


def test_a_bus_shaped_mesh_is_stated_an_m3_that_needs_the_blind_spot_field(export, rigopt_home):
    from in_process import run_rigopt

    added = run_rigopt("vehicle", "add", "bus", "--mesh", str(export(a_bus_mesh(), "bus.stl")), "--forward", "+x",
                       env={"RIGOPT_HOME": str(rigopt_home)})
    assert added.returncode == 0, added.stderr
    said = " ".join(added.stdout.split())
    assert "category: M3" in said and "a bus" in said and "front axle 3.00 m behind the front" in said
    assert "fields required by default: r151, r159, r158" in said
    assert load_vehicle("bus").category == "M3" and find_spec("bus").category == "M3"  # stored, not guessed again


def test_a_category_given_is_stored_and_a_wrong_one_refused(box_stl, rigopt_home):
    from in_process import run_rigopt

    assert user.add_user_vehicle("mycar", box_stl, forward="+x", category=" n2 ").category == "N2"
    assert find_spec("mycar").category == "N2"
    refused = run_rigopt("vehicle", "add", "other", "--mesh", str(box_stl), "--forward", "+x", "--category",
                         "truck", env={"RIGOPT_HOME": str(rigopt_home)})
    assert refused.returncode == 2 and refused.stdout == ""
    assert refused.stderr.strip().splitlines() == [
        "rigopt: error: --category 'truck' is not a UN vehicle category: give one of M1, M2, M3, N1, N2, N3 (M: "
        "carrying people, N: goods; 1 light, 2 medium, 3 heavy)"]
    assert "other" not in vehicle_names()


def test_a_body_wider_than_the_legal_maximum_is_warned_of_and_mirrors_do_not_count(export):
    """The box bus is 2.5 m wide: no warning; a 2.9 m wide one is warned of; mirrors reaching 0.2 m out of the
    2.5 m body change nothing (the width is the body's, median over the length)."""
    from rigopt.vehicle.category import body_width

    bus = a_bus_mesh()
    mirrors = [trimesh.creation.box(extents=[0.1, 0.4, 0.3], transform=trimesh.transformations.translation_matrix(
        [5.5, side * 1.25, 2.0])) for side in (1.0, -1.0)]
    mirrored = user.add_user_vehicle("bus", export(trimesh.util.concatenate([bus, *mirrors]), "bus.stl"),
                                     forward="+x")
    assert not any("wide without its mirrors" in w for w in mirrored.warnings)
    assert body_width(load_vehicle("bus")) == pytest.approx(2.5, abs=0.03)
    wide = a_bus_mesh()
    wide.apply_scale([1.0, 1.16, 1.0])
    warned = user.add_user_vehicle("widebus", export(wide, "wide.stl"), forward="+x")
    assert any("2.90 m wide without its mirrors, above the 2.55 m" in w for w in warned.warnings)
