"""The format registry: one :class:`Format` per spec of the light catalogue, in its order, with a listing exactly
when the spec takes --list and a writer exactly when it writes; ``rigopt import`` refuses an option a format does
not take (a zero value included) and its help names, per option, the formats that take it."""

from __future__ import annotations

import pytest
import typer
from in_process import run_rigopt

from rigopt.cli import app
from rigopt.rig.formats.catalogue import CALIBRATION, LIST, SPECS, FormatSpec, taking, writing
from rigopt.rig.formats.registry import FORMATS, Format

OPTIONS = sorted({o for s in SPECS.values() for o in s.options}, key=lambda o: o.flag)


def test_every_spec_has_its_format_in_the_same_order():
    assert list(FORMATS) == list(SPECS)
    assert all(f.spec is SPECS[name] for name, f in FORMATS.items())


def test_readers_and_writers_are_the_format_modules_functions():
    assert FORMATS["carla"].write.__module__ == "rigopt.rig.formats.carla"
    assert [f.name for f in FORMATS.values() if f.write is not None] == [s.name for s in writing()]


def test_a_listing_needs_the_list_option():
    with pytest.raises(ValueError, match="--list"):
        Format(FormatSpec("x", "a test"), print, listing=print)
    with pytest.raises(ValueError, match="--list"):
        Format(FormatSpec("x", "a test", (CALIBRATION, LIST)), print)


def test_a_writer_needs_writes():
    with pytest.raises(ValueError, match="writer"):
        Format(FormatSpec("x", "a test"), print, write=print)
    with pytest.raises(ValueError, match="writer"):
        Format(FormatSpec("x", "a test", writes=True), print)


def test_an_option_of_another_format_is_refused_even_when_zero(tmp_path):
    result = run_rigopt("import", "carla", tmp_path / "none.json", "--out", tmp_path / "r.json", "--calibration", "0")
    assert result.returncode == 2
    assert result.stderr == ("rigopt: error: --calibration: not an option of carla (it takes none beyond --out, "
                             "--vehicle, --name, --origin); drop it\n")


def test_the_refusal_lists_what_the_format_takes(tmp_path):
    result = run_rigopt("import", "dgp", tmp_path / "none", "--out", tmp_path / "r.json", "--log", "x", "--raw-lens")
    assert result.returncode == 2
    assert result.stderr == ("rigopt: error: --log, --raw-lens: not an option of dgp (it takes --calibration, "
                             "--image-size, --list); drop them\n")


@pytest.mark.parametrize("option", OPTIONS, ids=lambda o: o.flag)
def test_import_help_names_the_formats_taking_each_option(option):
    command = typer.main.get_command(app).commands["import"]
    (param,) = [p for p in command.params if option.flag in p.opts]
    assert param.help.startswith(f"{', '.join(s.name for s in taking(option))}: {option.help}")
