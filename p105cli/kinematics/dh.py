"""Denavit-Hartenberg tables and Part 105 mechanisms (ISO 10303-105 Annex F).

A DH table describes a serial chain of revolute (``R``) and prismatic
(``P``) joints, joint ``k`` moving link ``k`` against link ``k-1``:

* **standard** DH: ``A_k = Rz(theta_k) Tz(d_k) Tx(a_k) Rx(alpha_k)`` (joint k
  turns or slides about/along ``z_(k-1)``);
* **modified** DH (Craig): ``A_k = Rx(alpha_(k-1)) Tx(a_(k-1)) Rz(theta_k) Tz(d_k)``,
  with ``alpha_(k-1)``, ``a_(k-1)`` stored on row k (as roboticstoolbox does);
* the joint variable ``q_k`` replaces ``theta_k`` of a revolute joint and
  ``d_k`` of a prismatic joint, plus the constant ``offset_k``:
  ``theta_k = q_k + offset_k`` (R), ``d_k = q_k + offset_k`` (P); the
  replaced field must be empty or 0 (a constant belongs in ``offset``);
* end pose ``T = base . A_1(q_1) ... A_n(q_n) . tool``.

The mechanism (:func:`to_mechanism`) has links ``link0`` (the base, fixed)
to ``linkN`` whose link frames *are* the DH frames, one pair per joint named
after it (``link(k-1)`` first, ``link k`` second), and the initial state
``q = 0``. ``base`` is the mechanism's ``T_world_base``; ``tool`` is the
named frame ``"tool"`` of the last link, so the end pose is
``T_world_base . T_link0_linkN(q) . linkN.frames["tool"]``
(:func:`chain_pose`).

Pair frames (Annex F, extended to offsets, prismatic joints and the modified
convention; pair motion ``T_link1_link2(q) = P1 Mz(q) inv(P2)`` with
``Mz = Rz`` (R) or ``Tz`` (P), so ``P1`` holds what comes *before* the
joint's motion in ``A_k`` and ``inv(P2)`` what comes after it)::

    standard  R: P1 = I                      P2 = inv(Rz(offset) Tz(d) Tx(a) Rx(alpha))
                 su_1 = (0, 0, 0, 0, 0, 0)    su_2 = (a, alpha, -d, pi - offset, 0, pi)
              P: P1 = I                      P2 = inv(Rz(theta) Tz(offset) Tx(a) Rx(alpha))
                 su_1 = (0, 0, 0, 0, 0, 0)    su_2 = (a, alpha, -offset, pi - theta, 0, pi)
    modified  R: P1 = Rx(alpha) Tx(a)        P2 = inv(Rz(offset) Tz(d))
                 su_1 = (a, alpha, 0, 0, 0, 0) su_2 = (0, 0, 0, -offset, -d, 0)
              P: P1 = Rx(alpha) Tx(a) Rz(theta)  P2 = inv(Tz(offset))
                 su_1 = (a, alpha, 0, theta, 0, 0) su_2 = (0, 0, 0, 0, -offset, 0)

(su tuples are ``(a, alpha, b, beta, c, gamma)`` of
:func:`p105cli.kinematics.placements.su_parameters`; for offset 0 the
standard revolute row is Annex F's ``b = -d, beta = gamma = pi``.) A
prismatic pair of the AP242 layout slides along x: both its frames are
turned by :data:`Z_TO_X` (x onto the 1996 z), which leaves
``T_link1_link2`` unchanged.

The way back (:func:`from_mechanism`) walks the serial chain from the base
and reads each pair's placement as a DH row; a pair whose placements are
not a DH row of the requested convention (its axis is not the DH axis of
the link frames, or the link frames are not DH frames) is named in a
:class:`DHConversionError`.

Everything is SI (metres, radians); arrays carry leading batch axes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .model import SI, Link, Mechanism, Pair, frozen_array
from .placements import su_parameters, su_parameters_from_transform
from .spatial import compose, inverse, rot_x, rot_y, rot_z, trans_x, trans_z

__all__ = [
    "CONVENTIONS", "JOINT_TYPES", "Z_TO_X", "DHJoint", "DHTable", "DHConversionError",
    "dh_transform", "joint_transforms", "forward", "annex_f", "to_mechanism", "serial_chain",
    "chain_pose", "from_mechanism",
]

CONVENTIONS = ("standard", "modified")
#: Joint type letters of a DH table and the pair kinds they become.
JOINT_TYPES = {"R": "revolute", "P": "prismatic"}

#: Post-multiplied to both frames of a prismatic pair in the AP242 layout (which slides
#: along x): ``Ry(-pi/2)`` turns the frame's x axis onto its 1996 z axis.
Z_TO_X = rot_y(-math.pi / 2)

COLUMNS = ("name", "type", "a", "alpha", "d", "theta", "offset")
OPTIONAL_COLUMNS = ("lower", "upper")

_PI = math.pi
DEG = _PI / 180.0
_NOISE = 16.0 * np.finfo(float).eps


def _wrap(x: float) -> float:
    """An angle in (-pi, pi], never -0.0."""
    y = _PI - math.fmod(_PI - float(x), 2.0 * _PI)
    if y <= -_PI:
        y += 2.0 * _PI
    elif y > _PI:
        y -= 2.0 * _PI
    return y + 0.0


# ------------------------------------------------------------------ the table

@dataclass(frozen=True)
class DHJoint:
    """One row of a DH table (SI: metres, radians).

    ``type`` is ``"R"`` or ``"P"``; the replaced field (``theta`` of R,
    ``d`` of P) is 0. ``lower``/``upper`` limit the joint variable q (None:
    unlimited)."""

    name: str
    type: str
    a: float
    alpha: float
    d: float = 0.0
    theta: float = 0.0
    offset: float = 0.0
    lower: Optional[float] = None
    upper: Optional[float] = None

    def __post_init__(self):
        if self.type not in JOINT_TYPES:
            raise ValueError(f"joint {self.name!r}: type must be R or P, got {self.type!r}")

    @property
    def kind(self) -> str:
        return JOINT_TYPES[self.type]

    def dh_values(self, q):
        """``(a, alpha, d, theta)`` at joint variable ``q`` (broadcast)."""
        q = np.asarray(q, dtype=np.float64)
        if self.type == "R":
            return self.a, self.alpha, np.full(q.shape, self.d), q + self.offset
        return self.a, self.alpha, q + self.offset, np.full(q.shape, self.theta)


@dataclass(frozen=True)
class DHTable:
    """A DH table: convention, joints (base to tip), base and tool transforms (4x4)."""

    convention: str
    joints: tuple
    base: np.ndarray = field(default_factory=lambda: np.eye(4))
    tool: np.ndarray = field(default_factory=lambda: np.eye(4))
    name: str = "dh_arm"

    def __post_init__(self):
        if self.convention not in CONVENTIONS:
            raise ValueError(f"DH convention must be one of {CONVENTIONS}, got {self.convention!r}")
        object.__setattr__(self, "joints", tuple(self.joints))
        if not self.joints:
            raise ValueError("a DH table needs at least one joint")
        names = [j.name for j in self.joints]
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise ValueError(f"duplicate joint names in the DH table: {dup}")
        object.__setattr__(self, "base", frozen_array(self.base, (4, 4)))
        object.__setattr__(self, "tool", frozen_array(self.tool, (4, 4)))


class DHConversionError(ValueError):
    """A mechanism that is not a DH chain; ``pair`` names the first offending pair (or None)."""

    def __init__(self, message: str, pair: Optional[str] = None):
        super().__init__(message)
        self.pair = pair


# ------------------------------------------------------------------ DH products

def dh_transform(convention: str, a, alpha, d, theta) -> np.ndarray:
    """``A`` (..., 4, 4) of one DH row: standard ``Rz(theta) Tz(d) Tx(a) Rx(alpha)``,
    modified ``Rx(alpha) Tx(a) Rz(theta) Tz(d)``; arguments broadcast."""
    if convention == "standard":
        return compose(rot_z(theta), trans_z(d), trans_x(a), rot_x(alpha))
    if convention == "modified":
        return compose(rot_x(alpha), trans_x(a), rot_z(theta), trans_z(d))
    raise ValueError(f"DH convention must be one of {CONVENTIONS}, got {convention!r}")


def joint_transforms(table: DHTable, q) -> np.ndarray:
    """``A_k(q_k)`` for every joint: (..., n, 4, 4) from ``q`` (..., n)."""
    q = np.asarray(q, dtype=np.float64)
    n = len(table.joints)
    if q.ndim < 1 or q.shape[-1] != n:
        raise ValueError(f"q must have shape (..., {n}), got {q.shape}")
    return np.stack([dh_transform(table.convention, *j.dh_values(q[..., k]))
                     for k, j in enumerate(table.joints)], axis=-3)


def forward(table: DHTable, q) -> np.ndarray:
    """The plain DH product ``base . A_1(q_1) ... A_n(q_n) . tool``: (..., 4, 4)."""
    A = joint_transforms(table, q)
    T = np.broadcast_to(table.base, A.shape[:-3] + (4, 4))
    for k in range(A.shape[-3]):
        T = T @ A[..., k, :, :]
    return T @ table.tool


# ------------------------------------------------------------------ Annex F: DH -> SU

def annex_f(convention: str, joint: DHJoint) -> tuple:
    """``(su_1, su_2)``: Sheth-Uicker parameters ``(a, alpha, b, beta, c, gamma)`` of the
    pair frames on link k-1 and link k (1996 layout: the pair moves along/about z)."""
    a, al, off = float(joint.a), float(joint.alpha), float(joint.offset)
    if convention == "standard":
        zero = (0.0,) * 6
        if joint.type == "R":
            return zero, (a, _wrap(al), -float(joint.d) + 0.0, _wrap(_PI - off), 0.0, _PI)
        return zero, (a, _wrap(al), -off + 0.0, _wrap(_PI - float(joint.theta)), 0.0, _PI)
    if convention == "modified":
        if joint.type == "R":
            return (a, _wrap(al), 0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, _wrap(-off), -float(joint.d) + 0.0, 0.0)
        return (a, _wrap(al), 0.0, _wrap(joint.theta), 0.0, 0.0), (0.0, 0.0, 0.0, 0.0, -off + 0.0, 0.0)
    raise ValueError(f"DH convention must be one of {CONVENTIONS}, got {convention!r}")


def _layout_frame(su: tuple, prismatic_ap242: bool):
    """(su, P) of a pair frame; an AP242 prismatic frame is turned so x is the slide axis."""
    P = su_parameters(*su)
    if prismatic_ap242:
        su = tuple(float(v) for v in su_parameters_from_transform(compose(P, Z_TO_X)))
        P = su_parameters(*su)
    return su, P


def to_mechanism(table: DHTable, layout: str = "1996", name: Optional[str] = None) -> Mechanism:
    """The Part 105 mechanism of a DH table (see the module docstring).

    ``layout`` is ``"1996"`` (AP214 / p105 files: prismatic pairs slide
    along z) or ``"ap242"`` (slide along x). Pair frames are exactly
    ``su_parameters(*params["su_k"])`` so that a writer can write them as
    su_parameters or as the equivalent axis2_placement_3d.
    """
    if layout not in ("1996", "ap242"):
        raise ValueError(f"layout must be '1996' or 'ap242', got {layout!r}")
    n = len(table.joints)
    links = [Link("link0", description="base link (DH frame 0)")]
    pairs = []
    for k, j in enumerate(table.joints, start=1):
        frames = {"tool": table.tool} if k == n else {}
        links.append(Link(f"link{k}", description=f"DH link {k} (moved by joint {j.name})", frames=frames))
        su1, su2 = annex_f(table.convention, j)
        turn = j.type == "P" and layout == "ap242"
        su1, P1 = _layout_frame(su1, turn)
        su2, P2 = _layout_frame(su2, turn)
        params = {"su_1": su1, "su_2": su2}
        if j.type == "P":
            params["layout"] = layout
        pairs.append(Pair(j.name, j.kind, f"link{k - 1}", f"link{k}", P1, P2, params=params,
                          lower=(j.lower,), upper=(j.upper,), actuated=True,
                          description=f"DH joint {k} ({table.convention}, {j.type})"))
    return Mechanism(name or table.name, links, pairs, "link0", T_world_base=table.base,
                     initial={j.name: (0.0,) for j in table.joints}, units=SI,
                     description=f"from a {table.convention} DH table ({n} joints)")


# ------------------------------------------------------------------ serial chains

def serial_chain(mech: Mechanism) -> list:
    """The pairs from the base to the tip as ``[(pair, forward)]``, ``forward`` True when the
    pair's first link is the one nearer the base: the spanning tree of
    :func:`p105cli.kinematics.graph.topology`. DHConversionError when the pairs do not form
    one unbranched open chain from the base link."""
    from .graph import topology

    _, tree, _, _, chords, _ = topology(mech)
    if chords:
        p = _closing_pair(mech)
        raise DHConversionError(f"pair {p.name!r} closes a loop (between {p.link1!r} and {p.link2!r}): "
                                "a DH table describes an open serial chain", p.name)
    children = {}
    for k, parent, child, forward in tree:
        children.setdefault(parent, []).append((mech.pairs[k], child, forward))
    chain, used = [], set()
    link = mech.base
    while children.get(link):
        nxt = children[link]
        if len(nxt) > 1:
            raise DHConversionError(
                f"link {link!r} branches into pairs {', '.join(repr(p.name) for p, _, _ in nxt)}: "
                "a DH table describes one unbranched serial chain", nxt[1][0].name)
        p, link, forward = nxt[0]
        used.add(p.name)
        chain.append((p, forward))
    rest = [p for p in mech.pairs if p.name not in used]
    if rest:
        raise DHConversionError(f"pair {rest[0].name!r} is not on the serial chain from the base link "
                                f"{mech.base!r}", rest[0].name)
    if not chain:
        raise DHConversionError(f"mechanism {mech.name!r} has no pair at its base link {mech.base!r}")
    return chain


def _closing_pair(mech: Mechanism):
    """The pair a loop is blamed on: the first, in model order, that joins two links already
    joined by the pairs before it."""
    root = {ln: ln for ln in mech.link_names}

    def find(x):
        while root[x] != x:
            root[x] = root[root[x]]
            x = root[x]
        return x

    for p in mech.pairs:
        r1, r2 = find(p.link1), find(p.link2)
        if r1 == r2:
            return p
        root[r1] = r2
    raise AssertionError("no pair closes a loop")  # topology found a chord: unreachable


def _oriented(pair: Pair, forward: bool, q) -> np.ndarray:
    T = pair.transform(np.asarray(q, dtype=np.float64)[..., None])
    return T if forward else inverse(T)


def chain_pose(mech: Mechanism, q, *, tool: str | None = "tool") -> np.ndarray:
    """End pose ``T_world_base . T_base_tip(q) . tip.frames[tool]`` (..., 4, 4) of a serial
    chain of one-value pairs, ``q`` (..., n) in chain order (base to tip), by the solver's
    forward kinematics; the tool frame is left out when the tip link has none (or ``tool``
    is None)."""
    from .solver import forward, plan

    chain = serial_chain(mech)
    q = np.asarray(q, dtype=np.float64)
    if q.ndim < 1 or q.shape[-1] != len(chain):
        raise ValueError(f"q must have shape (..., {len(chain)}), got {q.shape}")
    many = [p.name for p, _ in chain if p.value_count != 1]
    if many:
        raise ValueError(f"pairs {many} have more than one value: q gives one per pair")
    pl = plan(mech)
    cols = [mech.value_slices[p.name].start for p, _ in chain]
    Q = np.zeros((int(np.prod(q.shape[:-1], dtype=int)), pl.nv))
    Q[:, cols] = q.reshape(-1, len(chain))
    p, fwd = chain[-1]
    tip = p.link2 if fwd else p.link1
    T = forward(pl, Q)[:, pl.link_index[tip]].reshape(q.shape[:-1] + (4, 4))
    frame = None if tool is None else _named_frame(mech.link(tip), tool)
    return T if frame is None else T @ frame


def _named_frame(link: Link, name: str):
    """The link's frame ``name``; a file written by p105 names it ``"<link> <name>"``."""
    frames = link.frames
    return frames.get(name, frames.get(f"{link.name} {name}"))


# ------------------------------------------------------------------ model -> DH

def _decompose(convention: str, T: np.ndarray) -> tuple:
    """``(a, alpha, d, theta)`` read from a 4x4 that is meant to be one DH transform."""
    R, p = T[:3, :3], T[:3, 3]
    if convention == "standard":
        theta = math.atan2(R[1, 0], R[0, 0])
        alpha = math.atan2(R[2, 1], R[2, 2])
        return p[0] * math.cos(theta) + p[1] * math.sin(theta), alpha, p[2], theta
    alpha = math.atan2(-R[1, 2], R[2, 2])
    theta = math.atan2(-R[0, 1], R[0, 0])
    return p[0], alpha, -math.sin(alpha) * p[1] + math.cos(alpha) * p[2], theta


def _misfit(A: np.ndarray, B: np.ndarray, length: float) -> float:
    """Largest difference of two transforms, translations measured in units of ``length``."""
    return max(float(np.abs(A[..., :3, :3] - B[..., :3, :3]).max()),
               float(np.abs(A[..., :3, 3] - B[..., :3, 3]).max()) / length)


def from_mechanism(mech: Mechanism, convention: str, *, tol: float = 1e-9) -> DHTable:
    """The DH table of a serial chain of revolute and prismatic pairs whose link frames are
    DH frames of ``convention``; base = ``T_world_base``, tool = the tip link's ``"tool"``
    frame (identity when absent). Raises DHConversionError naming the first pair that is
    not a DH row (``tol``: on rotations, and on lengths relative to the model's size)."""
    if convention not in CONVENTIONS:
        raise ValueError(f"DH convention must be one of {CONVENTIONS}, got {convention!r}")
    chain = serial_chain(mech)
    size = max(mech.size(), float(np.abs(mech.T_world_base[:3, 3]).max()), 1e-3)
    joints, tip = [], mech.base
    for p, fwd in chain:
        parent, child = (p.link1, p.link2) if fwd else (p.link2, p.link1)
        tip = child
        where = f"pair {p.name!r} ({parent} -> {child})"
        if p.kind not in JOINT_TYPES.values():
            raise DHConversionError(f"{where} is a {p.kind} pair: a DH row is a revolute or prismatic "
                                    "joint", p.name)
        jt = "R" if p.kind == "revolute" else "P"
        # The joint axis in the parent's and the child's link coordinates (1996 sense: +z of the
        # pair frames; an AP242 prismatic pair slides along its frames' x).
        slide_x = jt == "P" and p.motion_params().get("layout", "1996") == "ap242"
        axis_col = 0 if slide_x else 2
        P_parent, P_child = (p.P1, p.P2) if fwd else (p.P2, p.P1)
        sense = 1.0 if fwd else -1.0
        u_parent, o_parent = sense * P_parent[:3, axis_col], P_parent[:3, 3]
        u_child, o_child = sense * P_child[:3, axis_col], P_child[:3, 3]
        if convention == "standard":
            u, o, frame = u_parent, o_parent, parent
        else:
            u, o, frame = u_child, o_child, child
        off_axis = float(np.abs(u - (0.0, 0.0, 1.0)).max())
        if jt == "R":
            off_axis = max(off_axis, float(np.abs(o[:2]).max()) / size)
        if off_axis > tol:
            what = "axis" if jt == "R" else "slide direction"
            raise DHConversionError(
                f"{where}: its placements are not a {convention} DH row: the pair's {what} is not "
                f"the +z axis of {frame} (off by {off_axis:.3g}; {convention} DH moves joint k "
                f"{'about' if jt == 'R' else 'along'} z of link {'k-1' if convention == 'standard' else 'k'})",
                p.name)
        T0 = _oriented(p, fwd, 0.0)
        a, alpha, d, theta = _decompose(convention, T0)
        A0 = dh_transform(convention, a, alpha, d, theta)
        bad = _misfit(A0, T0, size)
        if bad > tol:
            frames = (f"the x axis of {child} does not cross the z axis of {parent} at a right angle"
                      if convention == "standard" else
                      f"the z axis of {child} does not cross the x axis of {parent} at a right angle")
            raise DHConversionError(f"{where}: its placements are not a {convention} DH row: {frames} "
                                    f"(off by {bad:.3g})", p.name)
        # Rounding noise of the file's numbers (1e-33 for a zero, 4e-16 for a zero angle) is not a
        # DH parameter: values within 16 eps of zero (lengths: of the model's size) are zero.
        a, d = (0.0 if abs(v) <= _NOISE * size else float(v) + 0.0 for v in (a, d))
        alpha, theta = (0.0 if abs(w) <= _NOISE else w for w in (_wrap(alpha), _wrap(theta)))
        if jt == "R":
            row = DHJoint(p.name, "R", a, alpha, d=d, offset=theta)
        else:
            row = DHJoint(p.name, "P", a, alpha, theta=theta, offset=d)
        # Safety net: the row must give the pair's motion at other values too.
        qs = np.array([0.9, -2.1]) if jt == "R" else np.array([1.0, -0.6]) * size
        bad = _misfit(dh_transform(convention, *row.dh_values(qs)), _oriented(p, fwd, qs), size)
        if bad > tol:
            raise DHConversionError(f"{where}: its placements are not a {convention} DH row "
                                    f"(motion differs by {bad:.3g})", p.name)
        lo, up = p.lower[0], p.upper[0]
        if not fwd:
            lo, up = (None if up is None else -up), (None if lo is None else -lo)
        joints.append(DHJoint(row.name, row.type, row.a, row.alpha, row.d, row.theta, row.offset, lo, up))
    tool = _named_frame(mech.link(tip), "tool")
    tool = np.eye(4) if tool is None else tool
    return DHTable(convention, joints, mech.T_world_base, tool, name=mech.name)
