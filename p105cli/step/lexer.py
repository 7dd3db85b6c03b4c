"""The careful half of the Part 21 reader: tokens, parameters and strings.

The fast index (``index.py``) only finds where instances begin and end.
Everything that turns text into values happens here, one instance at a
time, so a command pays only for the instances it reads. This module is
also the reference grammar: when the index stops on something it does
not expect, the tokenizer is run from that point to say exactly what is
wrong and where.

Values come out already in the JSON model's shape (see docs/json-model.md):
int, float, str, None for ``$``, lists, and small dicts for references,
enumerations, ``*``, binaries and typed parameters. One representation
in memory and on the wire keeps the mapping in one place.
"""

from __future__ import annotations

import math
import re
import sys

from .errors import ModelError, StepSyntaxError

# Lists nested deeper than this are refused: no real schema nests more than a
# handful of levels, and the limit keeps every later recursive consumer
# (json, the writer, the schema layer) far from Python's recursion limit.
MAX_NESTING = 200

_TOKEN = re.compile(
    r"""
    (?P<ws>[ \t\r\n]+)
  | (?P<comment>/\*.*?\*/)
  | (?P<real>[+-]?[0-9]+\.[0-9]*(?:[eE][+-]?[0-9]+)?)
  | (?P<int>[+-]?[0-9]+)
  | (?P<string>'[^']*(?:''[^']*)*')
  | (?P<ref>\#[0-9]+)
  | (?P<enum>\.[A-Za-z_][A-Za-z0-9_]*\.)
  | (?P<binary>"[0-3][0-9A-Fa-f]*")
  | (?P<keyword>!?[A-Za-z_][A-Za-z0-9_]*)
  | (?P<punct>[(),;=$*])
    """,
    re.X | re.S,
)

DERIVED = {"derived": True}


def _syntax_error_at(text: str, pos: int) -> StepSyntaxError:
    """Describe the character at ``pos`` that no token can start with."""
    if pos >= len(text):
        return StepSyntaxError("unexpected end of input", pos)
    ch = text[pos]
    if text.startswith("/*", pos):
        return StepSyntaxError("unterminated comment", pos)
    if ch == "'":
        return StepSyntaxError("unterminated string", pos)
    if ch == '"':
        return StepSyntaxError("malformed binary (expected \"<0-3><hex digits>\")", pos)
    if ch == ".":
        return StepSyntaxError("malformed enumeration (expected .NAME.)", pos)
    if ch == "#":
        return StepSyntaxError("malformed instance name (expected #digits)", pos)
    if ch.isprintable() and ch != " ":
        return StepSyntaxError(f"unexpected character {ch!r}", pos)
    return StepSyntaxError(f"unexpected character U+{ord(ch):04X}", pos)


class Tokens:
    """A cursor over the tokens of ``text[pos:end]`` that skips whitespace and comments."""

    __slots__ = ("text", "pos", "end")

    def __init__(self, text: str, pos: int = 0, end: int | None = None):
        self.text = text
        self.pos = pos
        self.end = len(text) if end is None else end

    def next(self):
        """Return ``(kind, lexeme, offset)``; kind is ``'eof'`` at the end."""
        text, end, match = self.text, self.end, _TOKEN.match
        pos = self.pos
        while pos < end:
            m = match(text, pos, end)
            if m is None:
                raise _syntax_error_at(text, pos)
            kind = m.lastgroup
            if kind == "ws" or kind == "comment":
                pos = m.end()
                continue
            self.pos = m.end()
            return kind, m.group(), pos
        self.pos = pos
        return "eof", "", pos

    def expect(self, lexeme: str, what: str | None = None):
        kind, lex, at = self.next()
        if lex != lexeme:
            shown = "end of input" if kind == "eof" else repr(lex)
            raise StepSyntaxError(f"expected {what or repr(lexeme)}, found {shown}", at)
        return at


# ---------------------------------------------------------------- strings

_CODE_PAGE = re.compile(r"\\P([A-I])\\")
_HEX2 = re.compile(r"\\X\\([0-9A-Fa-f]{2})")
_XRUN = re.compile(r"\\X([24])\\((?:[0-9A-Fa-f]{4})*?)\\X0\\")


def decode_string(lexeme: str, offset: int = 0, warn=None) -> str:
    """Decode a Part 21 string token (quotes included) to Python text.

    Physical line breaks inside a string are not part of it (writers wrap
    long strings); ``''`` is a quote; the control directives ``\\\\``,
    ``\\S\\``, ``\\P?\\``, ``\\X\\hh``, ``\\X2\\..\\X0\\`` and
    ``\\X4\\..\\X0\\`` are decoded. A backslash that starts none of them
    is kept as a literal backslash and reported through ``warn`` (real
    files carry unescaped Windows paths in FILE_NAME).
    """
    s = lexeme[1:-1]
    if "\r" in s or "\n" in s:
        s = s.replace("\r", "").replace("\n", "")
    s = s.replace("''", "'")
    if "\\" not in s:
        return s
    out: list[str] = []
    page = "iso8859-1"
    i, n = 0, len(s)
    while i < n:
        j = s.find("\\", i)
        if j < 0:
            out.append(s[i:])
            break
        out.append(s[i:j])
        i = j
        if s.startswith("\\\\", i):
            out.append("\\")
            i += 2
        elif s.startswith("\\S\\", i) and i + 3 < n and ord(s[i + 3]) < 128:
            out.append(bytes([ord(s[i + 3]) + 128]).decode(page, errors="replace"))
            i += 4
        elif (m := _CODE_PAGE.match(s, i)) is not None:
            page = f"iso8859-{ord(m.group(1)) - 64}"
            i = m.end()
        elif (m := _HEX2.match(s, i)) is not None:
            out.append(chr(int(m.group(1), 16)))
            i = m.end()
        elif (m := _XRUN.match(s, i)) is not None:
            raw = bytes.fromhex(m.group(2))
            width = 2 if m.group(1) == "2" else 4
            if width == 4 and len(raw) % 4:
                raise StepSyntaxError("\\X4\\ needs groups of eight hex digits", offset + 1 + i)
            try:
                out.append(raw.decode("utf-16-be" if width == 2 else "utf-32-be"))
            except UnicodeDecodeError:
                raise StepSyntaxError(
                    f"\\X{width}\\ sequence is not valid {'UCS-2/UTF-16' if width == 2 else 'UCS-4'}",
                    offset + 1 + i,
                ) from None
            i = m.end()
        else:
            if warn is not None:
                warn("backslash that starts no escape kept as a literal backslash", offset + 1 + i)
            out.append("\\")
            i += 1
    return "".join(out)


_NEEDS_ESCAPE = re.compile(r"[^\x20-\x7e]|['\\]")
_ESCAPE_PIECE = re.compile(r"[^\x00-\x7f]+|[\x00-\x1f\x7f]|'|\\")
_SURROGATE = re.compile("[\ud800-\udfff]")


def _escape_piece(m: re.Match) -> str:
    piece = m.group()
    if piece == "'":
        return "''"
    if piece == "\\":
        return "\\\\"
    if len(piece) == 1 and ord(piece) < 0x80:
        return f"\\X\\{ord(piece):02X}"
    if _SURROGATE.search(piece) is not None:
        # No escape can carry it: \X2\ would write text that no reader accepts.
        raise ModelError("string holds an unpaired surrogate: it cannot be written to Part 21")
    if max(piece) <= "\uffff":
        return "\\X2\\" + "".join(f"{ord(c):04X}" for c in piece) + "\\X0\\"
    return "\\X4\\" + "".join(f"{ord(c):08X}" for c in piece) + "\\X0\\"


def encode_string(s: str) -> str:
    """Encode Python text as a Part 21 string token, using only printable ASCII."""
    if _NEEDS_ESCAPE.search(s) is None:
        return "'" + s + "'"
    return "'" + _ESCAPE_PIECE.sub(_escape_piece, s) + "'"


# ---------------------------------------------------------------- numbers

def decode_int(lexeme: str, offset: int) -> int:
    """An integer (or the digits of an instance name) of any size up to the
    interpreter's limit on decimal conversion (``sys.get_int_max_str_digits``,
    4300 digits by default): converting longer ones takes quadratic time, and
    neither ``json`` nor ``str(int)`` would write them back."""
    try:
        return int(lexeme)
    except ValueError:
        pass
    digits = lexeme.lstrip("+-").lstrip("0") or "0"  # leading zeros count against the limit
    if len(digits) <= sys.get_int_max_str_digits():
        return -int(digits) if lexeme.startswith("-") else int(digits)
    raise StepSyntaxError(f"integer of {len(digits)} digits is too long "
                          f"(at most {sys.get_int_max_str_digits()})", offset)


def decode_real(lexeme: str, offset: int) -> float:
    value = float(lexeme)
    if math.isinf(value):
        raise StepSyntaxError(f"real {lexeme} is out of the range of a double", offset)
    return value


def encode_real(value: float) -> str:
    """Shortest text that reads back to the same double, always with a point."""
    if not math.isfinite(value):
        raise ValueError(f"{value!r} cannot be written to Part 21")
    r = repr(value)
    mantissa, e, exponent = r.partition("e")
    if "." not in mantissa:
        mantissa += "."
    elif mantissa.endswith(".0"):
        mantissa = mantissa[:-1]
    if e:
        return f"{mantissa}E{exponent.lstrip('+')}"
    return mantissa


# ---------------------------------------------------------------- parameters

def parse_parameters(tokens: Tokens, warn=None) -> list:
    """Parse a parenthesised parameter list; the cursor must be before ``(``.

    Iterative, with an explicit stack, so hostile nesting cannot exhaust
    the interpreter's stack; nesting beyond MAX_NESTING is an error.
    """
    open_at = tokens.expect("(", "'('")
    # A frame is [items, typed-parameter name or None, offset of its '('].
    stack = [[[], None, open_at]]
    expect_value = True  # after '(' or ','
    first = True  # right after '(' a ')' may close an empty list
    while True:
        kind, lex, at = tokens.next()
        frame = stack[-1]
        if expect_value:
            if kind == "punct" and lex == ")" and first and frame[1] is None:
                expect_value = False
            else:
                if kind == "int":
                    try:
                        value = int(lex)
                    except ValueError:
                        value = decode_int(lex, at)  # leading zeros, or a syntax error
                elif kind == "real":
                    value = decode_real(lex, at)
                elif kind == "string":
                    value = decode_string(lex, at, warn)
                elif kind == "ref":
                    try:
                        value = {"ref": int(lex[1:])}
                    except ValueError:
                        value = {"ref": decode_int(lex[1:], at + 1)}
                elif kind == "enum":
                    value = {"enum": lex[1:-1].upper()}
                elif kind == "binary":
                    value = {"binary": lex[1:-1].upper()}
                elif kind == "punct" and lex == "$":
                    value = None
                elif kind == "punct" and lex == "*":
                    value = DERIVED
                elif kind == "punct" and lex == "(" or kind == "keyword":
                    if len(stack) >= MAX_NESTING:
                        raise StepSyntaxError(f"lists nested deeper than {MAX_NESTING} levels", at)
                    if kind == "keyword":
                        tokens.expect("(", f"'(' after typed parameter {lex}")
                        stack.append([[], lex.upper(), at])
                    else:
                        stack.append([[], None, at])
                    first = True
                    continue
                else:
                    shown = "end of input" if kind == "eof" else repr(lex)
                    raise StepSyntaxError(f"expected a parameter, found {shown}", at)
                frame[0].append(value)
                expect_value = False
                first = False
                continue
        # after a value: ',' or ')'
        if kind == "punct" and lex == ",":
            if frame[1] is not None:
                raise StepSyntaxError(f"typed parameter {frame[1]} takes exactly one value", at)
            expect_value = True
            first = False
            continue
        if kind == "punct" and lex == ")":
            items, typed, _ = stack.pop()
            value = {"type": typed, "value": items[0]} if typed is not None else items
            if not stack:
                return value
            stack[-1][0].append(value)
            expect_value = False
            first = False
            continue
        shown = "end of input" if kind == "eof" else repr(lex)
        raise StepSyntaxError(f"expected ',' or ')', found {shown}", at)


def parse_instance_body(text: str, start: int, end: int, warn=None) -> dict:
    """Decode the instance written at ``text[start:end]`` (``#id=...;``)."""
    tokens = Tokens(text, start, end)
    kind, lex, at = tokens.next()
    if kind != "ref":
        raise StepSyntaxError("expected an instance name #n", at)
    record: dict = {"id": decode_int(lex[1:], at + 1)}
    tokens.expect("=", "'=' after the instance name")
    kind, lex, at = tokens.next()
    if kind == "keyword":
        record["type"] = lex.lower()
        record["args"] = parse_parameters(tokens, warn)
    elif kind == "punct" and lex == "(":
        parts = []
        while True:
            kind, lex, at = tokens.next()
            if kind == "punct" and lex == ")":
                break
            if kind != "keyword":
                shown = "end of input" if kind == "eof" else repr(lex)
                raise StepSyntaxError(f"expected an entity name in a complex instance, found {shown}", at)
            parts.append({"type": lex.lower(),
                          "args": parse_parameters(tokens, warn)})
        if not parts:
            raise StepSyntaxError("complex instance with no entity", at)
        record["complex"] = parts
    else:
        shown = "end of input" if kind == "eof" else repr(lex)
        raise StepSyntaxError(f"expected an entity name or '(' after '=', found {shown}", at)
    tokens.expect(";", "';' at the end of the instance")
    kind, lex, at = tokens.next()
    if kind != "eof":
        raise StepSyntaxError(f"unexpected {lex!r} after the end of the instance", at)
    return record
