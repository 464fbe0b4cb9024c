"""Meshes as they come: formats, the pose flags and the checks that name them, closing, wheels.

The raw car is tests/sim_car.py's: body without a floor, cabin and four wheels as separate parts.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
import trimesh

from rigopt.errors import DataError, RigoptError
from rigopt.vehicle.closing import CLOSING_P95_LIMIT, close_mesh
from rigopt.vehicle.library import load_vehicle
from rigopt.vehicle.orientation import SIZE_LIMITS, check_pose, frame_rotation
from rigopt.vehicle.user import add_user_vehicle, prepare_user_mesh, read_mesh_file

import sim_car
from sim_car import AXLES, RADIUS, TRACK, WIDTH, sim_car_mesh, sim_car_parts, to_file_frame, write_obj
from rigopt.vehicle.wheels import find_wheels

pytestmark = pytest.mark.usefixtures("rigopt_home")

FLAG = re.compile(r"--(scale|forward|up) (\S+)")


def suggested_flags(message: str) -> dict[str, str]:
    """The flags after the last 'add' of an error message: {'scale': '0.01', ...} (the first of alternatives)."""
    fix = message.rsplit(": add ", 1)[1]
    flags = {}
    for name, value in FLAG.findall(fix):
        flags.setdefault(name, value.rstrip(",;)"))
    return flags


def pose_flags(flags: dict[str, str]) -> dict:
    return {"scale": float(flags.get("scale", 1.0)), "forward": flags.get("forward"), "up": flags.get("up")}


def iso_raw(mesh: trimesh.Trimesh, forward=None, up=None, scale=1.0) -> trimesh.Trimesh:
    """What the flags make of a file mesh (before closing)."""
    rotation = frame_rotation(forward or "+x", up or "+z")
    return trimesh.Trimesh(mesh.vertices @ rotation.T * scale, mesh.faces, process=False)


def check(mesh, **flags):
    return check_pose(iso_raw(mesh, flags.get("forward"), flags.get("up"), flags.get("scale", 1.0)), "car.obj",
                      **flags)


# --- the checks name the flag that fixes them, and it does ------------------------------------------------------


@pytest.mark.parametrize("scale, unit", [(0.01, "centimetres"), (0.001, "millimetres"), (0.0254, "inches")])
def test_units_are_named_with_the_scale_that_fixes_them(scale, unit):
    mesh = sim_car_mesh(scale=scale)
    with pytest.raises(DataError, match=rf"looks like {unit} \([\d.]+ m long\): add --scale {scale:g}") as caught:
        check(mesh)
    assert check(mesh, **pose_flags(suggested_flags(str(caught.value))), ) == []


@pytest.mark.parametrize("forward", ["+y", "-y"])
def test_a_turned_mesh_gets_the_forward_axis_its_front_faces(forward):
    mesh = sim_car_mesh(forward=forward)
    with pytest.raises(DataError, match=f"longest along y.*its front seems to face {re.escape(forward)} .*: "
                                        f"add --forward {re.escape(forward)}"):
        check(mesh)
    assert check(mesh, forward=forward) == []


def test_a_backwards_mesh_is_not_accepted_silently():
    mesh = sim_car_mesh(forward="-x")
    with pytest.raises(DataError, match=r"seems to face -x .*: add --forward -x, or --forward \+x if"):
        check(mesh)
    assert check(mesh, forward="-x") == []
    assert check(mesh, forward="+x") == []  # an explicit --forward is believed


def test_a_mesh_whose_ends_look_alike_needs_forward_confirmed(box_car):
    with pytest.raises(DataError, match=r"cannot tell the mesh's front.*confirm it with --forward \+x"):
        check_pose(box_car.mesh, "box.stl")
    assert check_pose(box_car.mesh, "box.stl", forward="+x") == []


@pytest.mark.parametrize("forward", ["+x", "+z", "-z"])
def test_a_y_up_mesh_is_told_to_use_up_y(forward):
    mesh = sim_car_mesh(forward=forward, up="+y")
    with pytest.raises(DataError, match=r"z does not seem to be up.*add --up \+y"):
        check(mesh)
    flags = suggested_flags(str(mesh_error(mesh)))
    assert flags["up"] == "+y"
    if forward != "+x":
        assert flags["forward"] in ("+z", "-z")
    assert check(mesh, up="+y", forward=forward) == []


def mesh_error(mesh) -> DataError:
    with pytest.raises(DataError) as caught:
        check(mesh)
    return caught.value


def test_a_mesh_standing_on_end_is_refused():
    mesh = sim_car_mesh(forward="+z", up="-x")
    with pytest.raises(DataError, match="on its side|--up"):
        check(mesh)


def fire_truck(width: float = 3.56) -> trimesh.Trimesh:
    """A closed fire-truck-like mesh (cab lower than the body, mirrors making it ``width`` wide), ISO frame."""
    parts = [trimesh.creation.box([5.6, 2.5, 2.6]), trimesh.creation.box([2.2, 2.5, 2.0]),
             trimesh.creation.box([0.15, width, 0.5])]
    for part, centre in zip(parts, [[-1.2, 0, 2.0], [2.7, 0, 1.7], [3.0, 0, 2.2]]):
        part.apply_translation(centre)
    for x in (2.6, -2.7):
        for y in (1.0, -1.0):
            wheel = trimesh.creation.cylinder(0.55, 0.35, sections=24)
            wheel.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
            wheel.apply_translation([x, y, 0.55])
            parts.append(wheel)
    return trimesh.util.concatenate(parts)


def test_a_wide_fire_truck_names_the_dimension_and_the_limit():
    with pytest.raises(DataError, match=r"width 3\.56 m is outside a road vehicle's 1\.4-3 m .*--allow-size"):
        check_pose(fire_truck(), "truck.obj")


def test_allow_size_accepts_the_fire_truck_with_a_warning(tmp_path):
    path = tmp_path / "truck.glb"
    fire_truck().export(path)
    added = add_user_vehicle("truck", path, allow_size=True)
    assert [w for w in added.warnings if "width 3.56 m" in w and "1.4-3" in w]
    assert added.closing.method == "exact"
    assert load_vehicle("truck").size[1] == pytest.approx(3.56, abs=1e-3)


def test_size_limits_are_documented_values():
    assert SIZE_LIMITS == {"length": (2.5, 25.0), "width": (1.4, 3.0), "height": (1.0, 4.5)}


def test_forward_and_up_must_differ():
    with pytest.raises(RigoptError, match="different axes"):
        frame_rotation("+z", "+z")
    with pytest.raises(RigoptError, match="--forward must be one of"):
        frame_rotation("ahead", "+z")


def test_frame_rotation_is_a_proper_rotation_taking_forward_to_x():
    for forward, up in [("-y", "+z"), ("+z", "+y"), ("-x", "+z"), ("+x", "+y")]:
        rotation = frame_rotation(forward, up)
        assert np.linalg.det(rotation) == pytest.approx(1.0)
        from rigopt.vehicle.orientation import AXES
        np.testing.assert_allclose(rotation @ AXES[forward], [1, 0, 0])
        np.testing.assert_allclose(rotation @ AXES[up], [0, 0, 1])


# --- formats: scenes of many geometries are merged with their transforms -------------------------------------------


def sim_scene() -> trimesh.Scene:
    """The car's parts as scene nodes; each part moved by -1 m in y in its geometry and back by its node."""
    scene = trimesh.Scene()
    for name, part in sim_car_parts().items():
        moved = part.copy()
        moved.apply_translation([0, -1.0, 0])
        scene.add_geometry(moved, node_name=name, geom_name=name,
                           transform=trimesh.transformations.translation_matrix([0, 1.0, 0]))
    return scene


@pytest.mark.parametrize("suffix", [".glb", ".dae", ".obj", ".ply", ".stl"])
def test_mesh_formats_are_read_whole(tmp_path, suffix):
    path = tmp_path / f"car{suffix}"
    if suffix == ".obj":
        write_obj(path)
    elif suffix == ".dae":  # trimesh writes COLLADA from a list of geometries (no node transforms)
        path.write_bytes(trimesh.exchange.dae.export_collada(list(sim_car_parts().values())))
    else:
        source = sim_scene() if suffix == ".glb" else sim_car_mesh()
        source.export(path)
    mesh = read_mesh_file(path)
    expected = sim_car_mesh()
    np.testing.assert_allclose(mesh.bounds, expected.bounds, atol=1e-4)
    assert mesh.area == pytest.approx(expected.area, rel=1e-4)


def test_unknown_format_is_refused(tmp_path):
    path = tmp_path / "car.xyz"
    path.write_text("1 2 3\n")
    with pytest.raises(DataError, match="not a mesh format"):
        read_mesh_file(path)


# --- closing ---------------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def closed_sim_car():
    return close_mesh(sim_car_mesh(), "sim.obj")


@pytest.mark.slow
def test_open_multi_part_mesh_is_closed_and_its_error_reported(closed_sim_car):
    closed, report = closed_sim_car
    assert closed.is_watertight and closed.is_winding_consistent and closed.volume > 0
    assert report.method == "distance" and report.pitch == pytest.approx(4.6 / 200)
    assert 0 < report.p95_error < 0.01 and report.max_error < 0.03
    assert 0.1 < report.buried < 0.5  # the cabin's floor, the roof under it, the wheels' insides
    assert "closing error max" in report.describe() and "95th percentile" in report.describe()


def test_closing_keeps_the_size(closed_sim_car):
    closed, report = closed_sim_car
    np.testing.assert_allclose(closed.bounds, sim_car_mesh().bounds, atol=2 * report.pitch)


def test_closing_fills_the_body_without_a_floor(closed_sim_car):
    from rigopt.raycast import RayCaster

    closed, _ = closed_sim_car
    inside = RayCaster(closed).inside([[0.0, 0.0, 0.5], [0.0, 0.0, 1.2], [1.45, 0.78, 0.33]])
    below = RayCaster(closed).inside([[0.0, 0.0, 0.15], [0.0, 0.0, 2.0]])  # under the floorless body, above the roof
    assert inside.all() and not below.any()


def test_closed_parts_are_joined_exactly():
    closed, report = close_mesh(fire_truck(), "truck.obj")
    assert report.method == "exact" and report.max_error < 1e-4
    assert closed.is_watertight


@pytest.mark.slow
def test_a_single_sided_sheet_is_kept_as_a_thin_slab():
    awning = trimesh.creation.box([4.0, 1.8, 0.01])
    awning = trimesh.Trimesh(awning.vertices, awning.faces[awning.face_normals[:, 2] > 0.5], process=False)
    awning.apply_translation([0, 0, 2.2])  # a single-sided sheet: no volume of its own
    closed, report = close_mesh(trimesh.util.concatenate([sim_car_mesh(), awning.subdivide()]), "awning.obj")
    assert report.thin > 0.1 and report.p95_error < 0.03
    from rigopt.raycast import RayCaster

    assert RayCaster(closed).inside([[0.0, 0.0, 2.2]]).all()  # the sheet is a slab now
    assert not RayCaster(closed).inside([[0.0, 0.0, 2.2 + 2 * report.pitch]]).any()


def test_a_mesh_turned_inside_out_is_refused_with_the_step_that_fixes_it():
    box = trimesh.creation.box([4.0, 1.8, 1.4])
    with pytest.raises(DataError, match="turned inside out; export it with outward-facing normals"):
        close_mesh(trimesh.Trimesh(box.vertices, box.faces[:, ::-1]), "inside_out.stl")


def test_closing_is_refused_with_the_finer_pitch_that_fixes_it():
    awning = trimesh.creation.box([4.0, 1.8, 0.01])
    awning = trimesh.Trimesh(awning.vertices, awning.faces[awning.face_normals[:, 2] > 0.5], process=False)
    awning.apply_translation([0, 0, 2.2])
    mesh = trimesh.util.concatenate([sim_car_mesh(), awning.subdivide()])
    with pytest.raises(DataError, match=f"within {CLOSING_P95_LIMIT * 100:.0f} cm.*add --pitch 0.05 ") as caught:
        close_mesh(mesh, "awning.obj", pitch=0.1)  # the sheet thickened by 7.5 cm on each side
    finer = float(re.search(r"--pitch (\S+)", str(caught.value)).group(1))
    _, report = close_mesh(mesh, "awning.obj", pitch=finer)
    assert report.p95_error <= CLOSING_P95_LIMIT


# --- wheels -----------------------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_wheels_are_found_on_the_raw_car(tmp_path):
    path = tmp_path / "car.obj"
    write_obj(path, forward="-y", scale=0.01)
    prepared = prepare_user_mesh(path, scale=0.01, forward="-y")
    assert [w.x for w in prepared.wheels] == pytest.approx(AXLES, abs=0.02)
    for wheel in prepared.wheels:
        assert wheel.radius == pytest.approx(RADIUS, abs=0.03)
        assert wheel.track == pytest.approx(TRACK, abs=0.02)
        assert wheel.width == pytest.approx(WIDTH, abs=0.02)


def test_wheels_of_a_body_that_hugs_its_tyres_are_measured_on_the_tyres():
    wheels = find_wheels(sim_car.joined(sim_car.hugging_car_parts()))  # arches 3 cm around them, sills at 14 cm
    assert [w.x for w in wheels] == pytest.approx(sim_car.HUG_AXLES, abs=0.01)
    for wheel in wheels:
        assert wheel.radius == pytest.approx(sim_car.HUG_RADIUS, abs=0.01)  # not the arch's 0.34 m
        assert wheel.width == pytest.approx(sim_car.HUG_WIDTH, abs=0.01)
        assert wheel.track == pytest.approx(sim_car.HUG_TRACK, abs=0.01)


def test_dual_rear_wheels_count_as_one_wide_tyre():
    front, rear = find_wheels(sim_car.joined(sim_car.dual_truck_parts()))
    assert (front.x, rear.x) == pytest.approx(sim_car.DUAL_AXLES, abs=0.01)
    assert front.radius == pytest.approx(sim_car.DUAL_RADIUS, abs=0.01)
    assert rear.radius == pytest.approx(sim_car.DUAL_RADIUS, abs=0.01)
    assert front.width == pytest.approx(sim_car.DUAL_FRONT_WIDTH, abs=0.01)
    assert rear.width == pytest.approx(sim_car.DUAL_REAR_WIDTH, abs=0.01)  # the pair, its gap included
    assert (front.track, rear.track) == pytest.approx((sim_car.DUAL_FRONT_TRACK, sim_car.DUAL_REAR_TRACK), abs=0.01)


def test_a_wall_beside_the_ground_is_not_a_tyre(box_car):
    assert find_wheels(box_car.mesh, axles=[1.3, -1.2]) == ()  # the box's bottom touches the ground; no tread


@pytest.fixture
def hatch(tmp_path):
    path = tmp_path / "hatch.stl"
    sim_car.joined(sim_car.hugging_car_parts()).export(path)
    return path


def test_axles_given_twice_are_refused(hatch):
    with pytest.raises(RigoptError, match="distinct and at least 0.4 m apart"):
        add_user_vehicle("hatch", hatch, forward="+x", axles=[1.4, 1.4])


def test_an_axle_given_off_its_tyres_is_refused_with_where_they_are(hatch):
    with pytest.raises(DataError, match=r"--axles 1: the tyres there stand centred at x = 1\.40 m.*give --axles 1\.40"):
        add_user_vehicle("hatch", hatch, forward="+x", axles=[1.0, -1.35])


def test_given_axles_keep_their_measured_wheels(hatch):
    added = add_user_vehicle("hatch", hatch, forward="+x", axles=[1.4, -1.35])
    assert added.axles == (1.4, -1.35)
    assert [w.radius for w in added.wheels] == pytest.approx([sim_car.HUG_RADIUS] * 2, abs=0.01)


def test_a_box_without_wheels_has_no_axles(box_car, tmp_path):
    path = tmp_path / "box.stl"
    box_car.mesh.export(path)
    added = add_user_vehicle("boxy", path, forward="+x")
    assert added.axles == () and added.wheels == ()
    assert load_vehicle("boxy").axles == () and load_vehicle("boxy").rear_axle is None


def test_axles_override(box_car, tmp_path):
    path = tmp_path / "box.stl"
    box_car.mesh.export(path)
    add_user_vehicle("boxy", path, forward="+x", axles=[-1.2, 1.3])
    vehicle = load_vehicle("boxy")
    assert vehicle.axles == (1.3, -1.2)
    np.testing.assert_allclose(vehicle.rear_axle, [-1.2, 0, 0])


def test_axles_off_the_mesh_are_refused(box_car, tmp_path):
    path = tmp_path / "box.stl"
    box_car.mesh.export(path)
    with pytest.raises(RigoptError, match="outside the mesh's length"):
        add_user_vehicle("boxy", path, forward="+x", axles=[9.0])


def test_roof_rack_adds_a_raised_zone(tmp_path):
    path = tmp_path / "truck.glb"
    fire_truck(2.5).export(path)
    add_user_vehicle("truck", path, roof_rack=0.8)
    zones = [z for z in load_vehicle("truck").zones if z.name == "roof_rack"]
    assert len(zones) == 1 and zones[0].raised_max == 0.8 and zones[0].raised
    assert all(not z.raised for z in load_vehicle("truck").zones if z.name != "roof_rack")


def test_roof_rack_height_is_checked(box_car, tmp_path):
    path = tmp_path / "box.stl"
    box_car.mesh.export(path)
    with pytest.raises(RigoptError, match="--roof-rack"):
        add_user_vehicle("boxy", path, forward="+x", roof_rack=-0.5)


def test_to_file_frame_round_trips():
    mesh = sim_car_mesh()
    back = iso_raw(to_file_frame(mesh, "-z", "+y", 0.01), "-z", "+y", 0.01)
    np.testing.assert_allclose(back.vertices, mesh.vertices, atol=1e-9)
