"""``p105 solve``'s tables: JSON Lines records or CSV rows per configuration, and the summary.

Values leave in the user's units: lengths divided by ``length`` (metres per unit),
angles by ``angle`` (radians per unit). One configuration record::

    {"type": "configuration", "index", "t", "status", "branch"?, "pairs": {name: value or
     [values]}, "links": {name: 3x4... 4x4 pose}, "position_error", "rotation_error" (inverse) |
     "residual", "residual_position", "residual_rotation" (forward), "iterations", "message"?}

CSV: ``index,t,status[,branch],<pair values>,<errors>,iterations,<link>.m00..m23``.
The summary record (JSON Lines only) comes from :class:`Tally`, which also keeps what the
exit status and the warnings need.
"""

from __future__ import annotations

import csv
import json
import math
import re

import numpy as np

__all__ = ["Table", "Tally", "write_blocks"]


_NONFINITE_CELL = re.compile(r"(?<=,)-?(?:inf|nan)(?=,|$)")


def _f(x) -> float | None:
    """A plain float for JSON (no -0.0 noise from round-off, no numpy types); null for a value
    that is not finite (an error that diverged): JSON has no NaN or Infinity."""
    v = float(x)
    if not math.isfinite(v):
        return None
    return 0.0 if v == 0.0 else v


def _value_out(p, q, length, angle):
    vals = [_f(v / (angle if a else length)) for v, a in zip(q, p.type.angle_mask)]
    return vals[0] if len(vals) == 1 else vals


def _pose_out(T, length):
    M = T.copy()
    M[:3, 3] /= length
    return [[_f(x) for x in row] for row in M]


class Table:
    """solve's jsonl or csv output of one run, written block by block.

    ``fmt`` is ``"jsonl"`` or ``"csv"``; ``inverse`` whether the results are an inverse
    analysis's; the branch invariant is written when it exists (forward, with loops)."""

    def __init__(self, out, fmt: str, mech, pl, *, inverse: bool, length: float = 1.0, angle: float = 1.0):
        self.out, self.fmt, self.mech, self.pl = out, fmt, mech, pl
        self.inverse, self.length, self.angle = inverse, length, angle
        self.branched = bool(pl.loops) and not inverse

    def header(self) -> None:
        """The CSV header (nothing for JSON Lines)."""
        if self.fmt != "csv":
            return
        mech = self.mech
        head = ["index", "t", "status"] + (["branch"] if self.branched else [])
        for p in mech.pairs:
            head += [p.name] if p.value_count == 1 else [f"{p.name}[{j}]" for j in range(p.value_count)]
        head += ["position_error", "rotation_error"] if self.inverse else ["residual"]
        head += ["iterations"]
        for name in mech.link_names:
            head += [f"{name}.m{r}{c}" for r in range(3) for c in range(4)]
        csv.writer(self.out, lineterminator="\n").writerow(head)

    def write(self, result, links, t, offset: int) -> None:
        """One block: ``result`` (MotionResult or PathResult), ``links`` its link poses
        (N, links, 4, 4), ``t`` its times (or None), ``offset`` the index of its first row."""
        (self._jsonl if self.fmt == "jsonl" else self._csv)(result, links, t, offset)

    def _jsonl(self, result, links, t, offset):
        mech, length, angle = self.mech, self.length, self.angle
        slices = mech.value_slices
        link_index = result.plan.link_index
        for i in range(result.Q.shape[0]):
            rec = {"type": "configuration", "index": offset + i, "t": _f(t[i]) if t is not None else None,
                   "status": result.status[i]}
            if self.branched:
                rec["branch"] = int(result.branch[i])
            rec["pairs"] = {p.name: _value_out(p, result.Q[i, slices[p.name]], length, angle) for p in mech.pairs}
            rec["links"] = {name: _pose_out(links[i, link_index[name]], length) for name in mech.link_names}
            if self.inverse:
                rec["position_error"] = _f(result.position_error[i] / length)
                rec["rotation_error"] = _f(result.rotation_error[i])
            else:
                rec["residual"] = _f(result.residual[i])
                rec["residual_position"] = _f(result.residual_m[i] / length)
                rec["residual_rotation"] = _f(result.residual_rad[i])
            rec["iterations"] = int(result.iterations[i])
            if result.messages[i]:
                rec["message"] = result.messages[i]
            self.out.write(json.dumps(rec, separators=(",", ":")) + "\n")

    def _csv(self, result, links, t, offset):
        """The numbers of the block are gathered into one array (values in the output units,
        errors, link poses) and formatted by C loops (``tolist``, ``map(repr)``): per-value
        Python made 100 000 configurations of a 6R arm take 20 s of formatting."""
        mech, length, angle = self.mech, self.length, self.angle
        slices = mech.value_slices
        n = result.Q.shape[0]
        cols = []
        for p in mech.pairs:
            scale = np.array([angle if a else length for a in p.type.angle_mask])
            cols.append(result.Q[:, slices[p.name]] / scale)
        if self.inverse:
            cols.append(np.column_stack([result.position_error / length, result.rotation_error]))
        else:
            cols.append(np.asarray(result.residual, dtype=np.float64)[:, None])
        left = np.hstack(cols) + 0.0   # + 0.0: no "-0.0" in the output
        poses = links[:, [result.plan.link_index[name] for name in mech.link_names], :3, :].copy()
        poses[..., 3] /= length
        right = poses.reshape(n, -1) + 0.0
        index = range(offset, offset + n)
        tt = [""] * n if t is None else [repr(x) for x in (np.asarray(t, dtype=np.float64) + 0.0).tolist()]
        iters = np.asarray(result.iterations).tolist()
        if self.branched:   # the column after status
            status = [f"{s},{b}" for s, b in zip(result.status, np.asarray(result.branch).astype(int).tolist())]
        else:
            status = result.status
        write = self.out.write
        for i, ti, st, a, it, b in zip(index, tt, status, left.tolist(), iters, right.tolist()):
            row = f"{i},{ti},{st},{','.join(map(repr, a))},{it},{','.join(map(repr, b))}"
            if "n" in row:  # inf or nan (a diverged error): an empty cell, as for a missing value
                row = _NONFINITE_CELL.sub("", row)
            write(row + "\n")


class Tally:
    """Statistics over all blocks, for the summary record and the exit status."""

    MAX_WARNINGS = 20

    def __init__(self, inverse):
        self.inverse = inverse
        self.n = 0
        self.counts = {}
        self.worst = {}
        self.max_iter = 0
        self.seconds = 0.0
        self.failed = False
        self.bad = []

    def add(self, result, offset):
        n = result.Q.shape[0]
        self.n += n
        self.seconds += result.seconds
        for i, s in enumerate(result.status):
            self.counts[s] = self.counts.get(s, 0) + 1
            if s != "ok":
                self.failed = True
                if len(self.bad) < self.MAX_WARNINGS:
                    self.bad.append((offset + i, s, result.messages[i]))
        fields = (("position_error", "rotation_error") if self.inverse
                  else ("residual", "residual_m", "residual_rad"))
        for f in fields:
            v = float(np.max(getattr(result, f))) if n else 0.0
            self.worst[f] = max(self.worst.get(f, 0.0), v)
        self.max_iter = max(self.max_iter, int(np.max(result.iterations)) if n else 0)

    def summary(self, mech, length, angle, timings) -> dict:
        """The summary record of the JSON Lines output (``timings``: the time it took)."""
        out = {"type": "summary", "mechanism": mech.name, "configurations": self.n,
               "status": {k: self.counts[k] for k in sorted(self.counts)},
               "units": {"length": "m" if length == 1.0 else "mm", "angle": "rad" if angle == 1.0 else "deg"}}
        if self.inverse:
            out["max_position_error"] = _f(self.worst.get("position_error", 0.0) / length)
            out["max_rotation_error"] = _f(self.worst.get("rotation_error", 0.0))
        else:
            out["max_residual"] = _f(self.worst.get("residual", 0.0))
            out["max_residual_position"] = _f(self.worst.get("residual_m", 0.0) / length)
            out["max_residual_rotation"] = _f(self.worst.get("residual_rad", 0.0))
        out["max_iterations"] = self.max_iter
        if timings:
            out["seconds"] = self.seconds
            out["seconds_per_configuration"] = self.seconds / max(self.n, 1)
        return out

    def write_summary(self, out, mech, length, angle, timings) -> None:
        out.write(json.dumps(self.summary(mech, length, angle, timings), separators=(",", ":")) + "\n")

    def messages(self, for_a_person: bool) -> list:
        """``[(level, text)]`` for stderr: what the run achieved and cost (``for_a_person``:
        someone watches a terminal; csv and model output have no summary record), then the
        configurations that are not ok."""
        out = []
        if for_a_person and self.n:
            worst = (f"max pose error {self.worst.get('position_error', 0.0):.3g} m / "
                     f"{self.worst.get('rotation_error', 0.0):.3g} rad" if self.inverse
                     else f"max residual {self.worst.get('residual', 0.0):.3g}")
            out.append(("note", f"{self.n} configurations, {worst}, "
                                f"{1e6 * self.seconds / self.n:.1f} us per configuration"))
        for i, s, msg in self.bad:
            out.append(("warning", f"configuration {i}: {s}: {msg}"))
        more = sum(v for k, v in self.counts.items() if k != "ok") - len(self.bad)
        if more > 0:
            out.append(("warning", f"{more} more configurations are not ok"))
        return out


def write_blocks(blocks, t, write, tally: Tally, link_names, placements=None) -> None:
    """Every block of results through ``write(result, links, t, offset)`` (a :class:`Table`'s, or
    the model's), counted in ``tally``; with a list ``placements``, also ``(t, {link: 4x4})``
    per configuration (t as given, else the index): the motion a scene follows."""
    offset = 0
    for result in blocks:
        links = result.links()
        n = result.Q.shape[0]
        tb = t[offset:offset + n] if t is not None else None
        tally.add(result, offset)
        write(result, links, tb, offset)
        if placements is not None:
            index = result.plan.link_index
            placements += [(float(tb[i]) if tb is not None else float(offset + i),
                            {name: links[i, index[name]] for name in link_names}) for i in range(n)]
        offset += n
