"""Outputs written whole or not at all, and output places checked before any work.

A folder is written into a temporary sibling (``.<name>.partial-<pid>``) and renamed into place once
complete; a file into a temporary sibling with the same extension, then ``os.replace``-d over the target.
A failure or an interrupt (``KeyboardInterrupt`` too) removes the temporary sibling, so the target holds
either nothing or its previous complete content. An existing non-empty output folder is refused unless
``force`` is given; it is then replaced whole (the old folder is removed only after the new one is in place),
never mixed with new files. A process killed outright (SIGKILL, power loss) cannot clean up: its temporary
siblings are swept by the next atomic write of the same target, once no running process has the process id in
their name (a previous output set aside while being replaced is put back first when the target is missing).

Input places are checked here too (:func:`existing_file`, :func:`existing_folder`): a folder where a file is
expected, or a file where a folder is, is named as such, never as a missing file.

Every problem is a :class:`~rigopt.errors.RigoptError` that names the place and the option it came from.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import shutil
import tempfile
from pathlib import Path
from typing import Iterator, Sequence

from rigopt.errors import RigoptError

#: Prefix of the temporary siblings; hidden so that a listing of the parent does not show work in progress.
PARTIAL = ".partial-"


def _label(path, option: str | None) -> str:
    """How a message names a place: ``--rigs PATH`` for an option's value, else the path alone."""
    return f"{option} {path}" if option else str(path)


def existing_file(path, what: str, fix: str = "", *, option: str | None = None,
                  kind: type[RigoptError] = RigoptError) -> Path:
    """``path`` as a Path when it is an existing file (or a link to one); otherwise a ``kind`` error naming
    ``option`` (when given) and the path: "no such WHAT", or "is a folder; give the WHAT itself".

    what : the file expected, e.g. "URDF file"; fix : how to get one, appended after "; ".
    """
    path = Path(path)
    if path.is_file():
        return path
    tail = f"; {fix}" if fix else ""
    if path.is_dir():
        raise kind(f"{_label(path, option)} is a folder; give the {what} itself, not a folder{tail}")
    raise kind(f"{_label(path, option)}: no such {what}{tail}")


def existing_folder(path, holding: str, fix: str = "", *, option: str | None = None,
                    kind: type[RigoptError] = RigoptError) -> Path:
    """``path`` as a Path when it is an existing folder (or a link to one); otherwise a ``kind`` error naming
    ``option`` (when given) and the path: "no such folder", or "is a file; give the folder holding HOLDING".

    holding : what the folder holds, e.g. "sensor.json and calibrated_sensor.json"; fix : appended after "; ".
    """
    path = Path(path)
    if path.is_dir():
        return path
    tail = f"; {fix}" if fix else ""
    if path.exists():
        raise kind(f"{_label(path, option)} is a file; give the folder holding {holding}{tail}")
    raise kind(f"{_label(path, option)}: no such folder; give the folder holding {holding}{tail}")


def _io_problem(error: OSError) -> str:
    """An OSError as a short reason and what to do about it."""
    if error.errno == errno.ENOSPC:
        return "no space left on the device; free some space or write elsewhere"
    if error.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        return "permission denied; choose a place you can write to"
    if error.errno == errno.ENAMETOOLONG:
        return "the name is too long; choose a shorter one"
    return error.strerror or str(error)


def _writable_parent(path: Path, option: str) -> None:
    """The nearest existing ancestor of ``path`` must be a folder this process can write into."""
    parent = path.parent
    while not parent.exists():
        if parent.is_symlink():  # a dangling link
            raise RigoptError(f"{option} {path}: {parent} is a broken link; choose another place")
        parent = parent.parent
    if not parent.is_dir():
        raise RigoptError(f"{option} {path}: {parent} is a file, not a folder; choose a place inside a folder")
    try:  # a real attempt: permissions, read-only and special file systems (/proc), even for root
        probe = tempfile.mkdtemp(prefix=".rigopt-probe-", dir=parent)
    except OSError as error:
        raise RigoptError(f"{option} {path}: cannot write in {parent} ({_io_problem(error)})") from None
    os.rmdir(probe)


def check_out_folder(path, *, force: bool = False, resume: bool = False, option: str = "--out") -> Path:
    """Check, before any work, that ``path`` can become an output folder; returns it as a Path.

    Refused: an empty name, an existing file, a non-empty folder without ``force`` (or ``resume``: a
    resumable output that is added to), a place under a file or where this process cannot write.
    """
    if not str(path).strip():
        raise RigoptError(f"{option} needs a folder name, got an empty string")
    path = Path(path)
    if not resume and path.name in ("", ".", ".."):
        raise RigoptError(f"{option} {path}: give the output folder a name of its own (it is replaced whole)")
    if path.exists() and not path.is_dir():
        raise RigoptError(f"{option} {path} is a file; give the name of a folder to write (a new one, or an existing "
                          "one with --force)")
    if path.is_dir() and not (force or resume) and any(path.iterdir()):
        raise RigoptError(f"{option} {path}: the folder exists and is not empty; add --force to replace it whole, "
                          f"or choose another {option}")
    _writable_parent(path, option)
    if path.is_dir() and not os.access(path if resume else path.parent, os.W_OK | os.X_OK):
        raise RigoptError(f"{option} {path}: cannot write there (permission denied); choose another place")
    return path


def check_out_file(path, *, suffixes: Sequence[str] | None = None, option: str = "--out") -> Path:
    """Check, before any work, that ``path`` can be written as an output file (an existing file is replaced).

    ``suffixes`` (lower case, with the dot) are the extensions the writer understands; anything else is
    refused with the list.
    """
    if not str(path).strip():
        raise RigoptError(f"{option} needs a file name, got an empty string")
    path = Path(path)
    if suffixes is not None and path.suffix.lower() not in suffixes:
        shown = path.suffix or "no extension"
        raise RigoptError(f"{option} {path}: {shown} is not a format this writes; use {', '.join(suffixes)}")
    if path.is_dir():
        example = path / f"NAME{suffixes[0]}" if suffixes else path / "NAME"
        raise RigoptError(f"{option} {path} is a folder; give the name of the file to write, e.g. {example}")
    _writable_parent(path, option)
    return path


def _temporary_sibling(path: Path, suffix: str = "") -> Path:
    return path.parent / f".{path.name}{PARTIAL}{os.getpid()}{suffix}"


def process_running(pid: int) -> bool:
    """True when a process with id ``pid`` (> 0) exists, this one included (signal 0 probes without sending)."""
    if pid <= 0:
        return True  # 0 and negative ids name process groups: never taken for a finished process
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # PermissionError: it runs as another user
        return True
    return True


def sweep_stale_partials(path) -> list[Path]:
    """Remove the temporary siblings of ``path`` (``.<name>.partial-<pid>`` with its suffix, or ``.old``) left
    by processes that no longer run; returns what was removed or put back.

    A ``.old`` sibling is the previous complete output, set aside while a new one was being moved in: when
    ``path`` is missing (the process died between the two renames) it is put back in place of ``path``.
    A partial whose process id was taken again by a running process is kept (it cannot be told apart).
    """
    path = Path(path)
    if path.name in ("", ".", ".."):
        return []
    try:
        siblings = list(path.parent.iterdir())
    except OSError:
        return []
    pattern = re.compile(re.escape(f".{path.name}{PARTIAL}") + r"(\d+)(.*)")
    swept = []
    for sibling in sorted(siblings, key=lambda p: p.name.endswith(".old"), reverse=True):  # .old first
        match = pattern.fullmatch(sibling.name)
        if match is None or match.group(2) not in ("", ".old", path.suffix) or process_running(int(match.group(1))):
            continue
        if match.group(2) == ".old" and not path.exists() and not path.is_symlink():
            with contextlib.suppress(OSError):
                os.rename(sibling, path)
                swept.append(sibling)
                continue
        _remove(sibling)
        swept.append(sibling)
    return swept


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(OSError):
            path.unlink()


@contextlib.contextmanager
def atomic_folder(path, *, force: bool = False, option: str = "--out") -> Iterator[Path]:
    """Yield an empty temporary sibling of ``path`` to write into; rename it to ``path`` when the block ends.

    On an exception (any, KeyboardInterrupt included) the temporary folder is removed and ``path`` is left as
    it was. An OSError while writing becomes a RigoptError naming ``path``. Temporary siblings of ``path`` left by
    killed processes are swept first (:func:`sweep_stale_partials`).
    """
    if str(path).strip():
        sweep_stale_partials(path)
    path = check_out_folder(path, force=force, option=option)
    work = _temporary_sibling(path)
    try:
        _remove(work)  # a leftover of an earlier run killed with this process id
        work.mkdir(parents=True)
    except OSError as error:
        raise RigoptError(f"{option} {path}: cannot create the folder ({_io_problem(error)})") from None
    with _published_or_removed(work, path, option, "the output", _publish_folder):
        yield work


@contextlib.contextmanager
def _published_or_removed(work: Path, path: Path, option: str, what: str, publish) -> Iterator[None]:
    """Around writing into ``work``: ``publish(work, path)`` when the block ends; on any exception ``work`` is
    removed, and an OSError becomes a RigoptError naming ``path`` (``what`` could not be written)."""
    try:
        yield
        publish(work, path)
    except OSError as error:
        _remove(work)
        raise RigoptError(f"{option} {path}: cannot write {what} ({_io_problem(error)}); nothing was changed "
                          "there") from None
    except BaseException:
        _remove(work)
        raise


def _publish_folder(work: Path, path: Path) -> None:
    """Put the complete folder ``work`` in the place of ``path`` (which may exist: it is replaced whole)."""
    if not path.exists():
        os.rename(work, path)
        return
    old = _temporary_sibling(path, ".old")
    _remove(old)
    os.rename(path, old)
    try:
        os.rename(work, path)
    except BaseException:
        os.rename(old, path)  # put the previous output back
        raise
    _remove(old)


@contextlib.contextmanager
def atomic_file(path, *, option: str = "--out") -> Iterator[Path]:
    """Yield a temporary sibling of the file ``path`` (same extension, so format-by-extension writers work);
    it replaces ``path`` when the block ends. On an exception it is removed and ``path`` is left as it was.
    Temporary siblings of ``path`` left by killed processes are swept first (:func:`sweep_stale_partials`)."""
    path = Path(path)
    sweep_stale_partials(path)
    work = _temporary_sibling(path, path.suffix)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise RigoptError(f"{option} {path}: cannot create its folder ({_io_problem(error)})") from None
    with _published_or_removed(work, path, option, "the file", os.replace):
        yield work


def write_text_atomic(path, text: str, *, option: str = "--out") -> Path:
    """Write ``text`` (UTF-8) to ``path`` whole or not at all; returns ``path``."""
    path = Path(path)
    with atomic_file(path, option=option) as work:
        work.write_text(text, encoding="utf-8")
    return path


def published(paths: Sequence[Path], work: Path, path: Path) -> list[Path]:
    """``paths`` written under the temporary folder ``work`` as they are named once it became ``path``."""
    return [Path(path) / Path(p).relative_to(work) for p in paths]
