"""``p105 export``: leave the toolchain in the format the next tool wants."""

from __future__ import annotations

import click

from .contract import EXIT_STATUS_TEXT, load_document, open_output, report_warnings
from .options import input_argument, output_option, stream_option
from ._emit import emit_json, emit_p21


@click.command(epilog=EXIT_STATUS_TEXT)
@click.option("--to", "to", type=click.Choice(["p21", "json"]), default="p21", show_default=True,
              help="Output format: Part 21 text, or the p105/1 JSON model.")
@input_argument
@output_option
@stream_option
def export(to, input, output, stream):
    """Write a model (Part 21 or p105/1 JSON, sniffed) as Part 21 or JSON.

    Part 21 output is canonical: one instance per line, shortest exact
    reals, header as read. The same model always gives the same bytes.
    """
    if stream and to != "json":
        raise click.UsageError("--stream applies to --to json only")
    doc = load_document(input)
    with open_output(output, (input,)) as out:
        if to == "p21":
            emit_p21(doc, out)
        else:
            emit_json(doc, out, stream)
    report_warnings(doc)
