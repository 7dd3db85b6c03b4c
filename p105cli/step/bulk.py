"""Decoding every instance of a file at once (full ``parse``, ``export``).

The careful tokenizer (``lexer.parse_instance_body``) spends microseconds
of Python per token. For whole files this module turns the text of many
instances at once into JSON text with operations that run in C
(``re.split``/``subn`` with literal replacements, ``str.replace``,
``str.translate``, joins) and lets ``json`` build the values. The records
are identical to the careful path's: same values, same int / float types,
-0.0 kept, same warnings.

A run of instances ``#id = NAME(...);`` and ``#id = (A(...) B(...));`` (at
most CHUNK, never across two DATA sections; comments between instances
blanked out) becomes JSON:

1. string literals are split out (one regular expression) and a
   placeholder put in their place; bodies without backslash, quote or line
   break go back verbatim as JSON strings, the others are decoded by
   ``lexer.decode_string`` (with the same offsets, hence the same warnings
   and errors) and re-encoded;
2. enumerations ``.NAME.`` are split out the same way, and so are the part
   names of complex instances (``#id = (A(`` and ``) B(``, where nothing
   else may follow a ``)``): a complex instance becomes the flat list
   ``["a", [...], "b", [...]]``, and a record only if its elements at that
   level are exactly its part names and argument lists;
3. each instance head (the ``;`` ending the previous instance, then
   ``#id = NAME (``) becomes one placeholder; ids and types come from the
   index;
4. the code left may hold only numbers, references, ``$``, ``*``,
   punctuation, white space and the placeholders. The parentheses of each
   instance must balance within the instance (checked on the parentheses
   alone by deleting ``()`` pairs, which also measures the nesting depth),
   so the JSON parser sees exactly one list per instance, and numbers must
   be of a form on which Part 21 and JSON agree;
5. then ``#12`` -> ``{"ref":12}``, ``5.`` -> ``5.0``, ``+5`` -> ``5``,
   ``$`` -> ``null``, ``*`` -> ``{"derived":true}``, ``()`` -> ``[]``, the
   enumerations and strings go back in, and ``json`` decodes the lot.

Anything outside that subset goes to the careful path
(``StepFile._decode_careful``), instance by instance and in file order:
typed parameters, comments inside an instance,
binaries, user-defined entity names, positive exponents of 100 or more,
mantissas of 200 digits or more, nesting of MAX_NESTING - 10 or more,
strings the careful path refuses, and instances whose JSON the parser
refuses (leading zeros, syntax errors, ...). Each check names the
instances concerned, so only those go careful and the rest of the run is
tried again; a run that fails without naming any is halved. So malformed
input raises exactly the careful path's error (message, offset, line and
column), after exactly the same records.
"""

from __future__ import annotations

import gc
import json
import re
from json.encoder import encode_basestring_ascii

from .errors import StepError
from .lexer import MAX_NESTING, decode_string

# Instances decoded per batch: bounds memory (a few times the batch's text)
# and lets records stream out.
CHUNK = 5_000
# A run the JSON parser refuses is halved until it is this small; then its
# instances go to the careful path.
_SMALL = 8
# Runs nested this deep or more go to the careful path, which knows the limit.
_DEPTH_LIMIT = MAX_NESTING - 10

_STRING = re.compile(r"'([^']*(?:''[^']*)*)'")  # the lexer's string token
# String bodies that cannot be copied into JSON as they are ('' is a quote,
# line breaks are dropped, backslashes start escapes, " needs escaping).
_SLOW_BODY = re.compile(r"[\\'\"\r\n]")
_SURROGATE = re.compile("[\ud800-\udfff]")
_ENUM = re.compile(r"\.([A-Za-z_][A-Za-z0-9_]*)\.")
# Instance heads, each with the ';' that ends the previous instance (the code
# of a run gets a ';' in front so that the first head has one too).
_HEAD = re.compile(r";[ \t\r\n]*+#[0-9]++[ \t\r\n]*+=[ \t\r\n]*+[A-Za-z_][A-Za-z0-9_]*+[ \t\r\n]*+\(")
# A complex instance's head with its first part's name, or a later part's name after the
# ')' that closes the part before it (where nothing else can follow a ')' in valid code).
_PART = re.compile(r"(;[ \t\r\n]*+#[0-9]++[ \t\r\n]*+=[ \t\r\n]*+\(|\))[ \t\r\n]*+"
                   r"([A-Za-z_][A-Za-z0-9_]*+)[ \t\r\n]*+\(")
# Placeholders in the code text: strings, enumerations, heads (after a ';'), part names.
_PH_STRING, _PH_ENUM, _PH_HEAD, _PH_PART = "'", "@", "\x01", "\x02"
_HEAD_REPL = ";" + _PH_HEAD + "("
# A complex instance is a flat list: part name, part arguments, part name, ...
_COMPLEX_HEAD_REPL = ";" + _PH_HEAD + "(" + _PH_PART + ",("
_NEXT_PART_REPL = ")," + _PH_PART + ",("
# Once the placeholders are in, nothing else may be left.
_BAD_CHAR = re.compile(r"[^0-9eE.+\-#,();$*'@\x01\x02 \t\r\n]")
_PLACEHOLDERS = re.compile("[@\x01\x02]")
# Number checks, with literal prefixes so that the searches run fast. On the
# reversed code: an exponent whose mantissa has no point (``1E5`` is an int
# then a keyword for Part 21, a float for JSON), and a real with 200 digits
# or more before its point (it may overflow). On the code: a positive
# exponent of 100 or more (idem); smaller ones cannot overflow with such
# mantissas, and negative ones give the same float (or 0.0) either way.
_REV_EXP_NO_POINT = {"E": re.compile(r"E[0-9]*+(?!\.)"), "e": re.compile(r"e[0-9]*+(?!\.)")}
_REV_LONG_MANTISSA = re.compile(r"\.[0-9]{200}")
_BIG_EXPONENT = {"E": re.compile(r"E\+?+0*+[1-9][0-9][0-9]"), "e": re.compile(r"e\+?+0*+[1-9][0-9][0-9]")}
# A '+' that is not an exponent's is a leading sign, which JSON does not have.
# It is dropped once sure that punctuation or white space comes before it and
# a digit after it (so that no two tokens can merge).
_PLUS_BAD = re.compile(r"\+(?:(?<![(,\x01 \t\r\neE]\+)|(?<![eE]\+)(?![0-9]))")
_PLUS_SIGN = re.compile(r"\+(?<![eE]\+)")
_DOT = re.compile(r"\.(?![0-9])")  # '5.' -> '5.0' (enumerations are out by then)
_REF = re.compile(r"(#)([0-9]+)()")  # split into '#', digits, '' around each reference
# The parentheses and instance ends alone (a head opens the instance's list).
_PARENS = str.maketrans({c: None for c in range(128) if chr(c) not in "();"})
# To JSON. Each head becomes ',\r[': a carriage return is JSON white space and
# marks where each instance starts, as nothing else in the JSON text is one
# (in code it becomes a space, and string bodies holding one are escaped).
_FINAL = str.maketrans({"(": "[", ")": "]", ";": ",", "\r": " ", _PH_HEAD: "\r"})
_MARK = "\r"
_DECODER = json.JSONDecoder(strict=False)  # control characters in strings are data


class _Fail(Exception):
    """The fast path cannot take this run; ``blame`` lists suspect slots (relative)."""

    def __init__(self, blame=None):
        super().__init__()
        self.blame = blame


class _EnumJson(dict):
    """Enumeration name -> its JSON text (there are few distinct names)."""

    def __missing__(self, name):
        if len(self) > 10_000:  # a hostile file must not grow it without end
            self.clear()
        value = self[name] = '{"enum":"' + name.upper() + '"}'
        return value


_ENUM_JSON = _EnumJson()


def decode_all(step_file, warn=None):
    """Yield every instance record of ``step_file`` in file order; its warnings go to ``warn``
    (message, offset), by default the file's own list."""
    if warn is None:
        warn = step_file._warn
    end = 0
    for section in step_file.sections:  # no chunk spans two DATA sections
        begin, end = end, end + section.count
        for a in range(begin, end, CHUNK):
            out: list = []
            try:
                _decode_range(step_file, a, min(a + CHUNK, end), out, warn)
            except Exception:
                # The careful path's error, after every record before it.
                yield from out
                raise
            yield from out


def _decode_range(sf, a: int, b: int, out: list, warn) -> None:
    """Append the records of slots a..b-1."""
    _decode_run(sf, a, b, out, warn)


def _decode_run(sf, a: int, b: int, out: list, warn) -> None:
    """Append the records of slots a..b-1.

    A run the fast path refuses is split around the instances it blames
    (those go careful) or, when it cannot tell, halved; the parts are tried
    again, in file order. A work stack rather than recursion: no input can
    take this anywhere near the interpreter's recursion limit.
    """
    todo = [(a, b)]  # (first, end) fast, or (slot, None) careful; last one next
    while todo:
        a, b = todo.pop()
        if b is None:
            out.append(sf._decode_careful(a, warn))
            continue
        if a >= b:
            continue
        try:
            out += _fast(sf, a, b, warn)
            continue
        except _Fail as fail:
            blamed = sorted({a + rel for rel in fail.blame or () if 0 <= rel < b - a})
        except (ValueError, TypeError, KeyError, IndexError, RecursionError, StepError):
            blamed = []
        if blamed:
            parts = []
            k = a
            for slot in blamed:
                parts += [(k, slot), (slot, None)]
                k = slot + 1
            parts.append((k, b))
        elif b - a <= _SMALL:
            parts = [(k, None) for k in range(a, b)]
        else:
            mid = (a + b) // 2
            parts = [(a, mid), (mid, b)]
        todo += reversed(parts)


def _blame(code: str, positions) -> _Fail:
    """The instances holding the given (sorted) offsets of ``code``.

    Instance k (from 0) of the run is the text after the (k+1)-th ';'.
    """
    slots: list[int] = []
    seen = 0
    last = 0
    for p in positions:
        seen += code.count(";", last, p)
        last = p
        slot = max(seen - 1, 0)
        if not slots or slots[-1] != slot:
            slots.append(slot)
    return _Fail(slots)


def _fast(sf, a: int, b: int, warn) -> list:
    """The records of slots a..b-1, or _Fail (or the JSON parser's ValueError)."""
    idx = sf.index
    n = b - a
    start = idx.starts[a]
    text = sf.text[start:idx.ends[b - 1]]
    if "/*" in text:
        text = _blank_gaps(text, idx, a, b)
    pieces = _STRING.split(";" + text)
    del text
    bodies = pieces[1::2]
    code = _PH_STRING.join(pieces[0::2])
    if code.count(_PH_STRING) != len(bodies):
        raise _Fail()
    slow, warnings = _slow_strings(pieces, bodies, start - 1)
    if type(slow) is int:
        # A string the careful path refuses or that must not go through json
        raise _Fail([sum(p.count(";") for p in pieces[0:slow:2]) - 1])

    # The other placeholders must be new to the code (neither is Part 21).
    if _PH_ENUM in code or _PH_HEAD in code or _PH_PART in code:
        raise _blame(code, [m.start() for m in _PLACEHOLDERS.finditer(code)])

    # Enumerations out.
    enums = None
    if "." in code:
        parts = _ENUM.split(code)
        if len(parts) > 1:
            enums = parts[1::2]
            code = _PH_ENUM.join(parts[0::2])

    # Part names of complex instances out (their heads with them).
    part_names = None
    complex_heads = 0
    if None in idx.types[a:b]:
        code, part_names, complex_heads = _part_names(code)

    # Heads out.
    code, heads = _HEAD.subn(_HEAD_REPL, code)
    heads += complex_heads
    # Nothing left but numbers, references, $, *, punctuation and placeholders.
    if _BAD_CHAR.search(code) is not None:
        raise _blame(code, [m.start() for m in _BAD_CHAR.finditer(code)])
    if heads != n or code.count(";") != n + 1:
        # A head where none belongs (#1=A(#2=B(1));): one per instance.
        segments = code.split(";")
        if len(segments) != n + 2:
            raise _Fail()
        raise _Fail([k for k, seg in enumerate(segments[1:-1]) if seg.count(_PH_HEAD) != 1])

    # Each instance one balanced list, not too deep.
    parens = code.translate(_PARENS)
    for _ in range(_DEPTH_LIMIT):
        reduced = parens.replace("()", "")
        if len(reduced) == len(parens):
            break
        parens = reduced
    if len(parens) != n + 1:
        # Only ';' should be left: blame the instances that still hold a parenthesis.
        blame = []
        k = -1
        for ch in parens:
            if ch == ";":
                k += 1
            elif not blame or blame[-1] != k:
                blame.append(k)
        raise _Fail(blame)

    # Numbers on which Part 21 and JSON agree.
    rev = None
    bad = []
    for letter in "Ee":
        if letter in code:
            if rev is None:
                rev = code[::-1]
            pattern = _REV_EXP_NO_POINT[letter]
            if pattern.search(rev) is not None:
                bad += [len(code) - 1 - m.start() for m in pattern.finditer(rev)]
            pattern = _BIG_EXPONENT[letter]
            if pattern.search(code) is not None:
                bad += [m.start() for m in pattern.finditer(code)]
    if "." in code:
        if rev is None:
            rev = code[::-1]
        if _REV_LONG_MANTISSA.search(rev) is not None:
            bad += [len(code) - 1 - m.start() for m in _REV_LONG_MANTISSA.finditer(rev)]
    plus = "+" in code and code.count("+") != code.count("E+") + code.count("e+")
    if plus:
        bad += [m.start() for m in _PLUS_BAD.finditer(code)]
    if bad:
        raise _blame(code, sorted(bad))
    del rev
    if plus:
        code = _PLUS_SIGN.sub("", code)

    # Rewrite into JSON.
    if "." in code:
        code = _DOT.sub(".0", code)
    if "#" in code:
        parts = _REF.split(code)
        m = len(parts) // 4
        parts[1::4] = ['{"ref":'] * m
        parts[3::4] = ["}"] * m
        code = "".join(parts)
    if "$" in code:
        code = code.replace("$", "null")
    if "*" in code:
        code = code.replace("*", '{"derived":true}')
    code = code.translate(_FINAL)
    if enums:
        parts = code.split(_PH_ENUM)
        merged = [None] * (2 * len(parts) - 1)
        merged[0::2] = parts
        merged[1::2] = map(_ENUM_JSON.__getitem__, enums)
        code = "".join(merged)
    if part_names:
        parts = code.split(_PH_PART)
        merged = [None] * (2 * len(parts) - 1)
        merged[0::2] = parts
        merged[1::2] = ['"' + name + '"' for names in part_names.values() for name in names]
        code = "".join(merged)

    # Strings back in.
    if bodies:
        pieces[0::2] = code.split(_PH_STRING)
        for i, value in slow:
            pieces[i] = value
        code = '"'.join(pieces)
    del pieces, bodies
    # ',[...],[...],' -> '[[...],[...]]'
    code = "[" + code[1:-1] + "]"

    enabled = gc.isenabled()
    gc.disable()  # many new containers, none of them cyclic
    try:
        try:
            values = _DECODER.decode(code)
        except ValueError:
            raise _Fail(_json_culprits(code, n)) from None
        del code
        if len(values) != n:
            raise _Fail()
        if part_names is None:
            records = [{"id": i, "type": t, "args": v}
                       for i, t, v in zip(idx.ids[a:b], idx.types[a:b], values)]
        else:
            records = _with_complex(idx, a, b, values, part_names)
    finally:
        if enabled:
            gc.enable()
    if warnings:
        for message, offset in warnings:
            warn(message, offset)
    return records


def _part_names(code: str):
    """``code`` with the part names of complex instances out (``_PH_PART``): (code,
    {relative slot: [part names, lower case]} in the order of the code, number of complex
    heads)."""
    pieces = _PART.split(code)
    if len(pieces) == 1:
        return code, None, 0
    parts: dict = {}
    out = [pieces[0]]
    seen = pieces[0].count(";")  # the instance k (from 0) is after the (k+1)-th ';'
    heads = 0
    for j in range(1, len(pieces), 3):
        if pieces[j][0] == ";":
            seen += 1
            heads += 1
            out.append(_COMPLEX_HEAD_REPL)
        else:
            out.append(_NEXT_PART_REPL)
        parts.setdefault(seen - 1, []).append(pieces[j + 1].lower())
        rest = pieces[j + 2]
        out.append(rest)
        seen += rest.count(";")
    return "".join(out), parts, heads


def _with_complex(idx, a: int, b: int, values: list, parts: dict) -> list:
    """The records of slots a..b-1, complex ones from their flat lists; _Fail for an
    instance whose part names are not where parts of a complex instance are."""
    records = []
    bad = []
    for rel, (i, t, v) in enumerate(zip(idx.ids[a:b], idx.types[a:b], values)):
        names = parts.get(rel)
        if t is not None:
            if names is not None:
                bad.append(rel)
            records.append({"id": i, "type": t, "args": v})
            continue
        if (names is None or len(v) != 2 * len(names) or v[0::2] != names
                or any(type(x) is not list for x in v[1::2])):
            bad.append(rel)
            continue
        records.append({"id": i, "complex": [{"type": n, "args": x} for n, x in zip(names, v[1::2])]})
    if bad:
        raise _Fail(bad)
    return records


def _blank_gaps(text: str, idx, a: int, b: int) -> str:
    """``text`` (slots a..b-1) with the comments between instances blanked out.

    Between two instances the index leaves only white space and comments;
    spaces of the same length keep every offset.
    """
    starts, ends = idx.starts, idx.ends
    origin = starts[a]
    pieces = []
    last = 0
    for k in range(a, b - 1):
        gap_start, gap_end = ends[k] - origin, starts[k + 1] - origin
        if gap_end > gap_start and "/*" in text[gap_start:gap_end]:
            pieces += [text[last:gap_start], " " * (gap_end - gap_start)]
            last = gap_end
    pieces.append(text[last:])
    return "".join(pieces)


def _slow_strings(pieces: list, bodies: list, origin: int):
    """JSON text for the string bodies that need decoding: [(piece index, text)], warnings.

    ``pieces`` alternates code and string bodies as ``_STRING.split`` left
    them from text starting at offset ``origin``; piece ``i`` begins at
    ``origin + sum(len(pieces[:i])) + i`` (a quote before each piece but the
    first).
    """
    if not bodies or _SLOW_BODY.search("".join(bodies)) is None:
        return (), None
    slow = []
    warnings: list = []

    def warn(message, offset):
        warnings.append((message, offset))

    pos, done = origin, 0
    for j, body in enumerate(bodies):
        if "'" in body or "\\" in body or '"' in body or "\r" in body or "\n" in body:
            i = 2 * j + 1
            pos += sum(map(len, pieces[done:i])) + (i - done)
            done = i
            try:
                value = decode_string("'" + body + "'", pos - 1, warn)
            except StepError:
                return i, None
            if _SURROGATE.search(value) is not None:
                return i, None  # json would join an escaped pair into one character
            slow.append((i, encode_basestring_ascii(value)[1:-1]))
    return slow, warnings


def _json_culprits(js: str, n: int):
    """The instances (relative slots) whose JSON does not parse on its own.

    ``js`` is ``[\r[...],\r[...],...]`` with one carriage return before each
    instance's list and nowhere else; each list is parsed alone, and must be
    followed by ',' (or the final ']').
    """
    scan = _DECODER.scan_once
    bad = []
    at = js.find(_MARK)
    for k in range(n):
        if at < 0:
            break
        following = js.find(_MARK, at + 1)
        stop = len(js) if following < 0 else following
        try:
            value, end = scan(js, at + 1)
            ok = type(value) is list and js[end:stop].strip(" \t\n") == ("]" if following < 0 else ",")
        except (StopIteration, ValueError, RecursionError):
            ok = False
        if not ok:
            bad.append(k)
        at = following
    return bad or None
