"""Read a Part 21 exchange structure (ISO 10303-21 edition 3) lazily.

``read_step`` parses the file's frame (HEADER, DATA sections, and the
edition 3 ANCHOR / REFERENCE / SIGNATURE sections, which are kept
verbatim), indexes every instance in one pass and decodes nothing else.
``StepFile.record(id)`` decodes one instance; ``StepFile.records()``
decodes them all, in file order.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from .errors import StepError, StepSyntaxError
from .index import _SKIP, InstanceIndex, _SKIP_RE, index_data_section
from .lexer import Tokens, parse_instance_body, parse_parameters

MAGIC = "ISO-10303-21"
MAX_WARNINGS = 1000  # kept per file; the rest are counted in StepFile.warnings_dropped
_FRAME_WORD = re.compile(r"(ISO-10303-21|END-ISO-10303-21|HEADER|DATA|ANCHOR|REFERENCE|SIGNATURE|ENDSEC)\b", re.I)
# Raw body of a section kept verbatim, up to its ENDSEC; strings and comments may hold anything.
# An unterminated comment stops the match (as a lone '/', each later '/*' would rescan the rest).
_RAW_SECTION = re.compile(r"(?:[^'/E]++|'[^']*+'|/\*.*?\*/|/(?!\*)|E(?!NDSEC" + _SKIP + r";))*+", re.S)

HEADER_FIELDS = {
    "file_description": ("description", "implementation_level"),
    "file_name": ("name", "time_stamp", "author", "organization",
                  "preprocessor_version", "originating_system", "authorization"),
}


def header_to_json(entities: list[tuple[str, list]]) -> dict:
    """Map header entities to the JSON model: the three standard ones by name."""
    header: dict = {}
    other: list = []
    for etype, args in entities:
        fields = HEADER_FIELDS.get(etype)
        if fields is not None and etype not in header and len(args) == len(fields):
            header[etype] = dict(zip(fields, args))
        elif (etype == "file_schema" and etype not in header and len(args) == 1
              and isinstance(args[0], list) and all(isinstance(s, str) for s in args[0])):
            header[etype] = list(args[0])
        else:
            other.append({"type": etype, "args": args})
    if other:
        header["other"] = other
    return header


def header_from_json(header: dict) -> list[tuple[str, list]]:
    """The header's entities in the order a writer puts them."""
    out = []
    for etype, fields in HEADER_FIELDS.items():
        if etype in header:
            out.append((etype, [header[etype][f] for f in fields]))
        if etype == "file_name" and "file_schema" in header:
            out.append(("file_schema", [list(header["file_schema"])]))
    for entry in header.get("other", []):
        out.append((entry["type"], entry["args"]))
    return out


@dataclass
class DataSection:
    """One DATA section: its parameters (edition 3: name and schema) and its instances."""
    parameters: list | None
    count: int


class Latin1Text(str):
    """Text decoded as ISO 8859-1 because its bytes are not UTF-8 (see :func:`decode_bytes`):
    each character U+0080..U+00FF stands for one raw 8-bit byte of the file."""

    __slots__ = ()


_HIGH = re.compile("[\x80-\xff]+")


@dataclass(frozen=True)
class NotUtf8:
    """The raw 8-bit bytes of a file that is not UTF-8, read as ISO 8859-1 characters.

    ISO 10303-21 strings hold the characters 32-126 and reach the others through the
    control directives (\\S\\, \\X\\hh, \\X2\\...\\X0\\, \\X4\\...\\X0\\);
    edition 3 also allows UTF-8. Raw bytes of another encoding (GBK from SolidWorks,
    Windows-1252) are neither: their characters cannot be known, so they are kept as
    ISO 8859-1 (byte for byte) and reported. ``count``: how many bytes; ``runs``: (offset,
    length) of the first run of them on each line (at most MAX_WARNINGS lines)."""

    count: int
    runs: tuple

    def summary(self) -> tuple[str, int]:
        """The one warning of a file (message, offset of the first byte)."""
        n = self.count
        return (f"not UTF-8: {n} raw 8-bit byte{'s' if n != 1 else ''} (the first here) read "
                f"as ISO 8859-1, so the characters of the strings that hold them may be wrong "
                f"(ISO 10303-21 writes them as \\X2\\...\\X0\\)", self.runs[0][0])

    def details(self, text: str):
        """(message, offset) of the first run of raw bytes on each line."""
        for offset, length in self.runs:
            shown = text[offset:offset + min(length, 8)]
            hexes = " ".join(f"{ord(c):02X}" for c in shown) + (" ..." if length > 8 else "")
            yield (f"raw 8-bit byte{'s' if length != 1 else ''} {hexes} not UTF-8, read as "
                   f"ISO 8859-1 {shown!r}{_as_gbk(text[offset:offset + length])}: write the "
                   f"characters as \\X2\\...\\X0\\"), offset


def _as_gbk(run: str) -> str:
    """A hint when the bytes read as GBK (SolidWorks' Chinese exports), else ''."""
    if len(run) > 32 or len(run) % 2:
        return ""
    try:
        return f" (as GBK: {run.encode('latin-1').decode('gbk')!r})"
    except UnicodeDecodeError:
        return ""


def not_utf8(text: str) -> NotUtf8 | None:
    """What :class:`NotUtf8` says of ``text``; None unless it is a :class:`Latin1Text`."""
    if not isinstance(text, Latin1Text):
        return None
    count = 0
    runs: list = []
    last_line_end = -1
    for m in _HIGH.finditer(text):
        count += m.end() - m.start()
        if m.start() > last_line_end and len(runs) < MAX_WARNINGS:
            runs.append((m.start(), m.end() - m.start()))
            nl = text.find("\n", m.end())
            last_line_end = len(text) if nl < 0 else nl
    return NotUtf8(count, tuple(runs)) if count else None


@dataclass
class StepFile:
    """An indexed exchange structure. Instances are decoded on demand."""

    text: str
    source: str
    header: dict
    sections: list[DataSection]
    index: InstanceIndex
    other_sections: list[dict] = field(default_factory=list)
    warnings: list[tuple[str, int]] = field(default_factory=list)
    # Warnings beyond MAX_WARNINGS are only counted: a 100 MB string of
    # stray backslashes must not need gigabytes of warning records.
    warnings_dropped: int = 0
    # Raw 8-bit bytes that are not UTF-8 (one summary among ``warnings``; validate
    # reports each line).
    not_utf8: NotUtf8 | None = None

    def _warn(self, message: str, offset: int) -> None:
        if len(self.warnings) < MAX_WARNINGS:
            self.warnings.append((message, offset))
        else:
            self.warnings_dropped += 1

    def __len__(self) -> int:
        return len(self.index)

    def _decode_slot(self, k: int) -> dict:
        idx = self.index
        try:
            return parse_instance_body(self.text, idx.starts[k], idx.ends[k], self._warn)
        except StepError as err:
            _attach(err, self.text, self.source)
            raise

    def record(self, instance_id: int) -> dict:
        """The decoded instance ``#instance_id`` (KeyError if absent)."""
        k = self.index.slot(instance_id)
        if k < 0:
            raise KeyError(instance_id)
        return self._decode_slot(k)

    def records(self):
        """Every instance, decoded, in file order (the bulk decoder; see bulk.py)."""
        from .bulk import decode_all
        return decode_all(self)

    def check(self) -> None:
        """Decode every instance once, keeping nothing: raises the first error in file order,
        the one ``parse`` reports. Instances are decoded on demand, so a command that reads
        only the instances it needs would otherwise never see an error in the others.
        Warnings are left to the decoding that keeps the records (none recorded twice)."""
        kept, dropped = len(self.warnings), self.warnings_dropped
        try:
            for _ in self.records():
                pass
        finally:
            del self.warnings[kept:]
            self.warnings_dropped = dropped

    def careful_records(self):
        """Every instance decoded one by one by the reference tokenizer."""
        for k in range(len(self.index)):
            yield self._decode_slot(k)

    def slots_of_type(self, *types: str) -> list[int]:
        """File-order positions of the simple instances of the given (lower-case) types."""
        wanted = set(types)
        return [k for k, t in enumerate(self.index.types) if t in wanted]

    def line_col(self, offset: int) -> tuple[int, int]:
        err = StepSyntaxError("", offset, self.text)
        return err.line, err.column


def _attach(err: StepError, text: str, source: str) -> None:
    err.source = source
    if isinstance(err, StepSyntaxError) and not err.line:
        err.attach_text(text)


def decode_bytes(raw: bytes) -> str:
    """Text of a Part 21 file: UTF-8 (edition 3), else ISO 8859-1 byte for byte, as a
    :class:`Latin1Text` so that the reader reports the bytes (:class:`NotUtf8`)."""
    if raw.startswith(b"\xef\xbb\xbf"):
        raw = raw[3:]
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return Latin1Text(raw.decode("latin-1"))


def read_step(text: str, source: str = "<input>") -> StepFile:
    """Parse the frame of a Part 21 text and index its instances."""
    try:
        return _read(text, source)
    except StepError as err:
        _attach(err, text, source)
        raise


def _skip(text: str, pos: int) -> int:
    pos = _SKIP_RE.match(text, pos).end()
    if text.startswith("/*", pos):
        raise StepSyntaxError("unterminated comment", pos)
    return pos


def _frame_word(text: str, pos: int, expected: str | None = None) -> tuple[str, int]:
    pos = _skip(text, pos)
    m = _FRAME_WORD.match(text, pos)
    word = m.group(1).upper() if m else None
    if word is None or (expected is not None and word != expected):
        found = text[pos:pos + 20].split(None, 1)[0] if text[pos:pos + 20].strip() else "end of input"
        want = expected or "a section keyword (DATA, ANCHOR, REFERENCE, SIGNATURE, END-ISO-10303-21)"
        raise StepSyntaxError(f"expected {want}, found {found!r}", pos)
    return word, m.end()


def _semicolon(text: str, pos: int, after: str) -> int:
    pos = _skip(text, pos)
    if not text.startswith(";", pos):
        raise StepSyntaxError(f"expected ';' after {after}", pos)
    return pos + 1


def _read(text: str, source: str) -> StepFile:
    warnings: list[tuple[str, int]] = []
    dropped = 0

    def warn(message, offset):
        nonlocal dropped
        if len(warnings) < MAX_WARNINGS:
            warnings.append((message, offset))
        else:
            dropped += 1

    pos = _skip(text, 0)
    if text[pos:pos + len(MAGIC)].upper() != MAGIC:
        raise StepSyntaxError("not a Part 21 file: it does not start with 'ISO-10303-21;'", pos)
    pos = _semicolon(text, pos + len(MAGIC), MAGIC)
    _, pos = _frame_word(text, pos, "HEADER")
    pos = _semicolon(text, pos, "HEADER")

    entities = []
    tokens = Tokens(text, pos)
    while True:
        kind, lex, at = tokens.next()
        if kind == "keyword" and lex.upper() == "ENDSEC":
            tokens.expect(";", "';' after ENDSEC")
            break
        if kind != "keyword":
            shown = "end of input" if kind == "eof" else repr(lex)
            raise StepSyntaxError(f"expected a header entity or ENDSEC, found {shown}", at)
        args = parse_parameters(tokens, warn)
        tokens.expect(";", f"';' after header entity {lex}")
        entities.append((lex.lower(), args))
    pos = tokens.pos

    index = InstanceIndex()
    sections: list[DataSection] = []
    other: list[dict] = []
    while True:
        word, after = _frame_word(text, pos)
        if word == "END-ISO-10303-21":
            pos = _semicolon(text, after, word)
            break
        if word in ("ANCHOR", "REFERENCE", "SIGNATURE"):
            body_start = _semicolon(text, after, word)
            m = _RAW_SECTION.match(text, body_start)
            if not text.startswith("ENDSEC", m.end()):
                if text.startswith("/*", m.end()):
                    raise StepSyntaxError("unterminated comment", m.end())
                if text.startswith("'", m.end()):
                    raise StepSyntaxError("unterminated string", m.end())
                raise StepSyntaxError(f"{word} section is not closed by ENDSEC;", body_start)
            other.append({"keyword": word, "after_data": len(sections), "text": text[body_start:m.end()]})
            pos = _semicolon(text, m.end() + len("ENDSEC"), "ENDSEC")
            continue
        if word != "DATA":
            raise StepSyntaxError(f"unexpected {word} here", _skip(text, pos))
        q = _skip(text, after)
        parameters = None
        if text.startswith("(", q):
            tokens = Tokens(text, q)
            parameters = parse_parameters(tokens, warn)
            q = tokens.pos
        q = _semicolon(text, q, "DATA")
        before = len(index)
        pos = index_data_section(text, q, len(text), index)
        sections.append(DataSection(parameters, len(index) - before))
    if not sections:
        raise StepSyntaxError("no DATA section", pos)
    rest = _SKIP_RE.match(text, pos).end()
    if rest < len(text):
        warn("text after END-ISO-10303-21; ignored", rest)
    index.finish()
    encoding = not_utf8(text)
    if encoding is not None:
        warnings.insert(0, encoding.summary())
    return StepFile(text, source, header_to_json(entities), sections, index, other, warnings, dropped,
                    encoding)
