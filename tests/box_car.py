"""The box car of the tests: a 4 x 1.8 x 1.2 m box (x in [-2, 2], y in [-0.9, 0.9], z in [0.3, 1.5]) as
vehicle spec text, with front and side zones, an optional roof zone and optional wheels. Imported by test modules (the
tests folder is on the import path through its conftest)."""

import textwrap

BOX_BODY = """
[[solids]]
name = "body"
type = "prism"
side = [[-2, 0.3], [2, 0.3], [2, 1.5], [-2, 1.5]]
plan = [[2, 0], [2, 0.9], [-2, 0.9], [-2, 0]]
"""

#: The box car's wheels (solid text to add to BOX_BODY): axles at x = 1.3 and -1.3 m, so its rear axle, the
#: reports' datum, lies 1.3 m behind its centre.
BOX_WHEELS = """
[[solids]]
name = "wheels"
type = "wheels"
axles = [1.3, -1.3]
radius = 0.35
width = 0.25
track = 1.6
"""

BOX_ZONES = """
[[zones]]
name = "front"
min = [1.9, -1.0, 0.2]
max = [2.2, 1.0, 1.6]
normal = [1, 0, 0]
cone_deg = 45

[[zones]]
name = "side"
min = [-2.1, 0.8, 0.2]
max = [2.1, 1.0, 1.6]
normal = [0, 1, 0]
cone_deg = 45
mirrored = true
"""

ROOF_ZONE = """
[[zones]]
name = "roof"
min = [-0.3, -0.3, 1.4]
max = [0.3, 0.3, 1.6]
normal = [0, 0, 1]
cone_deg = 30
"""


def spec_text(name: str = "boxcar", solids: str = BOX_BODY, zones: str = BOX_ZONES) -> str:
    """Spec TOML of a vehicle ``name`` (blueprint ``vehicle.test.<name>``) with ``solids`` and ``zones``."""
    return f'name = "{name}"\nblueprint = "vehicle.test.{name}"\n' + textwrap.dedent(solids) + textwrap.dedent(zones)


def install_user_vehicle(home, name: str = "boxcar", zones: str = BOX_ZONES + ROOF_ZONE):
    """Write the box car (with ``zones``) as user vehicle ``name`` under ``home`` (a RIGOPT_HOME folder), so
    that commands find it by name; returns its spec file."""
    from pathlib import Path

    folder = Path(home) / "vehicles" / name
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "vehicle.toml"
    path.write_text(spec_text(name, zones=zones))
    return path


def front_and_left_rig(blueprint: str, name: str = "boxrig"):
    """A two-camera rig on the box car: F on the front face looking forward (100 deg), L on the left side
    looking left (90 deg); both 4 cm off the surface."""
    import numpy as np

    from rigopt.rig.model import Camera, Rig

    left = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    return Rig(name, blueprint, (Camera.pinhole("CAM_FRONT", np.array([2.04, 0.0, 1.0]), np.eye(3), 100.0),
                                 Camera.pinhole("CAM_LEFT", np.array([0.0, 0.94, 1.0]), left, 90.0)))
