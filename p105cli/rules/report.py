"""Every report format of ``p105 validate``: one writer per format, all ``(results, out)``.

:data:`FORMATS` maps each ``-f`` name to its writer, in the order the CLI and the docs
list them; the first line of each writer's docstring is its one-line description.
Every writer is deterministic: it sorts files and diagnostics itself, so the same
results give the same bytes whatever order they were produced in. Writers emit
nothing that depends on the clock or the environment (``seconds`` comes from the
results), and they never write lone surrogates or characters XML forbids.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import xml.etree.ElementTree as ET
from typing import Callable, Iterable, Mapping, TextIO
from urllib.parse import quote

from p105cli import __version__

from .diagnostics import Diagnostic, RunResult, Summary, rule_description

__all__ = ["FORMATS", "FORMAT_NAME", "SARIF_SCHEMA_URI", "resolve_format", "write_report",
           "write_text", "write_json", "write_jsonl", "write_sarif", "write_junit",
           "write_github", "write_gitlab", "format_line", "entity_suffix"]

#: The ``format`` member of the JSON report (bumped on incompatible changes).
FORMAT_NAME = "p105-validate/1"

#: The published OASIS SARIF 2.1.0 schema (errata 01), named by ``$schema``.
SARIF_SCHEMA_URI = ("https://docs.oasis-open.org/sarif/sarif/v2.1.0/errata01/os/schemas/"
                    "sarif-schema-2.1.0.json")

#: The key of our fingerprint in SARIF ``partialFingerprints`` (versioned recipe).
SARIF_FINGERPRINT_KEY = "p105/v1"

Writer = Callable[[list, TextIO], None]


# -- shared helpers ----------------------------------------------------------------------

def _clean(s: str) -> str:
    """``s`` safe to encode as UTF-8: a lone surrogate becomes a visible ``\\udcXX``."""
    return s.encode("utf-8", "backslashreplace").decode("utf-8")


# Line breaks and other controls (a terminal escape, say) in text meant for one line.
_CONTROLS = re.compile("[\x00-\x08\x0a-\x1f\x7f\x85\u2028\u2029]")
_SHOWN = {"\n": "\\n", "\r": "\\r"}


def _show_control(m: re.Match) -> str:
    c = m.group()
    return _SHOWN.get(c) or (f"\\x{ord(c):02x}" if ord(c) < 0x100 else f"\\u{ord(c):04x}")


def _one_line(s: str) -> str:
    """``s`` on one line: LF and CR shown as ``\\n`` and ``\\r``, other controls but TAB
    as ``\\xNN`` (``\\u2028`` for the Unicode line separators)."""
    return _clean(_CONTROLS.sub(_show_control, s))


# XML 1.0 forbids C0 controls but TAB/LF/CR, and U+FFFE/U+FFFF.
_XML_BAD = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]")


def _xml(s: str) -> str:
    return _XML_BAD.sub(lambda m: f"\\x{ord(m.group()):02x}", _clean(s))


def _ordered(results: Iterable[RunResult]) -> list[RunResult]:
    return sorted(results, key=lambda r: r.file)


def _all_diags(results: Iterable[RunResult]) -> list[Diagnostic]:
    return sorted(d for r in results for d in r.diagnostics)


def _total(results: list[RunResult]) -> Summary:
    return Summary.combine(r.summary for r in results)


def entity_suffix(d: Diagnostic) -> str:
    """``"(#12 KINEMATIC_JOINT)"``, ``"(#12)"``, ``"(KINEMATIC_JOINT)"`` or ``""``."""
    parts = []
    if d.entity is not None:
        parts.append(f"#{d.entity}")
    if d.entity_type:
        parts.append(d.entity_type)
    return f"({' '.join(parts)})" if parts else ""


def _message_with_entity(d: Diagnostic) -> str:
    suffix = entity_suffix(d)
    return f"{d.message} {suffix}" if suffix else d.message


def format_line(d: Diagnostic) -> str:
    """The text form: ``FILE:LINE:COL: severity[RULE] message (#id TYPE)``.

    ``FILE:LINE:`` when the column is unknown, ``FILE:`` when the line is; newlines
    in the message are shown as ``\\n`` so that one finding is one line.
    """
    where = d.file
    if d.line is not None:
        where += f":{d.line}"
        if d.column is not None:
            where += f":{d.column}"
    return _one_line(f"{where}: {d.severity}[{d.rule}] {_message_with_entity(d)}")


def _summary_line(name: str, s: Summary, unreadable: str = "") -> str:
    line = (f"{name}: {s.errors} errors, {s.warnings} warnings, {s.notes} notes; "
            f"rules evaluated {s.rules_evaluated}/{s.rules_applicable}")
    if s.not_evaluated:
        line += f"; {s.not_evaluated} not evaluated"
    if unreadable:
        line += f"; {unreadable}"
    return _one_line(line)


def _file_summary_line(r: RunResult) -> str:
    return _summary_line(r.file, r.summary, "" if r.readable else "not readable")


def _file_entry(r: RunResult) -> dict:
    return {"file": _clean(r.file), "readable": r.readable, "summary": r.summary.as_dict()}


def _diag_dict(d: Diagnostic) -> dict:
    out = d.as_dict()
    for k in ("message", "file", "entity_type"):
        if out[k] is not None:
            out[k] = _clean(out[k])
    return out


# -- text --------------------------------------------------------------------------------

def write_text(results: list[RunResult], out: TextIO) -> None:
    """Human-readable lines FILE:LINE:COL: severity[RULE] message (#id TYPE), then summaries.

    After the sorted findings comes one summary line per file
    (``FILE: N errors, N warnings, N notes; rules evaluated E/A``, with
    ``; N not evaluated`` and ``; not readable`` when they apply) and, for several
    files, a ``p105 validate: N files, ...`` total.
    """
    results = _ordered(results)
    for d in _all_diags(results):
        out.write(format_line(d) + "\n")
    for r in results:
        out.write(_file_summary_line(r) + "\n")
    if len(results) > 1:
        total = _total(results)
        out.write(_summary_line(f"p105 validate: {total.files} files", total,
                                f"{total.unreadable} not readable" if total.unreadable else "")
                  + "\n")


# -- json / jsonl ------------------------------------------------------------------------

def _dumps(obj, **kw) -> str:
    return json.dumps(obj, ensure_ascii=False, allow_nan=False, **kw)


def write_json(results: list[RunResult], out: TextIO) -> None:
    """One JSON document: format, files, diagnostics and the run's summary."""
    results = _ordered(results)
    doc = {"format": FORMAT_NAME,
           "files": [_file_entry(r) for r in results],
           "diagnostics": [_diag_dict(d) for d in _all_diags(results)],
           "summary": _total(results).as_dict()}
    out.write(_dumps(doc, indent=2) + "\n")


def write_jsonl(results: list[RunResult], out: TextIO) -> None:
    """JSON Lines: one {"type": "diagnostic"} record per finding, then one {"type": "summary"}."""
    results = _ordered(results)
    compact = {"separators": (",", ":")}
    for d in _all_diags(results):
        out.write(_dumps({"type": "diagnostic", **_diag_dict(d)}, **compact) + "\n")
    summary = {"type": "summary", "format": FORMAT_NAME, **_total(results).as_dict(),
               "per_file": [_file_entry(r) for r in results]}
    out.write(_dumps(summary, **compact) + "\n")


# -- SARIF 2.1.0 -------------------------------------------------------------------------

_WINDOWS_ABS = re.compile(r"^[A-Za-z]:/")


def _uri(path: str) -> str:
    """A SARIF artifact URI: the path as given (``/`` separators), percent-encoded.

    Relative paths stay relative references; absolute ones become ``file://`` URIs.
    """
    p = _clean(path).replace("\\", "/")
    if p.startswith("./"):
        p = p[2:]
    if _WINDOWS_ABS.match(p):
        return "file:///" + quote(p, safe="/:")
    if p.startswith("/"):
        return "file://" + quote(p, safe="/")
    return quote(p, safe="/")


def write_sarif(results: list[RunResult], out: TextIO) -> None:
    """SARIF 2.1.0 (one run of tool p105), for GitHub code scanning and other SARIF viewers."""
    results = _ordered(results)
    diags = _all_diags(results)
    rule_ids = sorted({d.rule for d in diags})
    rule_index = {rule: i for i, rule in enumerate(rule_ids)}
    artifact_index = {r.file: i for i, r in enumerate(results)}
    sarif_results = []
    for d in diags:
        physical: dict = {"artifactLocation": {"uri": _uri(d.file)}}
        if d.file in artifact_index:
            physical["artifactLocation"]["index"] = artifact_index[d.file]
        if d.line is not None and d.line >= 1:
            region = {"startLine": d.line}
            if d.column is not None and d.column >= 1:
                region["startColumn"] = d.column
            physical["region"] = region
        result = {"ruleId": d.rule, "ruleIndex": rule_index[d.rule], "level": d.severity,
                  "message": {"text": _clean(d.message)},
                  "locations": [{"physicalLocation": physical}],
                  "partialFingerprints": {SARIF_FINGERPRINT_KEY: d.fingerprint}}
        props = {}
        if d.entity is not None:
            props["entity"] = d.entity
        if d.entity_type:
            props["entity_type"] = _clean(d.entity_type)
        if props:
            result["properties"] = props
        sarif_results.append(result)
    run = {
        "tool": {"driver": {
            "name": "p105",
            "version": __version__,
            "rules": [{"id": rule, "shortDescription": {"text": rule_description(rule)}}
                      for rule in rule_ids],
        }},
        "invocations": [{"executionSuccessful": all(r.readable for r in results)}],
        "artifacts": [{"location": {"uri": _uri(r.file)}} for r in results],
        "results": sarif_results,
        "columnKind": "unicodeCodePoints",
        "properties": {"summary": _total(results).as_dict(),
                       "files": [_file_entry(r) for r in results]},
    }
    log = {"$schema": SARIF_SCHEMA_URI, "version": "2.1.0", "runs": [run]}
    out.write(_dumps(log, indent=2) + "\n")


# -- JUnit XML ---------------------------------------------------------------------------

def _seconds(s: float) -> str:
    return f"{max(s, 0.0):.3f}"


def _testcase_name(d: Diagnostic) -> str:
    name = d.rule
    suffix = entity_suffix(d)
    if suffix:
        name += " " + suffix
    if d.line is not None:
        name += f" at line {d.line}"
        if d.column is not None:
            name += f", column {d.column}"
    return _xml(_one_line(name))


def write_junit(results: list[RunResult], out: TextIO) -> None:
    """JUnit XML: a testsuite per file, a failing testcase per error or warning.

    A file with no error or warning gets one passing testcase named ``conformance``;
    a file that could not be read gets a testcase ``read`` with an ``<error>``. Notes
    are not test cases (they are in the suite's ``<system-out>``).
    """
    results = _ordered(results)
    root = ET.Element("testsuites", {"name": "p105 validate"})
    tot_tests = tot_fail = tot_err = 0
    tot_time = 0.0
    for r in results:
        suite = ET.SubElement(root, "testsuite", {"name": _xml(r.file)})
        tests = failures = errors = 0
        if not r.readable:
            case = ET.SubElement(suite, "testcase", {"name": "read", "classname": _xml(r.file)})
            why = "; ".join(d.message for d in r.diagnostics if d.severity == "error")
            err = ET.SubElement(case, "error", {"type": "unreadable",
                                                "message": _xml(why or "file could not be read")})
            err.text = _xml("\n".join(format_line(d) for d in r.diagnostics))
            tests, errors = 1, 1
        else:
            findings = [d for d in r.diagnostics if d.severity in ("error", "warning")]
            for d in findings:
                case = ET.SubElement(suite, "testcase",
                                     {"name": _testcase_name(d), "classname": _xml(r.file)})
                fail = ET.SubElement(case, "failure", {"type": _xml(d.rule),
                                                       "message": _xml(_message_with_entity(d))})
                fail.text = _xml(format_line(d))
            tests, failures = len(findings), len(findings)
            if not findings:
                ET.SubElement(suite, "testcase", {"name": "conformance", "classname": _xml(r.file)})
                tests = 1
        notes = [d for d in r.diagnostics if d.severity == "note"]
        lines = [format_line(d) for d in notes] + [_file_summary_line(r)]
        ET.SubElement(suite, "system-out").text = _xml("\n".join(lines))
        suite.set("tests", str(tests))
        suite.set("failures", str(failures))
        suite.set("errors", str(errors))
        suite.set("skipped", "0")
        suite.set("time", _seconds(r.summary.seconds))
        tot_tests += tests
        tot_fail += failures
        tot_err += errors
        tot_time += r.summary.seconds
    root.set("tests", str(tot_tests))
    root.set("failures", str(tot_fail))
    root.set("errors", str(tot_err))
    root.set("time", _seconds(tot_time))
    ET.indent(root, space="  ")
    out.write('<?xml version="1.0" encoding="UTF-8"?>\n')
    out.write(ET.tostring(root, encoding="unicode") + "\n")


# -- GitHub Actions workflow commands ----------------------------------------------------

_GITHUB_LEVEL = {"error": "error", "warning": "warning", "note": "notice"}


# Controls other than TAB, CR and LF would reach the log raw: shown as \xNN instead.
_GH_CONTROLS = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]")


def _gh_data(s: str) -> str:
    """Escape a workflow-command message (actions/toolkit ``escapeData``: ``%``, CR, LF).

    Other control characters (a terminal escape in a quoted string, say) are shown as
    ``\\xNN`` rather than written to the log.
    """
    s = _clean(s).replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")
    return _GH_CONTROLS.sub(lambda m: f"\\x{ord(m.group()):02x}", s)


def _gh_property(s: str) -> str:
    """Escape a workflow-command property value (actions/toolkit ``escapeProperty``)."""
    return _gh_data(s).replace(":", "%3A").replace(",", "%2C")


def write_github(results: list[RunResult], out: TextIO) -> None:
    """GitHub Actions annotations (::error/::warning/::notice), then plain summary lines."""
    results = _ordered(results)
    for d in _all_diags(results):
        props = [f"file={_gh_property(d.file)}"]
        if d.line is not None:
            props.append(f"line={d.line}")
            if d.column is not None:
                props.append(f"col={d.column}")
        props.append(f"title={_gh_property(d.rule)}")
        out.write(f"::{_GITHUB_LEVEL[d.severity]} {','.join(props)}::"
                  f"{_gh_data(_message_with_entity(d))}\n")
    for r in results:
        out.write(_file_summary_line(r) + "\n")


# -- GitLab Code Quality -----------------------------------------------------------------

_GITLAB_SEVERITY = {"error": "major", "warning": "minor", "note": "info"}


def _gitlab_path(path: str) -> str:
    p = _clean(path).replace("\\", "/")
    return p[2:] if p.startswith("./") else p


def write_gitlab(results: list[RunResult], out: TextIO) -> None:
    """GitLab Code Quality JSON (a CodeClimate subset) for merge-request widgets.

    Severity: error -> ``major``, warning -> ``minor``, note -> ``info``. GitLab shows
    one finding per fingerprint, so a repeat of the same fingerprint (the same finding
    at another line) gets a derived one: ``sha256(fp + "#" + k)[:16]`` for its k-th repeat
    in sorted order. ``lines.begin`` is 1 when the line is unknown.
    """
    items = []
    seen: dict[str, int] = {}
    for d in _all_diags(_ordered(results)):
        fp = d.fingerprint
        k = seen.get(fp, 0)
        seen[fp] = k + 1
        if k:
            fp = hashlib.sha256(f"{fp}#{k}".encode()).hexdigest()[:16]
        items.append({"description": _clean(_message_with_entity(d)),
                      "check_name": d.rule,
                      "fingerprint": fp,
                      "severity": _GITLAB_SEVERITY[d.severity],
                      "location": {"path": _gitlab_path(d.file),
                                   "lines": {"begin": d.line if d.line and d.line >= 1 else 1}}})
    out.write(_dumps(items, indent=2) + "\n")


# -- registry ----------------------------------------------------------------------------

#: ``-f`` name -> writer, in the order the CLI's help and the docs list them.
FORMATS: dict[str, Writer] = {
    "text": write_text,
    "json": write_json,
    "jsonl": write_jsonl,
    "sarif": write_sarif,
    "junit": write_junit,
    "github": write_github,
    "gitlab": write_gitlab,
}


def describe(name: str) -> str:
    """The one-line description of a format (its writer's docstring's first line)."""
    return (FORMATS[name].__doc__ or "").strip().splitlines()[0]


def resolve_format(name: str, environ: Mapping[str, str] | None = None) -> str:
    """The concrete format for ``-f NAME``: ``auto`` is ``github`` under GitHub Actions,
    else ``text``.

    GitHub Actions is detected by a non-empty ``GITHUB_ACTIONS`` variable that is not
    ``false``/``0`` (the runner sets it to ``true``). Unknown names raise ValueError.
    """
    if name == "auto":
        env = os.environ if environ is None else environ
        flag = env.get("GITHUB_ACTIONS", "").strip().lower()
        return "github" if flag and flag not in ("false", "0") else "text"
    if name not in FORMATS:
        raise ValueError(f"unknown report format {name!r} (expected auto or one of: "
                         f"{', '.join(FORMATS)})")
    return name


def write_report(fmt: str, results: list[RunResult], out: TextIO,
                 environ: Mapping[str, str] | None = None) -> None:
    """Write ``results`` to ``out`` in format ``fmt`` (``auto`` resolved from ``environ``)."""
    FORMATS[resolve_format(fmt, environ)](list(results), out)
