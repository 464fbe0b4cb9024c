"""Values made ready for strict JSON: NaN and inf floats become null (None)."""

from __future__ import annotations

import math


def json_ready(value):
    """``value`` (nested dicts, lists, tuples) with NaN and inf floats replaced by None."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    return value
