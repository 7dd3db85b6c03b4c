"""The EXPRESS tokenizer: comments blanked out, then the text cut into
token keys, values, offsets and line numbers for the parser.
"""

from __future__ import annotations

import re
import sys


class ExpressSyntaxError(Exception):
    """The text is not EXPRESS. ``str()`` is ``FILE:LINE:COL: message``."""

    def __init__(self, message: str, filename: str, line: int, column: int):
        super().__init__(message)
        self.message = message
        self.filename = filename
        self.line = line
        self.column = column

    def __str__(self) -> str:
        return f"{self.filename}:{self.line}:{self.column}: {self.message}"


# Comments are blanked out first (they nest, which a regular expression
# cannot follow); strings must be recognised on the way so that a quote in
# a string does not open a comment and "(*" in a string is left alone.
_COMMENT_SCAN = re.compile(r"'(?:[^']|'')*'|\"[^\"]*\"|--[^\n]*|\(\*")
_BLOCK_SCAN = re.compile(r"\(\*|\*\)")

_TOKEN = re.compile(
    r"""[ \t\r\n\f\v]*(?:
        (?P<real>[0-9]+\.[0-9]*(?:[eE][+-]?[0-9]+)?)
      | (?P<int>[0-9]+)
      | (?P<id>[A-Za-z][A-Za-z0-9_]*)
      | (?P<str>'(?:[^']|'')*')
      | (?P<enc>"[^"]*")
      | (?P<bin>%[01]*)
      | (?P<op>:=:|:<>:|<\*|<=|>=|<>|:=|\|\||\*\*|[-+*/=<>()\[\]{}.,;:\\|?])
      | (?P<bad>\S)
    )""", re.X | re.S)

# token keys of literal tokens; identifiers and operators use their own text
K_INT, K_REAL, K_STR, K_BIN, K_EOF = "\0int", "\0real", "\0str", "\0bin", "\0eof"


def _blank(seg: str) -> str:
    if "\n" not in seg:
        return " " * len(seg)
    return "\n".join(" " * len(x) for x in seg.split("\n"))


def _line_col(text: str, pos: int) -> tuple:
    pos = max(0, min(pos, len(text)))
    line = text.count("\n", 0, pos) + 1
    col = pos - (text.rfind("\n", 0, pos) + 1) + 1
    return line, col


def strip_comments(text: str, filename: str = "<string>") -> str:
    """``text`` with every comment replaced by spaces (newlines kept, so
    lines and columns do not move)."""
    out = []
    last = 0
    pos = 0
    n = len(text)
    scan = _COMMENT_SCAN.search
    while True:
        m = scan(text, pos)
        if m is None:
            break
        s = m.group()
        if s[0] in "'\"":
            pos = m.end()
            continue
        start = m.start()
        if s[0] == "-":
            end = m.end()
        else:  # "(*": find the matching "*)", counting nesting
            depth = 0
            end = -1
            for b in _BLOCK_SCAN.finditer(text, start):
                if b.group() == "(*":
                    depth += 1
                else:
                    depth -= 1
                    if depth == 0:
                        end = b.end()
                        break
            if end < 0:
                line, col = _line_col(text, start)
                raise ExpressSyntaxError("unterminated comment '(*'", filename, line, col)
        out.append(text[last:start])
        out.append(_blank(text[start:end]))
        last = pos = end
        if pos >= n:
            break
    if not out:
        return text
    out.append(text[last:])
    return "".join(out)


def _decode_encoded(s: str) -> str:
    body = s[1:-1]
    return "".join(chr(int(body[i:i + 8], 16)) for i in range(0, len(body), 8))


def tokenize(text: str, filename: str = "<string>"):
    """Four parallel lists (keys, values, positions, lines). ``keys`` is the
    lower-case text for identifiers and operators, a K_* marker for
    literals; ``values`` holds the literal value (identifiers: lower case)."""
    clean = strip_comments(text, filename)
    keys: list = []
    vals: list = []
    poss: list = []
    lines: list = []
    ka, va, pa, la = keys.append, vals.append, poss.append, lines.append
    intern = sys.intern
    count = clean.count
    line = 1
    prev = 0
    for m in _TOKEN.finditer(clean):
        kind = m.lastgroup
        start = m.start(kind)
        line += count("\n", prev, start)
        prev = start
        v = m.group(kind)
        if kind == "id":
            v = intern(v.lower())
            ka(v)
            va(v)
        elif kind == "op":
            ka(v)
            va(v)
        elif kind == "int":
            ka(K_INT)
            va(int(v))
        elif kind == "real":
            ka(K_REAL)
            va(float(v))
        elif kind == "str":
            ka(K_STR)
            va(v[1:-1].replace("''", "'"))
            line += v.count("\n")
            prev = m.end()
        elif kind == "enc":
            body = v[1:-1]
            if len(body) % 8 or not re.fullmatch(r"[0-9A-Fa-f]*", body):
                lc = _line_col(text, start)
                raise ExpressSyntaxError(
                    "bad encoded string literal (expected groups of 8 hex digits)",
                    filename, *lc)
            ka(K_STR)
            va(("enc", _decode_encoded(v)))
        elif kind == "bin":
            if len(v) < 2:
                raise ExpressSyntaxError("empty binary literal '%'", filename,
                                         *_line_col(text, start))
            ka(K_BIN)
            va(v[1:])
        else:
            what = ("unterminated string literal" if v == "'" else
                    "unterminated encoded string literal" if v == '"' else
                    f"unexpected character {v!r}")
            raise ExpressSyntaxError(what, filename, *_line_col(text, start))
        pa(start)
        la(line)
    line += count("\n", prev, len(clean))
    ka(K_EOF)
    va(None)
    pa(len(clean))
    la(line)
    return keys, vals, poss, lines
