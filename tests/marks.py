"""Parametrised cases of which some need the slow marker (``python -m pytest -m slow`` runs those)."""

from __future__ import annotations

import pytest


def cases(values, slow) -> list:
    """``values`` as parametrize arguments, each one named in ``slow`` marked slow."""
    unknown = set(slow) - set(values)
    assert not unknown, f"slow cases that are no cases: {sorted(unknown)}"
    return [pytest.param(value, marks=pytest.mark.slow) if value in slow else value for value in values]
