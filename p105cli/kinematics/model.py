"""The schema-neutral mechanism model: immutable description, separate evaluation state.

One mechanism, whichever layout it came from (the Part 105:1996 layout of
AP214 / the ``p105`` profile, or AP242's ed. 2 layout), is a
:class:`Mechanism`: links, pairs (each pair *is* its joint: Part 105 ties
exactly one pair to a joint), ranges, actuation, the base link and its
placement, the initial state, and the paths of the motion program.

Conventions (pinned by tests):

* **SI inside.** Lengths in metres, angles in radians, everywhere in the
  model: placements, pair parameters, pair values, ranges, geometry. The
  reader converts from the file's unit context, the writers convert back
  (:class:`Units` keeps the file's factors so a round trip writes the same
  numbers).
* **Pair motion.** ``T_link1_link2(q) = P1 @ M(q) @ inv(P2)`` with ``M`` of
  :mod:`p105cli.kinematics.pairs`; ``P1``/``P2`` are the pair frames on the
  first and second link, in link coordinates. Higher-pair geometry
  (curves, surfaces of :mod:`p105cli.kinematics.geometry`) is held in the
  coordinates of the pair frame it belongs to (``params["curve"]``,
  ``params["surface"]``, ``..._1``/``..._2`` for the two-sided pairs).
* **Values** are tuples in the order of :attr:`PairType.value_names` of the
  pair's kind; a range is a per-value ``(lower, upper)`` with ``None`` for
  an unlimited side.
* **Immutable.** Dataclasses are frozen; arrays are read-only. Evaluation
  state (configurations, solver work) lives elsewhere (``State`` objects of
  the solvers), as in Pinocchio's Model/Data split.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Mapping, Optional

import numpy as np

__all__ = ["Units", "Link", "Pair", "Mechanism", "frozen_array", "SI"]


def frozen_array(a, shape: tuple | None = None) -> np.ndarray:
    """A read-only float64 copy of ``a`` (checked against ``shape`` when given)."""
    out = np.array(a, dtype=np.float64, copy=True)
    if shape is not None and out.shape != shape:
        raise ValueError(f"expected an array of shape {shape}, got {out.shape}")
    out.flags.writeable = False
    return out


def _frozen_mapping(m: Mapping | None) -> Mapping:
    return MappingProxyType(dict(m or {}))


@dataclass(frozen=True)
class Units:
    """The file's units as SI factors: ``value_SI = value_file * factor``.

    ``length_name``/``angle_name`` are the labels a writer uses to rebuild
    the unit context (``"metre"``, ``"millimetre"``, ``"radian"``,
    ``"degree"``)."""

    length: float = 1.0
    angle: float = 1.0
    length_name: str = "metre"
    angle_name: str = "radian"


#: SI units (metre, radian).
SI = Units()

#: Keys of ``Pair.params`` that describe the pair frames, not the motion.
FRAME_PARAMS = ("su_1", "su_2")


@dataclass(frozen=True)
class Link:
    """A rigid link. ``name`` is the link's name (1996 links have none: the
    link representation's name, else ``#id``); ``frames`` are named frames
    of the link (4x4, link coordinates, metres) beyond the pair frames."""

    name: str
    id: Optional[int] = None  # source instance id (kinematic_link / link representation)
    description: str = ""
    frames: Mapping[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "frames",
                           _frozen_mapping({k: frozen_array(v, (4, 4)) for k, v in dict(self.frames).items()}))


@dataclass(frozen=True)
class Pair:
    """A kinematic pair and its joint.

    ``kind`` is a key of :data:`p105cli.kinematics.pairs.PAIR_KINDS`
    (``"revolute"``, ..., ``"point_on_surface"``); ``link1``/``link2`` are
    link names in the joint's direction (first -> second); ``P1``/``P2``
    the pair frames (4x4, link coordinates, metres); ``params`` the pair
    type's parameters in SI (``pitch``, radii, ``input_skew_angle``,
    ``layout`` for prismatic pairs, geometry objects for higher pairs);
    ``lower``/``upper`` per-value limits (``None`` = unlimited);
    ``actuated`` whether the pair is meant to be driven (pair_actuator /
    actuated_kinematic_pair); ``ids`` the source instance ids by role
    (``pair``, ``joint``, ``range``, ``actuator``, ``value``)."""

    name: str
    kind: str
    link1: str
    link2: str
    P1: np.ndarray
    P2: np.ndarray
    params: Mapping[str, Any] = field(default_factory=dict)
    lower: tuple = ()
    upper: tuple = ()
    actuated: bool = False
    joint: str = ""
    description: str = ""
    ids: Mapping[str, int] = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "P1", frozen_array(self.P1, (4, 4)))
        object.__setattr__(self, "P2", frozen_array(self.P2, (4, 4)))
        object.__setattr__(self, "params", _frozen_mapping(self.params))
        object.__setattr__(self, "ids", _frozen_mapping(self.ids))
        n = self.type.value_count
        lo = tuple(self.lower) if self.lower else (None,) * n
        up = tuple(self.upper) if self.upper else (None,) * n
        if len(lo) != n or len(up) != n:
            raise ValueError(f"pair {self.name!r}: a {self.kind} pair has {n} values, "
                             f"got {len(lo)} lower and {len(up)} upper limits")
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", up)
        if not self.joint:
            object.__setattr__(self, "joint", self.name)

    @property
    def type(self):
        """The :class:`p105cli.kinematics.pairs.PairType` of this pair."""
        from .pairs import PAIR_KINDS

        try:
            return PAIR_KINDS[self.kind]
        except KeyError:
            raise ValueError(f"pair {self.name!r}: unknown pair kind {self.kind!r}") from None

    @property
    def value_count(self) -> int:
        return self.type.value_count

    @property
    def freedoms(self) -> int:
        """The pair's freedoms: its values less those its flags lock (:meth:`PairType.freedoms`)."""
        return self.type.freedoms(self.params)

    @property
    def value_names(self) -> tuple:
        return self.type.value_names

    def motion_params(self) -> dict:
        """The keyword parameters of :meth:`PairType.motion` for this pair.

        ``params["su_1"]``/``params["su_2"]`` (the Sheth-Uicker parameters
        ``(a, alpha, b, beta, c, gamma)`` of ``P1``/``P2``, SI, when the pair
        frames are su_parameters) describe the frames, not the motion, and
        are left out."""
        return {k: v for k, v in self.params.items() if k not in FRAME_PARAMS}

    def motion(self, q) -> np.ndarray:
        """``M(q)`` (..., 4, 4) for values ``q`` (..., n) in SI."""
        return self.type.motion(q, **self.motion_params())

    def transform(self, q) -> np.ndarray:
        """``T_link1_link2(q) = P1 @ M(q) @ inv(P2)``, batched (:func:`~.pairs.link_transform`)."""
        from .pairs import link_transform

        return link_transform(self.P1, self.motion(q), self.P2)


@dataclass(frozen=True)
class Mechanism:
    """One mechanism. ``links[i].name`` are unique, ``pairs[j].name`` are unique.

    ``base`` is the name of the link fixed to the ground; ``T_world_base``
    places it (identity when the file gives no base placement); ``initial``
    maps pair names to their initial-state values (SI, value order of the
    pair type); ``paths`` holds the motion program's paths as the motion
    layer reads them; ``units`` the file's units; ``profile`` the schema
    profile it was read from (``"ap214"``, ``"p105"``, ``"ap242"``) or
    ``None`` for a model built in code; ``ids`` source ids by role
    (``mechanism``, ``structure``, ``base_placement``, ``initial_state``, ...).
    """

    name: str
    links: tuple
    pairs: tuple
    base: str
    T_world_base: np.ndarray = field(default_factory=lambda: np.eye(4))
    initial: Mapping[str, tuple] = field(default_factory=dict)
    paths: tuple = ()
    units: Units = SI
    profile: Optional[str] = None
    description: str = ""
    ids: Mapping[str, int] = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "links", tuple(self.links))
        object.__setattr__(self, "pairs", tuple(self.pairs))
        object.__setattr__(self, "paths", tuple(self.paths))
        object.__setattr__(self, "T_world_base", frozen_array(self.T_world_base, (4, 4)))
        object.__setattr__(self, "initial",
                           _frozen_mapping({k: tuple(float(x) for x in v) for k, v in dict(self.initial).items()}))
        object.__setattr__(self, "ids", _frozen_mapping(self.ids))
        names = [ln.name for ln in self.links]
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise ValueError(f"mechanism {self.name!r}: duplicate link names {dup}")
        pnames = [p.name for p in self.pairs]
        if len(set(pnames)) != len(pnames):
            dup = sorted({n for n in pnames if pnames.count(n) > 1})
            raise ValueError(f"mechanism {self.name!r}: duplicate pair names {dup}")
        known = set(names)
        for p in self.pairs:
            for ln in (p.link1, p.link2):
                if ln not in known:
                    raise ValueError(f"mechanism {self.name!r}: pair {p.name!r} names unknown link {ln!r}")
        if self.base not in known:
            raise ValueError(f"mechanism {self.name!r}: base link {self.base!r} is not one of its links")
        pset = set(pnames)
        for k, v in self.initial.items():
            if k not in pset:
                raise ValueError(f"mechanism {self.name!r}: initial state names unknown pair {k!r}")

    # -- lookups
    def link(self, name: str) -> Link:
        for ln in self.links:
            if ln.name == name:
                return ln
        raise KeyError(name)

    def pair(self, name: str) -> Pair:
        for p in self.pairs:
            if p.name == name:
                return p
        raise KeyError(name)

    @property
    def link_names(self) -> tuple:
        return tuple(ln.name for ln in self.links)

    @property
    def pair_names(self) -> tuple:
        return tuple(p.name for p in self.pairs)

    # -- the flat value vector of all pairs
    @property
    def value_slices(self) -> Mapping[str, slice]:
        """Where each pair's values sit in the flat configuration vector."""
        out, i = {}, 0
        for p in self.pairs:
            out[p.name] = slice(i, i + p.value_count)
            i += p.value_count
        return MappingProxyType(out)

    @property
    def value_count(self) -> int:
        return sum(p.value_count for p in self.pairs)

    def initial_vector(self) -> np.ndarray:
        """The initial state as a flat vector (0 for pairs the state does not give)."""
        q = np.zeros(self.value_count)
        for name, sl in self.value_slices.items():
            if name in self.initial:
                q[sl] = self.initial[name]
        return q

    def size(self) -> float:
        """A characteristic length of the mechanism (metres, > 0): the largest
        distance of a pair frame origin from its link origin, for tolerances
        relative to model size."""
        r = [float(np.linalg.norm(P[:3, 3])) for p in self.pairs for P in (p.P1, p.P2)]
        s = max(r) if r else 0.0
        return s if s > 0.0 else 1.0
