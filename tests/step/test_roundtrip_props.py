"""Property tests: random valid Part 21 files survive every round trip exactly.

The strategy writes Part 21 text itself (independently of ``writer.py``) and
knows the records that text must read as: random instance names in random
order (leading zeros too), simple and complex instances, every value kind
(integers of any size up to the interpreter's 4300-digit limit, reals
including -0.0, subnormals and huge or tiny exponents written in many
equivalent ways, strings over all of Unicode but surrogates with every
escape and physical line breaks, enumerations, binaries, references, ``$``,
``*``, typed parameters, nested lists), with random whitespace and comments
between tokens, several DATA sections and an ANCHOR section.

Properties: the text reads as those records (type-exact); ``records()``
equals ``careful_records()``; read_step -> write_json -> read_json ->
write_step gives text that reads back to the same records; writing is
deterministic and the canonical text is a fixed point.
"""

from __future__ import annotations

import io
import math
import struct

from hypothesis import HealthCheck, given, settings, strategies as st

from conftest import same_records, same_value

from p105cli.step import read_json, read_step, write_json, write_step
from p105cli.step.lexer import decode_real, decode_string, encode_real, encode_string

SETTINGS = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])

# ---------------------------------------------------------------- lexical noise

COMMENT_TEXT = st.text(st.characters(codec="utf-8", exclude_characters="*"), max_size=8)


@st.composite
def gap(draw, required: bool = False) -> str:
    """Whitespace and comments allowed between two tokens."""
    parts = draw(st.lists(st.one_of(st.sampled_from([" ", "\n", "\r\n", "\t", "  "]),
                                    COMMENT_TEXT.map(lambda c: f"/*{c}*/")), max_size=2))
    text = "".join(parts)
    return text if text or not required else " "


# ---------------------------------------------------------------- values: (Part 21 text, model value)

NAME = st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,12}", fullmatch=True)

INTEGERS = st.one_of(
    st.integers(-1000, 1000),
    st.integers(-2 ** 64, 2 ** 64),
    st.integers(),
    st.integers(-(10 ** 4300 - 1), 10 ** 4300 - 1),
    st.sampled_from([2 ** 63 - 1, -2 ** 63, 2 ** 63, 10 ** 4300 - 1, -(10 ** 4300 - 1)]),
)


@st.composite
def integer(draw):
    v = draw(INTEGERS)
    digits = str(abs(v))
    zeros = "0" * draw(st.sampled_from([0, 0, 0, 1, 3]))
    sign = "-" if v < 0 else draw(st.sampled_from(["", "", "+"]))
    return sign + zeros + digits, v


def _decimal(x: float) -> tuple[str, str, int]:
    """Sign, digits and exponent such that abs(x) == int(digits) * 10**exponent (repr's decimal)."""
    sign = "-" if math.copysign(1.0, x) < 0 else ""
    mant, _, exp = repr(abs(x)).partition("e")
    whole, _, frac = mant.partition(".")
    digits = (whole + frac).lstrip("0") or "0"
    return sign, digits, (int(exp) if exp else 0) - len(frac)


@st.composite
def real_text(draw, x: float) -> str:
    """One of many Part 21 spellings of exactly the decimal repr(x), so it reads as x."""
    sign, digits, exponent = _decimal(x)
    zeros = draw(st.integers(0, 3))  # trailing zeros: more digits, same value
    digits, exponent = digits + "0" * zeros, exponent - zeros
    k = draw(st.integers(1, len(digits)))  # how many digits go before the point
    before = "0" * draw(st.sampled_from([0, 0, 1])) + digits[:k]
    after = digits[k:]
    exp = exponent + len(after)
    sign = sign or draw(st.sampled_from(["", "+"]))
    if exp == 0 and draw(st.booleans()):
        return f"{sign}{before}.{after}"
    e = draw(st.sampled_from(["E", "e"]))
    exp_sign = "-" if exp < 0 else draw(st.sampled_from(["", "+"]))
    pad = "0" * draw(st.sampled_from([0, 0, 1, 2]))
    return f"{sign}{before}.{after}{e}{exp_sign}{pad}{abs(exp)}"


FLOATS = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False),
    st.sampled_from([0.0, -0.0, 5e-324, -5e-324, 2.2250738585072014e-308, 2.225073858507201e-308,
                     1.7976931348623157e308, -1.7976931348623157e308, 1e-320, 0.1, 1e16, 1e22, 1e23]),
    st.integers(0, 2 ** 64 - 1).map(lambda b: struct.unpack("<d", struct.pack("<Q", b))[0])
      .filter(math.isfinite),
)


@st.composite
def real(draw):
    if draw(st.integers(0, 9)) == 0:
        # Decimal text with far more digits or a far larger exponent than a double holds:
        # it reads as the nearest double (correctly rounded), never as inf.
        mant = draw(st.from_regex(r"[0-9]{1,40}\.[0-9]{0,40}", fullmatch=True))
        exp = draw(st.integers(-1200, 300 - len(mant.split(".")[0])))  # below 1E300: finite
        text = f"{mant}E{exp}"
        return text, float(text)
    x = draw(FLOATS)
    return draw(real_text(x)), x


STRING_CHARS = st.characters(exclude_categories=("Cs",))
INVALID_ESCAPE_NEXT = "QZqz019 #"


@st.composite
def string(draw):
    """A Part 21 string literal and its value, each character spelt one of the valid ways."""
    value = draw(st.text(STRING_CHARS, max_size=12))
    out = []
    i = 0
    extra = ""  # characters added to the value by invalid escapes
    while i < len(value):
        c = value[i]
        o = ord(c)
        ways = []
        if c == "'":
            ways.append("''")
        elif c == "\\":
            ways.append("\\\\")
        elif 0x20 <= o < 0x7F:
            ways.append(c)
        if o > 0x7F and c not in "\r\n":
            ways.append(c)  # raw (the file is UTF-8)
        if o <= 0xFF:
            ways.append(f"\\X\\{o:02X}" if draw(st.booleans()) else f"\\X\\{o:02x}")
        if 0xA0 <= o <= 0xFF:
            s_char = chr(o - 0x80)
            ways.append("\\S\\" + ("''" if s_char == "'" else s_char))
            ways.append("\\PA\\\\S\\" + ("''" if s_char == "'" else s_char))
        # A run of characters in one \X2\ or \X4\ group.
        n = draw(st.integers(1, 3))
        run = value[i:i + n]
        if all(ord(ch) <= 0xFFFF for ch in run):
            ways.append("\\X2\\" + "".join(f"{ord(ch):04X}" for ch in run) + "\\X0\\")
        else:
            ways.append("\\X2\\" + run.encode("utf-16-be").hex().upper() + "\\X0\\")
        ways.append("\\X4\\" + "".join(f"{ord(ch):08X}" for ch in run) + "\\X0\\")
        way = draw(st.sampled_from(ways))
        out.append(way)
        i += len(run) if way.startswith(("\\X2\\", "\\X4\\")) else 1
        if draw(st.integers(0, 15)) == 0:
            out.append(draw(st.sampled_from(["\n", "\r\n"])))  # a physical line break: not in the value
    body = "".join(out)
    if draw(st.integers(0, 9)) == 0:
        # A backslash that starts no escape: kept as a literal backslash (with a warning).
        nxt = draw(st.sampled_from(INVALID_ESCAPE_NEXT))
        body += "\\" + nxt
        extra = "\\" + nxt
    return "'" + body + "'", value + extra


@st.composite
def enum(draw):
    name = draw(NAME)
    return f".{name}.", {"enum": name.upper()}


@st.composite
def binary(draw):
    text = draw(st.from_regex(r"[0-3][0-9A-Fa-f]{0,20}", fullmatch=True))
    return f'"{text}"', {"binary": text.upper()}


@st.composite
def reference(draw):
    n = draw(st.one_of(st.integers(0, 50), st.integers(0, 2 ** 70)))
    return f"#{'0' * draw(st.sampled_from([0, 0, 2]))}{n}", {"ref": n}


SIMPLE = st.one_of(
    integer(), real(), string(), enum(), binary(), reference(),
    st.just(("$", None)), st.just(("*", {"derived": True})),
)


def _typed(child):
    @st.composite
    def typed(draw):
        name = draw(st.one_of(NAME, NAME.map(lambda n: "!" + n)))
        text, value = draw(child)
        return f"{name}({text})", {"type": name.upper(), "value": value}
    return typed()


def _list_of(child):
    return st.lists(child, max_size=4).map(
        lambda items: ("(" + ",".join(t for t, _ in items) + ")", [v for _, v in items]))


VALUE = st.recursive(SIMPLE, lambda child: st.one_of(_list_of(child), _typed(child)), max_leaves=12)
ARGS = st.lists(VALUE, max_size=6)


def noisy_join(draw, pieces: list[str]) -> str:
    """Join tokens with random whitespace and comments between them."""
    return "".join(p + draw(gap()) for p in pieces)


@st.composite
def parameter_list(draw, args):
    """``(a,b,...)`` with noise between the top-level tokens."""
    pieces = ["("]
    for k, (text, _) in enumerate(args):
        if k:
            pieces.append(",")
        pieces.append(text)
    pieces.append(")")
    return noisy_join(draw, pieces)


@st.composite
def instance(draw, iid: int):
    zeros = "0" * draw(st.sampled_from([0, 0, 0, 1]))
    head = f"#{zeros}{iid}" + draw(gap()) + "=" + draw(gap())
    if draw(st.integers(0, 4)) == 0:
        parts = []
        texts = []
        for _ in range(draw(st.integers(1, 3))):
            name = draw(NAME)
            args = draw(ARGS)
            parts.append({"type": name.lower(), "args": [v for _, v in args]})
            texts.append(name + draw(gap()) + draw(parameter_list(args)))
        text = head + "(" + draw(gap()) + "".join(texts) + ")" + draw(gap()) + ";"
        return text, {"id": iid, "complex": parts}
    name = draw(st.one_of(NAME, NAME, NAME.map(lambda n: "!" + n)))
    args = draw(ARGS)
    text = head + name + draw(gap()) + draw(parameter_list(args)) + draw(gap()) + ";"
    return text, {"id": iid, "type": name.lower(), "args": [v for _, v in args]}


@st.composite
def part21_file(draw):
    """(text, expected records) of a random valid Part 21 file."""
    ids = draw(st.lists(st.one_of(st.integers(0, 200), st.integers(0, 2 ** 63 - 1)),
                        unique=True, max_size=8))
    instances = [draw(instance(i)) for i in ids]
    desc_text, _ = draw(string())
    name_text, _ = draw(string())
    header = ("ISO-10303-21;" + draw(gap()) + "HEADER;\n"
              f"FILE_DESCRIPTION(({desc_text}),'2;1');\n"
              f"FILE_NAME({name_text},'2026-01-01T00:00:00',(''),(''),'','','');\n"
              "FILE_SCHEMA(('TEST_SCHEMA'));\n")
    if draw(st.booleans()):
        other_text, _ = draw(string())
        header += f"EXTRA_HEADER_ENTITY({other_text},(1,2.5,$));\n"
    header += "ENDSEC;\n"
    # Split the instances into one to three DATA sections, maybe with edition 3 parameters.
    n_sections = draw(st.integers(1, 3))
    cuts = sorted(draw(st.lists(st.integers(0, len(instances)), min_size=n_sections - 1,
                                max_size=n_sections - 1)))
    bounds = [0, *cuts, len(instances)]
    body = []
    for s in range(n_sections):
        if n_sections > 1 or draw(st.integers(0, 3)) == 0:
            body.append(f"DATA(('section {s}'),('TEST_SCHEMA'));\n")
        else:
            body.append("DATA;\n")
        for text, _ in instances[bounds[s]:bounds[s + 1]]:
            body.append(text + draw(st.sampled_from(["\n", "", " ", "\n/* between */\n"])))
        body.append("ENDSEC" + draw(gap()) + ";\n")
        if draw(st.integers(0, 5)) == 0:
            body.append("ANCHOR;\n<anchor_1> = #1;\n<a2> = 'ENDSEC;' /* ENDSEC; */;\nENDSEC;\n")
    text = header + "".join(body) + "END-ISO-10303-21;\n"
    return text, [r for _, r in instances]


# ---------------------------------------------------------------- helpers

def step_text(doc) -> str:
    out = io.StringIO()
    write_step(doc, out)
    return out.getvalue()


def json_text(doc, stream: bool = False) -> str:
    out = io.StringIO()
    write_json(doc, out, stream)
    return out.getvalue()


def same_frame(a, b) -> None:
    assert same_value(a.header, b.header)
    assert [(s.count, s.parameters) for s in a.sections] == [(s.count, s.parameters) for s in b.sections]
    assert a.other_sections == b.other_sections


# ---------------------------------------------------------------- properties

@settings(max_examples=120, **SETTINGS)
@given(part21_file())
def test_part21_json_part21_round_trip(file):
    text, expected = file
    sf = read_step(text)
    records = list(sf.records())
    assert same_records(records, expected)

    # The bulk decoder and the reference tokenizer agree, warnings included.
    careful_file = read_step(text)
    assert same_records(list(careful_file.careful_records()), records)
    assert careful_file.warnings == sf.warnings

    # Part 21 -> JSON -> model -> Part 21 -> records: nothing lost, types exact, -0.0 kept.
    js = json_text(sf)
    assert js == json_text(sf)
    doc = read_json(js)
    same_frame(doc, sf)
    assert same_records(doc.data, records)
    canonical = step_text(doc)
    assert canonical == step_text(doc)
    again = read_step(canonical)
    assert same_records(list(again.records()), records)
    same_frame(again, sf)
    assert not again.warnings

    # The canonical text is a fixed point, whichever document it is written from.
    assert step_text(sf) == canonical
    assert step_text(again) == canonical
    assert json_text(again) == js

    # The JSON Lines stream carries the same model.
    stream = read_json(json_text(sf, stream=True))
    assert same_records(stream.data, records)
    assert step_text(stream) == canonical


@settings(max_examples=300, **SETTINGS)
@given(string())
def test_string_literals_decode_to_their_value(lit):
    text, value = lit
    assert decode_string(text) == value
    assert decode_string(encode_string(value)) == value
    assert encode_string(value).isascii()


@settings(max_examples=300, **SETTINGS)
@given(real())
def test_real_literals_read_and_write_exactly(lit):
    text, value = lit
    x = decode_real(text, 0)
    assert same_value(x, value)
    written = encode_real(x)
    assert "." in written
    assert struct.pack("<d", decode_real(written, 0)) == struct.pack("<d", x)


@settings(max_examples=100, **SETTINGS)
@given(integer())
def test_integers_of_any_size_round_trip(lit):
    text, value = lit
    sf = read_step("ISO-10303-21;HEADER;ENDSEC;DATA;#1=A(" + text + ");ENDSEC;END-ISO-10303-21;")
    records = list(sf.records())
    assert records[0]["args"] == [value] and type(records[0]["args"][0]) is int
    doc = read_json(json_text(sf))
    assert list(read_step(step_text(doc)).records()) == records
