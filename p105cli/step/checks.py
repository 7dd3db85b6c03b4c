"""Structural checks that need the whole file: references to missing instances."""

from __future__ import annotations

import bisect
import re

# Strings and comments are matched first so that '#12' inside them is not a reference.
_REF_SCAN = re.compile(r"'[^']*'|/\*.*?\*/|#([0-9]+)", re.S)


def _refs_in_value(value, out: list) -> None:
    stack = [value]
    while stack:
        v = stack.pop()
        t = type(v)
        if t is list:
            stack.extend(v)
        elif t is dict:
            if "ref" in v:
                out.append(v["ref"])
            elif "value" in v:
                stack.append(v["value"])


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
            refs: list = []
            for part in record.get("complex", [record]):
                _refs_in_value(part["args"], refs)
            found.extend((record["id"], m) for m in refs if m not in present)
        return found
    index = doc.index
    if not len(index):
        return []
    lo, hi = index.starts[0], index.ends[len(index) - 1]
    referenced = {int(g) for g in _REF_SCAN.findall(text, lo, hi) if g}
    missing = sorted(i for i in referenced if index.slot(i) < 0)
    if not missing:
        return []
    found = []
    starts = index.starts
    for m in missing:
        for hit in re.finditer(rf"'[^']*'|/\*.*?\*/|(#{m})(?![0-9])", text[lo:hi], re.S):
            if hit.group(1):
                k = bisect.bisect_right(starts, lo + hit.start(1)) - 1
                found.append((index.ids[k], m))
    found = list(dict.fromkeys(found))
    found.sort(key=lambda p: index.slot(p[0]))
    return found
