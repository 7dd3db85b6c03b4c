"""The usage rules of ``p105 solve``: which options go together (click.UsageError, exit 2),
checked in order before any input is read."""

from __future__ import annotations

import math

import click

from .contract import diag
from .options import check_tol

__all__ = ["check_usage"]


def check_usage(o):
    """The usage errors of the command line, in order; the requested branch invariant."""
    _check_outputs(o.model, o.scene, o.to, o.plot, o.animation, o.resulting_paths)
    check_tol(o.tol)
    _check_motion(o.values, o.sets, o.sweeps, o.path, o.target_link, o.program)
    _check_sampling(o.program, o.count, o.step)
    want = _check_branch(o.branch, o.model, o.scene, o.path)
    if o.model is None and o.scene is None:
        o.model = "-"
    stdin_users = [n for n, v in (("MODEL", o.model), ("--values", o.values), ("--path", o.path)) if v == "-"]
    if len(stdin_users) > 1:
        raise click.UsageError(f"only one of {' and '.join(stdin_users)} can read standard input")
    return want


def _check_outputs(model, scene, to, plot, animation, resulting_paths):
    if scene is not None and to != "jsonl":
        raise click.UsageError("--scene writes JSON Lines (--to jsonl)")
    for name, target in (("--plot", plot), ("--animate", animation)):
        if target is not None and model is None and scene is None:
            raise click.UsageError(f"{name} draws a scene's cables: it needs --scene (or a model with a scene)")
    if resulting_paths and to != "model":
        # the tables carry every link's placement already; the path entities are model output
        diag("note", f"--resulting-path is written with --to model only; the {to} output has the link placements")


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
