"""p105 validate in process: inputs read by cli/inputs.py, the report, --pass."""

from __future__ import annotations

import json

from conftest import EXAMPLES

FOUR_BAR = EXAMPLES / "four_bar_ap242.stp"


def test_pass_copies_the_input_bytes(p105):
    r = p105("validate", "--pass", FOUR_BAR)
    assert r.returncode == 0, r.stderr
    assert r.stdout == FOUR_BAR.read_bytes()


def test_unreadable_inputs_are_findings_of_their_own_file(p105, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"format":"p105/1","header":{},"data":' + "[" * 100_000 + "]" * 100_000 + "}")
    r = p105("validate", "-f", "json", FOUR_BAR, bad)
    assert r.returncode == 2
    report = json.loads(r.stdout)
    files = json.dumps(report)
    assert str(bad) in files and "JSON nested too deeply" in files


def test_stdin_is_named_stdin_in_the_report(p105):
    r = p105("validate", "-f", "json", "-", input="ISO-10303-21;\nHEADER;\n")
    assert r.returncode == 2 and "<stdin>" in r.stdout.decode()


def test_findings_reported_to_a_file_still_say_why_on_stderr(p105, tmp_path):
    # every exit 1 says why on stderr: with -o the report is not on the terminal
    bad = tmp_path / "bad.stp"
    bad.write_text(FOUR_BAR.read_text().replace("KINEMATIC_LINK('rocker')", "KINEMATIC_LINK('coupler')", 1))
    report = tmp_path / "report.txt"
    r = p105("validate", "--fail-on", "warning", bad, "-o", report)
    assert r.returncode == 1 and r.stdout == b""
    assert r.stderr.decode().startswith(f"p105: error: {bad}: 0 errors, 1 warnings"), r.stderr
    assert f"(the report is in {report})" in r.stderr.decode() and report.stat().st_size > 0
    clean = p105("validate", FOUR_BAR, "-o", report)
    assert clean.returncode == 0 and clean.stderr == b""
