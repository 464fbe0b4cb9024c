"""Commands that write folders or files leave either nothing or the previous complete output when a writer
fails part-way (a full disk, a bug, Ctrl-C), and refuse an existing output folder without --force. The cases
that write a whole coverage report run with ``-m slow``."""

from __future__ import annotations

import errno
from pathlib import Path

import pytest
from typer.testing import CliRunner

from rigopt.cli.app import app
from rigopt.errors import RigoptError

REPO = Path(__file__).resolve().parents[2]
SHIPPED_CSV = REPO / "metrics" / "pccr_transfer.csv"

runner = CliRunner()


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


def snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def fail_with(error):
    def writer(*args, **kwargs):
        raise error
    return writer


@pytest.fixture(scope="module")
def r1_report():
    """R1's coverage report, computed once: the tests are about writing it, not about computing it."""
    from rigopt.coverage.measures import coverage_report
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.library import load_vehicle

    rig = load_rig("R1")
    return coverage_report(rig, load_vehicle(rig.vehicle))


@pytest.fixture
def known_report(r1_report, monkeypatch):
    monkeypatch.setattr("rigopt.coverage.measures.coverage_report", lambda rig, vehicle, settings=None: r1_report)


@pytest.fixture(scope="module")
def coverage_out(tmp_path_factory, r1_report):
    """A complete ``rigopt coverage R1 --out`` folder (made once; tests copy it)."""
    out = tmp_path_factory.mktemp("coverage") / "out"
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr("rigopt.coverage.measures.coverage_report", lambda rig, vehicle, settings=None: r1_report)
        result = invoke("coverage", "R1", "--out", out)
    assert result.exit_code == 0, result.output
    return out


@pytest.fixture
def previous_coverage(coverage_out, tmp_path, known_report):
    import shutil

    out = tmp_path / "out"
    shutil.copytree(coverage_out, out)
    return out


@pytest.mark.slow
def test_an_existing_folder_is_refused_without_force(previous_coverage):
    before = snapshot(previous_coverage)
    result = invoke("coverage", "R1", "--out", previous_coverage)
    assert isinstance(result.exception, RigoptError) and "--force" in str(result.exception)
    assert snapshot(previous_coverage) == before


@pytest.mark.slow
@pytest.mark.parametrize("error", [OSError(errno.ENOSPC, "No space left on device"), RuntimeError("a bug"),
                                   KeyboardInterrupt()])
def test_a_failing_writer_keeps_the_previous_output(previous_coverage, monkeypatch, error):
    before = snapshot(previous_coverage)
    monkeypatch.setattr("rigopt.report.coverage_html.write_blind_figure", fail_with(error))
    result = invoke("coverage", "R1", "--out", previous_coverage, "--force")
    assert result.exit_code != 0
    assert snapshot(previous_coverage) == before
    assert [p.name for p in previous_coverage.parent.iterdir()] == ["out"]  # no temporary sibling left


@pytest.mark.slow
def test_a_failing_writer_leaves_no_folder(tmp_path, monkeypatch, known_report):
    monkeypatch.setattr("rigopt.report.coverage_html.write_html_report",
                        fail_with(OSError(errno.ENOSPC, "No space left on device")))
    result = invoke("coverage", "R1", "--out", tmp_path / "new")
    assert isinstance(result.exception, RigoptError)
    assert "no space left" in str(result.exception) and str(tmp_path / "new") in str(result.exception)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_force_replaces_the_folder_whole(previous_coverage):
    (previous_coverage / "stale.txt").write_text("from an older run")
    result = invoke("coverage", "R1", "--out", previous_coverage, "--force")
    assert result.exit_code == 0, result.output
    assert not (previous_coverage / "stale.txt").exists()
    assert (previous_coverage / "report.html").is_file()


def test_calibrate_failing_part_way_leaves_no_folder(tmp_path, monkeypatch):
    monkeypatch.setattr("rigopt.report.calibration_figures.write_calibration_figures",
                        fail_with(OSError(errno.ENOSPC, "No space left on device")))
    result = invoke("calibrate", "--results", SHIPPED_CSV, "--bootstrap", "2", "--out", tmp_path / "cal")
    assert isinstance(result.exception, RigoptError)
    assert list(tmp_path.iterdir()) == []


def test_vehicle_export_failing_leaves_no_file(tmp_path, monkeypatch):
    import trimesh

    monkeypatch.setattr(trimesh.Trimesh, "export", fail_with(OSError(errno.ENOSPC, "No space left on device")))
    result = invoke("vehicle", "export", "tt", "--out", tmp_path / "tt.ply")
    assert isinstance(result.exception, RigoptError)
    assert list(tmp_path.iterdir()) == []


def test_vehicle_export_of_an_unknown_format_leaves_no_file(tmp_path):
    result = invoke("vehicle", "export", "tt", "--out", tmp_path / "tt.xyz")
    assert isinstance(result.exception, RigoptError) and ".ply" in str(result.exception)
    assert list(tmp_path.iterdir()) == []
