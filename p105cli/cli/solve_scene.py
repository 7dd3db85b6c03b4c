"""The scene of ``p105 solve`` (cables): the scene file, the model's own scene block, the run
on the solved motion (:mod:`p105cli.cable.run`); input errors are exit 2 naming their file."""

from __future__ import annotations

import click

from .contract import ExitCode, InputError, diag, open_output
from .inputs import is_stdin

__all__ = ["load_scene", "model_scene", "run_scene", "scene_only"]


def scene_only(o):
    """A scene without a model: its cables between fixed ends or along key points."""
    if o.values is not None or o.sets or o.sweeps or o.path is not None:
        raise click.UsageError("--values, --set, --sweep and --path need a MODEL")
    with open_output(o.output, (o.scene, o.keypoints)) as out:
        ok = run_scene(o.scene_dict, o.scene, o.keypoints, None, out, o.pictures, o.timings)
    if not ok:
        raise click.exceptions.Exit(ExitCode.FINDINGS)


def model_scene(doc, model, to, to_given):
    """The model carries its scene (a JSON model's "scene" block): run it as --scene would.
    Returns the output format, the scene and its name."""
    if not to_given:
        to = "jsonl"
    if to == "jsonl":
        return to, doc.scene, model if not is_stdin(model) else "."
    diag("note", f"{doc.source}: the model's scene is run with --to jsonl only")
    return to, None, None


def load_scene(path):
    """The scene file of --scene (JSON or TOML)."""
    from p105cli.cable import run
    try:
        return run.load_scene(path)
    except run.SceneInputError as err:
        raise InputError(str(err)) from None


def run_scene(scene, scene_path, keypoints, motion, out, pictures=(None, None), timings=True) -> bool:
    """The scene's effects on the motion as JSON Lines records; False on findings."""
    from p105cli.cable import run
    try:
        return run.run(scene, scene_path, keypoints, motion, out, pictures, warn=lambda m: diag("warning", m),
                       timings=timings)
    except run.SceneInputError as err:
        raise InputError(str(err)) from None
