"""Shared test helpers: minimal files, the CLI runner, type-exact comparison."""

from __future__ import annotations

import io
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("P105_SHARED", ROOT.parent / "shared"))
CORPUS = SHARED / "corpus"
EXAMPLES = ROOT / "examples"

HEADER = ("ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n"
          "FILE_NAME('t.stp','2026-01-01T00:00:00',(''),(''),'','','');\n"
          "FILE_SCHEMA(('TEST_SCHEMA'));\nENDSEC;\n")


def p21(instances: str, header: str = HEADER) -> str:
    """A complete Part 21 text around the given DATA section body."""
    return f"{header}DATA;\n{instances}\nENDSEC;\nEND-ISO-10303-21;\n"


def run_cli(*args, input: bytes | str | None = None, timeout: float = 60, env=None):
    """Run ``python -m p105cli ARGS``; returns CompletedProcess with bytes out/err."""
    if isinstance(input, str):
        input = input.encode("utf-8")
    full_env = dict(os.environ)
    full_env.pop("CI", None)
    if env:
        full_env.update(env)
    return subprocess.run([sys.executable, "-m", "p105cli", *map(str, args)], input=input,
                          capture_output=True, timeout=timeout, env=full_env, cwd=ROOT)


class _Stdin:
    """A stand-in for sys.stdin: main() reads ``sys.stdin.buffer``."""

    def __init__(self, data: bytes):
        self.buffer = io.BytesIO(data)

    def isatty(self) -> bool:
        return False


@pytest.fixture
def p105(capfdbinary, monkeypatch):
    """Run the CLI in this process: ``p105(*args, input=...)`` gives a CompletedProcess
    (returncode, stdout and stderr as bytes) like :func:`run_cli`, without starting an
    interpreter. Output is captured at the file descriptors, so stdout written with
    os.write (validate --pass) is seen too. Use run_cli for what needs a real process:
    pipes, signals, start-up, the exit status the operating system sees."""
    from p105cli.cli import main

    monkeypatch.delenv("CI", raising=False)

    def run(*args, input: bytes | str | None = None, env: dict | None = None):
        if isinstance(input, str):
            input = input.encode("utf-8")
        argv = [str(a) for a in args]
        with monkeypatch.context() as m:
            m.setattr(sys, "stdin", _Stdin(input or b""))
            for name, value in (env or {}).items():
                m.setenv(name, value)
            capfdbinary.readouterr()
            code = main(argv)
            out, err = capfdbinary.readouterr()
        return subprocess.CompletedProcess(["p105", *argv], int(code), out, err)

    return run


def cli_in_process(*args, input: bytes | str | None = None, env: dict | None = None):
    """``p105 ARGS`` run in this process, with the shape of :func:`run_cli`'s result
    (returncode, stdout and stderr as bytes), from the repository root. What a process
    adds (pipes, signals, start-up, time limits) is run_cli's job; everything else is
    tested here, without paying an interpreter and a schema load per call."""
    from make_golden import run_in_process

    if isinstance(input, str):
        input = input.encode("utf-8")
    saved = {k: os.environ.get(k) for k in (*(env or {}), "CI")}
    os.environ.pop("CI", None)
    os.environ.update(env or {})
    try:
        code, out, err = run_in_process([str(a) for a in args], input or b"")
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    return subprocess.CompletedProcess(["p105", *map(str, args)], code, out, err.encode("utf-8"))


def same_value(a, b) -> bool:
    """Equality that also requires the same types and the same sign of zero."""
    if type(a) is not type(b):
        return False
    if type(a) is float:
        if a == 0.0 and b == 0.0:
            return math.copysign(1.0, a) == math.copysign(1.0, b)
        return a == b
    if type(a) is list:
        return len(a) == len(b) and all(same_value(x, y) for x, y in zip(a, b))
    if type(a) is dict:
        return a.keys() == b.keys() and all(same_value(a[k], b[k]) for k in a)
    return a == b


def corpus_files() -> list[Path]:
    """Every Part 21 file of the shared corpus and of examples/."""
    files = sorted(EXAMPLES.glob("*.stp"))
    if CORPUS.is_dir():
        files += sorted(p for p in CORPUS.rglob("*") if p.suffix.lower() in (".stp", ".step", ".p21"))
    return files


@pytest.fixture
def tmp_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return tmp_path


# ---------------------------------------------------------------- hostile input helpers
# (added for test_hostile.py / test_roundtrip_props.py / fuzz_reader.py)

import re as _re

# A diagnostic that says where: FILE:LINE:COL: (text position), FILE: #id: (instance),
# FILE:/json/pointer: (JSON model) or FILE:line N/pointer: (JSON Lines stream).
LOCATED = _re.compile(r"^p105: error: \S*?:(\d+:\d+|/[^ ]*|line \d+[^ ]*|)(?:: | #\d+: )", _re.M)


def clean_exit(proc, code: int) -> str:
    """Assert the exit code and a traceback-free stderr; return stderr as text."""
    err = proc.stderr.decode("utf-8", "replace")
    assert "Traceback" not in err, err[-3000:]
    assert proc.returncode == code, f"exit {proc.returncode}, expected {code}: {err[-3000:]}"
    return err


def clean_error(proc, *needles: str) -> str:
    """Assert exit 2 with exactly one error line on stderr mentioning every needle."""
    err = clean_exit(proc, 2)
    lines = [ln for ln in err.splitlines() if ln.startswith("p105: error:")]
    assert len(lines) == 1, err[-3000:]
    for needle in needles:
        assert needle in lines[0], f"{needle!r} not in {lines[0]!r}"
    return lines[0]


def line_col_of(text: str, offset: int) -> str:
    """``LINE:COL`` (1-based) of a character offset, as diagnostics write it."""
    line = text.count("\n", 0, offset) + 1
    return f"{line}:{offset - (text.rfind(chr(10), 0, offset) + 1) + 1}"


def read_all(text: str, source: str = "<input>"):
    """read_step + records(): the whole reading path, in process."""
    from p105cli.step import read_step
    sf = read_step(text, source)
    return sf, list(sf.records())


def same_records(a: list, b: list) -> bool:
    """Type-exact comparison of two record lists (see same_value)."""
    return len(a) == len(b) and all(same_value(x, y) for x, y in zip(a, b))
