"""The vehicles rigopt knows: the built-in ones (``vehicles/<name>/vehicle.toml``: the benchmark's four CARLA
vehicles and the cars of the nuScenes, Argoverse and Waymo datasets) and the user's own.

A vehicle is found by its name, an alias or its CARLA blueprint, case-insensitively. The datasets' cars carry
the vehicle names rigopt's importers write by default as aliases (``nuscenes``, ``argoverse2``, ``waymo``), so
that an imported rig is on its own car. User vehicles live
in ``$RIGOPT_HOME/vehicles/<name>/`` (default ``~/.rigopt``), written by ``rigopt vehicle add``. A user
vehicle whose spec cannot be read is skipped (see :func:`broken_user_vehicles`), so that it never breaks the
look-up of any other vehicle; asked for by its own name, it is reported with its problem.
"""

from __future__ import annotations

import os
from functools import lru_cache
from pathlib import Path

from rigopt.errors import RigoptError, UnknownNameError, unknown_name
from rigopt.resources import data_dir
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import VehicleSpec, read_spec

SPEC_FILE = "vehicle.toml"


def user_vehicles_dir() -> Path:
    """Folder of the user's vehicles: ``$RIGOPT_HOME/vehicles`` (default ``~/.rigopt/vehicles``)."""
    return Path(os.environ.get("RIGOPT_HOME", Path.home() / ".rigopt")) / "vehicles"


def _user_spec_files() -> list[Path]:
    folder = user_vehicles_dir()
    return sorted(folder.glob(f"*/{SPEC_FILE}")) if folder.is_dir() else []


def _read_user_specs() -> tuple[list[VehicleSpec], dict[str, str]]:
    """The user's readable specs, and folder name -> problem for each one that cannot be read."""
    specs, broken = [], {}
    for path in _user_spec_files():
        try:
            specs.append(read_spec(path))
        except RigoptError as error:
            broken[path.parent.name] = str(error)
    return specs, broken


def broken_user_vehicles() -> dict[str, str]:
    """User vehicles (folder name) whose spec cannot be read, with the problem; they are skipped everywhere."""
    return _read_user_specs()[1]


def vehicle_specs() -> list[VehicleSpec]:
    """Every known vehicle's spec, built-in first; broken user vehicles are left out."""
    builtin = [read_spec(path) for path in sorted(data_dir("vehicles").glob(f"*/{SPEC_FILE}"))]
    return builtin + _read_user_specs()[0]


def vehicle_names() -> list[str]:
    return [spec.name for spec in vehicle_specs()]


def find_spec(name: str) -> VehicleSpec:
    """The spec whose name, alias or blueprint is ``name`` (case-insensitive)."""
    wanted = name.lower()
    specs = vehicle_specs()
    for spec in specs:
        if wanted in {k.lower() for k in (spec.name, spec.blueprint, *spec.aliases)}:
            return spec
    for folder, problem in broken_user_vehicles().items():
        if folder.lower() == wanted:
            raise UnknownNameError(f"user vehicle {folder!r} cannot be read: {problem}; fix its vehicle.toml or "
                                   f"add it again with rigopt vehicle add {folder} --mesh FILE --force")
    listed = [s.name if s.blueprint == s.name else f"{s.name} ({s.blueprint})" for s in specs]
    error = unknown_name("vehicle", name, listed)
    raise UnknownNameError(f"{error}; your own vehicles are read from $RIGOPT_HOME/vehicles (default "
                           "~/.rigopt/vehicles): add one with rigopt vehicle add NAME --mesh FILE")


@lru_cache(maxsize=16)
def _built(source: str, mtime: float) -> Vehicle:
    return Vehicle.from_spec(read_spec(source))


def load_vehicle(name: str) -> Vehicle:
    """The vehicle called ``name`` with its mesh built (cached per spec file and modification time)."""
    spec = find_spec(name)
    path = Path(spec.source)
    return _built(str(path), path.stat().st_mtime)
