"""Discrete Kirchhoff rod for cable statics (the default cable model).

Model (docs/cable-rod.md has the derivation, the measured order and the limits)
------------------------------------------------------------------------------

An inextensible, unshearable rod of length ``L`` with bending stiffnesses
``A`` (about the section's x axis), ``B`` (about y) and torsional stiffness
``C`` (about the tangent z), loaded by a constant distributed weight ``f``
(N/m, world) and optional dead point forces at free ends. Nodes
``s_0 = 0 < ... < s_n = L`` (uniform, or graded towards the ends) carry
orientations ``q_k`` (unit quaternions wxyz, body to world, z axis = tangent
``d3``) and positions ``x_k``. The potential

    E = sum_i (2/h_i) V_i^T K V_i  -  sum_k w_k f . x_k  -  F_end . x_n

(``V_i`` = vector part of ``conj(q_i) q_{i+1}``, so ``2 V_i / h_i`` is the
cell's Darboux vector; ``w_k`` trapezoid weights) is made stationary subject
to ``c_i = x_{i+1} - x_i - (h_i/2)(d3_i + d3_{i+1}) = 0`` with multipliers
``mu_i`` = the internal force at the cell midpoints. Midpoint energy and
trapezoid centreline on full cells: a symmetric scheme, error ~ h^2 with an
even expansion, so Richardson extrapolation (n, 2n) gives h^4.

Solver: Newton on the KKT system with body-frame rotation increments
(``q <- q exp(theta/2)``) and exact second derivatives. Forces and positions
are eliminated, leaving a block-tridiagonal rotation system bordered by three
end-position rows: LAPACK ``dgbsv``, O(n) (the full interleaved KKT matrix,
band 11, is the fallback). The constrained Hessian's inertia is checked by a
banded Cholesky of ``H + rho C^T C`` (Finsler's lemma); when it fails the
rotation block is shifted (Levenberg-Marquardt, the trust-region dual), near
non-minimal stationary points the step follows the negative curvature
direction. Steps are capped at ``MAX_TURN`` rad per node and accepted on
residual decrease or by backtracking on an exact-penalty merit. Warm starts on
a key-point path extrapolate the previous solutions (quadratically from three),
so one Newton step per key point and mesh suffices. At these sizes the cost is
the number of numpy calls, so the per-step work is written as few, large array
operations (quadratic-form tensors, cached mesh data).

Conventions: see :class:`RodProblem` and :class:`RodSolution`. SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy.linalg import eig_banded, lapack
from scipy.optimize import brentq

from p105cli.cable.catenary import catenary
from p105cli.kinematics.placements import matrix_to_quaternion

__all__ = ["RodProblem", "RodSolution", "solve_rod", "state_from_frames", "auto_grading", "END_KINDS"]

END_KINDS = ("clamped", "pinned", "free")
MAX_TURN = 0.6          # rad: largest rotation of one segment in one Newton step
_EYE3 = np.eye(3)
_E3 = np.array([0.0, 0.0, 1.0])
_E3X = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])  # [e3]x
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


# --------------------------------------------------------------------------- quaternion helpers

def _qmul_components(a, b):
    aw, ax, ay, az = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bw, bx, by, bz = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    out = np.empty(a.shape if a.shape == b.shape else np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = aw * bw - ax * bx - ay * by - az * bz
    out[..., 1] = aw * bx + ax * bw + ay * bz - az * by
    out[..., 2] = aw * by - ax * bz + ay * bw + az * bx
    out[..., 3] = aw * bz + ax * by - ay * bx + az * bw
    return out


def _qconj(q):
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def _qexp(theta):
    """exp(theta/2) as a unit quaternion, theta (..., 3) rotation vector."""
    ang = np.sqrt(np.einsum("...i,...i->...", theta, theta))
    half = 0.5 * ang
    # sin(half)/ang, series below 1e-4
    k = np.where(ang < 1e-4, 0.5 - ang * ang / 48.0, np.sin(half) / np.where(ang < 1e-4, 1.0, ang))
    return np.concatenate([np.cos(half)[..., None], k[..., None] * theta], axis=-1)


def _qlog(q):
    """Rotation vector of a unit quaternion (shortest: sign of w made >= 0)."""
    q = np.where(q[..., :1] < 0.0, -q, q)
    v = q[..., 1:]
    sv = np.linalg.norm(v, axis=-1)
    ang = 2.0 * np.arctan2(sv, q[..., 0])
    k = np.where(sv < 1e-12, 2.0, ang / np.where(sv < 1e-12, 1.0, sv))
    return k[..., None] * v


def _quadratic_form_of_rotation():
    """M (16, 9) with R(q).ravel() = (q q^T).ravel() @ M for a unit quaternion q (wxyz)."""
    M = np.zeros((4, 4, 3, 3))
    w, x, y, z = range(4)

    def put(i, j, terms):
        for c, a, b in terms:
            M[a, b, i, j] += c
    # R = (w^2 - |v|^2) I + 2 v v^T + 2 w [v]x, written with w^2 + |v|^2 = 1 kept homogeneous
    put(0, 0, [(1, w, w), (1, x, x), (-1, y, y), (-1, z, z)])
    put(1, 1, [(1, w, w), (-1, x, x), (1, y, y), (-1, z, z)])
    put(2, 2, [(1, w, w), (-1, x, x), (-1, y, y), (1, z, z)])
    put(0, 1, [(2, x, y), (-2, z, w)])
    put(0, 2, [(2, x, z), (2, y, w)])
    put(1, 0, [(2, x, y), (2, z, w)])
    put(1, 2, [(2, y, z), (-2, x, w)])
    put(2, 0, [(2, x, z), (-2, y, w)])
    put(2, 1, [(2, y, z), (2, x, w)])
    return M.reshape(16, 9)


# Products of quaternion components by matmuls with 0/1 matrices (numpy broadcasting over a
# trailing axis of 4 is several times slower): a_i b_j for all 16 pairs, a_i a_j for the 10 with i <= j
_I16 = np.repeat(np.eye(4), 4, axis=1)
_J16 = np.tile(np.eye(4), (1, 4))
_PAIRS = [(i, j) for i in range(4) for j in range(i, 4)]
_I10 = np.eye(4)[:, [i for i, _ in _PAIRS]]
_J10 = np.eye(4)[:, [j for _, j in _PAIRS]]


def _outer16(a, b):
    """(..., 16) products a_i b_j (i major) of two (..., 4) arrays."""
    return (a @ _I16) * (b @ _J16)


def _square10(a):
    """(..., 10) products a_i a_j, i <= j, of a (..., 4) array (pairs as in _PAIRS)."""
    return (a @ _I10) * (a @ _J10)


def _fold10(T):
    """A quadratic-form tensor (16, k) on a_i a_j rewritten for _square10 (10, k)."""
    T = np.asarray(T).reshape(4, 4, -1)
    return np.stack([T[i, j] + T[j, i] if i != j else T[i, i] for i, j in _PAIRS])


_QFORM = _quadratic_form_of_rotation()
_QFORM10 = _fold10(_QFORM)
_QM = np.stack([_qmul_components(np.eye(4)[i], np.eye(4)[j]) for i in range(4) for j in range(4)])


def _qmul(a, b):
    """Quaternion product (wxyz, broadcasting): bilinear, so the 16 component products and one matmul."""
    return _outer16(a, b) @ _QM


def _qmat(q):
    """Rotation matrices (..., 3, 3) of unit quaternions (..., 4): quadratic monomials, one matmul."""
    return (_square10(q) @ _QFORM10).reshape(q.shape[:-1] + (3, 3))


def _cross(a, b):
    out = np.empty(a.shape if a.shape == b.shape else np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def _solve3(S, r):
    """Solve a 3x3 system by the adjugate; None when nearly singular (|det| < 1e-13 ||S||^3)."""
    (a, b, c), (d, e, f), (g, h, i) = S.tolist()
    A, B, C = e * i - f * h, f * g - d * i, d * h - e * g
    det = a * A + b * B + c * C
    nrm = max(abs(a), abs(b), abs(c), abs(d), abs(e), abs(f), abs(g), abs(h), abs(i))
    if not abs(det) > 1e-13 * nrm ** 3:
        return None
    inv = np.array([[A, c * h - b * i, b * f - c * e],
                    [B, a * i - c * g, c * d - a * f],
                    [C, b * g - a * h, a * e - b * d]]) / det
    return inv @ r


def _skew(v):
    S = np.zeros(v.shape[:-1] + (3, 3))
    S[..., 0, 1], S[..., 0, 2] = -v[..., 2], v[..., 1]
    S[..., 1, 0], S[..., 1, 2] = v[..., 2], -v[..., 0]
    S[..., 2, 0], S[..., 2, 1] = -v[..., 1], v[..., 0]
    return S


def _slerp_mid(qa, qb, t=0.5):
    """q_a exp(t log(conj(q_a) q_b)) (geodesic interpolation)."""
    return _qmul(qa, _qexp(t * _qlog(_qmul(_qconj(qa), qb))))


def _pose_quat(T):
    """Quaternion (wxyz) of one pose's rotation: Shepperd's method on Python floats (hot path;
    same result as placements.matrix_to_quaternion up to sign)."""
    R = np.asarray(T, dtype=float)[:3, :3].tolist()
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R
    tr = r00 + r11 + r22
    k = max(range(4), key=lambda i: (tr, r00, r11, r22)[i])
    if k == 0:
        q = [1.0 + tr, r21 - r12, r02 - r20, r10 - r01]
    elif k == 1:
        q = [r21 - r12, 1.0 + 2.0 * r00 - tr, r01 + r10, r02 + r20]
    elif k == 2:
        q = [r02 - r20, r01 + r10, 1.0 + 2.0 * r11 - tr, r12 + r21]
    else:
        q = [r10 - r01, r02 + r20, r12 + r21, 1.0 + 2.0 * r22 - tr]
    q = np.array(q)
    return q / np.sqrt(q @ q)


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


# --------------------------------------------------------------------------- banded storage

@lru_cache(maxsize=64)
def _band_map(nblk: int, b: int, kl: int, ku: int, extra: int):
    """Flat target/source indices that scatter block-tridiagonal (D, U, U^T) into LAPACK band storage.

    Storage: A[i, j] at ab[extra + ku + i - j, j] (``extra = kl`` for dgbsv,
    ``0`` with ``kl = 0`` for the upper form of dpbtrf). Returns
    (tD, sD, tU, sU, tL, sL, shape).
    """
    N = nblk * b
    nrow = extra + ku + kl + 1
    r, c = np.meshgrid(np.arange(b), np.arange(b), indexing="ij")
    blk = np.arange(nblk)[:, None, None]
    out = []
    for (I, J) in (
        (blk * b + r, blk * b + c),                            # D_i
        ((blk[:-1]) * b + r, (blk[:-1] + 1) * b + c),         # U_i: block i rows, i+1 cols
        ((blk[:-1] + 1) * b + c, (blk[:-1]) * b + r),         # U_i^T: block i+1 rows, i cols
    ):
        d = I - J
        ok = (d >= -ku) & (d <= kl)
        tgt = (extra + ku + d) * N + J
        out.append(tgt[ok])
        out.append(np.flatnonzero(ok.ravel()))
    out.append((nrow, N))
    return tuple(out)


def _to_band(D, U, kl, ku, extra):
    nblk, b = D.shape[0], D.shape[1]
    tD, sD, tU, sU, tL, sL, shape = _band_map(nblk, b, kl, ku, extra)
    ab = np.zeros(shape)
    flat = ab.reshape(-1)
    flat[tD] = D.reshape(-1)[sD]
    if nblk > 1:
        flat[tU] = U.reshape(-1)[sU]
        flat[tL] = U.reshape(-1)[sL]
    return ab


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


# --------------------------------------------------------------------------- initial guesses

def _transport_frames(t, q0):
    """Quaternions of frames with z = t (n,3), carried from q0 by parallel transport.

    Discrete parallel transport composes the minimal rotations between
    consecutive tangents; for a start guess the direct minimal rotation from
    q0's z axis to each tangent is used instead when no tangent turns by more
    than ~150 degrees from it (same frames up to a small, smooth roll).
    """
    q0 = np.asarray(q0, dtype=float)
    z0 = _qmat(q0)[:, 2]
    c = t @ z0
    if np.all(c > -0.85):
        ax = _cross(z0, t)
        # quaternion of the minimal rotation z0 -> t: (1 + c, z0 x t) normalised
        rot = np.concatenate([(1.0 + c)[:, None], ax], axis=1)
        rot /= np.linalg.norm(rot, axis=1, keepdims=True)
        return _qmul(rot, q0[None, :])
    n = t.shape[0]
    out = np.empty((n, 4))
    q = q0
    prev = z0
    for i in range(n):
        ti = t[i]
        ax = _cross(prev, ti)
        cth = float(np.clip(prev @ ti, -1.0, 1.0))
        sn = float(np.linalg.norm(ax))
        if sn > 1e-15:
            q = _qmul(_qexp(ax / sn * np.arctan2(sn, cth)), q)
        elif cth < 0.0:     # exact reversal: turn about the frame's x axis
            q = _qmul(q, np.array([0.0, 1.0, 0.0, 0.0]))
        out[i] = q / np.linalg.norm(q)
        q = out[i]
        prev = ti
    return out


def _resample(curve_pts, frac):
    """Nodes at the arc-length fractions ``frac`` along a densely sampled curve."""
    seg = np.linalg.norm(np.diff(curve_pts, axis=0), axis=1)
    sc = np.concatenate([[0.0], np.cumsum(seg)])
    target = frac * sc[-1]
    return np.stack([np.interp(target, sc, curve_pts[:, k]) for k in range(3)], axis=1)


def _hermite_guess(m: _Model):
    """Cubic Hermite curve between the end points with the end tangents, length L."""
    d = m.pe - m.ps
    dist = float(np.linalg.norm(d))
    t0 = _qmat(m.qs)[:, 2]
    t1 = _qmat(m.qe)[:, 2] if m.clamp_e else (d / dist if dist > 0 else t0)
    if m.start != "clamped":
        t0 = d / dist if dist > 0 else t0
    # if both tangents are along the chord the cubic is straight: then a bow is
    # added in the plane of the start section's x axis (deterministic)
    side = _qmat(m.qs)[:, 1 if m.K[0] <= m.K[1] else 0]   # bow = bending about the weaker axis
    if dist > 0:
        side = side - (side @ d) / dist**2 * d
    if np.linalg.norm(side) < 1e-9:
        ref = np.array([0.0, 0.0, 1.0]) if abs(d[2]) < 0.9 * dist else np.array([1.0, 0.0, 0.0])
        side = _cross(d, ref)
    side = side / np.linalg.norm(side)
    gu, gw = np.polynomial.legendre.leggauss(6)
    ug = ((np.arange(24)[:, None] + 0.5 * (gu[None, :] + 1.0)) / 24.0).reshape(-1, 1)
    wg = np.tile(gw, 24) / 48.0

    def length(k, b):
        u = ug
        dc = ((3 * u**2 - 4 * u + 1) * (k * t0) + (-6 * u**2 + 6 * u) * d
              + (3 * u**2 - 2 * u) * (k * t1) + b * (4.0 - 8.0 * u) * side)
        return float(wg @ np.sqrt(np.einsum("ij,ij->i", dc, dc)))

    kmax = 3.0 * m.L
    dh = d / dist if dist > 0 else t0
    collinear = max(np.linalg.norm(_cross(t0, dh)), np.linalg.norm(_cross(t1, dh))) < 1e-6
    if not collinear and length(kmax, 0.0) >= m.L:
        k, b = brentq(lambda k: length(k, 0.0) - m.L, 0.0, kmax, xtol=1e-12 * m.L), 0.0
    else:
        k = dist
        b = brentq(lambda b: length(k, b) - m.L, 0.0, 2.0 * m.L, xtol=1e-12 * m.L)
    u = np.linspace(0.0, 1.0, 20 * m.n + 1)[:, None]
    return (m.ps + (u**3 - 2 * u**2 + u) * (k * t0) + (-2 * u**3 + 3 * u**2) * d
            + (u**3 - u**2) * (k * t1) + b * 4.0 * u * (1.0 - u) * side)


def _initial_guess(m: _Model):
    """Start: catenary for cables with weight (fixed ends), straight line for free ends, else Hermite."""
    n, L = m.n, m.L
    s_mid = 0.5 * (m.s[:-1] + m.s[1:])
    mu = None
    wnorm = float(np.linalg.norm(m.f))
    if not m.fixed_e:
        t0 = _qmat(m.qs)[:, 2]
        x = m.ps + m.s[:, None] * t0
        mu = m.Fe + (L - s_mid)[:, None] * m.f      # statically determinate
    else:
        x = None
        if wnorm > 0.0 and m.K.max() < 2.0 * wnorm * L ** 3:
            try:
                cat = catenary(m.ps, m.pe, L, m.f)
                x = cat.points(m.s)
                mu = cat.internal_force(s_mid)
            except ValueError:
                x = None
        if x is None:
            x = _resample(_hermite_guess(m), m.s / L)
    # node tangents: central differences, one-sided second order at the ends
    t = np.empty_like(x)
    t[1:-1] = x[2:] - x[:-2]
    t[0] = -3.0 * x[0] + 4.0 * x[1] - x[2]
    t[-1] = 3.0 * x[-1] - 4.0 * x[-2] + x[-3]
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    if m.clamp_s:
        t[0] = _qmat(m.qs)[:, 2]
    if m.clamp_e:
        t[-1] = _qmat(m.qe)[:, 2]
    q = _transport_frames(t, m.qs)
    if m.clamp_e:
        # distribute the roll mismatch at the end clamp linearly along the rod
        rel = _qmul(_qconj(q[-1]), m.qe)
        rel = np.where(rel[0] < 0, -rel, rel)
        roll = 2.0 * np.arctan2(rel[3], rel[0])
        q = _qmul(q, _qexp(np.outer(m.s / L * roll, _E3)))
        q[-1] = m.qe
    if m.clamp_s:
        q[0] = m.qs
    if mu is None:
        mu = np.zeros((n, 3)) + (L - s_mid)[:, None] * m.f * 0.5
    x = x.copy()
    x[0] = m.ps
    if m.fixed_e:
        x[-1] = m.pe
    return q, mu, x


# --------------------------------------------------------------------------- Newton

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
    if problem.start != "free" and problem.end != "free":
        dist = float(np.linalg.norm(np.asarray(problem.T_end, float)[:3, 3]
                                    - np.asarray(problem.T_start, float)[:3, 3]))
        if dist >= L * (1.0 - 1e-9):
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
