"""Command-line values every command reads the same way: image sizes, origin offsets.

One parser, one message: ``rigopt import`` (``--image-size``), ``rigopt design`` (``--image-size``) and
``rigopt bench generate`` (``--size``) take ``WIDTHxHEIGHT`` in whole pixels.
"""

from __future__ import annotations

import math

from rigopt.benchmark import MAX_IMAGE_SIDE  # the largest image side any command takes (a camera's)
from rigopt.errors import RigoptError

#: Smallest image side (px): below every camera a detector is fed (a thumbnail is not a camera).
MIN_IMAGE_SIDE = 16
#: Largest origin offset (m) in any coordinate: a rig's positions lie within 100 m of its origin
#: (``rigopt.rig.model.MAX_POSITION_M``), so a larger offset is a typo or a wrong unit.
MAX_ORIGIN_OFFSET_M = 100.0


def parse_image_size(text: str, option: str = "--image-size", smallest: int = MIN_IMAGE_SIDE) -> tuple[int, int]:
    """``"1600x900"`` -> (1600, 900): (width, height) in pixels, each a whole number in smallest..MAX_IMAGE_SIDE.

    option : the option the value came from, named in the RigoptError raised for anything else; smallest : the
    smallest side, a camera's MIN_IMAGE_SIDE by default (a rendering size for tests may go down to 1).
    """
    width, sep, height = (part.strip() for part in text.strip().lower().partition("x"))
    size = None
    if sep and all(part.isascii() and part.isdigit() for part in (width, height)):
        size = (int(width), int(height))
    if size is None or not all(smallest <= side <= MAX_IMAGE_SIDE for side in size):
        raise RigoptError(f"{option} must be WIDTHxHEIGHT in whole pixels, each side {smallest} to "
                          f"{MAX_IMAGE_SIDE}, e.g. 1600x900; got {text!r}")
    return size


def image_size_text(size: tuple[int, int]) -> str:
    """(1600, 900) -> ``"1600x900"``, the form :func:`parse_image_size` reads."""
    return f"{size[0]}x{size[1]}"


def parse_origin_offset(text: str) -> tuple[float, float, float]:
    """``"-1.4,0,0.3"`` -> (-1.4, 0.0, 0.3) metres; raises RigoptError on anything but three finite numbers within
    MAX_ORIGIN_OFFSET_M."""
    parts = text.split(",")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) and abs(v) <= MAX_ORIGIN_OFFSET_M for v in values):
        raise RigoptError(f"--origin-offset must be three numbers X,Y,Z in metres (x forward, y left, z up), each "
                          f"within {MAX_ORIGIN_OFFSET_M:g} m, e.g. -1.4,0,0.3; got {text!r}")
    return values
