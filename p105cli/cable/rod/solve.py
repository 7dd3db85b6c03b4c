"""``solve_rod``: the mesh pair (n, 2n), Richardson extrapolation, warm starts
between key points, and ``state_from_frames``.
"""

from __future__ import annotations

import numpy as np

from p105cli.kinematics.spatial import matrix_to_quaternion

from .continuation import _solve_n
from .model import _Model, auto_grading
from .problem import (
    RodProblem, RodSolution, _FLIP, _chord_family_axis, _coaxial_family_axis, _overlength_solution,
    _reversed, _unreverse, _validate,
)
from .quaternions import _qconj, _qmat, _qmul, _slerp_mid

#: A held cable whose slack (L - |R|) / L is below this and whose solve fails is reported as
#: nearly taut: the tension ~ (L - |R|)^-1/2 is then what the Newton iteration cannot resolve.
NEAR_TAUT = 1e-6


def state_from_frames(problem: RodProblem, frames, forces=None, grading=0.0):
    """A warm-start state from node frames ``(n+1, 4, 4)`` (e.g. another model's answer or a guess).

    ``forces`` (n, 3): optional internal forces at the segment midpoints
    (what the part after exerts on the part before); zero if not given.
    Pass the result as ``warm=`` to :func:`solve_rod` with ``segments=n``.
    Free-start problems are stored reversed, as :func:`solve_rod` solves them.
    """
    F = np.asarray(frames, dtype=float)
    n = F.shape[0] - 1
    p = problem
    if p.start == "free":
        p = _reversed(p)
        F = F[::-1] @ _FLIP
        if forces is not None:
            forces = -np.asarray(forces, float)[::-1]
    m = _Model(p, n, grading)
    q = m.align(matrix_to_quaternion(F[:, :3, :3]))
    mu = np.zeros((n, 3)) if forces is None else np.asarray(forces, float).reshape(n, 3).copy()
    return {"n": n, "q": q, "mu": mu, "x": F[:, :3, 3].copy(), "Ts": m.Ts.copy(), "Te": m.Te.copy(),
            "kinds": (p.start, p.end), "L": m.L, "grading": m.grading}


def _refine_state(st):
    """Warm state at 2n segments from one at n: nodes interpolated, frames by geodesic midpoints."""
    n = st["n"]
    x = np.empty((2 * n + 1, 3))
    x[::2] = st["x"]
    x[1::2] = 0.5 * (st["x"][:-1] + st["x"][1:])
    q = np.empty((2 * n + 1, 4))
    q[::2] = st["q"]
    q[1::2] = _slerp_mid(st["q"][:-1], st["q"][1:])
    mu = np.repeat(st["mu"], 2, axis=0)
    return {**st, "n": 2 * n, "q": q, "mu": mu, "x": x}


def _fine_start(coarse, coarse_prev, fine_prev):
    """Warm state for the 2n solve: refined n solution, plus the previous key point's 2n correction."""
    st = _refine_state(coarse)
    ok = (isinstance(coarse_prev, dict) and isinstance(fine_prev, dict)
          and fine_prev.get("n") == st["n"] and coarse_prev.get("n") == coarse["n"]
          and fine_prev.get("grading") == st.get("grading") and fine_prev.get("kinds") == st["kinds"])
    if not ok:
        return st
    rp = _refine_state(coarse_prev)
    qp = rp["q"] * np.sign(np.einsum("ij,ij->i", rp["q"], fine_prev["q"]))[:, None]
    corr = _qmul(_qconj(qp), fine_prev["q"])                 # body-frame correction
    q = _qmul(st["q"], corr)
    q /= np.sqrt(np.einsum("ij,ij->i", q, q))[:, None]
    return {**st, "q": q, "x": st["x"] + (fine_prev["x"] - rp["x"]),
            "mu": st["mu"] + (fine_prev["mu"] - rp["mu"])}


def _same_path(wc, wf, n, p: RodProblem, grading) -> bool:
    """Whether the previous key point's n and 2n states (``wc``, ``wf``) fit this problem (same
    meshes, ends, grading, length) and both have a history to extrapolate from."""
    if not (isinstance(wc, dict) and isinstance(wf, dict) and isinstance(wf.get("prev"), dict)
            and isinstance(wc.get("prev"), dict)):
        return False
    kinds, L = (p.start, p.end), float(p.length)
    return (wc.get("n") == n and wf.get("n") == 2 * n and wf["prev"]["q"].shape == wf["q"].shape
            and wc["prev"]["q"].shape == wc["q"].shape
            and wf.get("kinds") == kinds == wc.get("kinds")
            and wf.get("grading") == grading == wc.get("grading")
            and abs(wf.get("L", -1.0) - L) <= 1e-12 * L and abs(wc.get("L", -1.0) - L) <= 1e-12 * L)


def _richardson(c: RodSolution, f: RodSolution):
    """Combine the n and 2n solutions (second-order errors cancel) on the n grid."""
    def ex(a, b):
        return b + (b - a) / 3.0
    nodes = ex(c.nodes, f.nodes[::2])
    # node quaternions: the solves' own (frames = their rotation matrices), else from the frames
    qc = c._state["q"] if c._state is not None else _pose_quat_batch(c.frames)
    qf = f._state["q"][::2] if f._state is not None else _pose_quat_batch(f.frames[::2])
    # extrapolated rotations qf + (qf - qc)/3 componentwise (signs aligned), normalised: differs from
    # the geodesic extrapolation by O(d^3), d the n-2n rotation difference (heavy 3D cable: 2e-13
    # at n = 128, 1e-9 at n = 32 where the extrapolated frames' own error is 2e-5)
    qf = np.where((np.einsum("ij,ij->i", qc, qf) < 0.0)[:, None], -qf, qf)
    qn = ex(qc, qf)
    qn /= np.sqrt(np.einsum("ij,ij->i", qn, qn))[:, None]
    frames = np.empty((len(nodes), 4, 4))
    frames[:, 3] = (0.0, 0.0, 0.0, 1.0)
    frames[:, :3, :3] = _qmat(qn)
    frames[:, :3, 3] = nodes
    # geodesic midpoints: normalised sums of sign-aligned neighbours (as _build_solution)
    qa, qb = qn[:-1], qn[1:]
    qseg = qa + np.where((np.einsum("ij,ij->i", qa, qb) < 0.0)[:, None], -qb, qb)
    qseg /= np.sqrt(np.einsum("ij,ij->i", qseg, qseg))[:, None]
    err = float(np.abs(f.nodes[::2] - c.nodes).max()) / 3.0
    conv = c.converged and f.converged
    return RodSolution(c.s.copy(), nodes, frames, qseg,
                       ex(c.force_start, f.force_start), ex(c.moment_start, f.moment_start),
                       ex(c.force_end, f.force_end), ex(c.moment_end, f.moment_end),
                       ex(c.curvature, f.curvature[::2]), residual=max(c.residual, f.residual),
                       iterations=c.iterations + f.iterations, converged=conv,
                       status="ok" if conv else "not_converged", error_estimate=err, stable=f.stable,
                       _state={"richardson": (c._state, f._state)})


def _pose_quat_batch(frames):
    return matrix_to_quaternion(frames[:, :3, :3])


def solve_rod(problem: RodProblem, *, segments: int = 50, tol: float = 1e-10, warm=None,
              richardson: bool = False, max_iter: int = 50, inertia: bool = True,
              grading: float | None = None) -> RodSolution:
    """Static equilibrium of a cable (discrete Kirchhoff rod); see the module docstring.

    ``warm``: ``previous.state()`` (continuation in the end poses from the
    previous key point, with step halving). ``richardson``: solve with n and
    2n segments and extrapolate (nodes, frames, end loads, curvature).
    ``inertia=False`` turns the minimum-seeking inertia correction off (plain
    damped Newton): use it with a warm start to follow unstable equilibria.
    ``stable`` in the result says whether the equilibrium found is a strict
    local minimum of the potential (constrained Hessian positive definite).
    ``grading``: cells shrink to (1 - grading) h at both ends (see
    :func:`_graded_nodes`); ``None`` = :func:`auto_grading` (only clamped
    cables whose boundary layer is thinner than a cell are graded).
    Never raises for a well-formed problem: over-length, non-convergence and
    continuous families are reported in ``status``. Raises ``ValueError`` for
    malformed input (non-finite numbers, non-rotations, both ends free).
    """
    _validate(problem)
    n = int(segments)
    if n < 2:
        raise ValueError("rod: segments must be >= 2")
    L = float(problem.length)
    dist = None
    if problem.start != "free" and problem.end != "free":
        dist = float(np.linalg.norm(np.asarray(problem.T_end, float)[:3, 3]
                                    - np.asarray(problem.T_start, float)[:3, 3]))
        # over-length is |R| >= L exactly (docs/cable.md): a cable with any slack has an equilibrium;
        # one the solver cannot reach is not_converged, with the slack as the reason
        if dist >= L:
            return _overlength_solution(problem, n, f"end points {dist:.9g} m apart, cable {L:.9g} m")
    rev = problem.start == "free"
    p = _reversed(problem) if rev else problem
    fam = _coaxial_family_axis(p)
    chord = _chord_family_axis(p)
    fam_msg = ("isotropic rod between coaxial clamps: bent equilibria form a continuous "
               "family (rotation about the clamp axis); one member returned")
    if fam is None and chord is not None:
        fam = chord
        fam_msg = ("pinned ends with the weight along the chord (or none): bent equilibria form a "
                   "continuous family (rotation about the chord); one member returned")
    esc = fam is None      # on a continuous family every member is marginal: no saddle escape
    a = auto_grading(p, n) if grading is None else float(grading)
    if not 0.0 <= a < 1.0:
        raise ValueError("rod: grading must be in [0, 1)")
    if richardson:
        wc, wf = warm.get("richardson", (warm, None)) if isinstance(warm, dict) else (None, None)
        c = f = None
        extra = 0
        if _same_path(wc, wf, n, p, a):
            # on a key-point path both solves follow their own histories (extrapolated: one Newton
            # step each; the inertia check only on the n solve, half the size, whose stability is
            # then reported). They must stay on one branch: the 2n - n difference (the
            # discretisation error) changes slowly along a path, a jump means another branch: then
            # solve again as below
            c, _ = _solve_n(p, n, tol, max_iter, wc, inertia, esc, a)
            f, _ = _solve_n(p, 2 * n, tol, max_iter, wf, inertia, esc, a, check_first=False)
            if f.stable is None:
                f.stable = c.stable
            d_prev = float(np.abs(wf["x"][::2] - wc["x"]).max())
            d_new = float(np.abs(f.nodes[::2] - c.nodes).max())
            if not (c.converged and f.converged and d_new <= 4.0 * d_prev + 1e-9 * L):
                extra = c.iterations + f.iterations
                c = f = None
        if c is None:
            c, _ = _solve_n(p, n, tol, max_iter, wc, inertia, esc, a)
            # the 2n solve starts from the refined n solution (same branch), corrected by the previous
            # key point's difference between its 2n and refined n solutions (the discretisation
            # difference changes slowly along a path)
            # the inertia check runs on the n solve (half the size); the 2n solve from it stays on
            # its branch (a failure is solved again with the check)
            fs = _fine_start(c._state, wc, wf)
            f, _ = _solve_n(p, 2 * n, tol, max_iter, fs, inertia, esc, a, check_first=False)
            if not f.converged:
                extra += f.iterations
                f, _ = _solve_n(p, 2 * n, tol, max_iter, fs, inertia, esc, a)
            if f.stable is None:
                f.stable = c.stable
            f.iterations += extra
            # the 2n history is the previous key points' 2n solutions (not this start guess)
            if f._state is not None:
                f._state.pop("prev", None)
                f._state.pop("prev2", None)
                if isinstance(wf, dict) and wf.get("n") == 2 * n and wf.get("kinds") == c._state["kinds"]:
                    f._state["prev"] = {k: wf[k] for k in ("q", "mu", "x", "Ts", "Te", "pose_vec") if k in wf}
                    if isinstance(wf.get("prev"), dict):
                        f._state["prev2"] = wf["prev"]
        sol = _richardson(c, f)
    else:
        sol, _ = _solve_n(p, n, tol, max_iter, warm if isinstance(warm, dict) else None, inertia, esc, a)
    if sol.converged and (not np.all(np.isfinite(sol.nodes)) or not np.isfinite(sol.residual)):
        sol.converged, sol.status = False, "not_converged"
    if fam is not None and sol.converged:
        o, a = fam
        off = sol.nodes - o
        off = off - (off @ a)[:, None] * a
        if float(np.linalg.norm(off, axis=1).max()) > 1e-9 * L:
            sol.status = "non_unique"
            sol.message = fam_msg
    if not sol.converged and sol.status == "not_converged":
        _sanitize(sol)
        if dist is not None and L - dist < NEAR_TAUT * L:
            sol.message = (f"nearly taut: the end points are {L - dist:.3g} m closer than the cable's length "
                           f"{L:.6g} m (slack {(L - dist) / L:.3g}); the tension grows like (L - |R|)^-1/2")
    return _unreverse(sol, L) if rev else sol


def _sanitize(sol: RodSolution) -> None:
    """No NaN ever leaves: replace non-finite entries of a failed solve by zeros."""
    for name in ("nodes", "frames", "quaternions", "force_start", "moment_start", "force_end",
                 "moment_end", "curvature"):
        a = getattr(sol, name)
        if not np.all(np.isfinite(a)):
            setattr(sol, name, np.nan_to_num(a, nan=0.0, posinf=0.0, neginf=0.0))
    if not np.isfinite(sol.residual):
        sol.residual = 1e300
