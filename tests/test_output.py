"""rigopt.output: folders and files written whole or not at all, output places checked before any work."""

from __future__ import annotations

import errno
import os

import pytest

from rigopt.errors import RigoptError
from rigopt.output import (PARTIAL, atomic_file, atomic_folder, check_out_file, check_out_folder, existing_file,
                           existing_folder, process_running, published, write_text_atomic)


def write_two(folder, fail_after_first=None):
    (folder / "a.txt").write_text("new a")
    if fail_after_first is not None:
        raise fail_after_first
    (folder / "b.txt").write_text("new b")


def previous(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "a.txt").write_text("old a")
    (out / "old_only.txt").write_text("old")
    return out


def test_a_complete_folder_appears_and_nothing_else(tmp_path):
    with atomic_folder(tmp_path / "out") as work:
        write_two(work)
        assert not (tmp_path / "out").exists()  # nothing in place until complete
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["a.txt", "b.txt"]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


@pytest.mark.parametrize("failure", [ValueError("bug"), KeyboardInterrupt(), OSError(errno.ENOSPC, "full")])
def test_a_failure_part_way_leaves_nothing(tmp_path, failure):
    with pytest.raises((ValueError, KeyboardInterrupt, RigoptError)):
        with atomic_folder(tmp_path / "out") as work:
            write_two(work, failure)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("failure", [ValueError("bug"), KeyboardInterrupt(), OSError(errno.ENOSPC, "full")])
def test_a_failure_part_way_keeps_the_previous_output(tmp_path, failure):
    out = previous(tmp_path)
    with pytest.raises((ValueError, KeyboardInterrupt, RigoptError)):
        with atomic_folder(out, force=True) as work:
            write_two(work, failure)
    assert {p.name: p.read_text() for p in out.iterdir()} == {"a.txt": "old a", "old_only.txt": "old"}
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_a_full_disk_names_the_output_and_the_fix(tmp_path):
    with pytest.raises(RigoptError, match="no space left") as caught:
        with atomic_folder(tmp_path / "out") as work:
            write_two(work, OSError(errno.ENOSPC, "No space left on device"))
    assert str(tmp_path / "out") in str(caught.value)


def test_an_existing_folder_is_refused_without_force(tmp_path):
    out = previous(tmp_path)
    with pytest.raises(RigoptError, match="--force"):
        check_out_folder(out)
    with pytest.raises(RigoptError, match="--force"):
        with atomic_folder(out):
            pass


def test_force_replaces_the_folder_whole(tmp_path):
    out = previous(tmp_path)
    with atomic_folder(out, force=True) as work:
        write_two(work)
    assert {p.name: p.read_text() for p in out.iterdir()} == {"a.txt": "new a", "b.txt": "new b"}
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_an_empty_existing_folder_is_used(tmp_path):
    (tmp_path / "out").mkdir()
    with atomic_folder(tmp_path / "out") as work:
        write_two(work)
    assert len(list((tmp_path / "out").iterdir())) == 2


def test_published_names_the_final_paths(tmp_path):
    with atomic_folder(tmp_path / "out") as work:
        write_two(work)
        written = [work / "a.txt", work / "b.txt"]
    assert published(written, work, tmp_path / "out") == [tmp_path / "out" / "a.txt", tmp_path / "out" / "b.txt"]
    assert all(p.is_file() for p in published(written, work, tmp_path / "out"))


def test_resumable_folders_are_kept(tmp_path):
    out = previous(tmp_path)
    assert check_out_folder(out, resume=True) == out


@pytest.mark.parametrize("make, name, message", [
    (lambda tmp: (tmp / "f").write_text("x"), "f", "is a file"),
    (lambda tmp: (tmp / "f").write_text("x"), "f/sub", "is a file, not a folder"),
    (lambda tmp: None, "", "needs a folder name"),
    (lambda tmp: None, ".", "a name of its own"),
])
def test_bad_folders_are_refused(tmp_path, make, name, message):
    make(tmp_path)
    with pytest.raises(RigoptError, match=message):
        check_out_folder(str(tmp_path / name) if name not in ("", ".") else name)


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root may write anywhere")
def test_an_unwritable_place_is_refused(tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        with pytest.raises(RigoptError, match="permission denied"):
            check_out_folder(locked / "out")
        with pytest.raises(RigoptError, match="permission denied"):
            check_out_file(locked / "x.png")
    finally:
        locked.chmod(0o700)


def test_file_suffixes_are_checked(tmp_path):
    with pytest.raises(RigoptError, match=r"\.txt is not a format.*\.png"):
        check_out_file(tmp_path / "x.txt", suffixes=(".png", ".pdf"))
    with pytest.raises(RigoptError, match="no extension"):
        check_out_file(tmp_path / "cov07", suffixes=(".png",))
    assert check_out_file(tmp_path / "x.PNG", suffixes=(".png",)) == tmp_path / "x.PNG"
    (tmp_path / "d.png").mkdir()
    with pytest.raises(RigoptError, match="is a folder"):
        check_out_file(tmp_path / "d.png", suffixes=(".png",))


def test_a_file_keeps_its_extension_while_written_and_replaces_the_old_one(tmp_path):
    target = tmp_path / "x.json"
    target.write_text("old")
    with atomic_file(target) as work:
        assert work.suffix == ".json" and work.parent == tmp_path
        work.write_text("new")
        assert target.read_text() == "old"
    assert target.read_text() == "new"
    assert [p.name for p in tmp_path.iterdir()] == ["x.json"]


@pytest.mark.parametrize("failure", [ValueError("bug"), KeyboardInterrupt(), OSError(errno.ENOSPC, "full")])
def test_a_failed_file_leaves_the_old_one(tmp_path, failure):
    target = tmp_path / "x.json"
    target.write_text("old")
    with pytest.raises((ValueError, KeyboardInterrupt, RigoptError)):
        with atomic_file(target) as work:
            work.write_text("half")
            raise failure
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["x.json"]


def test_a_failed_new_file_leaves_nothing(tmp_path):
    with pytest.raises(ValueError):
        with atomic_file(tmp_path / "x.ply") as work:
            work.write_bytes(b"")
            raise ValueError("the writer failed")
    assert list(tmp_path.iterdir()) == []


def test_write_text_atomic(tmp_path):
    assert write_text_atomic(tmp_path / "a" / "b.txt", "é").read_text(encoding="utf-8") == "é"


# ------------------------------------------------------------------------------------ stale partials, interrupts


def finished_pid() -> int:
    """The id of a process that has run and been reaped: no process has it (until the system reuses it)."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True,
                          check=True)
    pid = int(done.stdout)
    assert not process_running(pid)
    return pid


def test_a_killed_writer_leaves_a_partial_that_the_next_write_sweeps(tmp_path):
    """A real process killed (SIGKILL) inside atomic_folder leaves its partial; the next write removes it."""
    import signal
    import subprocess
    import sys

    out = tmp_path / "out"
    child = subprocess.Popen(
        [sys.executable, "-c", "import sys\nfrom rigopt.output import atomic_folder\n"
         f"with atomic_folder({str(out)!r}) as work:\n    (work / 'a.txt').write_text('half')\n"
         "    print('ready', flush=True)\n    sys.stdin.read()\n"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "ready"
    finally:
        child.send_signal(signal.SIGKILL)
        child.communicate()
    left = [p.name for p in tmp_path.iterdir()]
    assert left == [f".out{PARTIAL}{child.pid}"]  # killed outright: nothing could clean up
    with atomic_folder(out) as work:
        write_two(work)
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
    assert sorted(p.name for p in out.iterdir()) == ["a.txt", "b.txt"]


def test_stale_file_partials_are_swept_and_live_ones_kept(tmp_path):
    import subprocess
    import sys

    dead = finished_pid()
    stale = tmp_path / f".x.json{PARTIAL}{dead}.json"
    stale.write_text("half")
    other_target = tmp_path / f".y.json{PARTIAL}{dead}.json"  # another target's: not this write's to sweep
    other_target.write_text("half")
    live = subprocess.Popen([sys.executable, "-c", "import sys; sys.stdin.read()"], stdin=subprocess.PIPE)
    try:
        running = tmp_path / f".x.json{PARTIAL}{live.pid}.json"
        running.write_text("being written")
        write_text_atomic(tmp_path / "x.json", "whole")
        assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["x.json", other_target.name, running.name])
    finally:
        live.communicate(b"")


def test_a_previous_output_set_aside_by_a_killed_run_is_put_back(tmp_path):
    """Killed between moving the old output aside and moving the new one in: the old one comes back, and a
    write without --force is refused as for any existing output; the half-published new one is removed."""
    dead = finished_pid()
    aside = tmp_path / f".out{PARTIAL}{dead}.old"
    aside.mkdir()
    (aside / "a.txt").write_text("old a")
    new = tmp_path / f".out{PARTIAL}{dead}"
    new.mkdir()
    (new / "a.txt").write_text("new a")
    with pytest.raises(RigoptError, match="--force"):
        with atomic_folder(tmp_path / "out"):
            pass
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
    assert (tmp_path / "out" / "a.txt").read_text() == "old a"


def test_an_interrupt_while_the_new_output_is_moved_in_keeps_the_previous_one(tmp_path, monkeypatch):
    out = previous(tmp_path)
    real_rename = os.rename
    calls = []

    def interrupted_second_rename(source, target):
        calls.append((source, target))
        if len(calls) == 2:  # the old output is aside; moving the new one in is interrupted
            raise KeyboardInterrupt
        real_rename(source, target)

    monkeypatch.setattr("rigopt.output.os.rename", interrupted_second_rename)
    with pytest.raises(KeyboardInterrupt):
        with atomic_folder(out, force=True) as work:
            write_two(work)
    assert {p.name: p.read_text() for p in out.iterdir()} == {"a.txt": "old a", "old_only.txt": "old"}
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_process_running():
    assert process_running(os.getpid())
    assert not process_running(finished_pid())
    assert process_running(0)  # a process group, never taken for a finished process


# ------------------------------------------------------------------------------------ input places


def test_a_folder_given_for_a_file_is_named_as_such(tmp_path):
    (tmp_path / "d").mkdir()
    (tmp_path / "f.txt").write_text("x")
    assert existing_file(tmp_path / "f.txt", "rig file") == tmp_path / "f.txt"
    with pytest.raises(RigoptError, match=r"--in .*d is a folder; give the rig file itself, not a folder; fix$"):
        existing_file(tmp_path / "d", "rig file", "fix", option="--in")
    with pytest.raises(RigoptError, match=r"nothere: no such rig file$"):
        existing_file(tmp_path / "nothere", "rig file")


def test_a_file_given_for_a_folder_is_named_as_such(tmp_path):
    (tmp_path / "d").mkdir()
    (tmp_path / "f.txt").write_text("x")
    assert existing_folder(tmp_path / "d", "rig files") == tmp_path / "d"
    with pytest.raises(RigoptError, match=r"^--rigs .*f\.txt is a file; give the folder holding rig files$"):
        existing_folder(tmp_path / "f.txt", "rig files", option="--rigs")
    with pytest.raises(RigoptError, match=r"nothere: no such folder; give the folder holding rig files; fix$"):
        existing_folder(tmp_path / "nothere", "rig files", "fix")
