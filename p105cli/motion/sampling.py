"""What ``p105 interpolate`` does, without the CLI: read and sample; the records are
written by :mod:`p105cli.formats.samples`.

Numbers leave here in SI (metres, radians).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .paths import PathError, parameter_grid, sample_path

__all__ = ["Plan", "SamplingError", "SampledModel", "sample_model"]


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
        from p105cli.kinematics.placements import matrix_to_quaternion, ypr_from_matrix

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


def sample_model(doc, *, what: str = "all", paths=(), sequences=(), plan: Plan = Plan(),
                 profile: str | None = None) -> SampledModel:
    """Read what ``what`` asks for and check the request; sampling happens as the
    records are drawn from the returned :class:`SampledModel`."""
    from p105cli.kinematics.reader import population

    pop, _ = population(doc, profile)
    out = SampledModel(plan=plan)
    if what in ("all", "paths"):
        from .reader import read_paths

        read = read_paths(doc, pop=pop)
        out.skipped.extend(read.skipped)
        missing = set(paths) - {p.name for p in read.paths}
        if missing:
            raise SamplingError(f"no path named {', '.join(repr(m) for m in sorted(missing))}")
        out.path_list = [p for p in read.paths if not paths or p.name in paths]
    if what in ("all", "configurations"):
        from .reader import read_configuration_sequences

        seqs, kinds, skipped = read_configuration_sequences(doc, pop=pop)
        out.skipped.extend(skipped)
        out.kinds = kinds
        missing = set(sequences) - {q.name for q in seqs}
        if missing:
            raise SamplingError(f"no configuration sequence named {', '.join(repr(m) for m in sorted(missing))}")
        out.sequence_list = [q for q in seqs if not sequences or q.name in sequences]
    # check every requested t against every range before writing anything
    for item in (*out.path_list, *out.sequence_list):
        if plan.t is not None:
            lo, hi = item.t_start, item.t_end
            tol = 1e-12 * max(1.0, abs(lo), abs(hi))
            bad = [t for t in plan.t if not (lo - tol <= t <= hi + tol)]
            if bad:
                raise SamplingError(f"#{item.id} {item.name!r}: t = {bad[0]!r} is outside its range "
                                    f"[{lo!r}, {hi!r}]")
    return out
