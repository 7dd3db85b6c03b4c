"""Loop closure: the only loop residual and its Jacobian (the solvers' Newton system, and the
structure analysis's rank).

Each independent loop (a chord of the spanning tree, then the tree path
back) must close: the product of the pair transforms around it, ``T_loop =
A_1 ... A_n`` (``A_k = T_link1_link2`` traversed forward, its inverse
backwards), must be the identity. The residual of a loop is ``(p / size, 2
q_v)`` of ``T_loop = [R, p]``, ``(q_w >= 0, q_v)`` the quaternion of ``R``
(zero only at the identity; lengths divided by the model size, so the same
mechanism in millimetres and in metres takes the same steps). Its Jacobian
is analytic: the spatial twist of factor k in the loop's start frame is
``Ad(A_1 ... A_{k-1}) xi_k`` with ``xi_k = Ad(P1 M) J_body`` forward and
``-Ad(P2) J_body`` backwards (``J_body`` from :mod:`p105cli.kinematics.pairs`),
and a spatial twist ``(v, w)`` changes the residual by ``(v + w x p) / size``
and ``q_w w + w x q_v``.
"""

from __future__ import annotations

import numpy as np

from ..spatial import adjoint_apply, inverse, quaternion_parts
from .forward import _E, const_twists, left_twists, pair_transform
from .plan import Plan

__all__ = ["closure", "loop_twists", "root_loop_twists", "loop_errors"]


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


def _loop_terms(pl: Plan, li: int, Q, jacobian: bool, factors: dict):
    """``T_loop`` (B, 4, 4) of loop ``li`` and, with ``jacobian``, the spatial twists (B, 6, n)
    of its factors in the loop's start frame and their flat value columns (n,). ``factors``
    keeps each pair's oriented transform and left twists for the other loops of this call
    (a pair on several loops is evaluated once)."""
    B = Q.shape[0]
    lp = pl.loops[li]
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
        M = None
        if pl.types[k].kind != "revolute" and ((k, fwd) not in factors or jacobian and fwd):
            # the motion once for the transform and the twists of this pair
            M = factors.get(("motion", k))
            if M is None:
                M = factors[("motion", k)] = pl.types[k].motion(Q[:, pl.slices[k]], **pl.params[k])
        if jacobian:
            X = factors.get(("twists", k, fwd))
            if X is None:
                X = factors[("twists", k, fwd)] = left_twists(pl, k, Q, fwd, M)
            blocks.append(np.broadcast_to(X, (B,) + X.shape[-2:]) if T is None else adjoint_apply(T, X))
            idx.extend(range(pl.slices[k].start, pl.slices[k].stop))
        A = factors.get((k, fwd))
        if A is None:
            A = pair_transform(pl, k, Q, M)
            A = factors[(k, fwd)] = A if fwd else inverse(A)
        T = A if T is None else T @ A
    if not (jacobian and idx):
        return T, None, idx
    return T, blocks[0] if len(blocks) == 1 else np.concatenate(blocks, axis=-1), idx


def closure(pl: Plan, Q, *, jacobian: bool = True):
    """Loop residuals r (B, 6L) and their Jacobian dr/dq (B, 6L, nv), dimensionless.

    ``r = (p / size, 2 q_v)`` per loop of ``T_loop = [R, p]``, ``(q_w >= 0, q_v)`` the
    quaternion of ``R``."""
    Q = np.atleast_2d(Q)
    B, L = Q.shape[0], len(pl.loops)
    r = np.zeros((B, 6 * L))
    J = np.zeros((B, 6 * L, pl.nv)) if jacobian else None
    factors = {}
    for li in range(L):
        T, S, idx = _loop_terms(pl, li, Q, jacobian, factors)
        R, p = T[:, :3, :3], T[:, :3, 3]
        r[:, 6 * li:6 * li + 3] = p / pl.size
        qw, qv = quaternion_parts(R)
        r[:, 6 * li + 3:6 * li + 6] = 2.0 * qv
        if S is not None:
            # S: spatial twists. d(p / size) = (v + w x p) / size;  d(2 q_v) = q_w w + w x q_v
            # (left perturbation): Jl = M S with M (B, 6, 6) linear in (p / size, q_v, q_w).
            y = np.empty((B, 7))
            np.divide(p, pl.size, out=y[:, :3])
            y[:, 3:6] = qv
            y[:, 6] = qw
            M = np.matmul(y, _JL_MAP).reshape(B, 6, 6)
            M[:, _I3, _I3] = 1.0 / pl.size
            J[:, 6 * li:6 * li + 6, idx] = M @ S   # a loop owns its rows; a pair appears once in it
    return r, J


def loop_twists(pl: Plan, Q, loops=None):
    """The loops before the residual map: ``T_loop`` (B, L, 4, 4) and the twist Jacobian
    (B, 6L, nv), the spatial twist ``(v, w)`` of each ``T_loop`` (in its start link's frame)
    per unit change of each value, for the loops of ``pl.loops`` numbered in ``loops`` (all
    by default), in that order. :func:`closure`'s Jacobian is ``D(T_loop)`` times it, ``D``
    invertible (``q_w > 0``): the same rank and null space, so the structure analysis
    (:mod:`p105cli.kinematics.graph`) reads mobility and redundancy from this one."""
    Q = np.atleast_2d(Q)
    loops = range(len(pl.loops)) if loops is None else list(loops)
    B, L = Q.shape[0], len(loops)
    Tl = np.empty((B, L, 4, 4))
    J = np.zeros((B, 6 * L, pl.nv))
    factors = {}
    for i, li in enumerate(loops):
        T, S, idx = _loop_terms(pl, li, Q, True, factors)
        Tl[:, i] = T
        if S is not None:
            J[:, 6 * i:6 * i + 6, idx] = S
    return Tl, J


def root_loop_twists(pl: Plan, q, X, loops=None) -> np.ndarray:
    """The loops' twist Jacobian for one configuration ``q`` (nv,) in each component root's
    frame: (6L, nv). ``X``: the link placements at ``q`` in their component root's frame, by
    link index (:func:`forward.link_poses`). Each pair on a loop is evaluated once, its twist
    taken at the tree's placement of its second link (``Ad(X_link2 P2) J_body``, crossed
    backwards its negative), and a loop's rows are the signed sum of its pairs' twists. Where
    the loops close this is :func:`loop_twists` turned by ``Ad(X_a)`` (``X_a`` the loop's
    start link); the structure analysis reads rank and self-stresses from it, the
    self-stresses of different loops adding up as wrenches in one frame."""
    loops = range(len(pl.loops)) if loops is None else list(loops)
    q = np.asarray(q, dtype=np.float64)
    on_loop = sorted({k for li in loops for k, _ in pl.loops[li]})
    cols, F, Jb = [], [], []
    for k in on_loop:
        sl = pl.slices[k]
        Jb.append(pl.types[k].motion_jacobian(q[sl], **pl.params[k]))
        cols.extend(range(sl.start, sl.stop))
        F.extend([X[pl.link_index[pl.mech.pairs[k].link2]] @ pl.P2[k]] * (sl.stop - sl.start))
    S = np.zeros((6, pl.nv))
    if cols:
        # Ad(X_link2 P2) J_body per value column, all columns at once
        S[:, cols] = adjoint_apply(np.asarray(F), np.concatenate(Jb, axis=-1).T[:, :, None])[:, :, 0].T
    J = np.zeros((6 * len(loops), pl.nv))
    for i, li in enumerate(loops):
        for k, fwd in pl.loops[li]:
            sl = pl.slices[k]
            J[6 * i:6 * i + 6, sl] = S[:, sl] if fwd else -S[:, sl]
    return J


def _revolute_loop(pl: Plan, li: int):
    """Constants of a loop of revolute pairs only (None otherwise): every factor, forward or
    backwards, is ``E0 + cos q E1 + sin q E2`` (backwards: ``P2 Rz(-q) P1^-1``), stored as
    (n, 3, 16); and every left twist is constant: ``sgn (p x z, z)`` of the joint axis (z, p)
    in the factor's left frame (P1 forward, P2 backwards), kept as homogeneous columns
    (n, 4, 2) so that the twists in the loop's start frame are one product with the prefix
    placements."""
    cache = pl.revolute_loops
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
        X.append(const_twists(pl, k, fwd)[:, 0])
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


def loop_errors(pl: Plan, Q):
    """Per configuration: largest loop position error (metres) and rotation error (radians)."""
    Q = np.atleast_2d(Q)
    B = Q.shape[0]
    pos, rot = np.zeros(B), np.zeros(B)
    for lp in pl.loops:
        T = None
        for k, fwd in lp:
            A = pair_transform(pl, k, Q)
            A = A if fwd else inverse(A)
            T = A if T is None else T @ A
        if T is None:
            continue
        pos = np.maximum(pos, np.linalg.norm(T[:, :3, 3], axis=-1))
        c = np.clip(0.5 * (T[:, 0, 0] + T[:, 1, 1] + T[:, 2, 2] - 1.0), -1.0, 1.0)
        s = 0.5 * np.linalg.norm(np.stack([T[:, 2, 1] - T[:, 1, 2], T[:, 0, 2] - T[:, 2, 0],
                                           T[:, 1, 0] - T[:, 0, 1]], axis=-1), axis=-1)
        rot = np.maximum(rot, np.arctan2(s, c))
    return pos, rot
