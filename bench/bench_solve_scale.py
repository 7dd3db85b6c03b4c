#!/usr/bin/env python3
"""``p105 graph`` and ``p105 solve`` of long serial chains: how the time grows with the pairs.

Usage (what ``make bench-solve-scale`` runs)::

    python bench/bench_solve_scale.py --markdown docs/benchmarks-solve.md

Target (issue 11): ``p105 solve`` of a 10,000-pair mechanism within 10 s. The
mechanism is a serial chain of revolute pairs (the shape of
``../shared/external/crashes/D19_chain_1000_pairs.stp``: n + 1 links, the first
three pairs actuated), built in code and written as AP242 Part 21 by
:func:`p105cli.part105.write_mechanism.write_mechanism`, the same bytes on
every run. Each command is timed through the real CLI in a fresh interpreter
(start-up, reading and writing included), best of ``--repeat``; the growth
law is the least-squares slope of log(time) against log(pairs).
"""

from __future__ import annotations

import argparse
import datetime
import io
import math
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
from p105cli.fileio import write_text_atomically  # noqa: E402

SIZES = (1000, 3000, 10000)
TARGET_S = 10.0
MARK = "<!-- bench_solve_scale -->"


def chain(n: int):
    """A serial chain of ``n`` revolute pairs: link j carries pair j+1 at 0.1 m along its x
    axis, the joint axes alternating between z and y; q0 = 0.01 rad on every pair."""
    from p105cli.kinematics.model import Link, Mechanism, Pair
    from p105cli.kinematics.spatial import compose, rot_x, trans_x

    links = [Link(f"L{j}") for j in range(n + 1)]
    eye = np.eye(4)
    pairs = [Pair(f"J{j}", "revolute", f"L{j - 1}", f"L{j}",
                  compose(trans_x(0.1), rot_x(math.pi / 2 if j % 2 else 0.0)) if j > 1 else eye, eye,
                  actuated=j <= 3)
             for j in range(1, n + 1)]
    return Mechanism(f"chain{n}", links, pairs, "L0", initial={p.name: (0.01,) for p in pairs})


def chain_file(n: int, folder: Path) -> Path:
    """``chain{n}.stp`` in ``folder`` (written once)."""
    from p105cli.part105.write_mechanism import write_mechanism
    from p105cli.step import write_step

    path = folder / f"chain{n}.stp"
    if not path.exists():
        doc, _ = write_mechanism(chain(n), "ap242")
        buf = io.StringIO()
        write_step(doc, buf)
        write_text_atomically(path, buf.getvalue())
    return path


def timed(args, repeat: int) -> tuple[float, float, int]:
    """(best wall time, its CPU time, exit status) of ``p105 ARGS`` in a fresh interpreter. The CPU
    time (user + system of the child) is what an idle machine's wall time would be."""
    best, cpu, rc = math.inf, math.inf, None
    env = dict(os.environ, PYTHONPATH=str(REPO))
    for _ in range(repeat):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        r = subprocess.run([sys.executable, "-m", "p105cli", *map(str, args)], env=env,
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if wall < best:
            best = wall
            cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        rc = r.returncode
        if rc not in (0, 1):
            raise SystemExit(f"p105 {' '.join(map(str, args))}: exit {rc}\n{r.stderr.decode()}")
    return best, cpu, rc


def slope(ns, ts) -> float:
    return float(np.polyfit(np.log(ns), np.log(ts), 1)[0])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=list(SIZES))
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--folder", type=Path, default=None, help="where the chains are written (default: a temporary folder)")
    ap.add_argument("--markdown", type=Path, default=None,
                    help="replace the section after the marker in this file with the table")
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        folder = a.folder or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        rows = []
        for n in a.sizes:
            f = chain_file(n, folder)
            g = timed(["graph", f], a.repeat)
            s = timed(["solve", f, "--to", "jsonl", "--no-timings"], a.repeat)
            m = timed(["solve", f, "-o", folder / f"chain{n}_solved.stp"], a.repeat)
            rows.append((n, f.stat().st_size, g, s, m))
            print(f"{n:6d} pairs  {f.stat().st_size / 1e6:6.1f} MB  graph {g[0]:6.2f} s  solve --to jsonl "
                  f"{s[0]:6.2f} s  solve --to model {m[0]:6.2f} s (exit {s[2]}, {m[2]})", flush=True)
    ns = [r[0] for r in rows]
    laws = {k: slope(ns, [r[i][1] for r in rows]) if len(rows) > 1 else float("nan")
            for k, i in (("graph", 2), ("jsonl", 3), ("model", 4))}
    biggest = max(rows)
    worst = max(biggest[3][0], biggest[4][0])
    worst_cpu = max(biggest[3][1], biggest[4][1])
    verdict = "met" if worst <= TARGET_S and biggest[0] >= 10000 else "NOT MET"
    lines = [MARK, "", "## Long serial chains: growth with the number of pairs", "",
             "Generated by `python bench/bench_solve_scale.py --markdown docs/benchmarks-solve.md` "
             "(`make bench-solve-scale`; this section only).", "",
             f"- date: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC",
             f"- machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
             f"numpy {np.__version__}",
             f"- load average while running: {' '.join(f'{x:.2f}' for x in os.getloadavg())} (a shared "
             f"machine: wall times of the CLI in a fresh interpreter, best of {a.repeat})", "",
             "Serial chains of n revolute pairs (n + 1 links, the shape of "
             "`../shared/external/crashes/D19_chain_1000_pairs.stp`), AP242 Part 21 from p105's writer:", "",
             "| pairs | file | graph | solve --to jsonl | solve (model out) |",
             "|---:|---:|---:|---:|---:|"]
    lines += [f"| {n:,} | {size / 1e6:.1f} MB | " + " | ".join(f"{w:.2f} s ({c:.2f} s CPU)" for w, c, _ in (g, s, m))
              + " |" for n, size, g, s, m in rows]
    lines += ["", "Growth law (least-squares slope of log CPU time against log pairs): "
              f"graph n^{laws['graph']:.2f}, solve --to jsonl n^{laws['jsonl']:.2f}, "
              f"solve --to model n^{laws['model']:.2f}. Where the time goes: docs/solve.md, Accuracy and cost.", "",
              f"- **{verdict}**: `p105 solve` of a {biggest[0]:,}-pair chain within {TARGET_S:g} s: "
              f"{worst:.1f} s wall, {worst_cpu:.1f} s CPU (the slower of jsonl and model output).", ""]
    text = "\n".join(lines)
    print(text)
    if a.markdown is not None:
        old = a.markdown.read_text() if a.markdown.exists() else ""
        head = old.split(MARK)[0].rstrip("\n")
        write_text_atomically(a.markdown, (head + "\n\n" if head else "") + text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
