"""A scene run as ``p105 solve --scene`` does it: the scene file, the key points, the records
written as JSON Lines, the pictures asked for.

No click: bad input, and a picture that cannot be drawn, are :class:`SceneInputError` (the
message names the file). Nothing of the
rod solvers or matplotlib is imported unless the scene has cables or a picture is asked for.
"""

from __future__ import annotations

import json
import os

__all__ = ["SceneInputError", "Prepared", "load_scene", "prepare", "run", "json_default"]


class SceneInputError(ValueError):
    """A scene or key-point file that cannot be used; the message names the file."""


def load_scene(path, raw: bytes | None = None) -> dict:
    """The raw scene of a JSON or TOML file; ``raw``: its bytes when already read (standard
    input, named ``path``; TOML unless it is a JSON object)."""
    try:
        from p105cli.cable.scene import load_scene_file, looks_like_toml, parse_scene_bytes
    except ImportError:
        raise SceneInputError("--scene: scenes are not supported by this build") from None
    if raw is None and not os.path.exists(path):
        raise SceneInputError(f"{path}: cannot read: no such file")
    toml = os.fspath(path).endswith(".toml") if raw is None else looks_like_toml(raw)
    try:
        return load_scene_file(path) if raw is None else parse_scene_bytes(raw, path, toml=toml)
    except (ValueError, OSError) as err:
        raise SceneInputError(f"{path}: {err}") from None
    except RecursionError:   # only the json and toml decoders recurse
        raise SceneInputError(f"{path}: {'TOML' if toml else 'JSON'} nested too deeply") from None


class Prepared:
    """A scene checked and its key points read, before any motion is solved: bad input is an
    error before the first record (a scene's mistakes never follow a solved mechanism's output)."""

    def __init__(self, scene, scene_path, keypoints):
        self.scene_path = scene_path
        self.scene = scene          # a cable.scene.Scene
        self.keypoints = keypoints  # [{"t", "pose", "line"}] or None

    @property
    def has_cables(self) -> bool:
        return bool(self.scene.cables)

    def check_motion(self, link_names, samples: int | None) -> None:
        """The cables' links are links of the mechanism and the key points pair up with the
        motion's ``samples`` (None: not known yet): checked before the motion is solved."""
        known = set(link_names)
        for spec in self.scene.cables:
            for which, end in (("start", spec.start), ("end", spec.end)):
                if end.link is not None and end.link not in known:
                    raise SceneInputError(f"{self.scene_path}: cable {spec.name!r} {which} is attached to link "
                                          f"{end.link!r}, which is not a link of the mechanism (links: "
                                          f"{', '.join(link_names)})")
        if self.keypoints is not None and samples is not None and len(self.keypoints) != samples:
            raise SceneInputError(f"{self.scene_path}: {len(self.keypoints)} key points but {samples} motion "
                                  "samples: they must pair up")


def prepare(scene, scene_path, keypoints, keypoints_text: str | None = None) -> Prepared:
    """Check the raw ``scene`` and read the ``keypoints`` file (a name, relative to the
    working directory; ``keypoints_text``: its text when already read, standard input)."""
    from p105cli.cable import workflow
    try:
        checked = workflow.read_scene(scene)
        kps = None
        if keypoints is not None and checked.cables:
            # named as given (errors as solve --path's); a relative name is the working directory's
            kps = workflow.load_keypoints(keypoints, keypoints_text)
    except workflow.KeypointError as err:   # names its own file
        raise SceneInputError(str(err)) from None
    except ValueError as err:
        raise SceneInputError(f"{scene_path}: {err}") from None
    return Prepared(checked, scene_path, kps)


def run(prepared: Prepared, motion, out, pictures=(None, None), warn=None,
        timings: bool = True, error=None) -> bool:
    """Run the scene's effects on the motion (``[(t, {link: 4x4})]`` or None); its records as
    JSON Lines on ``out``, and the pictures ``(plot, animation)`` asked for. False on findings.
    ``timings`` False: no record says how long it took (``time_s`` left out), so the same
    input gives the same bytes.

    ``warn(message)`` receives remarks (nothing to draw); ``error(message)`` why the run
    failed (the error records and the bend-radius violations), so that a failure says why
    outside the records too."""
    scene_path = prepared.scene_path
    if not prepared.has_cables:
        if any(pictures) and warn is not None:
            warn(f"{scene_path}: the scene has no cables: nothing to draw")
        return True
    from p105cli.cable import workflow  # only a scene with cables pays for the rod solvers
    ok = True
    kept = [] if any(pictures) else None
    try:
        for rec in workflow.run_scene(prepared.scene, keypoints=prepared.keypoints, motion=motion):
            if rec.get("type") == "diagnostic" and rec.get("level") == "error" and error is not None:
                error(f"{scene_path}: key point {rec['key']} (t = {rec['t']:g}): {rec['message']}")
            if rec.get("type") == "summary" and rec.get("exit_code", 0):
                ok = False
                if rec.get("min_bend_radius_violations") and error is not None:
                    error(f"{scene_path}: {rec['min_bend_radius_violations']} cable state(s) bent tighter "
                          "than the minimum bend radius")
            if kept is not None and rec.get("type") == "cable_state":
                kept.append(rec)
            if not timings:
                rec.pop("time_s", None)
            out.write(json.dumps(rec, separators=(",", ":"), default=json_default) + "\n")
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
