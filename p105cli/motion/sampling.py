"""The sampling of ``p105 interpolate``: a :class:`SampledModel` (paths and configuration
sequences already read, by :func:`p105cli.part105.motion.sample_model`) yields its records as
they are drawn; they are written by :mod:`p105cli.formats.samples`.

Numbers leave here in SI (metres, radians).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .paths import PathError, parameter_grid, sample_path

__all__ = ["Plan", "SamplingError", "SampledModel"]


class SamplingError(ValueError):
    """A request that cannot be met (t out of range, unknown path name)."""


@dataclass(frozen=True)
class Plan:
    t: Optional[tuple] = None
    step: Optional[float] = None
    count: Optional[int] = None
    nodes: bool = True
    quaternion: Optional[str] = None
    ypr: bool = False

    def grid(self, t_start: float, t_end: float, breakpoints) -> np.ndarray:
        if self.t is not None:
            t = np.array(sorted(set(self.t)), dtype=np.float64)
            return np.union1d(t, breakpoints) if self.nodes else t
        if self.step is None and self.count is None:
            return np.asarray(breakpoints, dtype=np.float64)
        try:
            return parameter_grid(t_start, t_end, step=self.step, count=self.count,
                                  breakpoints=breakpoints if self.nodes else None)
        except ValueError as err:  # a grid too fine to hold: the request, not a bug
            raise SamplingError(str(err)) from None


def _clean(x: float) -> float:
    x = float(x)
    return 0.0 if x == 0.0 else x  # no "-0.0" in output


def _matrix(T) -> list:
    return [[_clean(v) for v in row] for row in np.asarray(T)]


#: Samples evaluated per block: bounded memory, and output starts at once (pipes, head).
CHUNK = 8192


@dataclass
class SampledModel:
    """Streams of records: :meth:`frames` and :meth:`configurations` yield them
    block by block; ``skipped`` lists ``(#id, message)`` of what could not be read."""

    path_list: list = field(default_factory=list)
    sequence_list: list = field(default_factory=list)
    kinds: dict = field(default_factory=dict)
    plan: Plan = Plan()
    skipped: list = field(default_factory=list)
    counts: dict = field(default_factory=lambda: {"frames": 0, "configurations": 0})

    @property
    def pair_columns(self) -> list:
        """Pair value columns of the sequences: ``name`` or ``name[i]``."""
        cols: list = []
        for seq in self.sequence_list:
            for name in seq.pair_names:
                n = len(seq.nodes[0].values[name])
                for c in ([name] if n == 1 else [f"{name}[{j}]" for j in range(n)]):
                    if c not in cols:
                        cols.append(c)
        return cols

    def frames(self):
        from p105cli.kinematics.placements import ypr_from_matrix
        from p105cli.kinematics.spatial import matrix_to_quaternion

        plan = self.plan
        for path in self.path_list:
            grid = plan.grid(path.t_start, path.t_end, path.breakpoints)
            for lo in range(0, grid.shape[0], CHUNK):
                t = grid[lo:lo + CHUNK]
                try:
                    s = sample_path(path, t)
                except PathError as err:
                    raise SamplingError(f"#{path.id}: {err}") from None
                q = matrix_to_quaternion(s.T, plan.quaternion) if plan.quaternion else None
                y = np.stack(ypr_from_matrix(s.T), axis=-1) if plan.ypr else None
                for i in range(t.shape[0]):
                    k = int(s.segment[i])
                    rec = {"type": "frame", "path": path.name, "link": path.link, "t": _clean(s.t[i]),
                           "segment": k, "segment_kind": path.segments[k].kind,
                           "prescribed": bool(s.prescribed[i]), "matrix": _matrix(s.T[i])}
                    if q is not None:
                        rec["quaternion"] = {"order": plan.quaternion, "value": [_clean(v) for v in q[i]]}
                    if y is not None:
                        rec["ypr"] = {"yaw": _clean(y[i, 0]), "pitch": _clean(y[i, 1]), "roll": _clean(y[i, 2])}
                    self.counts["frames"] += 1
                    yield rec

    def configurations(self):
        from .configurations import sample_configurations

        for seq in self.sequence_list:
            grid = self.plan.grid(seq.t_start, seq.t_end, [n.t for n in seq.nodes])
            for lo in range(0, grid.shape[0], CHUNK):
                try:
                    s = sample_configurations(seq, grid[lo:lo + CHUNK], self.kinds)
                except ValueError as err:
                    raise SamplingError(f"#{seq.id}: {err}") from None
                for i in range(s.t.shape[0]):
                    pairs = {}
                    for name, vals in s.values.items():
                        v = [_clean(x) for x in vals[i]]
                        pairs[name] = v[0] if len(v) == 1 else v
                    self.counts["configurations"] += 1
                    yield {"type": "configuration", "sequence": seq.name, "t": _clean(s.t[i]),
                           "interval": int(s.interval[i]), "interpolation": s.interpolation[i],
                           "prescribed": bool(s.prescribed[i]), "pairs": pairs}
