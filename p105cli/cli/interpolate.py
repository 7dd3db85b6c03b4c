"""``p105 interpolate``: sample kinematic paths and configuration sequences at t."""

from __future__ import annotations

import click

from .contract import (EXIT_STATUS_TEXT, READ_LENIENTLY_TEXT, ExitCode, InputError, diag, open_output,
                       report_deviations, report_warnings)
from .inputs import load_document, naming_source, source_of
from .options import count_option, input_argument, output_option, schema_option, step_option, to_option


@click.command(epilog=READ_LENIENTLY_TEXT + EXIT_STATUS_TEXT)
@input_argument
@click.option("--what", type=click.Choice(["all", "paths", "configurations"]), default="all", show_default=True,
              help="Sample the kinematic paths, the configuration interpolation sequences, or both.")
@click.option("--path", "paths", multiple=True, metavar="NAME",
              help="Only the path(s) of this name (repeatable).")
@click.option("--sequence", "sequences", multiple=True, metavar="NAME",
              help="Only the configuration sequence(s) of this name (repeatable).")
@click.option("--t", "t_values", multiple=True, type=float, metavar="T",
              help="Sample at this parameter value (repeatable).")
@step_option("Sample every DT from the start of each path or sequence (its end included).")
@count_option("Sample N evenly spaced values over each path or sequence (ends included).")
@click.option("--nodes/--no-nodes", default=None,
              help="Also sample every node (segment end). Default: on with --step, and when no "
                   "sampling option is given (then only the nodes are sampled).")
@click.option("--quaternion", type=click.Choice(["wxyz", "xyzw"]), default=None,
              help="Add each frame's rotation as a unit quaternion in this (labelled) order, w >= 0.")
@click.option("--ypr", is_flag=True, help="Add each frame's rotation as ypr angles (ISO 10303-105 Annex E), radians.")
@to_option(["jsonl", "csv"], "jsonl",
           help="JSON Lines records, or a CSV table (needs --what paths or --what configurations).")
@schema_option
@output_option
def interpolate(input, what, paths, sequences, t_values, step, count, nodes, quaternion, ypr, to, schema, output):
    """Sample the model's kinematic paths and configuration sequences at parameter values t.

    Paths (AP242 kinematic_path_defined_by_nodes: point-to-point, linear,
    circular and curve-based segments; several segments make a composite
    path) give the 4x4 placement of the link frame that follows them, in
    metres, in the path's coordinate system. Rotations are interpolated by
    slerp of unit quaternions (never by angles), synchronised with the
    translation on one parameter; translations as the segment type says
    (linear; along the circle through the via point; along the path curve).
    Point-to-point segments prescribe no interpolation: their samples use
    the linear rule and say "prescribed": false.

    Configuration interpolation sequences (both layouts) give every pair's
    values at t (SI units, radians): linear, synchronous (linear law,
    "prescribed": false), discontinuous or undefined (held until the next
    configuration). Spherical pair rotations are slerped.

    Records (--to jsonl): {"type": "frame", "path", "link", "t", "segment",
    "segment_kind", "prescribed", "matrix"} and {"type": "configuration",
    "sequence", "t", "interval", "interpolation", "prescribed", "pairs"},
    then one {"type": "summary"} record. Exit 1 when the model has nothing
    that can be sampled.

    An option that would do nothing with the --what chosen is a usage error
    (exit 2): --path, --quaternion and --ypr with --what configurations,
    --sequence with --what paths.
    """
    given = _check(t_values, step, count, to, what)
    _check_what(what, paths, sequences, quaternion, ypr)
    from p105cli.formats import samples
    from p105cli.motion import sampling
    from p105cli.part105.model_file import ModelFile
    from p105cli.part105.motion import sample_model

    doc = load_document(input)
    plan = sampling.Plan(t=tuple(t_values) or None, step=step, count=count,
                         nodes=(step is not None or given == 0) if nodes is None else nodes,
                         quaternion=quaternion, ypr=ypr)
    try:
        with naming_source(doc):
            model = ModelFile.of(doc, schema)  # kept: its reading warnings are reported
            result = sample_model(model, what=what, paths=paths, sequences=sequences, plan=plan)
    except sampling.SamplingError as err:
        raise InputError(f"{source_of(doc)}: {err}") from None
    for inst, msg in result.skipped:
        diag("warning", f"{source_of(doc)}: #{inst}: {msg}")
    try:
        with naming_source(doc), open_output(output, (input,)) as out:
            if to == "jsonl":
                samples.write_jsonl(result, out)
            else:
                samples.write_csv(result, out, what)
    except sampling.SamplingError as err:
        raise InputError(f"{source_of(doc)}: {err}") from None
    report_warnings(doc)
    report_deviations(doc)
    if not result.path_list and not result.sequence_list:
        diag("error", f"{source_of(doc)}: nothing to interpolate (no sampled path or configuration sequence)")
        raise click.exceptions.Exit(ExitCode.FINDINGS)


def _check(t_values, step, count, to, what) -> int:
    """The usage errors; how many of --t, --step and --count are given."""
    given = sum(x is not None and x != () for x in (t_values or None, step, count))
    if given > 1:
        raise click.UsageError("give at most one of --t, --step and --count")
    if to == "csv" and what == "all":
        raise click.UsageError("--to csv needs --what paths or --what configurations (their columns differ)")
    if count is not None and count < 1:
        raise click.BadParameter("must be at least 1", param_hint="--count")
    if step is not None and not step > 0.0:
        raise click.BadParameter("must be positive", param_hint="--step")
    return given


def _check_what(what, paths, sequences, quaternion, ypr) -> None:
    """Options that would do nothing with the --what chosen are usage errors."""
    if what == "configurations":
        for flag, given, does in (("--path", paths, "names a kinematic path"),
                                  ("--quaternion", quaternion, "adds to the kinematic paths' frames"),
                                  ("--ypr", ypr, "adds to the kinematic paths' frames")):
            if given:
                raise click.UsageError(f"{flag} {does}: --what configurations samples only the configuration "
                                       "sequences")
    if what == "paths" and sequences:
        raise click.UsageError("--sequence names a configuration sequence: --what paths samples only the "
                               "kinematic paths")
