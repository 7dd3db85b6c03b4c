#!/usr/bin/env python3
"""Fuzz the readers and writers: ``make fuzz`` (``P105_FUZZ_SECONDS``, default 120).

Bytes go through everything a p105 command does with its input:
decode_bytes -> read_step -> records -> write_step / write_json (encoded as
UTF-8, as the CLI writes them), and read_json -> write_step / write_json.
A ``StepError`` (``ModelError`` included) is the clean way to refuse an
input; any other exception is a crash. When a Part 21 text reads, its
canonical text must read back to the same records (type-exact) and the
JSON written from it must read back too.

With atheris (libFuzzer, coverage-guided) when it can be imported; otherwise
a hypothesis loop (random bytes, mutated seeds and generated valid files)
for the same budget. Either way it stops by itself and exits 0 if nothing
crashed, 1 (with the input) otherwise. Not a pytest module (no ``test_``
names, and pytest does not collect ``fuzz_*.py``).
"""

from __future__ import annotations

import io
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path[:0] = [str(ROOT), str(HERE)]

SECONDS = float(os.environ.get("P105_FUZZ_SECONDS", "120"))
MAX_LEN = 1 << 14

try:
    import atheris
except ImportError:  # the hypothesis loop below
    atheris = None
if os.environ.get("P105_FUZZ_NO_ATHERIS"):  # force the hypothesis loop
    atheris = None

if atheris is not None:
    with atheris.instrument_imports(include=["p105cli"]):
        from p105cli.step import (StepError, decode_bytes, read_json, read_step, write_json,
                                  write_step)
else:
    from p105cli.step import StepError, decode_bytes, read_json, read_step, write_json, write_step


def _write(writer, doc, **kw) -> str:
    out = io.StringIO()
    writer(doc, out, **kw)
    text = out.getvalue()
    text.encode("utf-8")  # what the CLI does with it: a lone surrogate fails here
    return text


def _same(a, b) -> bool:
    """Type-exact equality, -0.0 apart from 0.0 (as conftest.same_value, without recursion)."""
    stack = [(a, b)]
    while stack:
        x, y = stack.pop()
        if type(x) is not type(y):
            return False
        if type(x) is list:
            if len(x) != len(y):
                return False
            stack.extend(zip(x, y))
        elif type(x) is dict:
            if x.keys() != y.keys():
                return False
            stack.extend((x[k], y[k]) for k in x)
        elif type(x) is float:
            if x != y or str(x) != str(y):
                return False
        elif x != y:
            return False
    return True


def check_step(text: str) -> None:
    try:
        sf = read_step(text, "<fuzz>")
        records = list(sf.records())
    except StepError:
        return
    careful = list(read_step(text, "<fuzz>").careful_records())
    assert _same(records, careful), "records() and careful_records() differ"
    canonical = _write(write_step, sf)
    again = read_step(canonical, "<canonical>")
    assert _same(list(again.records()), records), "the canonical Part 21 text reads differently"
    assert _write(write_step, again) == canonical, "the canonical Part 21 text is not a fixed point"
    js = _write(write_json, sf)
    doc = read_json(js, "<json>")
    assert _same(doc.data, records), "the JSON model reads differently"
    _write(write_json, sf, stream=True)


def check_json(text: str) -> None:
    try:
        doc = read_json(text, "<fuzz>")
    except StepError:
        return
    except RecursionError:
        # Deep JSON: the CLI (inputs.load_document) reports it as an input error, exit 2.
        return
    for writer in (write_step, write_json):
        try:
            _write(writer, doc)
        except StepError:  # e.g. a string the model allows but Part 21 cannot carry
            pass


def one_input(data: bytes) -> None:
    text = decode_bytes(data)
    check_step(text)
    if text.lstrip(" \t\r\n\ufeff").startswith("{"):
        check_json(text)


# ---------------------------------------------------------------- seeds

def seeds() -> list[bytes]:
    out = [p.read_bytes() for p in sorted((ROOT / "examples").glob("*.stp"))]
    for raw in list(out):
        try:
            out.append(_write(write_json, read_step(decode_bytes(raw))).encode())
            out.append(_write(write_json, read_step(decode_bytes(raw)), stream=True).encode())
        except StepError:
            pass
    head = ("ISO-10303-21;HEADER;FILE_DESCRIPTION((''),'2;1');FILE_NAME('','',(''),(''),'','','');"
            "FILE_SCHEMA(('X'));ENDSEC;DATA;\n")
    tail = "\nENDSEC;END-ISO-10303-21;"
    for body in ["#1=A(#2);#2=B(#1);", "#1=A('\\X2\\00E9\\X0\\\\X4\\0001F600\\X0\\''\\\\\\S\\A\\PB\\');",
                 "#1=A(-0.,1.E-320,1.E300,123,.T.,\"0FF\",*,$,X((1,2)));", "#1=(B(1)C((2)));",
                 "#1 /*c*/ = A ( /* ; */ 'x;' ) ;", "#1=A(" + "(" * 210 + ")" * 210 + ");"]:
        out.append((head + body + tail).encode())
    out.append((head + "#1=A();" + "\nENDSEC;ANCHOR;<a>=#1;ENDSEC;DATA(('n'),('S'));#2=B();" + tail).encode())
    return out


DICTIONARY = ["ISO-10303-21;", "END-ISO-10303-21;", "HEADER;", "DATA;", "ENDSEC;", "ANCHOR;",
              "REFERENCE;", "SIGNATURE;", "FILE_DESCRIPTION", "FILE_NAME", "FILE_SCHEMA", "#1", "#2=",
              "'", "''", "\\\\", "\\S\\", "\\PA\\", "\\X\\", "\\X2\\", "\\X4\\", "\\X0\\", "D800", "0001F600",
              "/*", "*/", "(", ")", ",", ";", "=", "$", "*", ".T.", "\"0F\"", "1.E400", "-0.", "1.E-320",
              "E", "{", "}", "[", "]", "\"format\":\"p105/1\"", "\"stream\":true", "\"data\":",
              "\"header\":", "\"ref\":", "\"enum\":", "\"type\":", "\"value\":", "\"args\":", "\"id\":",
              "\"complex\":", "\"other_sections\":", "\"data_sections\":", "\"other\":", "NaN", "Infinity",
              "\"\\ud800\"", "9223372036854775808"]


# ---------------------------------------------------------------- atheris

def run_atheris() -> int:
    # The corpus grows from run to run under build/ (git-ignored); crashes are saved there too.
    artifacts = ROOT / "build" / "fuzz"
    corpus = artifacts / "corpus"
    corpus.mkdir(parents=True, exist_ok=True)
    for k, seed in enumerate(seeds()):
        (corpus / f"seed{k}").write_bytes(seed)
    dictionary = artifacts / "p21.dict"
    dictionary.write_text("".join('"' + "".join(f"\\x{b:02x}" for b in w.encode()) + '"\n'
                                  for w in DICTIONARY))
    print(f"fuzz: atheris for {SECONDS:g} s; corpus {corpus}; crashes go to {artifacts}/", flush=True)
    args = [sys.argv[0], f"-max_total_time={int(SECONDS)}", f"-max_len={MAX_LEN}", "-timeout=20",
            "-rss_limit_mb=4096", f"-dict={dictionary}", f"-artifact_prefix={artifacts}/",
            "-print_final_stats=1", *sys.argv[1:], str(corpus)]
    atheris.Setup(args, one_input)
    atheris.Fuzz()  # exits the process: 0 when the time is up, non-zero on a crash
    return 0


# ---------------------------------------------------------------- hypothesis fallback

def run_hypothesis() -> int:
    import random

    from hypothesis import HealthCheck, Phase, given, settings, strategies as st

    from step.test_roundtrip_props import part21_file

    seed_list = seeds()
    words = [w.encode() for w in DICTIONARY]

    @st.composite
    def mutated(draw):
        data = bytearray(draw(st.sampled_from(seed_list)))
        rnd = random.Random(draw(st.integers(0, 2 ** 32)))
        for _ in range(rnd.randint(1, 8)):
            op = rnd.randrange(5)
            pos = rnd.randint(0, len(data))
            if op == 0 and data:
                del data[pos:pos + rnd.randint(1, 16)]
            elif op == 1:
                data[pos:pos] = rnd.choice(words)
            elif op == 2:
                data[pos:pos] = bytes(rnd.randrange(256) for _ in range(rnd.randint(1, 4)))
            elif op == 3 and data:
                data = data[:pos]  # truncate
            else:
                chunk = data[pos:pos + rnd.randint(1, 64)]
                data[pos:pos] = chunk * rnd.randint(1, 40)  # repeat: nesting, long runs
        return bytes(data[:MAX_LEN])

    inputs = st.one_of(st.binary(max_size=512), mutated(), mutated(),
                       part21_file().map(lambda f: f[0].encode("utf-8")))
    failures: list = []

    @settings(max_examples=200, deadline=None, database=None, derandomize=False,
              phases=[Phase.generate, Phase.shrink], report_multiple_bugs=False,
              suppress_health_check=list(HealthCheck))
    @given(inputs)
    def batch(data):
        try:
            one_input(data)
        except Exception:
            failures.append(data)
            raise

    print(f"fuzz: hypothesis loop for {SECONDS:g} s (atheris not importable or disabled)", flush=True)
    end = time.monotonic() + SECONDS
    runs = 0
    while time.monotonic() < end:
        try:
            batch()
        except Exception as err:  # noqa: BLE001 - a crash: report it with the input
            import traceback
            traceback.print_exception(err)
            data = failures[-1] if failures else b""
            crash = ROOT / "build" / "fuzz" / "crash-hypothesis"
            crash.parent.mkdir(parents=True, exist_ok=True)
            crash.write_bytes(data)
            print(f"fuzz: CRASH on the input saved in {crash}: {data[:200]!r}", file=sys.stderr)
            return 1
        runs += 200
    print(f"fuzz: {runs} inputs, no crash", flush=True)
    return 0


def main() -> int:
    sys.setrecursionlimit(max(sys.getrecursionlimit(), 1000))
    if atheris is not None:
        return run_atheris()
    return run_hypothesis()


if __name__ == "__main__":
    sys.exit(main())
