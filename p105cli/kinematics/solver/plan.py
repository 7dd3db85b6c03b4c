"""The compiled mechanism (:class:`Plan`), the solver's errors, and what every analysis needs
of the values: which are angles, their scale, their ranges.

A :class:`Plan` is built once per mechanism (:func:`plan`) and is immutable
in what it describes; the constants that evaluation derives from it (per
pair, per tree step, per loop) are filled in on first use into its explicit
cache fields.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..spatial import adjoint, inverse

#: Status of a configuration, from best to worst (records and the summary use these words).
STATUSES = ("ok", "out_of_range", "singular", "branch_change", "not_converged", "not_assemblable")

_PERIODIC_KINDS = ("revolute", "cylindrical", "universal", "homokinetic", "planar")


class SolveError(ValueError):
    """A request the solver cannot honour (unknown pair, no path to a link...)."""


class BranchUndefined(SolveError):
    """A branch was asked for (``branch=+1/-1``) where the invariant is not defined: no loop
    unknowns, the passive values not fixed by the loops, or a singular initial state."""


@dataclass
class Plan:
    """A mechanism compiled for evaluation (immutable description + index arrays).

    ``tree`` and ``loops`` are :func:`p105cli.kinematics.graph.topology`'s (the one
    spanning-tree walk) with pair and link indices; ``roots`` are the links the connected
    components grow from (the base link first)."""

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
    roots: tuple = (0,)                              # link index of each component's root
    # Constants derived on first use by forward.py and closure.py (not part of the description):
    revolute_consts: dict = field(default_factory=dict, repr=False, compare=False)  # pair -> (3, 4, 4)
    const_twists: dict = field(default_factory=dict, repr=False, compare=False)     # (pair, fwd) -> (6, n)
    forward_steps: list | None = field(default=None, repr=False, compare=False)    # one per tree entry
    revolute_loops: dict = field(default_factory=dict, repr=False, compare=False)  # loop -> constants

    @property
    def nv(self) -> int:
        return int(self.angle_mask.size)

    def locked_values(self) -> np.ndarray:
        """(nv,) True where a pair's flags lock the value (``PairType.locked``): no unknown of
        the solvers, so it stays exactly as given."""
        out = np.zeros(self.nv, dtype=bool)
        for k, sl in enumerate(self.slices):
            out[sl] = self.types[k].locked(self.params[k])
        return out

    def loop_values(self) -> np.ndarray:
        """Flat indices of the free values of every pair that lies on a loop."""
        locked = self.locked_values()
        idx = sorted({i for lp in self.loops for k, _ in lp for i in range(*self.slices[k].indices(self.nv))
                      if not locked[i]})
        return np.array(idx, dtype=int)


def angle_value_mask(pair) -> list:
    """Which of a pair's values are angles (the rest are lengths): ``PairType.value_units``."""
    return list(pair.type.angle_mask)


def plan(mech) -> Plan:
    """Compile ``mech`` (a :class:`p105cli.kinematics.model.Mechanism`) for the solvers."""
    from ..graph import topology

    order, tree, roots, _, _, loops = topology(mech)
    reached = set(order)
    missing = [n for n in mech.link_names if n not in reached]
    if missing:
        raise SolveError(f"mechanism {mech.name!r}: links {missing} are not connected to the base "
                         f"link {mech.base!r}")
    link_index = {n: i for i, n in enumerate(order)}
    value_slices = mech.value_slices   # a property that walks every pair: once
    slices, mask = [], []
    for p in mech.pairs:
        slices.append(value_slices[p.name])
        mask.extend(angle_value_mask(p))
    P1 = np.array([p.P1 for p in mech.pairs]).reshape(-1, 4, 4)
    P2 = np.array([p.P2 for p in mech.pairs]).reshape(-1, 4, 4)
    P2inv = inverse(P2) if len(P2) else P2
    AdP2 = adjoint(P2) if len(P2) else np.zeros((0, 6, 6))
    tree_idx = [(k, link_index[u], link_index[v], bool(f)) for k, u, v, f in tree]
    parent_of = {c: i for i, (_, _, c, _) in enumerate(tree_idx)}
    return Plan(mech, tuple(order), link_index, tuple(mech.pair_names), slices, np.array(mask, dtype=bool),
                tree_idx, [[(k, bool(f)) for k, f in lp] for lp in loops], mech.size(),
                P1, P2, P2inv, AdP2, [p.motion_params() for p in mech.pairs], [p.type for p in mech.pairs],
                parent_of, tuple(link_index[r] for r in roots))


def value_scale(pl: Plan) -> np.ndarray:
    """Per-value scale that makes lengths dimensionless (1 for angles, 1/size for lengths)."""
    return np.where(pl.angle_mask, 1.0, 1.0 / pl.size)



def wrap_periodic(pl: Plan, Q) -> np.ndarray:
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


def out_of_range(pl: Plan, Q, rtol=1e-9) -> list:
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
