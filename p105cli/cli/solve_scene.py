"""The scene of ``p105 solve`` (cables): the scene file, the model's own scene block, the run
on the solved motion (:mod:`p105cli.cable.run`); input errors are exit 2 naming their file."""

from __future__ import annotations

import click

from .contract import ExitCode, InputError, diag, open_output
from .inputs import STDIN, is_stdin, read_input_bytes, read_text

__all__ = ["check_samples", "load_scene", "model_scene", "prepare_scene", "run_scene", "scene_only"]


def scene_only(o):
    """A scene without a model: its cables between fixed ends or along key points."""
    if o.values is not None or o.sets or o.sweeps or o.path is not None:
        raise click.UsageError("--values, --set, --sweep and --path need a MODEL")
    prepared = prepare_scene(o)
    with open_output(o.output, (o.scene, o.keypoints)) as out:
        ok = run_scene(prepared, None, out, o.pictures, o.timings)
    if not ok:
        raise click.exceptions.Exit(ExitCode.FINDINGS)


def model_scene(doc, model, to, to_given):
    """The model carries its scene (a JSON model's "scene" block): run it as --scene would.
    Returns the output format, the scene and its name."""
    if not to_given:
        to = "jsonl"
    if to == "jsonl":
        return to, doc.scene, model if not is_stdin(model) else STDIN
    diag("note", f"{doc.source}: the model's scene is run with --to jsonl only")
    return to, None, None


def load_scene(path):
    """The scene file of --scene (JSON or TOML; ``-``: standard input, TOML unless a JSON object)."""
    from p105cli.cable import run
    try:
        if is_stdin(path):
            return run.load_scene(STDIN, read_input_bytes(path)[0])
        return run.load_scene(path)
    except run.SceneInputError as err:
        raise InputError(str(err)) from None


def prepare_scene(o, mech=None):
    """The scene checked and its key points read (``-``: standard input), and with a model
    its cables' links checked, before anything is solved."""
    from p105cli.cable import run
    name = o.scene if not is_stdin(o.scene) else STDIN
    keypoints, text = o.keypoints, None
    if keypoints is not None and is_stdin(keypoints):
        text, keypoints = read_text(keypoints)
    try:
        prepared = run.prepare(o.scene_dict, name, keypoints, text)
        if mech is not None:
            prepared.check_motion(mech.link_names, None)
        return prepared
    except run.SceneInputError as err:
        raise InputError(str(err)) from None


def check_samples(prepared, mech, samples):
    """The key points pair up with the motion's samples (known once the motion is read)."""
    from p105cli.cable import run
    try:
        prepared.check_motion(mech.link_names, samples)
    except run.SceneInputError as err:
        raise InputError(str(err)) from None


def run_scene(prepared, motion, out, pictures=(None, None), timings=True) -> bool:
    """The scene's effects on the motion as JSON Lines records; False on findings (each said
    on stderr)."""
    from p105cli.cable import run
    try:
        return run.run(prepared, motion, out, pictures, warn=lambda m: diag("warning", m),
                       timings=timings, error=lambda m: diag("error", m))
    except run.SceneInputError as err:
        raise InputError(str(err)) from None
