"""THE way every subcommand reads an input.

* ``FILE`` or ``-``/nothing for stdin; the bytes are read once and never modified;
* the name reported for stdin is ``<stdin>`` (also when a model has lost its
  source: ``<input>`` is only the step package's "not known yet" marker);
* text: UTF-8, else ISO 8859-1 (Part 21's older writers), as ``step.decode_bytes``;
* a JSON text nested deeper than Python's json decoder can go is malformed input
  naming its file (exit 2), whichever command reads it: the decoder is the only
  recursive reader (Part 21 and the model checks are iterative), and it is reached
  from several places (the model reader's stream sniffing, the DH table sniffing).
"""

from __future__ import annotations

import contextlib
import sys

from .contract import InputError

#: The name of standard input in diagnostics.
STDIN = "<stdin>"
#: What step's errors and documents say before they know their file.
_UNKNOWN = "<input>"

TOO_DEEP = "JSON nested too deeply"


def is_stdin(path) -> bool:
    return path in (None, "-")


def read_input_bytes(path: str | None) -> tuple[bytes, str]:
    """The bytes of ``path`` (``-`` or None: stdin) and the name to report."""
    if is_stdin(path):
        return sys.stdin.buffer.read(), STDIN
    try:
        with open(path, "rb") as fh:
            return fh.read(), path
    except OSError as err:
        raise InputError(f"{path}: cannot read: {err.strerror or err}") from None


def decode(raw: bytes) -> str:
    """Text of an input: UTF-8 (a BOM dropped), else ISO 8859-1; never fails."""
    from p105cli.step import decode_bytes
    return decode_bytes(raw)


def read_text(path: str | None) -> tuple[str, str]:
    """``(text, source name)`` of an input (model, values, poses, DH table)."""
    raw, source = read_input_bytes(path)
    return decode(raw), source


def source_of(doc) -> str:
    """The name a document's diagnostics give: its source, else ``<stdin>``."""
    source = getattr(doc, "source", None)
    return source if source and source != _UNKNOWN else STDIN


@contextlib.contextmanager
def nesting_guard(source: str):
    """Inside: a RecursionError is the input's JSON nested too deeply, a ModelError
    naming ``source`` (exit 2), never an internal error."""
    try:
        yield
    except RecursionError:
        from p105cli.step import ModelError
        err = ModelError(TOO_DEEP)
        err.source = source
        raise err from None


def parse_document(text: str, source: str, *, decodes_all: bool = False):
    """A Part 21 or p105/1 JSON model from text (sniffed); StepError on bad input.

    Every instance of a Part 21 file is decoded once here, so that a syntax error anywhere
    in the file is reported as FILE:LINE:COL (exit 2) by every command, before any analysis;
    the records are kept, and the analysis reads them without decoding again
    (``StepFile.check``). ``decodes_all``: the caller decodes every instance in file order
    itself (``parse``, ``validate``) and reports the same error."""
    from p105cli.step import StepFile, read_any
    with nesting_guard(source):
        doc = read_any(text, source)
        if not decodes_all and isinstance(doc, StepFile):
            doc.check(keep=True)
    return doc


def load_document(path: str | None, *, decodes_all: bool = False):
    """Read a model from a Part 21 or JSON input (sniffed); StepError on bad input
    (a syntax error in any instance too, see :func:`parse_document`)."""
    text, source = read_text(path)
    return parse_document(text, source, decodes_all=decodes_all)


@contextlib.contextmanager
def naming_source(doc):
    """Errors found in a model while analysing it name its file: a ModelError raised
    deep in the science knows the ``#id`` but not where the model came from. An
    unknown FILE_SCHEMA is a usage error naming the file too."""
    from p105cli.schema.profiles import UnknownSchemaError
    from p105cli.step.errors import StepError

    source = source_of(doc)
    try:
        with nesting_guard(source):
            yield
    except StepError as err:
        if err.source in (None, _UNKNOWN):
            err.source = source
        raise
    except UnknownSchemaError as err:
        raise InputError(f"{source}: {err}") from None
