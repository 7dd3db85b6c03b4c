"""``p105 validate`` end to end: corpus clean, probes' known faults, formats, exit codes."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest

from conftest import CORPUS, EXAMPLES, ROOT, p21

DATA = ROOT / "tests" / "data"
GENERATED = sorted((DATA / "corpus").glob("*.stp"))
SARIF_SCHEMA = json.loads((DATA / "schemas" / "sarif-schema-2.1.0.json").read_text())


def _profile_args(path: Path) -> list[str]:
    return ["--schema", "p105"] if path.stem.endswith("_p105") else []


def _diags(p105, path, *extra):
    r = p105("validate", "-f", "json", *extra, path)
    return r, json.loads(r.stdout)


@pytest.mark.parametrize("path", GENERATED + sorted(EXAMPLES.glob("*.stp")),
                         ids=lambda p: p.name)
def test_generated_corpus_and_examples_validate_clean_with_full_coverage(p105, path):
    r, report = _diags(p105, path, *_profile_args(path))
    assert r.returncode == 0, r.stdout.decode()
    assert report["diagnostics"] == []
    summary = report["summary"]
    assert summary["rules_applicable"] > 100
    assert summary["rules_evaluated"] == summary["rules_applicable"]


def test_occt_style_probe_reports_the_derived_flags(p105):
    probe = CORPUS / "authored" / "probe_occt_style.stp"
    if not probe.exists():
        pytest.skip("shared corpus not present")
    r, report = _diags(p105, probe)
    assert r.returncode == 1
    derived = {(d["entity"], d["severity"], d["message"].split(":")[0]) for d in report["diagnostics"]
               if d["rule"] == "SCH-DERIVED-EXPLICIT"}
    # OCCT copies what the standard derives: a warning each, no error
    assert derived == {(15, "warning", "name, t_x, t_y, t_z, r_x, r_y, r_z"),
                       (20, "warning", "context_of_items")}
    assert not any(d["rule"].startswith("SCH-DERIVED") and d["severity"] == "error"
                   for d in report["diagnostics"])
    for d in report["diagnostics"]:
        assert set(d) >= {"rule", "severity", "message", "file", "line", "column", "entity", "entity_type",
                          "fingerprint"}


def test_1996_probe_breaks_kinematic_link_wr2(p105):
    probe = CORPUS / "authored" / "probe_p105_1996_ap214.stp"
    if not probe.exists():
        pytest.skip("shared corpus not present")
    r = p105("validate", "-f", "text", probe)
    assert r.returncode == 1
    assert b"error[SCH-kinematic_link.wr2]" in r.stdout and b"(#10 kinematic_link)" in r.stdout


def _broken_four_bar(tmp_path) -> Path:
    """The four-bar with one joint connecting a link to itself (kinematic_joint.wr1)."""
    text = (EXAMPLES / "four_bar_ap242.stp").read_text()
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if "=KINEMATIC_JOINT(" in line:
            head, args = line.split("(", 1)
            parts = args.rstrip(");").split(",")
            parts[-1] = parts[-2]
            lines[i] = f"{head}({','.join(parts)});"
            break
    out = tmp_path / "broken.stp"
    out.write_text("\n".join(lines) + "\n")
    return out


def test_a_violated_where_rule_is_reported_with_its_long_form_label(p105, tmp_path):
    r, report = _diags(p105, _broken_four_bar(tmp_path))
    assert r.returncode == 1
    rules = {d["rule"] for d in report["diagnostics"]}
    assert "SCH-kinematic_joint.wr1" in rules


def test_sarif_output_conforms_to_sarif_2_1_0(p105, tmp_path):
    r = p105("validate", "-f", "sarif", _broken_four_bar(tmp_path))
    assert r.returncode == 1
    doc = json.loads(r.stdout)
    jsonschema.Draft4Validator(SARIF_SCHEMA).validate(doc)
    assert any(res["ruleId"] == "SCH-kinematic_joint.wr1" for res in doc["runs"][0]["results"])


def test_github_format_is_chosen_automatically_on_actions(p105, tmp_path):
    r = p105("validate", _broken_four_bar(tmp_path), env={"GITHUB_ACTIONS": "true"})
    assert r.stdout.decode().startswith("::error file=")


def test_fail_on_exit_zero_select_and_ignore(p105, tmp_path):
    broken = _broken_four_bar(tmp_path)
    assert p105("validate", "--exit-zero", broken).returncode == 0
    assert p105("validate", "--ignore", "SCH-*", broken).returncode == 0
    selected = p105("validate", "-f", "json", "--select", "SCH-kinematic_joint.*", broken)
    assert {d["rule"] for d in json.loads(selected.stdout)["diagnostics"]} == {"SCH-kinematic_joint.wr1"}


def test_pass_copies_a_passing_input_unchanged(p105, tmp_path):
    example = EXAMPLES / "four_bar_ap242.stp"
    r = p105("validate", "--pass", "-", input=example.read_bytes())
    assert r.returncode == 0 and r.stdout == example.read_bytes()
    bad = p105("validate", "--pass", _broken_four_bar(tmp_path))
    assert bad.returncode == 1 and bad.stdout == b"" and b"SCH-kinematic_joint.wr1" in bad.stderr


def test_unreadable_and_unknown_schema_are_exit_2_and_several_files_take_the_worst(p105, tmp_path):
    bad_syntax = tmp_path / "bad.stp"
    bad_syntax.write_text(p21("#1=A(1 2);"))
    r = p105("validate", "-f", "json", bad_syntax)
    assert r.returncode == 2
    (d,) = json.loads(r.stdout)["diagnostics"]
    assert (d["rule"], d["line"], d["column"]) == ("P21-SYNTAX", 8, 8)
    unknown = tmp_path / "unknown.stp"
    unknown.write_text(p21("#1=A(1);"))
    r = p105("validate", unknown)
    assert r.returncode == 2 and b"ap214" in r.stdout and b"ap242" in r.stdout and b"p105" in r.stdout
    r = p105("validate", EXAMPLES / "four_bar_ap242.stp", _broken_four_bar(tmp_path), bad_syntax)
    assert r.returncode == 2


def test_list_rules_prints_express_sources(p105):
    r = p105("validate", "--list-rules", "--schema", "ap242")
    lines = r.stdout.decode().splitlines()
    assert r.returncode == 0
    joint = [line for line in lines if line.startswith("SCH-kinematic_joint.wr1\t")]
    assert joint and "WR1" in joint[0].upper()
    assert any(line.startswith("SCH-ARITY\t") for line in lines)


def test_big_real_files_give_no_errors(p105):
    big = sorted((CORPUS / "big").glob("*.step"))[:1]
    if not big:
        pytest.skip("shared corpus not present")
    r, report = _diags(p105, big[0])
    assert r.returncode == 0
    assert not [d for d in report["diagnostics"] if d["severity"] == "error"]


def test_validate_reads_json_models_like_part21(p105):
    example = EXAMPLES / "four_bar_ap242.stp"
    model = p105("parse", example).stdout
    from_json = p105("validate", "-f", "json", "-", input=model)
    from_p21 = p105("validate", "-f", "json", "-", input=example.read_bytes())
    assert from_json.returncode == from_p21.returncode == 0
    assert json.loads(from_json.stdout)["summary"]["rules_evaluated"] == \
        json.loads(from_p21.stdout)["summary"]["rules_evaluated"]
    passed = p105("validate", "--pass", "-o", "/dev/null", "-", input=model)
    assert passed.stdout == model


def test_report_file_is_written_atomically_and_names_syntax_errors(p105, tmp_path):
    out = tmp_path / "report.json"
    r = p105("validate", "-f", "json", "-o", out, input=p21("#1=A(1);\n#2=B(1 2);"))
    assert r.returncode == 2 and r.stdout == b""
    (d,) = json.loads(out.read_text())["diagnostics"]
    assert (d["file"], d["line"], d["column"], d["rule"]) == ("<stdin>", 9, 8, "P21-SYNTAX")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.json"]


def test_raw_8bit_bytes_are_a_p21_encoding_warning_per_line_with_line_and_column(p105, tmp_path):
    path = tmp_path / "gbk.stp"
    text = p21("#1=CARTESIAN_POINT('@@',(0.,0.,0.));\n#2=CARTESIAN_POINT('a@',(0.,0.,0.));",
               header=(EXAMPLES / "four_bar_ap242.stp").read_text().split("DATA;")[0])
    path.write_bytes(text.encode("ascii").replace(b"@@", "\u4e2a".encode("gbk"))
                     .replace(b"a@", b"a\xe9"))
    r, report = _diags(p105, path)
    assert r.returncode == 0  # a warning: the gate says so, and passes
    enc = [(d["line"], d["column"], d["severity"]) for d in report["diagnostics"]
           if d["rule"] == "P21-ENCODING"]
    header_lines = text.split("DATA;")[0].count("\n")
    assert enc == [(header_lines + 2, 21, "warning"), (header_lines + 3, 22, "warning")]
    assert not [d for d in report["diagnostics"] if d["rule"] == "P21-WARNING"]
    # parse and the analysis commands: one warning per file, at the first byte, with the count
    r = p105("parse", path)
    assert r.returncode == 0
    (line,) = r.stderr.decode().splitlines()
    assert line.startswith(f"p105: warning: {path}:{header_lines + 2}:21: not UTF-8: 3 raw 8-bit bytes")
