"""One fast pass over a DATA section: where each instance is, and what type.

Kinematics commands read a few hundred instances out of files that hold
hundreds of thousands of geometry instances. The index finds every
instance's id, entity type (``None`` for a complex instance) and span
with one regular expression that runs in C, and stores them in compact
arrays; parameters are decoded later, only for the instances asked for
(``lexer.parse_instance_body``).

Anything the fast pattern does not recognise (a comment between ``=``
and the type, a syntax error) is handed to the careful tokenizer for that
one instance, so the index is exact either way and errors come with the
position the tokenizer found.
"""

from __future__ import annotations

import re
from array import array

from .errors import StepStructureError, StepSyntaxError
from .lexer import Tokens

_SKIP = r"(?:[ \t\r\n]++|/\*(?:[^*]++|\*(?!/))*+\*/)*+"
# The body up to the terminating ';', stepping over strings and comments,
# which may contain ';'. Possessive quantifiers: no backtracking, linear time.
# A '/' that opens no closed comment ends the fast match (the careful
# tokenizer then reports the unterminated comment): read as a lone '/',
# every further '/*' would rescan the rest of the text, quadratic time.
_BODY = r"[^;'/]*+(?:(?:'[^']*+'|/\*(?:[^*]++|\*(?!/))*+\*/|/(?!\*))[^;'/]*+)*+"
_INSTANCE = re.compile(
    _SKIP + r"\#([0-9]+)[ \t\r\n]*=[ \t\r\n]*(?:([A-Za-z_!][A-Za-z0-9_]*)|\()" + _BODY + ";"
)
_SKIP_RE = re.compile(_SKIP)
_ENDSEC = re.compile(r"ENDSEC" + _SKIP + ";", re.I)
# Instance names are stored in signed 64-bit arrays.
MAX_INSTANCE_ID = 2**63 - 1


def _instance_id(digits: str, offset: int) -> int:
    """The instance name of ``#digits`` at ``offset``; a syntax error if too large."""
    significant = digits.lstrip("0") or "0"
    if len(significant) <= 19 and int(significant) <= MAX_INSTANCE_ID:
        return int(significant)
    raise StepSyntaxError(f"instance name #{digits[:30]}{'...' if len(digits) > 30 else ''} "
                          f"is too large (at most #{MAX_INSTANCE_ID})", offset)


class InstanceIndex:
    """Ids, entity types and spans of the instances of one file, in file order."""

    __slots__ = ("ids", "starts", "ends", "types", "_slot_of", "_dense")

    def __init__(self):
        self.ids = array("q")
        self.starts = array("q")
        self.ends = array("q")
        self.types: list[str | None] = []
        self._slot_of = None
        self._dense = False

    def __len__(self) -> int:
        return len(self.ids)

    def finish(self) -> None:
        """Build the id -> slot lookup; a repeated id is a structural error."""
        ids = self.ids
        n = len(ids)
        top = max(ids) if n else 0
        if top <= 4 * n + 1024:
            # Ids are nearly always dense: a flat table is both the smallest
            # and the fastest map (8 bytes a slot, no Python objects).
            table = array("q", [-1]) * (top + 1)
            for k, i in enumerate(ids):
                if table[i] >= 0:
                    raise StepStructureError("instance name used more than once", i)
                table[i] = k
            self._slot_of, self._dense = table, True
        else:
            table = {}
            for k, i in enumerate(ids):
                if i in table:
                    raise StepStructureError("instance name used more than once", i)
                table[i] = k
            self._slot_of, self._dense = table, False

    def slot(self, instance_id: int) -> int:
        """Position of instance ``#instance_id`` in file order, or -1."""
        if self._dense:
            table = self._slot_of
            return table[instance_id] if 0 <= instance_id < len(table) else -1
        return self._slot_of.get(instance_id, -1)

    def __contains__(self, instance_id: int) -> bool:
        return self.slot(instance_id) >= 0


def _careful_instance(text: str, pos: int, end: int):
    """Find one instance's extent with the tokenizer; exact errors on bad input."""
    tokens = Tokens(text, pos, end)
    kind, lex, at = tokens.next()
    if kind != "ref":
        shown = "end of input" if kind == "eof" else repr(lex)
        raise StepSyntaxError(f"expected an instance '#n = ...;' or ENDSEC, found {shown}", at)
    start, iid = at, _instance_id(lex[1:], at)
    tokens.expect("=", "'=' after the instance name")
    kind, lex, kat = tokens.next()
    if kind == "keyword":
        etype = lex
        depth = 0
    elif kind == "punct" and lex == "(":
        etype = None
        depth = 1
    else:
        shown = "end of input" if kind == "eof" else repr(lex)
        raise StepSyntaxError(f"expected an entity name or '(' after '=', found {shown}", kat)
    while True:
        kind, lex, at = tokens.next()
        if kind == "eof":
            raise StepSyntaxError(f"instance #{iid} is not terminated by ';'", start)
        if kind == "punct":
            if lex == "(":
                depth += 1
            elif lex == ")":
                depth -= 1
            elif lex == ";" and depth <= 0:
                return iid, etype, start, tokens.pos


def index_data_section(text: str, pos: int, end: int, into: InstanceIndex) -> int:
    """Index instances from ``pos`` up to the section's ``ENDSEC;``.

    Appends to ``into`` and returns the offset just past ``ENDSEC;``.
    """
    ids, starts, ends, types = into.ids, into.starts, into.ends, into.types
    lower: dict = {None: None}
    match = _INSTANCE.match
    while True:
        m = match(text, pos, end)
        if m is not None:
            raw = m.group(2)
            name = lower.get(raw)
            if name is None and raw is not None:
                name = lower[raw] = raw.lower()
            try:
                ids.append(int(m.group(1)))
            except (OverflowError, ValueError):
                ids.append(_instance_id(m.group(1), m.start(1) - 1))  # or a syntax error
            starts.append(m.start(1) - 1)
            ends.append(m.end())
            types.append(name)
            pos = m.end()
            continue
        pos = _SKIP_RE.match(text, pos, end).end()
        e = _ENDSEC.match(text, pos, end)
        if e is not None:
            return e.end()
        if pos >= end:
            raise StepSyntaxError("DATA section is not closed by ENDSEC;", pos)
        if text[pos:pos + 6].upper() == "ENDSEC":  # but not followed by ';'
            Tokens(text, pos + 6, end).expect(";", "';' after ENDSEC")
        iid, etype, s, pos = _careful_instance(text, pos, end)
        ids.append(iid)
        starts.append(s)
        ends.append(pos)
        types.append(None if etype is None else etype.lower())
