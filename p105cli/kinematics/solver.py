"""Position analysis of mechanisms: forward analysis of trees and closed loops, inverse analysis.

Everything here is SI (metres, radians) and batched over configurations
(leading axes). Nothing imports click.

Forward analysis (:func:`solve_motion`, :func:`iter_motion`)
-----------------------------------------------------------

The mechanism's links are placed by a spanning tree from the base link
(:func:`plan`, from :func:`p105cli.kinematics.graph.analyse`). A tree is
evaluated for every configuration at once (:func:`forward`): one batched
4x4 product per pair, in tree order.

Each independent loop (a chord of the tree plus the tree path back) must
close: the product of the pair transforms around it,
``T_loop = A_1 ... A_n`` (``A_k = T_link1_link2`` traversed forward, its
inverse backwards), must be the identity. The residual of a loop is
``(p / size, 2 q_v)`` of ``T_loop = [R, p]``, ``(q_w >= 0, q_v)`` the
quaternion of ``R`` (zero only at the identity; lengths divided by the
model size, so the same mechanism in millimetres and in metres takes the
same steps). Its Jacobian is analytic: the spatial twist of factor k in
the loop's start frame is ``Ad(A_1 ... A_{k-1}) xi_k`` with
``xi_k = Ad(P1 M) J_body`` forward and ``-Ad(P2) J_body`` backwards
(``J_body`` from :mod:`p105cli.kinematics.pairs`), and a spatial twist
``(v, w)`` changes the residual by ``(v + w x p) / size`` and
``q_w w + w x q_v``.

The unknowns are the values of the pairs in loops that are not driven.
Newton steps are least-squares steps with a round-off-level
regularisation (minimum norm where the Jacobian has lost rank), so
redundant constraints (a planar loop in 3D: 6 equations, rank 3; a
Bennett linkage) and remaining mobility are handled alike. A closing
Newton step from the last evaluation takes the values from the tolerance
to round-off.

Continuation and branches. The initial state is assembled first (its
driven values held, the rest by Levenberg-Marquardt); its assembly branch
is tracked along the input sequence. The branch invariant is the sign of
``det(U0^T J_u V0)``: the passive Jacobian reduced onto rank-r bases of
its column and row spaces, re-anchored (Procrustes-aligned) at every
accepted configuration. It can only change sign where the passive
Jacobian loses rank (a dead centre or a bifurcation), so a sign change
between two accepted configurations is a branch change and never accepted
silently. Configurations are solved in chunks from a tangent predictor
(``dq_u = -J_u^+ J_d dd``); a solution is accepted only if Newton
converged, the configuration is regular, the sign is the tracked one and
it lies where the first-order step from its predecessor puts it (up to
that step's size: a jump to another branch at a bifurcation is as large);
otherwise the chunk shrinks, and a single step is halved (down to 1/4096)
before the configuration is diagnosed: ``singular`` (converged with the
passive Jacobian rank-deficient: a dead centre; or a bifurcation passed
between two samples), ``branch_change`` (only the other branch could be
reached: the new branch is tracked from then on), ``not_assemblable``
(the least-squares residual stalls above the tolerance: reported with
it), ``not_converged``. The invariant is +1 at the initial assembly (the
bases are its singular vectors); ``branch=-1`` starts instead from another
assembly at the same driven values with invariant -1 (in those bases),
found by a deterministic multi-start Levenberg-Marquardt
(:func:`_other_assembly`).

Inverse analysis (:func:`solve_path`)
-------------------------------------

A link frame follows prescribed poses: damped least squares on the pose
error (position of the frame's origin in metres, rotation vector in
radians, world axes), analytic geometric Jacobians, the damping raised
only near singular configurations (so the answer is the exact one away
from them and finite through them), warm started along the path.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from .spatial import adjoint
from .placements import inverse

__all__ = ["Plan", "plan", "forward", "MotionResult", "solve_motion", "PathResult", "solve_path",
           "angle_value_mask", "STATUSES", "SolveError", "BranchUndefined"]

#: Status of a configuration, from best to worst (records and the summary use these words).
STATUSES = ("ok", "out_of_range", "singular", "branch_change", "not_converged", "not_assemblable")

_PERIODIC_KINDS = ("revolute", "cylindrical", "universal", "homokinetic", "planar")
_MAX_HALVINGS = 12
_MAX_CHUNK = 1024   # configurations solved together at most
_K0 = 64            # the first chunk after the initial state


class SolveError(ValueError):
    """A request the solver cannot honour (unknown pair, no path to a link...)."""


# --------------------------------------------------------------------------- structure

class BranchUndefined(SolveError):
    """A branch was asked for (``branch=+1/-1``) where the invariant is not defined: no loop
    unknowns, the passive values not fixed by the loops, or a singular initial state."""


@dataclass
class Plan:
    """A mechanism compiled for evaluation (immutable description + index arrays)."""

    mech: object
    link_names: tuple
    link_index: dict
    pair_names: tuple
    slices: list                 # flat value slice of each pair
    angle_mask: np.ndarray       # (nv,) True where the value is an angle
    tree: list                   # (pair index, parent link index, child link index, forward)
    loops: list                  # [[(pair index, forward), ...], ...]
    size: float
    P1: np.ndarray               # (np, 4, 4)
    P2: np.ndarray
    P2inv: np.ndarray
    AdP2: np.ndarray             # (np, 6, 6)
    params: list                 # motion parameters per pair
    types: list
    parent_of: dict = field(default_factory=dict)   # link index -> tree entry index

    @property
    def nv(self) -> int:
        return int(self.angle_mask.size)

    def loop_values(self) -> np.ndarray:
        """Flat indices of the values of every pair that lies on a loop."""
        idx = sorted({i for lp in self.loops for k, _ in lp for i in range(*self.slices[k].indices(self.nv))})
        return np.array(idx, dtype=int)


def angle_value_mask(pair) -> list:
    """Which of a pair's values are angles (the rest are lengths): ``PairType.value_units``."""
    return list(pair.type.angle_mask)


def _structure(mech):
    """Spanning tree and independent loops, from :func:`p105cli.kinematics.graph.analyse`."""
    from .graph import analyse

    s = analyse(mech)
    return list(s.order), list(s.tree), [list(lp) for lp in s.loops]


def plan(mech) -> Plan:
    """Compile ``mech`` (a :class:`p105cli.kinematics.model.Mechanism`) for the solvers."""
    order, tree, loops = _structure(mech)
    missing = [n for n in mech.link_names if n not in order]
    if missing:
        raise SolveError(f"mechanism {mech.name!r}: links {missing} are not connected to the base "
                         f"link {mech.base!r}")
    link_index = {n: i for i, n in enumerate(order)}
    pair_index = {p.name: i for i, p in enumerate(mech.pairs)}
    slices, mask = [], []
    for p in mech.pairs:
        slices.append(mech.value_slices[p.name])
        mask.extend(angle_value_mask(p))
    P1 = np.array([p.P1 for p in mech.pairs]).reshape(-1, 4, 4)
    P2 = np.array([p.P2 for p in mech.pairs]).reshape(-1, 4, 4)
    P2inv = inverse(P2) if len(P2) else P2
    AdP2 = adjoint(P2) if len(P2) else np.zeros((0, 6, 6))
    tree_idx = [(pair_index[pn], link_index[u], link_index[v], bool(f)) for pn, u, v, f in tree]
    parent_of = {c: k for k, (_, _, c, _) in enumerate(tree_idx)}
    return Plan(mech, tuple(order), link_index, tuple(mech.pair_names), slices, np.array(mask, dtype=bool),
                tree_idx, [[(pair_index[pn], bool(f)) for pn, f in lp] for lp in loops], mech.size(),
                P1, P2, P2inv, AdP2, [p.motion_params() for p in mech.pairs], [p.type for p in mech.pairs],
                parent_of)


# --------------------------------------------------------------------------- evaluation

def _pair_T(pl: Plan, k: int, Q) -> np.ndarray:
    """(B, 4, 4) ``T_link1_link2`` of pair k for flat values Q (B, nv)."""
    t, sl = pl.types[k], pl.slices[k]
    if t.kind == "revolute":
        # P1 Rz(q) P2^-1 = C0 + cos q C1 + sin q C2: elementwise, no matrix product (and no
        # BLAS call, whose threads only cost time on (B x 3) operands).
        C = _revolute_consts(pl, k)
        q = Q[:, sl.start]
        return C[0] + np.cos(q)[:, None, None] * C[1] + np.sin(q)[:, None, None] * C[2]
    M = t.motion(Q[:, sl], **pl.params[k])
    return pl.P1[k] @ M @ pl.P2inv[k]


_E = (np.diag([0.0, 0.0, 1.0, 1.0]), np.diag([1.0, 1.0, 0.0, 0.0]),
      np.array([[0.0, -1.0, 0, 0], [1.0, 0.0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]]))


def _revolute_consts(pl: Plan, k: int):
    cache = pl.__dict__.setdefault("_rev", {})
    if k not in cache:
        cache[k] = np.array([pl.P1[k] @ E @ pl.P2inv[k] for E in _E])
    return cache[k]


def _const_twists(pl: Plan, k: int, fwd: bool):
    """Left twists (6, n) of a revolute or prismatic pair: they do not depend on the value."""
    cache = pl.__dict__.setdefault("_const", {})
    key = (k, fwd)
    if key not in cache:
        t = pl.types[k]
        if t.kind == "revolute" or (t.kind == "prismatic"):
            Jb = t.motion_jacobian(np.zeros(1), **pl.params[k])
            M = t.motion(np.zeros(1), **pl.params[k])
            # Rz(q) and Tz(s) leave their own axis fixed: Ad(P1 M) J = Ad(P1) J for every value.
            cache[key] = adjoint(pl.P1[k] @ M) @ Jb if fwd else -(pl.AdP2[k] @ Jb)
        else:
            cache[key] = None
    return cache[key]


def _left_twists(pl: Plan, k: int, Q, fwd: bool) -> np.ndarray:
    """(B, 6, n_k) or (6, n_k): twists of the factor (pair k, forward or backwards) in its left frame."""
    X = _const_twists(pl, k, fwd)
    if X is not None:
        return X
    t, sl = pl.types[k], pl.slices[k]
    Jb = t.motion_jacobian(Q[:, sl], **pl.params[k])
    if fwd:
        M = t.motion(Q[:, sl], **pl.params[k])
        return adjoint(pl.P1[k] @ M) @ Jb
    return -(pl.AdP2[k] @ Jb)


def _ad(T, X) -> np.ndarray:
    """``adjoint(T) @ X`` for T (B, 4, 4) and twists X (B, 6, n) or (6, n), without forming Ad."""
    B, n = T.shape[0], X.shape[-1]
    R, p = T[:, :3, :3], T[:, :3, 3:]
    out = np.empty((B, 6, n))
    w = np.matmul(R, X[..., 3:, :], out=out[:, 3:])
    v = np.matmul(R, X[..., :3, :], out=out[:, :3])
    v[:, 0] += p[:, 1] * w[:, 2] - p[:, 2] * w[:, 1]
    v[:, 1] += p[:, 2] * w[:, 0] - p[:, 0] * w[:, 2]
    v[:, 2] += p[:, 0] * w[:, 1] - p[:, 1] * w[:, 0]
    return out


def _inv(T) -> np.ndarray:
    """Rigid inverse of (B, 4, 4) (no argument checks: internal hot path)."""
    out = np.zeros(T.shape)
    Rt = np.swapaxes(T[..., :3, :3], -1, -2)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -(Rt @ T[..., :3, 3:])[..., 0]
    out[..., 3, 3] = 1.0
    return out


_FK_BLOCK = 4096   # configurations per block in forward(): the block's link placements stay in cache


def _z_commutes(L) -> bool:
    """True when the rigid transform L is a rotation about z and a shift along z (so
    ``L Rz(q) = Rz(q) L``: the constant can move to the other side of the joint rotation)."""
    R, t = L[:3, :3], L[:3, 3]
    return (abs(R[2, 2] - 1.0) <= 4e-16 and max(abs(R[0, 2]), abs(R[1, 2]), abs(R[2, 0]), abs(R[2, 1])) <= 4e-16
            and max(abs(t[0]), abs(t[1])) <= 1e-15 * (1.0 + abs(t[2])))


def _forward_steps(pl: Plan):
    """Per tree entry: ``(k, parent, child, fwd, col, sgn, L, R)`` with ``A = L Rz(sgn q) R`` for a
    revolute pair (L None when it folds into R), ``col`` None for any other pair."""
    cache = pl.__dict__.get("_fk")
    if cache is not None:
        return cache
    steps = []
    for k, parent, child, fwd in pl.tree:
        if pl.types[k].kind != "revolute":
            steps.append((k, parent, child, fwd, None, 1.0, None, None))
            continue
        # T_link1_link2 = P1 Rz(q) P2^-1; crossed backwards P2 Rz(-q) P1^-1.
        L, R = (pl.P1[k], pl.P2inv[k]) if fwd else (pl.P2[k], inverse(pl.P1[k]))
        if _z_commutes(L):
            L, R = None, L @ R
        steps.append((k, parent, child, fwd, pl.slices[k].start, 1.0 if fwd else -1.0, L, np.ascontiguousarray(R)))
    pl.__dict__["_fk"] = steps
    return steps


def forward(pl: Plan, Q, *, world: bool = True) -> np.ndarray:
    """Placements of every link (B, n_links, 4, 4) in ``pl.link_names`` order for values Q (B, nv).

    The tree is followed from the base; loop closure is the caller's business
    (pass solved values). ``world`` prepends ``T_world_base``."""
    Q = np.atleast_2d(np.asarray(Q, dtype=np.float64))
    B = Q.shape[0]
    steps = _forward_steps(pl)
    # Link-major storage: each link's placements are contiguous (B, 4, 4) blocks, so a block of
    # them is a (4b, 4) matrix and a constant factor is one BLAS product on it.
    out = np.empty((len(pl.link_names), B, 4, 4))
    out[0] = pl.mech.T_world_base if world else np.eye(4)
    cols = [s[4] for s in steps if s[4] is not None]
    sgn = np.array([s[5] for s in steps if s[4] is not None])
    b = min(_FK_BLOCK, max(B, 1))
    W = np.empty((b, 4, 4))
    t0, t1 = np.empty((b, 4)), np.empty((b, 4))
    for i0 in range(0, B, b):
        i1 = min(B, i0 + b)
        n = i1 - i0
        q = Q[i0:i1]
        if cols:
            qr = q[:, cols]
            C, S = np.cos(qr), np.sin(qr)
            if (sgn < 0).any():
                S *= sgn
        w, a, c_ = W[:n], t0[:n], t1[:n]
        w0, w1 = w[:, :, 0], w[:, :, 1]
        j = 0
        for k, parent, child, fwd, col, _, L, R in steps:
            P = out[parent, i0:i1]
            dst = out[child, i0:i1]
            if col is None:
                T = _pair_T(pl, k, q)
                np.matmul(P, T if fwd else _inv(T), out=dst)
                continue
            # T_child = T_parent L Rz(q) R: Rz(q) on the right turns columns 0 and 1 only. Blocks
            # of 4096 keep the (4b, 4) BLAS products single-threaded (OpenBLAS starts threads
            # from about 16 000 configurations on, which made them four times slower here).
            c, s = C[:, j, None], S[:, j, None]
            j += 1
            if L is None:
                y0, y1 = P[:, :, 0], P[:, :, 1]
                w[:, :, 2:] = P[:, :, 2:]
            else:
                np.matmul(P.reshape(-1, 4), L, out=w.reshape(-1, 4))
                y0, y1 = w0, w1
            np.multiply(y1, c, out=a)
            np.multiply(y0, s, out=c_)
            np.subtract(a, c_, out=a)                      # new column 1
            np.multiply(y0, c, out=c_)
            np.multiply(y1, s, out=w0)
            np.add(w0, c_, out=w0)                         # new column 0
            w1[...] = a
            np.matmul(w.reshape(-1, 4), R, out=dst.reshape(-1, 4))
    return np.moveaxis(out, 0, 1)


def _scale(pl: Plan) -> np.ndarray:
    """Per-value scale that makes lengths dimensionless (1 for angles, 1/size for lengths)."""
    return np.where(pl.angle_mask, 1.0, 1.0 / pl.size)


def _jl_map():
    """(7, 36): the residual Jacobian's map M (6, 6) from the twist, linear in
    y = (p / size, q_v, q_w) (the constant 1/size diagonal is set separately)."""
    m = np.zeros((7, 6, 6))
    for i, (j, k) in enumerate(((1, 2), (2, 0), (0, 1))):
        # row i: (w x y)_i = w_j y_k - w_k y_j, for y = p / size (rows 0-2) and y = q_v (rows 3-5)
        for base in (0, 3):
            m[base + k, base + i, 3 + j] = 1.0
            m[base + j, base + i, 3 + k] = -1.0
        m[6, 3 + i, 3 + i] = 1.0
    return m.reshape(7, 36)


_JL_MAP = _jl_map()
_I3 = np.arange(3)


def closure(pl: Plan, Q, *, jacobian: bool = True):
    """Loop residuals r (B, 6L) and their Jacobian dr/dq (B, 6L, nv), dimensionless.

    ``r = (p / size, vee(R - R^T) / 2)`` per loop of ``T_loop = [R, p]``."""
    Q = np.atleast_2d(Q)
    B, L = Q.shape[0], len(pl.loops)
    r = np.zeros((B, 6 * L))
    J = np.zeros((B, 6 * L, pl.nv)) if jacobian else None
    for li, lp in enumerate(pl.loops):
        rev = _revolute_loop(pl, li)
        if rev is not None:
            T, S, idx = _revolute_loop_terms(rev, Q, jacobian)
            idx = list(idx)
            blocks = [S] if jacobian else []
            lp = ()
        else:
            T = None
            blocks, idx = [], []
        for k, fwd in lp:
            if jacobian:
                X = _left_twists(pl, k, Q, fwd)
                blocks.append(np.broadcast_to(X, (B,) + X.shape[-2:]) if T is None else _ad(T, X))
                idx.extend(range(pl.slices[k].start, pl.slices[k].stop))
            A = _pair_T(pl, k, Q)
            A = A if fwd else _inv(A)
            T = A if T is None else T @ A
        R, p = T[:, :3, :3], T[:, :3, 3]
        r[:, 6 * li:6 * li + 3] = p / pl.size
        qw, qv = _half_quaternion(R)
        r[:, 6 * li + 3:6 * li + 6] = 2.0 * qv
        if jacobian and idx:
            S = blocks[0] if len(blocks) == 1 else np.concatenate(blocks, axis=-1)  # spatial twists
            # d(p / size) = (v + w x p) / size;  d(2 q_v) = q_w w + w x q_v  (left perturbation):
            # Jl = M S with M (B, 6, 6) linear in (p / size, q_v, q_w), one product.
            y = np.empty((B, 7))
            np.divide(p, pl.size, out=y[:, :3])
            y[:, 3:6] = qv
            y[:, 6] = qw
            M = np.matmul(y, _JL_MAP).reshape(B, 6, 6)
            M[:, _I3, _I3] = 1.0 / pl.size
            J[:, 6 * li:6 * li + 6, idx] = M @ S   # a loop owns its rows; a pair appears once in it
    return r, J


def _half_quaternion(R):
    """Unit quaternion (w >= 0, v) of rotations R (B, 3, 3).

    The loop residual's rotation part is ``2 v`` (about the rotation vector near the
    identity), which vanishes only at the identity: ``vee(R - R^T) / 2`` would also vanish
    at every half-turn, where Newton can land (a gear train did)."""
    tr = R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2]
    d = np.empty(R.shape[:1] + (3,))
    np.subtract(R[:, 2, 1], R[:, 1, 2], out=d[:, 0])
    np.subtract(R[:, 0, 2], R[:, 2, 0], out=d[:, 1])
    np.subtract(R[:, 1, 0], R[:, 0, 1], out=d[:, 2])
    w = 0.5 * np.sqrt(np.maximum(1.0 + tr, 0.0))
    far = w < 0.3  # beyond about 145 degrees: Shepperd's pivoting, no division by a small w
    if not far.any():
        return w, d / (4.0 * w)[:, None]
    v = d / (4.0 * np.where(far, 1.0, w))[:, None]
    from .placements import matrix_to_quaternion
    qf = matrix_to_quaternion(R[far])
    w = w.copy()
    w[far], v[far] = qf[:, 0], qf[:, 1:]
    return w, v


def _revolute_loop(pl: Plan, li: int):
    """Constants of a loop of revolute pairs only (None otherwise): every factor, forward or
    backwards, is ``E0 + cos q E1 + sin q E2`` (backwards: ``P2 Rz(-q) P1^-1``), stored as
    (n, 3, 16); and every left twist is constant: ``sgn (p x z, z)`` of the joint axis (z, p)
    in the factor's left frame (P1 forward, P2 backwards), kept as homogeneous columns
    (n, 4, 2) so that the twists in the loop's start frame are one product with the prefix
    placements."""
    cache = pl.__dict__.setdefault("_revloops", {})
    if li in cache:
        return cache[li]
    lp = pl.loops[li]
    if not lp or any(pl.types[k].kind != "revolute" for k, _ in lp):
        cache[li] = None
        return None
    E, H, X, sig, cols = [], [], [], [], []
    P1inv = inverse(pl.P1)
    for k, fwd in lp:
        if fwd:
            E.append([(pl.P1[k] @ e @ pl.P2inv[k]).ravel() for e in _E])
        else:
            E.append([(pl.P2[k] @ e @ P1inv[k] * sgn).ravel() for e, sgn in zip(_E, (1.0, 1.0, -1.0))])
        F = pl.P1[k] if fwd else pl.P2[k]
        H.append(np.stack([np.r_[F[:3, 2], 0.0], np.r_[F[:3, 3], 1.0]], axis=1))
        X.append(_const_twists(pl, k, fwd)[:, 0])
        sig.append(1.0 if fwd else -1.0)
        cols.append(pl.slices[k].start)
    cache[li] = (np.array(E), np.array(H), np.array(X), np.array(sig), np.array(cols))
    return cache[li]


def _revolute_loop_terms(rev, Q, jacobian):
    """T_loop (B, 4, 4) and the spatial twists (B, 6, n) of a revolute loop, all factors at once."""
    E, H, X, sig, cols = rev
    n, B = len(cols), Q.shape[0]
    q = Q[:, cols].T                                                   # (n, B)
    # A = E0 + cos q E1 + sin q E2, in this order (the residual's round-off, hence the last
    # bits of the converged values, do not depend on how this is vectorised).
    A = np.multiply(np.cos(q)[..., None], E[:, None, 1])                # (n, B, 16)
    A += E[:, None, 0]
    A += np.sin(q)[..., None] * E[:, None, 2]
    A = A.reshape(n, B, 4, 4)
    if n == 1:
        prefix = A
    else:
        prefix = np.empty((n, B, 4, 4))
        np.matmul(A[0], A[1], out=prefix[1])
        prefix[0] = A[0]
        for k in range(2, n):
            np.matmul(prefix[k - 1], A[k], out=prefix[k])
    if not jacobian:
        return prefix[-1], None, cols
    S = np.empty((B, 6, n))
    S[:, :, 0] = X[0]
    if n > 1:
        # (n-1, B, 4, 2): each prefix block as one (4B, 4) matrix times its factor's axis
        G = np.matmul(prefix[:-1].reshape(n - 1, 4 * B, 4), H[1:]).reshape(n - 1, B, 4, 2)
        w = G[:, :, :3, 0] * sig[1:, None, None]                          # (n-1, B, 3)
        p = G[:, :, :3, 1]
        Sv, Sw = S[:, :3, 1:], S[:, 3:, 1:]                               # (B, 3, n-1) views
        Sw[...] = w.transpose(1, 2, 0)
        Sv[:, 0] = (p[..., 1] * w[..., 2] - p[..., 2] * w[..., 1]).T      # v = p x w
        Sv[:, 1] = (p[..., 2] * w[..., 0] - p[..., 0] * w[..., 2]).T
        Sv[:, 2] = (p[..., 0] * w[..., 1] - p[..., 1] * w[..., 0]).T
    return prefix[-1], S, cols


def _loop_errors(pl: Plan, Q):
    """Per configuration: largest loop position error (metres) and rotation error (radians)."""
    Q = np.atleast_2d(Q)
    B = Q.shape[0]
    pos, rot = np.zeros(B), np.zeros(B)
    for lp in pl.loops:
        T = None
        for k, fwd in lp:
            A = _pair_T(pl, k, Q)
            A = A if fwd else _inv(A)
            T = A if T is None else T @ A
        if T is None:
            continue
        pos = np.maximum(pos, np.linalg.norm(T[:, :3, 3], axis=-1))
        c = np.clip(0.5 * (T[:, 0, 0] + T[:, 1, 1] + T[:, 2, 2] - 1.0), -1.0, 1.0)
        s = 0.5 * np.linalg.norm(np.stack([T[:, 2, 1] - T[:, 1, 2], T[:, 0, 2] - T[:, 2, 0],
                                           T[:, 1, 0] - T[:, 0, 1]], axis=-1), axis=-1)
        rot = np.maximum(rot, np.arctan2(s, c))
    return pos, rot


# --------------------------------------------------------------------------- Newton on the loops

@dataclass
class _Loops:
    """The loop problem for a fixed split of the values into driven and unknown."""

    pl: Plan
    u: np.ndarray           # flat indices of the unknowns
    d: np.ndarray           # flat indices of the driven values
    scale_u: np.ndarray     # per-unknown scale (1/size for lengths)
    scale_d: np.ndarray     # per-driven-value scale
    tol: float
    max_iter: int
    rank: int = 0
    U0: np.ndarray = None
    V0: np.ndarray = None
    rcond: float = 1e-10

    def evaluate(self, Q):
        """Residual and the Jacobian columns of the unknowns and of the driven values, per
        scaled value (lengths / size): dimensionless, so steps do not depend on the unit."""
        r, J = closure(self.pl, Q)
        Ju, Jd = J[:, :, self.u], J[:, :, self.d]
        if not self._unit_u:
            Ju /= self.scale_u
        if not self._unit_d:
            Jd /= self.scale_d
        return r, Ju, Jd

    def __post_init__(self):
        self._unit_u = bool(np.all(self.scale_u == 1.0))
        self._unit_d = bool(np.all(self.scale_d == 1.0))

    def sign(self, Ju) -> np.ndarray:
        """Branch invariant: sign of det(U0^T J_u V0) (0 when there is no loop unknown)."""
        if self.U0 is None or self.rank == 0:
            return np.zeros(Ju.shape[0])
        return np.sign(np.linalg.det(np.swapaxes(self.U0, -1, -2) @ Ju @ self.V0))

    def reanchor(self, Ju) -> float:
        """Move the bases U0, V0 of the invariant to the configuration of ``Ju`` (1, rows, m),
        aligned (orthogonal Procrustes) with the current ones, and return the sign there.

        A redundant system's column space turns with the mechanism (two planar loops: a
        4-dimensional space inside a 6-dimensional one); bases fixed at the initial state would
        make the projected determinant vanish where the mechanism is regular. Re-anchored at
        every accepted configuration, the bases follow it continuously."""
        if self.U0 is None or self.rank == 0:
            return 0.0
        U, S, Vt = np.linalg.svd(Ju[0])
        r = self.rank

        def align(new, old):
            a, _, bt = np.linalg.svd(new.T @ old)
            return new @ (a @ bt)
        self.U0 = align(U[:, :r], self.U0)
        self.V0 = align(Vt[:r].T, self.V0)
        return float(np.sign(np.linalg.det(self.U0.T @ Ju[0] @ self.V0)))

    @property
    def singular_below(self) -> float:
        """Conditioning under which a converged configuration is a dead centre: Newton stops
        about sqrt(tol) from a fold, where the conditioning is of that order."""
        return max(1e-7, 10.0 * math.sqrt(self.tol))

    def conditioning(self, Ju) -> np.ndarray:
        """Ratio of the rank-th to the largest singular value of J_u (0: singular)."""
        if self.rank == 0:
            return np.ones(Ju.shape[0])
        S = np.linalg.svd(Ju, compute_uv=False)
        return S[:, self.rank - 1] / np.maximum(S[:, 0], 1e-300)

    def step(self, r, Ju):
        """Newton step on the unknowns: least squares by the normal equations, with a
        regularisation at the round-off level (the minimum-norm step where J_u has lost rank)."""
        JtJ = np.swapaxes(Ju, -1, -2) @ Ju
        g = np.einsum("bij,bi->bj", Ju, r)
        m = JtJ.shape[-1]
        mu = 1e-13 * np.trace(JtJ, axis1=-2, axis2=-1) + 1e-300
        JtJ[:, np.arange(m), np.arange(m)] += mu[:, None]
        try:
            return -np.linalg.solve(JtJ, g[..., None])[..., 0]
        except np.linalg.LinAlgError:
            return self.step_svd(r, Ju)

    def step_svd(self, r, Ju):
        """Minimum-norm Newton step on the unknowns (SVD, small singular values cut)."""
        U, S, Vt = np.linalg.svd(Ju, full_matrices=False)
        keep = S > self.rcond * np.maximum(S[:, :1], 1e-300)
        inv = np.where(keep, 1.0 / np.where(keep, S, 1.0), 0.0)
        c = np.einsum("bji,bj->bi", U, r) * inv
        return -np.einsum("bij,bi->bj", Vt, c)

    def newton(self, Q, *, max_iter=None, damped=False):
        """Newton (or Levenberg-Marquardt, ``damped``) on the unknowns of Q (B, nv), in place.

        Returns (converged (B,), residual (B,), iterations (B,), J_u at the end, stalled (B,)).
        ``self.last_Jd`` keeps J_d at the end (for the next tangent)."""
        max_iter = self.max_iter if max_iter is None else max_iter
        if not damped:
            return self._newton_plain(Q, max_iter)
        B = Q.shape[0]
        it = np.zeros(B, dtype=int)
        r, Ju, Jd = self.evaluate(Q)
        res = np.abs(r).max(axis=1) if r.shape[1] else np.zeros(B)
        stalled = np.zeros(B, dtype=bool)
        done = res <= self.tol
        lam = np.full(B, 1e-3)
        for _ in range(max_iter):
            active = ~done & ~stalled
            if not active.any():
                break
            a = np.flatnonzero(active)
            dq = self._lm_step(r[a], Ju[a], lam[a])
            big = np.abs(dq).max(axis=1)
            dq *= np.minimum(1.0, 1.0 / np.maximum(big, 1e-300))[:, None]
            Qt = Q[a].copy()
            Qt[:, self.u] += dq / self.scale_u
            rt, Jt, Jdt = self.evaluate(Qt)
            rest = np.abs(rt).max(axis=1)
            ok = rest < res[a] * (1.0 - 1e-4) + 1e-300
            lam[a] = np.where(ok, lam[a] * 0.3, lam[a] * 10.0)
            stalled[a] = (~ok) & (lam[a] > 1e8)
            if not ok.all():
                # No progress: stationary when the gradient vanishes relative to J and r.
                g = np.linalg.norm(np.einsum("bij,bi->bj", Ju[a], r[a]), axis=1)
                nj = np.linalg.norm(Ju[a], axis=(1, 2)) * np.linalg.norm(r[a], axis=1)
                stalled[a] |= (~ok) & (g <= 1e-12 * np.maximum(nj, 1e-300))
            acc = a[ok]
            Q[acc] = Qt[ok]
            r[acc], Ju[acc], Jd[acc], res[acc] = rt[ok], Jt[ok], Jdt[ok], rest[ok]
            done[acc] = rest[ok] <= self.tol
            it[a] += 1
        self.last_Jd = Jd
        return done, res, it, Ju, stalled

    def _newton_plain(self, Q, max_iter):
        """:meth:`newton` without damping: the hot path of the continuation, so the whole batch
        is updated in place while every configuration is still iterating (no index copies)."""
        B = Q.shape[0]
        it = np.zeros(B, dtype=int)
        r, Ju, Jd = self.evaluate(Q)
        res = np.abs(r).max(axis=1) if r.shape[1] else np.zeros(B)
        stalled = np.zeros(B, dtype=bool)
        done = res <= self.tol
        u = self.u
        for _ in range(max_iter):
            act = ~(done | stalled)
            if not act.any():
                break
            full = bool(act.all())
            a = slice(None) if full else np.flatnonzero(act)
            dq = self.step(r[a], Ju[a])
            # Keep a step within a radian (or a model size): far guesses must not jump branches.
            big = np.abs(dq).max(axis=1)
            np.multiply(dq, np.minimum(1.0, 1.0 / np.maximum(big, 1e-300))[:, None], out=dq)
            if not self._unit_u:
                dq /= self.scale_u
            if full:
                Q[:, u] += dq
                rt, Jt, Jdt = self.evaluate(Q)
            else:
                Qa = Q[a]
                Qa[:, u] += dq
                Q[a] = Qa
                rt, Jt, Jdt = self.evaluate(Qa)
            rest = np.abs(rt).max(axis=1)
            prev = res[a]
            # Accepted anyway (a line search would fight quadratic convergence at the noise
            # floor), but a rise of the residual after three iterations counts as stalling.
            stalled[a] = (rest >= prev * (1.0 - 1e-4)) & (rest > 10 * self.tol) & (it[a] > 3)
            # Converged, or converging quadratically so fast that the closing step below lands
            # under the tolerance: r_next ~ C r^2 with C = r / r_prev^2.
            C = rest / np.maximum(prev, 1e-300) ** 2
            fin = (rest <= self.tol) | ((rest < 1e-4) & (rest < 0.1 * prev) & (C * rest * rest <= 0.01 * self.tol))
            if full:
                r, Ju, Jd, res, done = rt, Jt, Jdt, rest, fin
            else:
                r[a], Ju[a], Jd[a], res[a], done[a] = rt, Jt, Jdt, rest, fin
            it[a] += 1
        self.last_Jd = Jd
        if done.any():
            # One more Newton step from the last evaluation (no new one): quadratic convergence
            # takes the error from about the tolerance to round-off, so the answer is good to
            # the tolerance itself and not only its residual. Only where it is a small correction.
            c = np.flatnonzero(done & (res > 0.0))
            if len(c):
                dq = self.step(r[c], Ju[c])
                small = np.abs(dq).max(axis=1) <= 1e-3
                Q[np.ix_(c[small], u)] += dq[small] / self.scale_u
                res[c[small]] = np.minimum(res[c[small]], self.tol)
        return done & (res <= self.tol), res, it, Ju, stalled

    def _lm_step(self, r, Ju, lam):
        U, S, Vt = np.linalg.svd(Ju, full_matrices=False)
        f = S / (S * S + (lam[:, None] * np.maximum(S[:, :1], 1e-300)) ** 2)
        c = np.einsum("bji,bj->bi", U, r) * f
        return -np.einsum("bij,bi->bj", Vt, c)

    def conditioning_and_tangent(self, Ju, Jd):
        """:meth:`conditioning` and :meth:`tangent` from one SVD of J_u.

        When J_u has full column rank (the common case) the regular configurations skip the
        SVD: the conditioning estimated from the eigenvalues of J_u^T J_u (about eps / cond^2
        off) is far enough above :attr:`singular_below` to decide, and the pseudo-inverse is
        then the plain inverse ``(J_u^T J_u)^-1 J_u^T`` (no singular value is cut). Only the
        others (near or below the threshold) take the SVD, so the decisions are the SVD's."""
        B, m = Ju.shape[0], Ju.shape[-1]
        if self.rank == m and m and B > 1:   # (one configuration: the SVD costs the same)
            Jt = np.swapaxes(Ju, -1, -2)
            JtJ = Jt @ Ju
            lam = np.linalg.eigvalsh(JtJ)
            est = np.sqrt(np.maximum(lam[:, 0], 0.0) / np.maximum(lam[:, -1], 1e-300))
            easy = est > 4.0 * self.singular_below
            if easy.any():
                cond = est.copy()
                T = np.empty((B, m, Jd.shape[-1]))
                e = slice(None) if easy.all() else np.flatnonzero(easy)
                T[e] = np.linalg.solve(JtJ[e], Jt[e] @ Jd[e])
                T *= -self.scale_d[None, None, :] / self.scale_u[None, :, None]
                if not easy.all():
                    h = np.flatnonzero(~easy)
                    cond[h], T[h] = self._conditioning_and_tangent_svd(Ju[h], Jd[h])
                return cond, T
        return self._conditioning_and_tangent_svd(Ju, Jd)

    def _conditioning_and_tangent_svd(self, Ju, Jd):
        U, S, Vt = np.linalg.svd(Ju, full_matrices=False)
        if self.rank == 0:
            cond = np.ones(Ju.shape[0])
        else:
            cond = S[:, self.rank - 1] / np.maximum(S[:, 0], 1e-300)
        keep = S > self.rcond * np.maximum(S[:, :1], 1e-300)
        inv = np.where(keep, 1.0 / np.where(keep, S, 1.0), 0.0)
        pinv = np.swapaxes(Vt, -1, -2) @ (inv[:, :, None] * np.swapaxes(U, -1, -2))
        return cond, -(pinv @ Jd) * self.scale_d[None, None, :] / self.scale_u[None, :, None]

    def tangent(self, Q, Ju=None, Jd=None):
        """dq_u/dd at Q (B, nv): (B, nu, nd), in SI units of the values (J_u, J_d there if known)."""
        if Ju is None:
            r, Ju, Jd = self.evaluate(Q)
        U, S, Vt = np.linalg.svd(Ju, full_matrices=False)
        keep = S > self.rcond * np.maximum(S[:, :1], 1e-300)
        inv = np.where(keep, 1.0 / np.where(keep, S, 1.0), 0.0)
        pinv = np.swapaxes(Vt, -1, -2) @ (inv[:, :, None] * np.swapaxes(U, -1, -2))
        return -(pinv @ Jd) * self.scale_d[None, None, :] / self.scale_u[None, :, None]


# --------------------------------------------------------------------------- forward analysis

@dataclass
class MotionResult:
    """Solved configurations: values Q (N, nv) in SI, per-configuration diagnostics."""

    plan: Plan
    Q: np.ndarray
    status: list
    residual: np.ndarray         # dimensionless loop residual (p / size, rotation)
    residual_m: np.ndarray       # largest loop position error, metres
    residual_rad: np.ndarray     # largest loop rotation error, radians
    iterations: np.ndarray
    messages: list
    seconds: float
    driven: np.ndarray           # flat indices of the driven values
    branch: np.ndarray           # branch sign per configuration (0: undefined or singular)

    def links(self) -> np.ndarray:
        """(N, n_links, 4, 4) world placements in ``plan.link_names`` order."""
        return forward(self.plan, self.Q)


def _wrap_periodic(pl: Plan, Q) -> np.ndarray:
    """Angles of periodic pair values as the range reads them: a value outside its range is
    moved by whole turns into it when that is possible (a multi-turn range keeps the value
    the continuation reached); without a range, into (-pi, pi]."""
    Q = Q.copy()
    two_pi = 2.0 * math.pi
    for k, p in enumerate(pl.mech.pairs):
        if p.kind not in _PERIODIC_KINDS:
            continue
        sl = pl.slices[k]
        for j, is_angle in enumerate(angle_value_mask(p)):
            if not is_angle:
                continue
            i = sl.start + j
            v = Q[:, i]
            lo, up = p.lower[j], p.upper[j]
            if lo is None and up is None:
                w = v - two_pi * np.round(v / two_pi)
                Q[:, i] = np.where(w <= -math.pi, w + two_pi, w)
                continue
            eps = 1e-9
            lo_ = -np.inf if lo is None else lo - eps
            up_ = np.inf if up is None else up + eps
            inside = (v >= lo_) & (v <= up_)
            ref = lo_ if lo is not None else up_
            shifted = v + two_pi * (np.ceil((lo_ - v) / two_pi) if lo is not None else np.floor((up_ - v) / two_pi))
            fits = (shifted >= lo_) & (shifted <= up_)
            Q[:, i] = np.where(inside | ~fits, v, shifted)
            del ref
    return Q


def _out_of_range(pl: Plan, Q, rtol=1e-9) -> list:
    """Per configuration, the list of 'pair[j]' values outside their ranges."""
    bad = [[] for _ in range(Q.shape[0])]
    for k, p in enumerate(pl.mech.pairs):
        sl = pl.slices[k]
        for j in range(p.value_count):
            lo, up = p.lower[j], p.upper[j]
            if lo is None and up is None:
                continue
            v = Q[:, sl.start + j]
            eps = rtol * (1.0 if pl.angle_mask[sl.start + j] else pl.size)
            out = np.zeros(v.shape, dtype=bool)
            if lo is not None:
                out |= v < lo - eps
            if up is not None:
                out |= v > up + eps
            for b in np.flatnonzero(out):
                bad[b].append(p.name if p.value_count == 1 else f"{p.name}[{j}]")
    return bad


def _driven_columns(pl: Plan, driven: dict):
    """Flat indices (nd,) and values (N, nd) of the driven values."""
    didx, cols, N = [], [], None
    for key, vals in driven.items():
        name, j = key if isinstance(key, tuple) else (key, None)
        if name not in pl.pair_names:
            raise SolveError(f"{name!r} is not a pair of mechanism {pl.mech.name!r} "
                             f"(pairs: {', '.join(pl.pair_names)})")
        sl = pl.slices[pl.pair_names.index(name)]
        v = np.asarray(vals, dtype=np.float64)
        idx = list(range(sl.start, sl.stop)) if j is None else [sl.start + j]
        v = v.reshape(v.shape[0], -1) if v.ndim else v.reshape(1, 1)
        if v.shape[1] != len(idx):
            raise SolveError(f"pair {name!r} has {len(idx)} value(s), {v.shape[1]} given")
        if N is not None and v.shape[0] != N:
            raise SolveError("driven value columns have different lengths")
        N = v.shape[0]
        didx.extend(idx)
        cols.append(v)
    if len(set(didx)) != len(didx):
        raise SolveError("a pair value is driven twice")
    D = np.concatenate(cols, axis=1) if cols else np.zeros((1 if N is None else N, 0))
    if not np.all(np.isfinite(D)):
        raise SolveError("driven values must be finite numbers")
    return np.array(didx, dtype=int), D


def solve_motion(mech, driven: dict, *, initial=None, tol: float = 1e-10, max_iter: int = 30,
                 pl: Plan | None = None, branch: int | None = None) -> MotionResult:
    """Forward position analysis along a sequence of driven values.

    ``driven`` maps pair names to arrays (N,) or (N, k) of values in SI (a
    ``(name, j)`` key drives value j of a multi-valued pair only). Pairs not
    driven keep their initial-state values unless they lie on a loop, whose
    closure fixes them. ``tol`` is the loop residual relative to the model
    size (lengths) and in radians (rotations). ``branch`` (+1 / -1, None: the initial
    state's) chooses the assembly to track: see :func:`iter_motion`."""
    blocks = list(iter_motion(mech, driven, initial=initial, tol=tol, max_iter=max_iter, pl=pl, block=None,
                              branch=branch))
    return blocks[0]


def iter_motion(mech, driven: dict, *, initial=None, tol: float = 1e-10, max_iter: int = 30,
                pl: Plan | None = None, block: int | None = 4096, branch: int | None = None):
    """:func:`solve_motion` in consecutive blocks of ``block`` configurations (all at once when
    None): one :class:`MotionResult` per block, the continuation (values, branch) carried
    from block to block, so a long sequence streams in bounded memory.

    ``branch``: None tracks the assembly of the initial state (its invariant is +1 by
    construction: the bases are anchored there). +1 asks for that same assembly, -1 for the
    other one at the initial state's driven values (:func:`_other_assembly`); either raises
    :class:`BranchUndefined` where the invariant is not defined."""
    if branch not in (None, 1, -1):
        raise ValueError("branch must be None, +1 or -1")
    pl = pl or plan(mech)
    q0 = mech.initial_vector() if initial is None else np.asarray(initial, dtype=np.float64).copy()
    d, D = _driven_columns(pl, driven)
    N = D.shape[0]
    loopv = pl.loop_values()
    dset = set(d.tolist())
    u = np.array([i for i in loopv if i not in dset], dtype=int)
    sc = _scale(pl)
    prob = _Loops(pl, u, d, sc[u], sc[d], tol, max_iter)
    prob.want = branch
    if branch is not None and (len(u) == 0 or not pl.loops):
        raise BranchUndefined("the mechanism has no closed loop" if not pl.loops else
                              "every value of its loops is driven: no assembly to choose")
    state = None
    step = N if not block else block
    for start in range(0, N, step):
        t0 = time.perf_counter()
        Db = D[start:start + step]
        n = Db.shape[0]
        Q = np.tile(q0, (n, 1))
        Q[:, d] = Db
        status, messages = ["ok"] * n, [""] * n
        iters, branch = np.zeros(n, dtype=int), np.zeros(n)
        if len(u) == 0 or not pl.loops:
            # A tree (or loops fully driven): nothing to solve, residuals still reported.
            res = np.abs(closure(pl, Q, jacobian=False)[0]).max(axis=1) if pl.loops else np.zeros(n)
            for b in np.flatnonzero(res > tol):
                status[b], messages[b] = "not_assemblable", "the driven values do not close the loops"
        else:
            state = _continuation(prob, q0, Q, Db, status, messages, iters, branch, state)
        pos, rot = _loop_errors(pl, Q) if pl.loops else (np.zeros(n), np.zeros(n))
        res = np.maximum(pos / pl.size, rot)
        for b in np.flatnonzero(res > 10.0 * tol):
            # The closing Newton step is not re-evaluated during the solve: checked here.
            if status[b] in ("ok", "singular", "branch_change"):
                status[b] = "not_converged"
                messages[b] = f"loop residual {res[b]:.3g} above the tolerance"
        Qw = _wrap_periodic(pl, Q)
        for b, names in enumerate(_out_of_range(pl, Qw)):
            if names and status[b] == "ok":
                status[b] = "out_of_range"
                messages[b] = "outside its range: " + ", ".join(names)
        yield MotionResult(pl, Qw, status, res, pos, rot, iters, messages, time.perf_counter() - t0, d, branch)


def _continuation(prob: _Loops, q0, Q, D, status, messages, iters, branch, state=None):
    """Solve every configuration of Q (rows; driven columns set) by continuation from q0, or
    from ``state`` (where a previous block ended). Returns the state to continue from."""
    if state is not None:
        return _follow(prob, state, Q, D, status, messages, iters, branch)
    if getattr(prob, "missing", None):   # a later block: the requested branch was not found before
        status[:], messages[:] = ["not_assemblable"] * Q.shape[0], [prob.missing] * Q.shape[0]
        return None
    # Assemble the initial state: driven values as the initial state gives them.
    qa = q0[None, :].copy()
    conv, res, it, Ju, stalled = prob.newton(qa, max_iter=200, damped=True)
    if not conv[0]:
        conv, res, it, Ju, stalled = prob.newton(qa, max_iter=50)
    if not conv[0]:
        msg = f"the initial state cannot be assembled (loop residual {res[0]:.3g})"
        for b in range(Q.shape[0]):
            status[b], messages[b] = "not_assemblable", msg
        return None
    U, S, Vt = np.linalg.svd(Ju[0])
    rank = int(np.sum(S > 1e-8 * S[0])) if S.size else 0
    prob.rank = rank
    prob.U0, prob.V0 = U[:, :rank], Vt[:rank].T
    sign = prob.sign(Ju)[0]
    want = getattr(prob, "want", None)
    if want is not None:
        if rank < len(prob.u) or prob.conditioning(Ju)[0] <= prob.singular_below:
            raise BranchUndefined(
                "the assembly branch is not defined at the initial state: "
                + ("the loops leave the passive values free (the passive Jacobian has rank "
                   f"{rank} < {len(prob.u)})" if rank < len(prob.u) else
                   "it is a singular configuration (dead centre)"))
        if want != sign:
            other = _other_assembly(prob, qa[0])
            if other is None:
                msg = (f"the requested assembly branch ({'+' if want > 0 else '-'}) was not found at the "
                       "initial state: no other assembly closes the loops there")
                for b in range(Q.shape[0]):
                    status[b], messages[b] = "not_assemblable", msg
                prob.missing = msg
                return None
            qa[0], Ju, Jd = other
            sign = prob.reanchor(Ju)
            prob.last_Jd = Jd
    state = {"q": qa[0], "sign": sign, "J": (Ju[:1], prob.last_Jd[:1]), "K": _K0}
    return _follow(prob, state, Q, D, status, messages, iters, branch)


#: Fixed seed and count of the random starts of :func:`_other_assembly` (same input, same answer).
_BRANCH_SEED = 105
_BRANCH_STARTS = 256


def _other_assembly(prob: _Loops, q0):
    """Another assembly of the loops at q0's driven values whose invariant (with the bases of
    the initial state) has the requested sign ``prob.want``: a deterministic multi-start
    Levenberg-Marquardt. Starts, in order: the passive angles reflected (-q: the mirror
    assembly of a planar loop about its ground line) and turned by pi; q pushed along each
    right singular vector of J_u; then a fixed-seed random set. The first start (in that order)
    that closes the loops to the tolerance, regular and with the requested sign, is taken.
    Returns (q, J_u (1, ., .), J_d (1, ., .)) or None."""
    u = prob.u
    ang = prob.pl.angle_mask[u]
    qu = q0[u]
    starts = [np.where(ang, -qu, qu), np.where(ang, qu + math.pi, qu), np.where(ang, math.pi - qu, qu)]
    _, _, Vt = np.linalg.svd(prob.evaluate(q0[None])[1][0])
    for vec in Vt:
        for eps in (0.5, 1.5, 3.0):
            for sgn in (1.0, -1.0):
                starts.append(qu + sgn * eps * vec / prob.scale_u)
    rng = np.random.default_rng(_BRANCH_SEED)
    # Random passive values: angles anywhere on the circle, lengths within a model size of q0's.
    R = rng.uniform(-1.0, 1.0, size=(_BRANCH_STARTS, len(u)))
    starts += list(np.where(ang, math.pi * R, qu + R / prob.scale_u))
    Qs = np.tile(q0, (len(starts), 1))
    Qs[:, u] = np.array(starts)
    conv = prob.newton(Qs, max_iter=200, damped=True)[0]
    if conv.any():
        # a closing Newton polish to round-off (the continuation starts from here)
        c = np.flatnonzero(conv)
        Qc = Qs[c]
        conv_c, _, _, Ju_c, _ = prob.newton(Qc, max_iter=5)
        Jd_c = prob.last_Jd
        sg, cond = prob.sign(Ju_c), prob.conditioning(Ju_c)
        good = conv_c & (sg == prob.want) & (cond > prob.singular_below)
        if good.any():
            k = int(np.argmax(good))
            return Qc[k], Ju_c[k:k + 1], Jd_c[k:k + 1]
    return None


def _follow(prob, state, Q, D, status, messages, iters, branch):
    n, i, K = Q.shape[0], 0, state["K"]
    while i < n:
        K = min(K, n - i)
        qlast = state["q"]
        Tg = state.get("T")
        if Tg is None:
            Tg = prob.tangent(qlast[None], *state["J"])[0] if state.get("J") else prob.tangent(qlast[None])[0]
        dd = D[i:i + K] - qlast[prob.d]
        Qc = Q[i:i + K].copy()
        Qc[:, prob.u] = qlast[prob.u] + dd @ Tg.T          # tangent predictor
        # Inside a chunk Newton gets few iterations: a prediction that needs more is rejected anyway.
        conv, res, it, Ju, stalled = prob.newton(Qc, max_iter=min(prob.max_iter, 8))
        sg = prob.sign(Ju)
        cond, Tl = prob.conditioning_and_tangent(Ju, prob.last_Jd)
        # Each configuration against the first-order step from its predecessor (the local
        # tangent there): a jump to another branch at a bifurcation, where the sign of the
        # invariant may not tell, shows as a correction as large as the step itself.
        prevQ = np.vstack([qlast[None], Qc[:-1]])
        prevT = np.concatenate([Tg[None], Tl[:-1]])
        local = prevQ[:, prob.u] + np.einsum("kuj,kj->ku", prevT, D[i:i + K] - prevQ[:, prob.d])
        good = _acceptable(prob, prevQ[:, prob.u], local, Qc, conv, sg, cond, state["sign"], 1.0)
        nk = K if good.all() else int(np.argmin(good))
        if nk:
            Q[i:i + nk] = Qc[:nk]
            iters[i:i + nk] = it[:nk]
            branch[i:i + nk] = sg[:nk]
            state["q"] = Qc[nk - 1]
            state["sign"] = prob.reanchor(Ju[nk - 1:nk]) or state["sign"]
            state["J"] = (Ju[nk - 1:nk], prob.last_Jd[nk - 1:nk])
            state["T"] = Tl[nk - 1]
            i += nk
            K = min(2 * K, _MAX_CHUNK) if nk == K else max(1, nk)
            continue
        if K > 1:
            K = max(1, K // 4)
            continue
        # One configuration that the plain step cannot reach: halve the step.
        _single(prob, state, Q, D, i, status, messages, iters, branch)
        state["J"] = state["T"] = None
        i += 1
        K = 2
    state["K"] = K
    return state


def _acceptable(prob, base_u, pred, Qc, conv, sg, cond, sign, factor=0.5) -> np.ndarray:
    """Converged, regular, on the tracked branch, and close to the predictor ``pred`` made from
    ``base_u`` (the correction at most ``factor`` times the predicted step)."""
    step = np.abs((pred - base_u) * prob.scale_u).max(axis=1)
    corr = np.abs((Qc[:, prob.u] - pred) * prob.scale_u).max(axis=1)
    near = corr <= factor * step + 1e-6
    regular = cond > prob.singular_below
    return conv & near & regular & ((sg == sign) | (sign == 0))


def _single(prob: _Loops, state, Q, D, i, status, messages, iters, branch):
    """Reach configuration i from the last accepted one by step halving; diagnose on failure."""
    qa, sign = state["q"].copy(), state["sign"]
    da, db = qa[prob.d].copy(), D[i]
    s, h, total_it = 0.0, 1.0, 0
    halvings = 0
    while s < 1.0:
        h = min(h, 1.0 - s)
        target = da + (s + h) * (db - da)
        q = qa.copy()
        Tg = prob.tangent(q[None])[0]
        q[prob.u] += Tg @ (target - q[prob.d])
        q[prob.d] = target
        pred = q[prob.u].copy()
        qq = q[None]
        conv, res, it, Ju, stalled = prob.newton(qq, max_iter=min(prob.max_iter, 15))
        total_it += int(it[0])
        sg, cond = prob.sign(Ju)[0], prob.conditioning(Ju)[0]
        ok = _acceptable(prob, qa[None, prob.u], pred[None], qq, conv, np.array([sg]), np.array([cond]), sign)[0]
        if conv[0] and cond > prob.singular_below and sign != 0 and sg == -sign:
            state["flipped"] = True   # the plain continuation crosses to the other sign here
        if ok:
            qa, s = qq[0], s + h
            h *= 2.0
            sign = state["sign"] = prob.reanchor(Ju) or sign
            continue
        if conv[0] and cond <= prob.singular_below and s + h >= 1.0:
            # Converged onto a rank-deficient configuration: a dead centre / bifurcation.
            Q[i], iters[i], branch[i] = qq[0], total_it, 0
            status[i] = "singular"
            messages[i] = (f"singular configuration (dead centre): the passive Jacobian has lost rank "
                           f"(conditioning {cond:.2g}); the assembly branch is kept")
            # The continuation goes on from the last regular configuration, not from the fold.
            return
        halvings += 1
        h *= 0.5
        if halvings > _MAX_HALVINGS:
            break
    else:
        Q[i], iters[i], branch[i] = qa, total_it, sign
        state["q"] = qa
        return
    # Continuation failed: look for the tracked branch from the last good state, then any branch.
    _diagnose(prob, state, Q, D, i, status, messages, iters, branch, total_it)
    if status[i] == "ok" and state.pop("flipped", False):
        # Kept the sign, but the path through here crosses a singular configuration (a
        # bifurcation): the configuration reported is on the other geometric branch that keeps it.
        status[i] = "singular"
        messages[i] = ("a singular configuration (bifurcation) lies between this configuration and the "
                       "previous one: the invariant of the initial state's branch is kept, which here "
                       "is a different geometric branch from the one followed so far")
    state.pop("flipped", None)


def _diagnose(prob, state, Q, D, i, status, messages, iters, branch, total_it):
    qa, sign = state["q"], state["sign"]
    starts = [qa]
    r, Ju, _ = prob.evaluate(qa[None])
    _, S, Vt = np.linalg.svd(Ju[0])
    for vec in Vt[max(prob.rank - 1, 0):prob.rank][::-1] if prob.rank else []:
        for eps in (1e-2, 0.2):
            for sgn in (1.0, -1.0):
                q = qa.copy()
                q[prob.u] += sgn * eps * vec / prob.scale_u
                starts.append(q)
    found = None
    best = (math.inf, None)
    for q0 in starts:
        q = q0.copy()
        q[prob.d] = D[i]
        qq = q[None]
        conv, res, it, Jq, stalled = prob.newton(qq, max_iter=60, damped=True)
        if not conv[0] and res[0] < 1e-3:
            conv, res, it, Jq, stalled = prob.newton(qq, max_iter=10)
        total_it += int(it[0])
        if conv[0]:
            sg, cond = prob.sign(Jq)[0], prob.conditioning(Jq)[0]
            if cond <= prob.singular_below:
                found = found or ("singular", qq[0], 0.0)
            elif sg == sign or sign == 0:
                found = ("ok", qq[0], sg)
                break
            elif found is None or found[0] != "singular":
                found = ("branch_change", qq[0], sg)
        elif res[0] < best[0]:
            best = (res[0], qq[0], bool(stalled[0]))
    iters[i] = total_it
    if found is not None:
        kind, q, sg = found
        Q[i], branch[i] = q, sg
        if kind != "singular":
            state["q"] = q
            _, Jq, _ = prob.evaluate(q[None])
            state["sign"] = prob.reanchor(Jq) or sg
        if kind == "branch_change":
            status[i] = "branch_change"
            messages[i] = ("the assembly branch of the initial state cannot be reached here; "
                           "continuing on the other branch")
        elif kind == "singular":
            status[i] = "singular"
            messages[i] = "singular configuration (dead centre): the passive Jacobian has lost rank"
        return
    res, q, stationary = best
    if q is not None:
        Q[i] = q
    status[i] = "not_assemblable" if stationary or res > 1e3 * prob.tol else "not_converged"
    messages[i] = (f"cannot be assembled: smallest loop residual {res:.3g}" if status[i] == "not_assemblable"
                   else f"Newton did not converge (loop residual {res:.3g})")


# --------------------------------------------------------------------------- inverse analysis

@dataclass
class PathResult:
    """Inverse analysis along a path: values Q (N, nv) and per-sample pose errors."""

    plan: Plan
    Q: np.ndarray
    status: list
    position_error: np.ndarray   # metres
    rotation_error: np.ndarray   # radians
    iterations: np.ndarray
    messages: list
    seconds: float
    unknowns: np.ndarray

    def links(self) -> np.ndarray:
        return forward(self.plan, self.Q)


def _chain(pl: Plan, link: str):
    """Tree entries from the base to ``link`` (in order)."""
    if link not in pl.link_index:
        raise SolveError(f"{link!r} is not a link of mechanism {pl.mech.name!r} "
                         f"(links: {', '.join(pl.link_names)})")
    out, li = [], pl.link_index[link]
    while li in pl.parent_of:
        k = pl.parent_of[li]
        out.append(pl.tree[k])
        li = pl.tree[k][1]
    return out[::-1]


def _rotvec(R) -> np.ndarray:
    """Rotation vectors (B, 3) of rotation matrices (B, 3, 3), accurate near 0 and near pi."""
    c = np.clip(0.5 * (np.trace(R, axis1=-2, axis2=-1) - 1.0), -1.0, 1.0)
    w = 0.5 * np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], axis=-1)
    s = np.linalg.norm(w, axis=-1)
    th = np.arctan2(s, c)
    f = np.where(s > 1e-12, th / np.where(s > 1e-12, s, 1.0), 1.0 + th * th / 6.0)
    out = w * f[:, None]
    near_pi = c < -0.99
    if near_pi.any():
        # sin(th) ~ 0: take the axis from the symmetric part, the sign from w.
        for b in np.flatnonzero(near_pi):
            Rs = 0.5 * (R[b] + R[b].T) - c[b] * np.eye(3)
            j = int(np.argmax(np.diag(Rs)))
            axis = Rs[j] / np.linalg.norm(Rs[j])
            if axis @ w[b] < 0:
                axis = -axis
            out[b] = th[b] * axis
    return out


def _ik_eval(pl: Plan, chain, Q, T_link_frame, u_cols):
    """Frame poses (B, 4, 4) and world geometric Jacobians (B, 6, nu) (point velocity, angular)."""
    B = Q.shape[0]
    T = np.broadcast_to(pl.mech.T_world_base, (B, 4, 4)).copy()
    blocks = []
    for k, parent, child, fwd in chain:
        X = _left_twists(pl, k, Q, fwd)
        blocks.append(_ad(T, X))
        A = _pair_T(pl, k, Q)
        T = T @ (A if fwd else _inv(A))
    T = T @ T_link_frame
    Js = np.concatenate(blocks, axis=-1)[:, :, u_cols] if blocks else np.zeros((B, 6, 0))
    p = T[:, :3, 3]
    # Linear velocity of the frame origin: v + w x p.
    v = Js[:, :3] + np.cross(Js[:, 3:], p[:, :, None], axis=1)
    return T, np.concatenate([v, Js[:, 3:]], axis=1)


_IK_JUMP = 1.0  # radians (or model sizes) a value may move between two samples of a path


class _IK:
    """Damped least squares on the pose error of one frame, batched over samples."""

    def __init__(self, pl, chain, Tf, cols, u, sc, tol, max_iter, damping, chain_pos=None):
        self.pl, self.chain, self.Tf, self.cols, self.u, self.sc = pl, chain, Tf, cols, u, sc
        self.tol, self.max_iter, self.damping = tol, max_iter, damping
        self.chain_pos = chain_pos  # with loops: where the chain's values sit among the unknowns
        L = len(pl.loops) if chain_pos is not None else 0
        self.W = np.concatenate([np.full(3, 1.0 / pl.size), np.ones(3), np.ones(6 * L)])

    def error(self, Q, targets):
        """Errors (B, 6 [+ 6L]) and their Jacobian (B, rows, nu): the pose error (position of the
        frame's origin, rotation vector, world axes) and, with loops, minus the loop residuals."""
        T, Jp = _ik_eval(self.pl, self.chain, Q, self.Tf, self.cols)
        e = np.concatenate([targets[:, :3, 3] - T[:, :3, 3],
                            _rotvec(targets[:, :3, :3] @ np.swapaxes(T[:, :3, :3], -1, -2))], axis=1)
        if self.chain_pos is None:
            return e, Jp
        r, Jl = closure(self.pl, Q)
        J = np.zeros((Q.shape[0], 6 + r.shape[1], len(self.u)))
        J[:, :6, self.chain_pos] = Jp
        J[:, 6:, :] = Jl[:, :, self.u]
        return np.concatenate([e, -r], axis=1), J

    def solve(self, Q, targets):
        """Iterate Q (B, nv) in place; returns converged, position and rotation errors, iterations."""
        B = Q.shape[0]
        it = np.zeros(B, dtype=int)
        active = np.ones(B, dtype=bool)
        best = np.full(B, np.inf)
        stall = np.zeros(B, dtype=int)
        lam_max = self.damping
        for k in range(self.max_iter + 1):
            e, J = self.error(Q, targets)
            pe, re = np.linalg.norm(e[:, :3], axis=1), np.linalg.norm(e[:, 3:6], axis=1)
            err = np.maximum(pe / self.pl.size, re)
            if e.shape[1] > 6:
                err = np.maximum(err, np.abs(e[:, 6:]).max(axis=1))
            stall = np.where(err < 0.999 * best, 0, stall + 1)
            best = np.minimum(best, err)
            active = (err > self.tol) & (stall < 20)
            if k == self.max_iter or not active.any():
                break
            a = np.flatnonzero(active)
            Js = (J[a] * self.W[None, :, None]) / self.sc[None, None, :]
            Uj, S, Vt = np.linalg.svd(Js, full_matrices=False)
            smin = S[:, -1] if S.shape[1] else np.zeros(len(a))
            # Damping only near a singularity (Nakamura & Hanafusa), so Newton is exact elsewhere.
            lam2 = np.where(smin >= lam_max, 0.0, (1.0 - (smin / lam_max) ** 2) * lam_max ** 2)
            cut = S > 1e-12 * np.maximum(S[:, :1], 1e-300)
            f = np.where(cut, S / np.where(cut, S * S + lam2[:, None], 1.0), 0.0)
            dq = np.einsum("bji,bj->bi", Vt, f * np.einsum("bji,bj->bi", Uj, e[a] * self.W))
            big = np.abs(dq).max(axis=1) if dq.shape[1] else np.zeros(len(a))
            dq *= np.minimum(1.0, 0.5 / np.maximum(big, 1e-300))[:, None]
            Q[np.ix_(a, self.u)] += dq / self.sc
            it[a] += 1
        return err <= self.tol, pe, re, it


def solve_path(mech, link: str, poses, *, frame=None, initial=None, tol: float = 1e-10,
               max_iter: int = 100, damping: float = 1e-2, pl: Plan | None = None) -> PathResult:
    """Inverse analysis: values that put ``frame`` (4x4 in ``link``'s coordinates, default its
    origin) on each of ``poses`` (N, 4, 4, world, SI), warm started along the path.

    Unknowns: the values of the pairs on the tree path from the base to
    ``link``; with closed loops also every value of the pairs on loops, the
    loop residuals joining the pose error in one least-squares system (a
    mechanism with fewer freedoms than six follows a path it can follow: the
    poses of one of its frames from a forward analysis). Converged when the
    position error is below ``tol * size``, the rotation error and the loop
    residuals below ``tol``. ``damping`` is the largest
    damping, used only where the smallest singular value of the scaled
    Jacobian falls below it (so no NaN and no wild step through a
    singularity)."""
    t0 = time.perf_counter()
    pl = pl or plan(mech)
    poses = np.asarray(poses, dtype=np.float64).reshape(-1, 4, 4)
    if not np.all(np.isfinite(poses)):
        raise SolveError("target poses must be finite")
    chain = _chain(pl, link)
    Tf = np.eye(4) if frame is None else np.asarray(frame, dtype=np.float64)
    cols, u = [], []
    off = 0
    for k, _, _, _ in chain:
        sl = pl.slices[k]
        for j in range(sl.stop - sl.start):
            cols.append(off + j)
            u.append(sl.start + j)
        off += sl.stop - sl.start
    u = np.array(u, dtype=int)
    cols = np.array(cols, dtype=int)
    chain_pos = None
    if pl.loops:
        chain_u = u
        u = np.array(sorted(set(u.tolist()) | set(pl.loop_values().tolist())), dtype=int)
        chain_pos = np.searchsorted(u, chain_u)
    sc = _scale(pl)[u]
    N = poses.shape[0]
    q = (mech.initial_vector() if initial is None else np.asarray(initial, dtype=np.float64)).copy()
    Q = np.tile(q, (N, 1))
    perr, rerr = np.zeros(N), np.zeros(N)
    iters = np.zeros(N, dtype=int)
    status, messages = ["ok"] * N, [""] * N
    ik = _IK(pl, chain, Tf, cols, u, sc, tol, max_iter, damping, chain_pos)
    # Warm start in chunks: every sample of a chunk starts from the last accepted solution and
    # the chunk is solved batched; a sample is accepted when it converged without a jump
    # (no joint moved more than _IK_JUMP from the previous sample), else the chunk shrinks.
    i, K = 0, 8
    while i < N:
        K = min(K, N - i)
        Qc = np.tile(q, (K, 1))
        conv, pe, re, it = ik.solve(Qc, poses[i:i + K])
        prev = np.vstack([q[None, u], Qc[:-1, u]])
        jump = np.abs((Qc[:, u] - prev) * sc).max(axis=1) if len(u) else np.zeros(K)
        good = conv & (jump <= _IK_JUMP)
        nk = K if good.all() else int(np.argmin(good))
        if nk == 0 and K > 1:
            K = max(1, K // 4)
            continue
        nk = max(nk, 1)  # one sample on its own: take what damped least squares gives
        Q[i:i + nk], perr[i:i + nk], rerr[i:i + nk], iters[i:i + nk] = Qc[:nk], pe[:nk], re[:nk], it[:nk]
        for b in range(nk):
            if not conv[b]:
                status[i + b] = "not_converged"
                messages[i + b] = (f"pose not reached: position error {pe[b]:.3g} m, "
                                   f"rotation error {re[b]:.3g} rad")
        q = Qc[nk - 1].copy()
        i += nk
        K = min(2 * K, 256) if nk == K else max(1, nk)
    Qw = _wrap_periodic(pl, Q)
    for b, names in enumerate(_out_of_range(pl, Qw)):
        if names and status[b] == "ok":
            status[b] = "out_of_range"
            messages[b] = "outside its range: " + ", ".join(names)
    return PathResult(pl, Qw, status, perr, rerr, iters, messages, time.perf_counter() - t0, u)
