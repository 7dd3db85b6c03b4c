"""``p105 parse``: Part 21 in, the lossless p105/1 JSON model out."""

from __future__ import annotations

import click

from .contract import EXIT_STATUS_TEXT, open_output, report_warnings
from .inputs import load_document
from .options import input_argument, output_option, stream_option
from ._emit import emit_json


@click.command(epilog=EXIT_STATUS_TEXT)
@input_argument
@output_option
@stream_option
def parse(input, output, stream):
    """Read a Part 21 file (or a p105/1 model) and write the p105/1 JSON model.

    Every instance is kept, kinematic or not; `p105 export --to p21` gives
    the Part 21 file back. Syntax errors are reported as FILE:LINE:COL.
    """
    doc = load_document(input, decodes_all=True)  # emit_json reports a syntax error
    with open_output(output, (input,)) as out:
        emit_json(doc, out, stream)
    report_warnings(doc)
