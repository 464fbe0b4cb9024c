"""The box car of the tests: a 4 x 1.8 x 1.2 m box (x in [-2, 2], y in [-0.9, 0.9], z in [0.3, 1.5]) as
vehicle spec text, with front and side zones and an optional roof zone. Imported by test modules (the
tests folder is on the import path through its conftest)."""

import textwrap

BOX_BODY = """
[[solids]]
name = "body"
type = "prism"
side = [[-2, 0.3], [2, 0.3], [2, 1.5], [-2, 1.5]]
plan = [[2, 0], [2, 0.9], [-2, 0.9], [-2, 0]]
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
