"""Structural checks that need the whole file: references to missing instances."""

from __future__ import annotations

import bisect
import re

from .lexer import decode_int
from .values import record_refs

# Strings and comments are matched first so that '#12' inside them is not a reference.
_REF_SCAN = re.compile(r"'[^']*'|/\*.*?\*/|#([0-9]+)", re.S)


def _ref_id(digits: str) -> int:
    try:
        return int(digits)
    except ValueError:
        return decode_int(digits, 0)


def dangling_references(doc) -> list[tuple[int, int]]:
    """``(referring instance id, missing id)`` pairs, in file order.

    For an indexed Part 21 file this scans the DATA text once in C; the
    referring instance is looked up only for the (rare) missing ids.
    """
    text = getattr(doc, "text", None)
    if text is None:
        present = {r["id"] for r in doc.data}
        found = []
        for record in doc.data:
            refs = record_refs(record)
            found.extend((record["id"], m) for m in refs if m not in present)
        return found
    index = doc.index
    if not len(index):
        return []
    lo, hi = index.starts[0], index.ends[len(index) - 1]
    try:
        referenced = {int(g) for g in _REF_SCAN.findall(text, lo, hi) if g}
    except ValueError:  # a name with thousands of digits (leading zeros, or an undecoded file)
        referenced = {_ref_id(g) for g in _REF_SCAN.findall(text, lo, hi) if g}
    missing = {i for i in referenced if index.slot(i) < 0}
    if not missing:
        return []
    # One more pass to find who refers to each missing id (one pass per missing
    # id would take quadratic time on a file full of dangling references).
    found = []
    starts, ids = index.starts, index.ids
    for hit in _REF_SCAN.finditer(text, lo, hi):
        g = hit.group(1)
        if g and _ref_id(g) in missing:
            k = bisect.bisect_right(starts, hit.start(1)) - 1
            found.append((ids[k], _ref_id(g)))
    found = list(dict.fromkeys(found))
    # Instances in file order, and each one's missing ids in increasing order.
    found.sort(key=lambda p: (index.slot(p[0]), p[1]))
    return found
