"""Golden CLI outputs: every command and format on the corpus and the examples, unchanged.

The cases and their golden files are made by ``tests/make_golden.py`` (see its
docstring; regenerate with ``python tests/make_golden.py`` when a change of output
is meant). Each case runs in-process (``p105cli.cli.main``) and is compared:

* exit status and stderr: exactly;
* stdout: equal bytes pass; otherwise both are cut into number and non-number
  tokens: every non-number token and every integer must be identical, and reals
  may differ by ``max(1e-12 * max(|a|, |b|), 1e-12)`` (relative 1e-12, with an
  absolute floor of 1e-12 for values near zero: 1 pm in SI lengths, 1e-12 rad),
  so that another CPU's last-bit differences cannot fail the test but any real
  change of a value does. ``P105_GOLDEN_EXACT=1`` demands equal bytes (the same
  machine before and after a refactoring).

A few cases also run as a real ``python -m p105cli`` process: in-process running
must print what a user sees.
"""

from __future__ import annotations

import os
import re

import pytest

import make_golden as mg

EXACT = os.environ.get("P105_GOLDEN_EXACT", "") not in ("", "0")
REL, ABS = 1e-12, 1e-12

_CASES = mg.cases()
CASES = [c for c in _CASES if not c.needs_shared or mg.SHARED.is_dir()]

#: A number: sign, digits with an optional point (Part 21 writes ``1.``, ``1.E-07``), exponent.
TOKEN = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _tokens(line: str) -> list[str]:
    """Non-number text and numbers, alternating (text first)."""
    out, at = [], 0
    for m in TOKEN.finditer(line):
        out += [line[at:m.start()], m.group(0)]
        at = m.end()
    out.append(line[at:])
    return out


def _is_integer(token: str) -> bool:
    return not any(ch in token for ch in ".eE")


def line_difference(expected: str, actual: str) -> str | None:
    """Why two lines differ beyond the tolerance, or None when they agree."""
    if expected == actual:
        return None
    a, b = _tokens(expected), _tokens(actual)
    if len(a) != len(b):
        return "different text"
    for k, (x, y) in enumerate(zip(a, b)):
        if x == y:
            continue
        if k % 2 == 0:
            return f"text {x!r} != {y!r}"
        if _is_integer(x) or _is_integer(y):
            return f"integer {x} != {y}"
        fx, fy = float(x), float(y)
        if abs(fx - fy) > max(REL * max(abs(fx), abs(fy)), ABS):
            return f"real {x} != {y} (difference {abs(fx - fy):.3g})"
    return None


def stdout_difference(expected: str, actual: str, exact: bool = EXACT) -> str | None:
    """The first line where ``actual`` differs from ``expected`` (beyond the tolerance, or at
    all when ``exact``)."""
    if expected == actual:
        return None
    el, al = expected.split("\n"), actual.split("\n")
    for n, (e, a) in enumerate(zip(el, al), start=1):
        why = "bytes differ (P105_GOLDEN_EXACT)" if exact and e != a else line_difference(e, a)
        if why:
            return f"stdout line {n}: {why}\n  expected: {_clip(e)}\n  actual:   {_clip(a)}"
    if len(el) != len(al):
        return f"stdout has {len(al)} lines, expected {len(el)}"
    return None


def _clip(s: str, n: int = 300) -> str:
    return s if len(s) <= n else s[:n] + f"... ({len(s)} chars)"


def _stdin_of(case_id: str) -> str:
    return mg.load(case_id)["stdout"]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_golden(case):
    golden = mg.load(case.id)
    assert golden["args"] == list(case.args) and golden["stdin"] == case.stdin, \
        f"{case.id}: the case changed: run python tests/make_golden.py"
    got = mg.run_case(case, _stdin_of)
    cmd = "p105 " + " ".join(mg.command_line(case)) + (f" < {case.stdin}" if case.stdin else "")
    assert got["exit"] == golden["exit"], f"{case.id}: exit {got['exit']}, expected {golden['exit']}\n  {cmd}\n" \
                                          f"  stderr: {_clip(got['stderr'], 1000)}"
    assert got["stderr"] == golden["stderr"], f"{case.id}: stderr differs\n  {cmd}\n" \
                                              f"  expected: {golden['stderr']!r}\n  actual:   {got['stderr']!r}"
    why = stdout_difference(golden["stdout"], got["stdout"])
    assert why is None, f"{case.id}: {why}\n  {cmd}"


def test_every_golden_file_is_a_case():
    ids = {c.id for c in _CASES}
    stray = sorted(p.name for p in mg.DATA.glob("*.json*") if p.name.split(".json")[0] not in ids)
    assert not stray, f"golden files of no case (run python tests/make_golden.py): {stray}"


def test_no_golden_case_is_an_internal_error():
    assert not [c.id for c in CASES if mg.load(c.id)["exit"] == 3]


#: Cases that also run as a real process: warnings on stderr, exit 2 and 1, stdin, the
#: input's bytes copied by file descriptor (validate --pass), a shared file's path.
SUBPROCESS = ["export-schema-ap214--ur5_arm_ap242", "fail-malformed-parse", "fail-missing-file-solve",
              "validate-pass--ex-four_bar_ap242", "validate-stdin--ex-four_bar_ap242", "fail-bad-option",
              "solve-scene", "ext-parse--defects-raw8bit"]


@pytest.mark.parametrize("case_id", SUBPROCESS)
def test_in_process_is_what_a_process_prints(case_id):
    case = next(c for c in _CASES if c.id == case_id)
    if case.needs_shared and not mg.SHARED.is_dir():
        pytest.skip(f"{mg.SHARED} absent")
    inproc = mg.run_case(case, _stdin_of)
    process = mg.run_case(case, _stdin_of, runner=mg.run_subprocess)
    assert process == inproc


def test_a_suite_run_prints_what_a_single_run_prints():
    """State left by earlier runs in this process (caches, warning registries) does not
    change a case: the same case first and after every other command kind."""
    case = next(c for c in _CASES if c.id == "export-schema-ap214--ur5_arm_ap242")
    first = mg.run_case(case, _stdin_of)
    for other in ("validate-json--ur5_arm_ap242", "solve-program-jsonl--ur5_arm_ap242", "graph--ur5_arm_ap242"):
        mg.run_case(next(c for c in _CASES if c.id == other), _stdin_of)
    assert mg.run_case(case, _stdin_of) == first


# ---------------------------------------------------------------- the comparison itself

def test_comparison_tolerates_last_bits_only():
    assert line_difference('{"x":0.1,"n":3}', '{"x":0.10000000000000002,"n":3}') is None
    assert line_difference("#5=CARTESIAN_POINT('',(1.E-07,0.,30.));",
                           "#5=CARTESIAN_POINT('',(1.0000000000000001E-07,-0.,30.));") is None
    assert line_difference('{"r":1e-17}', '{"r":-3e-16}') is None  # absolute floor
    assert line_difference('{"x":0.1}', '{"x":0.1000000000002}') is None  # 0.2 pm: under the floor
    assert line_difference('{"x":0.1}', '{"x":0.100000000002}') is not None
    assert line_difference('{"x":1500.0}', '{"x":1500.000000001}') is None
    assert line_difference('{"x":1500.0}', '{"x":1500.00000001}') is not None
    assert line_difference('{"n":3}', '{"n":4}').startswith("integer")
    assert line_difference('{"iterations":3}', '{"iterations":3.0}').startswith("integer")
    assert line_difference("#12=REVOLUTE_PAIR('A')", "#12=REVOLUTE_PAIR('B')").startswith("text")
    assert line_difference("#12=A", "#13=A").startswith("integer")
    assert line_difference("a,b", "a,b,c") is not None


def test_comparison_reports_the_first_differing_line():
    why = stdout_difference("a\nb 1.5\nc\n", "a\nb 1.6\nc\n", exact=False)
    assert why.startswith("stdout line 2: real 1.5 != 1.6")
    assert stdout_difference("a\n", "a\nb\n", exact=False).startswith("stdout line 2: text '' != 'b'")
    assert stdout_difference("a\nb", "a\nb\n", exact=False) == "stdout has 3 lines, expected 2"
    assert stdout_difference("x 0.1\n", "x 0.1\n", exact=True) is None
    assert stdout_difference("x 0.1\n", "x 0.10000000000000002\n", exact=False) is None
    assert stdout_difference("x 0.1\n", "x 0.10000000000000002\n", exact=True).startswith("stdout line 1: bytes")
