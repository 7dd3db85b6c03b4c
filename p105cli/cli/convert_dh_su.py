"""``p105 convert-dh-su``: DH tables to Part 105 mechanisms (Annex F) and back."""

from __future__ import annotations

import click

from .contract import EXIT_STATUS_TEXT, ExitCode, InputError, diag, open_output
from .inputs import naming_source, nesting_guard, parse_document, read_text
from .options import input_argument, output_option, output_schema, to_option

SCHEMAS = ["ap242", "p105", "ap214"]
TARGETS = ["p21", "json", "dh", "dh-json"]


def _table(text: str, source: str, convention, deg: bool, name):
    """The DH table of the input (CSV or JSON, sniffed)."""
    from p105cli.formats import dh_table

    with nesting_guard(source):  # sniffing and reading a JSON table decode JSON
        kind = dh_table.looks_like_dh(text)
        table = _read_table(text, source, kind, convention, deg)
    if name:
        from dataclasses import replace
        table = replace(table, name=name)
    return table


def _read_table(text, source, kind, convention, deg):
    from p105cli.formats import dh_table

    if kind is None:
        from p105cli.step import sniff
        if sniff(text) != "unknown":
            raise click.UsageError(f"{source} is a model; convert-dh-su reads a DH table (CSV or JSON) "
                                   "unless --to dh or --to dh-json asks for the table of a model")
        raise InputError(f"{source}: neither a Part 21 file nor a p105/1 JSON model, and not a DH table "
                         f"(CSV with the header {','.join(dh_table.COLUMNS)}, or JSON with \"joints\")")
    if kind == "csv" and convention is None:
        raise click.UsageError("--convention standard|modified is required: a DH table does not "
                               "say which convention it uses")
    try:
        if kind == "csv":
            return dh_table.read_csv(text, convention, deg=deg, source=source)
        return dh_table.read_json(text, convention, deg=deg, source=source)
    except dh_table.DHTableError as err:
        raise InputError(str(err)) from None


def _model_to_table(text: str, source: str, convention, name):
    """The DH table of the model's serial chain; exit 1 naming the pair that is not a DH row."""
    from p105cli.formats.dh_table import looks_like_dh
    from p105cli.kinematics import dh
    from p105cli.part105.read_mechanism import read_mechanism

    if convention is None:
        raise click.UsageError("--convention standard|modified is required: say which DH form to write")
    with nesting_guard(source):
        table_text = looks_like_dh(text) is not None
    if table_text:
        raise click.UsageError(f"{source} is a DH table; --to dh/dh-json reads a model (Part 21 or "
                               "p105/1 JSON)")
    doc = parse_document(text, source)
    with naming_source(doc):
        mech = read_mechanism(doc, name=name)
    try:
        return dh.from_mechanism(mech, convention)
    except dh.DHConversionError as err:
        diag("error", f"{source}: mechanism {mech.name!r}: {err}")
        raise click.exceptions.Exit(ExitCode.FINDINGS) from None


def _write_table(text, source, convention, deg, name, to, input, output):
    from p105cli.formats import dh_table

    table = _model_to_table(text, source, convention, name)
    if to == "dh" and not (dh_table.is_identity(table.base) and dh_table.is_identity(table.tool)):
        diag("warning", f"{source}: the base placement or tool frame is not the identity and CSV "
                        "cannot hold it; use --to dh-json to keep it")
    with open_output(output, (input,)) as out:
        (dh_table.write_csv if to == "dh" else dh_table.write_json)(table, out, deg=deg)


def _write_model(text, source, convention, deg, name, schema, to, input, output):
    from p105cli.kinematics import dh
    from p105cli.part105.write_mechanism import write_mechanism
    from ._emit import emit_json, emit_p21

    table = _table(text, source, convention, deg, name)
    mech = dh.to_mechanism(table, "ap242" if schema == "ap242" else "1996")
    doc, notes = write_mechanism(mech, schema)
    for note in notes:
        diag("warning", f"{source}: {note}")
    with open_output(output, (input,)) as out:
        if to == "p21":
            emit_p21(doc, out)
        else:
            emit_json(doc, out, False)


@click.command(epilog=EXIT_STATUS_TEXT)
@click.option("--convention", type=click.Choice(["standard", "modified"]), default=None,
              help="DH convention: standard (Rz(theta) Tz(d) Tx(a) Rx(alpha)) or modified (Craig: "
                   "Rx(alpha) Tx(a) Rz(theta) Tz(d)). Required (a JSON table may say it instead).")
@click.option("--deg", is_flag=True,
              help="Angles of the table (alpha, theta, revolute offsets and limits) are in degrees, "
                   "in and out; default radians.")
@output_schema(SCHEMAS, "ap242",
               help="Schema profile of the model written: AP242 layout, Part 105:1996 layout with "
                    "su_parameters (p105), or AP214 (pair frames as the equivalent axis2_placement_3d).")
@to_option(TARGETS, "p21",
           help="Output: the mechanism as Part 21 or p105/1 JSON, or (from a model) its DH table "
                "as CSV (dh) or JSON with base and tool (dh-json).")
@click.option("--name", default=None, metavar="NAME",
              help="Name of the mechanism written (default: the JSON table's name, else dh_arm); with "
                   "--to dh/dh-json, the mechanism of the model to read.")
@input_argument
@output_option
def convert_dh_su(convention, deg, schema, to, name, input, output):
    """Convert a Denavit-Hartenberg table to a Part 105 mechanism (ISO 10303-105 Annex F).

    The table is CSV with the header name,type,a,alpha,d,theta,offset
    (type R or P; the joint variable q gives theta = q + offset for R and
    d = q + offset for P, so that field is empty or 0; optional lower,upper
    columns limit q) or JSON {"convention", "joints": [...], "base": 4x4,
    "tool": 4x4}. Lengths in metres. The mechanism has links link0 (the
    base) to linkN whose frames are the DH frames, one pair per joint named
    after it, the base transform as the base placement, the tool as the
    frame "tool" of linkN, and the initial state q = 0.

    With --to dh (CSV) or --to dh-json the input is a model: the serial
    chain of revolute and prismatic pairs from its base link is read back
    as a DH table; a pair whose placements are not a DH row is named (exit 1).
    """
    text, source = read_text(input)
    if to in ("dh", "dh-json"):
        _write_table(text, source, convention, deg, name, to, input, output)
    else:
        _write_model(text, source, convention, deg, name, schema, to, input, output)
