"""Forward position analysis of closed loops: Newton on the loop residual
(:mod:`.closure`), continuation along the driven values, assembly branches.

The unknowns are the values of the pairs in loops that are not driven.
Newton steps are least-squares steps with a round-off-level
regularisation (minimum norm where the Jacobian has lost rank), so
redundant constraints (a planar loop in 3D: 6 equations, rank 3; a
Bennett linkage) and remaining mobility are handled alike. A closing
Newton step from the last evaluation takes the values from the tolerance
to round-off. Branches and diagnoses: see the package docstring.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from .closure import closure, loop_errors
from .forward import forward
from .plan import BranchUndefined, Plan, SolveError, out_of_range, plan, value_scale, wrap_periodic

__all__ = ["MotionResult", "solve_motion", "iter_motion"]

_MAX_HALVINGS = 12
_MAX_CHUNK = 1024   # configurations solved together at most
_K0 = 64            # the first chunk after the initial state


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
    sc = value_scale(pl)
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
        pos, rot = loop_errors(pl, Q) if pl.loops else (np.zeros(n), np.zeros(n))
        res = np.maximum(pos / pl.size, rot)
        for b in np.flatnonzero(res > 10.0 * tol):
            # The closing Newton step is not re-evaluated during the solve: checked here.
            if status[b] in ("ok", "singular", "branch_change"):
                status[b] = "not_converged"
                messages[b] = f"loop residual {res[b]:.3g} above the tolerance"
        Qw = wrap_periodic(pl, Q)
        for b, names in enumerate(out_of_range(pl, Qw)):
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
