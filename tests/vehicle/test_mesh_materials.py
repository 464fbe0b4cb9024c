"""What a user mesh's materials name (``rigopt.vehicle.materials``, ``rigopt.vehicle.glass``), read from OBJ's MTL
and glTF: the windscreen and rear window become the windshield zones, side windows keep-outs, lamps and number
plates fixtures; a file without materials has none."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from in_process import run_rigopt
from trimesh.visual import TextureVisuals
from trimesh.visual.material import PBRMaterial, SimpleMaterial

from rigopt.vehicle.glass import ROOF_REASON, SIDE_REASON, glass_features
from rigopt.vehicle.materials import FIXTURE_MARGIN, material_kind, material_parts, part_fixtures

#: The windscreen's foot and top (x, z) m, from the car's centre: raked 29 deg above the horizontal.
SCREEN_TOP, SCREEN_FOOT = (0.6, 1.4), (1.4, 0.95)


def glass_triangles(path) -> np.ndarray:
    return np.concatenate([t for _, t in material_parts(path)["glass"]] + [np.zeros((0, 3, 3))])


def _box(low, high) -> trimesh.Trimesh:
    low, high = np.asarray(low, float), np.asarray(high, float)
    box = trimesh.creation.box(extents=high - low)
    box.apply_translation((low + high) / 2)
    return box


def _slab(points_xz, y0: float, y1: float) -> trimesh.Trimesh:
    points = np.asarray(points_xz, dtype=float)
    return trimesh.convex.convex_hull(np.vstack([np.column_stack([points[:, 0], np.full(len(points), y), points[:, 1]])
                                                 for y in (y0, y1)]))


def _car_parts() -> list[tuple[str, trimesh.Trimesh]]:
    """A 4.2 m car, its parts with the names of their materials: body, cabin, windscreen, rear window, side windows,
    tyres, two tail lamps (one material) and a number plate, x forward, from the footprint's centre on the ground."""
    (tx, tz), (fx, fz) = SCREEN_TOP, SCREEN_FOOT
    parts = [("paint", _slab([(-2.1, 0.3), (2.1, 0.3), (2.1, 0.95), (-2.1, 0.95)], -0.9, 0.9)),
             ("paint", _slab([(-1.2, 0.95), (0.6, 0.95), (0.6, 1.4), (-1.2, 1.4)], -0.8, 0.8)),
             ("windscreen", _slab([(tx, tz), (tx + 0.02, tz + 0.02), (fx + 0.02, fz + 0.02), (fx, fz)], -0.75, 0.75)),
             ("rear_glass", _slab([(-1.2, 1.4), (-1.22, 1.42), (-1.72, 0.97), (-1.7, 0.95)], -0.75, 0.75))]
    parts += [("side_window", _slab([(-1.1, 1.0), (0.5, 1.0), (0.5, 1.35), (-1.1, 1.35)], s * 0.8, s * 0.82))
              for s in (1, -1)]
    for x in (-1.3, 1.3):
        for y in (-0.8, 0.8):
            tyre = trimesh.creation.cylinder(radius=0.32, height=0.2, sections=32)
            tyre.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
            tyre.apply_translation([x, y, 0.32])
            parts.append(("tyre", tyre))
    parts += [("Tail_Lamp", _box([-2.12, s * 0.85 - 0.1, 0.75], [-2.1, s * 0.85 + 0.1, 0.9])) for s in (1, -1)]
    parts.append(("licence_plate", _box([-2.115, -0.26, 0.45], [-2.1, 0.26, 0.56])))
    return parts


def _write_obj(folder, parts, turn=None, materials=True):
    """Write ``parts`` as car.obj with car.mtl (side windows see-through, d 0.4; the others opaque, named);
    ``turn`` (3, 3) applied to every vertex first."""
    lines, offset = ["mtllib car.mtl"] if materials else [], 1
    for material, mesh in parts:
        vertices = mesh.vertices @ (turn.T if turn is not None else np.eye(3))
        lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in vertices]
        lines += [f"usemtl {material}"] if materials else []
        lines += [f"f {a + offset} {b + offset} {c + offset}" for a, b, c in mesh.faces]
        offset += len(mesh.vertices)
    (folder / "car.obj").write_text("\n".join(lines) + "\n")
    (folder / "car.mtl").write_text("".join(f"newmtl {name}\nKd 0.2 0.2 0.2\n" + ("d 0.4\n" if name == "side_window" else "")
                                            for name in ("paint", "windscreen", "rear_glass", "side_window", "tyre",
                                                         "Tail_Lamp", "licence_plate")))
    return folder / "car.obj"


def test_what_materials_name():
    kind = material_kind
    assert kind(SimpleMaterial(name="Windshield_01")) == kind(SimpleMaterial(name="GLASS")) == "glass"
    assert kind(SimpleMaterial(name="paint")) is None and kind(None) is None
    see_through = SimpleMaterial(name="m1")
    see_through.kwargs = {"d": ["0.4"]}
    assert kind(see_through) == "glass"
    see_through.kwargs = {"Tr": ["0.6"]}
    assert kind(see_through) == "glass"
    see_through.kwargs = {"d": ["1.0"]}
    assert kind(see_through) is None
    assert kind(PBRMaterial(name="m2", baseColorFactor=[200, 200, 220, 80], alphaMode="BLEND")) == "glass"
    assert kind(PBRMaterial(name="m3", baseColorFactor=[200, 200, 220, 80], alphaMode="OPAQUE")) is None
    assert kind(SimpleMaterial(name="headlight_glass")) == kind(SimpleMaterial(name="Indicator.L")) == "lamp"
    assert kind(SimpleMaterial(name="License Plate")) == kind(SimpleMaterial(name="numberplate")) == "number_plate"


def test_the_obj_glass_is_read_and_sorted_into_windscreen_rear_window_and_side_windows(tmp_path):
    parts = _car_parts()
    triangles = glass_triangles(_write_obj(tmp_path, parts))
    glass_faces = sum(len(m.faces) for name, m in parts if name in ("windscreen", "rear_glass", "side_window"))
    assert triangles.shape == (glass_faces, 3, 3)
    zones, keep_outs = glass_features(triangles, [0.0, 0.0, 0.7])
    front, rear = zones
    assert front["name"] == "windshield_front" and rear["name"] == "windshield_rear"
    assert front["min"] == pytest.approx([0.55, -0.8, 0.9], abs=1e-3)
    assert front["max"] == pytest.approx([1.47, 0.8, 1.47], abs=1e-3)
    rake = np.radians(np.degrees(np.arctan2(0.45, 0.8)))  # the glass's normal leans forward by its rake
    assert front["normal"] == pytest.approx([np.sin(rake), 0.0, np.cos(rake)], abs=0.02)
    assert rear["max"][0] == pytest.approx(-1.15, abs=1e-3) and rear["normal"][0] < -0.5
    assert [(k["name"], k["reason"]) for k in keep_outs] == [("side window 1", SIDE_REASON), ("side window 2", SIDE_REASON)]
    assert keep_outs[0]["min"] == pytest.approx([-1.13, 0.77, 0.97], abs=1e-3)
    assert ROOF_REASON not in {k["reason"] for k in keep_outs}


def test_each_lamp_and_the_number_plate_is_a_fixture(tmp_path):
    """Both tail lamps share one material (one part of the OBJ): each connected lamp is a fixture of its own."""
    fixtures = part_fixtures(material_parts(_write_obj(tmp_path, _car_parts())))
    assert [(f["kind"], f["name"]) for f in fixtures] == [
        ("lamp", "lamp 1 (material Tail_Lamp)"), ("lamp", "lamp 2 (material Tail_Lamp)"),
        ("number_plate", "number plate 1 (material licence_plate)")]
    m = FIXTURE_MARGIN
    assert fixtures[0]["min"] == pytest.approx([-2.12 - m, 0.75 - m, 0.75 - m], abs=1e-6)
    assert fixtures[2]["max"] == pytest.approx([-2.1 + m, 0.26 + m, 0.56 + m], abs=1e-6)


def test_a_glb_with_blended_glass_and_a_mesh_without_materials(tmp_path):
    body, screen = _car_parts()[0][1], _car_parts()[2][1].copy()
    screen.visual = TextureVisuals(material=PBRMaterial(name="m", baseColorFactor=[200, 200, 220, 60], alphaMode="BLEND"))
    trimesh.Scene({"body": body, "screen": screen}).export(tmp_path / "car.glb")
    zones, _ = glass_features(glass_triangles(tmp_path / "car.glb"), [0.0, 0.0, 0.7])
    assert [z["name"] for z in zones] == ["windshield_front"]
    trimesh.util.concatenate([m for _, m in _car_parts()]).export(tmp_path / "car.stl")
    assert glass_triangles(tmp_path / "car.stl").shape == (0, 3, 3)
    assert glass_triangles(_write_obj(tmp_path, _car_parts(), materials=False)).shape == (0, 3, 3)


def test_vehicle_add_turns_the_glass_into_zones_and_keep_outs_in_any_pose(tmp_path):
    """The same car stored from its file as drawn and from a copy turned to face -y (--forward -y): the same zones
    and keep-outs; a point on a side window is in a keep-out, one on the windscreen in its zone, one on a lamp or the
    plate on a fixture; the summary names them."""
    from rigopt.mounting.features import on_fixtures
    from rigopt.mounting.practice import in_keep_outs
    from rigopt.vehicle.library import load_vehicle

    env = {"RIGOPT_HOME": str(tmp_path / "home")}
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    straight = _write_obj(tmp_path / "a", _car_parts())
    to_minus_y = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # a turn about z taking +x to -y
    turned = _write_obj(tmp_path / "b", _car_parts(), to_minus_y)
    first = run_rigopt("vehicle", "add", "gcar", "--mesh", straight, env=env)
    second = run_rigopt("vehicle", "add", "gcar2", "--mesh", turned, "--forward", "-y", env=env)
    assert first.returncode == 0 and second.returncode == 0, first.stderr + second.stderr
    flat = " ".join(first.stdout.split())
    assert "glass (parts its materials call glass): windshield_front zone" in flat and "side window 2" in flat
    assert "lamps and number plates (named by their materials), where no lens sits: lamp 1 (material Tail_Lamp)" in flat
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("RIGOPT_HOME", env["RIGOPT_HOME"])
        cars = [load_vehicle("gcar"), load_vehicle("gcar2")]
    zones = [{z.name: (z.min, z.max) for z in car.zones} for car in cars]
    for name in ("windshield_front", "windshield_rear"):
        assert np.allclose(zones[0][name][0], zones[1][name][0], atol=2e-3)
        assert np.allclose(zones[0][name][1], zones[1][name][1], atol=2e-3)
    assert [z.name for z in cars[0].zones][:2] == ["windshield_front", "windshield_rear"]
    on_window, on_screen = np.array([-0.3, 0.81, 1.2]), np.array([1.0, 0.0, 1.19])
    found = in_keep_outs(cars[0], [on_window, on_screen])
    assert found[0] == [f"side window 1 ({SIDE_REASON})"] and found[1] == []
    on_lamp, on_plate = np.array([-2.12, 0.85, 0.8]), np.array([-2.115, 0.0, 0.5])
    found = on_fixtures(cars[0], [on_lamp, on_plate, on_screen], 0.05)
    assert "lamp 1" in found[0][0] and "its lens must stay uncovered" in found[0][0]
    assert "number plate 1" in found[1][0] and found[2] == []
    low, high = zones[0]["windshield_front"]
    assert np.all(on_screen >= low) and np.all(on_screen <= high)
