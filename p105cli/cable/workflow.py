"""The patent's moving-cable workflow (CN101727523A, steps 231-236) over a scene.

For every key point of the moving end, in time order, and for every cable
of the scene:

1. over-length check: the straight distance ``|R|`` between the held ends
   against the length ``L``; ``|R| >= L`` ends the run with an ``error``
   diagnostic (the caller exits 1); a ``warning`` while the slack
   ``(L - |R|) / L`` is below ``slack_warning``, because the tension grows
   like ``(L - |R|)^-1/2`` as the slack vanishes;
2. solve (model ``rod`` or ``patent``), warm-started from the previous key
   point; a failed solve is retried by halving the step (intermediate end
   poses: linear in position, slerp in rotation) up to ``MAX_HALVINGS``
   times;
3. symmetry-error check between consecutive key points: the node farthest
   from the vertical plane through both ends (when it is farther than
   ``symmetry_threshold * L``) must not switch sides (be farther than that
   on the other side at the next key point). If it does, the new
   solution is mirrored back across the plane only when the end conditions
   are mirror-symmetric (then the mirror image is an equilibrium of the same
   problem); otherwise the step is rejected and halved;
4. node frames (4x4, translation in the last column), end loads on both
   bodies (world, the loads the cable exerts on them), maximum curvature
   against the minimum bend radius;
5. stop after the last key point.

Records (plain dicts, JSON-ready, SI units, never NaN)::

    {"type": "cable_state", "cable", "key", "t", "status", "converged", "model",
     "segments", "nodes"?, "frames"?, "end_loads"?, "max_curvature"?,
     "min_bend_radius"?, "min_bend_radius_ok"?, "slack"?, "symmetry"?,
     "residual", "iterations", "halvings", "error_estimate"?, "time_s"}
    {"type": "diagnostic", "level": "error"|"warning", "code", "cable", "key", "t", "message", ...}
    {"type": "summary", ..., "exit_code": 0|1}           (always last)

Fields marked ``?`` are present only when the cable's ``effects`` ask for
them. Nothing is imported, evaluated or written for an effect or a cable
the scene does not call for: a scene without cables imports neither solver.
"""

from __future__ import annotations

import math
import os
import time
from typing import Iterable, Iterator

import numpy as np

from p105cli.cable.scene import Scene, SceneError, pose_matrix, read_scene, scene_has_cables
from p105cli.formats.poses import parse_pose_file, parse_poses
from p105cli.formats.text import FormatError

__all__ = ["run_scene", "load_keypoints", "KeypointError", "scene_needs_cables",
           "mirror_solution", "symmetry_plane", "MAX_HALVINGS"]

MAX_HALVINGS = 6
scene_needs_cables = scene_has_cables


class KeypointError(FormatError):
    """A key-point file that cannot be read; the message names FILE:LINE:COL."""


# --- key points ---------------------------------------------------------------------

def load_keypoints(path, text: str | None = None) -> list[dict]:
    """Key points ``[{"t": float, "pose": (4, 4) array, "line": int}]`` from a pose file.

    The file is read by :mod:`p105cli.formats.poses` (JSON Lines ``{"t", "pose"}``
    or CSV ``t,m00,...,m23``; the format of ``solve --path``): a missing ``t``
    is the key point's index. Poses are in the scene's length unit and in the
    frame the scene gives for the moving end; they are converted by
    :func:`run_scene`. Times must not decrease. Errors name ``FILE:LINE:COL``.
    ``text``: the file's text when it is already read (standard input), named ``path``.
    """
    path = os.fspath(path)
    try:
        samples = parse_pose_file(path) if text is None else parse_poses(text, path)
    except OSError as err:
        raise KeypointError(f"{path}: cannot read: {err.strerror}") from None
    except FormatError as err:
        raise KeypointError(str(err)) from None
    out, last_t = [], -math.inf
    for t, T, line in zip(samples.times().tolist(), samples.poses, samples.lines):
        if t < last_t:
            raise KeypointError(f"{path}:{line}:1: t = {t:g} goes back in time (previous {last_t:g})")
        last_t = t
        out.append({"t": t, "pose": T, "line": line})
    return out


# --- geometry helpers ----------------------------------------------------------------

def _up(scene: Scene) -> np.ndarray:
    """The patent's zeta axis: against gravity, world +z without gravity."""
    if scene.gravity is not None and np.linalg.norm(scene.gravity) > 0:
        return -scene.gravity / np.linalg.norm(scene.gravity)
    return np.array([0.0, 0.0, 1.0])


def symmetry_plane(p_start, p_end, up, length):
    """Unit normal of the vertical plane through both ends, or None when the chord is vertical.

    The patent writes it as the line ``(d-b)x + (a-c)y + bc - ad = 0`` through
    the horizontal projections (a, b) and (c, d) of the ends; this is the same
    plane for any ``up``.
    """
    chord = np.asarray(p_end, float) - np.asarray(p_start, float)
    horiz = chord - (chord @ up) * up
    if np.linalg.norm(horiz) < 1e-9 * length:
        return None
    nrm = np.cross(up, horiz)
    return nrm / np.linalg.norm(nrm)


def _mirror_variant(T, nrm, tol=1e-9):
    """Which section flip S makes the reflected frame equal to T: 'y', 'x' or None."""
    R = T[:3, :3]
    d1, d2, d3 = R[:, 0] @ nrm, R[:, 1] @ nrm, R[:, 2] @ nrm
    if abs(d3) > tol:
        return None
    if abs(d1) < tol and abs(abs(d2) - 1) < tol:
        return "y"        # d1 in the plane, d2 across it: M R diag(1,-1,1) = R
    if abs(d2) < tol and abs(abs(d1) - 1) < tol:
        return "x"
    return None


def mirror_symmetric(spec, T_s, T_e, nrm, up) -> str | None:
    """The section flip for which the problem is its own mirror image, or None.

    Positions lie in the plane by construction and gravity is vertical; a
    clamped end needs its tangent in the plane and one section axis across
    it; a free end needs its force in the plane. A pinned end constrains
    only its position.
    """
    variants = set()
    for end, T in ((spec.start, T_s), (spec.end, T_e)):
        if end.condition == "clamped":
            v = _mirror_variant(T, nrm)
            if v is None:
                return None
            variants.add(v)
        elif end.condition == "free" and end.force is not None:
            if abs(end.force @ nrm) > 1e-9 * (np.linalg.norm(end.force) + 1e-300):
                return None
    if len(variants) > 1:
        return None
    return variants.pop() if variants else "y"


def mirror_solution(sol, p0, nrm, variant="y"):
    """The mirror image of a rod solution across the plane through ``p0`` with normal ``nrm``.

    Points and forces reflect with ``M = I - 2 n n^T``; moments are axial
    vectors (``-M m``); frames become ``M R S`` with ``S`` the section flip
    that keeps them right-handed (``diag(1,-1,1)`` or ``diag(-1,1,1)``).
    """
    import dataclasses

    from p105cli.kinematics.spatial import matrix_to_quaternion, quaternion_to_matrix

    M = np.eye(3) - 2.0 * np.outer(nrm, nrm)
    S = np.diag([1.0, -1.0, 1.0]) if variant == "y" else np.diag([-1.0, 1.0, 1.0])
    nodes = p0 + (sol.nodes - p0) @ M.T
    frames = np.array(sol.frames, float, copy=True)
    frames[:, :3, :3] = M @ frames[:, :3, :3] @ S
    frames[:, :3, 3] = nodes
    q = np.asarray(sol.quaternions, float)
    qm = matrix_to_quaternion(M @ quaternion_to_matrix(q) @ S)
    def mirror_state(st):
        # the solvers' warm-start states hold the same kinds of quantities
        if isinstance(st, (tuple, list)):
            return type(st)(mirror_state(x) for x in st)
        if not isinstance(st, dict):
            return None
        out = {}
        for k, v in st.items():
            if k in ("q", "quaternions"):
                out[k] = matrix_to_quaternion(M @ quaternion_to_matrix(np.asarray(v, float)) @ S)
            elif k in ("mu", "force_end"):
                out[k] = np.asarray(v, float) @ M.T
            elif k == "x":
                out[k] = p0 + (np.asarray(v, float) - p0) @ M.T
            elif k in ("Ts", "Te"):
                T = np.array(v, float, copy=True)
                T[:3, :3] = M @ T[:3, :3] @ S
                T[:3, 3] = p0 + M @ (T[:3, 3] - p0)
                out[k] = T
            else:
                # nested states (the Richardson mesh, the predictor's history) mirror alike
                out[k] = mirror_state(v) if isinstance(v, (dict, tuple, list)) and k in (
                    "richardson", "prev", "prev2") else v
        return out

    return dataclasses.replace(
        sol, nodes=nodes, frames=frames, quaternions=qm,
        force_start=M @ sol.force_start, force_end=M @ sol.force_end,
        moment_start=-(M @ sol.moment_start), moment_end=-(M @ sol.moment_end),
        _state=mirror_state(sol.state()))


def _interp_pose(Ta, Tb, f):
    from p105cli.kinematics.spatial import slerp
    T = np.eye(4)
    T[:3, :3] = slerp(Ta[:3, :3], Tb[:3, :3], f)
    T[:3, 3] = (1 - f) * Ta[:3, 3] + f * Tb[:3, 3]
    return T


# --- the run -------------------------------------------------------------------------

class _Timer:
    def __init__(self):
        self.per_effect = {}

    def add(self, name, dt):
        self.per_effect[name] = self.per_effect.get(name, 0.0) + dt


def _schedule(scene: Scene, keypoints, motion, base_dir):
    """[(t, {cable name: (T_start_world, T_end_world)})] for the whole run."""
    if keypoints is not None and isinstance(keypoints, (str, os.PathLike)):
        p = os.fspath(keypoints)
        # as given (relative to the working directory); else next to the scene file
        if base_dir and not os.path.isabs(p) and not os.path.exists(p):
            p = os.path.join(base_dir, p)
        keypoints = load_keypoints(p)
    samples = []
    if motion is not None:
        samples = [(float(t), dict(links)) for t, links in motion]
        if not samples:
            raise ValueError("motion has no samples")
    if keypoints is not None:
        kps = list(keypoints)
        if not kps:
            raise ValueError("no key points")
        if samples and len(samples) != len(kps):
            raise ValueError(f"{len(kps)} key points but {len(samples)} motion samples: they must pair up")
    kp_poses = []
    if keypoints is not None:
        for i, kp in enumerate(kps):
            if not isinstance(kp, dict) or "pose" not in kp or "t" not in kp:
                raise ValueError(f"key point {i}: expected {{'t': t, 'pose': 4x4}}")
            try:   # checked like a scene pose; translation from the scene's length unit
                kp_poses.append(pose_matrix(np.asarray(kp["pose"], float).tolist(), "pose",
                                            scene.length_unit))
            except (SceneError, ValueError) as err:
                where = f"line {kp['line']}" if "line" in kp else f"key point {i}"
                raise ValueError(f"{where}: {getattr(err, 'message', err)}") from None
    n = len(kps) if keypoints is not None else (len(samples) if samples else 1)
    out = []
    for i in range(n):
        links = samples[i][1] if samples else {}
        t = float(kps[i]["t"]) if keypoints is not None else (samples[i][0] if samples else 0.0)
        poses = {}
        for spec in scene.cables:
            ends = []
            for which, end in (("start", spec.start), ("end", spec.end)):
                local = end.pose
                if which == "end" and keypoints is not None:
                    local = kp_poses[i]
                if end.link is None:
                    ends.append(local)
                    continue
                if end.link not in links:
                    what = f"motion sample {i}" if samples else "the scene (no motion given)"
                    raise ValueError(f"cable {spec.name!r} {which} is attached to link {end.link!r}, "
                                     f"which {what} does not place")
                ends.append(np.asarray(links[end.link], float) @ local)
            poses[spec.name] = tuple(ends)
        out.append((t, poses))
    return out


def _problem(spec, scene, T_s, T_e):
    from p105cli.cable.rod import RodProblem
    return RodProblem(length=spec.length, stiffness=tuple(spec.stiffness), weight=scene.weight(spec),
                      T_start=T_s, T_end=T_e, start=spec.start.condition, end=spec.end.condition,
                      start_force=spec.start.force, end_force=spec.end.force)


def _solver(spec):
    if spec.model == "patent":
        from p105cli.cable.patent import solve_patent

        def solve(problem, warm):
            return solve_patent(problem, segments=spec.segments, tol=spec.tol, warm=warm)
    else:
        from p105cli.cable.rod import solve_rod

        def solve(problem, warm):
            return solve_rod(problem, segments=spec.segments, tol=spec.tol, warm=warm,
                             richardson=spec.richardson)
    return solve


def _ok(sol):
    # "non_unique": converged, one member of a continuous family of equilibria (reported)
    return bool(sol.converged) and sol.status in ("ok", "non_unique")


class _CableRun:
    """The state carried from key point to key point for one cable."""

    def __init__(self, spec, scene, timer):
        self.spec, self.scene, self.timer = spec, scene, timer
        self.solve = _solver(spec)
        self.up = _up(scene)
        self.prev = None            # (T_s, T_e, solution) at the previous key point
        self.mirrored = 0
        self.halved = 0

    def _flip(self, prev, T_s, T_e, sol):
        """(flipped, normal) of the symmetry-error test between ``prev`` and ``sol``."""
        spec = self.spec
        if prev is None or not spec.wants("symmetry_check"):
            return False, None
        Tps, Tpe, psol = prev
        L = spec.length
        n_prev = symmetry_plane(Tps[:3, 3], Tpe[:3, 3], self.up, L)
        n_new = symmetry_plane(T_s[:3, 3], T_e[:3, 3], self.up, L)
        if n_prev is None or n_new is None:
            return False, n_new
        d_prev = (psol.nodes - Tps[:3, 3]) @ n_prev
        i = int(np.argmax(np.abs(d_prev)))
        if abs(d_prev[i]) <= spec.symmetry_threshold * L:
            return False, n_new
        j = int(round(i * (len(sol.nodes) - 1) / max(len(psol.nodes) - 1, 1)))
        d_new = (sol.nodes[j] - T_s[:3, 3]) @ n_new
        # a real switch puts it past the threshold on the other side (not rounding around 0)
        return bool(d_new * np.sign(d_prev[i]) < -spec.symmetry_threshold * L), n_new

    def _attempt(self, prev, T_s, T_e, depth):
        """Solve at (T_s, T_e) from ``prev``; returns (solution, action, halvings)."""
        t0 = time.perf_counter()
        warm = prev[2].state() if prev is not None else None
        sol = self.solve(_problem(self.spec, self.scene, T_s, T_e), warm)
        self.timer.add("solve", time.perf_counter() - t0)
        action = "none"
        if _ok(sol):
            if not self.spec.wants("symmetry_check"):
                return sol, action, 0
            t1 = time.perf_counter()
            flipped, nrm = self._flip(prev, T_s, T_e, sol)
            if flipped:
                variant = mirror_symmetric(self.spec, T_s, T_e, nrm, self.up)
                if variant is not None:
                    sol = mirror_solution(sol, T_s[:3, 3], nrm, variant)
                    action = "mirrored"
                else:
                    action = "rejected"
            self.timer.add("symmetry_check", time.perf_counter() - t1)
            if action != "rejected":
                return sol, action, 0
        if prev is None or depth >= MAX_HALVINGS:
            return sol, action, 0
        # halve the step: reach the midpoint first, then the target from there
        Tm_s = _interp_pose(prev[0], T_s, 0.5)
        Tm_e = _interp_pose(prev[1], T_e, 0.5)
        msol, _, h1 = self._attempt(prev, Tm_s, Tm_e, depth + 1)
        if not _ok(msol):
            return msol, action, h1 + 1
        sol2, action2, h2 = self._attempt((Tm_s, Tm_e, msol), T_s, T_e, depth + 1)
        if action == "rejected" and action2 != "rejected":
            action2 = "halved"
        return sol2, action2, h1 + h2 + 1

    def step(self, key, t, T_s, T_e):
        """Records for one key point; the last one tells whether to stop."""
        spec, timer = self.spec, self.timer
        L = spec.length
        records = []
        t_key = time.perf_counter()
        rec = {"type": "cable_state", "cable": spec.name, "key": key, "t": t,
               "model": spec.model, "segments": spec.segments}
        held = spec.start.condition != "free" and spec.end.condition != "free"
        if held:
            t0 = time.perf_counter()
            dist = float(np.linalg.norm(T_e[:3, 3] - T_s[:3, 3]))
            slack = (L - dist) / L
            timer.add("overlength", time.perf_counter() - t0)
            if dist >= L:
                records.append(_diag("error", "overlength", spec.name, key, t,
                                     f"cable {spec.name!r}: the ends are {dist:.6g} m apart, "
                                     f"longer than the cable ({L:.6g} m)",
                                     distance=dist, length=L))
                return records, True
            if spec.wants("overlength"):
                rec["slack"] = slack
                if slack < spec.slack_warning:
                    records.append(_diag("warning", "near_taut", spec.name, key, t,
                                         f"cable {spec.name!r}: slack {100 * slack:.3g} % of its length; "
                                         "the tension grows like (L - |R|)^-1/2", distance=dist, length=L))
        sol, action, halvings = self._attempt(self.prev, T_s, T_e, 0)
        if action == "mirrored":
            self.mirrored += 1
        if action == "halved":
            self.halved += 1
        rec.update(status=sol.status, converged=bool(sol.converged),
                   residual=float(sol.residual), iterations=int(sol.iterations), halvings=halvings)
        if spec.wants("symmetry_check"):
            rec["symmetry"] = {"action": action if action != "rejected" else "unresolved"}
            if action == "rejected":
                records.append(_diag("warning", "symmetry_unresolved", spec.name, key, t,
                                     f"cable {spec.name!r}: the farthest node still switches sides of the "
                                     f"vertical plane after {MAX_HALVINGS} halvings (a snap-through?)"))
        if not _ok(sol):
            rec["time_s"] = time.perf_counter() - t_key
            records.append(_clean(rec))
            records.append(_diag("error", sol.status if sol.status != "ok" else "not_converged",
                                 spec.name, key, t,
                                 f"cable {spec.name!r}: the {spec.model} solver did not converge "
                                 f"(status {sol.status}, residual {float(sol.residual):.3g})"
                                 + (f": {sol.message}" if getattr(sol, "message", "") else "")))
            return records, True
        if sol.status == "non_unique":
            records.append(_diag("warning", "non_unique", spec.name, key, t,
                                 f"cable {spec.name!r}: " + (getattr(sol, "message", "") or
                                                            "the equilibrium is not unique")))
        if getattr(sol, "error_estimate", None) is not None:
            rec["error_estimate"] = float(sol.error_estimate)
        if spec.wants("shape"):
            t0 = time.perf_counter()
            rec["nodes"] = np.asarray(sol.nodes, float).tolist()
            timer.add("shape", time.perf_counter() - t0)
        if spec.wants("frames"):
            t0 = time.perf_counter()
            rec["frames"] = np.asarray(sol.frames, float).tolist()
            timer.add("frames", time.perf_counter() - t0)
        if spec.wants("end_loads"):
            t0 = time.perf_counter()
            rec["end_loads"] = {
                "start": {"link": spec.start.link, "force": np.asarray(sol.force_start, float).tolist(),
                          "moment": np.asarray(sol.moment_start, float).tolist()},
                "end": {"link": spec.end.link, "force": np.asarray(sol.force_end, float).tolist(),
                        "moment": np.asarray(sol.moment_end, float).tolist()}}
            timer.add("end_loads", time.perf_counter() - t0)
        if spec.wants("min_bend_radius"):
            t0 = time.perf_counter()
            kmax = float(np.max(sol.curvature)) if len(sol.curvature) else 0.0
            rec["max_curvature"] = kmax
            rec["min_bend_radius"] = spec.min_bend_radius
            rec["min_bend_radius_ok"] = bool(kmax * spec.min_bend_radius <= 1.0)
            if not rec["min_bend_radius_ok"]:
                records.append(_diag("warning", "min_bend_radius", spec.name, key, t,
                                     f"cable {spec.name!r}: bend radius {1.0 / kmax:.4g} m is below the "
                                     f"minimum {spec.min_bend_radius:.4g} m",
                                     bend_radius=1.0 / kmax, limit=spec.min_bend_radius))
            timer.add("min_bend_radius", time.perf_counter() - t0)
        self.prev = (T_s, T_e, sol)
        rec["time_s"] = time.perf_counter() - t_key
        records.insert(0, _clean(rec))
        return records, False


def _diag(level, code, cable, key, t, message, **extra):
    d = {"type": "diagnostic", "level": level, "code": code, "cable": cable, "key": key, "t": t,
         "message": message}
    d.update(extra)
    return _clean(d)


def _clean(obj):
    """JSON-ready copy with every non-finite float replaced by None (no NaN ever leaves)."""
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def run_scene(scene, *, keypoints=None, motion: Iterable | None = None, base_dir=None) -> Iterator[dict]:
    """Run the workflow; yields ``cable_state`` and ``diagnostic`` records, then one ``summary``.

    ``scene``: a raw scene dict (checked here; :class:`SceneError` naming
    the JSON path) or a :class:`Scene`. ``keypoints``: a list of
    ``{"t", "pose"}`` (pose 4x4 in the scene's length unit, in the frame of
    each cable's ``end``) or the path of a JSONL/CSV file (as given, else
    relative to ``base_dir``, the scene file's folder). ``motion``: an
    iterable of ``(t, {link name: 4x4 world placement in metres})``. With
    neither, the scene's poses are solved once (t = 0).

    Bad input (:class:`SceneError`, :class:`KeypointError`, ``ValueError``
    for links the motion does not place) is raised before the first record.
    The summary's ``exit_code`` is 1 when the run stopped on an over-length
    or a failed solve, or a check failed (bend radius); 0 otherwise.
    """
    t_start = time.perf_counter()
    if not isinstance(scene, Scene):
        scene = read_scene(scene)
    timer = _Timer()
    counts = {"states": 0, "error": 0, "warning": 0, "violations": 0}
    statuses = {}
    max_res = 0.0
    stop_reason = None
    keys = 0
    runs = {}
    if scene.cables:
        schedule = _schedule(scene, keypoints, motion, base_dir)
        runs = {spec.name: _CableRun(spec, scene, timer) for spec in scene.cables}
        for key, (t, poses) in enumerate(schedule):
            keys += 1
            for spec in scene.cables:
                T_s, T_e = poses[spec.name]
                recs, stop = runs[spec.name].step(key, t, T_s, T_e)
                for r in recs:
                    if r["type"] == "cable_state":
                        counts["states"] += 1
                        statuses[r["status"]] = statuses.get(r["status"], 0) + 1
                        if r.get("residual") is not None:
                            max_res = max(max_res, r["residual"])
                        if r.get("min_bend_radius_ok") is False:
                            counts["violations"] += 1
                    else:
                        counts[r["level"]] += 1
                    yield r
                if stop:
                    stop_reason = next((r["code"] for r in recs if r["type"] == "diagnostic"
                                        and r["level"] == "error"), "failed")
                    break
            if stop_reason:
                break
    failed = stop_reason is not None or counts["violations"] > 0
    yield _clean({
        "type": "summary", "units": "SI",
        "cables": [c.name for c in scene.cables],
        "key_points": keys, "states": counts["states"],
        "statuses": dict(sorted(statuses.items())),
        "max_residual": max_res,
        "diagnostics": {"error": counts["error"], "warning": counts["warning"]},
        "min_bend_radius_violations": counts["violations"],
        "symmetry_corrections": {"mirrored": sum(r.mirrored for r in runs.values()),
                                 "halved": sum(r.halved for r in runs.values())},
        "stopped": stop_reason is not None, "stop_reason": stop_reason,
        "time_s": {"total": time.perf_counter() - t_start,
                   "per_effect": dict(sorted(timer.per_effect.items()))},
        "exit_code": 1 if failed else 0,
    })
