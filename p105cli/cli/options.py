"""Options shared by subcommands, declared once."""

from __future__ import annotations

import click

input_argument = click.argument("input", metavar="[FILE|-]", required=False, default="-")

output_option = click.option(
    "-o", "--output", metavar="OUT", default=None,
    help="Write to OUT atomically (a temporary file renamed into place) instead of stdout.")

stream_option = click.option(
    "--stream", is_flag=True,
    help="JSON Lines: a header record, then one instance per line (for very large files).")

schema_option = click.option(
    "--schema", type=click.Choice(["ap214", "ap242", "p105"]), default=None,
    help="Schema profile of the input (default: from FILE_SCHEMA; a 1996-layout file with "
         "su_parameters is read as p105).")
