"""The bulk decoder (step/bulk.py) against the careful reference path.

``StepFile.records()`` must give exactly what ``careful_records()`` gives:
the same records (type-exact, sign of zero included), the same warnings,
and on malformed input the same error (message, offset, line, column)
after the same records. Also: ``write_json``'s batched writing gives the
same bytes as writing record by record.
"""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from p105cli.step import StepError, StepSyntaxError, bulk, jsonmodel, read_step
from p105cli.step.jsonmodel import dumps, write_json
from p105cli.step.reader import DataSection

CORPUS = Path("/work/shared/corpus")
HEAD = ("ISO-10303-21;HEADER;FILE_DESCRIPTION((''),'2;1');FILE_NAME('','',(''),(''),'','','');"
        "FILE_SCHEMA(('X'));ENDSEC;DATA;\n")
TAIL = "\nENDSEC;END-ISO-10303-21;"


def p21(instances: str) -> str:
    return HEAD + instances + TAIL


# ---------------------------------------------------------------- comparison helpers

def same(a, b) -> bool:
    """Equal, with the same types all the way down, the same dict key order and sign of zero."""
    if type(a) is not type(b):
        return False
    if type(a) is float:
        if math.isnan(a) or math.isnan(b):
            return False
        return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)
    if type(a) is list:
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if type(a) is dict:
        return list(a) == list(b) and all(same(a[k], b[k]) for k in a)
    return a == b


def drain(iterator):
    """(records until the first error, description of that error or None)."""
    records = []
    try:
        for record in iterator:
            records.append(record)
    except StepError as err:
        return records, (type(err), err.message, getattr(err, "offset", None),
                         getattr(err, "line", None), getattr(err, "column", None), err.source, str(err))
    except Exception as err:  # noqa: BLE001 - compared, not hidden
        return records, (type(err), str(err))
    return records, None


def both_paths(text: str):
    """Run both paths on fresh StepFiles: ((records, error, warnings) bulk, (...) careful)."""
    fast_file = read_step(text, "t.stp")
    careful_file = read_step(text, "t.stp")
    fast = drain(fast_file.records())
    careful = drain(careful_file.careful_records())
    return (*fast, fast_file.warnings), (*careful, careful_file.warnings)


def assert_same_behaviour(text: str):
    (frec, ferr, fwarn), (crec, cerr, cwarn) = both_paths(text)
    assert len(frec) == len(crec), (frec, crec, ferr, cerr)
    for x, y in zip(frec, crec):
        assert same(x, y), (x, y)
    assert ferr == cerr
    assert fwarn == cwarn
    return crec, cerr


def careful_slots(text: str) -> list[int]:
    """Slots the bulk decoder hands to the careful path (their records checked too)."""
    sf = read_step(text, "t.stp")
    used = []
    decode = sf._decode_careful

    def spy(k, warn):
        used.append(k)
        return decode(k, warn)

    sf._decode_careful = spy
    records = list(sf.records())
    reference = list(read_step(text, "t.stp").careful_records())
    assert len(records) == len(reference)
    assert all(same(x, y) for x, y in zip(records, reference))
    return used


# ---------------------------------------------------------------- corpus

def _corpus(folder: str) -> list[Path]:
    path = CORPUS / folder
    if not path.is_dir():
        return []
    return sorted(p for p in path.iterdir() if p.suffix.lower() in (".stp", ".step", ".p21"))


def _check_file(path: Path):
    from p105cli.step import decode_bytes
    text = decode_bytes(path.read_bytes())
    sf = read_step(text, str(path))
    fast = list(sf.records())
    fast_warnings = list(sf.warnings)
    sf2 = read_step(text, str(path))
    careful = list(sf2.careful_records())
    assert len(fast) == len(careful)
    bad = [(x, y) for x, y in zip(fast, careful) if not same(x, y)]
    assert not bad, bad[:3]
    assert fast_warnings == sf2.warnings


@pytest.mark.skipif(not (CORPUS / "authored").is_dir(), reason="no shared corpus")
@pytest.mark.parametrize("path", _corpus("authored"), ids=lambda p: p.name)
def test_authored_corpus(path):
    _check_file(path)


_BIG = _corpus("big")


@pytest.mark.skipif(not _BIG, reason="no big corpus")
def test_one_big_file():
    # The smallest one: about 2 s for both paths.
    _check_file(min(_BIG, key=lambda p: p.stat().st_size))


@pytest.mark.slow
@pytest.mark.skipif(not _BIG, reason="no big corpus")
@pytest.mark.parametrize("path", _BIG, ids=lambda p: p.name[:20])
def test_every_big_file(path):
    _check_file(path)


@pytest.mark.skipif(not _BIG, reason="no big corpus")
def test_big_file_mostly_fast():
    # Performance guard: only complex instances and typed parameters go careful.
    path = min(_BIG, key=lambda p: p.stat().st_size)
    from p105cli.step import decode_bytes
    sf = read_step(decode_bytes(path.read_bytes()), str(path))
    used = []
    decode = sf._decode_careful
    sf._decode_careful = lambda k, warn: (used.append(k), decode(k, warn))[1]
    n = sum(1 for _ in sf.records())
    assert n == len(sf)
    assert len(used) < 20, [sf.index.types[k] for k in used]


# ---------------------------------------------------------------- targeted cases

VALID = {
    "strings": r"""#1=A('','a','it''s','''','''''',' spaced ');""",
    "backslashes": r"""#1=A('C:\\dir\\f','\X2\00E9\X0\','\X\E9','\S\a','\X4\0001F600\X0\','a\qb');""",
    "breaks in strings": "#1=A('line\none','cr\r\nlf','tab\there');\n#2=A('x\r\ny');",
    "punctuation in strings": "#1=A(';','#12','.T.','(',')','$','*','\"q\"','/* c */','\\\\',',');",
    "non-ascii": "#1=A('é€😀','\x01\x1f\x7f');",
    "numbers": "#1=A(0,-0,+5,5,-5,12345678901234567890123,0.,-0.,+0.,1.,-1.,1.5,-2.25E-3,"
               "3.E+000,4.E-000,5.e2,1.E-320,1.5E+99,2.5E-300,0.160801270189,8.580127018922E-02);",
    "leading zeros": "#1=A(007,-007,+007,00.5,-01.5,#0012);",
    "big exponents": "#1=A(1.5E+300,1.E100,-1.7E+308,1.E-400,1.E+0099);",
    "refs and enums": "#1=A(#2,#34,(#5,#6),.T.,.F.,.U.,.t.,.Unspecified.,.A_1.,._X.);",
    "unset and derived": "#1=A($,*,($,*),'$');",
    "binary": '#1=A("0","0FF","3a1",("1"));',
    "empty lists": "#1=A();\n#2=B(());\n#3=C((),((),()));",
    "nesting": "#1=A(" + "(" * 40 + "1" + ")" * 40 + ");",
    "near the nesting limit": "#1=A(" + "(" * 195 + "1" + ")" * 195 + ");",
    "typed parameters": "#1=A(LENGTH_MEASURE(5.),(B(1),C((2))),D('x'),E($));\n#2=F(G(H(.T.)));",
    "complex": "#1=(A(1)B('x',#2)C());\n#2=( NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) LENGTH_UNIT() );",
    "complex in a run": "#1=A(1);\n#2=(B((#1,#3))\nC('a)b(c',(1.5,-2.),.T.) D ( $ ) E());\n#3=F(#2);\n"
                        "#4=(g(1)h(+2));\n#5=A(2);",
    "complex with typed parameters": "#1=(A(LENGTH_MEASURE(1.))B());\n#2=(C((D(1)))E(2));",
    "complex with comments": "#1=(A(1)/*c*/B(2));\n#2=(/*c*/C(3));",
    "comments": "/* before */#1=A(1,/* in ; it's */2);/* between ' ; */\n#2 /*x*/ = B(3);\n#3=C/*y*/(4);",
    "whitespace": "#1 = A ( 1 , 2. , ( #3 , $ ) ) ;\r\n\t#2\t=\tB\t(\t'x'\t)\t;\n#3=C(\n1,\n2\n);",
    "user defined": "#1=!MY_ENTITY(1,'a');\n#2=A(!B(1));",
    "lower case names": "#1=cartesian_point('',(0.,1.,2.));\n#2=Mixed_Case(1);",
    "typed parameter of a list": "#1=A(B((1,2)));",
    "ids": "#10=A(1);\n#2=B(#10);\n#000003=C(1);\n#4=D(#0004);",
}


@pytest.mark.parametrize("instances", VALID.values(), ids=VALID.keys())
def test_valid_cases(instances):
    records, err = assert_same_behaviour(p21(instances))
    assert err is None
    assert records


def test_values_in_detail():
    sf = read_step(p21("#1=A(+5,007,-0.,1.E-320,1.5E+300,-0,'it''s','\\X2\\00E9\\X0\\',\"0ff\",.t.);"))
    (record,) = list(sf.records())
    args = record["args"]
    assert same(args[:3], [5, 7, -0.0]) and math.copysign(1.0, args[2]) == -1.0
    assert same(args[3:], [1e-320, 1.5e300, 0, "it's", "é", {"binary": "0FF"}, {"enum": "T"}])


def test_simple_instances_take_the_fast_path():
    text = p21("\n".join([
        VALID["strings"].replace("#1", "#11"),
        VALID["breaks in strings"].replace("#1", "#21").replace("#2=", "#22="),
        VALID["numbers"].replace("#1", "#31"),
        VALID["refs and enums"].replace("#1", "#41"),
        VALID["unset and derived"].replace("#1", "#51"),
        VALID["empty lists"].replace("#1", "#61").replace("#2", "#62").replace("#3", "#63"),
        VALID["whitespace"].replace("#1", "#71").replace("#2", "#72").replace("#3", "#73"),
        VALID["nesting"].replace("#1", "#81"),
        VALID["lower case names"].replace("#1", "#91").replace("#2", "#92"),
        "#101=A('\\X2\\00E9\\X0\\','C:\\\\x','a\\qb');",
    ]))
    assert careful_slots(text) == []


def test_unusual_instances_go_careful():
    lines = ["#1=A(1);", "#2=(B(1)C(2));", "#3=A(LENGTH_MEASURE(1.));", "#4=A(1,/*c*/2);",
             '#5=A("0F");', "#6=!X(1);", "#7=A(007);", "#8=A(1.E+300);", "#9=A(1);",
             "#10=(B(C(1))D());"]
    used = careful_slots(p21("\n".join(lines)))
    assert used == [*range(2, 8), 9], used  # the complex instance #2 is fast, #10 has a typed parameter


def test_complex_instances_take_the_fast_path():
    text = p21(VALID["complex in a run"] + "\n" + VALID["complex"].replace("#1", "#11").replace("#2", "#12"))
    assert careful_slots(text) == []


def test_comments_between_instances_take_the_fast_path():
    text = p21("#1=A(1);/* it's ; a ( comment */\n#2=A('x');\n/*c*/ #3=A(2/*in*/);/**/#4=B(1);"
               "\nENDSEC;DATA;\n/* second section */#5=A(#1);")
    assert careful_slots(text) == [2]
    assert_same_behaviour(text)


def test_json_failures_are_localized():
    # Instances the JSON parser refuses (here: leading zeros) go careful alone,
    # not the runs around them.
    lines = [f"#{i}=A({'007' if i % 3 == 0 else i},'x',#{i + 1});" for i in range(1, 40)]
    assert careful_slots(p21("\n".join(lines))) == list(range(2, 39, 3))
    lines = [f"#{i}=A('\\X4\\0001\\X0\\');" if i % 5 == 0 else f"#{i}=A('\\X\\E9',{i});" for i in range(1, 30)]
    _, err = assert_same_behaviour(p21("\n".join(lines)))
    assert err is not None and "\\X4\\" in err[1]


def test_warnings_identical():
    text = p21("#1=A('C:\\dir\\file','ok');\n#2=A(1);\n#3=A('x\\qy\\wz');")
    (_, _, fwarn), (_, _, cwarn) = both_paths(text)
    assert fwarn == cwarn and len(cwarn) == 4  # \d, \f (twice: C:\dir\file), \q, \w


# ---------------------------------------------------------------- malformed input

MALFORMED = {
    "missing comma": "#1=A(1 2);",
    "empty parameter": "#1=A(1,,2);",
    "int with exponent": "#1=A(1E5);",
    "negative int with exponent": "#1=A(-12e+3);",
    "unterminated enum": "#1=A(.T);",
    "overflow": "#1=A(1.E400);",
    "overflow big mantissa": "#1=A(" + "9" * 320 + ".);",
    "overflow with exponent": "#1=A(" + "9" * 250 + ".E80);",
    "trailing comma": "#1=A(1,);",
    "leading comma": "#1=A(,1);",
    "missing paren": "#1=A((1,2);",
    "extra paren": "#1=A(1));",
    "two lists": "#1=A(1),(2);",
    "value after list": "#1=A(1)5;",
    "no parameters": "#1=A;",
    "keyword": "#1=A(B);",
    "true": "#1=A(true,false,null);",
    "nan": "#1=A(NaN,Infinity);",
    "plus then minus": "#1=A(+-5);",
    "lone plus": "#1=A(+);",
    "plus space": "#1=A(+ 5);",
    "sum": "#1=A(1+2);",
    "point first": "#1=A(.5);",
    "two points": "#1=A(1..5);",
    "ref with fraction": "#1=A(#12.5);",
    "ref without digits": "#1=A(# 12);",
    "signed ref": "#1=A(-#12);",
    "dollar glued": "#1=A($5);",
    "two strings": "#1=A('a' 'b');",
    "string then number": "#1=A('a'5);",
    "two enums": "#1=A(.A..B.);",
    "enum then letters": "#1=A(.A.B.);",
    "bad escape": "#1=A('\\X4\\0001\\X0\\');",
    "bad utf16": "#1=A('\\X2\\D800\\X0\\');",
    "too deep": "#1=A(" + "(" * 205 + ")" * 205 + ");",
    "unbalanced pair": "#1=A((1);\n#2=B(2));",
    "compensated": "#1=A((1);\n#2=B(2));\n#3=C(2),(4);",
    "form feed": "#1=A(1,\x0c2);",
    "non-ascii in code": "#1=A(1,é);",
    "typed parameter two values": "#1=A(B(1,2));",
    "complex empty": "#1=();",
    "complex part in a list": "#1=(A((1)B(2)));",
    "complex parts with a comma": "#1=(A(1),B(2));",
    "complex string after a part": "#1=(A(1)'x');",
    "complex value after a part": "#1=(A(1)2);",
    "complex part not closed": "#1=(A(1)B(2);",
    "complex closed twice": "#1=(A(1)B(2)));",
    "complex part without arguments": "#1=(A(1)B);",
    "part name after a list": "#1=A((1)B(2));",
    "simple then part": "#1=A(1)B(2);",
    "complex nested": "#1=((A(1)));",
    "semicolon in list": "#1=A(1;2);",
    "garbage after head": "#1=A B(1);",
}


@pytest.mark.parametrize("bad", MALFORMED.values(), ids=MALFORMED.keys())
def test_malformed_same_error(bad):
    good = "\n".join(f"#{i}=P('x',(#{i + 1},{i}.5),.T.);" for i in range(100, 130))
    later = "\n".join(f"#{i}=Q({i});" for i in range(200, 230))
    try:
        read_step(p21(good + "\n" + bad + "\n" + later))
    except StepError:
        pytest.skip("rejected by the index already")
    records, err = assert_same_behaviour(p21(good + "\n" + bad + "\n" + later))
    if err is not None:
        assert len(records) == 30
        assert err[0] is StepSyntaxError


@pytest.mark.parametrize("bad", ["#1=A(1 2);", "#1=A(1,,2);", "#1=A(1E5);", "#1=A(.T);", "#1=A(1.E400);"])
def test_brief_examples_raise_careful_error(bad):
    text = p21("#7=B(1);\n" + bad + "\n#8=C(2);")
    sf = read_step(text, "t.stp")
    it = sf.records()
    assert same(next(it), {"id": 7, "type": "b", "args": [1]})
    with pytest.raises(StepSyntaxError) as got:
        next(it)
    sf2 = read_step(text, "t.stp")
    it2 = sf2.careful_records()
    next(it2)
    with pytest.raises(StepSyntaxError) as want:
        next(it2)
    assert (got.value.message, got.value.offset, got.value.line, got.value.column) == \
        (want.value.message, want.value.offset, want.value.line, want.value.column)
    assert str(got.value) == str(want.value)


def test_chunk_boundaries(monkeypatch):
    # Small chunks: errors, complex and careful instances across chunk edges.
    monkeypatch.setattr(bulk, "CHUNK", 3)
    parts = []
    for i in range(1, 40):
        if i % 7 == 0:
            parts.append(f"#{i}=(A({i})B(.T.));")
        elif i % 5 == 0:
            parts.append(f"#{i}=A(LENGTH_MEASURE({i}.));")
        else:
            parts.append(f"#{i}=A('s{i}',#{i + 1},{i}.,(1,2));")
    assert_same_behaviour(p21("\n".join(parts)))
    parts[23] = "#24=A(1 2);"
    _, err = assert_same_behaviour(p21("\n".join(parts)))
    assert err is not None


def test_many_instances_and_sections():
    body = "\n".join(f"#{i}=A({i},'{i}',#{i + 1},{i}.25E-1);" for i in range(1, 3000))
    text = (HEAD + body + "\nENDSEC;DATA;\n" + "#5000=B(1.);\n#5001=C(#1);" + TAIL)
    records, err = assert_same_behaviour(text)
    assert err is None and len(records) == 3001


# ---------------------------------------------------------------- random instances

_names = st.sampled_from(["A", "b", "CARTESIAN_POINT", "x_1", "LENGTH_MEASURE", "_U"])
_ws = st.sampled_from(["", "", "", " ", "\n", "\r\n", "\t", "  "])
_sep = st.builds(lambda a, b: a + "," + b, _ws, _ws) | st.sampled_from([",", ",", ", ", ",/* c */", " "])
_digits = st.text("0123456789", min_size=1, max_size=6)
_int = st.builds(lambda s, d: s + d, st.sampled_from(["", "", "-", "+"]), _digits)
_exp = st.builds(lambda e, s, d: e + s + d, st.sampled_from(["E", "e"]), st.sampled_from(["", "+", "-"]),
                 st.text("0123456789", min_size=1, max_size=3))
_real = st.builds(lambda s, i, f, e: s + i + "." + f + e, st.sampled_from(["", "", "-", "+"]), _digits,
                  st.text("0123456789", max_size=5), st.sampled_from([""]) | _exp)
_string_piece = st.sampled_from([
    "a", "Z", " ", "''", "\\\\", "\\X2\\00E9\\X0\\", "\\X\\E9", "\\S\\a", "\\P A\\", "\\q", ";", "#12",
    ".T.", "(", ")", "\n", "\r\n", "\t", '"', "é", "/*", "*/", "$", "*", "\\X4\\0001F600\\X0\\",
])
_string = st.lists(_string_piece, max_size=5).map(lambda ps: "'" + "".join(ps) + "'")
_atom = (_int | _real | _string | st.builds(lambda d: "#" + d, _digits)
         | st.sampled_from([".T.", ".F.", ".u.", ".UNSPECIFIED.", "$", "*", '"0FF"', '"1"']))


def _values(depth: int):
    if depth <= 0:
        return _atom
    inner = _values(depth - 1)
    lists = st.builds(lambda vs, seps, w1, w2: "(" + w1 + "".join(
        v + (seps[i % len(seps)] if i < len(vs) - 1 else "") for i, v in enumerate(vs)) + w2 + ")",
        st.lists(inner, max_size=4), st.lists(_sep, min_size=1, max_size=3), _ws, _ws)
    typed = st.builds(lambda n, v: n + "(" + v + ")", _names, inner)
    return st.one_of(_atom, _atom, lists, typed)


_args = st.builds(lambda vs, seps: "(" + "".join(
    v + (seps[i % len(seps)] if i < len(vs) - 1 else "") for i, v in enumerate(vs)) + ")",
    st.lists(_values(3), max_size=5), st.lists(_sep, min_size=1, max_size=3))
_simple = st.builds(lambda n, w1, w2, w3, args: w1 + "=" + w2 + n + w3 + args, _names, _ws, _ws, _ws, _args)
_complex = st.builds(lambda parts: "=(" + " ".join(n + a for n, a in parts) + ")",
                     st.lists(st.tuples(_names, _args), min_size=1, max_size=3))
_instance = st.one_of(_simple, _simple, _simple, _complex)


# The same, restricted to what the fast path takes (no typed parameters,
# binaries, comments, complex instances or leading zeros), so that the
# random instances exercise it rather than the careful path.
_plain_digits = st.from_regex(r"\A(?:0|[1-9][0-9]{0,6})\Z")
_plain_int = st.builds(lambda s, d: s + d, st.sampled_from(["", "", "-", "+"]), _plain_digits)
_plain_real = st.builds(lambda s, i, f, e: s + i + "." + f + e, st.sampled_from(["", "", "-", "+"]),
                        _plain_digits, st.text("0123456789", max_size=5), st.sampled_from([""]) | _exp)
_plain_atom = (_plain_int | _plain_real | _string | st.builds(lambda d: "#" + d, _plain_digits)
               | st.sampled_from([".T.", ".F.", ".u.", ".UNSPECIFIED.", "$", "*"]))
_plain_sep = st.builds(lambda a, b: a + "," + b, _ws, _ws)


def _plain_values(depth: int):
    if depth <= 0:
        return _plain_atom
    inner = _plain_values(depth - 1)
    lists = st.builds(lambda vs, seps, w1, w2: "(" + w1 + "".join(
        v + (seps[i % len(seps)] if i < len(vs) - 1 else "") for i, v in enumerate(vs)) + w2 + ")",
        st.lists(inner, max_size=4), st.lists(_plain_sep, min_size=1, max_size=3), _ws, _ws)
    return st.one_of(_plain_atom, _plain_atom, lists)


_plain_args = st.builds(lambda vs, seps: "(" + "".join(
    v + (seps[i % len(seps)] if i < len(vs) - 1 else "") for i, v in enumerate(vs)) + ")",
    st.lists(_plain_values(3), max_size=6), st.lists(_plain_sep, min_size=1, max_size=3))
_plain_instance = st.builds(lambda n, w1, w2, w3, args: w1 + "=" + w2 + n + w3 + args,
                            _names, _ws, _ws, _ws, _plain_args)


def _mutate(text: str, data) -> str:
    """Sometimes damage one character, to compare the errors too."""
    if not text or not data.draw(st.booleans()):
        return text
    i = data.draw(st.integers(0, len(text) - 1))
    junk = data.draw(st.sampled_from(["", " ", ",", "(", ")", "'", "#", ".", "E", "+", "-", "1", "$", "x", "/*"]))
    return text[:i] + junk + text[i + 1:]


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(_instance, min_size=1, max_size=6), st.data())
def test_random_instances(bodies, data):
    instances = "\n".join(f"#{i + 1}{body};" for i, body in enumerate(bodies))
    text = p21(_mutate(instances, data))
    try:
        read_step(text, "t.stp")
    except StepError:
        return  # the index refused it: nothing to decode
    assert_same_behaviour(text)


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(_plain_instance, min_size=1, max_size=6), st.data())
def test_random_plain_instances(bodies, data):
    instances = "\n".join(f"#{i + 1}{body};" for i, body in enumerate(bodies))
    text = p21(_mutate(instances, data))
    try:
        read_step(text, "t.stp")
    except StepError:
        return
    assert_same_behaviour(text)


# ---------------------------------------------------------------- write_json

def _reference_write_json(doc, fh, stream: bool = False) -> None:
    """write_json as it was: one encoder call per record."""
    frame = jsonmodel._frame(doc)
    write = fh.write
    if stream:
        frame = {"format": jsonmodel.FORMAT, "stream": True, **{k: v for k, v in frame.items() if k != "format"}}
        write(dumps(frame))
        write("\n")
        for record in doc.records():
            write(dumps(record))
            write("\n")
        return
    text = dumps(frame)
    write(text[:-1])
    write(',\n"data":[')
    sep = "\n"
    for record in doc.records():
        write(sep)
        write(dumps(record))
        sep = ",\n"
    write("\n]}\n")


class _Doc:
    def __init__(self, records, fail_after=None):
        self.header = {"file_schema": ["X"]}
        self.sections = [DataSection(None, len(records))]
        self.other_sections = []
        self._records = records
        self._fail_after = fail_after

    def records(self):
        for n, record in enumerate(self._records):
            if n == self._fail_after:
                raise StepSyntaxError("boom", 0)
            yield record


def _outputs(doc, stream):
    got, want = io.StringIO(), io.StringIO()
    errors = []
    for writer, out in ((write_json, got), (_reference_write_json, want)):
        try:
            writer(doc, out, stream)
            errors.append(None)
        except Exception as err:  # noqa: BLE001
            errors.append((type(err), str(err)))
    return got.getvalue(), want.getvalue(), errors


RECORD_SETS = {
    "plain": [{"id": i, "type": "a", "args": [i, float(i) / 3, "é\n\"", {"ref": i}, None]} for i in range(50)],
    "empty": [],
    "one": [{"id": 1, "type": "a", "args": []}],
    "complex": [{"id": 1, "complex": [{"type": "a", "args": [1]}]}, {"id": 2, "type": "b", "args": []}],
    "key order": [{"id": 1, "type": "a", "args": []}, {"type": "b", "id": 2, "args": []},
                  {"id": 3, "type": "c", "args": []}],
    "boundary inside": [{"id": 1, "type": "a", "args": [[{"x": 1}, {"id": 2}]]}, {"id": 3, "type": "b", "args": []}],
    "boundary in string": [{"id": 1, "type": "a", "args": ['},{"id":']}, {"id": 2, "type": "b", "args": []}],
    "not dicts": [{"id": 1, "type": "a", "args": []}, ["id", 2]],
    "empty dict": [{"id": 1, "type": "a", "args": []}, {}],
    "nan": [{"id": 1, "type": "a", "args": [1.0]}, {"id": 2, "type": "a", "args": [math.nan]},
            {"id": 3, "type": "a", "args": []}],
}


@pytest.mark.parametrize("stream", [False, True])
@pytest.mark.parametrize("name", RECORD_SETS)
def test_write_json_same_bytes(monkeypatch, name, stream):
    monkeypatch.setattr(jsonmodel, "_BATCH", 7)
    got, want, errors = _outputs(_Doc(RECORD_SETS[name]), stream)
    assert got == want
    assert errors[0] == errors[1]


@pytest.mark.parametrize("stream", [False, True])
@pytest.mark.parametrize("fail_after", [0, 3, 7, 8, 20])
def test_write_json_records_failing(monkeypatch, fail_after, stream):
    monkeypatch.setattr(jsonmodel, "_BATCH", 7)
    got, want, errors = _outputs(_Doc(RECORD_SETS["plain"], fail_after), stream)
    assert got == want
    assert errors[0] == errors[1] and errors[0] is not None


@pytest.mark.parametrize("stream", [False, True])
def test_write_json_step_file(stream):
    text = p21("\n".join(
        VALID[name].replace("#", f"#{k}0") for k, name in enumerate(VALID, 1) if name != "ids"))
    sf = read_step(text, "t.stp")
    got, want, errors = _outputs(sf, stream)
    assert got == want and errors == [None, None]
    if stream:
        assert len([json.loads(line) for line in got.splitlines()]) == len(sf) + 1
    else:
        assert len(json.loads(got)["data"]) == len(sf)
