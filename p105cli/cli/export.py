"""``p105 export``: leave the toolchain in the format the next tool wants."""

from __future__ import annotations

import click

from .contract import (EXIT_STATUS_TEXT, READ_LENIENTLY_TEXT, ExitCode, InputError, diag, open_output,
                       report_deviations, report_warnings)
from .inputs import load_document, naming_source
from .options import input_argument, output_option, output_schema, stream_option, to_option
from ._emit import emit_json, emit_p21


def _convert(doc, schema: str, occt_compat: bool):
    """The document converted to ``schema`` (p105cli.part105.write_mechanism); diagnostics on stderr."""
    from p105cli.part105.model_file import ModelFile
    from p105cli.part105.read_mechanism import read_mechanisms
    from p105cli.part105.write_mechanism import write_mechanism

    with naming_source(doc):
        model = ModelFile.of(doc)  # one population: the mechanism is read and converted from it
        try:
            mechanisms = read_mechanisms(model)
        finally:
            report_deviations(doc)
    if len(mechanisms) != 1:
        what = "no mechanism" if not mechanisms else f"{len(mechanisms)} mechanisms"
        raise InputError(f"{doc.source}: holds {what}; --schema converts a file with one mechanism")
    with naming_source(doc):  # the conversion reads the source too: its errors name the file
        out, diagnostics = write_mechanism(mechanisms[0], schema, source=model, occt_compat=occt_compat)
    for message in diagnostics:
        diag("warning", f"{doc.source}: {message}")
    return out


#: How many of the converted file's errors are listed before "and N more".
GATE_SHOWN = 10


def _gate(doc, schema: str) -> bool:
    """True when the converted model passes validate; its errors on stderr otherwise.

    The contract of --schema: never write, with exit 0, a file that validate
    rejects. A conversion carries over what it does not touch, the source's
    own defects too (a dangling reference, a missing attribute), and those
    are what this stops; the ids are the converted file's."""
    import io

    from p105cli.rules.validate import validate_document
    from p105cli.step import read_step, write_step

    text = io.StringIO()
    write_step(doc, text)
    converted = read_step(text.getvalue(), doc.source)
    result = validate_document(converted, doc.source, "p105" if schema == "p105" else None)
    errors = [d for d in result.diagnostics if d.severity == "error"]
    for d in errors[:GATE_SHOWN]:
        where = f"#{d.entity} ({d.entity_type.lower()}) of the result" if d.entity is not None else "the result"
        diag("error", f"{doc.source}: converted to {schema}, {where} breaks {d.rule}: {d.message}")
    if len(errors) > GATE_SHOWN:
        diag("error", f"{doc.source}: converted to {schema}, the result breaks {len(errors) - GATE_SHOWN} more rules")
    if errors:
        diag("error", f"{doc.source}: not converted: the {schema} result would not pass p105 validate "
                      f"({len(errors)} {'error' if len(errors) == 1 else 'errors'})")
    return not errors


@click.command(epilog=READ_LENIENTLY_TEXT + EXIT_STATUS_TEXT)
@to_option(["p21", "json"], "p21", help="Output format: Part 21 text, or the p105/1 JSON model.")
@output_schema(["ap214", "p105", "ap242"],
               help="Convert the mechanism to this schema profile's layout (ap214 and p105: the "
                    "Part 105:1996 layout, p105 with su_parameters; ap242: the AP242 layout). "
                    "What the target cannot express is reported on stderr.")
@click.option("--occt-compat", is_flag=True,
              help="With --schema ap242: write what Open CASCADE misreads explicitly (pair freedom "
                   "flags, pair names, state contexts) instead of the standard '*', and leave out "
                   "what it does not read (actuation, loops, configuration sequences).")
@input_argument
@output_option
@stream_option
def export(to, schema, occt_compat, input, output, stream):
    """Write a model (Part 21 or p105/1 JSON, sniffed) as Part 21 or JSON.

    Part 21 output is canonical: one instance per line, shortest exact
    reals, header as read. The same model always gives the same bytes.
    With --schema the mechanism is converted between the Part 105:1996
    layout (ap214; p105 allows su_parameters) and the AP242 layout;
    everything else in the file is kept, and whatever the target cannot
    express is reported on stderr with its #id. A pair the target has no
    entity for (an AP242 low_order_kinematic_pair whose freedom flags are
    no named pair's, going to the 1996 layout) is not dropped: the
    conversion is refused with exit 1, naming the pair, and nothing is
    written.

    --occt-compat (AP242 only): Open CASCADE's reader misreads the
    standard '*' of derived attributes (it takes the freedom flags of a
    revolute pair as all TRUE) and does not know actuated pairs, loops or
    configuration sequences; this writes the flags, pair names and state
    contexts explicitly, orientations as rotation_about_direction, and
    leaves actuation, loops and sequences out (each reported), so the file
    loads there with an empty check list. Without it the output is the
    standard form, which p105 validate passes: a conversion whose result
    validate would reject (the source's own errors carried over, what the
    target cannot hold) lists the result's errors and exits 1 without
    writing it.

    With --schema a file read with departures from its schema (warned as
    graph and solve warn them) is repaired: the converted mechanism is
    written in the standard form, each link representation in its shape's
    context and in a context of its own, the 1996 ground in one of its own
    (each repair a warning). What cannot be repaired is exit 1 naming it,
    and nothing is written.
    """
    if stream and to != "json":
        raise click.UsageError("--stream applies to --to json only")
    if occt_compat and schema != "ap242":
        raise click.UsageError("--occt-compat applies to --schema ap242 only")
    doc = load_document(input)
    passes = True
    if schema is not None:
        from p105cli.part105.emit import NotWritableError
        report_warnings(doc)
        try:
            doc = _convert(doc, schema, occt_compat)
        except NotWritableError as err:  # the target cannot express it or the source cannot be
            # repaired to conform (convert.RepairError): no output, not a bad input
            diag("error", f"{doc.source}: {err}")
            return ExitCode.FINDINGS
        # (--occt-compat writes Open CASCADE's dialect on purpose: not validate's to judge)
        passes = occt_compat or _gate(doc, schema)
    if passes or output not in (None, "-"):  # a failed -o is written only with --keep-partial
        with open_output(output, (input,)) as out:
            if to == "p21":
                emit_p21(doc, out)
            else:
                emit_json(doc, out, stream)
    if schema is None:
        report_warnings(doc)
    if not passes:
        raise click.exceptions.Exit(ExitCode.FINDINGS)
