"""Every bad input of the catalogue (studies/bad_inputs/cases.py) exits 2 with one ``rigopt: error:`` line
that contains its fragment, and docs/errors.md shows exactly that line; every input it flags (its WARNINGS) exits 0
with one ``rigopt: warning:`` line holding its fragment, shown in the page's second table.

The cases run in-process through ``rigopt.cli.run`` (the console script's ``main`` minus the stdout
diversion, which tests/cli/test_console_script.py checks in real processes); studies/bad_inputs/run.py runs
the same table through the installed console script and rewrites the docs page.
"""

from __future__ import annotations

import errno
import importlib.util
import re
from pathlib import Path

import pytest

from marks import cases
from rigopt.cli import INPUT_ERROR, INTERRUPTED, run

REPO = Path(__file__).resolve().parents[2]
DOC = REPO / "docs" / "errors.md"


def _load_cases():
    spec = importlib.util.spec_from_file_location("bad_input_cases", REPO / "studies" / "bad_inputs" / "cases.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


CASES_MODULE = _load_cases()
CASES = {name: (args, fragment) for name, args, fragment in CASES_MODULE.CASES}
WARNINGS = {name: (args, fragment) for name, args, fragment in CASES_MODULE.WARNINGS}
#: The heading of docs/errors.md's second table, the warnings.
WARNINGS_HEADING = "\n## Warnings: "


def documented(table: str = "errors") -> dict[str, str]:
    """class -> message, from the errors table (or the ``"warnings"`` table) in docs/errors.md."""
    errors, _, warnings = DOC.read_text().partition(WARNINGS_HEADING)
    rows = re.findall(r"^\| (.+?) \| `rigopt .*?` \| `(.*)` \|$", errors if table == "errors" else warnings,
                      flags=re.MULTILINE)
    return dict(rows)


@pytest.fixture(scope="module")
def scratch(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("bad_inputs").resolve()
    env = CASES_MODULE.make_fixtures(tmp)
    return tmp, env


def test_the_catalogue_has_no_duplicate_classes():
    assert len(CASES) == len(CASES_MODULE.CASES)


def test_the_docs_table_lists_every_class():
    assert set(documented()) == set(CASES)
    assert set(documented("warnings")) == set(WARNINGS)
    assert not set(CASES) & set(WARNINGS)


#: The cases that need a design or a coverage report before their error (2-5 s each).
SLOW = {"design --pareto with no feasible point", "design --min-height above every mount point",
        "coverage of a rig that sees only its body", "coverage unknown --compare"}


def run_case(scratch, args, capsys, monkeypatch) -> tuple[int, str, str]:
    """(exit code, stdout, stderr) of ``rigopt ARGS`` run in-process in the scratch folder with its environment."""
    tmp, env = scratch
    for key, value in env.items():
        monkeypatch.setenv(key, value)
    monkeypatch.chdir(tmp)
    capsys.readouterr()
    code = run([a.format(tmp=tmp, repo=REPO) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("name", cases(CASES, SLOW))
def test_bad_input(scratch, name, capsys, monkeypatch):
    tmp = scratch[0]
    fragment = CASES[name][1]
    code, out, err = run_case(scratch, CASES[name][0], capsys, monkeypatch)
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == INPUT_ERROR, err
    assert CASES_MODULE.one_error_line(lines), err  # the error last; before it only indented progress lines
    assert fragment in lines[-1]
    assert out == ""
    shown = lines[-1].replace(str(tmp), "{tmp}").replace(str(REPO), "{repo}").replace("|", "/")
    assert documented()[name] == shown, "docs/errors.md is out of date: python studies/bad_inputs/run.py"


@pytest.mark.parametrize("name", sorted(WARNINGS))
def test_flagged_input(scratch, name, capsys, monkeypatch):
    tmp = scratch[0]
    fragment = WARNINGS[name][1]
    code, _, err = run_case(scratch, WARNINGS[name][0], capsys, monkeypatch)
    warned = [line for line in err.splitlines() if line.startswith("rigopt: warning: ")]
    assert code == 0, err
    assert len(warned) == 1 and fragment in warned[0], err
    shown = warned[0].replace(str(tmp), "{tmp}").replace(str(REPO), "{repo}").replace("|", "/")
    assert documented("warnings")[name] == shown, "docs/errors.md is out of date: python studies/bad_inputs/run.py"


def test_an_interrupt_is_one_line_and_exit_130(monkeypatch, capsys):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("rigopt.metrics.rigv.rigv", interrupted)
    assert run(["rigv", "R1"]) == INTERRUPTED
    assert capsys.readouterr().err.strip() == "rigopt: interrupted"


def test_an_os_error_reaching_the_top_is_one_line(monkeypatch, capsys):
    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", "/somewhere/file")

    monkeypatch.setattr("rigopt.metrics.rigv.rigv", full)
    assert run(["rigv", "R1"]) == INPUT_ERROR
    assert capsys.readouterr().err.strip() == ("rigopt: error: /somewhere/file: no space left on the device; free "
                                               "some space or write elsewhere (--out)")
