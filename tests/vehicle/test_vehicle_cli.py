"""``rigopt vehicles``, ``vehicle add|export|show`` and ``check`` on a user box car under a tmp RIGOPT_HOME.

The built-in vehicles are replaced by one fake built-in (see ``rigopt_home`` in conftest) for the
in-process runs; the subprocess run only needs a name that no vehicle has.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from typer.testing import CliRunner

from in_process import run_rigopt
from rigopt.cli.app import app

pytestmark = pytest.mark.usefixtures("rigopt_home")

runner = CliRunner()


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture
def mycar(asymmetric_car, tmp_path):
    """The asymmetric box car added as user vehicle "mycar" through the CLI."""
    path = tmp_path / "mycar.stl"
    asymmetric_car.mesh.export(path)
    result = invoke("vehicle", "add", "mycar", "--mesh", path, "--forward", "+x")
    assert result.exit_code == 0, (result.output, result.exception)
    from rigopt.vehicle.library import load_vehicle

    return load_vehicle("mycar")  # as stored: moved to the centre of its footprint box


def test_vehicle_add_reports_the_stored_spec(asymmetric_car, tmp_path, rigopt_home):
    path = tmp_path / "mycar.stl"
    asymmetric_car.mesh.export(path)
    result = invoke("vehicle", "add", "mycar", "--mesh", path, "--forward", "+x")
    assert result.exit_code == 0, result.output
    assert "mycar" in result.output
    assert (rigopt_home / "vehicles" / "mycar" / "vehicle.toml").is_file()


def test_vehicles_json_lists_the_new_vehicle_with_its_size(mycar):
    result = invoke("vehicles", "--json")
    assert result.exit_code == 0, result.output
    rows = {row["vehicle"]: row for row in json.loads(result.stdout)}
    assert "mycar" in rows
    size = np.ptp(mycar.mesh.bounds, axis=0)
    row = rows["mycar"]
    assert [row["length"], row["width"], row["height"]] == pytest.approx(size.tolist(), abs=1e-4)
    assert "bumper_front" in row["zones"]


def test_check_json_shape(mycar):
    result = invoke("check", "R1", "--vehicle", "mycar", "--json")
    data = json.loads(result.stdout)
    assert set(data) == {"rig", "vehicle", "cameras"}
    assert data["vehicle"] == "mycar"
    assert data["cameras"]
    for entry in data["cameras"]:
        assert set(entry) == {"id", "valid", "distance_to_surface", "zone", "problems"}
        assert isinstance(entry["problems"], list)
        assert entry["valid"] == (not entry["problems"])


def test_check_exit_code_follows_validity(mycar):
    result = invoke("check", "R1", "--vehicle", "mycar", "--json")
    valid = all(c["valid"] for c in json.loads(result.stdout)["cameras"])
    assert result.exit_code == (0 if valid else 1)


def test_export_in_carla_frame_is_reflected(mycar, tmp_path):
    out = tmp_path / "x.ply"
    result = invoke("vehicle", "export", "mycar", "--out", out, "--frame", "carla")
    assert result.exit_code == 0, result.output
    loaded = trimesh.load(out, force="mesh")
    (x0, y0, z0), (x1, y1, z1) = mycar.mesh.bounds
    np.testing.assert_allclose(loaded.bounds, [[x0, -y1, z0], [x1, -y0, z1]], atol=1e-4)
    centroid = mycar.mesh.center_mass
    np.testing.assert_allclose(loaded.center_mass, centroid * [1, -1, 1], atol=1e-4)
    assert abs(centroid[1]) > 0.01  # the car is asymmetric (one mirror), so the reflection shows


def test_export_in_carla_frame_keeps_normals_outward(mycar, tmp_path):
    out = tmp_path / "x.ply"
    invoke("vehicle", "export", "mycar", "--out", out, "--frame", "carla")
    assert trimesh.load(out, force="mesh").volume == pytest.approx(mycar.mesh.volume, abs=1e-4)


def test_export_in_iso_frame_is_unchanged(mycar, tmp_path):
    out = tmp_path / "x.stl"
    assert invoke("vehicle", "export", "mycar", "--out", out).exit_code == 0
    np.testing.assert_allclose(trimesh.load(out, force="mesh").bounds, mycar.mesh.bounds, atol=1e-4)


def test_vehicle_show_writes_a_png(mycar, tmp_path):
    out = tmp_path / "car.png"
    result = invoke("vehicle", "show", "mycar", "--out", out)
    assert result.exit_code == 0, result.output
    assert out.read_bytes()[:4] == b"\x89PNG"


def test_unknown_vehicle_is_a_one_line_error(tmp_path):
    result = run_rigopt("vehicle", "show", "nosuchcar", "--out", tmp_path / "x.png", cwd=tmp_path,
                        env={"RIGOPT_HOME": str(tmp_path / "home")})
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("rigopt: error:")
    assert "nosuchcar" in lines[0]
    assert "Traceback" not in result.stderr
    assert not (tmp_path / "x.png").exists()


def test_re_adding_through_the_cli_needs_force(mycar, tmp_path):
    path = tmp_path / "again.stl"
    mycar.mesh.export(path)
    refused = invoke("vehicle", "add", "MYCAR", "--mesh", path, "--forward", "+x")
    assert refused.exit_code != 0 and "--force" in str(refused.exception)
    assert invoke("vehicle", "add", "MYCAR", "--mesh", path, "--forward", "+x", "--force").exit_code == 0


def test_check_works_beside_a_broken_user_vehicle(mycar, rigopt_home):
    (rigopt_home / "vehicles" / "wreck").mkdir()
    (rigopt_home / "vehicles" / "wreck" / "vehicle.toml").write_bytes(b"\xff\xfe not text")
    result = invoke("check", "R1", "--json")
    assert result.exit_code in (0, 1), result.output
    assert json.loads(result.stdout)["vehicle"] == "etron"
    listed = invoke("vehicles", "--json")
    assert "wreck" in listed.stderr and "skipped" in listed.stderr
    assert "wreck" not in {row["vehicle"] for row in json.loads(listed.stdout)}

