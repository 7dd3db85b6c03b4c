"""``p105 validate``: the CI gate for kinematic exchange files."""

from __future__ import annotations

import sys

import click

from .contract import EXIT_STATUS_TEXT, ExitCode, copy_to_stdout, diag, open_output
from .inputs import decode, parse_document, read_input_bytes
from .options import SCHEMA_HELP_SHORT, inputs_argument, output_to, input_schema

FORMAT_NAMES = ["auto", "text", "json", "jsonl", "sarif", "junit", "github", "gitlab"]


def _check_one(path: str, schema: str | None, timings: bool):
    """(RunResult, raw bytes or None) for one input; unreadable inputs become results too."""
    from p105cli.rules.diagnostics import Diagnostic, RunResult
    from p105cli.rules.validate import validate_document
    from p105cli.schema.profiles import UnknownSchemaError
    from p105cli.step import StepError, StepSyntaxError

    raw, source = read_input_bytes(path)
    try:
        doc = parse_document(decode(raw), source, decodes_all=True)  # rules report P21-SYNTAX
        try:
            return validate_document(doc, source, schema, timings), raw
        except UnknownSchemaError:
            # A syntax error says more than an unknown schema: decode everything first.
            for _ in doc.records():
                pass
            raise
    except StepSyntaxError as err:
        diag = Diagnostic("P21-SYNTAX", "error", err.message, source, err.line or None, err.column or None)
    except StepError as err:
        entity = getattr(err, "instance_id", None)
        pointer = getattr(err, "pointer", "")  # a JSON model's place (/data/0), as the other commands say it
        message = f"{pointer}: {err.message}" if pointer.startswith("/") else err.message
        diag = Diagnostic("P21-STRUCTURE", "error", message, source, entity=entity)
    except UnknownSchemaError as err:
        diag = Diagnostic("P21-SCHEMA", "error", str(err), source)
    return RunResult.make(source, [diag], readable=False), None


@click.command(epilog=EXIT_STATUS_TEXT)
@inputs_argument
@click.option("-f", "--format", "fmt", type=click.Choice(FORMAT_NAMES), default="auto", show_default=True,
              help="Report format; auto is github when GITHUB_ACTIONS is set, else text.")
@click.option("--fail-on", type=click.Choice(["error", "warning", "note"]), default="error", show_default=True,
              help="Exit 1 when a diagnostic of this severity or worse is reported.")
@click.option("--exit-zero", is_flag=True, help="Exit 0 even with findings (unreadable input still exits 2).")
@click.option("--select", multiple=True, metavar="PATTERNS",
              help="Report only rules matching these globs (comma-separated or repeated), e.g. 'SCH-*'.")
@click.option("--ignore", multiple=True, metavar="PATTERNS",
              help="Do not report rules matching these globs, e.g. 'KIN-UNREACHABLE'.")
@input_schema(SCHEMA_HELP_SHORT)
@output_to("Write the report to OUT atomically instead of stdout (also when it has findings).", partial=False)
@click.option("--pass", "pass_through", is_flag=True,
              help="If the input passes, copy it unchanged to stdout (the report goes to stderr or -o).")
@click.option("--list-rules", is_flag=True,
              help="Print every rule of the --schema profile (default ap242) with its EXPRESS source, and exit.")
@click.option("--timings", is_flag=True, help="Record the time spent in the summary (makes output vary).")
def validate(inputs, fmt, fail_on, exit_zero, select, ignore, schema, output, pass_through, list_rules, timings):
    """Check Part 21 files (or p105/1 models) against the schema and Part 105's rules.

    Reports P21-* syntax, structure and encoding (P21-ENCODING: raw 8-bit
    bytes that are not UTF-8, a warning per line), SCH-* conformance (types,
    arity, references, entity types unknown to the declared schema, and the
    WHERE, UNIQUE and global rules evaluated from the EXPRESS long form on
    every kinematic instance and what it uses), and KIN-* checks the schema
    cannot express (units, ranges, placements). A value written where the
    schema derives the attribute is compared with the derivation:
    SCH-DERIVED-EXPLICIT (warning) when equal, SCH-DERIVED-CONFLICT (error,
    naming both values) when not. The edition of AP214 comes from
    FILE_SCHEMA's object identifier (edition 1 writes a unit's dimensions).
    With several files all are checked and the exit status is the worst.
    """
    from p105cli.rules.diagnostics import exit_code

    if list_rules:
        return _list_rules(schema, output)
    inputs = inputs or ("-",)
    if pass_through and len(inputs) != 1:
        raise click.UsageError("--pass takes exactly one input")
    results, raws = _check_all(inputs, schema, timings, select, ignore)
    code = exit_code(results, fail_on, exit_zero)
    if output is not None:
        _say_unreadable(results)
        if code == ExitCode.FINDINGS:
            _say_findings(results, output)
    _report(fmt, results, output, inputs, pass_through)
    if pass_through and code == ExitCode.OK and raws[0] is not None:
        copy_to_stdout(raws[0])  # the input's own bytes, unchanged
    if code:
        raise click.exceptions.Exit(code)


def _list_rules(schema, output):
    from p105cli.rules.validate import list_rules as rules_of
    from p105cli.schema.profiles import get_profile
    with open_output(output) as out:
        for rule, text in rules_of(get_profile(schema or "ap242")):
            out.write(f"{rule}\t{text}\n")


def _check_all(inputs, schema, timings, select, ignore):
    """(results, raw bytes) of every input, the diagnostics selected."""
    from p105cli.rules.diagnostics import RunResult, parse_patterns, select_rules
    sel, ign = parse_patterns(select), parse_patterns(ignore)
    results, raws = [], []
    for path in inputs:
        result, raw = _check_one(path, schema, timings)
        if sel or ign:
            kept = select_rules(result.diagnostics, sel, ign)
            result = RunResult.make(result.file, kept, result.summary.rules_evaluated,
                                    result.summary.rules_applicable, result.summary.seconds, result.readable)
        results.append(result)
        raws.append(raw)
    return results, raws


def _say_unreadable(results):
    """The report is in a file: still say on stderr why a file could not be checked."""
    for result in results:
        if not result.readable:
            for d in result.diagnostics:
                where = f"{d.file}:{d.line}:{d.column}" if d.line else d.file
                diag("error", f"{where}: {d.message}")


def _say_findings(results, output):
    """The report is in a file: an exit 1 still says why on stderr, one line per file."""
    for result in results:
        s = result.summary
        if result.readable and (s.errors or s.warnings or s.notes):
            diag("error", f"{result.file}: {s.errors} errors, {s.warnings} warnings, {s.notes} notes "
                          f"(the report is in {output})")


def _report(fmt, results, output, inputs, pass_through):
    """The report on stdout or -o; with --pass, stdout is the input's, so stderr or -o."""
    from p105cli.rules.report import write_report
    if pass_through and output is None:
        write_report("text" if fmt == "auto" else fmt, results, sys.stderr)
        return
    with open_output(output, inputs, report=True) as out:  # findings are the verdict: written
        write_report(fmt, results, out)
