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

from p105cli.fileio import DEVICE_ERRNOS, AtomicWriteError, PendingFile


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
    keep_partial = False  # --keep-partial: -o OUT is written even when the command fails

    @classmethod
    def reset(cls) -> None:
        cls.verbosity, cls.keep_partial = 0, False


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


STDOUT_NAME = "<stdout>"

#: -o outputs written completely and waiting for the command's exit status (see finish_outputs).
_pending: list[PendingFile] = []


def is_write_error(err: BaseException) -> bool:
    """A write refused by the device (a full disk, a quota): exit 2 with the path, not a bug."""
    return isinstance(err, OSError) and err.errno in DEVICE_ERRNOS


def write_error(path: str, err: OSError) -> "OutputError":
    return OutputError(f"{path}: cannot write: {err.strerror or err}")


@contextlib.contextmanager
def open_output(path: str | None, inputs: tuple = (), report: bool = False):
    """A text stream for the command's data: stdout, or ``path`` written atomically.

    ``path`` is replaced only when the command ends with exit status 0 (see
    :func:`finish_outputs`; with --keep-partial, whatever the status): a
    failed run leaves an existing file as it was and writes no new one, so a
    make rule that wants OUT runs again. A ``report`` (validate's) is the
    verdict itself and is written whenever it is complete. An output that is
    one of the inputs is refused: input is never modified.
    """
    if path in (None, "-"):
        out = _stdout_text()
        try:
            yield out
            out.flush()
        except BrokenPipeError:
            raise PipeClosed() from None
        except OSError as err:
            if is_write_error(err):
                raise write_error(STDOUT_NAME, err) from None
            raise
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
        pending = PendingFile(path)
    except AtomicWriteError as err:
        raise OutputError(f"{path}: cannot write: {err.strerror or err}") from None
    try:
        yield pending.file
        pending.finish()
    except BaseException as err:
        if is_write_error(err):
            pending.discard()
            raise write_error(path, err) from None
        if Settings.keep_partial and _finished(pending):
            _pending.append(pending)  # what was written before the failure, as asked
        else:
            pending.discard()
        raise
    if report:
        _commit(pending)
    else:
        _pending.append(pending)


def _finished(pending: PendingFile) -> bool:
    try:
        pending.finish()
        return True
    except OSError:
        return False


def _commit(pending: PendingFile) -> None:
    try:
        pending.commit()
    except OSError as err:
        raise OutputError(f"{pending.path}: cannot write: {err.strerror or err}") from None


def finish_outputs(code: int) -> int:
    """Rename the command's -o outputs into place when it succeeded (or --keep-partial was
    given), remove them otherwise; the exit status after that (2 if one cannot be renamed)."""
    keep = code == ExitCode.OK or Settings.keep_partial
    while _pending:
        pending = _pending.pop(0)
        if not keep:
            pending.discard()
            continue
        try:
            _commit(pending)
        except OutputError as err:
            err.show()
            code = ExitCode.USAGE
            keep = False  # one output missing: the others are not left half a result either
    return code


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
    except OSError as err:
        if is_write_error(err):
            raise write_error(STDOUT_NAME, err) from None
        raise


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
