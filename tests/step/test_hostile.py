"""Hostile input never crashes or hangs.

Each case gives a clean diagnostic (exit 2, one line, FILE:LINE:COL or #id,
no traceback) or the right value, in bounded time and memory; no NaN or inf
ever enters the model silently. Cases go through the CLI in a subprocess
with a timeout, so a hang fails the test instead of the run; a few exhaustive
sweeps (every truncation point) also run in process, where they are cheap.

hostile JSON models are clean errors too (jsonmodel.py).
"""

from __future__ import annotations

import filecmp
import hashlib
import io
import json
import random
import resource
import time

import pytest

from conftest import (LOCATED, clean_error, clean_exit, cli_in_process, line_col_of, p21, read_all, run_cli,
                      same_records, same_value)

from p105cli.step import StepError, decode_bytes, read_json, read_step, write_json, write_step


def parse(text, *args, **kw):
    """``p105 parse`` of a Part 21 (or JSON) text given on stdin: in this process, or in a
    process of its own when the test sets a time limit (a hang must fail, not stall)."""
    run = run_cli if "timeout" in kw else cli_in_process
    return run("parse", *args, "-", input=text, **kw)


def parsed_records(proc) -> list:
    clean_exit(proc, 0)
    return json.loads(proc.stdout)["data"]


def error_line(proc, *needles) -> str:
    line = clean_error(proc, *needles)
    assert LOCATED.match(line), f"the error does not say where: {line!r}"
    return line


def at(text: str, needle: str, delta: int = 0) -> str:
    """``:LINE:COL:`` of the first ``needle`` in ``text`` (plus ``delta`` characters)."""
    return f":{line_col_of(text, text.index(needle) + delta)}:"


# ---------------------------------------------------------------- nesting

def test_100k_deep_nesting_is_a_clean_error_fast():
    depth = 100_000
    text = p21("#1=A(" + "(" * depth + ")" * depth + ");")
    t0 = time.monotonic()
    proc = parse(text)
    assert time.monotonic() - t0 < 20
    error_line(proc, "nested deeper than 200", at(text, "#1=A(", 4 + 200))  # the 201st "("


def test_100k_deep_unclosed_nesting_is_a_clean_error():
    text = p21("#1=A(" + "(" * 100_000)
    error_line(parse(text), ":")


def test_100k_deep_nesting_in_the_header_is_a_clean_error():
    text = p21("#1=A();").replace("FILE_SCHEMA(('TEST_SCHEMA'))",
                                  "FILE_SCHEMA(" + "(" * 100_000 + ")" * 100_000 + ")")
    error_line(parse(text), "nested deeper than 200")


def test_deepest_allowed_nesting_round_trips():
    # The limit counts the argument list itself: 199 more levels are allowed.
    text = p21("#1=A(" + "(" * 199 + "1" + ")" * 199 + ");\n#2=B(" + "X(" * 199 + "2" + ")" * 199 + ");")
    records = parsed_records(parse(text))
    proc = cli_in_process("export", "--to", "p21", "-", input=json.dumps({"format": "p105/1", "header": {},
                                                                     "data": records}))
    clean_exit(proc, 0)
    assert same_records(parsed_records(parse(proc.stdout)), records)


# ---------------------------------------------------------------- a huge string

def _canonical_frame() -> tuple[str, str]:
    """A canonical Part 21 text split around the one string value of #1."""
    sf = read_step(p21("#1=BIG('@');"))
    out = io.StringIO()
    write_step(sf, out)
    pre, post = out.getvalue().split("'@'")
    return pre + "'", "'" + post


# One block as written in Part 21 (canonical escapes) and as decoded.
P21_BLOCK = ("Lorem ipsum ''quoted'' \\\\ back \\X2\\00E9\\X0\\ 0123456789 ;/*x*/#1 "
             "\\X4\\0001F600\\X0\\ abcdefghijklmnopqrstuvwxyz ")
VALUE_BLOCK = ("Lorem ipsum 'quoted' \\ back \u00e9 0123456789 ;/*x*/#1 "
               "\U0001F600 abcdefghijklmnopqrstuvwxyz ")


def _huge_string_round_trip(tmp_path, size: int, timeout: float) -> None:
    rss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    pre, post = _canonical_frame()
    n = size // len(P21_BLOCK) + 1
    src = tmp_path / "big.stp"
    chunk = P21_BLOCK * 1000
    with open(src, "w", encoding="ascii", newline="\n") as fh:
        fh.write(pre)
        for _ in range(n // 1000):
            fh.write(chunk)
        fh.write(P21_BLOCK * (n % 1000))
        fh.write(post)
    assert src.stat().st_size >= size

    # Part 21 -> JSON: the value, checked by hash without loading the output.
    js = tmp_path / "big.json"
    clean_exit(run_cli("parse", src, "-o", js, timeout=timeout), 0)
    expected = hashlib.sha256()
    piece = json.dumps(VALUE_BLOCK, ensure_ascii=False)[1:-1].encode()
    for _ in range(n // 1000):
        expected.update(piece * 1000)
    expected.update(piece * (n % 1000))
    prefix, suffix = b'{"id":1,"type":"big","args":["', b'"]}\n]}\n'
    total = js.stat().st_size
    with open(js, "rb") as fh:
        head = fh.read(4096)
        start = head.index(prefix) + len(prefix)
        fh.seek(total - len(suffix))
        assert fh.read() == suffix
        fh.seek(start)
        got, left = hashlib.sha256(), total - len(suffix) - start
        while left:
            block = fh.read(min(left, 1 << 22))
            got.update(block)
            left -= len(block)
    assert got.hexdigest() == expected.hexdigest()

    # JSON -> Part 21, and Part 21 -> Part 21: the canonical input comes back byte for byte.
    back = tmp_path / "back.stp"
    clean_exit(run_cli("export", "--to", "p21", js, "-o", back, timeout=timeout), 0)
    assert filecmp.cmp(src, back, shallow=False)
    js.unlink()
    again = tmp_path / "again.stp"
    clean_exit(run_cli("export", "--to", "p21", src, "-o", again, timeout=timeout), 0)
    assert filecmp.cmp(src, again, shallow=False)
    # The test itself streams everything: its own peak memory stays far below the file size.
    grown_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - rss_before
    assert grown_kb < 64 * 1024 + size // 1024 // 10


def test_5mb_string_literal_round_trips(tmp_path):
    _huge_string_round_trip(tmp_path, 5_000_000, timeout=60)


@pytest.mark.slow
def test_100mb_string_literal_round_trips(tmp_path):
    _huge_string_round_trip(tmp_path, 100_000_000, timeout=300)


def test_string_wrapped_over_lines_drops_the_line_breaks():
    text = p21("#1=A('abc\r\ndef\n''ghi''\n');")
    assert parsed_records(parse(text)) == [{"id": 1, "type": "a", "args": ["abcdef'ghi'"]}]


# ---------------------------------------------------------------- references

def test_reference_cycles_are_fine_and_round_trip():
    text = p21("#1=A(#2);\n#2=B(#1,(#2,#3));\n#3=(C(#3)D(#1));\n#4=E(#4);")
    proc = parse(text)
    err = clean_exit(proc, 0)
    assert "warning" not in err
    records = json.loads(proc.stdout)["data"]
    assert records[0] == {"id": 1, "type": "a", "args": [{"ref": 2}]}
    back = cli_in_process("export", "--to", "p21", "-", input=proc.stdout)
    clean_exit(back, 0)
    assert same_records(parsed_records(parse(back.stdout)), records)
    again = cli_in_process("export", "--to", "p21", "-", input=back.stdout)
    assert again.stdout == back.stdout


def test_dangling_references_warn_naming_the_instance():
    text = p21("#1=A(#2);\n#3=B('#9 in a string',#1,(#7),/* #8 */ #1);")
    proc = parse(text)
    err = clean_exit(proc, 0)
    warnings = [ln for ln in err.splitlines() if "warning" in ln]
    assert warnings == [
        "p105: warning: <stdin>: #1: reference to #2, which is not in the file",
        "p105: warning: <stdin>: #3: reference to #7, which is not in the file",
    ]
    assert len(json.loads(proc.stdout)["data"]) == 2


def test_dangling_references_from_json_warn_too():
    doc = {"format": "p105/1", "header": {}, "data": [{"id": 5, "type": "a", "args": [{"ref": 6}]}]}
    err = clean_exit(cli_in_process("export", "--to", "p21", "-", input=json.dumps(doc)), 0)
    assert "#5: reference to #6" in err


def test_many_dangling_references_are_reported_in_linear_time():
    # Was one regex pass over the whole file per missing id: minutes for this.
    n = 30_000
    text = p21("#1=A((" + ",".join(f"#{i}" for i in range(2, n)) + "));\n#" + str(n) + "=B(#1);")
    t0 = time.monotonic()
    proc = parse(text, timeout=60)
    assert time.monotonic() - t0 < 20
    err = clean_exit(proc, 0)
    assert err.count("warning") == n - 2
    assert "#1: reference to #29999," in err


# ---------------------------------------------------------------- truncated and malformed frames

SAMPLE = p21(
    "#1=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));\n"
    "/* a comment; with 'quotes' */\n"
    "#2=CARTESIAN_POINT('p''t \\X2\\00E9\\X0\\',(0.,-1.5E-3,2.),$,\"0FF\",MEASURE(1.));\n"
    "#3 = AXIS2_PLACEMENT_3D ( 'frame' , #2 , $ , #1 ) ;\n"
    "#10=REVOLUTE_PAIR('j1',#3,#3,.F.,.T.,(1,(2,(3))));"
).replace("ENDSEC;\nEND-ISO", "ENDSEC;\nANCHOR;\n<a1>=#2;\nENDSEC;\nEND-ISO")


def test_sample_is_valid():
    assert len(read_all(SAMPLE)[1]) == 4


def test_every_truncation_is_a_clean_error_in_process():
    """Cut the file at every character: each cut is an error with a place, or a whole file."""
    end = SAMPLE.index("END-ISO-10303-21;") + len("END-ISO-10303-21;")
    for cut in range(len(SAMPLE)):
        text = SAMPLE[:cut]
        try:
            sf, records = read_all(text)
            out = io.StringIO()
            write_step(sf, out)
            write_json(sf, io.StringIO())
        except StepError as err:
            assert cut < end, (cut, str(err))
            assert LOCATED.match("p105: error: " + str(err)), (cut, str(err))
        else:
            assert cut >= end, f"a file cut at {cut} reads as valid: {text[-40:]!r}"


@pytest.mark.parametrize("frac", [i / 23 for i in range(23)])
def test_truncated_files_exit_2_through_the_cli(frac):
    cut = int(len(SAMPLE) * frac)
    proc = parse(SAMPLE[:cut])
    error_line(proc)


def test_truncated_files_at_interesting_places_exit_2():
    for needle in ("'p''t", "/* a comment", "\"0FF", ".MILLI", "(1,(2,", "<a1>", "ENDSEC;\nEND", "-1.5E"):
        cut = SAMPLE.index(needle) + 2
        error_line(parse(SAMPLE[:cut]))


def test_missing_data_endsec():
    text = SAMPLE.replace("ENDSEC;\nANCHOR", "ANCHOR")
    error_line(parse(text), "expected an instance", at(text, "ANCHOR"))
    text = p21("#1=A();").replace("\nENDSEC;\nEND-ISO-10303-21;\n", "\n")
    error_line(parse(text), "DATA section is not closed by ENDSEC;")


def test_missing_header_endsec():
    text = p21("#1=A();").replace("ENDSEC;\nDATA;", "DATA;")
    error_line(parse(text), at(text, "DATA;", 4))  # DATA read as a header entity: "expected '('"


def test_missing_end_iso():
    text = p21("#1=A();").replace("END-ISO-10303-21;\n", "")
    error_line(parse(text), "END-ISO-10303-21", "end of input")
    text = p21("#1=A();").replace("END-ISO-10303-21;", "END-ISO-10303-21")
    error_line(parse(text), "expected ';' after END-ISO-10303-21")


def test_unterminated_comments_are_errors_in_linear_time():
    # Each '/*' used to rescan the rest of the text: 25 s for 90 kB.
    for text in (p21("#1=A(" + "/*x" * 30_000 + ");"),
                 p21("#1=A();").replace("ENDSEC;\nEND", "ENDSEC;\nANCHOR;" + "/*x" * 30_000 + "\nENDSEC;\nEND"),
                 p21("#1=A();\n" + "/*x" * 30_000)):
        t0 = time.monotonic()
        proc = parse(text)
        assert time.monotonic() - t0 < 20
        error_line(proc, "unterminated comment")


def test_unterminated_string_in_an_anchor_section():
    text = p21("#1=A();").replace("ENDSEC;\nEND", "ENDSEC;\nANCHOR;<a>='x;\nENDSEC;\nEND")
    error_line(parse(text), "unterminated string", at(text, "'x;"))


def test_duplicate_instance_ids_name_the_id():
    error_line(parse(p21("#1=A();\n#2=B();\n#1=C();")), "#1:", "more than once")
    error_line(parse(p21("#7=A();\n#007=B();")), "#7:", "more than once")
    error_line(parse(p21("#5000000000=A();\n#5000000000=B();")), "#5000000000:")  # sparse ids


def test_duplicate_ids_in_json_name_the_id():
    doc = {"format": "p105/1", "header": {},
           "data": [{"id": 3, "type": "a", "args": []}, {"id": 3, "type": "b", "args": []}]}
    error_line(cli_in_process("export", "-", input=json.dumps(doc)), "#3", "/data/1")


# ---------------------------------------------------------------- binary garbage

def test_random_bytes_exit_2():
    rng = random.Random(105)
    for n in (1, 17, 4096):
        error_line(parse(bytes(rng.randrange(256) for _ in range(n))))


def test_random_bytes_in_the_data_section_exit_2():
    rng = random.Random(21)
    head, tail = p21("@").encode().split(b"@")
    garbage = bytes(rng.randrange(256) for _ in range(2000)).replace(b"#", b"").replace(b"E", b"")
    error_line(parse(head + b"#1=A();\n" + garbage + tail))


def test_nul_bytes_exit_2():
    error_line(parse(b"\0" * 1000))
    text = p21("#1=A(\0);")
    error_line(parse(text), "U+0000", at(text, "\0"))
    text = p21("#1=A();\0")
    error_line(parse(text), "U+0000", at(text, "\0"))


def test_nul_in_a_string_is_a_value():
    text = p21("#1=A('a\0b');")
    assert parsed_records(parse(text))[0]["args"] == ["a\0b"]


def test_invalid_utf8_outside_strings_exit_2():
    raw = p21("#1=A(@);").encode().replace(b"@", b"\xff\xfe")
    error_line(parse(raw), "unexpected character")
    error_line(parse(b"\xef\xbb\xbf\xc3\x28" + p21("#1=A();").encode()), "neither a Part 21 file")


def test_invalid_utf8_in_a_string_is_read_as_latin1():
    # Documented: a text that is not UTF-8 is ISO 8859-1 (older writers).
    raw = p21("#1=A('@');").encode().replace(b"@", b"caf\xe9 \xff")
    assert decode_bytes(raw).count("caf\u00e9 \u00ff") == 1
    assert parsed_records(parse(raw))[0]["args"] == ["caf\u00e9 \u00ff"]


def test_utf16_and_empty_inputs_exit_2():
    error_line(parse(p21("#1=A();").encode("utf-16")))
    error_line(parse(b""))
    error_line(parse(b"   \n\t"))


# ---------------------------------------------------------------- numbers

def test_real_overflow_is_an_error_naming_line_col():
    for lit in ("1.E400", "-1.E400", "9" * 400 + ".E0", "1.E99999999999999999999", "0.1E310"):
        text = p21(f"#1=A(0.,\n  {lit});")
        error_line(parse(text), "out of the range of a double", at(text, lit))


def test_reals_keep_their_exact_values():
    text = p21("#1=A(-0.,0.,1.E-320,4.9E-324,1.E-400,1.7976931348623157E308,-2.2250738585072014E-308,"
               "0.1,1.E16,123456789012345678901234567890.,1." + "0" * 5000 + "1)\n;")
    proc = parse(text)
    args = parsed_records(proc)[0]["args"]
    expected = [-0.0, 0.0, 1e-320, 5e-324, 0.0, 1.7976931348623157e308, -2.2250738585072014e-308,
                0.1, 1e16, 1.2345678901234568e29, 1.0]
    assert same_value(args, expected)
    back = cli_in_process("export", "--to", "p21", "-", input=proc.stdout)
    clean_exit(back, 0)
    assert "#1=A(-0.,0.,1.E-320,5.E-324,0.,1.7976931348623157E308,-2.2250738585072014E-308," \
           "0.1,1.E16,1.2345678901234568E29,1.);" in back.stdout.decode()
    assert same_value(parsed_records(parse(back.stdout))[0]["args"], expected)


def test_big_integers_round_trip_and_too_long_ones_are_errors():
    big = 10 ** 4299 - 1
    text = p21(f"#1=A({big},-{big},-0,+5,{'0' * 5000}7,#{'0' * 5000}1);")
    proc = parse(text)
    args = parsed_records(proc)[0]["args"]
    assert args == [big, -big, 0, 5, 7, {"ref": 1}]
    back = cli_in_process("export", "--to", "p21", "-", input=proc.stdout)
    clean_exit(back, 0)
    assert parsed_records(parse(back.stdout))[0]["args"] == args
    # Longer than the interpreter converts (quadratic time): an error at the number.
    for body, col in ((f"#1=A({'1' * 5000});", 6), (f"#1=A(-{'1' * 5000});", 6),
                      (f"#1=A(#{'1' * 5000});", 7)):
        error_line(parse(p21(body)), "integer of 5000 digits is too long", f":8:{col}:")


def test_instance_names_beyond_64_bits_are_errors():
    for body in ("#9223372036854775808=A();", "#" + "1" * 5000 + "=A();", "#1=A();\n#99999999999999999999=B();",
                 "#1=A();\n#99999999999999999999 /* */ =B();"):
        text = p21(body)
        error_line(parse(text), "too large", at(text, "#9" if "#9" in body else "#1"))
    assert parsed_records(parse(p21("#9223372036854775807=A();")))[0]["id"] == 2 ** 63 - 1


# ---------------------------------------------------------------- strings

STRINGS = [
    ("''", ""),
    ("''''", "'"),
    ("'it''s'", "it's"),
    ("'a\\\\b'", "a\\b"),
    ("'\\S\\A'", "\u00c1"),
    ("'\\PA\\\\S\\A'", "\u00c1"),
    ("'\\PB\\\\S\\!'", "\u0104"),                     # ISO 8859-2
    ("'\\PE\\\\S\\?'", "\u041f"),                     # ISO 8859-5
    ("'\\S\\'''", "\u00a7"),                          # \S\ then a quote (written '')
    ("'\\X\\E9\\X\\0A'", "\u00e9\n"),
    ("'\\X2\\00E9044F\\X0\\'", "\u00e9\u044f"),
    ("'\\X2\\D83DDE00\\X0\\'", "\U0001F600"),          # a surrogate pair in UCS-2/UTF-16
    ("'\\X4\\0001F6000010FFFF\\X0\\'", "\U0001F600\U0010FFFF"),
    ("'\\X2\\\\X0\\'", ""),
    ("'a\\X2\\0041\\X0\\\\X4\\00000042\\X0\\c'", "aABc"),
    ("'/* not a comment */ ; #1 \"0F\"'", "/* not a comment */ ; #1 \"0F\""),
    ("'\u00e9\u4e2d\U0001F600'", "\u00e9\u4e2d\U0001F600"),  # raw UTF-8
]


def test_every_escape_decodes_and_round_trips():
    text = p21("\n".join(f"#{k}=S({lit});" for k, (lit, _) in enumerate(STRINGS, 1)))
    proc = parse(text)
    err = clean_exit(proc, 0)
    assert "warning" not in err
    records = json.loads(proc.stdout)["data"]
    for record, (lit, value) in zip(records, STRINGS):
        assert record["args"] == [value], lit
    back = cli_in_process("export", "--to", "p21", "-", input=proc.stdout)
    clean_exit(back, 0)
    assert back.stdout.isascii()
    assert parsed_records(parse(back.stdout)) == records


INVALID_ESCAPES = ["'\\Q'", "'\\'", "'\\X\\G0'", "'\\X2\\00E\\X0\\'", "'\\X2\\00E9'", "'\\P\\'",
                   "'\\pa\\'", "'\\S\\\u00e9'", "'C:\\temp\\x'"]


def test_invalid_escapes_warn_with_line_col_and_keep_the_backslash():
    text = p21("\n".join(f"#{k}=S({lit});" for k, lit in enumerate(INVALID_ESCAPES, 1)))
    proc = parse(text)
    err = clean_exit(proc, 0)
    records = json.loads(proc.stdout)["data"]
    for record, lit in zip(records, INVALID_ESCAPES):
        assert "\\" in record["args"][0], lit
    sf = read_step(text)
    list(sf.records())
    for message, offset in sf.warnings:
        assert f"<stdin>:{line_col_of(text, offset)}: {message}" in err
        assert text[offset] == "\\"
    assert err.count("warning") >= len(INVALID_ESCAPES)


def test_many_warnings_are_capped_and_located_fast():
    # Every warning used to be kept (gigabytes for a big file of stray backslashes) and
    # located by recounting lines from the start of the file (minutes for this one).
    n = 100_000
    text = p21("\n".join(f"#{i}=A('\\Q','{'y' * 50}');" for i in range(1, n + 1)))
    t0 = time.monotonic()
    proc = parse(text, timeout=120)
    assert time.monotonic() - t0 < 30
    lines = clean_exit(proc, 0).splitlines()
    assert len(lines) == 1001
    assert lines[999] == (f"p105: warning: <stdin>:{line_col_of(text, text.index('#1000=') + 9)}: "
                          "backslash that starts no escape kept as a literal backslash")
    assert lines[1000] == f"p105: warning: <stdin>: {n - 1000} more warnings like these not shown"


def test_a_100k_stray_backslashes_string_keeps_its_value():
    text = p21("#1=A('" + "\\Q" * 100_000 + "');")
    proc = parse(text)
    assert parsed_records(proc)[0]["args"] == ["\\Q" * 100_000]
    assert proc.stderr.decode().count("\n") == 1001


@pytest.mark.parametrize("literal, message", [
    ("'\\X2\\D800\\X0\\'", "not valid UCS-2/UTF-16"),       # lone surrogate
    ("'\\X2\\DC00D800\\X0\\'", "not valid UCS-2/UTF-16"),
    ("'\\X4\\0000D800\\X0\\'", "not valid UCS-4"),
    ("'\\X4\\00110000\\X0\\'", "not valid UCS-4"),          # beyond U+10FFFF
    ("'\\X4\\FFFFFFFF\\X0\\'", "not valid UCS-4"),
    ("'\\X4\\0041\\X0\\'", "groups of eight hex digits"),
])
def test_invalid_unicode_escapes_are_errors(literal, message):
    text = p21(f"#1=A(1,{literal});")
    error_line(parse(text), message, ":8:")


@pytest.mark.parametrize("body, col", [
    ("#1=A('abc);", 6),
    ("#1=A(1,'abc''", 13),  # 'abc' then an unterminated 
    ("#1=A(');\n#2=B();", 6),
])
def test_unterminated_strings_are_errors(body, col):
    error_line(parse(p21(body)), "unterminated string", f":8:{col}:")


def test_a_string_that_runs_on_is_an_error_somewhere_later():
    # The quote of 'it''s is doubled: the string runs on into #2 and stops at its quote.
    error_line(parse(p21("#1=A('it''s);\n#2=B('x');")), ":9:")


def test_unterminated_string_in_the_header():
    text = p21("#1=A();").replace("'2;1'", "'2;1")  # runs on to the next quote
    error_line(parse(text))
    text = p21("#1=A();").replace("FILE_SCHEMA(('TEST_SCHEMA'));", "FILE_SCHEMA(('TEST_SCHEMA));")
    error_line(parse(text), "unterminated string", at(text, "'TEST"))


@pytest.mark.parametrize("body, message", [
    ("#1=A(.T);", "malformed enumeration"),
    ("#1=A(\"4F\");", "malformed binary"),
    ("#1=A(#);", "malformed instance name"),
    ("#1=A(1,);", "expected a parameter"),
    ("#1=A(X(1,2));", "takes exactly one value"),
    ("#1=A(X());", "expected a parameter"),
    ("#1=();", "complex instance with no entity"),
    ("#1=A()B();", "';' at the end of the instance"),
    ("#1=A(1)\n#2=B();", "';' at the end of the instance, found '#2'"),
    ("#1=A(1;2);", "expected an instance"),  # the instance ends at the first ';'
    ("#1=A(1 /* c */;", "expected ',' or ')'"),
    ("#1=A(\u00e9);", "unexpected character"),
    ("#1=A(\u2028);", "U+2028"),
    ("#1=A(1.E);", "expected ',' or ')'"),
])
def test_malformed_values_are_errors(body, message):
    text = p21(body)
    error_line(parse(text), message, ":9:1:" if "found '#2'" in message else ":8:")


# ---------------------------------------------------------------- hostile JSON

def export(doc: str | bytes | dict, to: str = "p21"):
    if isinstance(doc, dict):
        doc = json.dumps(doc)
    return cli_in_process("export", "--to", to, "-", input=doc)


def frame(**kw) -> dict:
    return {"format": "p105/1", "header": {}, "data": [], **kw}


def rec(*args, **kw) -> dict:
    return {"format": "p105/1", "header": {}, "data": [{"id": 1, "type": "a", "args": list(args), **kw}]}


def test_json_100k_deep_nesting():
    deep = "[" * 100_000 + "]" * 100_000
    for text in ('{"format":"p105/1","header":{},"data":' + deep + "}",
                 '{"format":"p105/1","header":{},\n"data":[{"id":1,"type":"a","args":' + deep + "}]}",
                 '{"stream":true,"format":"p105/1","x":' + deep + "}",
                 '{"format":"p105/1","stream":true,"header":{}}\n{"id":1,"type":"a","args":' + deep + "}\n"):
        for to in ("p21", "json"):
            clean_error(export(text, to), "nested too deeply")


def test_json_nesting_beyond_the_model_limit():
    deep = json.loads("[" * 250 + "]" * 250)
    error_line(export(rec(deep)), "nested deeper than 200", "/data/0/args/0")


def test_json_typed_parameter_nesting_beyond_the_model_limit():
    typed = 1
    for _ in range(250):
        typed = {"type": "X", "value": typed}
    error_line(export(rec(typed)), "nested deeper than 200")


@pytest.mark.parametrize("literal", ["NaN", "Infinity", "-Infinity", "1e400", "-1E999"])
def test_json_non_finite_reals_never_enter_the_model(literal):
    for text in ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[1.5,%s]}]}' % literal,
                 '{"format":"p105/1","header":{"file_name":{"name":"","time_stamp":"","author":[%s],'
                 '"organization":[],"preprocessor_version":"","originating_system":"",'
                 '"authorization":""}},"data":[]}' % literal,
                 '{"format":"p105/1","header":{},"data":[],"data_sections":'
                 '[{"parameters":[%s],"count":0}]}' % literal,
                 '{"format":"p105/1","stream":true,"header":{}}\n'
                 '{"id":1,"type":"a","args":[{"type":"X","value":%s}]}' % literal):
        for to in ("p21", "json"):
            error_line(export(text, to), "real is not finite")


def test_json_lone_surrogates_in_values():
    for text in ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":["ok\\ud800"]}]}',
                 '{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[["\\udfff"]]}]}',
                 '{"format":"p105/1","header":{"file_description":{"description":["\\ud800"],'
                 '"implementation_level":"2;1"}},"data":[]}'):
        for to in ("p21", "json"):
            error_line(export(text, to), "surrogate")


def test_json_surrogate_pairs_are_characters():
    text = '{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":["\\ud83d\\ude00"]}]}'
    proc = export(text)
    clean_exit(proc, 0)
    assert parsed_records(parse(proc.stdout))[0]["args"] == ["\U0001F600"]


def test_json_lone_surrogate_in_file_schema_to_p21():
    text = '{"format":"p105/1","header":{"file_schema":["\\ud800"]},"data":[]}'
    clean_error(export(text, "p21"), "surrogate")


def test_json_lone_surrogate_in_file_schema_to_json():
    text = '{"format":"p105/1","header":{"file_schema":["\\ud800"]},"data":[]}'
    clean_error(export(text, "json"), "surrogate")


def test_json_lone_surrogate_in_other_section_text_to_json():
    text = ('{"format":"p105/1","header":{},"data":[],'
            '"other_sections":[{"keyword":"ANCHOR","after_data":0,"text":"\\ud800"}]}')
    clean_error(export(text, "json"), "surrogate")


def test_json_other_section_text_that_cannot_be_written_to_p21():
    for text, message in (("\ud800", "unpaired surrogate"),
                          ("<a>=#1;\nENDSEC;", "ANCHOR section text cannot be written"),
                          ("'unterminated", "ANCHOR section text cannot be written"),
                          ("/* unterminated", "ANCHOR section text cannot be written")):
        doc = frame(data_sections=[{"parameters": None, "count": 0}],
                    other_sections=[{"keyword": "ANCHOR", "after_data": 1, "text": text}])
        clean_error(export(json.dumps(doc), "p21"), message)


BAD_SHAPES = [
    ("[1]", "neither"),
    ('"p105/1"', "neither"),
    ("null", "neither"),
    ('{"format":"p105/1","header":{},"data":null}', "/data"),
    ('\ufeff {"format":"p105/1","header":{},"data":null}', "/data"),
    ("{}", ""),
    ('{"format":"p105/2","header":{},"data":[]}', "format"),
    ('{"format":"p105/1","header":{}}', "/data"),
    ('{"format":"p105/1","header":{},"data":{}}', "/data"),
    ('{"format":"p105/1","header":[],"data":[]}', "/header"),
    ('{"format":"p105/1","header":{},"data":[], "extra":1}', "unknown top-level key"),
    ('{"format":"p105/1","header":{"x":1},"data":[]}', "unknown header key"),
    ('{"format":"p105/1","header":{"file_schema":"S"},"data":[]}', "file_schema"),
    ('{"format":"p105/1","header":{"file_name":{"name":""}},"data":[]}', "file_name"),
    ('{"format":"p105/1","header":{},"data":[1]}', "/data/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1}]}', "/data/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":-1,"type":"a","args":[]}]}', "/data/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":true,"type":"a","args":[]}]}', "/data/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1.0,"type":"a","args":[]}]}', "/data/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a b","args":[]}]}', "/data/0/type"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":7,"args":[]}]}', "/data/0/type"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":{}}]}', "/data/0/args"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[true]}]}', "/data/0/args/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[{}]}]}', "/data/0/args/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[{"ref":"1"}]}]}', "/data/0/args/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[{"ref":1,"x":2}]}]}', "/data/0/args/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[{"enum":"a.b"}]}]}', "/data/0/args/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[{"derived":false}]}]}', "/data/0/args/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[{"binary":"4F"}]}]}', "/data/0/args/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[{"type":"1X","value":1}]}]}',
     "/data/0/args/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"complex":[]}]}', "/data/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"complex":[{"type":"a"}]}]}', "/data/0/complex/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"complex":[],"type":"a","args":[]}]}', "/data/0"),
    ('{"format":"p105/1","header":{},"data":[],"data_sections":[]}', "/data_sections"),
    ('{"format":"p105/1","header":{},"data":[],"data_sections":[{"parameters":null,"count":1}]}',
     "/data_sections"),
    ('{"format":"p105/1","header":{},"data":[],"other_sections":[{"keyword":"DATA"}]}', "/other_sections/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[%s]}]}' % ("1" * 5000), "invalid JSON"),
    ('{"format":"p105/1","header":{},\n"data":[{"id":1,"type":"a","args":[1,]}]}', ":2:"),
    ('{"format":"p105/1","header":{},"data":[]', "invalid JSON"),
    ('{"format":"p105/1","stream":true,"header":{}}\n{"id":1,"type":"a","args":[]}\n[', ":3:"),
    ('{"format":"p105/1","stream":true,"header":{}}\n{"id":1,"type":"a","args":[]}\n{"id":1,"type":"b","args":[]}',
     "#1"),
]


@pytest.mark.parametrize("text, needle", BAD_SHAPES)
def test_json_wrong_shapes_are_clean_errors(text, needle):
    clean_error(export(text), needle)


@pytest.mark.parametrize("text", [
    '{"format":"p105/1","header":{"other":5},"data":[]}',
    '{"format":"p105/1","header":{},"data":[],"other_sections":5}',
])
def test_json_non_list_containers_are_clean_errors(text):
    clean_error(export(text))


def test_json_in_process_checks_match_the_cli():
    # read_json is the function behind the CLI: same hostile input, same verdict.
    with pytest.raises(StepError):
        read_json('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[NaN]}]}')
    with pytest.raises(StepError):
        read_json('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":["\\ud800"]}]}')


def test_warning_in_the_header_is_located():
    text = p21("#1=A();").replace("FILE_NAME('t.stp'", "FILE_NAME('C:\\dir\\t.stp'")
    proc = parse(text)
    err = clean_exit(proc, 0)
    col = text.split("\n")[3].index("\\") + 1
    assert f"<stdin>:4:{col}: backslash that starts no escape" in err
    assert json.loads(proc.stdout)["header"]["file_name"]["name"] == "C:\\dir\\t.stp"


def test_warning_positions_match_the_reader(capsys):
    from p105cli.cli.contract import report_warnings
    rng = random.Random(7)
    text = p21("\n".join(f"#{i}=A('{'x' * rng.randrange(30)}');" for i in range(1, 300)))
    sf = read_step(text)
    offsets = [0, 1, len(text), text.index("\n"), text.index("\n") + 1] + \
              [rng.randrange(len(text) + 1) for _ in range(200)]
    sf.warnings = [(f"w{k}", off) for k, off in enumerate(offsets)]
    report_warnings(sf)
    lines = capsys.readouterr().err.splitlines()
    assert lines == [f"p105: warning: <input>:{line_col_of(text, off)}: w{k}" for k, off in enumerate(offsets)]
    assert all(f"{sf.line_col(off)[0]}:{sf.line_col(off)[1]}" == line_col_of(text, off) for off in offsets)
