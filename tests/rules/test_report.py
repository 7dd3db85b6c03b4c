"""The diagnostics model of ``p105 validate`` and every report format.

Golden files: ``tests/data/golden/report.<ext>``; regenerate them with
``P105_UPDATE_GOLDEN=1 python3 -m pytest tests/rules/test_report.py`` and review the diff by eye.
"""

from __future__ import annotations

import io
import json
import os
import random
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import jsonschema
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import p105cli
from p105cli.rules.diagnostics import (NOT_EVALUATED, Diagnostic, RunResult, Severity, Summary,
                                       exit_code, parse_patterns, rule_description,
                                       rule_selected, select_rules, worst_exit)
from p105cli.rules.report import (FORMATS, SARIF_FINGERPRINT_KEY, describe, entity_suffix,
                                  format_line, resolve_format, write_report)

DATA = Path(__file__).resolve().parents[1] / "data"
GOLDEN = DATA / "golden"
SCHEMAS = DATA / "schemas"
UPDATE = os.environ.get("P105_UPDATE_GOLDEN") == "1"

EXTENSIONS = {"text": "txt", "json": "json", "jsonl": "jsonl", "sarif": "sarif",
              "junit": "junit.xml", "github": "github.txt", "gitlab": "gitlab.json"}

MODEL = "models/arm.stp"
ODD = "odd dir/a:b,c%.stp"
MISSING = "missing.stp"
CLEAN = "./clean.stp"

SYNTAX_MSG = "expected ';' after instance #3, found ')'"


def fixed_results() -> list[RunResult]:
    """Four files: findings of every kind, one odd name, one unreadable, one clean."""
    model = [
        Diagnostic("P21-SYNTAX", "error", SYNTAX_MSG, MODEL, 3, 7),
        Diagnostic("P21-SYNTAX", "error", SYNTAX_MSG, MODEL, 30, 2),
        Diagnostic("SCH-ARITY", "error", "REVOLUTE_PAIR takes 6 attributes, found 5",
                   MODEL, 12, 1, 12, "REVOLUTE_PAIR"),
        Diagnostic("SCH-kinematic_joint.wr1", "warning",
                   "edge_start and edge_end are the same vertex: 100% degenerate\nsee #9",
                   MODEL, 15, 1, 15, "KINEMATIC_JOINT"),
        Diagnostic("KIN-UNITS", "error",
                   "plane angle unit is <missing> & length unit is \"mm\" 'assumed'", MODEL),
        Diagnostic("KIN-RANGE", "warning",
                   "lower limit 3.2 rad > upper limit \u22123.1 rad "
                   "(\u03a9 \u00fcn\u00efc\u00f6d\u00e9)",
                   MODEL, 20, None, 20, "REVOLUTE_PAIR_WITH_RANGE"),
        Diagnostic(NOT_EVALUATED, "note",
                   "kinematic_structure.wr2 calls a function p105 does not implement: "
                   "\u2200 joints\u2026",
                   MODEL),
    ]
    odd = [
        Diagnostic(NOT_EVALUATED, "note", "bell\x07 and CRLF\r\nend, 50%: done", ODD,
                   None, None, 7, "PAIR_VALUE"),
    ]
    missing = [Diagnostic("P21-READ", "error",
                          "cannot read file: [Errno 2] No such file or directory", MISSING)]
    return [
        RunResult.make(MODEL, model, rules_evaluated=40, rules_applicable=41, seconds=0.125),
        RunResult.make(ODD, odd, rules_evaluated=12, rules_applicable=13, seconds=0.0625),
        RunResult.make(MISSING, missing, seconds=0.0, readable=False),
        RunResult.make(CLEAN, [], rules_evaluated=42, rules_applicable=42, seconds=0.5),
    ]


def render(fmt: str, results=None) -> str:
    buf = io.StringIO()
    FORMATS[fmt](fixed_results() if results is None else results, buf)
    return buf.getvalue()


# -- the model ---------------------------------------------------------------------------

def test_severity_ranks_and_parse():
    assert Severity.NOTE < Severity.WARNING < Severity.ERROR
    assert Severity.parse("Warning") is Severity.WARNING
    assert Severity.ERROR.label == "error"
    with pytest.raises(ValueError):
        Severity.parse("fatal")


def test_diagnostic_validates_and_normalises():
    assert Diagnostic("X-Y", "ERROR", "m", "f").severity == "error"
    assert Diagnostic("X-Y", Severity.NOTE, "m", "f").severity == "note"
    with pytest.raises(ValueError):
        Diagnostic("X-Y", "fatal", "m", "f")
    with pytest.raises(ValueError):
        Diagnostic("A,B", "error", "m", "f")
    with pytest.raises(ValueError):
        Diagnostic("", "error", "m", "f")
    with pytest.raises(TypeError):
        Diagnostic("X-Y", "error", "m", "f", entity="#12")
    with pytest.raises(TypeError):
        Diagnostic("X-Y", "error", "m", "f", line=True)
    np = pytest.importorskip("numpy")
    d = Diagnostic("X-Y", "error", "m", "f", np.int64(3), np.int32(4), np.int64(12))
    assert (type(d.line), type(d.column), type(d.entity)) == (int, int, int)
    assert d == Diagnostic("X-Y", "error", "m", "f", 3, 4, 12)


def test_order_is_file_line_column_rule_entity_unknown_positions_first():
    a = Diagnostic("Z", "note", "m", "a.stp")
    b = Diagnostic("B", "error", "m", "a.stp", 2, 5)
    c = Diagnostic("A", "error", "m", "a.stp", 2, 5, 9)
    d = Diagnostic("A", "error", "m", "a.stp", 2, 5, 10)
    e = Diagnostic("A", "error", "m", "a.stp", 10, 1)
    f = Diagnostic("A", "error", "m", "b.stp", 1, 1)
    expected = [a, c, d, b, e, f]
    for seed in range(5):
        shuffled = expected[:]
        random.Random(seed).shuffle(shuffled)
        assert sorted(shuffled) == expected
    assert RunResult("a.stp", [e, a, d]).diagnostics == (a, d, e)


def test_fingerprint_is_stable_and_ignores_position_and_directory():
    base = Diagnostic("SCH-ARITY", "error", "takes 6", "models/arm.stp", 12, 1, 12, "REVOLUTE_PAIR")
    fp = base.fingerprint
    assert re.fullmatch(r"[0-9a-f]{16}", fp)
    moved = Diagnostic("SCH-ARITY", "error", "takes 6", "/abs/elsewhere/arm.stp", 99, 40, 12,
                       "REVOLUTE_PAIR")
    assert moved.fingerprint == fp
    assert Diagnostic("SCH-ARITY", "error", "takes 6", "models\\arm.stp", None, None, 12,
                      "REVOLUTE_PAIR").fingerprint == fp
    # Severity is not part of it either (a rule re-graded keeps its findings' identity).
    assert Diagnostic("SCH-ARITY", "warning", "takes 6", "arm.stp", 1, 1, 12,
                      "REVOLUTE_PAIR").fingerprint == fp
    rp = "REVOLUTE_PAIR"
    for other in (Diagnostic("SCH-OTHER", "error", "takes 6", "arm.stp", 12, 1, 12, rp),
                  Diagnostic("SCH-ARITY", "error", "takes 7", "arm.stp", 12, 1, 12, rp),
                  Diagnostic("SCH-ARITY", "error", "takes 6", "arm.stp", 12, 1, 13, rp),
                  Diagnostic("SCH-ARITY", "error", "takes 6", "arm.stp", 12, 1, 12, "PRISM"),
                  Diagnostic("SCH-ARITY", "error", "takes 6", "leg.stp", 12, 1, 12, rp)):
        assert other.fingerprint != fp
    # A documented recipe: pinned value, so a change of recipe is a visible decision.
    assert fp == __import__("hashlib").sha256(
        "SCH-ARITY\0arm.stp\x0012\0REVOLUTE_PAIR\0takes 6".encode()).hexdigest()[:16]


def test_fingerprint_survives_lone_surrogates():
    assert len(Diagnostic("P21-SYNTAX", "error", "bad byte \udcff", "f").fingerprint) == 16


def test_summary_counts_and_combine():
    results = fixed_results()
    s = results[0].summary
    assert (s.errors, s.warnings, s.notes, s.not_evaluated) == (4, 2, 1, 1)
    assert (s.rules_evaluated, s.rules_applicable, s.files) == (40, 41, 1)
    assert s.counts == {"error": 4, "warning": 2, "note": 1}
    total = Summary.combine(r.summary for r in results)
    assert (total.files, total.errors, total.warnings, total.notes) == (4, 5, 2, 2)
    assert (total.not_evaluated, total.unreadable) == (2, 1)
    assert (total.rules_evaluated, total.rules_applicable) == (94, 96)
    assert total.seconds == pytest.approx(0.6875)


def test_rule_descriptions():
    assert rule_description("SCH-kinematic_joint.wr1") == \
        "EXPRESS rule wr1 of entity kinematic_joint."
    assert "10303-21" in rule_description("P21-SYNTAX")
    assert rule_description("KIN-NEW").startswith("Kinematics consistency check")
    assert rule_description("ODD") == "p105 rule ODD."


# -- selection ---------------------------------------------------------------------------

def test_parse_patterns_splits_commas_and_repeats():
    assert parse_patterns(None) == ()
    assert parse_patterns("SCH-*, KIN-UNITS,,") == ("SCH-*", "KIN-UNITS")
    assert parse_patterns(["SCH-*,KIN-UNITS", "P21-*", "SCH-*"]) == ("SCH-*", "KIN-UNITS", "P21-*")


def test_select_and_ignore_globs():
    diags = [d for r in fixed_results() for d in r.diagnostics]
    rules = lambda ds: sorted({d.rule for d in ds})  # noqa: E731
    assert rules(select_rules(diags, None, None)) == rules(diags)
    assert rules(select_rules(diags, ["SCH-*"], None)) == ["SCH-ARITY", NOT_EVALUATED,
                                                          "SCH-kinematic_joint.wr1"]
    assert rules(select_rules(diags, "SCH-*.wr?,KIN-*", None)) == [
        "KIN-RANGE", "KIN-UNITS", "SCH-kinematic_joint.wr1"]
    assert rules(select_rules(diags, ["SCH-*"], ["SCH-NOT-*", "*.wr1"])) == ["SCH-ARITY"]
    # ignore wins over select; matching is case-sensitive
    assert select_rules(diags, ["KIN-UNITS"], ["KIN-UNITS"]) == []
    assert select_rules(diags, ["kin-units"], None) == []
    assert rules(select_rules(diags, None, "P21-*,SCH-*,KIN-RANGE")) == ["KIN-UNITS"]
    assert rule_selected("SCH-kinematic_joint.wr1", select=["SCH-kinematic_joint.*"])
    assert not rule_selected("SCH-ARITY", select=["SCH-kinematic_joint.*"])
    # order is kept
    picked = select_rules(diags, ["P21-*"], None)
    assert picked == [d for d in diags if d.rule.startswith("P21-")]


# -- exit codes --------------------------------------------------------------------------

def test_worst_exit_fail_on_levels():
    note = [Diagnostic("N", "note", "m", "f")]
    warn = note + [Diagnostic("W", "warning", "m", "f")]
    err = warn + [Diagnostic("E", "error", "m", "f")]
    table = {  # (diags, fail_on) -> code
        ("none", "error"): 0, ("none", "warning"): 0, ("none", "note"): 0,
        ("note", "error"): 0, ("note", "warning"): 0, ("note", "note"): 1,
        ("warn", "error"): 0, ("warn", "warning"): 1, ("warn", "note"): 1,
        ("err", "error"): 1, ("err", "warning"): 1, ("err", "note"): 1,
    }
    sets = {"none": [], "note": note, "warn": warn, "err": err}
    for (name, fail_on), code in table.items():
        assert worst_exit(sets[name], fail_on) == code, (name, fail_on)
        assert worst_exit(sets[name], fail_on, exit_zero=True) == 0
    assert worst_exit(err) == 1  # default --fail-on error
    with pytest.raises(ValueError):
        worst_exit(err, "fatal")


def test_exit_code_is_worst_over_files_and_2_for_unreadable():
    results = fixed_results()
    readable = [r for r in results if r.readable]
    assert exit_code(results) == 2
    assert exit_code(results, exit_zero=True) == 2  # a file not checked is not a finding
    assert exit_code(readable) == 1
    assert exit_code(readable, exit_zero=True) == 0
    clean_and_noted = [r for r in readable if r.file in (ODD, CLEAN)]
    assert exit_code(clean_and_noted, "warning") == 0
    assert exit_code(clean_and_noted, "note") == 1
    assert exit_code([]) == 0


# -- formats: registry, auto ---------------------------------------------------------------

def test_formats_registry():
    assert list(FORMATS) == ["text", "json", "jsonl", "sarif", "junit", "github", "gitlab"]
    for name in FORMATS:
        assert describe(name)


@pytest.mark.parametrize("env, expected", [
    ({}, "text"), ({"GITHUB_ACTIONS": "true"}, "github"), ({"GITHUB_ACTIONS": ""}, "text"),
    ({"GITHUB_ACTIONS": "false"}, "text"), ({"CI": "true"}, "text")])
def test_auto_format(env, expected):
    assert resolve_format("auto", env) == expected
    assert resolve_format("sarif", env) == "sarif"


def test_unknown_format():
    with pytest.raises(ValueError):
        resolve_format("html", {})


def test_write_report_dispatches():
    buf = io.StringIO()
    write_report("auto", fixed_results(), buf, environ={"GITHUB_ACTIONS": "true"})
    assert buf.getvalue() == render("github")


# -- golden files and determinism ----------------------------------------------------------

@pytest.fixture(autouse=True)
def _default_rule_catalogue(monkeypatch):
    """Rule descriptions as diagnostics.py alone defines them: other tests import
    checkers that register more, and the golden files must not depend on test order."""
    import p105cli.rules.diagnostics as diagnostics
    monkeypatch.setattr(diagnostics, "_RULES", dict(diagnostics._DEFAULT_RULES))


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_golden(fmt):
    path = GOLDEN / f"report.{EXTENSIONS[fmt]}"
    got = render(fmt).encode("utf-8")
    if UPDATE or not path.exists():
        if not UPDATE:
            pytest.fail(f"missing golden file {path}; run with P105_UPDATE_GOLDEN=1")
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(got)
    assert got == path.read_bytes(), f"{fmt} differs from {path.name}"


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_deterministic_whatever_the_input_order(fmt):
    first = render(fmt)
    assert render(fmt) == first
    for seed in range(4):
        rng = random.Random(seed)
        results = []
        for r in fixed_results():
            diags = list(r.diagnostics)
            rng.shuffle(diags)
            results.append(RunResult(r.file, diags, r.summary, r.readable))
        rng.shuffle(results)
        assert render(fmt, results) == first


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_empty_run(fmt):
    render(fmt, [])  # writes something valid, does not fail


# -- text --------------------------------------------------------------------------------

def test_text_lines():
    lines = render("text").splitlines()
    assert "models/arm.stp:12:1: error[SCH-ARITY] REVOLUTE_PAIR takes 6 attributes, found 5 " \
           "(#12 REVOLUTE_PAIR)" in lines
    assert "models/arm.stp: error[KIN-UNITS] plane angle unit is <missing> & length unit is " \
           "\"mm\" 'assumed'" in lines
    assert any(line.startswith("models/arm.stp:20: warning[KIN-RANGE] ") for line in lines)
    # one finding, one line: the newline in the message is shown as \n
    assert ("models/arm.stp:15:1: warning[SCH-kinematic_joint.wr1] edge_start and edge_end are "
            "the same vertex: 100% degenerate\\nsee #9 (#15 KINEMATIC_JOINT)") in lines
    assert "models/arm.stp: 4 errors, 2 warnings, 1 notes; rules evaluated 40/41; " \
           "1 not evaluated" in lines
    assert "./clean.stp: 0 errors, 0 warnings, 0 notes; rules evaluated 42/42" in lines
    assert "missing.stp: 1 errors, 0 warnings, 0 notes; rules evaluated 0/0; not readable" in lines
    assert lines[-1] == ("p105 validate: 4 files: 5 errors, 2 warnings, 2 notes; "
                         "rules evaluated 94/96; 2 not evaluated; 1 not readable")
    assert len(lines) == 9 + 4 + 1


def test_text_line_format_forms():
    assert format_line(Diagnostic("R-X", "note", "m", "f.stp")) == "f.stp: note[R-X] m"
    assert format_line(Diagnostic("R-X", "note", "m", "f.stp", 4)) == "f.stp:4: note[R-X] m"
    assert format_line(Diagnostic("R-X", "note", "m", "f.stp", 4, 2, 9)) == \
        "f.stp:4:2: note[R-X] m (#9)"
    assert format_line(Diagnostic("R-X", "note", "m", "f.stp", entity_type="T")) == \
        "f.stp: note[R-X] m (T)"


# -- json / jsonl ------------------------------------------------------------------------

DIAG_KEYS = ["rule", "severity", "message", "file", "line", "column", "entity", "entity_type",
             "fingerprint"]


def test_json_document():
    doc = json.loads(render("json"))
    assert list(doc) == ["format", "files", "diagnostics", "summary"]
    assert doc["format"] == "p105-validate/1"
    assert [f["file"] for f in doc["files"]] == sorted([MODEL, ODD, MISSING, CLEAN])
    assert {f["file"]: f["readable"] for f in doc["files"]}[MISSING] is False
    assert len(doc["diagnostics"]) == 9
    for d in doc["diagnostics"]:
        assert list(d) == DIAG_KEYS
        assert d["entity"] is None or type(d["entity"]) is int
    arity = next(d for d in doc["diagnostics"] if d["rule"] == "SCH-ARITY")
    assert arity == {"rule": "SCH-ARITY", "severity": "error",
                     "message": "REVOLUTE_PAIR takes 6 attributes, found 5", "file": MODEL,
                     "line": 12, "column": 1, "entity": 12, "entity_type": "REVOLUTE_PAIR",
                     "fingerprint": arity["fingerprint"]}
    units = next(d for d in doc["diagnostics"] if d["rule"] == "KIN-UNITS")
    assert units["line"] is None and units["column"] is None and units["entity"] is None
    # messages round-trip exactly, specials and all
    messages = {d.message for r in fixed_results() for d in r.diagnostics}
    assert {d["message"] for d in doc["diagnostics"]} == messages
    assert doc["summary"] == {"files": 4, "errors": 5, "warnings": 2, "notes": 2,
                              "rules_evaluated": 94, "rules_applicable": 96, "not_evaluated": 2,
                              "unreadable": 1, "seconds": 0.688}


def test_jsonl_records():
    lines = render("jsonl").splitlines()
    records = [json.loads(line) for line in lines]
    assert [r["type"] for r in records] == ["diagnostic"] * 9 + ["summary"]
    doc = json.loads(render("json"))
    assert [{k: v for k, v in r.items() if k != "type"} for r in records[:-1]] == doc["diagnostics"]
    summary = records[-1]
    assert summary["errors"] == 5 and summary["format"] == "p105-validate/1"
    assert [f["file"] for f in summary["per_file"]] == [f["file"] for f in doc["files"]]


# -- SARIF -------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def sarif_validator():
    schema = json.loads((SCHEMAS / "sarif-schema-2.1.0.json").read_text(encoding="utf-8"))
    cls = jsonschema.validators.validator_for(schema)
    cls.check_schema(schema)
    return cls(schema, format_checker=cls.FORMAT_CHECKER)


def test_sarif_conforms_to_the_schema(sarif_validator):
    log = json.loads(render("sarif"))
    errors = sorted(sarif_validator.iter_errors(log), key=lambda e: list(e.absolute_path))
    assert not errors, "\n".join(f"{list(e.absolute_path)}: {e.message}" for e in errors)
    sarif_validator.validate(json.loads(render("sarif", [])))


def test_the_sarif_schema_rejects_what_it_should(sarif_validator):
    """The schema really constrains (guards against a vacuous schema file)."""
    log = json.loads(render("sarif"))
    log["runs"][0]["results"][0]["level"] = "fatal"
    assert not sarif_validator.is_valid(log)
    log = json.loads(render("sarif"))
    log["runs"][0]["results"][0]["locations"][0]["physicalLocation"]["region"] = {"startLine": 0}
    assert not sarif_validator.is_valid(log)
    log = json.loads(render("sarif"))
    log["runs"][0]["tool"]["driver"]["informationUrl"] = "x"
    assert not sarif_validator.is_valid(log)


def test_sarif_content():
    log = json.loads(render("sarif"))
    assert log["version"] == "2.1.0" and log["$schema"].endswith("sarif-schema-2.1.0.json")
    (run,) = log["runs"]
    driver = run["tool"]["driver"]
    assert driver["name"] == "p105" and driver["version"] == p105cli.__version__
    rule_ids = [r["id"] for r in driver["rules"]]
    assert rule_ids == sorted({d.rule for r in fixed_results() for d in r.diagnostics})
    assert all(r["shortDescription"]["text"] for r in driver["rules"])
    results = run["results"]
    assert len(results) == 9
    for res in results:
        assert driver["rules"][res["ruleIndex"]]["id"] == res["ruleId"]
        assert res["level"] in ("error", "warning", "note")
        assert len(res["partialFingerprints"][SARIF_FINGERPRINT_KEY]) == 16
    by_rule = {res["ruleId"]: res for res in results}
    arity = by_rule["SCH-ARITY"]
    loc = arity["locations"][0]["physicalLocation"]
    assert loc["artifactLocation"]["uri"] == "models/arm.stp"
    assert loc["region"] == {"startLine": 12, "startColumn": 1}
    assert arity["properties"] == {"entity": 12, "entity_type": "REVOLUTE_PAIR"}
    units = by_rule["KIN-UNITS"]["locations"][0]["physicalLocation"]
    assert "region" not in units and "properties" not in by_rule["KIN-UNITS"]
    assert by_rule["KIN-RANGE"]["locations"][0]["physicalLocation"]["region"] == {"startLine": 20}
    (odd,) = [r for r in results if r.get("properties", {}).get("entity") == 7]
    assert odd["locations"][0]["physicalLocation"]["artifactLocation"]["uri"] == \
        "odd%20dir/a%3Ab%2Cc%25.stp"
    assert odd["level"] == "note"
    assert {a["location"]["uri"] for a in run["artifacts"]} == {
        "models/arm.stp", "odd%20dir/a%3Ab%2Cc%25.stp", "missing.stp", "clean.stp"}
    assert run["invocations"] == [{"executionSuccessful": False}]


# -- JUnit -------------------------------------------------------------------------------

def test_junit_structure_and_counts():
    text = render("junit")
    assert text.startswith('<?xml version="1.0" encoding="UTF-8"?>\n')
    root = ET.fromstring(text.encode("utf-8"))
    assert root.tag == "testsuites"
    suites = {s.get("name"): s for s in root.findall("testsuite")}
    assert list(suites) == sorted([MODEL, ODD, MISSING, CLEAN])
    for s in suites.values():  # required attributes of junit-10.xsd
        for attr in ("name", "tests", "failures", "errors"):
            assert s.get(attr) is not None
        assert int(s.get("tests")) == len(s.findall("testcase"))
        assert int(s.get("failures")) == len(s.findall("testcase/failure"))
        assert int(s.get("errors")) == len(s.findall("testcase/error"))
        assert re.fullmatch(r"\d+\.\d{3}", s.get("time"))
    model = suites[MODEL]
    assert (model.get("tests"), model.get("failures")) == ("6", "6")  # 4 errors + 2 warnings
    failures = model.findall("testcase/failure")
    assert {f.get("type") for f in failures} == {"P21-SYNTAX", "SCH-ARITY",
                                                 "SCH-kinematic_joint.wr1", "KIN-UNITS",
                                                 "KIN-RANGE"}
    units = next(f for f in failures if f.get("type") == "KIN-UNITS")
    assert units.get("message") == "plane angle unit is <missing> & length unit is \"mm\" 'assumed'"
    wr1 = next(f for f in failures if f.get("type") == "SCH-kinematic_joint.wr1")
    assert wr1.get("message") == ("edge_start and edge_end are the same vertex: 100% degenerate"
                                  "\nsee #9 (#15 KINEMATIC_JOINT)")  # attribute newline kept
    names = [c.get("name") for c in model.findall("testcase")]
    assert "SCH-ARITY (#12 REVOLUTE_PAIR) at line 12, column 1" in names
    assert len(set(names)) == len(names)
    # a file with only notes passes, its notes in system-out (control characters escaped)
    odd = suites[ODD]
    assert [c.get("name") for c in odd.findall("testcase")] == ["conformance"]
    assert odd.find("testcase/failure") is None
    assert "bell\\x07 and CRLF\\r\\nend" in odd.find("system-out").text
    assert [c.get("name") for c in suites[CLEAN].findall("testcase")] == ["conformance"]
    missing = suites[MISSING]
    assert missing.get("errors") == "1" and missing.find("testcase/error") is not None
    assert (root.get("tests"), root.get("failures"), root.get("errors")) == ("9", "6", "1")


def test_junit_conforms_to_the_xsd():
    xmlschema = pytest.importorskip("xmlschema")
    schema = xmlschema.XMLSchema(str(SCHEMAS / "junit-10.xsd"))
    schema.validate(render("junit"))
    schema.validate(render("junit", []))


# -- GitHub ------------------------------------------------------------------------------

def _gh_unescape(s: str) -> str:
    return (s.replace("%3A", ":").replace("%2C", ",").replace("%0D", "\r")
            .replace("%0A", "\n").replace("%25", "%"))


def _gh_shown(s: str) -> str:
    """What a GitHub command shows of ``s`` once unescaped: other controls as \\xNN."""
    return re.sub("[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]", lambda m: f"\\x{ord(m.group()):02x}", s)


COMMAND = re.compile(r"^::(error|warning|notice) ([^:]*)::(.*)$")


def test_github_commands():
    lines = render("github").splitlines()
    commands = [COMMAND.match(line) for line in lines if line.startswith("::")]
    assert len(commands) == 9 and all(commands)
    assert ("::error file=models/arm.stp,line=12,col=1,title=SCH-ARITY::REVOLUTE_PAIR takes 6 "
            "attributes, found 5 (#12 REVOLUTE_PAIR)") in lines
    assert ("::warning file=models/arm.stp,line=15,col=1,title=SCH-kinematic_joint.wr1::"
            "edge_start and edge_end are the same vertex: 100%25 degenerate%0Asee #9 "
            "(#15 KINEMATIC_JOINT)") in lines
    assert "::error file=models/arm.stp,title=KIN-UNITS::plane angle unit is <missing> & " \
           "length unit is \"mm\" 'assumed'" in lines
    assert any(line.startswith("::warning file=models/arm.stp,line=20,title=KIN-RANGE::")
               for line in lines)
    odd = next(line for line in lines if "PAIR_VALUE" in line)
    assert odd == ("::notice file=odd dir/a%3Ab%2Cc%25.stp,title=SCH-NOT-EVALUATED::"
                   "bell\\x07 and CRLF%0D%0Aend, 50%25: done (#7 PAIR_VALUE)")
    # every command's properties and message decode back to the original values
    expected = sorted((d.file, d.rule, _gh_shown(f"{d.message} {entity_suffix(d)}".rstrip(" ")))
                      for r in fixed_results() for d in r.diagnostics)
    decoded = []
    for m in commands:
        props = dict(p.split("=", 1) for p in m.group(2).split(","))
        decoded.append((_gh_unescape(props["file"]), _gh_unescape(props["title"]),
                        _gh_unescape(m.group(3))))
    assert sorted(decoded) == expected
    assert lines[-4:] == [line for line in render("text").splitlines()[9:13]]


# -- GitLab ------------------------------------------------------------------------------

def test_gitlab_conforms_and_maps():
    schema = json.loads((SCHEMAS / "gitlab-codequality.schema.json").read_text(encoding="utf-8"))
    jsonschema.Draft7Validator.check_schema(schema)
    items = json.loads(render("gitlab"))
    jsonschema.Draft7Validator(schema).validate(items)
    jsonschema.Draft7Validator(schema).validate(json.loads(render("gitlab", [])))
    assert len(items) == 9
    fps = [i["fingerprint"] for i in items]
    assert len(set(fps)) == len(fps), "GitLab shows one finding per fingerprint"
    syntax = [i for i in items if i["check_name"] == "P21-SYNTAX"]
    base = Diagnostic("P21-SYNTAX", "error", SYNTAX_MSG, MODEL).fingerprint
    assert [s["fingerprint"] == base for s in syntax] == [True, False]
    assert [s["location"]["lines"]["begin"] for s in syntax] == [3, 30]
    assert {i["severity"] for i in items} == {"major", "minor", "info"}
    units = next(i for i in items if i["check_name"] == "KIN-UNITS")
    assert units["location"] == {"path": "models/arm.stp", "lines": {"begin": 1}}
    assert units["severity"] == "major"
    arity = next(i for i in items if i["check_name"] == "SCH-ARITY")
    assert arity["description"] == "REVOLUTE_PAIR takes 6 attributes, found 5 (#12 REVOLUTE_PAIR)"
    assert next(i for i in items if i["check_name"] == "P21-READ")["location"]["path"] == MISSING


# -- properties over arbitrary diagnostics --------------------------------------------------

_text = st.text(st.characters(blacklist_categories=("Cs",)), max_size=30)
_diag = st.builds(
    Diagnostic,
    rule=st.sampled_from(["P21-SYNTAX", "SCH-ARITY", "SCH-kinematic_joint.wr1", "KIN-UNITS",
                          NOT_EVALUATED]),
    severity=st.sampled_from(["error", "warning", "note"]),
    message=_text,
    file=st.sampled_from(["a.stp", "dir/b c.stp", "x:y,z%.stp"]),
    line=st.none() | st.integers(1, 10_000),
    column=st.none() | st.integers(1, 500),
    entity=st.none() | st.integers(1, 10**9),
    entity_type=st.none() | st.sampled_from(["REVOLUTE_PAIR", "KINEMATIC_JOINT"]),
)


def _results_of(diags):
    by_file: dict[str, list] = {}
    for d in diags:
        by_file.setdefault(d.file, []).append(d)
    return [RunResult.make(f, ds, 3, 4, 0.001) for f, ds in by_file.items()]


@settings(max_examples=60, deadline=None)
@given(st.lists(_diag, max_size=12))
def test_every_format_valid_and_order_free_for_any_diagnostics(sarif_validator, diags):
    results = _results_of(diags)
    sarif_validator.validate(json.loads(render("sarif", results)))
    shuffled = _results_of(list(reversed(diags)))
    for fmt in FORMATS:
        out = render(fmt, results)
        assert render(fmt, shuffled) == out
        out.encode("utf-8")
    assert len(render("text", results).split("\n")) - 1 == len(diags) + len(results) + \
        (len(results) > 1)
    assert [d["message"] for d in json.loads(render("json", results))["diagnostics"]] == \
        [d.message for d in sorted(diags)]
    ET.fromstring(render("junit", results).encode("utf-8"))
    gh = [line for line in render("github", results).split("\n") if line.startswith("::")]
    assert len(gh) == len(diags)
    for line, d in zip(gh, sorted(diags)):
        message = COMMAND.match(line).group(3)
        expected = f"{d.message} {entity_suffix(d)}" if entity_suffix(d) else d.message
        assert _gh_unescape(message) == _gh_shown(expected)
        assert "\r" not in line and not re.search("[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]", line)
    assert len({i["fingerprint"] for i in json.loads(render("gitlab", results))}) == len(diags)


# -- packaging boundary --------------------------------------------------------------------

def test_rules_package_does_not_import_click():
    code = ("import sys, p105cli.rules, p105cli.rules.report; "
            "print('click' in sys.modules, 'rich' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=Path(__file__).resolve().parents[2], check=True).stdout
    assert out.split() == ["False", "False"]
