"""The usage rules of ``p105 solve``: which options go together (click.UsageError, exit 2),
checked in order before any input is read."""

from __future__ import annotations

import math

import click

from .options import check_tol

__all__ = ["check_after_reading", "check_usage"]


def check_usage(o):
    """The usage errors of the command line, in order; the requested branch invariant.
    ``o.given``: the options given on the command line (not their defaults)."""
    _check_outputs(o.model, o.scene, o.to, o.plot, o.animation, o.resulting_paths, o.keypoints, o.output)
    check_tol(o.tol)
    _check_motion(o.values, o.sets, o.sweeps, o.path, o.target_link, o.program)
    _check_targets(o.path, o.target_link, o.target_frame, o.program)
    _check_sampling(o.program, o.count, o.step)
    want = _check_branch(o.branch, o.model, o.scene, o.path)
    _check_idle(o)
    if o.model is None and o.scene is None:
        o.model = "-"
    stdin_users = [n for n, v in (("MODEL", o.model), ("--values", o.values), ("--path", o.path),
                                  ("--scene", o.scene), ("--keypoints", o.keypoints)) if v == "-"]
    if len(stdin_users) > 1:
        raise click.UsageError(f"only one of {' and '.join(stdin_users)} can read standard input")
    return want


def check_after_reading(o) -> None:
    """Once the model is read (it may carry its own scene, which makes JSON Lines the default
    output), before anything is solved: the options that would do nothing with the output and
    the scene that will be."""
    given = o.given
    if o.to != "jsonl" and "timings" in given and o.timings:
        raise click.UsageError(f"--timings reports times in the jsonl summary: --to {o.to} has none")
    if o.to == "model":
        if "angle_unit" in given and not (o.values is not None or o.sets or o.sweeps):
            raise click.UsageError("--angle-unit is the unit of --values, --set, --sweep and the jsonl/csv "
                                   "output: with --to model and none of them it does nothing")
        if "length_unit" in given and not (o.values is not None or o.sets or o.sweeps or o.path is not None):
            raise click.UsageError("--length-unit is the unit of --values, --set, --sweep, --path and the "
                                   "jsonl/csv output: with --to model and none of them it does nothing")
    if o.prepared is not None:
        return
    why = (f"the model's scene is run with --to jsonl only (not --to {o.to})" if o.scene_in_model
           else "the model has no scene and no --scene is given")
    for name, value in (("--keypoints", o.keypoints), ("--plot", o.plot), ("--animate", o.animation)):
        if value is not None:
            raise click.UsageError(f"{name} is for a scene's cables: {why}")


def _check_outputs(model, scene, to, plot, animation, resulting_paths, keypoints, output):
    if scene is not None and to != "jsonl":
        raise click.UsageError("--scene writes JSON Lines (--to jsonl)")
    for name, target in (("--plot", plot), ("--animate", animation), ("--keypoints", keypoints)):
        if target is not None and model is None and scene is None:
            raise click.UsageError(f"{name} is for a scene's cables: it needs --scene (or a model with a scene)")
    to_stdout = [name for name, target in (("--plot", plot), ("--animate", animation)) if target == "-"]
    if len(to_stdout) > 1:
        raise click.UsageError("only one of --plot - and --animate - can write to standard output")
    if to_stdout and output in (None, "-"):
        raise click.UsageError(f"{to_stdout[0]} - writes the picture to standard output: the records need "
                               "-o FILE then")
    if resulting_paths and to != "model":
        # the tables carry every link's placement already; the path entities are model output
        raise click.UsageError(f"--resulting-path is written with --to model only; the {to} output has the "
                               "link placements")


def _check_targets(path, target_link, target_frame, program):
    """--target-link and --target-frame place --path; without it they would do nothing."""
    for name, value in (("--target-link", target_link), ("--target-frame", target_frame)):
        if value is not None and path is None:
            why = ("the model's program names the link that follows its path" if program
                   else "they place the poses of --path (inverse analysis)")
            raise click.UsageError(f"{name} needs --path: {why}")


#: What only the analysis of a model uses (parameter name, flag).
_ANALYSIS_OPTIONS = (("program", "--program"), ("mechanism", "--mechanism"), ("schema", "--schema"),
                     ("resulting_paths", "--resulting-path"), ("tol", "--tol"), ("max_iter", "--max-iter"),
                     ("angle_unit", "--angle-unit"), ("length_unit", "--length-unit"))


def _check_idle(o):
    """Options that would do nothing in the mode chosen (usage errors, never silently ignored)."""
    given = o.given
    if o.model is None and o.scene is not None:   # a scene alone: no mechanism is analysed
        idle = next((flag for name, flag in _ANALYSIS_OPTIONS if name in given), None)
        if idle is not None:
            raise click.UsageError(f"{idle} is for the analysis of a MODEL: --scene without a model runs "
                                   "the scene alone (its records are in SI units)")


def _check_motion(values, sets, sweeps, path, target_link, program):
    """Which ways of giving a motion go together."""
    forward = values is not None or bool(sets) or bool(sweeps)
    if path is not None and target_link is None:
        raise click.UsageError("--path needs --target-link")
    if path is not None and forward:
        raise click.UsageError("--path (inverse analysis) cannot be combined with --values, --set or --sweep")
    if sweeps and values is not None:
        raise click.UsageError("--sweep and --values cannot be combined")
    if program and (forward or path is not None):
        raise click.UsageError("--program runs the model's own motion: it cannot be combined with --values, "
                               "--set, --sweep or --path")


def _check_sampling(program, count, step):
    if (count is not None or step is not None) and not program:
        raise click.UsageError("--count and --step sample a motion program: they need --program")
    if count is not None and step is not None:
        raise click.UsageError("give at most one of --count and --step")
    if step is not None and not (step > 0.0 and math.isfinite(step)):
        raise click.UsageError("--step must be a positive number")


def _check_branch(branch, model, scene, path):
    """The requested branch invariant (None: the initial state's)."""
    want = {"initial": None, "+": 1, "-": -1}[branch]
    if want is not None and (path is not None or (model is None and scene is not None)):
        raise click.UsageError(f"--branch {branch}: the assembly branch is chosen in forward analysis of a model "
                               "with closed loops" + (" (not with --path)" if path is not None else ""))
    return want
