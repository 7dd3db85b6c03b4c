"""Forward kinematics: the only one. Pair transforms, and link placements along the spanning
tree for given values of every pair (a tree's configurations, or solved loop values).

``T_link1_link2(q) = P1 M(q) P2^-1`` (:class:`p105cli.kinematics.pairs.PairType`); a pair
crossed backwards (its second link the parent in the tree) contributes the inverse. The tree
is :func:`p105cli.kinematics.graph.topology`'s, compiled into the :class:`Plan`.

Two evaluations of the same products: :func:`forward`, batched over configurations and
specialised for revolute pairs (the solvers' hot path), and :func:`link_poses`, one
configuration (or a batch) by plain products that tolerates pairs without a motion (the
structure analysis and the model writer); they agree to round-off.
"""

from __future__ import annotations

import numpy as np

from ..pairs import UnsupportedPairError, link_transform
from ..spatial import adjoint, inverse
from .plan import Plan

__all__ = ["pair_transform", "left_twists", "const_twists", "forward", "link_poses"]


def pair_transform(pl: Plan, k: int, Q, M=None) -> np.ndarray:
    """(B, 4, 4) ``T_link1_link2`` of pair k for flat values Q (B, nv); ``M`` its motion at Q
    when the caller has it (any pair but a revolute one)."""
    t, sl = pl.types[k], pl.slices[k]
    if t.kind == "revolute":
        # P1 Rz(q) P2^-1 = C0 + cos q C1 + sin q C2: elementwise, no matrix product (and no
        # BLAS call, whose threads only cost time on (B x 3) operands).
        C = _revolute_consts(pl, k)
        q = Q[:, sl.start]
        return C[0] + np.cos(q)[:, None, None] * C[1] + np.sin(q)[:, None, None] * C[2]
    if M is None:
        M = t.motion(Q[:, sl], **pl.params[k])
    return link_transform(pl.P1[k], M, P2inv=pl.P2inv[k])


_E = (np.diag([0.0, 0.0, 1.0, 1.0]), np.diag([1.0, 1.0, 0.0, 0.0]),
      np.array([[0.0, -1.0, 0, 0], [1.0, 0.0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]]))


def _revolute_consts(pl: Plan, k: int):
    cache = pl.revolute_consts
    if k not in cache:
        cache[k] = np.array([pl.P1[k] @ E @ pl.P2inv[k] for E in _E])
    return cache[k]


def const_twists(pl: Plan, k: int, fwd: bool):
    """Left twists (6, n) of a revolute or prismatic pair: they do not depend on the value."""
    cache = pl.const_twists
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


def left_twists(pl: Plan, k: int, Q, fwd: bool, M=None) -> np.ndarray:
    """(B, 6, n_k) or (6, n_k): twists of the factor (pair k, forward or backwards) in its left
    frame (``M``: the pair's motion at Q when the caller has it)."""
    X = const_twists(pl, k, fwd)
    if X is not None:
        return X
    t, sl = pl.types[k], pl.slices[k]
    Jb = t.motion_jacobian(Q[:, sl], **pl.params[k])
    if fwd:
        if M is None:
            M = t.motion(Q[:, sl], **pl.params[k])
        return adjoint(pl.P1[k] @ M) @ Jb
    return -(pl.AdP2[k] @ Jb)


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
    if pl.forward_steps is not None:
        return pl.forward_steps
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
    pl.forward_steps = steps
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
    for r in pl.roots[1:]:   # a component not connected to the base: from its own root
        out[r] = np.eye(4)
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
                T = pair_transform(pl, k, q)
                np.matmul(P, T if fwd else inverse(T), out=dst)
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


def link_poses(pl: Plan, q, *, world: bool = False, unsupported: str = "raise"):
    """Link placements for values ``q`` (..., nv), by plain products ``T_child = T_parent
    T_link1_link2`` (or its inverse) in tree order; each component's root at the identity
    (``world``: the base link's at ``T_world_base``).

    Returns ``(links, pairs, skipped)``: ``links`` the placements (..., 4, 4) in
    ``pl.link_names`` order, ``pairs`` every pair's ``T_link1_link2`` in pair order,
    ``skipped`` maps the index of every pair whose motion is not available at these values
    (:class:`UnsupportedPairError`, or parameters its motion refuses) to the reason. Such a
    pair: ``unsupported="raise"`` raises UnsupportedPairError naming it; ``"skip"`` leaves
    its ``T`` and the placements of the links beyond it None; ``"identity"`` takes its ``T``
    as the identity (its second link placed at its first's)."""
    if unsupported not in ("raise", "skip", "identity"):
        raise ValueError(f"unsupported must be 'raise', 'skip' or 'identity', got {unsupported!r}")
    q = np.asarray(q, dtype=np.float64)
    T, bad = [None] * len(pl.types), {}
    for k, t in enumerate(pl.types):
        try:
            M = t.motion(q[..., pl.slices[k]], **pl.params[k])
        except (UnsupportedPairError, ValueError, TypeError) as err:
            # no motion for this pair type (a rolling surface pair is not a function of its
            # values), or parameters its motion refuses (e.g. a skew angle against WR1)
            if unsupported == "raise":
                raise UnsupportedPairError(f"pair {pl.pair_names[k]!r}: {err}") from err
            bad[k] = str(err)
            if unsupported == "identity":
                T[k] = np.broadcast_to(np.eye(4), q.shape[:-1] + (4, 4))
            continue
        T[k] = link_transform(pl.P1[k], M, P2inv=pl.P2inv[k])
    eye = np.broadcast_to(np.eye(4), q.shape[:-1] + (4, 4))
    X = [None] * len(pl.link_names)
    for r in pl.roots:
        X[r] = eye
    if world and pl.roots:
        X[pl.roots[0]] = np.broadcast_to(pl.mech.T_world_base, eye.shape)
    for k, u, v, fwd in pl.tree:
        if T[k] is None or X[u] is None:
            continue
        X[v] = X[u] @ (T[k] if fwd else inverse(T[k]))
    return X, T, bad
