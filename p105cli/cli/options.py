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
