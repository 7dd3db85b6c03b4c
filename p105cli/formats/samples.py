"""``p105 interpolate``'s outputs: JSON Lines records and CSV tables of a sampled model.

Deterministic: the same model and options give the same bytes. Numbers in SI
(metres, radians), as :mod:`p105cli.motion.sampling` gives them.
"""

from __future__ import annotations

import csv
import json
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the writers only read what the sampler gives
    from p105cli.motion.sampling import SampledModel

__all__ = ["write_jsonl", "write_csv"]


def _dump(rec) -> str:
    return json.dumps(rec, ensure_ascii=False, separators=(", ", ": "), allow_nan=False)


def write_jsonl(result: SampledModel, out) -> None:
    for rec in result.frames():
        out.write(_dump(rec) + "\n")
    for rec in result.configurations():
        out.write(_dump(rec) + "\n")
    out.write(_dump({"type": "summary", "paths": len(result.path_list),
                     "sequences": len(result.sequence_list), **result.counts,
                     "units": {"length": "m", "angle": "rad"},
                     "skipped": [{"id": i, "message": m} for i, m in result.skipped]}) + "\n")


def write_csv(result: SampledModel, out, what: str) -> None:
    w = csv.writer(out, lineterminator="\n")
    if what == "paths":
        plan = result.plan
        head = ["path", "link", "t", "segment", "segment_kind", "prescribed"]
        head += [f"m{r}{c}" for r in range(3) for c in range(4)]
        if plan.quaternion:
            head += [f"q{ch}" for ch in plan.quaternion]
        if plan.ypr:
            head += ["yaw", "pitch", "roll"]
        w.writerow(head)
        for r in result.frames():
            row = [r["path"], r["link"] or "", repr(r["t"]), r["segment"], r["segment_kind"],
                   "true" if r["prescribed"] else "false"]
            row += [repr(v) for row_ in r["matrix"][:3] for v in row_]
            if plan.quaternion:
                row += [repr(v) for v in r["quaternion"]["value"]]
            if plan.ypr:
                row += [repr(r["ypr"][k]) for k in ("yaw", "pitch", "roll")]
            w.writerow(row)
        return
    names = result.pair_columns
    w.writerow(["sequence", "t", "interval", "interpolation", "prescribed"] + names)
    for r in result.configurations():
        flat = {}
        for k, v in r["pairs"].items():
            if isinstance(v, list):
                flat.update({f"{k}[{j}]": x for j, x in enumerate(v)})
            else:
                flat[k] = v
        w.writerow([r["sequence"], repr(r["t"]), r["interval"], r["interpolation"],
                    "true" if r["prescribed"] else "false"] + [repr(flat[c]) if c in flat else "" for c in names])
