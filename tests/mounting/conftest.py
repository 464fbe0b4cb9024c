"""The box car of the mounting tests (see tests/box_car.py): the box [-2, 2] x [-0.9, 0.9] x [0.3, 1.5] m with a
front zone and a mirrored side zone. Test modules cannot import this file, so they get it as a fixture."""

from __future__ import annotations

import pytest

from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

from box_car import spec_text


@pytest.fixture(scope="session")
def box_car(tmp_path_factory) -> Vehicle:
    path = tmp_path_factory.mktemp("boxcar") / "vehicle.toml"
    path.write_text(spec_text())
    return Vehicle.from_spec(read_spec(path))
