"""A scene run as ``p105 solve --scene`` does it: the scene file, the key points, the records
written as JSON Lines, the pictures asked for.

No click: bad input, and a picture that cannot be drawn, are :class:`SceneInputError` (the
message names the file). Nothing of the
rod solvers or matplotlib is imported unless the scene has cables or a picture is asked for.
"""

from __future__ import annotations

import json
import os

__all__ = ["SceneInputError", "load_scene", "run", "json_default"]


class SceneInputError(ValueError):
    """A scene or key-point file that cannot be used; the message names the file."""


def load_scene(path) -> dict:
    """The raw scene of a JSON or TOML file."""
    try:
        from p105cli.cable.scene import load_scene_file
    except ImportError:
        raise SceneInputError("--scene: scenes are not supported by this build") from None
    if not os.path.exists(path):
        raise SceneInputError(f"{path}: cannot read: no such file")
    try:
        return load_scene_file(path)
    except (ValueError, OSError) as err:
        raise SceneInputError(f"{path}: {err}") from None
    except RecursionError:   # only the json and toml decoders recurse
        kind = "TOML" if os.fspath(path).endswith(".toml") else "JSON"
        raise SceneInputError(f"{path}: {kind} nested too deeply") from None


def run(scene, scene_path, keypoints, motion, out, pictures=(None, None), warn=None,
        timings: bool = True) -> bool:
    """Run the scene's effects on the motion (``[(t, {link: 4x4})]`` or None); its records as
    JSON Lines on ``out``, and the pictures ``(plot, animation)`` asked for. False on findings.
    ``timings`` False: no record says how long it took (``time_s`` left out), so the same
    input gives the same bytes.

    ``keypoints`` is a file name (relative to the working directory); ``warn(message)``
    receives remarks (nothing to draw)."""
    from p105cli.cable.scene import scene_has_cables
    if not scene_has_cables(scene):
        if any(pictures) and warn is not None:
            warn(f"{scene_path}: the scene has no cables: nothing to draw")
        return True
    from p105cli.cable import workflow  # only a scene with cables pays for the rod solvers
    base_dir = os.path.dirname(os.path.abspath(scene_path))
    ok = True
    kept = [] if any(pictures) else None
    try:
        scene = workflow.read_scene(scene)
        if keypoints is not None:   # the key points first, as the scene's run would read them
            # named as given (errors as solve --path's); a relative name is the working directory's
            keypoints = workflow.load_keypoints(keypoints)
        for rec in workflow.run_scene(scene, keypoints=keypoints, motion=motion, base_dir=base_dir):
            if rec.get("type") == "summary" and rec.get("exit_code", 0):
                ok = False
            if kept is not None and rec.get("type") == "cable_state":
                kept.append(rec)
            if not timings:
                rec.pop("time_s", None)
            out.write(json.dumps(rec, separators=(",", ":"), default=json_default) + "\n")
    except workflow.KeypointError as err:   # names its own file
        raise SceneInputError(str(err)) from None
    except ValueError as err:
        raise SceneInputError(f"{scene_path}: {err}") from None
    if kept is not None:
        _draw(kept, pictures)
    return ok


def _draw(states, pictures) -> None:
    from p105cli.cable import display  # matplotlib only when a picture is asked for
    plot, animation = pictures
    try:
        if plot is not None:
            display.plot_shapes(states, plot)
        if animation is not None:
            display.animate(states, animation)
    except display.DisplayError as err:   # names its file, or what is missing (matplotlib)
        raise SceneInputError(str(err)) from None


def json_default(x):
    """numpy arrays and scalars in the records as JSON lists and numbers."""
    import numpy as np
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(f"not JSON serialisable: {type(x).__name__}")
