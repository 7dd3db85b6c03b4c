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
