"""The cable model of patent CN101727523A, as written, as a selectable baseline.

The patent models the cable as a Kirchhoff rod whose sections are oriented
by Euler parameters ``q = (q1, q2, q3, q4)`` (``q1`` the scalar part; the
same quaternion convention as ``placements.matrix_to_quaternion``, body to
world) and their arc-length derivatives ``Q = q'``. Curvature and twist in
the principal-axis frame are (patent eqs. 32-34)::

    w1 = 2(-q2 Q1 + q1 Q2 + q4 Q3 - q3 Q4)
    w2 = 2(-q3 Q1 - q4 Q2 + q1 Q3 + q2 Q4)        i.e. w = 2 G(q) Q
    w3 = 2(-q4 Q1 + q3 Q2 - q2 Q3 + q1 Q4)

and the moment balance (eqs. 20-22 with M = K w, K = diag(A, B, C))::

    K w' + w x K w + e3 x R(q)^T F = 0

The distributed weight is *not* in the equations: the internal force ``F``
is one constant vector (eqs. 35-37), the patent's ``F0`` being half the
cable weight along the vertical. Derivatives are backward differences over
``n`` equal segments, so ``q_k - q_{k-1} = h Q_k`` and
``w'_k = 2 G(q_k)(Q_k - Q_{k-1}) / h``, and node positions are
``r_k = r_{k-1} + h d3(q_k)`` (eqs. 57-59). Each segment gives 8 equations
(4 differences, 3 moments, ``|q_k| = 1``): 8n, plus the end conditions.

Two ways to solve it:

* ``iteration="newton"`` (default): a square Newton system. The patent's
  8n+5 equations with ``F`` fixed over-determine a cable held at both ends
  (3 free initial curvatures against 6 end conditions); the three missing
  unknowns are the components of ``F`` itself, i.e. the end reaction. So
  ``F = n_mean`` is solved for, and the patent's ``F0`` (half the weight,
  vertical) becomes the offset between it and the end forces:
  ``n(0) = F + W/2``, ``n(L) = F - W/2`` (``W`` the weight vector). For a
  free end the force is known (``F = P_end + W/2``: a heavy cantilever is
  modelled as carrying half its weight at the tip, the patent's constant
  force). Unknowns ``q_k, Q_k`` (k = 0..n) and ``F``: 8n+11 for a clamped
  or pinned end, 8n+8 for a free end (``F`` known); same number of
  equations; sparse LU, backtracking line search.
* ``iteration="overwrite"``: the patent's own iteration, for comparison.
  ``F`` is fixed (``force=`` or ``F = P_end + W/2``); 5 of the 8 known end
  Euler parameters (the 4 at the fixed end and the scalar part at the
  moving end) are iterated as unknowns with the patent's supplementary
  equations (end position, ``|q_0| = 1``, ``q_0 . Q_0 = 0``), and after
  every Newton step they are overwritten by their known values. The
  iteration converges linearly at best, to a point that does not satisfy
  all equations when the fixed ``F`` is not the true reaction; the history
  of step norms is returned so this can be shown.

The model is first order in ``h`` and its constant force cannot represent
distributed weight (no catenary limit; a heavy cantilever is 2-31 % off in
deflection). Use ``p105cli.cable.rod`` for real answers; this module is the
baseline the benchmark compares against.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from p105cli.cable.rod import RodSolution
from p105cli.kinematics.spatial import matrix_to_quaternion, quaternion_to_matrix

__all__ = ["solve_patent", "patent_force"]


# --- quaternion algebra (q = (w, x, y, z), R(q) body -> world) --------------

def _quad_tensor() -> np.ndarray:
    """T[i, j] (4x4 symmetric) with R(q)_ij = q^T T[i, j] q for any (unnormalised) q."""
    def r(q):
        w, x, y, z = q
        return np.array([
            [w*w + x*x - y*y - z*z, 2*(x*y - w*z), 2*(x*z + w*y)],
            [2*(x*y + w*z), w*w - x*x + y*y - z*z, 2*(y*z - w*x)],
            [2*(x*z - w*y), 2*(y*z + w*x), w*w - x*x - y*y + z*z]])
    e = np.eye(4)
    T = np.zeros((3, 3, 4, 4))
    for a in range(4):
        T[:, :, a, a] = r(e[a])
        for b in range(a + 1, 4):
            T[:, :, a, b] = T[:, :, b, a] = 0.5 * (r(e[a] + e[b]) - r(e[a]) - r(e[b]))
    return T


_T = _quad_tensor()
_E3X = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])  # e3 x v


def _G(v: np.ndarray) -> np.ndarray:
    """(..., 3, 4) matrix with w = 2 G(q) Q (patent eqs. 32-34); G(q) Q = -G(Q) q."""
    a, b, c, d = np.moveaxis(v, -1, 0)
    return np.stack([
        np.stack([-b, a, d, -c], -1),
        np.stack([-c, -d, a, b], -1),
        np.stack([-d, c, -b, a], -1)], -2)


def _R(q):
    return np.einsum("ijab,...a,...b->...ij", _T, q, q)


def _dR(q):
    """dR_ij / dq_a: (..., 3, 3, 4)."""
    return 2.0 * np.einsum("ijab,...b->...ija", _T, q)


def _cross_mat(v):
    x, y, z = np.moveaxis(v, -1, 0)
    o = np.zeros_like(x)
    return np.stack([np.stack([o, -z, y], -1), np.stack([z, o, -x], -1),
                     np.stack([-y, x, o], -1)], -2)


def _qmul_left(p):
    """L(p) with p (x) q = L(p) q."""
    a, b, c, d = p
    return np.array([[a, -b, -c, -d], [b, a, -d, c], [c, d, a, -b], [d, -c, b, a]])


def _conj(q):
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def patent_force(problem) -> np.ndarray:
    """The patent's constant internal force for a free end: ``P_end + W/2`` (world, N)."""
    W = np.asarray(problem.weight, float) * float(problem.length)
    P = np.zeros(3) if getattr(problem, "end_force", None) is None else np.asarray(problem.end_force, float)
    return P + 0.5 * W


# --- the discrete system -------------------------------------------------------

class _System:
    """Residual and sparse Jacobian of the patent's backward-difference equations.

    Nondimensional inside: arc length in units of L, stiffness in units of
    K_ref = max(A, B), forces in K_ref / L^2, so the residual is O(1).
    Variables: node k holds [q_k, Q_k] at 8k..8k+7; ``F`` (3) follows when
    it is unknown. Rows: segment k (1..n) at 8(k-1): 4 differences, 3
    moments, 1 normalisation; then the start and end conditions.
    """

    def __init__(self, problem, n, mode, force=None):
        self.n = n
        self.h = 1.0 / n
        L = float(problem.length)
        self.L = L
        K = np.asarray(problem.stiffness, float)
        if K.shape != (3,) or not np.all(K > 0) or not np.all(np.isfinite(K)):
            raise ValueError("stiffness must be three positive numbers (A, B, C)")
        self.Kref = float(max(K[0], K[1]))
        self.K = K / self.Kref
        self.fscale = self.Kref / L**2
        if getattr(problem, "start", "clamped") != "clamped":
            raise ValueError("patent model: the start end must be clamped (the patent's fixed end); "
                             "use model 'rod' for other end conditions")
        self.end = getattr(problem, "end", "clamped")
        if self.end not in ("clamped", "pinned", "free"):
            raise ValueError(f"patent model: unknown end condition {self.end!r}")
        Ts = np.asarray(problem.T_start, float)
        Te = np.asarray(problem.T_end, float)
        self.Ts, self.Te = Ts, Te
        self.r0 = Ts[:3, 3]
        self.dr = (Te[:3, 3] - Ts[:3, 3]) / L
        self.qs = matrix_to_quaternion(Ts[:3, :3])
        self.qe = matrix_to_quaternion(Te[:3, :3])
        self.W = np.asarray(problem.weight, float) * L      # weight vector, N
        self.mode = mode
        # F unknown only when Newton must find the end reaction
        self.F_unknown = mode == "newton" and self.end != "free"
        if force is not None:
            self.F_fixed = np.asarray(force, float) / self.fscale
        else:
            self.F_fixed = patent_force(problem) / self.fscale
        self.nvar = 8 * (n + 1) + (3 if self.F_unknown else 0)

    # variables <-> arrays
    def split(self, x):
        n = self.n
        nodes = x[: 8 * (n + 1)].reshape(n + 1, 8)
        F = x[8 * (n + 1):] if self.F_unknown else self.F_fixed
        return nodes[:, :4], nodes[:, 4:], F

    def residual_and_jacobian(self, x, want_jac=True, rows="newton"):
        n, h, K = self.n, self.h, self.K
        q, Q, F = self.split(x)
        qk, Qk, Qm = q[1:], Q[1:], Q[:-1]
        Gq = _G(qk)                                   # (n,3,4)
        w = 2.0 * np.einsum("kij,kj->ki", Gq, Qk)     # curvature-twist at nodes 1..n
        dw = 2.0 * np.einsum("kij,kj->ki", Gq, Qk - Qm) / h
        Kw = K * w
        R = _R(qk)
        Fb = np.einsum("kji,j->ki", R, F)             # R^T F
        mom = (K * dw + np.cross(w, Kw) + Fb @ _E3X.T) / K
        diff = qk - q[:-1] - h * Qk
        norm = np.sum(qk * qk, axis=1) - 1.0
        seg = np.concatenate([diff, mom, norm[:, None]], axis=1).ravel()
        d3 = R[:, :, 2]
        pos = h * d3.sum(axis=0) - self.dr
        extra = [q[0] - self.qs, [q[0] @ Q[0]]]
        if rows == "overwrite":
            extra = [pos, [q[0] @ Q[0]], [q[0] @ q[0] - 1.0]]
        elif self.end == "clamped":
            extra += [pos, (_qmul_left(_conj(self.qe)) @ q[n])[1:]]
        elif self.end == "pinned":
            extra += [pos, 2.0 * _G(q[n]) @ Q[n]]
        else:
            extra += [2.0 * _G(q[n]) @ Q[n]]
        r = np.concatenate([seg] + [np.asarray(e, float) for e in extra])
        if not want_jac:
            return r, None
        rows_i, cols_i, vals = [], [], []

        def put(r0, c0, block):
            # block (m, a, b): m blocks of a x b at rows r0[i].., cols c0[i]..
            block = np.asarray(block)
            m, a, b = block.shape
            rr = np.asarray(r0)[:, None, None] + np.arange(a)[None, :, None]
            cc = np.asarray(c0)[:, None, None] + np.arange(b)[None, None, :]
            rows_i.append(np.broadcast_to(rr, block.shape).ravel())
            cols_i.append(np.broadcast_to(cc, block.shape).ravel())
            vals.append(block.ravel())

        k = np.arange(1, n + 1)
        rb = 8 * (k - 1)
        cq, cQ, cqm, cQm = 8 * k, 8 * k + 4, 8 * (k - 1), 8 * (k - 1) + 4
        I4 = np.broadcast_to(np.eye(4), (n, 4, 4))
        put(rb, cq, I4)
        put(rb, cqm, -I4)
        put(rb, cQ, -h * I4)
        # moments: d/dq_k, d/dQ_k, d/dQ_{k-1}, d/dF
        Jg = -_cross_mat(Kw) + _cross_mat(w) * K[None, None, :]     # d(w x Kw)/dw
        dw_dq = -2.0 * _G(Qk)
        dw_dQ = 2.0 * Gq
        ddw_dq = -2.0 * _G(Qk - Qm) / h
        dR = _dR(qk)                                                  # (n,3,3,4)
        dFb_dq = np.einsum("kjia,j->kia", dR, F)
        Kinv = (1.0 / K)[None, :, None]
        put(rb + 4, cq, Kinv * (K[None, :, None] * ddw_dq + Jg @ dw_dq + _E3X @ dFb_dq))
        put(rb + 4, cQ, Kinv * (K[None, :, None] * dw_dQ / h + Jg @ dw_dQ))
        put(rb + 4, cQm, -dw_dQ / h)
        if self.F_unknown:
            put(rb + 4, np.full(n, 8 * (n + 1)), Kinv * (_E3X @ np.transpose(R, (0, 2, 1))))
        put(rb + 7, cq, 2.0 * qk[:, None, :])
        r0 = 8 * n
        dd3 = dR[:, :, 2, :]                                          # (n,3,4)

        def start_rows(r0):
            put([r0], [0], np.eye(4)[None])
            put([r0 + 4], [0], Q[0][None, None, :])
            put([r0 + 4], [4], q[0][None, None, :])
            return r0 + 5

        if rows == "overwrite":
            put(np.full(n, r0), cq, h * dd3)
            put([r0 + 3], [0], Q[0][None, None, :])
            put([r0 + 3], [4], q[0][None, None, :])
            put([r0 + 4], [0], 2.0 * q[0][None, None, :])
        else:
            r0 = start_rows(r0)
            if self.end in ("clamped", "pinned"):
                put(np.full(n, r0), cq, h * dd3)
                r0 += 3
            if self.end == "clamped":
                put([r0], [8 * n], (_qmul_left(_conj(self.qe))[1:])[None])
            else:
                put([r0], [8 * n], (-2.0 * _G(Q[n]))[None])
                put([r0], [8 * n + 4], (2.0 * _G(q[n]))[None])
        J = sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows_i), np.concatenate(cols_i))),
                          shape=(r.size, self.nvar))
        return r, J

    # outputs
    def nodes(self, q):
        d3 = _R(q[1:])[:, :, 2]
        steps = np.vstack([np.zeros(3), self.h * self.L * d3])
        return self.r0 + np.cumsum(steps, axis=0)


def _guess_curve(sysm: _System, problem, n):
    """Node quaternions of a smooth first guess joining the two end poses.

    A Hermite cubic between the end points along the end tangents, bulged
    along gravity (or across the chord) until its length is L, resampled at
    equal arc length; frames by parallel transport from the start frame,
    the twist left at the end spread linearly.
    """
    L = sysm.L
    p0, p1 = sysm.Ts[:3, 3] / L, sysm.Te[:3, 3] / L
    t0, t1 = sysm.Ts[:3, 2], sysm.Te[:3, 2]
    chord = p1 - p0
    c = np.linalg.norm(chord)
    g = np.asarray(problem.weight, float)
    # no gravity: bulge the way the section bends most easily (A-bending curves along d2)
    soft = sysm.Ts[:3, 1] if sysm.K[0] < sysm.K[1] else sysm.Ts[:3, 0]
    ref = g if np.linalg.norm(g) > 0 else soft
    u_dir = chord / c if c > 1e-12 else t0
    perp = ref - (ref @ u_dir) * u_dir
    if np.linalg.norm(perp) < 1e-9 * (np.linalg.norm(ref) + 1):
        perp = np.cross(u_dir, [0.0, 0.0, 1.0])
        if np.linalg.norm(perp) < 1e-9:
            perp = np.cross(u_dir, [1.0, 0.0, 0.0])
    perp /= np.linalg.norm(perp)
    m = max(c, 0.3)
    u = np.linspace(0.0, 1.0, 2001)[:, None]
    h00, h10, h01, h11 = 2*u**3 - 3*u**2 + 1, u**3 - 2*u**2 + u, -2*u**3 + 3*u**2, u**3 - u**2
    base = h00 * p0 + h10 * m * t0 + h01 * p1 + h11 * m * t1
    bump = 16.0 * u**2 * (1 - u) ** 2 * perp

    def length(b):
        return np.sum(np.linalg.norm(np.diff(base + b * bump, axis=0), axis=1))

    lo, hi = 0.0, 1.0
    if length(lo) > 1.0:
        b = 0.0
    else:
        while length(hi) < 1.0:
            hi *= 2.0
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if length(mid) < 1.0 else (lo, mid)
        b = 0.5 * (lo + hi)
    curve = base + b * bump
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(curve, axis=0), axis=1))])
    arc /= arc[-1]
    sk = np.linspace(0.0, 1.0, n + 1)
    pts = np.stack([np.interp(sk, arc, curve[:, i]) for i in range(3)], axis=1)
    tang = np.diff(pts, axis=0)
    tang /= np.linalg.norm(tang, axis=1, keepdims=True)
    Rs = [sysm.Ts[:3, :3].copy()]
    for k in range(n):
        Rs.append(_transport(Rs[-1], tang[k]))
    Rn, Re = Rs[-1], sysm.Te[:3, :3]
    # twist about the last tangent that brings x onto the end's x (projected)
    xe = Re[:, 0] - (Re[:, 0] @ Rn[:, 2]) * Rn[:, 2]
    phi = np.arctan2(np.cross(Rn[:, 0], xe) @ Rn[:, 2], Rn[:, 0] @ xe) if np.linalg.norm(xe) > 1e-9 else 0.0
    out = []
    for k, Rk in enumerate(Rs):
        a = phi * k / n
        ca, sa = np.cos(a), np.sin(a)
        Rz = np.array([[ca, -sa, 0.0], [sa, ca, 0.0], [0.0, 0.0, 1.0]])
        out.append(Rk @ Rz)
    return _continuous(matrix_to_quaternion(np.array(out)))


def _transport(Rp, t):
    """Rotate frame Rp by the minimal rotation taking its z axis onto t."""
    z = Rp[:, 2]
    v = np.cross(z, t)
    cth = float(z @ t)
    if cth < -1 + 1e-12:
        return Rp @ np.diag([1.0, -1.0, -1.0])
    vx = _cross_mat(v)
    Rm = np.eye(3) + vx + vx @ vx / (1.0 + cth)
    return Rm @ Rp


def _continuous(q):
    """Flip signs so consecutive quaternions lie in the same hemisphere."""
    q = np.array(q, float)
    for k in range(1, len(q)):
        if q[k] @ q[k - 1] < 0:
            q[k] = -q[k]
    return q


def _resample(q_old, n):
    """Node quaternions at n+1 equal stations from a warm start of any size (nlerp)."""
    q_old = _continuous(q_old)
    so = np.linspace(0.0, 1.0, len(q_old))
    sn = np.linspace(0.0, 1.0, n + 1)
    q = np.stack([np.interp(sn, so, q_old[:, i]) for i in range(4)], axis=1)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _initial(sysm, problem, n, warm):
    if warm is not None:
        st = warm.state() if hasattr(warm, "state") else warm
        if isinstance(st, dict) and "quaternions" in st:
            qw = st["quaternions"]
        elif isinstance(st, dict) and "q" in st:     # a rod state: its segment orientations
            qw = st["q"]
        else:   # a solution: its node frames
            qw = _continuous(matrix_to_quaternion(np.asarray(warm.frames)[:, :3, :3]))
        q = _resample(np.asarray(qw, float), n)
        if q[0] @ sysm.qs < 0:
            q = -q
    elif sysm.end == "free":
        q = np.tile(sysm.qs, (n + 1, 1))
    else:
        q = _guess_curve(sysm, problem, n)
        if q[0] @ sysm.qs < 0:
            q = -q
    q[0] = sysm.qs
    Q = np.zeros_like(q)
    Q[1:] = (q[1:] - q[:-1]) / sysm.h
    Q[0] = Q[1] - (Q[1] @ q[0]) * q[0]
    x = np.concatenate([np.concatenate([q, Q], axis=1).ravel()])
    if sysm.F_unknown:
        F0 = np.zeros(3)
        if warm is not None:
            fe = warm.force_end if hasattr(warm, "force_end") else None
            if fe is not None:
                F0 = (-np.asarray(fe, float) + 0.5 * sysm.W) / sysm.fscale
        x = np.concatenate([x, F0])
    return x


def _newton(sysm, x, tol, max_iter):
    """Damped Newton with sparse LU; returns (x, iterations, residual inf-norm, converged)."""
    r, J = sysm.residual_and_jacobian(x)
    res = float(np.max(np.abs(r)))
    it = 0
    while it < max_iter:
        if res <= tol:
            return x, it, res, True
        try:
            dx = spla.spsolve(J, -r)
        except RuntimeError:
            return x, it, res, False
        if not np.all(np.isfinite(dx)):
            return x, it, res, False
        it += 1
        step, f0 = 1.0, float(r @ r)
        while True:
            xn = x + step * dx
            rn, _ = sysm.residual_and_jacobian(xn, want_jac=False)
            if np.all(np.isfinite(rn)) and float(rn @ rn) < (1.0 - 1e-4 * step) * f0 or step < 1e-4:
                break
            step *= 0.5
        if not np.all(np.isfinite(rn)):
            return x, it, res, False
        x = xn
        r, J = sysm.residual_and_jacobian(x)
        res = float(np.max(np.abs(r)))
        if step * np.max(np.abs(dx)) < tol * 1e-3 and res > tol:
            break
    return x, it, res, res <= tol


def _least_squares_step(J, b):
    """J dx = b by sparse LU; for a singular J (the patent's system is rank deficient for
    planar configurations) the minimum-norm least-squares step, through Tikhonov-regularised
    normal equations with a regularisation far below the system's scale."""
    try:
        return spla.splu(J).solve(b)
    except RuntimeError:
        JtJ = (J.T @ J).tocsc()
        eps = 1e-12 * float(abs(JtJ).max())
        return spla.spsolve(JtJ + eps * sp.identity(J.shape[1], format="csc"), J.T @ b)


def _overwrite(sysm, x, tol, max_iter):
    """The patent's iteration: Newton step on the 8n+5 system, then overwrite the 5 knowns."""
    n = sysm.n
    qe = sysm.qe if sysm.qe @ x[8 * n: 8 * n + 4] >= 0 else -sysm.qe
    # columns: everything except the 3 vector parts of q_n (held at their known values)
    keep = np.setdiff1d(np.arange(sysm.nvar), 8 * n + np.array([1, 2, 3]))
    x = x.copy()
    x[8 * n: 8 * n + 4] = qe
    history, discarded = [], float("inf")
    for it in range(1, max_iter + 1):
        r, J = sysm.residual_and_jacobian(x, rows="overwrite")
        dx = _least_squares_step(J[:, keep].tocsc(), -r)
        if not np.all(np.isfinite(dx)):
            break
        x_old = x.copy()
        x[keep] += dx
        discarded = max(float(np.max(np.abs(x[0:4] - sysm.qs))), abs(float(x[8 * n] - qe[0])))
        x[0:4] = sysm.qs            # the patent: replace the iterated knowns by their exact values
        x[8 * n] = qe[0]
        step = float(np.max(np.abs(x - x_old)))
        history.append(step)
        if step <= tol:
            break
    return x, history, discarded


def solve_patent(problem, *, segments: int = 50, tol: float = 1e-10, warm=None,
                 iteration: str = "newton", force=None, max_iter: int = 50):
    """Solve the patent's model for ``problem`` (a ``rod.RodProblem`` or any object with its fields).

    Returns the same result type as ``rod.solve_rod``. ``tol`` bounds the
    nondimensional residual (Newton) or step (overwrite). ``info`` holds
    ``model``, ``iteration``, ``history`` (overwrite: max change of the
    iterate per iteration), ``discarded_correction`` (overwrite: the last
    Newton correction to the known parameters that the overwrite threw
    away, O(h) when the fixed force is right) and the internal force ``F``
    (world, N).
    """
    t0 = time.perf_counter()
    n = int(segments)
    if n < 2:
        raise ValueError("segments must be at least 2")
    if iteration not in ("newton", "overwrite"):
        raise ValueError("iteration must be 'newton' or 'overwrite'")
    sysm = _System(problem, n, iteration, force)
    if iteration == "overwrite" and sysm.end != "clamped":
        raise ValueError("the patent's overwrite iteration needs both ends clamped (known Euler parameters)")
    if sysm.end != "free" and np.linalg.norm(sysm.dr) >= 1.0:
        return _package(sysm, _initial(sysm, problem, n, None), 0, np.inf, False, "overlength",
                        [], t0)
    x = _initial(sysm, problem, n, warm)
    history, extra = [], {}
    if iteration == "newton":
        x, it, res, ok = _newton(sysm, x, tol, max_iter)
        if not ok and warm is None and sysm.end == "free":
            # load continuation from the unloaded rod (large tip loads)
            F_full = sysm.F_fixed.copy()
            xc = _initial(sysm, problem, n, None)
            ok = True
            for lam in (0.25, 0.5, 0.75, 1.0):
                sysm.F_fixed = lam * F_full
                xc, itc, res, ok = _newton(sysm, xc, tol, max_iter)
                it += itc
                if not ok:
                    break
            x = xc
        status = "ok" if ok else "not_converged"
    else:
        x, history, discarded = _overwrite(sysm, x, tol, max_iter)
        it = len(history)
        ok = bool(history) and history[-1] <= tol
        # how far the overwrite fixed point is from satisfying every equation
        full = _System(problem, n, "newton", force)
        xf = np.concatenate([x, sysm.F_fixed]) if full.F_unknown else x
        res = float(np.max(np.abs(full.residual_and_jacobian(xf, want_jac=False)[0])))
        extra["discarded_correction"] = discarded
        status = "ok" if ok else "not_converged"
    return _package(sysm, x, it, res, ok, status, history, t0, extra)


def _package(sysm, x, it, res, ok, status, history, t0, extra=None):
    q, Q, F = sysm.split(x)
    if not np.all(np.isfinite(x)):
        q, Q, F = np.tile(sysm.qs, (sysm.n + 1, 1)), np.zeros((sysm.n + 1, 4)), np.zeros(3)
        ok, status = False, "not_converged" if status == "ok" else status
    qn = q / np.linalg.norm(q, axis=1, keepdims=True)
    R = quaternion_to_matrix(qn)
    nodes = sysm.nodes(qn)
    frames = np.zeros((sysm.n + 1, 4, 4))
    frames[:, :3, :3] = R
    frames[:, :3, 3] = nodes
    frames[:, 3, 3] = 1.0
    w = 2.0 * np.einsum("kij,kj->ki", _G(q), Q) / sysm.L          # 1/m
    Kd = sysm.K * sysm.Kref
    m_world = np.einsum("kij,kj->ki", R, Kd * w)                    # internal moment m(s)
    Fw = np.asarray(F, float) * sysm.fscale
    n0 = Fw + 0.5 * sysm.W          # n(0): the cable's pull on the start body
    nL = Fw - 0.5 * sysm.W          # n(L): what the end body applies to the cable
    res = float(res) if np.isfinite(res) else float(np.finfo(float).max)
    kw = dict(
        s=np.linspace(0.0, sysm.L, sysm.n + 1), nodes=nodes, frames=frames, quaternions=qn,
        force_start=n0, moment_start=m_world[0], force_end=-nL, moment_end=-m_world[-1],
        curvature=np.hypot(w[:, 0], w[:, 1]), residual=res, iterations=int(it),
        converged=bool(ok), status=status,
        # leading O(h) term: backward (eq. 57-59) vs trapezoidal positions at the tip
        error_estimate=float(np.linalg.norm(0.5 * sysm.h * sysm.L * (R[0, :, 2] - R[-1, :, 2]))),
    )
    info = {"model": "patent", "iteration": sysm.mode, "history": list(history), "F": Fw.tolist(),
            "time_s": time.perf_counter() - t0, **(extra or {})}
    sol = RodSolution(**kw, message=status, _state={"quaternions": qn, "force_end": -nL, "model": "patent"})
    sol.info = info     # model-specific diagnostics (not part of RodSolution's fields)
    return sol
