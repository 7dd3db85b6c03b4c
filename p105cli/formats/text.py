"""Line-oriented reading shared by the user formats: CSV rows and JSON Lines records with
their LINE:COL, finite numbers, and the one error type that names where."""

from __future__ import annotations

import csv
import io
import json
import math


class FormatError(ValueError):
    """A malformed user file or option value; the message names ``source:line:column``."""


def number(text: str, where: str) -> float:
    """A finite float from a cell; errors name ``where``."""
    try:
        v = float(text)
    except ValueError:
        raise FormatError(f"{where}: {text.strip()!r} is not a number") from None
    if not math.isfinite(v):
        raise FormatError(f"{where}: {text.strip()!r} is not a finite number")
    return v


def csv_rows(text: str):
    """(line number, [(column, cell)]) of the CSV rows that are neither blank nor ``#`` comments."""
    reader = csv.reader(io.StringIO(text))
    out = []
    for row in reader:
        line = reader.line_num
        if not row or all(not c.strip() for c in row) or row[0].lstrip().startswith("#"):
            continue
        cols, col = [], 1
        for cell in row:
            cols.append((col, cell))
            col += len(cell) + 1
        out.append((line, cols))
    return out


def jsonl_records(text: str, source: str, *, comments: bool = True):
    """(line number, record) of the non-blank lines of a JSON Lines text (``#`` comment
    lines skipped if ``comments``); errors at LINE:COL."""
    for n, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s or (comments and s.startswith("#")):
            continue
        try:
            yield n, json.loads(line)
        except json.JSONDecodeError as err:
            raise FormatError(f"{source}:{n}:{err.colno}: {err.msg}") from None
        except RecursionError:  # only the json module's decoder recurses
            raise FormatError(f"{source}:{n}:1: JSON nested too deeply") from None


def is_jsonl(text: str) -> bool:
    """JSON Lines rather than CSV: the first line that is neither blank nor a comment is an object."""
    for line in text.splitlines():
        s = line.strip().lstrip("\ufeff")
        if s and not s.startswith("#"):
            return s.startswith("{")
    return False
