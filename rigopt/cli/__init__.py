"""rigopt's command line: thin commands over the library. ``main`` is the console script.

stdout carries only what rigopt itself prints (tables, JSON, "wrote" lines): ``main`` keeps a private
duplicate of file descriptor 1 for Python's ``sys.stdout`` and points descriptor 1 at stderr, so whatever a
C library prints there (HiGHS's "Running HiGHS ..." banner, IPOPT) lands on stderr. Every input error,
including click's usage errors, is one ``rigopt: error: ...`` line on stderr and exit code 2.
"""

from __future__ import annotations

import errno
import os
import sys

from rigopt.cli.app import app
from rigopt.cli import (  # noqa: F401  (importing registers the commands)
    detector_commands, bench_commands, calibrate_command, coverage_command, design_command, metric_commands,
    pack_commands, rig_commands, vehicle_commands,
)
from rigopt.errors import RigoptError

#: Exit code of bad input (as argparse and click use).
INPUT_ERROR = 2
#: Exit code after Ctrl-C (128 + SIGINT).
INTERRUPTED = 130
#: Exit code after SIGTERM (128 + SIGTERM).
TERMINATED = 143


#: Set by the SIGTERM handler (:func:`main` installs it), which raises KeyboardInterrupt so that partial
#: outputs are removed and worker processes ended on the way out, as after Ctrl-C.
_terminated = []


def _terminate(signum, frame) -> None:
    _terminated.append(signum)
    raise KeyboardInterrupt


def _interrupted() -> int:
    """Say how the run was stopped (SIGTERM or Ctrl-C) and, where the command can resume, how (its
    :func:`~rigopt.cli.app.resumable` hint); return its exit code."""
    from rigopt.cli.app import RESUME_HINTS

    how = f"; to resume, {RESUME_HINTS[-1]}" if RESUME_HINTS else ""
    print(f"rigopt: {'terminated' if _terminated else 'interrupted'}{how}", file=sys.stderr)
    return TERMINATED if _terminated else INTERRUPTED


class _CStdoutToStderr:
    """Point file descriptor 1 at stderr while ``sys.stdout`` writes to a private duplicate of it."""

    def __init__(self) -> None:
        self.saved_fd = None
        self.original = sys.stdout

    def __enter__(self) -> "_CStdoutToStderr":
        try:
            sys.stdout.flush()
            saved = os.dup(1)
        except (OSError, ValueError, AttributeError):  # no descriptor 1 (closed, or a fake stream)
            return self
        try:
            os.dup2(2, 1)
        except OSError:  # no descriptor 2: leave everything as it was
            os.close(saved)
            return self
        self.saved_fd = saved
        encoding = getattr(self.original, "encoding", None) or "utf-8"
        errors = getattr(self.original, "errors", None) or "strict"
        line_buffering = bool(getattr(self.original, "line_buffering", False))
        sys.stdout = open(os.dup(saved), "w", buffering=1 if line_buffering else -1, encoding=encoding, errors=errors)
        return self

    def __exit__(self, *exc) -> None:
        if self.saved_fd is None:
            return
        private, sys.stdout = sys.stdout, self.original
        try:
            private.close()  # flushes
        except OSError:  # a closed pipe (rigopt ... | head): the reader has what it wanted
            pass
        os.dup2(self.saved_fd, 1)
        os.close(self.saved_fd)


def _usage_message(error) -> str:
    """A click usage error as one line, with where to read about the command."""
    message = " ".join(error.format_message().split())
    if error.ctx is not None:
        message += f" (see '{error.ctx.command_path} --help')"
    return message


def _os_message(error: OSError) -> str:
    """An operating-system error that reached the top as one line naming the file and the fix."""
    where = f"{error.filename}: " if error.filename else ""
    if error.errno == errno.ENOSPC:
        return f"{where}no space left on the device; free some space or write elsewhere (--out)"
    if error.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        return f"{where}permission denied; choose a place you can write to (--out) or read"
    return f"{where}{error.strerror or error}"


def _error(message: str) -> None:
    """Print ``rigopt: error: message`` as one line on stderr, control characters from the input (a camera name's
    ESC or BEL, a newline) shown escaped (``\\x1b``), never sent to the terminal."""
    safe = "".join(c if c.isprintable() else repr(c)[1:-1] for c in message)
    print(f"rigopt: error: {safe}", file=sys.stderr)


def run(argv: list[str] | None = None) -> int:
    """Run the CLI on ``argv`` (default: the process's arguments) and return the exit code."""
    import importlib

    import typer

    from rigopt.cli.app import RESUME_HINTS

    # click's exceptions, wherever this typer takes click from (click itself, or its own copy)
    click = importlib.import_module(typer.BadParameter.__module__)
    RESUME_HINTS.clear()  # a hint is the running command's (in-process runs follow one another)
    try:
        result = app(args=argv, prog_name="rigopt", standalone_mode=False)
    except RigoptError as error:
        _error(str(error))
        return INPUT_ERROR
    except getattr(click, "NoArgsIsHelpError", ()) as error:  # a command group without a command: its help
        text = error.ctx.get_help()  # typer's rich help prints itself and returns ""
        if text:
            print(text)
        return INPUT_ERROR
    except click.UsageError as error:
        _error(_usage_message(error))
        return INPUT_ERROR
    except click.ClickException as error:
        _error(" ".join(error.format_message().split()))
        return INPUT_ERROR
    except (typer.Abort, KeyboardInterrupt):
        return _interrupted()
    except BrokenPipeError:
        return 0  # the reader of stdout closed it (rigopt ... | head): not an error of rigopt's
    except MemoryError:
        _error("out of memory; ask for less (smaller sizes, fewer items)")
        return INPUT_ERROR
    except OSError as error:
        _error(_os_message(error))
        return INPUT_ERROR
    if result == INTERRUPTED:  # typer turns Ctrl-C inside a command into this exit code
        return _interrupted()
    return result if isinstance(result, int) else 0


def main() -> None:
    """The console script: run the CLI with C-level stdout diverted to stderr, exit with its code.

    SIGTERM is handled as Ctrl-C is (exit 143, "rigopt: terminated"). After either the process ends at once
    (``os._exit``) once its streams are flushed: a native library's
    worker threads (the ray caster's, a solver's) may still be running, and tearing the interpreter down under
    them can abort it ("Fatal Python error: PyThreadState_Get"). Partial outputs are already gone by then
    (``rigopt.output`` removes them as the interrupt passes)."""
    import signal

    signal.signal(signal.SIGTERM, _terminate)
    # the semaphores of worker pools ended by an interrupt are freed by multiprocessing's tracker process, which
    # would warn about each: it takes its warning options from this process's
    sys.warnoptions.append("ignore::UserWarning:multiprocessing.resource_tracker")
    with _CStdoutToStderr():
        code = run()
    if code in (INTERRUPTED, TERMINATED):
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        os._exit(code)
    sys.exit(code)
