"""Structure analysis of a mechanism: its graph, loops and mobility.

A mechanism is a graph with the **links as vertices and the joints (pairs) as
edges** (ISO 10303-105:1996 clause 1 and 5.4.70). :func:`analyse` finds

* a **spanning tree** grown breadth-first from the base link (each further
  connected component from its first link in model order), with the link
  order (``order``) and the tree edges ``(pair, parent, child, forward)``;
  ``forward`` is True when the pair's first link is the parent;
* one **independent loop per chord** (a pair not in the tree): the chord
  traversed from its first to its second link, then the tree path back
  (``joints - links + components`` loops in all, the cyclomatic number);
  each loop is a list of ``(pair, forward)`` in traversal order, ``forward``
  True when the pair is crossed from its first to its second link;
* whether it is a **tree** (no loop) or a **network**;
* its **mobility** two ways. Gruebler-Kutzbach counts
  ``6 (links - 1 - joints) + sum(pair freedoms)`` (a component not connected
  to the base link floats and counts its 6 rigid-body freedoms). The rank
  method takes the loop-closure Jacobian ``J`` at the initial state:
  ``mobility = freedoms - rank(J) (+ 6 per floating component)`` and
  ``redundant_constraints = 6 loops - rank(J)``, so that
  ``mobility = mobility_gruebler + redundant_constraints`` always. A planar
  four-bar modelled in 3D: Gruebler -2, rank 3, mobility 1, 3 redundant.
  The rank is an *instantaneous* mobility: at a singular configuration
  (a folded linkage) it exceeds the finite mobility.

Redundant constraints are carried by joints: a vector ``w`` of the left null
space of ``J`` is a self-stress (loop wrenches that load the joints but do no
work on any freedom); joint ``j`` carries it when the sum of the wrenches of
the loops through ``j`` (signed by the traversal direction) is not zero.
``redundant_joints`` lists those joints.

**Loop closure** is the solver's (:mod:`p105cli.kinematics.solver.closure`,
the one loop residual). For loop ``l`` starting at link ``a`` (the chord's
first link), walking the pair transforms ``T_link1_link2(q)`` (inverted where a
pair is crossed backwards) round the loop gives ``T_loop(q)``, the placement of
link ``a`` reached round the loop in link ``a`` as it started; closed means
``T_loop = I``. The rank is taken on the loops' twist Jacobian (the spatial
twist ``(v, w)`` of ``T_loop`` per value, ``solver.loop_twists``), each loop's
rows turned into its component root's frame (``solver.root_loop_twists``: each
pair's twist once, at the tree's placements); the solver's residual ``(p / size,
2 q_v)`` has the same rank and null space (its Jacobian is an invertible map of
this one). :func:`loop_closure` is a view of the same loops in metres and
radians, ``r_l = (p, phi)``: ``p`` the translation of ``T_loop`` (in link ``a``'s
frame) and ``phi`` the rotation vector of its rotation (``|phi| <= pi``), with
the exact Jacobian ``dp = v + w x p`` and ``dphi = Jl(phi)^-1 w`` (``Jl`` the
left Jacobian of SO(3)).

**Tolerances.** The rank is taken on a dimensionless Jacobian: translation
rows divided, translation columns (values named ``*translation*``,
``*displacement*``) multiplied by the model size ``L`` (the largest pair-frame
distance, :meth:`Mechanism.size`, or of the pair frames from the base
origin). A singular value counts as zero below ``rtol * s_max`` with
``rtol = max(tol, min(100 * closure error, 1e-4))`` (``tol`` default 1e-8;
the closure error is the largest loop residual at the initial state,
translation over ``L``): a state that closes only to 1e-6 cannot resolve a
rank finer than that; a state that does not close at all is noted.

A science module: numpy only, no click.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .pairs import UnsupportedPairError
from .solver import link_poses, loop_twists, plan, root_loop_twists
from .spatial import hat3, inverse, left_jacobian_inverse, rotation_vector

__all__ = ["Structure", "Component", "analyse", "loop_closure", "DEFAULT_TOL", "length_columns"]

#: Default relative rank tolerance (dimensionless).
DEFAULT_TOL = 1e-8
# A joint carries a self-stress when its (unit-basis) wrench exceeds this.
_CARRY_TOL = 1e-6


@dataclass
class Component:
    """One connected part of the mechanism's graph."""

    links: list
    root: str
    pairs: list
    loops: list            # indices into Structure.loops
    floating: bool         # not connected to the base link
    dof: int               # sum of the freedoms of its pairs
    mobility_gruebler: int
    mobility: Optional[int] = None
    rank: Optional[int] = None
    redundant_constraints: Optional[int] = None
    redundant_joints: list = field(default_factory=list)
    singular_values: list = field(default_factory=list)
    closure_residual: float = 0.0


@dataclass
class Structure:
    """The result of :func:`analyse`. Link and pair names throughout.

    ``order``: links breadth-first from the base (then the other components);
    ``tree``: ``(pair, parent, child, forward)`` per tree edge, in ``order``;
    ``chords``: the pair closing each loop; ``loops``: per loop, ``(pair,
    forward)`` in traversal order (chord first); ``mobility`` (None when a
    pair's motion is not available), ``mobility_gruebler``,
    ``redundant_constraints``, ``redundant_joints``, ``kind`` ("tree" or
    "network"), ``components``, ``rank``, ``dof`` (sum of pair freedoms),
    ``tol`` (the rank tolerance used), ``closure_residual`` (largest loop
    residual at the initial state, dimensionless as described in the module
    docstring), ``size`` (the length scale), ``notes`` (why something could
    not be computed).
    """

    mechanism: str
    base: str
    order: list
    tree: list
    chords: list
    loops: list
    kind: str
    components: list
    dof: int
    mobility_gruebler: int
    mobility: Optional[int]
    redundant_constraints: Optional[int]
    redundant_joints: list
    rank: Optional[int]
    tol: float
    closure_residual: float
    size: float
    notes: list = field(default_factory=list)
    _plan: object = field(default=None, repr=False)   # the compiled mechanism (loop_closure)

    @property
    def loop_count(self) -> int:
        return len(self.loops)


# --------------------------------------------------------------------------- topology

def topology(mech):
    """The spanning forest (breadth-first from the base link, then from each further component's
    first link), chords and loops: ``(order, tree, roots, components, chords, loops)``, links by
    name, pairs by index (``tree``: ``(pair, parent, child, forward)``; loops: ``(pair, forward)``).
    The one spanning-tree walk: the solvers (:func:`p105cli.kinematics.solver.plan`) and the
    model writer use it."""
    pairs = mech.pairs
    adj = {ln.name: [] for ln in mech.links}
    for k, p in enumerate(pairs):
        adj[p.link1].append((k, p.link2))
        if p.link2 != p.link1:
            adj[p.link2].append((k, p.link1))
    parent = {}        # link -> (pair index, parent link, forward)
    depth = {}
    order, tree_idx, roots, comps = [], [], [], []
    used = set()
    starts = [mech.base] + [ln.name for ln in mech.links if ln.name != mech.base]
    for root in starts:
        if root in depth:
            continue
        roots.append(root)
        depth[root] = 0
        comp = [root]
        order.append(root)
        queue = deque([root])
        while queue:
            u = queue.popleft()
            for k, v in adj[u]:
                if v in depth:
                    continue
                fwd = pairs[k].link1 == u
                parent[v] = (k, u, fwd)
                depth[v] = depth[u] + 1
                used.add(k)
                tree_idx.append((k, u, v, fwd))
                order.append(v)
                comp.append(v)
                queue.append(v)
        comps.append(comp)
    chords = [k for k in range(len(pairs)) if k not in used]
    loops = []
    for c in chords:
        a, b = pairs[c].link1, pairs[c].link2
        up, down = [], []
        x, y = b, a
        while depth[x] > depth[y]:
            k, px, fwd = parent[x]
            up.append((k, not fwd))
            x = px
        while depth[y] > depth[x]:
            k, py, fwd = parent[y]
            down.append((k, fwd))
            y = py
        while x != y:
            k, px, fwd = parent[x]
            up.append((k, not fwd))
            x = px
            k, py, fwd = parent[y]
            down.append((k, fwd))
            y = py
        loops.append([(c, True)] + up + down[::-1])
    return order, tree_idx, roots, comps, chords, loops


# --------------------------------------------------------------------------- small numerics

def length_columns(mech) -> np.ndarray:
    """Boolean mask (n,) of the flat value vector's length-valued entries (translations)."""
    mask = []
    for p in mech.pairs:
        mask.extend(u == "L" for u in p.type.value_units)
    return np.array(mask, dtype=bool)


# --------------------------------------------------------------------------- loop closure

def _residual_and_jacobian(T_loop, J_a):
    """``(p, phi)`` of loop placements (..., 4, 4) and its Jacobian from the twist Jacobian
    (..., 6, n) in the loop's start frame: ``dp = v + w x p``, ``dphi = Jl(phi)^-1 w``."""
    p = T_loop[..., :3, 3]
    phi = rotation_vector(T_loop[..., :3, :3])
    r = np.concatenate([p, phi], axis=-1)
    Jv = J_a[..., :3, :] - hat3(p) @ J_a[..., 3:, :]
    Jw = left_jacobian_inverse(phi) @ J_a[..., 3:, :]
    return r, np.concatenate([Jv, Jw], axis=-2)


def _loop_twists(pl, Q, loops=None):
    """:func:`solver.loop_twists`, a pair without a motion reported as UnsupportedPairError."""
    try:
        return loop_twists(pl, Q, loops)
    except (UnsupportedPairError, ValueError, TypeError) as err:
        raise UnsupportedPairError(f"loop closure needs the motion of pair(s) without one here ({err})") from err


def loop_closure(mech, structure: Structure, q):
    """Loop-closure residual and its Jacobian for pair values ``q`` (..., n), in metres and
    radians: a view on the solver's loops (:func:`p105cli.kinematics.solver.loop_twists`).

    Returns ``(r, J)``: ``r`` (..., 6 L) stacks ``(p, phi)`` per loop in
    ``structure.loops`` order (see the module docstring: translation of the
    loop placement in metres, rotation vector in radians, both in the frame
    of the loop's first link); ``J`` (..., 6 L, n) is ``dr/dq`` with columns
    in :attr:`Mechanism.value_slices` order. Leading axes of ``q`` are batch
    axes. Raises :class:`UnsupportedPairError` when a pair of a loop has no
    motion defined.
    """
    q = np.asarray(q, dtype=np.float64)
    n = mech.value_count
    if q.ndim < 1 or q.shape[-1] != n:
        raise ValueError(f"q must have shape (..., {n}) (the flat pair-value vector), got {q.shape}")
    batch = q.shape[:-1]
    L = len(structure.loops)
    if L == 0:
        return np.zeros(batch + (0,)), np.zeros(batch + (0, n))
    Tl, J = _loop_twists(structure._plan, q.reshape(-1, n))
    r, Jr = _residual_and_jacobian(Tl, J.reshape(-1, L, 6, n))
    return r.reshape(batch + (6 * L,)), Jr.reshape(batch + (6 * L, n))


# --------------------------------------------------------------------------- analysis

def analyse(mech, *, tol: float | None = None) -> Structure:
    """Graph, loops and mobility of ``mech`` at its initial state (see the module docstring).

    ``tol``: relative rank tolerance (dimensionless, default :data:`DEFAULT_TOL`).
    """
    tol = DEFAULT_TOL if tol is None else float(tol)
    if not (tol > 0.0 and np.isfinite(tol)):
        raise ValueError(f"tol must be a positive number, got {tol!r}")
    pairs = mech.pairs
    names = [p.name for p in pairs]
    order, tree_idx, roots, comps, chords, loops = topology(mech)
    pl = plan(mech)
    link_comp = {ln: ci for ci, comp in enumerate(comps) for ln in comp}
    n = pl.nv
    slices = pl.slices          # by pair index
    size = float(pl.size)       # mech.size()
    notes = []

    q0 = mech.initial_vector()
    X, T, bad = link_poses(pl, q0, unsupported="skip")
    X = {ln: X[i] for ln, i in pl.link_index.items()}
    for k in sorted(bad):
        notes.append(f"pair {names[k]!r} ({pairs[k].kind}): no motion available ({bad[k]}), "
                     "so the rank mobility of its component is not computed")
    # Length scale for the dimensionless Jacobian: the model size, or the pair frames'
    # distance from their component's root when that is larger.
    for k, p in enumerate(pairs):
        X2 = X.get(p.link2)
        if X2 is not None:
            size = max(size, float(np.linalg.norm((X2 @ p.P2)[:3, 3])))
    lengths = length_columns(mech)
    col_scale = np.where(lengths, size, 1.0)

    loop_comp = [link_comp[pairs[lp[0][0]].link1] for lp in loops]
    components, worst_closure = [], 0.0
    for ci, comp in enumerate(comps):
        comp_set = set(comp)
        cpairs = [k for k, p in enumerate(pairs) if p.link1 in comp_set]
        cloops = [li for li, c in enumerate(loop_comp) if c == ci]
        floating = comp[0] != mech.base
        dof = sum(pairs[k].freedoms for k in cpairs)  # a locked value is no freedom
        n_links, n_joints = len(comp), len(cpairs)
        gruebler = 6 * (n_links - (0 if floating else 1) - n_joints) + dof
        c = Component(links=list(comp), root=comp[0], pairs=[names[k] for k in cpairs],
                      loops=cloops, floating=floating, dof=dof, mobility_gruebler=gruebler)
        if not cloops:
            c.rank, c.redundant_constraints = 0, 0
            c.mobility = dof + (6 if floating else 0)
        elif not (set(cpairs) & set(bad)):
            _rank_analysis(mech, pl, c, cloops, cpairs, q0, X, T, n, slices, size, col_scale, tol)
            worst_closure = max(worst_closure, c.closure_residual)
        components.append(c)

    def total(attr):
        vals = [getattr(c, attr) for c in components]
        return None if any(v is None for v in vals) else int(sum(vals))

    mobility = total("mobility")
    redundant = total("redundant_constraints")
    rank = total("rank")
    rtol_used = max([tol] + [_rank_rtol(tol, c.closure_residual) for c in components if c.loops])
    if worst_closure > 1e-6:
        notes.append(f"the initial state does not close the loops (largest residual {worst_closure:.3g} "
                     "relative to the model size): mobility by rank is taken at a state that is not assembled")
    redundant_joints = sorted({j for c in components for j in c.redundant_joints},
                              key=names.index)
    return Structure(
        mechanism=mech.name, base=mech.base, order=order,
        tree=[(names[k], u, v, fwd) for k, u, v, fwd in tree_idx],
        chords=[names[k] for k in chords],
        loops=[[(names[k], fwd) for k, fwd in lp] for lp in loops],
        kind="network" if loops else "tree", components=components, dof=sum(p.freedoms for p in pairs),
        mobility_gruebler=int(sum(c.mobility_gruebler for c in components)),
        mobility=mobility, redundant_constraints=redundant, redundant_joints=redundant_joints,
        rank=rank, tol=rtol_used, closure_residual=worst_closure, size=size, notes=notes, _plan=pl)


def _rank_rtol(tol, closure):
    # A state closed only to `closure` cannot resolve singular values finer than about that; past
    # 1e-4 the state is not assembled at all (a note says so) and the generic rank is the best guess.
    return max(tol, min(100.0 * closure, 1e-4))


def _rank_analysis(mech, pl, comp: Component, loop_ids, cpairs, q0, X, T, n, slices, size, col_scale, tol):
    """Rank, mobility, redundant constraints and the joints carrying them, for one component.

    The Jacobian is the solver's loop closure (:func:`solver.loop_twists`; the residual's
    Jacobian is an invertible map of it), each loop's rows turned from its start link's frame
    into the component root's (``Ad(X_a)``; :func:`solver.root_loop_twists`, each pair
    evaluated once), so that the self-stresses of different loops add up as wrenches in one
    frame. The closure reported is that of the initial state as
    forward kinematics places it (``X``, ``T``: :func:`solver.link_poses`): for the chord
    from link a to link b, ``T_chord X_b^-1 X_a``, which is ``T_loop``."""
    pairs = mech.pairs
    try:
        Jt = root_loop_twists(pl, q0, [X[ln] for ln in pl.link_names], loop_ids)
    except (UnsupportedPairError, ValueError, TypeError) as err:
        raise UnsupportedPairError(f"loop closure needs the motion of pair(s) without one here ({err})") from err
    closure = 0.0
    for li in loop_ids:
        c = pl.loops[li][0][0]
        a, b = pairs[c].link1, pairs[c].link2
        T_loop = T[c] @ inverse(X[b]) @ X[a]
        p = T_loop[:3, 3]
        phi = rotation_vector(T_loop[:3, :3])
        closure = max(closure, float(np.linalg.norm(p)) / size, float(np.linalg.norm(phi)))
    loops = [pl.loops[li] for li in loop_ids]
    cols = np.concatenate([np.arange(n)[slices[k]] for k in cpairs]) if cpairs else \
        np.zeros(0, dtype=int)
    J = Jt[:, cols]
    row_scale = np.tile(np.r_[np.full(3, 1.0 / size), np.ones(3)], len(loops))
    Jn = row_scale[:, None] * J * col_scale[cols][None, :]
    # U must span the whole row space (the left null space is wanted); V is not needed in full.
    U, s, _ = np.linalg.svd(Jn, full_matrices=Jn.shape[0] > Jn.shape[1])
    rtol = _rank_rtol(tol, closure)
    rank = int(np.sum(s > rtol * s[0])) if s.size and s[0] > 0.0 else 0
    comp.rank = rank
    comp.singular_values = [float(x) for x in s]
    comp.closure_residual = closure
    comp.mobility = comp.dof - rank + (6 if comp.floating else 0)
    comp.redundant_constraints = 6 * len(loops) - rank
    if comp.redundant_constraints:
        N = U[:, rank:].reshape(len(loops), 6, -1)      # self-stresses (left null space), per loop
        pos = {k: i for i, k in enumerate(cpairs)}
        sign = np.zeros((len(loops), len(cpairs)))       # loop-joint incidence, signed by direction
        for li, lp in enumerate(loops):
            for k, fwd in lp:
                sign[li, pos[k]] = 1.0 if fwd else -1.0
        W = np.einsum("lj,lrk->jrk", sign, N)             # wrench each joint carries, per self-stress
        in_loop = np.any(sign != 0.0, axis=0)
        heavy = np.max(np.abs(W), axis=(1, 2)) > _CARRY_TOL
        comp.redundant_joints = [pairs[k].name for i, k in enumerate(cpairs) if in_loop[i] and heavy[i]]
