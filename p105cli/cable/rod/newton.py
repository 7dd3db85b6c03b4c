"""Newton's method on the KKT system: step caps, inertia checks with the
Levenberg-Marquardt shift, negative-curvature steps, merit backtracking.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import eig_banded, lapack

from .banded import _to_band
from .model import _Model
from .quaternions import _qexp, _qmul


MAX_TURN = 0.6          # rad: largest rotation of one segment in one Newton step


def _newton(m: _Model, q, mu, x, tol, max_iter, inertia=True, check=True):
    """Globalised Newton. Returns (q, mu, x, residual, iterations, converged).

    Each iteration: KKT residual and Hessian; inertia check (banded Cholesky of
    H + rho C^T C, shifting the rotation block by delta until positive
    definite -- skipped once Newton is in its quadratic phase with no shift);
    banded LU solve; the step (capped at MAX_TURN rad per segment) is accepted
    if the scaled residual drops, else by backtracking on the exact-penalty
    merit; when that fails too the shift grows (trust region shrinks).
    ``inertia=False``: plain damped Newton (finds unstable equilibria too;
    backtracking on the residual only). ``check=False``: no inertia check until a step fails
    (a predicted start next to a known minimum; the caller checks stability elsewhere).
    """
    n = m.n
    q = m.align(q)
    delta = 0.0
    dscale = m.K.max() / m.hmin
    cur = m.residual(q, mu, x)
    res = m.scaled(*cur[:3])
    it = 0
    fx, th_p, th_k = m.fx, m.th_p, m.th_k
    m.inertia_ok = False
    escapes = 0
    while True:
        m.cur = (q, cur)
        if not np.isfinite(res):
            return q, mu, x, np.inf, it, False
        if res <= tol:
            return q, mu, x, res, it, True
        if it >= max_iter:
            return q, mu, x, res, it, False
        it += 1
        r_th, r_mu, r_x, bend, R, b, _ = cur
        need_p = inertia and (check or delta > 0.0)
        D, U, P, PU = m.matrices(bend, R, b, need_p=need_p, need_kkt=False)
        if need_p:
            delta = delta / 8.0 if delta > 1e-6 * dscale else 0.0
            pb0 = _to_band(P, PU, 0, 11, 0)
            for _ in range(60):
                pb = pb0.copy()
                if delta > 0.0:
                    pb[11] += delta * th_p
                _, info = lapack.dpbtrf(pb, lower=0, overwrite_ab=1)
                if info == 0:
                    break
                delta = max(4.0 * delta, 1e-4 * dscale)
            # Finsler: H + rho C^T C > 0 without shift proves a strict constrained minimum here
            m.inertia_ok = delta == 0.0
            if delta > 0.0 and res < 1e-3 and escapes < 4:
                # nearly stationary but not a minimum (or rho too small): check with a larger rho,
                # then step along the direction of negative curvature (a plain shift crawls there)
                d = _negative_curvature(m, bend, R, b)
                if d is None:
                    delta = 0.0
                    m.inertia_ok = True
                else:
                    escapes += 1
                    dth_n, dx_n = d
                    gdir = float(np.sum(m.grad_nodes(bend[1], bend[2]) * dth_n))
                    sgn = -1.0 if gdir > 0 else 1.0
                    q = m.align(_qmul(q, _qexp(sgn * 0.2 * dth_n)))
                    x = x.copy()
                    x[1:] += sgn * 0.2 * dx_n
                    cur = m.residual(q, mu, x)
                    res = m.scaled(*cur[:3])
                    delta, check = 0.0, True
                    continue
        step = m.solve_reduced(r_th, r_mu, r_x, delta)
        if step is None:
            # full KKT (rotations, forces, positions interleaved; band 11) by banded LU
            rhs = np.zeros((n + 1, 9))
            rhs[:, 0:3] = -r_th
            rhs[:-1, 3:6] = -r_mu
            rhs[:-1, 6:9] = -r_x
            rhs = rhs.reshape(-1)
            D, U = m._kkt_blocks(*m.blocks)
            ab = _to_band(D, U, 11, 11, 11)
            if delta > 0.0:
                ab[22] += delta * th_k
            _, _, sol, info = lapack.dgbsv(11, 11, ab, rhs, overwrite_ab=1, overwrite_b=1)
            if info != 0 or not np.all(np.isfinite(sol)):
                delta = max(4.0 * delta, 1e-4 * dscale)
                check = True
                continue
            sol = sol.reshape(n + 1, 9)
            step = sol[:, 0:3], sol[:-1, 3:6], sol[:-1, 6:9]
        dth, dmu, dx = step
        turn = float(np.sqrt(np.einsum("ij,ij->i", dth, dth).max()))
        alpha = min(1.0, MAX_TURN / turn) if turn > 0 else 1.0

        def trial(al):
            qt = _qmul(q, _qexp(al * dth))
            qt /= np.sqrt(np.einsum("ij,ij->i", qt, qt))[:, None]
            xt = x.copy()
            xt[1:] += al * dx
            return m.align(qt), mu + al * dmu, xt

        qt, mut, xt = trial(alpha)
        new = m.residual(qt, mut, xt)
        res_t = m.scaled(*new[:3])
        accepted = np.isfinite(res_t) and (res_t < 0.95 * res or res_t <= tol)
        if not accepted and not inertia:
            for _ in range(12):
                alpha *= 0.5
                qt, mut, xt = trial(alpha)
                new = m.residual(qt, mut, xt)
                res_t = m.scaled(*new[:3])
                if np.isfinite(res_t) and res_t < (1.0 - 0.5 * alpha) * res:
                    accepted = True
                    break
            if not accepted:
                return q, mu, x, res, it, False
        if not accepted:
            nu = 2.0 * float(np.abs(mu + dmu).max()) * np.sqrt(3.0) + m.F0 * 1e-3
            phi0 = m.merit(q, x, nu)
            dphi = (float(np.sum(m.grad_nodes(bend[1], bend[2]) * dth) + np.sum(fx * dx))
                    - nu * float(np.sqrt(np.einsum("ij,ij->i", r_mu, r_mu)).sum()))
            for _ in range(12):
                phi = m.merit(qt, xt, nu)
                if np.isfinite(phi) and phi <= phi0 + 1e-4 * alpha * min(dphi, 0.0) + 1e-13 * abs(phi0):
                    accepted = True
                    break
                alpha *= 0.5
                qt, mut, xt = trial(alpha)
                if alpha < 0.05:
                    # short steps: also accept a plain residual decrease (far from a solution the
                    # multiplier estimate behind the merit can be useless)
                    new = m.residual(qt, mut, xt)
                    res_t = m.scaled(*new[:3])
                    if np.isfinite(res_t) and res_t < (1.0 - 0.5 * alpha) * res:
                        accepted = True
                        break
            if accepted:
                new = m.residual(qt, mut, xt)
                res_t = m.scaled(*new[:3])
        if not accepted:
            delta = max(4.0 * delta, 1e-3 * dscale)
            check = True
            continue
        check = not (res_t < 1e-3 and delta == 0.0 and alpha == 1.0)
        q, mu, x, cur, res = qt, mut, xt, new, res_t


def _negative_curvature(m: _Model, bend, R, b):
    """Direction (dth, dx) of most negative curvature of H + rho C^T C (rho x100), or None if PD."""
    n = m.n
    _, _, P, PU = m.matrices(bend, R, b, rho_factor=100.0, need_kkt=False)
    pb = _to_band(P, PU, 0, 11, 0)
    if lapack.dpbtrf(pb.copy(), lower=0, overwrite_ab=1)[1] == 0:
        return None
    try:
        _, vec = eig_banded(pb, lower=False, select="i", select_range=(0, 0))
    except (np.linalg.LinAlgError, ValueError):
        return None
    v = vec[:, 0].reshape(n + 1, 6)
    dth = v[:, 3:6] * m.th_free[:, None]
    big = float(np.abs(dth).max())
    if not big > 0.0:
        return None
    dx = v[1:, 0:3].copy()
    if m.fixed_e:
        dx[-1] = 0.0
    return dth / big, dx / big
