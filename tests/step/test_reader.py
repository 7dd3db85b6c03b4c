"""The Part 21 reader and writer against the grammar of ISO 10303-21 edition 3."""

from __future__ import annotations

import io
import math

import pytest

from conftest import p21, same_value
from p105cli.step import (StepStructureError, StepSyntaxError, decode_bytes, read_step, write_json,
                          write_step)
from p105cli.step.lexer import decode_string, encode_real, encode_string


def records(text):
    return list(read_step(text, "t.stp").records())


def args_of(value_text):
    """The decoded args of ``#1=X(<value_text>);``."""
    return records(p21(f"#1=X({value_text});"))[0]["args"]


# ---------------------------------------------------------------- values

@pytest.mark.parametrize("text,expected", [
    ("1", [1]), ("-7", [-7]), ("+5", [5]), ("007", [7]),
    ("1.", [1.0]), ("-0.", [-0.0]), ("1.5E3", [1500.0]), ("1.e-3", [0.001]), ("2.E+2", [200.0]),
    ("1.E-320", [1e-320]), ("12345678901234567890", [12345678901234567890]),
    ("$", [None]), ("*", [{"derived": True}]), ("#12", [{"ref": 12}]),
    (".T.", [{"enum": "T"}]), (".UNLIMITED.", [{"enum": "UNLIMITED"}]), (".milli.", [{"enum": "MILLI"}]),
    ('"0FF"', [{"binary": "0FF"}]), ('"3a"', [{"binary": "3A"}]),
    ("()", [[]]), ("(1,(2,(3)))", [[1, [2, [3]]]]),
    ("LENGTH_MEASURE(1.)", [{"type": "LENGTH_MEASURE", "value": 1.0}]),
    ("parameter_value((1,2))", [{"type": "PARAMETER_VALUE", "value": [1, 2]}]),
    ("A(B(3))", [{"type": "A", "value": {"type": "B", "value": 3}}]),
    ("1 , 2", [1, 2]), ("1,/* comment; with ' quote */2", [1, 2]),
])
def test_values(text, expected):
    got = args_of(text)
    assert same_value(got, expected), got


def test_negative_zero_keeps_its_sign():
    (v,) = args_of("-0.")
    assert v == 0.0 and math.copysign(1.0, v) == -1.0


@pytest.mark.parametrize("lexeme,expected", [
    ("''", ""), ("'it''s'", "it's"), ("'a\\\\b'", "a\\b"),
    ("'\\S\\a'", "\u00e1"),                       # 'a' + 128 in ISO 8859-1
    ("'\\PE\\\\S\\a'", "\u0441"),                 # ISO 8859-5 (Cyrillic): 0xE1 -> U+0441
    ("'\\X\\E9'", "\u00e9"),
    ("'\\X2\\00E900FC\\X0\\'", "\u00e9\u00fc"),
    ("'\\X4\\0001F600\\X0\\'", "\U0001F600"),
    ("'\\X2\\D83DDE00\\X0\\'", "\U0001F600"),       # surrogate pair written as UTF-16
    ("'long\nline'", "longline"),                 # physical line breaks are not content
    ("'a;b#12.T.'", "a;b#12.T."),
    ("'caf\u00e9'", "caf\u00e9"),                 # edition 3: UTF-8 directly
])
def test_string_escapes(lexeme, expected):
    assert decode_string(lexeme) == expected


def test_unknown_backslash_is_kept_with_a_warning():
    warnings = []
    assert decode_string("'C:\\temp'", 0, lambda m, o: warnings.append((m, o))) == "C:\\temp"
    assert warnings


@pytest.mark.parametrize("s", ["", "plain", "it's", "back\\slash", "caf\u00e9", "\u4e2d\u6587",
                               "\U0001F600 smile", "tab\there", "new\nline", "\x7f", "mixed \u00e9\U0001F600x"])
def test_string_encoding_round_trips(s):
    token = encode_string(s)
    assert all(32 <= ord(c) < 127 for c in token)
    assert decode_string(token) == s


@pytest.mark.parametrize("value,text", [
    (1.0, "1."), (-0.0, "-0."), (0.1, "0.1"), (1e-320, "1.E-320"), (1e16, "1.E16"),
    (1.5e-7, "1.5E-07"), (123456.789, "123456.789"), (2.0 ** 0.5, "1.4142135623730951"),
])
def test_real_encoding(value, text):
    assert encode_real(value) == text
    assert float(text) == value


def test_real_encoding_refuses_non_finite():
    for bad in (math.inf, -math.inf, math.nan):
        with pytest.raises(ValueError):
            encode_real(bad)


# ---------------------------------------------------------------- structure

def test_simple_and_complex_instances():
    got = records(p21("#10=(A(1)B()C(#10,'x'));\n#2 = cartesian_point ( 'p' , ( 0. , 1. ) ) ;"))
    assert got == [
        {"id": 10, "complex": [{"type": "a", "args": [1]}, {"type": "b", "args": []},
                               {"type": "c", "args": [{"ref": 10}, "x"]}]},
        {"id": 2, "type": "cartesian_point", "args": ["p", [0.0, 1.0]]},
    ]


def test_comment_between_equals_and_type_is_indexed():
    sf = read_step(p21("#1 = /* why not */ A(1);\n/* between */ #2=B(2);"))
    assert list(sf.index.ids) == [1, 2]
    assert sf.index.types == ["a", "b"]
    assert [r["args"] for r in sf.records()] == [[1], [2]]


def test_lazy_lookup_by_id_decodes_only_what_is_asked():
    sf = read_step(p21("#5=A(1);\n#7=B(#5);\n#9=C(1 2);"))
    # #9 is malformed, but nothing asked for it yet.
    assert sf.record(7) == {"id": 7, "type": "b", "args": [{"ref": 5}]}
    with pytest.raises(StepSyntaxError):
        sf.record(9)
    with pytest.raises(KeyError):
        sf.record(6)


def test_header_fields_and_other_header_entities():
    header = ("ISO-10303-21;HEADER;FILE_DESCRIPTION(('d1','d2'),'2;1');"
              "FILE_NAME('n','2020-01-01T00:00:00',('a'),('o'),'pp','os','au');"
              "FILE_SCHEMA(('S1','S2'));FILE_POPULATION('S1','x',$);ENDSEC;")
    sf = read_step(header + "DATA;#1=A();ENDSEC;END-ISO-10303-21;")
    assert sf.header == {
        "file_description": {"description": ["d1", "d2"], "implementation_level": "2;1"},
        "file_name": {"name": "n", "time_stamp": "2020-01-01T00:00:00", "author": ["a"],
                      "organization": ["o"], "preprocessor_version": "pp",
                      "originating_system": "os", "authorization": "au"},
        "file_schema": ["S1", "S2"],
        "other": [{"type": "file_population", "args": ["S1", "x", None]}],
    }


def test_several_data_sections_and_verbatim_edition3_sections():
    text = ("ISO-10303-21;HEADER;FILE_DESCRIPTION((''),'3;1');FILE_NAME('','',(''),(''),'','','');"
            "FILE_SCHEMA(('S'));ENDSEC;\nANCHOR;\n<a1> = #1;\nENDSEC;\n"
            "DATA('one',('S'));#1=A(1);ENDSEC;\nDATA('two',('S'));#2=B(#1);#3=C();ENDSEC;\n"
            "END-ISO-10303-21;\n")
    sf = read_step(text)
    assert [(s.parameters, s.count) for s in sf.sections] == [(["one", ["S"]], 1), (["two", ["S"]], 2)]
    assert sf.other_sections == [{"keyword": "ANCHOR", "after_data": 0, "text": "\n<a1> = #1;\n"}]
    out = io.StringIO()
    write_step(sf, out)
    again = read_step(out.getvalue())
    assert [(s.parameters, s.count) for s in again.sections] == [(s.parameters, s.count) for s in sf.sections]
    assert again.other_sections == sf.other_sections
    assert list(again.records()) == list(sf.records())


def test_lower_case_keywords_are_read_and_written_upper_case():
    text = ("iso-10303-21;header;file_description((''),'2;1');file_name('','',(''),(''),'','','');"
            "file_schema(('s'));endsec;data;#1=point(.t.);endsec;end-iso-10303-21;")
    out = io.StringIO()
    write_step(read_step(text), out)
    assert "#1=POINT(.T.);" in out.getvalue()
    assert "FILE_SCHEMA(('s'));" in out.getvalue()


# ---------------------------------------------------------------- errors

@pytest.mark.parametrize("body,line,col,fragment", [
    ("#1=A(1);\n#2=B(1 2);", 9, 8, "expected ',' or ')'"),
    ("#1=A(1);\n#2=B('abc);", 9, 6, "unterminated string"),
    ("#1=A(1);\n#2=B(1.E400);", 9, 6, "out of the range"),
    ("#1=A(1);\n#2=B(.T);", 9, 6, "enumeration"),
    ("#1=A(1);\n#2=B(1);#3", 10, 1, "expected '='"),
    ("#1=A(1);\n  x", 9, 3, "expected an instance"),
])
def test_syntax_errors_name_line_and_column(body, line, col, fragment):
    text = p21(body)
    with pytest.raises(StepSyntaxError) as info:
        sf = read_step(text, "bad.stp")
        list(sf.records())
    err = info.value
    assert (err.line, err.column) == (line, col), str(err)
    assert fragment in err.message
    assert str(err).startswith(f"bad.stp:{line}:{col}: ")


def test_missing_endsec_and_end_marker():
    with pytest.raises(StepSyntaxError, match="ENDSEC"):
        read_step(p21("#1=A();").replace("\nENDSEC;\nEND-ISO-10303-21;\n", ""))
    with pytest.raises(StepSyntaxError):
        read_step(p21("#1=A();").replace("END-ISO-10303-21;\n", ""))


def test_duplicate_ids_name_the_instance():
    with pytest.raises(StepStructureError) as info:
        read_step(p21("#1=A();\n#2=B();\n#1=C();"), "dup.stp")
    assert str(info.value) == "dup.stp: #1: instance name used more than once"


def test_sparse_ids_use_the_dictionary_lookup():
    sf = read_step(p21("#1=A();\n#9000000000=B(#1);\n#1=C();".rsplit("\n", 1)[0]))
    assert sf.record(9000000000)["args"] == [{"ref": 1}]
    with pytest.raises(StepStructureError):
        read_step(p21("#1=A();\n#9000000000=B(#1);\n#9000000000=C();"))


def test_nesting_limit_is_a_clean_error():
    deep = "(" * 100_000 + ")" * 100_000
    with pytest.raises(StepSyntaxError, match="nested deeper"):
        list(read_step(p21(f"#1=A({deep});")).records())


def test_latin1_files_are_read():
    raw = p21("#1=A('caf\u00e9');").encode("latin-1")
    assert records(decode_bytes(raw))[0]["args"] == ["caf\u00e9"]


def test_raw_8bit_bytes_are_read_byte_for_byte_and_reported_once_with_the_first_place():
    # GBK from a SolidWorks export: bytes that are not UTF-8
    gbk = "\u4e2a\u4eba".encode("gbk")
    raw = p21("#1=A('x');\n#2=A('" + "\u00e9".encode("latin-1").decode("latin-1") + "');").encode("latin-1")
    raw = raw.replace(b"'x'", b"'" + gbk + b"'")
    sf = read_step(decode_bytes(raw), "t.stp")
    assert sf.record(1)["args"] == [gbk.decode("latin-1")]  # kept, byte for byte
    assert sf.not_utf8.count == len(gbk) + 1
    (message, offset), = sf.warnings
    line, col = sf.line_col(offset)
    assert (line, col) == (8, 7)  # the first raw byte, inside #1's string
    assert message.startswith(f"not UTF-8: {len(gbk) + 1} raw 8-bit bytes (the first here)")
    details = list(sf.not_utf8.details(sf.text))
    assert [sf.line_col(o) for _, o in details] == [(8, 7), (9, 7)]
    assert "as GBK: '\u4e2a\u4eba'" in details[0][0] and "E9" in details[1][0]


def test_utf8_files_give_no_encoding_warning():
    raw = p21("#1=A('\u00e9\u4e2a');").encode("utf-8")
    sf = read_step(decode_bytes(raw), "t.stp")
    assert sf.not_utf8 is None and sf.warnings == []
    assert sf.record(1)["args"] == ["\u00e9\u4e2a"]


def test_writer_is_canonical_and_deterministic():
    text = p21("#3 = A ( 1.000000000000000E-01 , 'x''y' , ( #1 , $ ) , * ) ;\n#1=B(+007,-0.);")
    first = io.StringIO()
    write_step(read_step(text), first)
    assert "#3=A(0.1,'x''y',(#1,$),*);\n#1=B(7,-0.);\n" in first.getvalue()
    second = io.StringIO()
    write_step(read_step(first.getvalue()), second)
    assert first.getvalue() == second.getvalue()


def test_json_writer_document_shape():
    out = io.StringIO()
    write_json(read_step(p21("#1=A(1.);")), out)
    lines = out.getvalue().splitlines()
    assert lines[0].startswith('{"format":"p105/1","header":{')
    assert lines[1:] == ['"data":[', '{"id":1,"type":"a","args":[1.0]}', "]}"]
