"""``p105 solve``: forward and inverse position analysis of a mechanism along a motion.

The thin CLI layer: options, input reading, output formats. The science is
in :mod:`p105cli.kinematics.solver`; the motion readers in
:mod:`p105cli.kinematics.motion_io`.
"""

from __future__ import annotations

import json
import math
import os

import click

from .contract import EXIT_STATUS_TEXT, ExitCode, InputError, diag, load_document, naming_source, open_output, \
    read_input_bytes, report_warnings, stderr_is_terminal
from .options import output_option

FORMATS = ["model", "jsonl", "csv"]

#: Driven angles beyond this many turns are refused (double precision keeps ~1e-9 rad there).
MAX_TURNS = 1e6


def _f(x) -> float:
    """A plain float for JSON (no -0.0 noise from round-off, no numpy types)."""
    v = float(x)
    return 0.0 if v == 0.0 else v


def _read_text(path, what: str) -> tuple[str, str]:
    from p105cli.step import decode_bytes
    raw, source = read_input_bytes(path)
    try:
        return decode_bytes(raw), source
    except Exception:  # noqa: BLE001 - any undecodable input is the user's file, not a bug
        raise InputError(f"{source}: {what} is not text") from None


def _key_label(key) -> str:
    return f"{key[0]}[{key[1]}]" if isinstance(key, tuple) else key


@click.command(epilog=EXIT_STATUS_TEXT)
@click.argument("model", metavar="[MODEL|-]", required=False, default=None)
@click.option("--values", "values", metavar="FILE|-", default=None,
              help="Driven pair values, one configuration per row: CSV with a header of pair names "
                   "(name[0], name[1]... for multi-valued pairs) and an optional t column, or JSON Lines "
                   '{"t": t, "pairs": {name: value}}.')
@click.option("--set", "sets", metavar="PAIR=VALUE", multiple=True,
              help="Drive PAIR at VALUE in every configuration (PAIR=V1,V2 or PAIR[j]=V for multi-valued "
                   "pairs). Without --values: one configuration.")
@click.option("--sweep", "sweeps", metavar="PAIR=START:STOP:COUNT", multiple=True,
              help="Drive PAIR from START to STOP in COUNT evenly spaced configurations (instead of "
                   "--values; several --sweep options run together).")
@click.option("--path", "path", metavar="FILE|-", default=None,
              help="Inverse analysis: target poses of --target-link, JSON Lines {\"t\": t, \"pose\": 4x4} "
                   "or CSV t,m00,...,m23.")
@click.option("--target-link", metavar="LINK", default=None, help="The link whose frame follows --path.")
@click.option("--target-frame", metavar="NAME", default=None,
              help="A named frame of --target-link to put on the path (default: the link frame).")
@click.option("--program", is_flag=True,
              help="Run the model's own motion program (its kinematic_control): a configuration sequence "
                   "drives the actuated pairs through its configurations; a prescribed path (AP242) is "
                   "followed by inverse analysis of its link frame.")
@click.option("--count", type=click.IntRange(1, 100_000_000), default=None, metavar="N",
              help="With --program: N evenly spaced samples of the program (default: its nodes).")
@click.option("--step", type=float, default=None, metavar="DT",
              help="With --program: a sample every DT of the program's parameter, nodes included.")
@click.option("--resulting-path", "resulting_paths", metavar="LINK[:FRAME]", multiple=True,
              help="With --to model: write the path of LINK's frame (or its named FRAME) through the solved "
                   "configurations as a Part 105 resulting path (repeatable). Default: the target link's frame "
                   "of an inverse analysis.")
@click.option("--tol", type=float, default=1e-10, show_default=True,
              help="Loop residual / pose error: lengths relative to the model size, rotations in radians.")
@click.option("--max-iter", type=click.IntRange(1, 10_000), default=30, show_default=True,
              help="Newton iterations per configuration (inverse analysis: x4).")
@click.option("--branch", "branch", type=click.Choice(["initial", "+", "-"]), default="initial", show_default=True,
              help="Closed loops: the assembly branch to track. initial: the initial state's; + / -: the "
                   "assembly whose branch invariant has that sign (+ is the initial state's, - the other "
                   "one, found at the initial state's driven values).")
@click.option("--to", "to", type=click.Choice(FORMATS), default=None,
              help="Output: the model with the analysis results added (default; in the input's format), "
                   "JSON Lines records (default with --scene), or a flat CSV table.")
@click.option("--angle-unit", type=click.Choice(["rad", "deg"]), default="rad", show_default=True,
              help="Unit of angles in --values, --set and the jsonl/csv output.")
@click.option("--length-unit", type=click.Choice(["m", "mm"]), default="m", show_default=True,
              help="Unit of lengths in --values, --set, --path and the jsonl/csv output.")
@click.option("--mechanism", "mechanism_name", metavar="NAME", default=None,
              help="Which mechanism of the model (when it has several).")
@click.option("--schema", type=click.Choice(["ap214", "ap242", "p105"]), default=None,
              help="Schema profile; default: chosen from FILE_SCHEMA.")
@click.option("--scene", metavar="FILE", default=None,
              help="A scene (JSON or TOML) of effects to simulate on the solved motion (cables).")
@click.option("--keypoints", metavar="FILE", default=None,
              help="Moving-end key points for the scene's cables (JSON Lines or CSV).")
@click.option("--plot", "plot", metavar="FILE", default=None,
              help="With a scene: draw the cable shapes over the key points to FILE (.png or .svg; "
                   "needs matplotlib: pip install 'p105cli[plot]').")
@click.option("--animate", "animation", metavar="FILE", default=None,
              help="With a scene: animate the cables along the path to FILE (.gif or a self-contained .html).")
@click.option("--timings/--no-timings", default=True, show_default=True,
              help="Report the time per configuration in the jsonl summary (what the run cost); "
                   "--no-timings gives byte-reproducible output.")
@output_option
def solve(model, values, sets, sweeps, path, target_link, target_frame, program, count, step, resulting_paths,
          tol, max_iter, branch, to, angle_unit, length_unit, mechanism_name, schema, scene, keypoints, plot, animation,
          timings, output):
    """Position analysis of a mechanism (Part 21 or p105/1 JSON, sniffed) along a motion.

    Forward: the pairs named in --values/--set are driven (without them, the
    actuated pairs at their initial values); trees are evaluated batched,
    closed loops are closed by Newton with analytic Jacobians, continued from
    the initial state, which fixes the assembly branch. A branch change, a
    dead centre or a configuration that cannot be assembled is reported on
    that configuration (status), never silently. Inverse: --path with
    --target-link. Exit 1 when any configuration is not ok.
    """
    to_given = to is not None
    to = to or ("jsonl" if scene is not None else "model")
    if scene is not None and to != "jsonl":
        raise click.UsageError("--scene writes JSON Lines (--to jsonl)")
    for name, target in (("--plot", plot), ("--animate", animation)):
        if target is not None and model is None and scene is None:
            raise click.UsageError(f"{name} draws a scene's cables: it needs --scene (or a model with a scene)")
    if resulting_paths and to != "model":
        # the tables carry every link's placement already; the path entities are model output
        diag("note", f"--resulting-path is written with --to model only; the {to} output has the link placements")
    if not (tol > 0.0 and math.isfinite(tol)):
        raise click.UsageError("--tol must be a positive number")
    if path is not None and target_link is None:
        raise click.UsageError("--path needs --target-link")
    if path is not None and (values is not None or sets or sweeps):
        raise click.UsageError("--path (inverse analysis) cannot be combined with --values, --set or --sweep")
    if sweeps and values is not None:
        raise click.UsageError("--sweep and --values cannot be combined")
    if program and (values is not None or sets or sweeps or path is not None):
        raise click.UsageError("--program runs the model's own motion: it cannot be combined with --values, "
                               "--set, --sweep or --path")
    if (count is not None or step is not None) and not program:
        raise click.UsageError("--count and --step sample a motion program: they need --program")
    if count is not None and step is not None:
        raise click.UsageError("give at most one of --count and --step")
    if step is not None and not (step > 0.0 and math.isfinite(step)):
        raise click.UsageError("--step must be a positive number")
    want = {"initial": None, "+": 1, "-": -1}[branch]
    if want is not None and (path is not None or (model is None and scene is not None)):
        raise click.UsageError(f"--branch {branch}: the assembly branch is chosen in forward analysis of a model "
                               "with closed loops" + (" (not with --path)" if path is not None else ""))
    if model is None and scene is None:
        model = "-"
    stdin_users = [n for n, v in (("MODEL", model), ("--values", values), ("--path", path)) if v == "-"]
    if len(stdin_users) > 1:
        raise click.UsageError(f"only one of {' and '.join(stdin_users)} can read standard input")
    from p105cli.kinematics.motion_io import ANGLE_UNITS, LENGTH_UNITS, MotionInputError
    lf, af = LENGTH_UNITS[length_unit], ANGLE_UNITS[angle_unit]

    scene_dict = None
    if scene is not None:
        scene_dict = _load_scene(scene)
    mech = None
    if model is not None:
        doc = load_document(model)
        report_warnings(doc)
        from p105cli.kinematics.reader import read_mechanism
        with naming_source(doc):
            mech = read_mechanism(doc, schema, mechanism_name)
        if scene_dict is None and getattr(doc, "scene", None) is not None:
            # the model carries its scene (a JSON model's "scene" block): run it as --scene would
            if not to_given:
                to = "jsonl"
            if to == "jsonl":
                scene_dict, scene = doc.scene, model if model not in (None, "-") else "."
            else:
                diag("note", f"{doc.source}: the model's scene is run with --to jsonl only")
    if mech is None:
        if values is not None or sets or sweeps or path is not None:
            raise click.UsageError("--values, --set, --sweep and --path need a MODEL")
        with open_output(output, (scene, keypoints)) as out:
            ok = _run_scene(scene_dict, scene, keypoints, None, out, (plot, animation))
        if not ok:
            raise click.exceptions.Exit(ExitCode.FINDINGS)
        return

    from p105cli.kinematics import solver
    prog = _program(doc, mech, schema, count, step) if program else None
    frame = None  # the target frame of an inverse analysis (link coordinates), None: the link frame
    try:
        pl = solver.plan(mech)
        if want is not None and prog is not None and prog[0] == "path":
            raise click.UsageError(f"--branch {branch}: the model's program is a prescribed path (inverse "
                                   "analysis): the assembly branch is chosen in forward analysis")
        if prog is not None and prog[0] == "path":
            _, t, poses, target_link, frame, target_frame = prog
            blocks = iter([solver.solve_path(mech, target_link, poses, frame=frame, tol=tol,
                                             max_iter=4 * max_iter, pl=pl)])
        elif prog is not None:
            _, t, driven = prog
            blocks = solver.iter_motion(mech, driven, tol=tol, max_iter=max_iter, pl=pl,
                                        block=None if to == "model" else 4096, branch=want)
        elif path is not None:
            from p105cli.kinematics.motion_io import read_poses
            text, source = _read_text(path, "the path")
            t, poses = read_poses(text, source, length=lf)
            frame = None
            if target_frame is not None:
                link = _link(mech, target_link)
                if target_frame not in link.frames:
                    raise InputError(f"link {target_link!r} has no frame {target_frame!r} "
                                     f"(frames: {', '.join(link.frames) or 'none'})")
                frame = link.frames[target_frame]
            blocks = iter([solver.solve_path(mech, target_link, poses, frame=frame, tol=tol,
                                             max_iter=4 * max_iter, pl=pl)])
        else:
            t, driven = _driven(mech, values, sets, sweeps, lf, af)
            # Model output needs every configuration at once; the tables stream block by block.
            blocks = solver.iter_motion(mech, driven, tol=tol, max_iter=max_iter, pl=pl,
                                        block=None if to == "model" else 4096, branch=want)
        first = next(blocks)
    except MotionInputError as err:
        raise InputError(str(err)) from None
    except solver.BranchUndefined as err:
        raise click.UsageError(f"--branch {branch}: mechanism {mech.name!r}: {err}") from None
    except solver.SolveError as err:
        raise InputError(f"{model if model not in (None, '-') else '<stdin>'}: {err}") from None

    inverse = path is not None or (prog is not None and prog[0] == "path")
    requests = _resulting_paths(mech, pl, resulting_paths, inverse, target_link, target_frame, frame) \
        if to == "model" else []
    tally = _Tally(inverse)
    motion = [] if scene_dict is not None else None
    with open_output(output, (model, values, path, scene, keypoints)) as out:
        if to == "csv":
            _csv_header(out, mech, pl, inverse)
        branched = bool(pl.loops) and not inverse   # the branch invariant exists: forward, with loops
        offset = 0
        for result in _chain(first, blocks):
            links = result.links()
            n = result.Q.shape[0]
            tb = t[offset:offset + n] if t is not None else None
            tally.add(result, offset)
            if to == "jsonl":
                _write_jsonl(out, mech, result, links, tb, offset, lf, af, inverse, branched)
            elif to == "csv":
                _write_csv(out, mech, result, links, tb, offset, lf, af, inverse, branched)
            else:
                _write_model(out, mech, result, doc, tb, requests)
            if motion is not None:
                motion += [(float(tb[i]) if tb is not None else float(offset + i),
                            {name: links[i, pl.link_index[name]] for name in mech.link_names})
                           for i in range(n)]
            offset += n
        if to == "jsonl":
            out.write(json.dumps(tally.summary(mech, lf, af, timings), separators=(",", ":")) + "\n")
            if scene_dict is not None and not _run_scene(scene_dict, scene, keypoints, motion, out,
                                                         (plot, animation)):
                tally.failed = True
    tally.report()
    if tally.failed:
        raise click.exceptions.Exit(ExitCode.FINDINGS)


def _chain(first, rest):
    yield first
    yield from rest


class _Tally:
    """Statistics over all blocks, for the summary record and the exit status."""

    MAX_WARNINGS = 20

    def __init__(self, inverse):
        self.inverse = inverse
        self.n = 0
        self.counts = {}
        self.worst = {}
        self.max_iter = 0
        self.seconds = 0.0
        self.failed = False
        self.bad = []

    def add(self, result, offset):
        import numpy as np
        n = result.Q.shape[0]
        self.n += n
        self.seconds += result.seconds
        for i, s in enumerate(result.status):
            self.counts[s] = self.counts.get(s, 0) + 1
            if s != "ok":
                self.failed = True
                if len(self.bad) < self.MAX_WARNINGS:
                    self.bad.append((offset + i, s, result.messages[i]))
        fields = (("position_error", "rotation_error") if self.inverse
                  else ("residual", "residual_m", "residual_rad"))
        for f in fields:
            v = float(np.max(getattr(result, f))) if n else 0.0
            self.worst[f] = max(self.worst.get(f, 0.0), v)
        self.max_iter = max(self.max_iter, int(np.max(result.iterations)) if n else 0)

    def summary(self, mech, lf, af, timings):
        out = {"type": "summary", "mechanism": mech.name, "configurations": self.n,
               "status": {k: self.counts[k] for k in sorted(self.counts)},
               "units": {"length": "m" if lf == 1.0 else "mm", "angle": "rad" if af == 1.0 else "deg"}}
        if self.inverse:
            out["max_position_error"] = _f(self.worst.get("position_error", 0.0) / lf)
            out["max_rotation_error"] = _f(self.worst.get("rotation_error", 0.0))
        else:
            out["max_residual"] = _f(self.worst.get("residual", 0.0))
            out["max_residual_position"] = _f(self.worst.get("residual_m", 0.0) / lf)
            out["max_residual_rotation"] = _f(self.worst.get("residual_rad", 0.0))
        out["max_iterations"] = self.max_iter
        if timings:
            out["seconds"] = self.seconds
            out["seconds_per_configuration"] = self.seconds / max(self.n, 1)
        return out

    def report(self):
        if stderr_is_terminal() and self.n:
            # what the run achieved and cost, for the person watching (csv and model output
            # have no summary record)
            worst = (f"max pose error {self.worst.get('position_error', 0.0):.3g} m / "
                     f"{self.worst.get('rotation_error', 0.0):.3g} rad" if self.inverse
                     else f"max residual {self.worst.get('residual', 0.0):.3g}")
            diag("note", f"{self.n} configurations, {worst}, "
                         f"{1e6 * self.seconds / self.n:.1f} us per configuration")
        for i, s, msg in self.bad:
            diag("warning", f"configuration {i}: {s}: {msg}")
        more = sum(v for k, v in self.counts.items() if k != "ok") - len(self.bad)
        if more > 0:
            diag("warning", f"{more} more configurations are not ok")


def _link(mech, name):
    try:
        return mech.link(name)
    except KeyError:
        raise InputError(f"{name!r} is not a link of mechanism {mech.name!r} "
                         f"(links: {', '.join(mech.link_names)})") from None


def _angle_checker(mech):
    from p105cli.kinematics.solver import angle_value_mask

    def is_angle(key):
        name, j = key if isinstance(key, tuple) else (key, 0)
        try:
            p = mech.pair(name)
        except KeyError:
            raise InputError(f"{name!r} is not a pair of mechanism {mech.name!r} "
                             f"(pairs: {', '.join(mech.pair_names)})") from None
        mask = angle_value_mask(p)
        if j >= len(mask):
            raise InputError(f"pair {name!r} has {len(mask)} value(s); {_key_label(key)} does not exist")
        return mask[j] if isinstance(key, tuple) or len(mask) == 1 else mask[0]
    return is_angle


def _program(doc, mech, schema, count, step):
    """The model's motion program, sampled: ``("values", t, driven)`` for a configuration
    sequence (the actuated pairs, else every pair it values), ``("path", t, poses,
    link, frame)`` for a prescribed path."""
    from p105cli.motion.sampling import SamplingError

    source = getattr(doc, "source", None) or "<stdin>"
    try:
        return _program_of(doc, mech, schema, count, step, source)
    except SamplingError as err:
        raise InputError(f"{source}: {err}") from None


def _program_of(doc, mech, schema, count, step, source):
    from p105cli.kinematics.reader import population
    from p105cli.motion.configurations import sample_configurations
    from p105cli.motion.paths import PathError, sample_path
    from p105cli.motion.sampling import Plan

    with naming_source(doc):
        pop, _ = population(doc, schema)
        programs = []
        if "kinematic_control" in pop.schema.entities:
            for c in pop.ids_of_type("kinematic_control"):
                v = pop.instance(c).get("contained_kinematic_programs")
                programs += [x["ref"] for x in (v if isinstance(v, list) else [v])
                             if isinstance(x, dict) and "ref" in x]
        if not programs:
            raise InputError(f"{source}: the model has no kinematic_control (motion program); "
                             "drive it with --values, --set, --sweep or --path")
        prog = programs[0]
        if len(programs) > 1:
            diag("note", f"{source}: the model has {len(programs)} motion programs; running the first, #{prog}")
        plan = Plan(step=step, count=count, nodes=step is not None)
        types = pop.instance(prog).types
        if "interpolated_configuration_sequence" in types:
            from p105cli.motion.reader import read_configuration_sequences
            seqs, kinds, _ = read_configuration_sequences(doc, pop=pop)
            seq = next(q for q in seqs if q.id == prog)
            t = plan.grid(seq.t_start, seq.t_end, [n.t for n in seq.nodes])
            sampled = sample_configurations(seq, t, kinds)
            names = [p.name for p in mech.pairs if p.actuated and p.name in sampled.values] \
                or [n for n in seq.pair_names if n in mech.pair_names]
            driven = {}
            for name in names:
                vals = sampled.values[name]
                if vals.shape[1] == 1:
                    driven[name] = vals[:, 0]
                else:
                    driven.update({(name, j): vals[:, j] for j in range(vals.shape[1])})
            return "values", t, driven
        from p105cli.motion.reader import read_paths
        paths = [p for p in read_paths(doc, pop=pop).paths if p.holder_id == prog]
        if not paths:
            raise InputError(f"{source}: #{prog}: the motion program is a "
                             f"{'+'.join(sorted(pop.instance(prog).leaf_types))} that p105 cannot run "
                             "(it runs configuration sequences and prescribed paths with geometry)")
        path = paths[0]
        if path.link is None or path.link not in mech.link_names:
            raise InputError(f"{source}: #{path.id}: the path is tied to no link of mechanism {mech.name!r}")
        frame = None
        if path.frame is not None:
            frames = mech.link(path.link).frames
            frame = frames.get(path.frame)
            if frame is None:  # the frame is the link frame itself, or a pair frame of the link
                frame = next((v for k, v in frames.items() if k.startswith(path.frame)), None)
        t = plan.grid(path.t_start, path.t_end, path.breakpoints)
        try:
            poses = sample_path(path, t).T
        except PathError as err:
            raise InputError(f"{source}: #{path.id}: {err}") from None
        return "path", t, poses, path.link, frame, path.frame


def _driven(mech, values, sets, sweeps, lf, af):
    """(t or None, {pair or (pair, j): (N,) or (N, k) SI values}) from --values, --sweep and --set."""
    import numpy as np
    from p105cli.kinematics.motion_io import parse_set, parse_sweep, read_values

    is_angle = _angle_checker(mech)
    t, cols = None, {}
    if values is not None:
        text, source = _read_text(values, "the values")
        t, cols = read_values(text, source, length=lf, angle=af, is_angle=is_angle)
    elif sweeps:
        cols = parse_sweep(sweeps, length=lf, angle=af, is_angle=is_angle)
    fixed = parse_set(sets, length=lf, angle=af, is_angle=is_angle)
    n = len(next(iter(cols.values()))) if cols else 1
    for key, v in fixed.items():
        if key in cols:
            raise InputError(f"--set {_key_label(key)}: the pair is in --values too")
        cols[key] = np.full(n, v)
    driven = {}
    for key, v in cols.items():
        # an angle of a million turns has no digits left for its position within the turn
        if is_angle(key) and np.size(v) and float(np.max(np.abs(v))) > MAX_TURNS * 2.0 * math.pi:
            raise InputError(f"{_key_label(key)}: an angle of {float(np.max(np.abs(v))):.3g} rad is more than "
                             f"{MAX_TURNS:.0e} turns: its position within a turn is lost to rounding")
        if not isinstance(key, tuple) and mech.pair(key).value_count > 1:
            raise InputError(f"pair {key!r} has {mech.pair(key).value_count} values: name them "
                             f"{key}[0], {key}[1], ...")
        if isinstance(key, tuple) and mech.pair(key[0]).value_count == 1 and key[1] == 0:
            key = key[0]
        driven[key] = v
    if not driven:
        # No motion given: the actuated pairs at their initial values, one configuration.
        q0 = mech.initial_vector()
        for p in mech.pairs:
            if p.actuated:
                driven[p.name] = q0[None, mech.value_slices[p.name]]
    else:
        named = {k[0] if isinstance(k, tuple) else k for k in driven}
        for p in mech.pairs:
            if p.name in named and not p.actuated and any(q.actuated for q in mech.pairs):
                diag("note", f"pair {p.name!r} is driven but has no actuator in the model")
    return t, driven


def _value_out(mech, p, q, lf, af):
    from p105cli.kinematics.solver import angle_value_mask
    mask = angle_value_mask(p)
    vals = [_f(v / (af if a else lf)) for v, a in zip(q, mask)]
    return vals[0] if len(vals) == 1 else vals


def _pose_out(T, lf):
    M = T.copy()
    M[:3, 3] /= lf
    return [[_f(x) for x in row] for row in M]


def _write_jsonl(out, mech, result, links, t, offset, lf, af, inverse, branched=False):
    pl = result.plan
    slices = mech.value_slices
    for i in range(result.Q.shape[0]):
        rec = {"type": "configuration", "index": offset + i, "t": _f(t[i]) if t is not None else None,
               "status": result.status[i]}
        if branched:
            rec["branch"] = int(result.branch[i])
        rec["pairs"] = {p.name: _value_out(mech, p, result.Q[i, slices[p.name]], lf, af) for p in mech.pairs}
        rec["links"] = {name: _pose_out(links[i, pl.link_index[name]], lf) for name in mech.link_names}
        if inverse:
            rec["position_error"] = _f(result.position_error[i] / lf)
            rec["rotation_error"] = _f(result.rotation_error[i])
        else:
            rec["residual"] = _f(result.residual[i])
            rec["residual_position"] = _f(result.residual_m[i] / lf)
            rec["residual_rotation"] = _f(result.residual_rad[i])
        rec["iterations"] = int(result.iterations[i])
        if result.messages[i]:
            rec["message"] = result.messages[i]
        out.write(json.dumps(rec, separators=(",", ":")) + "\n")


def _csv_header(out, mech, pl, inverse):
    head = ["index", "t", "status"] + (["branch"] if pl.loops and not inverse else [])
    for p in mech.pairs:
        head += [p.name] if p.value_count == 1 else [f"{p.name}[{j}]" for j in range(p.value_count)]
    head += ["position_error", "rotation_error"] if inverse else ["residual"]
    head += ["iterations"]
    for name in mech.link_names:
        head += [f"{name}.m{r}{c}" for r in range(3) for c in range(4)]
    import csv
    csv.writer(out, lineterminator="\n").writerow(head)


def _write_csv(out, mech, result, links, t, offset, lf, af, inverse, branched=False):
    """One block of rows. The numbers of the block are gathered into one array (values in
    the output units, errors, link poses) and formatted by C loops (``tolist``, ``map(repr)``):
    per-value Python made 100 000 configurations of a 6R arm take 20 s of formatting."""
    import numpy as np
    from p105cli.kinematics.solver import angle_value_mask

    pl = result.plan
    slices = mech.value_slices
    n = result.Q.shape[0]
    cols = []
    for p in mech.pairs:
        scale = np.array([af if a else lf for a in angle_value_mask(p)])
        cols.append(result.Q[:, slices[p.name]] / scale)
    if inverse:
        cols.append(np.column_stack([result.position_error / lf, result.rotation_error]))
    else:
        cols.append(np.asarray(result.residual, dtype=np.float64)[:, None])
    left = np.hstack(cols) + 0.0   # + 0.0: no "-0.0" in the output
    poses = links[:, [pl.link_index[name] for name in mech.link_names], :3, :].copy()
    poses[..., 3] /= lf
    right = poses.reshape(n, -1) + 0.0
    index = range(offset, offset + n)
    tt = [""] * n if t is None else [repr(x) for x in (np.asarray(t, dtype=np.float64) + 0.0).tolist()]
    iters = np.asarray(result.iterations).tolist()
    if branched:   # the column after status
        status = [f"{s},{b}" for s, b in zip(result.status, np.asarray(result.branch).astype(int).tolist())]
    else:
        status = result.status
    write = out.write
    for i, ti, st, a, it, b in zip(index, tt, status, left.tolist(), iters, right.tolist()):
        write(f"{i},{ti},{st},{','.join(map(repr, a))},{it},{','.join(map(repr, b))}\n")


def _resulting_paths(mech, pl, specs, inverse, target_link, target_frame, frame):
    """The link frames whose resulting paths go into the model: --resulting-path, else the
    target of an inverse analysis."""
    from p105cli.part105.results import ResultingPathError, resulting_path_request
    try:
        if specs:
            return [resulting_path_request(mech, pl, spec) for spec in dict.fromkeys(specs)]
        if inverse:
            spec = target_link if target_frame is None or frame is None else f"{target_link}:{target_frame}"
            return [resulting_path_request(mech, pl, spec, frame_matrix=frame)]
    except ResultingPathError as err:
        raise InputError(str(err)) from None
    return []


def _write_model(out, mech, result, doc, t, paths=()):
    """The input model plus the analysis results, in the input's format (Part 21 or JSON)."""
    from p105cli.part105.results import add_results
    from ._emit import emit_json, emit_p21
    try:
        new, notes = add_results(doc, mech, result.Q, t, result.status, paths=paths, pl=result.plan)
    except ValueError as err:
        raise InputError(f"{doc.source}: {err}") from None
    if hasattr(doc, "text"):
        emit_p21(new, out)
    else:
        emit_json(new, out, False)
    for note in notes:
        diag("note", f"{doc.source}: {note}")


def _load_scene(path):
    try:
        from p105cli.cable.scene import load_scene_file
    except ImportError:
        raise InputError("--scene: scenes are not supported by this build") from None
    if not os.path.exists(path):
        raise InputError(f"{path}: cannot read: no such file")
    try:
        return load_scene_file(path)
    except (ValueError, OSError) as err:
        raise InputError(f"{path}: {err}") from None


def _run_scene(scene_dict, scene_path, keypoints, motion, out, pictures=(None, None)) -> bool:
    """Run the scene's effects on the motion; its records as JSON Lines (and the pictures
    asked for). False on findings."""
    from p105cli.cable.scene import scene_has_cables
    if not scene_has_cables(scene_dict):
        if any(pictures):
            diag("warning", f"{scene_path}: the scene has no cables: nothing to draw")
        return True
    from p105cli.cable import workflow  # only a scene with cables pays for the rod solvers
    base_dir = os.path.dirname(os.path.abspath(scene_path))
    ok = True
    if keypoints is not None:
        keypoints = os.path.abspath(keypoints)  # the scene resolves relative names from its own directory
    kept = [] if any(pictures) else None
    try:
        for rec in workflow.run_scene(scene_dict, keypoints=keypoints, motion=motion, base_dir=base_dir):
            if rec.get("type") == "summary" and rec.get("exit_code", 0):
                ok = False
            if kept is not None and rec.get("type") == "cable_state":
                kept.append(rec)
            out.write(json.dumps(rec, separators=(",", ":"), default=_json_default) + "\n")
    except ValueError as err:
        raise InputError(f"{scene_path}: {err}") from None
    if kept is not None:
        from p105cli.cable import display  # matplotlib only when a picture is asked for
        plot, animation = pictures
        try:
            if plot is not None:
                display.plot_shapes(kept, plot)
            if animation is not None:
                display.animate(kept, animation)
        except display.DisplayError as err:
            raise InputError(str(err)) from None
    return ok


def _json_default(x):
    import numpy as np
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(f"not JSON serialisable: {type(x).__name__}")
