"""``p105 graph``: links and joints as a graph, loops, mobility; or the model enriched with graph entities."""

from __future__ import annotations

import click

from .contract import (EXIT_STATUS_TEXT, READ_LENIENTLY_TEXT, ExitCode, InputError, Settings, diag, open_output,
                       report_deviations, report_warnings)
from .inputs import load_document
from .options import SCHEMA_HELP_SHORT, check_tol, input_argument, mechanism_option, output_option, input_schema, \
    to_option, tol_option

#: graph's analysis formats (p105cli.formats.graph.FORMATS; not imported here: numpy loads lazily)
GRAPH_FORMATS = ("json", "dot", "graphml", "mermaid")


@click.command(epilog=READ_LENIENTLY_TEXT + EXIT_STATUS_TEXT)
@to_option(GRAPH_FORMATS + ("p21",),
           help="Output format: the analysis as json (default), dot, graphml or mermaid; with --enrich "
                "the model as p21 or json (default: the input's format).")
@click.option("--enrich", is_flag=True,
              help="Write the model back with the Part 105 graph entities added (AP242 layout: "
                   "kinematic_topology_tree_structure, kinematic_topology_network_structure, kinematic_loop, "
                   "oriented_joint).")
@mechanism_option
@input_schema(SCHEMA_HELP_SHORT)
@tol_option(None, metavar="RTOL",
            help="Relative rank tolerance of the loop-closure Jacobian (dimensionless)  [default: 1e-8]")
@input_argument
@output_option
def graph(to, enrich, mechanism, schema, tol, input, output):
    """Structure of a mechanism: spanning tree, independent loops and mobility.

    Links are the vertices and joints the edges. The spanning tree grows
    breadth-first from the base link; every joint outside it closes one
    independent loop. Mobility is given by Gruebler-Kutzbach and by the rank
    of the loop-closure Jacobian at the initial state, with the redundant
    constraints and the joints that carry them. Exit 1 when the mobility
    cannot be computed (a pair whose motion is not available).
    """
    check_tol(tol)  # inf too: it was an internal error in the analysis
    if enrich and to in ("dot", "graphml", "mermaid"):
        raise click.UsageError("--enrich writes a model: use --to p21 or --to json")
    if not enrich and to == "p21":
        raise click.UsageError("--to p21 writes a model: use it with --enrich")
    doc = load_document(input)
    report_warnings(doc)
    model, profile, mechs = _mechanisms(doc, schema, mechanism)
    if enrich:
        return _enrich(model, mechs, profile, to, input, output, tol)
    mech = _the_one(doc, mechs)
    from p105cli.formats.graph import render
    from p105cli.kinematics.graph import analyse
    st = analyse(mech, tol=tol)
    text = render(mech, st, to or "json")
    with open_output(output, (input,)) as out:
        out.write(text)
    for note in st.notes:
        diag("warning", f"{doc.source}: mechanism {mech.name!r}: {note}")
    if st.mobility is None:
        return ExitCode.FINDINGS
    return ExitCode.OK


def _mechanisms(doc, schema, name):
    """The model file (the command's one population), the profile it is read as, and its
    mechanisms (only the one called ``name``)."""
    from p105cli.part105.model_file import ModelFile
    from p105cli.part105.read_mechanism import read_mechanisms
    from p105cli.schema.profiles import UnknownSchemaError, profile_for_header
    try:
        profile = profile_for_header(doc.header, schema).name
    except UnknownSchemaError as err:
        raise InputError(f"{doc.source}: {err}") from None
    model = ModelFile.of(doc, schema)  # the command's one population
    try:
        mechs = read_mechanisms(model)
    finally:
        report_deviations(doc)
    if name is not None:
        mechs = [m for m in mechs if m.name == name]
        if not mechs:
            raise InputError(f"{doc.source}: no mechanism called {name!r}")
    return model, profile, mechs


def _the_one(doc, mechs):
    if not mechs:
        raise InputError(f"{doc.source}: no mechanism in the file")
    if len(mechs) > 1:
        names = ", ".join(repr(m.name) for m in mechs)
        raise click.UsageError(f"{doc.source} has {len(mechs)} mechanisms ({names}): choose one with --mechanism")
    return mechs[0]


def _enrich(model, mechs, profile, to, input, output, tol):
    from p105cli.kinematics.graph import analyse
    from p105cli.part105.topology import EnrichError, enrich
    from ._emit import emit_json, emit_p21

    doc = model.doc
    fmt = to or ("p21" if hasattr(doc, "text") else "json")
    try:
        new, notes = enrich(model, [(m, analyse(m, tol=tol)) for m in mechs], profile)
    except EnrichError as err:
        raise InputError(f"{doc.source}: {err}") from None
    with open_output(output, (input,)) as out:
        if fmt == "p21":
            emit_p21(new, out)
        else:
            emit_json(new, out, False)
    if Settings.verbosity > 0:
        for note in notes:
            diag("note", f"{doc.source}: {note}")
    return ExitCode.OK
