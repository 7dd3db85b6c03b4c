"""The rod problem and its solution (conventions in the class docstrings), and
what is done to a problem before it is solved: validation, reversal of the
arc length, the symmetric families, the over-length answer, pose paths.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from p105cli.kinematics.spatial import matrix_to_quaternion

from .quaternions import _EYE3, _cross, _pose_quat, _qmat, _qmul, _slerp_mid


END_KINDS = ("clamped", "pinned", "free")


_FLIP = np.diag([1.0, -1.0, -1.0, 1.0])   # half-turn about x: reverses the tangent, keeps x
_Q_FLIP = np.array([0.0, 1.0, 0.0, 0.0])


# --------------------------------------------------------------------------- problem / solution

@dataclass(frozen=True)
class RodProblem:
    """A cable held at its ends. Poses are 4x4 world placements (z = tangent, x/y = section axes).

    ``T_start``: origin = start point, z = tangent out of the start.
    ``T_end``: origin = end point, z = tangent into the end (increasing arc length).
    ``stiffness = (A, B, C)`` N m^2. ``weight`` (3,) N/m, world.
    End kinds: "clamped" (position and frame held), "pinned" (position held,
    no moment), "free" (no support; ``start_force``/``end_force`` dead point
    loads, N, world). At least one end must be supported.
    """

    length: float
    stiffness: tuple
    weight: np.ndarray
    T_start: np.ndarray
    T_end: np.ndarray
    start: str = "clamped"
    end: str = "clamped"
    start_force: np.ndarray | None = None
    end_force: np.ndarray | None = None


@dataclass
class RodSolution:
    """Equilibrium of a :class:`RodProblem` (all arrays world frame, SI, never NaN).

    ``force_*``/``moment_*``: force and moment the CABLE EXERTS ON THE BODY at
    that end (moment about the end point). With the weight ``W = f L`` they
    satisfy ``force_start + force_end = W`` (the bodies carry the weight).
    ``curvature`` (n+1,): bending curvature |(u_x, u_y)| at the nodes (ends:
    from the clamp half-cells, 0 at pinned/free ends). ``residual``: max of the
    scaled KKT residuals (docs/cable-rod.md). ``error_estimate``: Richardson
    estimate of the position error (m) when ``richardson=True``.
    """

    s: np.ndarray
    nodes: np.ndarray
    frames: np.ndarray
    quaternions: np.ndarray
    force_start: np.ndarray
    moment_start: np.ndarray
    force_end: np.ndarray
    moment_end: np.ndarray
    curvature: np.ndarray
    residual: float
    iterations: int
    converged: bool
    status: str
    error_estimate: float | None = None
    message: str = ""
    stable: bool | None = None
    _state: dict | None = field(default=None, repr=False)

    def state(self):
        """Opaque warm-start state for the next :func:`solve_rod` (``warm=``)."""
        return self._state


# --------------------------------------------------------------------------- problem handling

def _validate(p: RodProblem) -> None:
    if p.start not in END_KINDS or p.end not in END_KINDS:
        raise ValueError(f"rod: end kinds must be one of {END_KINDS}, got {p.start!r}, {p.end!r}")
    if p.start == "free" and p.end == "free":
        raise ValueError("rod: at least one end must be supported (clamped or pinned)")
    L = float(p.length)
    if not (np.isfinite(L) and L > 0.0):
        raise ValueError("rod: length must be finite and > 0")
    K = np.asarray(p.stiffness, dtype=float)
    if K.shape != (3,) or not np.all(np.isfinite(K)) or np.any(K <= 0.0):
        raise ValueError("rod: stiffness must be (A, B, C), all finite and > 0")
    for name in ("T_start", "T_end"):
        T = np.asarray(getattr(p, name), dtype=float)
        if T.shape != (4, 4) or not np.all(np.isfinite(T)):
            raise ValueError(f"rod: {name} must be a finite 4x4 pose")
        R = T[:3, :3]
        if np.abs(R.T @ R - _EYE3).max() > 1e-6 or float(_cross(R[:, 0], R[:, 1]) @ R[:, 2]) < 0:
            raise ValueError(f"rod: {name} rotation part is not a rotation")
    for name in ("weight", "start_force", "end_force"):
        v = getattr(p, name)
        if v is not None and (np.asarray(v, float).shape != (3,) or not np.all(np.isfinite(v))):
            raise ValueError(f"rod: {name} must be a finite 3-vector")


def _reversed(p: RodProblem) -> RodProblem:
    """The same cable with arc length reversed (start <-> end; section y and tangent flipped)."""
    return RodProblem(p.length, tuple(p.stiffness), p.weight,
                      np.asarray(p.T_end, float) @ _FLIP, np.asarray(p.T_start, float) @ _FLIP,
                      p.end, p.start, p.end_force, p.start_force)


def _unreverse(sol: RodSolution, L: float) -> RodSolution:
    frames = sol.frames[::-1] @ _FLIP
    return RodSolution(
        s=L - sol.s[::-1], nodes=sol.nodes[::-1].copy(), frames=frames,
        quaternions=_qmul(sol.quaternions[::-1], _Q_FLIP),
        force_start=sol.force_end, moment_start=sol.moment_end,
        force_end=sol.force_start, moment_end=sol.moment_start,
        curvature=sol.curvature[::-1].copy(), residual=sol.residual, iterations=sol.iterations,
        converged=sol.converged, status=sol.status, error_estimate=sol.error_estimate,
        message=sol.message, _state=sol._state, stable=sol.stable)


def _coaxial_family_axis(p: RodProblem):
    """Axis (point, unit direction) when the problem is invariant under rotation about it (else None).

    Isotropic section (A = B), both ends clamped on one axis with both tangents
    along it, weight zero or along it: rotating a bent equilibrium about the
    axis (with the material frames turned back about their tangents) gives
    another equilibrium, so bent solutions form a continuous family.
    """
    A, B, _ = (float(k) for k in p.stiffness)
    if abs(A - B) > 1e-9 * max(A, B) or p.start != "clamped" or p.end != "clamped":
        return None
    Ts, Te = np.asarray(p.T_start, float), np.asarray(p.T_end, float)
    zs, ze = Ts[:3, 2], Te[:3, 2]
    d = Te[:3, 3] - Ts[:3, 3]
    dist = float(np.linalg.norm(d))
    axis = d / dist if dist > 1e-12 * p.length else zs
    if np.linalg.norm(_cross(zs, axis)) > 1e-9 or np.linalg.norm(_cross(ze, axis)) > 1e-9:
        return None
    f = np.asarray(p.weight, float)
    if np.linalg.norm(_cross(f, axis)) > 1e-12 * max(np.linalg.norm(f), 1e-300):
        return None
    return Ts[:3, 3], axis


def _chord_family_axis(p: RodProblem):
    """(point, axis) when both ends are pinned and the weight is zero or along the chord."""
    if p.start != "pinned" or p.end != "pinned":
        return None
    Ts, Te = np.asarray(p.T_start, float), np.asarray(p.T_end, float)
    d = Te[:3, 3] - Ts[:3, 3]
    dist = float(np.linalg.norm(d))
    if dist <= 1e-12 * p.length:
        return None
    axis = d / dist
    f = np.asarray(p.weight, float)
    if np.linalg.norm(_cross(f, axis)) > 1e-12 * max(np.linalg.norm(f), 1e-300):
        return None
    return Ts[:3, 3], axis


def _overlength_solution(p: RodProblem, n: int, msg: str) -> RodSolution:
    """No equilibrium: the straight line of length L from the start towards the end point, zero loads."""
    L = float(p.length)
    Ts, Te = np.asarray(p.T_start, float), np.asarray(p.T_end, float)
    d = Te[:3, 3] - Ts[:3, 3]
    dist = float(np.linalg.norm(d))
    t = d / dist if dist > 0 else Ts[:3, 2]
    s = np.linspace(0.0, L, n + 1)
    nodes = Ts[:3, 3] + s[:, None] * t
    xs = Ts[:3, 0] - (Ts[:3, 0] @ t) * t
    if np.linalg.norm(xs) < 1e-6:
        xs = _cross(Ts[:3, 1], t)
    xs /= np.linalg.norm(xs)
    R = np.stack([xs, _cross(t, xs), t], axis=1)
    frames = np.tile(np.eye(4), (n + 1, 1, 1))
    frames[:, :3, :3] = R
    frames[:, :3, 3] = nodes
    q = np.tile(matrix_to_quaternion(R), (n, 1))
    z = np.zeros(3)
    return RodSolution(s, nodes, frames, q, z.copy(), z.copy(), z.copy(), z.copy(), np.zeros(n + 1),
                       residual=max(dist / L - 1.0, 0.0), iterations=0, converged=False,
                       status="overlength", error_estimate=None, message=msg, _state=None)


def _interp_pose(Ta, Tb, t):
    """Pose between Ta and Tb: position lerp, rotation geodesic (t in [0, 1])."""
    qa, qb = _pose_quat(Ta), _pose_quat(Tb)
    if qa @ qb < 0:
        qb = -qb
    T = np.eye(4)
    T[:3, :3] = _qmat(_slerp_mid(qa, qb, t))
    T[:3, 3] = (1.0 - t) * np.asarray(Ta, float)[:3, 3] + t * np.asarray(Tb, float)[:3, 3]
    return T


def _with_poses(p: RodProblem, Ts, Te) -> RodProblem:
    return RodProblem(p.length, tuple(p.stiffness), p.weight, Ts, Te, p.start, p.end,
                      p.start_force, p.end_force)
