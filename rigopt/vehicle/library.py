"""The vehicles rigopt knows: the four built in (``vehicles/<name>/vehicle.toml``) and the user's own.

A vehicle is found by its name, an alias or its CARLA blueprint, case-insensitively. User vehicles live
in ``$RIGOPT_HOME/vehicles/<name>/`` (default ``~/.rigopt``), written by ``rigopt vehicle add``.
"""

from __future__ import annotations

import os
from functools import lru_cache
from pathlib import Path

from rigopt.errors import unknown_name
from rigopt.resources import data_dir
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import VehicleSpec, read_spec

SPEC_FILE = "vehicle.toml"


def user_vehicles_dir() -> Path:
    """Folder of the user's vehicles: ``$RIGOPT_HOME/vehicles`` (default ``~/.rigopt/vehicles``)."""
    return Path(os.environ.get("RIGOPT_HOME", Path.home() / ".rigopt")) / "vehicles"


def _spec_files() -> list[Path]:
    builtin = sorted(data_dir("vehicles").glob(f"*/{SPEC_FILE}"))
    user = sorted(user_vehicles_dir().glob(f"*/{SPEC_FILE}")) if user_vehicles_dir().is_dir() else []
    return builtin + user


def vehicle_specs() -> list[VehicleSpec]:
    """Every known vehicle's spec, built-in first."""
    return [read_spec(path) for path in _spec_files()]


def vehicle_names() -> list[str]:
    return [spec.name for spec in vehicle_specs()]


def find_spec(name: str) -> VehicleSpec:
    """The spec whose name, alias or blueprint is ``name`` (case-insensitive)."""
    wanted = name.lower()
    for spec in vehicle_specs():
        if wanted in {k.lower() for k in (spec.name, spec.blueprint, *spec.aliases)}:
            return spec
    raise unknown_name("vehicle", name, [f"{s.name} ({s.blueprint})" for s in vehicle_specs()])


@lru_cache(maxsize=16)
def _built(source: str, mtime: float) -> Vehicle:
    return Vehicle.from_spec(read_spec(source))


def load_vehicle(name: str) -> Vehicle:
    """The vehicle called ``name`` with its mesh built (cached per spec file and modification time)."""
    spec = find_spec(name)
    path = Path(spec.source)
    return _built(str(path), path.stat().st_mtime)
