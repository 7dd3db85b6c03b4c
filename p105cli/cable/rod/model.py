"""The discrete Kirchhoff rod: mesh, bending energy tensors, residual, merit,
KKT blocks, the inertia (Finsler) test and the reduced Newton system.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy.linalg import lapack

from .banded import _to_band
from .problem import RodProblem, _chord_family_axis
from .quaternions import (
    _EYE3, _cross, _fold10, _outer16, _pose_quat, _qconj, _qmat, _qmul, _skew, _solve3, _square10,
)


def _bend_reference(K, qb):
    """Cell energy, gradient and Hessian blocks for h = 4 (c = 1), explicit formulas in qb = (w, v).

    With V = vector part of conj(q_a) q_b and J_a = Q/2, J_b = P/2 (P = [v]x + w I,
    Q = [v]x - w I): E = V^T K V / 2, g_a = -(v x g + w g)/2, g_b = -(v x g - w g)/2 (g = K v).
    Used only to build the quadratic-form tensor of :meth:`_Model.bend` by polarisation."""
    w, v = qb[:, 0], qb[:, 1:]
    g = K * v
    vxg = _cross(v, g)
    ga = -0.5 * (vxg + w[:, None] * g)
    gb = -0.5 * (vxg - w[:, None] * g)
    Sv = _skew(v)
    wI = w[:, None, None] * _EYE3
    P, Q = Sv + wI, Sv - wI
    KP, KQ = K[:, None] * P, K[:, None] * Q
    gv = np.einsum("ij,ij->i", g, v)
    diag_corr = (0.25 * gv)[:, None, None] * _EYE3
    Haa = -0.25 * (P @ KQ) - diag_corr
    Hbb = -0.25 * (Q @ KP) - diag_corr
    X = 0.25 * (g[:, :, None] * v[:, None, :] + v[:, :, None] * g[:, None, :]
                + w[:, None, None] * _skew(g) - gv[:, None, None] * _EYE3)
    Hab = -0.25 * (P @ KP) + X
    e = 0.5 * gv
    return np.concatenate([ga, gb, Haa.reshape(-1, 9), Hbb.reshape(-1, 9), Hab.reshape(-1, 9), e[:, None]],
                          axis=1)


@lru_cache(maxsize=32)
def _bend_tensor(K: tuple):
    """T (10, 34) with _bend_reference(K, qb) = _square10(qb) @ T (all entries are quadratic)."""
    K = np.array(K, dtype=float)
    E = np.eye(4)
    f = lambda x: _bend_reference(K, x)                       # noqa: E731
    diag = f(E)
    T = np.zeros((4, 4, 34))
    for a in range(4):
        T[a, a] = diag[a]
        for b in range(a + 1, 4):
            T[a, b] = T[b, a] = 0.5 * (f((E[a] + E[b])[None])[0] - diag[a] - diag[b])
    T = _fold10(T.reshape(16, 34))
    T.flags.writeable = False
    return T


def _qmul_tensor():
    """QB (16, 4) with qmul(conj(a), b) = (a b^T).ravel() @ QB."""
    E = np.eye(4)
    return np.stack([_qmul(_qconj(E[i]), E[j]) for i in range(4) for j in range(4)])


_QB = _qmul_tensor()


# --------------------------------------------------------------------------- the discrete model

def _graded_nodes(L: float, n: int, a: float) -> np.ndarray:
    """Node arc lengths s_k = L (sigma - a sin(2 pi sigma) / (2 pi)), sigma = k/n.

    ``a`` in [0, 1): cells shrink to (1 - a) h at both ends and grow to
    (1 + a) h in the middle (boundary layers at clamps). The map is smooth
    and symmetric, so the discretisation keeps its even error expansion and
    the 2n grid contains the n grid (Richardson).
    """
    sig = np.arange(n + 1) / n
    s = L * (sig - a * np.sin(2.0 * np.pi * sig) / (2.0 * np.pi))
    s[0], s[-1] = 0.0, L
    return s


def auto_grading(p: RodProblem, n: int) -> float:
    """Grading for a clamped cable whose boundary layer sqrt(EI/T) is thinner than 4 cells.

    T is estimated as max(|w| L, |end force|) (the tension of a hanging
    cable); the end cells are made about a quarter of the layer's width, at
    most 10x finer than uniform. 0 (uniform) otherwise.
    """
    if "clamped" not in (p.start, p.end):
        return 0.0
    K = np.asarray(p.stiffness, float)
    T = max(float(np.linalg.norm(p.weight)) * float(p.length),
            float(np.linalg.norm(p.end_force)) if p.end_force is not None else 0.0,
            float(np.linalg.norm(p.start_force)) if p.start_force is not None else 0.0)
    if not T > 0.0:
        return 0.0
    delta = np.sqrt(min(K[0], K[1]) / T)
    h = float(p.length) / n
    # resolve the layer with ~4 end cells; below that the clamp's cell error is O(h x angle)
    return float(min(0.9, max(0.0, 1.0 - delta / (4.0 * h))))


def _finsler_static(n, hc, fixed_e, clamp_s, clamp_e):
    """Constant parts of the Finsler matrix (per unit rho) and the masks of its held unknowns.

    Returns P0 (n+1, 6, 6): (C^T C)_xx = (number of cells at the node) I and
    (C^T C)_theta,theta diagonal tilt terms (h^2/4 per cell, x and y) with held unknowns' rows and
    columns replaced by I; the masks (1 = kept) for the rotation block, the (x, theta) block and
    the upper blocks."""
    P0 = np.zeros((n + 1, 6, 6))
    cnt = np.full(n + 1, 2.0)
    cnt[0] = cnt[-1] = 1.0
    h2 = np.zeros(n + 1)
    h2[:-1] += 0.25 * hc ** 2
    h2[1:] += 0.25 * hc ** 2
    P0[:, 0:3, 0:3] = cnt[:, None, None] * _EYE3
    P0[:, 3:6, 3:6] = h2[:, None, None] * np.diag([1.0, 1.0, 0.0])
    M = np.ones((n + 1, 6, 6))
    MU = np.ones((n, 6, 6))
    fixed = [(0, slice(0, 3))]
    if fixed_e:
        fixed.append((n, slice(0, 3)))
    if clamp_s:
        fixed.append((0, slice(3, 6)))
    if clamp_e:
        fixed.append((n, slice(3, 6)))
    for blk, sl in fixed:
        for A in (P0, M):
            A[blk, sl, :] = 0.0
            A[blk, :, sl] = 0.0
        P0[blk, sl, sl] = _EYE3
        if blk < n:
            MU[blk, sl, :] = 0.0
        if blk > 0:
            MU[blk - 1, :, sl] = 0.0
    return P0, M[:, 3:6, 3:6].copy(), M[:, 0:3, 3:6].copy(), MU


@lru_cache(maxsize=32)
def _model_data(n, L, grading, K, f, start, end, Fe):
    """Pose-independent data of a discretised problem (see _Model), arrays read-only."""
    d = {"n": n, "L": L, "h": L / n, "grading": grading}
    d["s"] = _graded_nodes(L, n, grading)
    d["hc"] = np.diff(d["s"])                       # cell lengths
    d["hmin"] = float(d["hc"].min())
    d["c4"] = 4.0 / d["hc"]
    d["hc2"] = 0.5 * d["hc"][:, None]
    d["K"] = np.array(K)
    d["bend_tensor"] = _bend_tensor(K)
    d["f"] = np.array(f)
    d["start"], d["end"] = start, end
    d["clamp_s"], d["clamp_e"], d["fixed_e"] = start == "clamped", end == "clamped", end != "free"
    d["Fe"] = np.array(Fe)
    wk = np.zeros(n + 1)
    wk[:-1] += 0.5 * d["hc"]
    wk[1:] += 0.5 * d["hc"]
    d["wk"] = wk
    Kmax = max(K)
    d["F0"] = max(Kmax / L ** 2, float(np.linalg.norm(d["f"])) * L, float(np.linalg.norm(d["Fe"])), 1e-300)
    d["M0"] = d["F0"] * L
    d["sigma_min"] = 1e-12 * Kmax / d["hmin"]      # keeps exactly singular steps finite
    # isotropic section and no clamp: turning every section about its tangent by the same
    # angle is an exact symmetry; its zero mode is pinned by stiffening node 0's twist in the
    # Newton matrix only (the gradient has no component along it, so the answer is unchanged)
    d["gauge"] = abs(K[0] - K[1]) <= 1e-12 * Kmax and not d["clamp_s"] and not d["clamp_e"]
    # 1 where a node's rotation is an unknown
    free = np.ones(n + 1)
    if d["clamp_s"]:
        free[0] = 0.0
    if d["clamp_e"]:
        free[-1] = 0.0
    d["th_free"] = free
    # Newton's constant vectors: external forces on x_1..x_n (merit slope), the rotation
    # unknowns' positions in the Finsler and full KKT orderings (shifts)
    fx = -wk[1:, None] * d["f"]
    if d["fixed_e"]:
        fx[-1] = 0.0
    else:
        fx[-1] -= d["Fe"]
    d["fx"] = fx
    th_p = np.zeros((n + 1, 6))
    th_p[:, 3:6] = free[:, None]
    d["th_p"] = th_p.reshape(-1)
    th_k = np.zeros((n + 1, 9))
    th_k[:, 0:3] = free[:, None]
    d["th_k"] = th_k.reshape(-1)
    d["finsler_static"] = _finsler_static(n, d["hc"], d["fixed_e"], d["clamp_s"], d["clamp_e"])
    for v in list(d.values()) + list(d["finsler_static"]):
        if isinstance(v, np.ndarray):
            v.flags.writeable = False
    return d


class _Model:
    """Fixed data of one discretised problem (start always supported: free starts are reversed).

    Unknowns: node orientations q_0..q_n (clamped ones held), node positions
    x_1..x_n (x_0 held; x_n held unless the end is free), multipliers mu_i of
    c_i = x_{i+1} - x_i - (h/2)(d3_i + d3_{i+1}) (i = 0..n-1).
    """

    def __init__(self, prob: RodProblem, n: int, grading: float = 0.0):
        # the pose-independent data is shared by all key points (cached; arrays read-only)
        fe = (0.0, 0.0, 0.0) if prob.end_force is None else \
            tuple(np.asarray(prob.end_force, float).reshape(3).tolist())
        self.__dict__.update(_model_data(
            n, float(prob.length), float(grading), tuple(float(k) for k in prob.stiffness),
            tuple(np.asarray(prob.weight, dtype=float).reshape(3).tolist()), prob.start, prob.end, fe))
        self.Ts = np.asarray(prob.T_start, dtype=float)
        self.Te = np.asarray(prob.T_end, dtype=float)
        self.ps, self.pe = self.Ts[:3, 3].copy(), self.Te[:3, 3].copy()
        self.qs, self.qe = _pose_quat(self.Ts), _pose_quat(self.Te)
        # pinned-pinned with the weight along the chord (or none): turning the whole cable about
        # the chord is an exact symmetry; pinned in the Newton matrix at the middle node
        self.chord_axis = None
        if self.start == "pinned" and self.end == "pinned":
            fam = _chord_family_axis(prob)
            self.chord_axis = None if fam is None else fam[1]

    def align(self, q):
        """Consecutive node quaternions get non-negative dot products (clamps keep their rotation)."""
        d = np.einsum("ij,ij->i", q[:-1], q[1:])
        if d.min() > 0.0:
            return q
        d = np.sign(d)
        d[d == 0] = 1.0
        sgn = np.concatenate([[1.0], d]).cumprod()
        return q * sgn[:, None]

    def bend(self, q):
        """Energy and gradient blocks of the n cells (q_i, q_{i+1}); the packed Hessian data for hess().

        Every cell quantity is a homogeneous quadratic in qb = conj(q_i) q_{i+1} (scaled by 4/h_i), so
        all of them come from one matmul with a precomputed tensor (numpy call overhead, not
        arithmetic, is the cost here)."""
        qb = _outer16(q[:-1], q[1:]) @ _QB
        out = _square10(qb) @ self.bend_tensor
        out *= self.c4[:, None]
        return float(out[:, 33].sum()), out[:, 0:3], out[:, 3:6], out, qb

    def hess(self, out, *_):
        """Hessian blocks (left-left, right-right, left-right) of the cell energies."""
        H = out[:, 6:33].reshape(-1, 3, 3, 3)
        return H[:, 0], H[:, 1], H[:, 2]

    def grad_nodes(self, ga, gb):
        G = np.zeros((self.n + 1, 3))
        G[:-1] += ga
        G[1:] += gb
        return G

    def residual(self, q, mu, x):
        """KKT residual blocks (r_theta (n+1,3), r_mu (n,3), r_x (n,3)), bending data, R, b."""
        n = self.n
        R = _qmat(q)
        bend = self.bend(q)
        G = self.grad_nodes(bend[1], bend[2])
        hm = 0.5 * self.hc[:, None] * mu
        S = np.zeros((n + 1, 3))
        S[:-1] += hm
        S[1:] += hm
        b = np.einsum("pji,pj->pi", R, S)        # R_i^T (h_{i-1} mu_{i-1} + h_i mu_i) / 2
        r_th = G
        r_th[:, 0] += b[:, 1]
        r_th[:, 1] -= b[:, 0]
        d3 = R[:, :, 2]
        r_mu = x[1:] - x[:-1] - 0.5 * self.hc[:, None] * (d3[:-1] + d3[1:])
        r_x = np.empty((n, 3))
        r_x[:-1] = -self.wk[1:-1, None] * self.f + mu[:-1] - mu[1:]
        if self.fixed_e:
            r_x[-1] = 0.0
        else:
            r_x[-1] = -self.wk[-1] * self.f - self.Fe + mu[-1]
        r_raw = r_th
        r_th = r_th * self.th_free[:, None]
        return r_th, r_mu, r_x, bend, R, b, r_raw

    def scaled(self, r_th, r_mu, r_x, *_):
        """Scaled residual: moments per length / (M0/L), constraints / L, forces per length / (F0/L)."""
        s1 = np.abs(r_th).max() * self.L / (self.h * self.M0)
        s2 = np.abs(r_mu).max() / self.L
        s3 = np.abs(r_x).max() * self.L / (self.h * self.F0)
        return float(max(s1, s2, s3))

    def merit(self, q, x, nu):
        """Exact-penalty merit: total potential + nu * sum |c_i|."""
        e = self.bend(q)[0]
        e -= float(np.einsum("k,kj,j->", self.wk, x, self.f))
        if not self.fixed_e:
            e -= float(self.Fe @ x[-1])
        d3 = _qmat(q)[:, :, 2]
        c = x[1:] - x[:-1] - 0.5 * self.hc[:, None] * (d3[:-1] + d3[1:])
        return e + nu * float(np.sqrt(np.einsum("ij,ij->i", c, c)).sum())

    def matrices(self, bend, R, b, rho_factor=1.0, need_p=True, need_kkt=True):
        """KKT blocks (n+1 of 9: theta_i, mu_i, x_{i+1}) and Finsler blocks (n+1 of 6: x_i, theta_i)."""
        n, h = self.n, self.h
        Haa, Hbb, Hab = self.hess(bend[3])
        Hd = np.zeros((n + 1, 3, 3))
        Hd[:-1] += Haa
        Hd[1:] += Hbb
        # second derivative of -(h_{i-1} mu_{i-1} + h_i mu_i)/2 . d3(q_i exp(theta)) w.r.t. theta:
        # -(b e3^T + e3 b^T)/2 + b_z I (in place, on views), plus sigma_min I
        Hd[:, :, 2] -= 0.5 * b
        Hd[:, 2, :] -= 0.5 * b
        Hd.reshape(n + 1, 9)[:, ::4] += (b[:, 2] + self.sigma_min)[:, None]
        if self.gauge:
            Hd[0, 2, 2] += self.K.max() / h
        if self.chord_axis is not None:
            k = n // 2
            ab = R[k].T @ self.chord_axis                  # the chord axis in node k's body frame
            Hd[k] = Hd[k] + (self.K.max() / h) * np.outer(ab, ab)
        Ho = Hab
        # held rotations: identity rows, no coupling (every consumer treats them so; in place, also
        # in the residual's Hessian data: idempotent)
        if self.clamp_s:
            Hd[0] = _EYE3
            Ho[0] = 0.0
        if self.clamp_e:
            Hd[-1] = _EYE3
            Ho[-1] = 0.0
        E = np.zeros((n + 1, 3, 3))          # R_i [e3]x
        E[:, :, 0] = R[:, :, 1]
        E[:, :, 1] = -R[:, :, 0]
        hh = 0.5 * self.hc[:, None, None]
        CtL = hh * E[:-1]                    # d c_i / d theta_i
        CtR = hh * E[1:]                     # d c_i / d theta_{i+1}
        self.blocks = (Hd, Ho, CtL, CtR)
        self.R = R
        D = U = None
        if need_kkt:
            D, U = self._kkt_blocks(Hd, Ho, CtL, CtR)
        if not need_p:
            return D, U, None, None
        return (D, U) + self._finsler(Hd, Ho, CtL, CtR, b, rho_factor)

    def _kkt_blocks(self, Hd, Ho, CtL, CtR):
        n = self.n
        D = np.zeros((n + 1, 9, 9))
        D[:, 0:3, 0:3] = Hd
        D[:-1, 0:3, 3:6] = np.swapaxes(CtL, 1, 2)
        D[:-1, 3:6, 0:3] = CtL
        D[:-1, 3:6, 6:9] = _EYE3
        D[:-1, 6:9, 3:6] = _EYE3
        D[-1, 3:6, 3:6] = _EYE3          # dummies of the last block
        D[-1, 6:9, 6:9] = _EYE3
        U = np.zeros((n, 9, 9))
        U[:, 0:3, 0:3] = Ho
        U[:, 3:6, 0:3] = CtR             # (mu_i, theta_{i+1})
        U[:-1, 6:9, 3:6] = -_EYE3        # (x_{i+1}, mu_{i+1})
        if self.fixed_e:
            D[-2, 3:6, 6:9] = 0.0
            D[-2, 6:9, 3:6] = 0.0
            D[-2, 6:9, 6:9] = _EYE3
        if self.clamp_s:
            D[0, 0:3, :] = 0.0
            D[0, :, 0:3] = 0.0
            D[0, 0:3, 0:3] = _EYE3
            U[0, 0:3, :] = 0.0
        if self.clamp_e:
            D[-1, 0:3, 0:3] = _EYE3
            U[-1, :, 0:3] = 0.0
        return D, U

    def _finsler(self, Hd, Ho, CtL, CtR, b, rho_factor):
        """Finsler test matrix H + rho C^T C in the primal unknowns [x_i, theta_i]: diagonal blocks P
        (upper triangle only: the banded Cholesky reads the upper band) and upper blocks PU. Held
        unknowns (x_0, a fixed x_n, clamped rotations) get rho I rows (static masks)."""
        h = self.hmin
        b_max = float(np.abs(b).max())      # b ~ h mu
        rho = 4.0 * rho_factor * (b_max + self.K.max() / h) / (h * h)
        P0, mth, mxt, mU = self.finsler_static
        P = rho * P0                    # rho (C^T C)_xx, rho h^2/4 (x, y) tilt terms, held: rho I
        P[:, 3:6, 3:6] += Hd * mth
        xt = np.zeros((self.n + 1, 3, 3))                  # (x_i, theta_i): -Ct from c_i, +Ct from c_{i-1}
        xt[:-1] -= CtL
        xt[1:] += CtR
        P[:, 0:3, 3:6] = (rho * xt) * mxt
        PU = np.empty((self.n, 6, 6))
        PU[:, 0:3, 0:3] = -rho * _EYE3                     # (x_i, x_{i+1})
        PU[:, 0:3, 3:6] = -rho * CtR                       # (x_i, theta_{i+1})
        PU[:, 3:6, 0:3] = rho * np.swapaxes(CtL, 1, 2)     # (theta_i, x_{i+1})
        PU[:, 3:6, 3:6] = Ho + rho * np.einsum("pki,pkj->pij", CtL, CtR)   # (theta_i, theta_{i+1})
        PU *= mU
        return P, PU

    def solve_reduced(self, r_th, r_mu, r_x, delta):
        """Newton step by eliminating x and mu: block-tridiagonal rotation system bordered by the
        3 end-position rows (fixed end) or none (free end); LAPACK dgbsv, O(n).

        Returns (dth, dmu, dx) or None when the bordered elimination is unreliable
        (singular rotation block or ill-conditioned 3x3 Schur complement).

        With E_i = R_i [e3]x (d d3_i / d theta_i), cell i's constraint Jacobian is
        (h_i/2)(E_i, E_{i+1}); node sums of these are written with the trapezoid weights.
        """
        n = self.n
        Hd, Ho, _, _ = self.blocks
        R = self.R
        fr = self.th_free
        if delta > 0.0:
            Hd = Hd + (delta * fr)[:, None, None] * _EYE3
        N = 3 * (n + 1)
        Y = np.empty((N, 4), order="F")
        # mu = a + dlam: a from the force balance (cumulative sums of r_x)
        if self.fixed_e:
            a = np.empty((n, 3))
            a[0] = 0.0
            np.cumsum(r_x[:-1], axis=0, out=a[1:])
        else:
            a = -np.cumsum(r_x[::-1], axis=0)[::-1]
        # rhs = -r_th - C_theta^T a: node i gets E_i^T (h_i a_i + h_{i-1} a_{i-1}) / 2
        ha = self.hc2 * a
        v = np.zeros((n + 1, 3))
        v[:-1] += ha
        v[1:] += ha
        u = np.einsum("pji,pj->pi", R, v)           # R_i^T v_i; E_i^T v = (u_y, -u_x, 0)
        rhs = Y[:, 0].reshape(n + 1, 3)
        rhs[:, 0] = -r_th[:, 0] - u[:, 1] * fr
        rhs[:, 1] = -r_th[:, 1] + u[:, 0] * fr
        rhs[:, 2] = -r_th[:, 2]
        if self.clamp_s:
            rhs[0] = 0.0
        if self.clamp_e:
            rhs[-1] = 0.0
        if self.fixed_e:
            # B^T (the end-position rows, transposed): node i's block w_i fr_i E_i^T
            BT = Y[:, 1:].reshape(n + 1, 3, 3)
            wf = self.wk * fr
            BT[:, 0, :] = wf[:, None] * R[:, :, 1]
            BT[:, 1, :] = -wf[:, None] * R[:, :, 0]
            BT[:, 2, :] = 0.0
            BT = Y[:, 1:].copy()
            _, _, Y, info = lapack.dgbsv(5, 5, _to_band(Hd, Ho, 5, 5, 5), Y, overwrite_ab=1, overwrite_b=1)
        else:
            _, _, Y, info = lapack.dgbsv(5, 5, _to_band(Hd, Ho, 5, 5, 5), Y[:, :1], overwrite_ab=1,
                                         overwrite_b=1)
        if info != 0 or not np.all(np.isfinite(Y)):
            return None
        if self.fixed_e:
            S = BT.T @ Y[:, 1:]
            rb = -r_mu.sum(axis=0)
            dlam = _solve3(S, BT.T @ Y[:, 0] - rb)
            if dlam is None:
                return None
            dth = (Y[:, 0] - Y[:, 1:] @ dlam).reshape(n + 1, 3)
            dmu = dlam + a
        else:
            dth = Y[:, 0].reshape(n + 1, 3)
            dmu = a
        dth *= fr[:, None]
        # C_theta dth: cell i gets (h_i/2)(E_i dth_i + E_{i+1} dth_{i+1}), E dth = R (-dth_y, dth_x, 0)
        t = np.empty((n + 1, 3))
        t[:, 0] = -dth[:, 1]
        t[:, 1] = dth[:, 0]
        t[:, 2] = 0.0
        ed = np.einsum("pij,pj->pi", R, t)
        dx = np.cumsum(-r_mu - self.hc2 * (ed[:-1] + ed[1:]), axis=0)      # x_1..x_n (x_0 held)
        if self.fixed_e:
            dx[-1] = 0.0
        return dth, dmu, dx
