"""Canonical Part 21 writer.

Same model in, same bytes out: one instance per line, in model order,
no optional whitespace, upper-case keywords, reals in their shortest
exact form with a decimal point, strings re-escaped to printable ASCII.
The header is written as it is in the model; nothing (time stamps
included) is changed behind the user's back.
"""

from __future__ import annotations

from .errors import ModelError
from .lexer import _SURROGATE, encode_real, encode_string
from .reader import _RAW_SECTION, header_from_json


def _value(v, out: list) -> None:
    """Append the Part 21 text of one JSON-model value to ``out``."""
    t = type(v)
    if t is str:
        out.append(encode_string(v))
    elif t is float:
        out.append(encode_real(v))
    elif t is int:
        out.append(str(v))
    elif t is dict:
        if "ref" in v:
            out.append(f"#{v['ref']}")
        elif "enum" in v:
            out.append(f".{v['enum'].upper()}.")
        elif "derived" in v:
            out.append("*")
        elif "type" in v:
            out.append(v["type"].upper())
            out.append("(")
            _value(v["value"], out)
            out.append(")")
        elif "binary" in v:
            out.append(f'"{v["binary"]}"')
        else:
            raise ModelError(f"unknown value object {sorted(v)}")
    elif v is None:
        out.append("$")
    elif t is list:
        _list(v, out)
    else:
        raise ModelError(f"value of type {t.__name__} cannot be written to Part 21")


def _list(items: list, out: list) -> None:
    out.append("(")
    first = True
    for item in items:
        if not first:
            out.append(",")
        first = False
        _value(item, out)
    out.append(")")


def _parameters(args: list) -> str:
    out: list = []
    _list(args, out)
    return "".join(out)


def instance_text(record: dict) -> str:
    """``#id=TYPE(...);`` for one record of the JSON model."""
    if "complex" in record:
        parts = "".join(p["type"].upper() + _parameters(p["args"]) for p in record["complex"])
        return f"#{record['id']}=({parts});"
    return f"#{record['id']}={record['type'].upper()}{_parameters(record['args'])};"


def _check_other_section(extra: dict) -> None:
    """Refuse verbatim section text that would not read back as that section."""
    text = extra["text"]
    m = _RAW_SECTION.match(text)
    if m.end() != len(text) or _SURROGATE.search(text) is not None:
        raise ModelError(f"{extra['keyword']} section text cannot be written to Part 21 as it is "
                         "(an unterminated string or comment, an ENDSEC; or an unpaired surrogate)")


def write_step(doc, fh) -> None:
    """Write a document (``StepFile`` or ``JsonDocument``) to a text stream."""
    write = fh.write
    for extra in doc.other_sections:
        _check_other_section(extra)
    write("ISO-10303-21;\nHEADER;\n")
    for etype, args in header_from_json(doc.header):
        write(f"{etype.upper()}{_parameters(args)};\n")
    write("ENDSEC;\n")
    other = list(doc.other_sections)
    records = iter(doc.records())
    for k, section in enumerate(doc.sections):
        for extra in other:
            if extra["after_data"] == k:
                write(f"{extra['keyword']};{extra['text']}ENDSEC;\n")
        if section.parameters is None:
            write("DATA;\n")
        else:
            write(f"DATA{_parameters(section.parameters)};\n")
        for _ in range(section.count):
            write(instance_text(next(records)))
            write("\n")
        write("ENDSEC;\n")
    for extra in other:
        if extra["after_data"] >= len(doc.sections):
            write(f"{extra['keyword']};{extra['text']}ENDSEC;\n")
    write("END-ISO-10303-21;\n")
