"""Inverse analysis: a link frame follows prescribed poses.

Damped least squares on the pose error (position of the frame's origin in
metres, rotation vector in radians, world axes), analytic geometric
Jacobians, the damping raised only near singular configurations (so the
answer is the exact one away from them and finite through them), warm
started along the path. With closed loops the loop residuals
(:mod:`.closure`) join the pose error in one least-squares system.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..spatial import adjoint_apply, inverse, rotation_vector
from .closure import closure
from .forward import forward, left_twists, pair_transform
from .plan import Plan, SolveError, out_of_range, plan, value_scale, wrap_periodic

__all__ = ["PathResult", "solve_path"]


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


def _ik_eval(pl: Plan, chain, Q, T_link_frame, u_cols):
    """Frame poses (B, 4, 4) and world geometric Jacobians (B, 6, nu) (point velocity, angular)."""
    B = Q.shape[0]
    T = np.broadcast_to(pl.mech.T_world_base, (B, 4, 4)).copy()
    blocks = []
    for k, parent, child, fwd in chain:
        X = left_twists(pl, k, Q, fwd)
        blocks.append(adjoint_apply(T, X))
        A = pair_transform(pl, k, Q)
        T = T @ (A if fwd else inverse(A))
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
                            rotation_vector(targets[:, :3, :3] @ np.swapaxes(T[:, :3, :3], -1, -2))], axis=1)
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
    locked = pl.locked_values()
    for k, _, _, _ in chain:
        sl = pl.slices[k]
        for j in range(sl.stop - sl.start):
            if not locked[sl.start + j]:  # a value the pair's flags lock is no unknown
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
    sc = value_scale(pl)[u]
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
    Qw = wrap_periodic(pl, Q)
    for b, names in enumerate(out_of_range(pl, Qw)):
        if names and status[b] == "ok":
            status[b] = "out_of_range"
            messages[b] = "outside its range: " + ", ".join(names)
    return PathResult(pl, Qw, status, perr, rerr, iters, messages, time.perf_counter() - t0, u)
