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

import json
import math
import re
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .model import SI, Link, Mechanism, Pair, frozen_array
from .placements import (
    compose, inverse, rot_x, rot_y, rot_z, su_parameters, su_parameters_from_transform, trans_x, trans_z,
)

__all__ = [
    "CONVENTIONS", "JOINT_TYPES", "Z_TO_X", "DHJoint", "DHTable", "DHTableError", "DHConversionError",
    "dh_transform", "joint_transforms", "forward", "annex_f", "to_mechanism", "serial_chain",
    "chain_pose", "from_mechanism", "read_csv", "read_json", "looks_like_dh", "write_csv", "write_json",
    "is_identity",
]

CONVENTIONS = ("standard", "modified")
#: Joint type letters of a DH table and the pair kinds they become.
JOINT_TYPES = {"R": "revolute", "P": "prismatic"}
_TYPE_NAMES = {"r": "R", "revolute": "R", "p": "P", "prismatic": "P"}

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


class DHTableError(ValueError):
    """A DH table that cannot be read; ``str()`` says where (``FILE:LINE:COL`` or ``FILE:/pointer``)."""

    def __init__(self, message: str, source: str = "<input>", line: int = 0, column: int = 0,
                 pointer: str = ""):
        super().__init__(message)
        self.message, self.source, self.line, self.column, self.pointer = message, source, line, column, pointer

    def __str__(self) -> str:
        if self.line:
            return f"{self.source}:{self.line}:{max(self.column, 1)}: {self.message}"
        if self.pointer:
            return f"{self.source}:{self.pointer}: {self.message}"
        return f"{self.source}: {self.message}"


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


# ------------------------------------------------------------------ reading tables

_REAL = r"(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_NUMBER = re.compile(rf"""^\s*(?P<sign>[-+]?)\s*(?:
        (?P<num>{_REAL})
      | (?:(?P<mul>{_REAL})\s*\*\s*)?pi(?:\s*/\s*(?P<div>{_REAL}))?
    )\s*$""", re.X | re.I)


def _number(text: str) -> float:
    """A finite real: a decimal number, or ``[k*]pi[/m]`` with an optional sign."""
    m = _NUMBER.match(text)
    if not m:
        raise ValueError(f"{text.strip()!r} is not a number (decimal, or pi, k*pi, pi/m, k*pi/m)")
    if m.group("num") is not None:
        v = float(m.group("num"))
    else:
        v = (float(m.group("mul")) if m.group("mul") else 1.0) * _PI
        if m.group("div"):
            div = float(m.group("div"))
            if div == 0.0:
                raise ValueError(f"{text.strip()!r}: division by zero")
            v /= div
    if not math.isfinite(v):
        raise ValueError(f"{text.strip()!r} is not a finite number")
    return -v if m.group("sign") == "-" else v


def _row_to_joint(get, deg: bool, where) -> DHJoint:
    """A DHJoint from a row accessor ``get(column) -> (text or None)``; errors via ``where(col, msg)``."""
    name = (get("name") or "").strip()
    if not name:
        raise where("name", "the joint needs a name")
    ttext = (get("type") or "").strip()
    jt = _TYPE_NAMES.get(ttext.lower())
    if jt is None:
        raise where("type", f"joint {name!r}: type must be R (revolute) or P (prismatic), got {ttext!r}")
    angle = DEG if deg else 1.0
    scale = {"a": 1.0, "alpha": angle, "d": 1.0, "theta": angle,
             "offset": angle if jt == "R" else 1.0,
             "lower": angle if jt == "R" else 1.0, "upper": angle if jt == "R" else 1.0}
    unused = "theta" if jt == "R" else "d"
    used = "d" if jt == "R" else "theta"
    vals = {}
    for col in ("a", "alpha", "d", "theta", "offset", "lower", "upper"):
        text = get(col)
        if text is None or not str(text).strip():
            if col in ("a", "alpha", used):
                raise where(col, f"joint {name!r}: {col} is missing")
            vals[col] = None if col in OPTIONAL_COLUMNS else 0.0
            continue
        try:
            vals[col] = _number(str(text)) * scale[col]
        except ValueError as err:
            raise where(col, f"joint {name!r}: {col}: {err}") from None
    if vals[unused] != 0.0:
        var = "theta = q + offset" if jt == "R" else "d = q + offset"
        raise where(unused, f"joint {name!r} is {JOINT_TYPES[jt]}: its joint variable gives {var}, so "
                            f"{unused} must be empty or 0 (a constant goes in the offset column)")
    lo, up = vals["lower"], vals["upper"]
    if lo is not None and up is not None and lo > up:
        raise where("lower", f"joint {name!r}: lower limit {lo:g} is above the upper limit {up:g}")
    return DHJoint(name, jt, vals["a"], vals["alpha"], vals["d"], vals["theta"], vals["offset"], lo, up)


def _csv_fields(line: str):
    """``[(text, column)]`` of one CSV line (RFC 4180 quotes; column 1-based)."""
    out, i, n = [], 0, len(line)
    while True:
        start = i
        if i < n and line[i] == '"':
            buf, i = [], i + 1
            while True:
                if i >= n:
                    raise ValueError((start + 1, "unterminated quoted field"))
                if line[i] == '"':
                    if i + 1 < n and line[i + 1] == '"':
                        buf.append('"')
                        i += 2
                        continue
                    i += 1
                    break
                buf.append(line[i])
                i += 1
            j = line.find(",", i)
            if line[i:j if j >= 0 else n].strip():
                raise ValueError((i + 1, "text after a closing quote"))
            out.append(("".join(buf), start + 1))
            i = n if j < 0 else j
        else:
            j = line.find(",", i)
            out.append((line[i:j if j >= 0 else n], start + 1))
            i = n if j < 0 else j
        if i >= n:
            return out
        i += 1  # the comma


def looks_like_dh(text: str) -> str | None:
    """``"csv"`` or ``"json"`` when ``text`` looks like a DH table, else None."""
    head = text.lstrip(" \t\r\n\ufeff")
    if head.startswith("{"):
        try:
            obj = json.loads(text.lstrip("\ufeff"))
        except ValueError:
            return None
        return "json" if isinstance(obj, dict) and "joints" in obj else None
    for line in text.splitlines():
        s = line.strip().lstrip("\ufeff")
        if not s or s.startswith("#"):
            continue
        try:
            cols = {f.strip().lower() for f, _ in _csv_fields(s)}
        except ValueError:
            return None
        return "csv" if {"name", "type"} <= cols else None
    return None


def read_csv(text: str, convention: str, *, deg: bool = False, source: str = "<input>",
             base=None, tool=None, name: str = "dh_arm") -> DHTable:
    """A DH table from CSV with the header ``name,type,a,alpha,d,theta,offset`` (any order;
    optional ``lower,upper`` columns limit q). Blank lines and lines starting with ``#`` are
    skipped. Angles in radians, or degrees with ``deg``; numbers may be ``pi``, ``k*pi/m``.
    Raises DHTableError naming ``source:line:column``."""
    if convention not in CONVENTIONS:
        raise ValueError(f"DH convention must be one of {CONVENTIONS}, got {convention!r}")
    header, joints, names = None, [], {}
    lineno = 0
    for lineno, raw in enumerate(text.lstrip("\ufeff").splitlines(), start=1):
        line = raw.rstrip("\r")
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        try:
            fields = _csv_fields(line)
        except ValueError as err:
            col, msg = err.args[0]
            raise DHTableError(msg, source, lineno, col) from None
        if header is None:
            header = {}
            for text_, col in fields:
                key = text_.strip().lower()
                if key not in COLUMNS + OPTIONAL_COLUMNS:
                    raise DHTableError(f"unknown column {text_.strip()!r}; the header is "
                                       f"{','.join(COLUMNS)} (optional: {','.join(OPTIONAL_COLUMNS)})",
                                       source, lineno, col)
                if key in header:
                    raise DHTableError(f"column {key!r} appears twice", source, lineno, col)
                header[key] = len(header)
            missing = [c for c in COLUMNS if c not in header]
            if missing:
                raise DHTableError(f"the header lacks column(s) {', '.join(missing)}; it must name "
                                   f"{','.join(COLUMNS)}", source, lineno, 1)
            continue
        if len(fields) != len(header):
            raise DHTableError(f"{len(fields)} fields, the header has {len(header)}", source, lineno,
                               fields[min(len(fields), len(header)) - 1][1])

        def get(col, fields=fields):
            i = header.get(col)
            return None if i is None else fields[i][0]

        def where(col, msg, fields=fields, lineno=lineno):
            i = header.get(col)
            return DHTableError(msg, source, lineno, fields[i][1] if i is not None else 1)

        j = _row_to_joint(get, deg, where)
        if j.name in names:
            raise DHTableError(f"joint name {j.name!r} is used twice (first on line {names[j.name]})",
                               source, lineno, fields[header["name"]][1])
        names[j.name] = lineno
        joints.append(j)
    if header is None:
        raise DHTableError(f"no header line ({','.join(COLUMNS)})", source, max(lineno, 1), 1)
    if not joints:
        raise DHTableError("the table has no joints", source, max(lineno, 1), 1)
    return DHTable(convention, joints, np.eye(4) if base is None else base,
                   np.eye(4) if tool is None else tool, name=name)


def _rigid(value, pointer: str, source: str, tol: float = 1e-9) -> np.ndarray:
    try:
        T = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        T = None
    if T is None or T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise DHTableError("expected a 4x4 matrix of numbers (rows)", source, pointer=pointer)
    R = T[:3, :3]
    if (np.abs(T[3] - (0.0, 0.0, 0.0, 1.0)).max() > tol or np.abs(R.T @ R - np.eye(3)).max() > tol
            or np.linalg.det(R) < 0.0):
        raise DHTableError("not a rigid transform (rotation block orthonormal with det +1, last row "
                           "0 0 0 1)", source, pointer=pointer)
    return T


def read_json(text: str, convention: str | None = None, *, deg: bool = False,
              source: str = "<input>") -> DHTable:
    """A DH table from JSON ``{"convention", "joints": [{name, type, a, alpha, d, theta,
    offset, lower?, upper?}], "base"?: 4x4, "tool"?: 4x4, "name"?, "angle_unit"?}``.

    ``convention`` (the command line's) must agree with the file's when both
    are given; one of them must be. ``angle_unit`` ("radian"/"degree") in the
    file overrides ``deg`` and must agree with it when ``deg`` is set.
    Raises DHTableError naming ``source:/json/pointer``."""
    try:
        obj = json.loads(text.lstrip("\ufeff"))
    except ValueError as err:
        raise DHTableError(f"not valid JSON: {err}", source) from None
    if not isinstance(obj, dict):
        raise DHTableError("a JSON DH table is an object", source, pointer="/")
    conv = obj.get("convention")
    if conv is not None and conv not in CONVENTIONS:
        raise DHTableError(f"convention must be one of {', '.join(CONVENTIONS)}, got {conv!r}", source,
                           pointer="/convention")
    if conv is not None and convention is not None and conv != convention:
        raise DHTableError(f"the file says convention {conv!r}, the command line {convention!r}", source,
                           pointer="/convention")
    conv = conv or convention
    if conv is None:
        raise DHTableError("no DH convention: give --convention standard|modified or \"convention\" in "
                           "the file", source, pointer="/convention")
    unit = obj.get("angle_unit")
    if unit is not None:
        if unit not in ("radian", "degree"):
            raise DHTableError(f"angle_unit must be 'radian' or 'degree', got {unit!r}", source,
                               pointer="/angle_unit")
        if deg and unit != "degree":
            raise DHTableError("--deg, but the file says its angles are in radians", source,
                               pointer="/angle_unit")
        deg = unit == "degree"
    rows = obj.get("joints")
    if not isinstance(rows, list) or not rows:
        raise DHTableError("\"joints\" must be a non-empty list of joints", source, pointer="/joints")
    joints, names = [], set()
    known = set(COLUMNS + OPTIONAL_COLUMNS)
    for i, row in enumerate(rows):
        ptr = f"/joints/{i}"
        if not isinstance(row, dict):
            raise DHTableError("a joint is an object", source, pointer=ptr)
        extra = sorted(set(row) - known)
        if extra:
            raise DHTableError(f"unknown key {extra[0]!r} (keys: {', '.join(COLUMNS + OPTIONAL_COLUMNS)})",
                               source, pointer=f"{ptr}/{extra[0]}")
        for key, v in row.items():
            if v is not None and not isinstance(v, (str, int, float)) or isinstance(v, bool):
                raise DHTableError("expected a number or a string", source, pointer=f"{ptr}/{key}")

        def get(col, row=row):
            v = row.get(col)
            return None if v is None else str(v) if not isinstance(v, float) else repr(v)

        def where(col, msg, ptr=ptr):
            return DHTableError(msg, source, pointer=f"{ptr}/{col}")

        j = _row_to_joint(get, deg, where)
        if j.name in names:
            raise DHTableError(f"joint name {j.name!r} is used twice", source, pointer=f"{ptr}/name")
        names.add(j.name)
        joints.append(j)
    base = _rigid(obj["base"], "/base", source) if obj.get("base") is not None else np.eye(4)
    tool = _rigid(obj["tool"], "/tool", source) if obj.get("tool") is not None else np.eye(4)
    name = obj.get("name") or "dh_arm"
    if not isinstance(name, str):
        raise DHTableError("name must be a string", source, pointer="/name")
    return DHTable(conv, joints, base, tool, name=name)


# ------------------------------------------------------------------ writing tables

def is_identity(T) -> bool:
    """Whether a 4x4 is exactly the identity (what a table without base or tool has)."""
    return bool(np.array_equal(np.asarray(T), np.eye(4)))


def _num(x: float) -> str:
    return repr(float(x) + 0.0)


def _out_values(j: DHJoint, deg: bool) -> dict:
    angle = 1.0 / DEG if deg else 1.0
    lin_or_ang = angle if j.type == "R" else 1.0
    out = {"name": j.name, "type": j.type, "a": j.a, "alpha": j.alpha * angle, "d": j.d,
           "theta": j.theta * angle, "offset": j.offset * lin_or_ang}
    out["lower"] = None if j.lower is None else j.lower * lin_or_ang
    out["upper"] = None if j.upper is None else j.upper * lin_or_ang
    return out


def write_csv(table: DHTable, out, *, deg: bool = False) -> None:
    """Write the table as CSV (``read_csv``'s format; lower/upper only when some joint has
    a limit). Base and tool are not part of the CSV format."""
    limits = any(j.lower is not None or j.upper is not None for j in table.joints)
    cols = COLUMNS + (OPTIONAL_COLUMNS if limits else ())
    out.write(",".join(cols) + "\n")
    for j in table.joints:
        v = _out_values(j, deg)
        name = v["name"]
        if any(c in name for c in ',"\n') or name != name.strip():
            v["name"] = '"' + name.replace('"', '""') + '"'
        cells = [v[c] if c in ("name", "type") else ("" if v[c] is None else _num(v[c])) for c in cols]
        out.write(",".join(cells) + "\n")


def write_json(table: DHTable, out, *, deg: bool = False) -> None:
    """Write the table as JSON (``read_json``'s format, with base, tool and angle_unit)."""
    rows = []
    for j in table.joints:
        v = _out_values(j, deg)
        rows.append({k: (val if k in ("name", "type") or val is None else float(val) + 0.0)
                     for k, val in v.items() if not (k in OPTIONAL_COLUMNS and val is None)})
    # One joint and one matrix row per line: diffable, and still plain JSON.
    def matrix(T):
        return "[\n" + ",\n".join("  " + json.dumps([float(x) + 0.0 for x in r]) for r in T) + "]"

    out.write("{\n")
    out.write(f' "name": {json.dumps(table.name)},\n "convention": {json.dumps(table.convention)},\n')
    out.write(f' "angle_unit": {json.dumps("degree" if deg else "radian")},\n')
    out.write(' "joints": [\n' + ",\n".join("  " + json.dumps(r) for r in rows) + "],\n")
    out.write(f' "base": {matrix(table.base)},\n "tool": {matrix(table.tool)}\n}}\n')
