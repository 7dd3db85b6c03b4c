"""Configuration interpolation sequences: pair values over the parameter ``t``.

A :class:`ConfigurationSequence` is a list of :class:`ConfigurationNode` s
(a full set of pair values at a parameter ``t``, SI units) with the
interpolation that leads from each node to the next. Both layouts map onto
it: the 1996 ``configuration_interpolation(previous, next, interpolation)``
with ``interpolation_type`` (undefined, synchronous, linear) and AP242's
``interpolated_configuration_segment(state, t_parameter, interpolation)``
(discontinuous_, synchronous_, linear_interpolation_type; a segment's
interpolation leads from its state to the next one).

Sampling between two nodes (fraction ``s`` of the interval):

* ``linear``: each pair value linearly in ``s``; the rotation of a
  spherical pair (and the rotational part of an unconstrained pair) by slerp
  of its ypr rotation, converted back to ypr angles (Annex E) -- angles of a
  spatial rotation are never interpolated one by one.
* ``synchronous``: the pairs start and reach the next configuration together;
  the standard prescribes no law, so the linear law above is used and the
  samples are labelled as not prescribed.
* ``discontinuous`` / ``undefined``: no interpolation; the configuration
  holds until the next node, where it jumps (``undefined`` samples are
  labelled as not prescribed).
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping, Optional

import numpy as np

from p105cli.kinematics.placements import ypr_from_matrix, ypr_rotation
from p105cli.kinematics.spatial import slerp

__all__ = ["INTERPOLATIONS", "ConfigurationNode", "ConfigurationSequence", "ConfigurationSamples",
           "sample_configurations"]

INTERPOLATIONS = ("linear", "synchronous", "discontinuous", "undefined")

#: Pair kinds whose values hold a spatial rotation as (yaw, pitch, roll), and where.
_YPR_SLOTS = {"spherical": slice(0, 3), "unconstrained": slice(3, 6)}


@dataclass(frozen=True)
class ConfigurationNode:
    t: float
    values: Mapping[str, tuple]
    interpolation: str = "linear"   # from this node to the next
    name: str = ""
    id: Optional[int] = None

    def __post_init__(self):
        if self.interpolation not in INTERPOLATIONS:
            raise ValueError(f"unknown interpolation {self.interpolation!r}; expected one of {INTERPOLATIONS}")
        object.__setattr__(self, "values",
                           MappingProxyType({k: tuple(float(x) for x in v) for k, v in dict(self.values).items()}))


@dataclass(frozen=True)
class ConfigurationSequence:
    name: str
    nodes: tuple
    closed: bool = False
    id: Optional[int] = None

    def __post_init__(self):
        nodes = tuple(sorted(self.nodes, key=lambda n: n.t))
        if len(nodes) < 1:
            raise ValueError(f"configuration sequence {self.name!r} has no configurations")
        ts = [n.t for n in nodes]
        if len(set(ts)) != len(ts):
            raise ValueError(f"configuration sequence {self.name!r}: two configurations share t = "
                             f"{next(t for t in ts if ts.count(t) > 1)!r}")
        object.__setattr__(self, "nodes", nodes)

    @property
    def t_start(self) -> float:
        return self.nodes[0].t

    @property
    def t_end(self) -> float:
        return self.nodes[-1].t

    @property
    def pair_names(self) -> tuple:
        """Pairs valued in every node, in the first node's order."""
        first = list(self.nodes[0].values)
        return tuple(p for p in first if all(p in n.values for n in self.nodes))


@dataclass(frozen=True)
class ConfigurationSamples:
    t: np.ndarray                 # (N,)
    values: Mapping[str, np.ndarray]  # pair -> (N, n_values)
    interval: np.ndarray          # (N,) index of the node the sample's interval starts at
    interpolation: tuple          # (N,) interpolation used for each sample
    prescribed: np.ndarray        # (N,) whether the file prescribes the law used


def sample_configurations(seq: ConfigurationSequence, t, kinds: Mapping[str, str] | None = None
                          ) -> ConfigurationSamples:
    """Pair values of ``seq`` at parameters ``t`` (1-D, within its range).

    ``kinds`` maps pair names to pair kinds (to slerp spherical rotations);
    a pair of unknown kind is interpolated value by value."""
    kinds = dict(kinds or {})
    t = np.atleast_1d(np.asarray(t, dtype=np.float64))
    lo, hi = seq.t_start, seq.t_end
    tol = 1e-12 * max(1.0, abs(lo), abs(hi))
    bad = ~np.isfinite(t) | (t < lo - tol) | (t > hi + tol)
    if np.any(bad):
        raise ValueError(f"configuration sequence {seq.name!r}: t = {t[np.argmax(bad)]!r} is outside "
                         f"its range [{lo!r}, {hi!r}]")
    t = np.clip(t, lo, hi)
    nodes = seq.nodes
    ts = np.array([n.t for n in nodes])
    k = np.clip(np.searchsorted(ts, t, side="right") - 1, 0, max(len(nodes) - 2, 0))
    if len(nodes) == 1:
        s = np.zeros_like(t)
    else:
        s = (t - ts[k]) / (ts[k + 1] - ts[k])
    law = np.array([n.interpolation for n in nodes], dtype=object)[k]
    hold = np.isin(law, ("discontinuous", "undefined")) & (s < 1.0)
    s_eff = np.where(hold, 0.0, s)
    out = {}
    for name in seq.pair_names:
        V = np.array([nodes[i].values[name] for i in range(len(nodes))])  # (n_nodes, n_values)
        a = V[k]
        b = V[np.minimum(k + 1, len(nodes) - 1)]
        vals = a + s_eff[:, None] * (b - a)
        sl = _YPR_SLOTS.get(kinds.get(name, ""))
        if sl is not None and V.shape[1] >= sl.stop:
            Ra = ypr_rotation(*np.moveaxis(a[:, sl], -1, 0))
            Rb = ypr_rotation(*np.moveaxis(b[:, sl], -1, 0))
            vals[:, sl] = np.stack(ypr_from_matrix(slerp(Ra, Rb, s_eff)), axis=-1)
            # keep the nodes' own angles exactly where a sample falls on a node
            at_a, at_b = s_eff == 0.0, s_eff == 1.0
            vals[at_a, sl] = a[at_a, sl]
            vals[at_b, sl] = b[at_b, sl]
        out[name] = vals
    prescribed = ~np.isin(law, ("synchronous", "undefined"))
    return ConfigurationSamples(t, MappingProxyType(out), k, tuple(law), prescribed)
