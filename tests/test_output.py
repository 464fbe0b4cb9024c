"""rigopt.output: folders and files written whole or not at all, output places checked before any work."""

from __future__ import annotations

import errno
import os

import pytest

from rigopt.errors import RigoptError
from rigopt.output import atomic_file, atomic_folder, check_out_file, check_out_folder, published, write_text_atomic


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
