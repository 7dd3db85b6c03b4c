"""Solving at one mesh size: continuation in the end poses from a warm start
(secant/quadratic prediction, step halving), cold starts with escape from
saddles, and the solution record.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack

from .banded import _to_band
from .guess import _initial_guess
from .model import _Model
from .newton import _negative_curvature, _newton
from .problem import RodProblem, RodSolution, _interp_pose, _with_poses
from .quaternions import _qexp, _qlog, _qmul


def _build_solution(m: _Model, q, mu, x, res, iters, conv, need_stable=True) -> RodSolution:
    """The solution record; ``need_stable=False``: ``stable`` only from the Newton iterations'
    inertia check (None when it was skipped), no extra test."""
    n, L = m.n, m.L
    cq, r = getattr(m, "cur", (None, None))
    if cq is not q:
        q = m.align(q)
        r = m.residual(q, mu, x)
    R, r_raw = r[4], r[6]
    # the clamp supplies the torque R_i r_theta_i (world, about the end point); the cable exerts the opposite
    m_s = -(R[0] @ r_raw[0]) if m.clamp_s else np.zeros(3)
    m_e = -(R[-1] @ r_raw[-1]) if m.clamp_e else np.zeros(3)
    frames = np.empty((n + 1, 4, 4))
    frames[:, 3] = (0.0, 0.0, 0.0, 1.0)
    frames[:, :3, :3] = R
    frames[:, :3, 3] = x
    u = _qlog(r[3][4]) / m.hc[:, None]          # cell Darboux vectors (body), from conj(q_i) q_{i+1}
    un = np.empty((n + 1, 3))
    un[1:-1] = 0.5 * (u[:-1] + u[1:])
    un[0] = 1.5 * u[0] - 0.5 * u[1]
    un[-1] = 1.5 * u[-1] - 0.5 * u[-2]
    kap = np.hypot(un[:, 0], un[:, 1])
    fs = mu[0] + 0.5 * m.hc[0] * m.f
    fe = -(mu[-1] - 0.5 * m.hc[-1] * m.f)
    stable = bool(conv and getattr(m, "inertia_ok", False))
    if conv and not stable and not need_stable:
        stable = None
    elif conv and not stable:
        _, _, P, PU = m.matrices(r[3], R, r[5], rho_factor=100.0)
        stable = bool(lapack.dpbtrf(_to_band(P, PU, 0, 11, 0), lower=0, overwrite_ab=1)[1] == 0)
    state = {"n": n, "q": q.copy(), "mu": mu.copy(), "x": x.copy(), "Ts": m.Ts.copy(), "Te": m.Te.copy(),
             "kinds": (m.start, m.end), "L": L, "grading": m.grading}
    qseg = q[:-1] + q[1:]      # normalised sum of aligned unit quaternions = geodesic midpoint
    qseg /= np.sqrt(np.einsum("ij,ij->i", qseg, qseg))[:, None]
    return RodSolution(m.s.copy(), x.copy(), frames, qseg,
                       fs, m_s, fe, m_e, kap,
                       residual=float(res), iterations=int(iters), converged=bool(conv),
                       status="ok" if conv else "not_converged", _state=state, stable=stable)


def _solve_n(p: RodProblem, n: int, tol: float, max_iter: int, warm, inertia=True, escape=True,
             grading=0.0, check_first=True):
    """Solve the (start-supported) problem at n segments; warm = state dict or None.

    ``check_first=False`` (warm starts only): the Newton solve from the key-point prediction, or
    from the warm state in one stage, skips the inertia check and ``stable`` is left None unless
    it was checked (the 2n solve of an extrapolated pair, whose n partner on the same branch is
    checked)."""
    m = _Model(p, n, grading)
    total_it = 0
    if warm is not None and warm.get("n") == n and warm.get("kinds") == (p.start, p.end) \
            and abs(warm.get("L", -1) - m.L) <= 1e-12 * m.L \
            and abs(warm.get("grading", 0.0) - m.grading) <= 1e-12:
        # continuation in the end poses from the previous key point, halving the step on failure
        q, mu, x = warm["q"], warm["mu"], warm["x"]
        Ts0, Te0 = warm["Ts"], warm["Te"]
        t_done, step = 0.0, 1.0
        pred = _secant_prediction(warm, p, m)
        if pred is not None:
            # the key points move on a smooth path: extrapolate from the last two solutions
            q1, mu1, x1, res, it, ok = _newton(m, *pred, tol, max_iter, inertia, check_first)
            total_it += it
            if ok:
                q, mu, x, t_done = q1, mu1, x1, 1.0
        while t_done < 1.0:
            t_try = min(1.0, t_done + step)
            Ts = _interp_pose(Ts0, p.T_start, t_try) if t_try < 1.0 else np.asarray(p.T_start, float)
            Te = _interp_pose(Te0, p.T_end, t_try) if t_try < 1.0 else np.asarray(p.T_end, float)
            mt = _Model(_with_poses(p, Ts, Te), n, grading) if t_try < 1.0 else m
            x0, q0 = x.copy(), q.copy()
            x0[0] = mt.ps
            if mt.fixed_e:
                x0[-1] = mt.pe
            if mt.clamp_s:
                q0[0] = mt.qs
            if mt.clamp_e:
                q0[-1] = mt.qe
            # a single full stage (no predictor) may skip the check like the predictor's solve
            chk = check_first if (pred is None and t_done == 0.0 and t_try == 1.0) else True
            q1, mu1, x1, res, it, ok = _newton(mt, q0, mu, x0, tol if t_try == 1.0 else max(tol, 1e-8),
                                             max_iter, inertia, chk)
            total_it += it
            if ok:
                q, mu, x, t_done = q1, mu1, x1, t_try
                step = min(1.0, 2.0 * step)
            else:
                step *= 0.5
                if step < 1.0 / 32:
                    break
        if t_done >= 1.0:
            sol = _build_solution(m, q, mu, x, res, total_it, True, check_first)
            sol._state["prev"] = {k: warm[k] for k in ("q", "mu", "x", "Ts", "Te", "pose_vec") if k in warm}
            if isinstance(warm.get("prev"), dict):
                sol._state["prev2"] = warm["prev"]       # three key points: quadratic predictor
            return sol, m
    q, mu, x = _initial_guess(m)
    q, mu, x, res, it, ok = _newton(m, q, mu, x, tol, max_iter, inertia)
    total_it += it
    sol = _build_solution(m, q, mu, x, res, total_it, ok)
    if inertia and escape and ok and not sol.stable:
        sol = _escape_saddle(m, sol, q, mu, x, tol, max_iter)
    return sol, m


def _pose_vec(Ts, Te, L):
    """The two end poses as one 24-vector (rotation columns scaled by L): differences of these are
    cheap pose steps, linear for small steps, enough to compare consecutive key-point steps."""
    v = np.empty((2, 3, 4))
    v[0] = np.asarray(Ts, float)[:3]
    v[1] = np.asarray(Te, float)[:3]
    v[:, :, :3] *= L
    return v.ravel()


def _state_pose_vec(st, L):
    """_pose_vec of a state's end poses, kept in the state (each is used at three key points).

    The cache is valid only for the very pose objects it was made from: a state whose poses were
    replaced (e.g. mirrored by the cable workflow) gets a fresh vector."""
    v = st.get("pose_vec")
    if not (isinstance(v, tuple) and len(v) == 4 and v[0] == L and v[1] is st["Ts"] and v[2] is st["Te"]):
        v = (L, st["Ts"], st["Te"], _pose_vec(st["Ts"], st["Te"], L))
        st["pose_vec"] = v
    return v[3]


def _secant_prediction(warm, p: RodProblem, m: _Model):
    """(q, mu, x) extrapolated from the last key points, when the end poses move on a smooth path.

    The new key point's place on the path is measured in pose space: rho = the new pose step in
    units of the last one (steps parallel within 25 %). With three previous solutions on such a
    path the extrapolation is quadratic (Lagrange, the older step measured the same way): its start
    is ~50x closer than the linear one, so one Newton step reaches ``tol`` 1e-10.
    """
    prev = warm.get("prev")
    if not isinstance(prev, dict) or prev["q"].shape != warm["q"].shape:
        return None
    v_warm = _state_pose_vec(warm, m.L)
    v_prev = _state_pose_vec(prev, m.L)
    d_old = v_warm - v_prev
    d_new = _pose_vec(p.T_start, p.T_end, m.L) - v_warm
    nn = float(d_old @ d_old)
    if not nn > 0.0:
        return None
    rho = float(d_new @ d_old) / nn
    e = d_new - rho * d_old
    if not 0.0 < rho <= 2.0 or float(e @ e) > 0.0625 * float(d_new @ d_new):
        return None
    # Lagrange weights at rho for the path parameters 0 (warm), -1 (prev), -1 - sigma (prev2)
    w_p, w_p2 = -rho, 0.0
    prev2 = warm.get("prev2")
    if isinstance(prev2, dict) and prev2["q"].shape == warm["q"].shape:
        d_older = v_prev - _state_pose_vec(prev2, m.L)
        sigma = float(d_older @ d_old) / nn
        e = d_older - sigma * d_old
        if 0.25 <= sigma <= 4.0 and float(e @ e) <= 0.0625 * float(d_older @ d_older):
            w2 = rho * (rho + 1.0) / (sigma * (1.0 + sigma))
            if w2 <= 4.0:      # modest weights only (equal steps: 3, -3, 1): no amplified noise
                w_p, w_p2 = -rho * (rho + 1.0 + sigma) / sigma, w2
    w_w = 1.0 - w_p - w_p2
    qw = warm["q"]
    # quaternions extrapolated componentwise (signs aligned node by node) and normalised: as
    # accurate as extrapolating rotation vectors (the error off the sphere is of the same order)
    # and a few array operations instead of log/exp
    qp = prev["q"]
    q = w_w * qw + (w_p * np.sign(np.einsum("ij,ij->i", qp, qw)))[:, None] * qp
    x = w_w * warm["x"] + w_p * prev["x"]
    mu = w_w * warm["mu"] + w_p * prev["mu"]
    if w_p2 != 0.0:
        qp2 = prev2["q"]
        q += (w_p2 * np.sign(np.einsum("ij,ij->i", qp2, qw)))[:, None] * qp2
        x += w_p2 * prev2["x"]
        mu += w_p2 * prev2["mu"]
    q /= np.sqrt(np.einsum("ij,ij->i", q, q))[:, None]
    x[0] = m.ps
    if m.fixed_e:
        x[-1] = m.pe
    if m.clamp_s:
        q[0] = m.qs
    if m.clamp_e:
        q[-1] = m.qe
    return q, mu, x


def _escape_saddle(m: _Model, sol, q, mu, x, tol, max_iter):
    """From an unstable equilibrium (symmetric starts stay on symmetric saddles), push along the
    direction of negative curvature and solve again; keep the first stable equilibrium found."""
    for _ in range(3):
        r = m.residual(q, mu, x)
        d = _negative_curvature(m, r[3], r[4], r[5])
        if d is None:
            return sol
        dth, dx = d
        for sign in (1.0, -1.0):
            qt = m.align(_qmul(q, _qexp(sign * 0.3 * dth)))
            xt = x.copy()
            xt[1:] += sign * 0.3 * dx
            q1, mu1, x1, res, it, ok = _newton(m, qt, mu, xt, tol, max_iter, True)
            if ok:
                cand = _build_solution(m, q1, mu1, x1, res, sol.iterations + it, ok)
                if cand.stable:
                    return cand
                q, mu, x, sol = q1, mu1, x1, cand
                break
    return sol
