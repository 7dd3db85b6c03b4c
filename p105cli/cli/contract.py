"""The contract every p105 subcommand keeps, in one place.

* exit codes (``ExitCode``), and how every failure maps onto them;
* input: a path or ``-``/nothing for stdin, format sniffed, never modified
  (read by :mod:`p105cli.cli.inputs`);
* output: stdout (data only) or ``-o FILE`` written atomically;
* diagnostics on stderr: plain text in pipes and CI, rich on a terminal;
  progress bars only on a terminal;
* a closed pipe ends quietly, Ctrl-C exits 130.

Subcommand modules use these helpers and :mod:`.inputs` and nothing else for I/O.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
from enum import IntEnum

import click

from p105cli.fileio import AtomicWriteError, atomic_file


class ExitCode(IntEnum):
    OK = 0
    FINDINGS = 1        # validation findings, an analysis that did not succeed
    USAGE = 2           # bad command line, or unreadable / malformed input
    INTERNAL = 3        # a bug in p105: the message says so
    BROKEN_PIPE = 141   # the reader of stdout went away (as for a process killed by SIGPIPE)
    INTERRUPTED = 130   # Ctrl-C


EXIT_STATUS_TEXT = """\b
Exit status:
  0    success
  1    findings or non-convergence (validation errors, an analysis that failed)
  2    usage error, or unreadable or malformed input (FILE:LINE:COL or #id named)
  3    internal error (a bug: traceback shown with -v)
  130  interrupted (Ctrl-C)
  141  stdout closed early (e.g. piped into head); nothing is printed"""

#: The epilog of the commands that read mechanisms leniently (part105.model_file: deviations).
READ_LENIENTLY_TEXT = """Files written the way build123d and Open CASCADE write AP242 kinematics
(pairs directly among the mechanism's items, links among the topology's,
explicit values where AP242 derives them, one shared context) are read
anyway, with one warning per departure naming its #id and the rule it
breaks; where an explicit value contradicts AP242, AP242 wins and the
warning says so. validate reports them as errors.

"""


class InputError(click.ClickException):
    """Unreadable or malformed input: exit 2 with the message as given."""

    exit_code = ExitCode.USAGE

    def show(self, file=None) -> None:
        diag("error", self.format_message())


class OutputError(InputError):
    """The output cannot be written (missing directory, no permission): exit 2."""


class PipeClosed(Exception):
    """The reader of stdout went away. (Click turns a raw EPIPE into exit 1; we want 141.)"""


class Settings:
    """Process-wide CLI settings set by the group's options."""

    verbosity = 0  # -1 quiet, 0 normal, >=1 verbose


def stderr_is_terminal() -> bool:
    """Progress and notes for a person: stderr is a terminal, and not in CI."""
    return sys.stderr.isatty() and not os.environ.get("CI")


def diag(level: str, message: str) -> None:
    """Write one diagnostic line to stderr (``level`` is error, warning or note)."""
    if level != "error" and Settings.verbosity < 0:
        return
    if stderr_is_terminal():
        from rich.console import Console
        style = {"error": "bold red", "warning": "yellow", "note": "cyan"}.get(level, "")
        Console(stderr=True, highlight=False).print(f"[{style}]{level}[/]: {message}", markup=True,
                                                    soft_wrap=True)
    else:
        sys.stderr.write(f"p105: {level}: {message}\n")


# ---------------------------------------------------------------- output

def _stdout_text() -> io.TextIOWrapper:
    return io.TextIOWrapper(sys.stdout.buffer, encoding="utf-8", newline="\n",
                            write_through=False, line_buffering=False)


@contextlib.contextmanager
def open_output(path: str | None, inputs: tuple = ()):
    """A text stream for the command's data: stdout, or ``path`` written atomically.

    The file appears only when everything was written; on any failure the
    temporary file is removed and an existing file is left as it was. An
    output that is one of the inputs is refused: input is never modified.
    """
    if path in (None, "-"):
        out = _stdout_text()
        try:
            yield out
            out.flush()
        except BrokenPipeError:
            raise PipeClosed() from None
        finally:
            try:
                out.detach()
            except (BrokenPipeError, ValueError):
                pass
        return
    if os.path.exists(path) and not os.path.isfile(path):
        # /dev/null, /dev/stdout, a FIFO: nothing to replace atomically, write straight through.
        try:
            with open(path, "w", encoding="utf-8", newline="\n") as out:
                yield out
        except OSError as err:
            raise OutputError(f"{path}: cannot write: {err.strerror or err}") from None
        return
    for src in inputs:
        if src not in (None, "-") and os.path.exists(path) and os.path.exists(src) \
                and os.path.samefile(src, path):
            raise click.UsageError(f"output {path} is the input {src}: p105 never overwrites its input")
    try:
        with atomic_file(path) as out:
            yield out
    except AtomicWriteError as err:
        raise OutputError(f"{path}: cannot write: {err.strerror or err}") from None


def copy_to_stdout(data: bytes) -> None:
    """Write ``data`` to stdout completely, by the file descriptor.

    A large BufferedWriter.write to a pipe may return a short count instead of
    raising when the reader goes away; os.write in a loop cannot lose bytes silently.
    """
    sys.stdout.flush()
    fd = sys.stdout.fileno()
    view = memoryview(data)
    try:
        while view:
            view = view[os.write(fd, view[:1 << 20]):]
    except BrokenPipeError:
        raise PipeClosed() from None


class Progress:
    """A rich progress bar on a terminal; nothing at all otherwise."""

    def __init__(self, total: int, description: str):
        self._bar = None
        if stderr_is_terminal() and Settings.verbosity >= 0 and total > 50_000:
            from rich.console import Console
            from rich.progress import Progress as RichProgress
            self._bar = RichProgress(transient=True, console=Console(stderr=True))
            self._task = self._bar.add_task(description, total=total)

    def __enter__(self):
        if self._bar is not None:
            self._bar.start()
        return self

    def advance(self, n: int = 1) -> None:
        if self._bar is not None:
            self._bar.advance(self._task, n)

    def __exit__(self, *exc):
        if self._bar is not None:
            self._bar.stop()


def report_deviations(doc) -> None:
    """Print, once each, the departures from the schema that the lenient model reader read
    anyway (``p105: warning: FILE: #id: ...``; p105cli.part105.model_file)."""
    from p105cli.part105.model_file import take_deviations
    for message in take_deviations(doc):
        diag("warning", f"{getattr(doc, 'source', None) or '<stdin>'}: {message}")


def report_warnings(doc) -> None:
    """Print the reader's warnings and dangling references of ``doc`` on stderr."""
    from p105cli.step.checks import dangling_references
    text = getattr(doc, "text", None)
    warnings = getattr(doc, "warnings", ())
    if text is not None and warnings:
        # Lines counted once for all warnings: a file with a warning on each of
        # its 100 000 lines must not be rescanned from the start for each one.
        where = {}
        line, line_start, at = 1, 0, 0
        for offset in sorted({max(0, min(off, len(text))) for _, off in warnings}):
            line += text.count("\n", at, offset)
            nl = text.rfind("\n", at, offset)
            if nl >= 0:
                line_start = nl + 1
            where[offset] = (line, offset - line_start + 1)
            at = offset
        for message, offset in warnings:
            line, col = where[max(0, min(offset, len(text)))]
            diag("warning", f"{doc.source}:{line}:{col}: {message}")
    dropped = getattr(doc, "warnings_dropped", 0)
    if dropped:
        diag("warning", f"{doc.source}: {dropped} more warnings like these not shown")
    for referrer, missing in dangling_references(doc):
        diag("warning", f"{doc.source}: #{referrer}: reference to #{missing}, which is not in the file")
