"""``p105 solve``: forward and inverse position analysis of a mechanism along a motion.

The thin CLI layer: options, which input goes where, exit codes. The motion is read by
:mod:`p105cli.formats.values` / :mod:`p105cli.formats.poses` or is the model's own program
(:mod:`p105cli.part105.program`); it is analysed by :mod:`p105cli.motion.analysis` and written
by :mod:`p105cli.formats.solve_records` (or into the model); scenes run in :mod:`p105cli.cable.run`.
"""

from __future__ import annotations

import itertools
from types import SimpleNamespace

import click

from .contract import (EXIT_STATUS_TEXT, READ_LENIENTLY_TEXT, ExitCode, InputError, diag, open_output,
                       report_deviations, report_warnings, stderr_is_terminal)
from .inputs import STDIN, is_stdin, load_document, naming_source, read_text, source_of
from .options import SCHEMA_HELP_SHORT, angle_unit_option, count_option, file_option, input_schema, \
    length_unit_option, mechanism_option, model_argument, output_option, step_option, to_option, tol_option
from .solve_rules import check_after_reading, check_usage
from .solve_scene import check_samples, load_scene, model_scene, prepare_scene, run_scene, scene_only

FORMATS = ["model", "jsonl", "csv"]


@click.command(epilog=READ_LENIENTLY_TEXT + EXIT_STATUS_TEXT)
@model_argument
@file_option("--values", "values",
             help="Driven pair values, one configuration per row: CSV with a header of pair names "
                  "(name[0], name[1]... for multi-valued pairs) and an optional t column, or JSON Lines "
                  '{"t": t, "pairs": {name: value}}.')
@click.option("--set", "sets", metavar="PAIR=VALUE", multiple=True,
              help="Drive PAIR at VALUE in every configuration (PAIR=V1,V2 or PAIR[j]=V for multi-valued "
                   "pairs). Without --values: one configuration.")
@click.option("--sweep", "sweeps", metavar="PAIR=START:STOP:COUNT", multiple=True,
              help="Drive PAIR from START to STOP in COUNT evenly spaced configurations (instead of "
                   "--values; several --sweep options run together).")
@file_option("--path", "path",
             help="Inverse analysis: target poses of --target-link, JSON Lines {\"t\": t, \"pose\": 4x4} "
                  "or CSV t,m00,...,m23.")
@click.option("--target-link", metavar="LINK", default=None, help="The link whose frame follows --path.")
@click.option("--target-frame", metavar="NAME", default=None,
              help="A named frame of --target-link to put on the path (default: the link frame).")
@click.option("--program", is_flag=True,
              help="Run the model's own motion program (its kinematic_control): a configuration sequence "
                   "drives the actuated pairs through its configurations; a prescribed path (AP242) is "
                   "followed by inverse analysis of its link frame.")
@count_option("With --program: N evenly spaced samples of the program (default: its nodes).",
              type=click.IntRange(1, 100_000_000))
@step_option("With --program: a sample every DT of the program's parameter, nodes included.")
@click.option("--resulting-path", "resulting_paths", metavar="LINK[:FRAME]", multiple=True,
              help="With --to model: write the path of LINK's frame (or its named FRAME) through the solved "
                   "configurations as a Part 105 resulting path (repeatable). Default: the target link's frame "
                   "of an inverse analysis.")
@tol_option(1e-10, help="Loop residual / pose error: lengths relative to the model size, rotations in radians.")
@click.option("--max-iter", type=click.IntRange(1, 10_000), default=30, show_default=True,
              help="Newton iterations per configuration (inverse analysis: x4).")
@click.option("--branch", "branch", type=click.Choice(["initial", "+", "-"]), default="initial", show_default=True,
              help="Closed loops: the assembly branch to track. initial: the initial state's; + / -: the "
                   "assembly whose branch invariant has that sign (+ is the initial state's, - the other "
                   "one, found at the initial state's driven values).")
@to_option(FORMATS, help="Output: the model with the analysis results added (default; in the input's format), "
                          "JSON Lines records (default with --scene), or a flat CSV table.")
@angle_unit_option
@length_unit_option
@mechanism_option
@input_schema(SCHEMA_HELP_SHORT)
@file_option("--scene", "scene",
             help="A scene (JSON or TOML; from standard input TOML unless it is a JSON object) of effects "
                  "to simulate on the solved motion (cables).")
@file_option("--keypoints", "keypoints",
             help="Moving-end key points for the scene's cables (JSON Lines or CSV).")
@file_option("--plot", "plot",
             help="With a scene: draw the cable shapes over the key points to FILE (.png or .svg; - : SVG "
                  "on standard output, the records going to -o; needs matplotlib: pip install 'p105cli[plot]').")
@file_option("--animate", "animation",
             help="With a scene: animate the cables along the path to FILE (.gif or a self-contained .html; "
                  "- : HTML on standard output, the records going to -o).")
@click.option("--timings/--no-timings", default=True, show_default=True,
              help="Report the time per configuration in the jsonl summary (what the run cost); "
                   "--no-timings gives byte-reproducible output.")
@output_option
def solve(**options):
    """Position analysis of a mechanism (Part 21 or p105/1 JSON, sniffed) along a motion.

    Forward: the pairs named in --values/--set are driven (without them, the
    actuated pairs at their initial values); trees are evaluated batched,
    closed loops are closed by Newton with analytic Jacobians, continued from
    the initial state, which fixes the assembly branch. A branch change, a
    dead centre or a configuration that cannot be assembled is reported on
    that configuration (status), never silently. Inverse: --path with
    --target-link. Exit 1 when any configuration is not ok, or a scene's
    cable is over-length or cannot be solved; the reason is on standard
    error.

    Every FILE option reads standard input when given as -, one of them
    per run. An option that would do nothing in the mode chosen is a usage
    error (exit 2), checked before anything is solved, as is a scene and its
    key points: --plot, --animate and --keypoints without a scene that runs;
    --target-link and --target-frame without --path; --resulting-path
    without --to model; --timings with --to csv or model; --angle-unit or
    --length-unit with --to model and nothing to convert; options of the
    analysis of a model (--program, --mechanism, --schema, --tol,
    --max-iter, --resulting-path, the units) with a scene alone.
    """
    o = SimpleNamespace(**options)
    ctx = click.get_current_context()
    o.given = {name for name in options
               if ctx.get_parameter_source(name) not in (None, click.core.ParameterSource.DEFAULT)}
    o.to_given = o.to is not None
    o.to = o.to or ("jsonl" if o.scene is not None else "model")
    o.want = check_usage(o)
    from p105cli.formats.values import ANGLE_UNITS, LENGTH_UNITS
    o.lf, o.af = LENGTH_UNITS[o.length_unit], ANGLE_UNITS[o.angle_unit]
    o.pictures = (o.plot, o.animation)
    o.scene_dict = load_scene(o.scene) if o.scene is not None else None
    if o.model is None:
        return scene_only(o)
    model, mech = _read_model(o.model, o.schema, o.mechanism)
    doc = model.doc
    o.scene_in_model = o.scene_dict is None and getattr(doc, "scene", None) is not None
    if o.scene_in_model:
        o.to, o.scene_dict, o.scene = model_scene(doc, o.model, o.to, o.to_given)
    # the scene is checked before the mechanism is solved: no output precedes its errors
    o.prepared = prepare_scene(o, mech) if o.scene_dict is not None else None
    check_after_reading(o)
    prog = _program(model, mech, o.count, o.step) if o.program else None
    pl, motion, blocks = _start(o, doc, mech, prog)
    if o.prepared is not None:
        check_samples(o.prepared, mech, _samples(motion))
    requests = _resulting_paths(mech, pl, o.resulting_paths, motion) if o.to == "model" else []
    if _output(o, model, mech, pl, motion, blocks, requests):
        raise click.exceptions.Exit(ExitCode.FINDINGS)


def _output(o, model, mech, pl, motion, blocks, requests) -> bool:
    """Every block written (and the scene run on the motion); the warnings. True on findings."""
    from p105cli.formats.solve_records import Table, Tally, write_blocks
    tally = Tally(motion.inverse)
    placements = [] if o.prepared is not None else None
    with open_output(o.output, (o.model, o.values, o.path, o.scene, o.keypoints)) as out:
        if o.to == "model":
            def write(result, links, t, offset):
                _write_model(out, model, mech, result, t, requests)
        else:
            table = Table(out, o.to, mech, pl, inverse=motion.inverse, length=o.lf, angle=o.af)
            table.header()
            write = table.write
        write_blocks(blocks, motion.t, write, tally, mech.link_names, placements)
        if o.to == "jsonl":
            tally.write_summary(out, mech, o.lf, o.af, o.timings)
            if o.prepared is not None and not run_scene(o.prepared, placements, out, o.pictures, o.timings):
                tally.failed = True
    for level, message in tally.messages(stderr_is_terminal()):
        diag(level, message)
    return tally.failed


def _read_model(model, schema, mechanism):
    """``(ModelFile, Mechanism)``: the command's one model file (one population: the program,
    the results and the mechanism are read from it)."""
    from p105cli.part105.model_file import ModelFile
    from p105cli.part105.read_mechanism import read_mechanism
    doc = load_document(model)
    report_warnings(doc)
    with naming_source(doc):
        mf = ModelFile.of(doc, schema)
        try:
            return mf, read_mechanism(mf, name=mechanism)
        finally:
            report_deviations(doc)


def _program(model, mech, count, step):
    from p105cli.part105.program import ProgramError, motion_program
    source = source_of(model.doc)
    try:
        with naming_source(model.doc):
            return motion_program(model, mech, count, step, source, note=lambda m: diag("note", m))
    except ProgramError as err:
        raise InputError(str(err)) from None


def _start(o, doc, mech, prog):
    """``(plan, motion, blocks)``: the analysis started, its first block computed (so that a
    request it cannot honour is a usage error before any output)."""
    from p105cli.formats.text import FormatError
    from p105cli.kinematics import solver
    from p105cli.motion.analysis import analyse_motion
    try:
        pl = solver.plan(mech)
        _check_pair_parameters(o, mech, pl)
        if o.want is not None and prog is not None and prog[0] == "path":
            raise click.UsageError(f"--branch {o.branch}: the model's program is a prescribed path (inverse "
                                   "analysis): the assembly branch is chosen in forward analysis")
        motion = _motion(o, mech, prog)
        _check_driven_values(o, mech, pl, motion.driven)
        # Model output needs every configuration at once; the tables stream block by block.
        blocks = analyse_motion(mech, motion, tol=o.tol, max_iter=o.max_iter, pl=pl,
                                block=None if o.to == "model" else 4096, branch=o.want)
        first = next(blocks)
    except FormatError as err:
        raise InputError(str(err)) from None
    except solver.BranchUndefined as err:
        raise click.UsageError(f"--branch {o.branch}: mechanism {mech.name!r}: {err}") from None
    except solver.SolveError as err:
        raise InputError(f"{o.model if not is_stdin(o.model) else STDIN}: {err}") from None
    return pl, motion, itertools.chain([first], blocks)


def _samples(motion) -> int | None:
    """How many configurations the motion has (None: not known before it is solved)."""
    if motion.t is not None:
        return len(motion.t)
    if motion.poses is not None:
        return len(motion.poses)
    if motion.driven:
        return len(next(iter(motion.driven.values())))
    return None


def _check_pair_parameters(o, mech, pl):
    """A pair whose motion refuses its parameters or initial values (a rule of the model
    broken, e.g. a universal pair's skew angle against WR1), or has no motion here (a helical
    gear), cannot be solved: an input error naming the pair (exit 2), before the solver
    meets it (every pair's motion is evaluated in the analysis)."""
    import numpy as np
    q0 = np.asarray(mech.initial_vector(), dtype=float)
    for k, kind in enumerate(pl.types):
        try:
            kind.motion(q0[pl.slices[k]], **pl.params[k])
        except (ValueError, NotImplementedError) as err:  # NotImplementedError: UnsupportedPairError
            name = pl.pair_names[k]
            iid = (getattr(mech.pair(name), "ids", None) or {}).get("pair")
            where = f"#{iid}: " if iid is not None else ""
            raise InputError(f"{o.model if not is_stdin(o.model) else STDIN}: {where}mechanism {mech.name!r}: "
                             f"pair {name!r}: {err}") from None


def _check_driven_values(o, mech, pl, driven, chunk: int = 65536):
    """Driven values a pair's motion refuses (a locked freedom of a low order pair driven away
    from 0) are an input error naming the pair, as for its parameters, before the solver meets
    them (fuzz: --set B=0.5,0.1,0.2 on such a pair was exit 3)."""
    import numpy as np
    if not driven:
        return
    q0 = np.asarray(mech.initial_vector(), dtype=float)
    for k, kind in enumerate(pl.types):
        name, sl = pl.pair_names[k], pl.slices[k]
        cols = {key: v for key, v in driven.items() if (key[0] if isinstance(key, tuple) else key) == name}
        if not cols:
            continue
        n = max(len(np.atleast_1d(v)) for v in cols.values())
        for start in range(0, n, chunk):
            q = np.tile(q0[sl], (min(chunk, n - start), 1))
            for key, v in cols.items():
                v = np.broadcast_to(np.asarray(v, dtype=float), (n,) + np.shape(v)[1:])[start:start + len(q)]
                if isinstance(key, tuple):
                    q[:, key[1]] = v
                elif v.ndim == 2:
                    q[:, :] = v
                else:
                    q[:, 0] = v
            try:
                kind.motion(q, **pl.params[k])
            except (ValueError, NotImplementedError) as err:
                iid = (getattr(mech.pair(name), "ids", None) or {}).get("pair")
                where = f"#{iid}: " if iid is not None else ""
                raise InputError(f"{o.model if not is_stdin(o.model) else STDIN}: {where}mechanism {mech.name!r}: "
                                 f"pair {name!r}: driven values: {err}") from None


def _motion(o, mech, prog):
    """The motion to analyse: the model's program, the poses of --path, or driven values."""
    from p105cli.motion.analysis import Motion
    if prog is not None and prog[0] == "path":
        _, t, poses, link, frame, frame_name = prog
        return Motion(t, poses=poses, link=link, frame=frame, frame_name=frame_name)
    if prog is not None:
        return Motion(prog[1], driven=prog[2])
    if o.path is not None:
        from p105cli.formats.poses import read_poses
        text, source = read_text(o.path)
        t, poses = read_poses(text, source, length=o.lf)
        frame = _target_frame(mech, o.target_link, o.target_frame) if o.target_frame is not None else None
        return Motion(t, poses=poses, link=o.target_link, frame=frame, frame_name=o.target_frame)
    from p105cli.formats.values import driven_columns
    t, driven, notes = driven_columns(mech, read_text(o.values) if o.values is not None else None, o.sets,
                                      o.sweeps, length=o.lf, angle=o.af)
    for note in notes:
        diag("note", note)
    return Motion(t, driven=driven)


def _target_frame(mech, link_name, frame_name):
    try:
        link = mech.link(link_name)
    except KeyError:
        raise InputError(f"{link_name!r} is not a link of mechanism {mech.name!r} "
                         f"(links: {', '.join(mech.link_names)})") from None
    if frame_name not in link.frames:
        raise InputError(f"link {link_name!r} has no frame {frame_name!r} "
                         f"(frames: {', '.join(link.frames) or 'none'})")
    return link.frames[frame_name]


def _resulting_paths(mech, pl, specs, motion):
    from p105cli.part105.results import ResultingPathError, resulting_path_requests
    try:
        return resulting_path_requests(mech, pl, specs, motion)
    except ResultingPathError as err:
        raise InputError(str(err)) from None


def _write_model(out, model, mech, result, t, paths=()):
    """The input model plus the analysis results, in the input's format (Part 21 or JSON)."""
    from p105cli.part105.results import model_with_results
    from ._emit import emit_json, emit_p21
    try:
        new, notes = model_with_results(model, mech, result, t, paths)
    except ValueError as err:
        raise InputError(f"{model.doc.source}: {err}") from None
    if hasattr(model.doc, "text"):
        emit_p21(new, out)
    else:
        emit_json(new, out, False)
    for note in notes:
        diag("note", f"{model.doc.source}: {note}")
