"""Options shared by subcommands, declared once.

Each option's flags, destination, type, metavar and default live here; a command
gives only what is its own (the choices of --to, the meaning of --tol, a help
text that says what the option does in that command). Checks of values that
click's types cannot express (a positive --tol) are helpers here, called from
the command body so that the messages and their order stay as they are.
"""

from __future__ import annotations

import math

import click

#: The schema profiles an input may be read as.
PROFILES = ("ap214", "ap242", "p105")

# ---------------------------------------------------------------- inputs

#: One model or file to read (FILE, or ``-``/nothing: stdin).
input_argument = click.argument("input", metavar="[FILE|-]", required=False, default="-")

#: solve's model: optional, because a scene alone needs none.
model_argument = click.argument("model", metavar="[MODEL|-]", required=False, default=None)

#: validate's files: any number, none meaning stdin.
inputs_argument = click.argument("inputs", metavar="[FILES|-]...", nargs=-1)


def file_option(flag: str, dest: str, help: str):
    """An option naming a file, ``-`` being standard input (or output, for a picture): every
    FILE option of p105 accepts ``-`` (at most one input per run reads stdin; the command checks)."""
    return click.option(flag, dest, metavar="FILE|-", default=None, help=help)

# ---------------------------------------------------------------- output


KEEP_PARTIAL_HELP = ("With -o: write OUT even when the command fails (exit status not 0), with what "
                     "was computed before the failure; by default a failed run leaves OUT as it was.")


def _partial_needs_output(ctx) -> None:
    # Both callbacks run whatever the order on the command line; the second one decides.
    if "p105.output" in ctx.meta and "p105.keep_partial" in ctx.meta:
        if ctx.meta["p105.keep_partial"] and ctx.meta["p105.output"] in (None, "-"):
            raise click.UsageError("--keep-partial applies to -o OUT (stdout is written as it goes)")


def _note_output(ctx, param, value):
    ctx.meta["p105.output"] = value
    _partial_needs_output(ctx)
    return value


def _keep_partial(ctx, param, value):
    from .contract import Settings
    ctx.meta["p105.keep_partial"] = value
    _partial_needs_output(ctx)
    Settings.keep_partial = value


def output_to(help: str = "Write to OUT atomically (a temporary file renamed into place) instead of stdout.",
              partial: bool = True):
    """``-o OUT``, and with ``partial`` the ``--keep-partial`` that goes with it (see
    contract.open_output: OUT is replaced only when the command succeeds)."""
    out = click.option("-o", "--output", metavar="OUT", default=None, help=help, callback=_note_output)
    if not partial:
        return out
    keep = click.option("--keep-partial", is_flag=True, expose_value=False, callback=_keep_partial,
                        help=KEEP_PARTIAL_HELP)
    return lambda f: out(keep(f))


output_option = output_to()

stream_option = click.option(
    "--stream", is_flag=True,
    help="JSON Lines: a header record, then one instance per line (for very large files).")


def to_option(choices, default=None, help: str | None = None):
    """``--to FORMAT``: what a command writes; the choices are the command's."""
    return click.option("--to", "to", type=click.Choice(list(choices)), default=default,
                        show_default=default is not None, help=help)

# ---------------------------------------------------------------- the model


SCHEMA_HELP = ("Schema profile of the input (default: from FILE_SCHEMA; a 1996-layout file with "
               "su_parameters is read as p105).")
SCHEMA_HELP_SHORT = "Schema profile; default: chosen from FILE_SCHEMA."


def input_schema(help: str = SCHEMA_HELP):
    """``--schema``: the profile an input is read as (not the profile a command writes)."""
    return click.option("--schema", type=click.Choice(list(PROFILES)), default=None, help=help)


schema_option = input_schema()


def output_schema(choices, default=None, help: str | None = None):
    """``--schema``: the profile a command writes (its layout); the order of ``choices`` is the
    command's (its default first where it has one)."""
    return click.option("--schema", type=click.Choice(list(choices)), default=default,
                        show_default=default is not None, help=help)

mechanism_option = click.option(
    "--mechanism", "mechanism", metavar="NAME", default=None,
    help="Analyse the mechanism called NAME (needed when the file has several).")

# ---------------------------------------------------------------- numbers


def tol_option(default, help: str, metavar: str | None = None):
    """``--tol``: a positive tolerance; its meaning is the command's (check with :func:`check_tol`)."""
    return click.option("--tol", type=float, default=default, metavar=metavar,
                        show_default=default is not None, help=help)


def check_tol(tol) -> None:
    """A usage error unless ``tol`` (if given) is a positive finite number."""
    if tol is not None and not (tol > 0.0 and math.isfinite(tol)):
        raise click.UsageError("--tol must be a positive number")


def count_option(help: str, type=int):
    """``--count N``: N evenly spaced samples."""
    return click.option("--count", type=type, default=None, metavar="N", help=help)


def step_option(help: str):
    """``--step DT``: a sample every DT of the parameter."""
    return click.option("--step", type=float, default=None, metavar="DT", help=help)


angle_unit_option = click.option(
    "--angle-unit", type=click.Choice(["rad", "deg"]), default="rad", show_default=True,
    help="Unit of angles in --values, --set and the jsonl/csv output.")

length_unit_option = click.option(
    "--length-unit", type=click.Choice(["m", "mm"]), default="m", show_default=True,
    help="Unit of lengths in --values, --set, --path and the jsonl/csv output.")
