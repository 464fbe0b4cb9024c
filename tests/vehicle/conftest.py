"""Small test vehicles written as spec TOML files, independent of the built-in vehicles' shapes.

The box car is one prism: the box [-2, 2] x [-0.9, 0.9] x [0.3, 1.5] m (ISO frame), with a front zone
(x in [1.9, 2.2], normal +x, cone 45 deg) and a mirrored side zone (y in [0.8, 1.0], normal +y, cone
45 deg). Test modules cannot import this file, so they get the vehicles and spec writers as fixtures.
"""

from __future__ import annotations


import pytest

from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

from box_car import BOX_BODY, BOX_ZONES, spec_text

#: A mirror housing on the left only: makes the body asymmetric in y (for frame reflections).
LEFT_MIRROR = """
[[solids]]
name = "mirror"
type = "box"
center = [0.5, 1.0, 1.2]
size = [0.2, 0.3, 0.1]
"""


@pytest.fixture
def write_spec(tmp_path):
    """Factory: write TOML text to ``tmp_path/<file>`` and return the path."""
    counter = iter(range(10**6))

    def write(text: str, file: str | None = None):
        path = tmp_path / (file or f"spec{next(counter)}.toml")
        path.write_text(text)
        return path

    return write


@pytest.fixture
def build_vehicle(write_spec):
    """Factory: a Vehicle from spec text (see :func:`spec_text`)."""

    def build(text: str) -> Vehicle:
        return Vehicle.from_spec(read_spec(write_spec(text)))

    return build


@pytest.fixture
def make_spec_text():
    return spec_text


@pytest.fixture
def box_body():
    """The box car's one prism as spec text (to append more solids to)."""
    return BOX_BODY


@pytest.fixture
def box_zones():
    return BOX_ZONES


@pytest.fixture(scope="session")
def box_car(tmp_path_factory) -> Vehicle:
    path = tmp_path_factory.mktemp("boxcar") / "vehicle.toml"
    path.write_text(spec_text())
    return Vehicle.from_spec(read_spec(path))


@pytest.fixture(scope="session")
def asymmetric_car(tmp_path_factory) -> Vehicle:
    """The box car with a left mirror housing: bounds y in [-0.9, 1.15]."""
    path = tmp_path_factory.mktemp("asymcar") / "vehicle.toml"
    path.write_text(spec_text("asymcar", BOX_BODY + LEFT_MIRROR))
    return Vehicle.from_spec(read_spec(path))


@pytest.fixture
def rigopt_home(tmp_path, monkeypatch):
    """RIGOPT_HOME in a tmp folder, and the built-in vehicles replaced by one fake built-in "etron" (a box car)
    so that nothing depends on the real built-in specs."""
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("RIGOPT_HOME", str(home))
    builtin = tmp_path / "builtin_vehicles"
    (builtin / "etron").mkdir(parents=True)
    (builtin / "etron" / "vehicle.toml").write_text(spec_text("etron").replace(
        'blueprint = "vehicle.test.etron"', 'blueprint = "vehicle.audi.etron"\naliases = ["suv"]'))
    monkeypatch.setattr("rigopt.vehicle.library.data_dir", lambda name: builtin)
    return home
