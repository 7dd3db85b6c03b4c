#!/usr/bin/env python3
"""``p105 validate`` timings against the issue's targets.

Usage (what ``make bench-validate`` runs)::

    python bench/bench_validate.py --corpus ../shared/corpus/big --markdown docs/benchmarks-validate.md

Each run is the real CLI in a fresh interpreter (start-up included), timed
from outside, best of ``--repeat``. Targets: a full conformance check of a
9 MB real file in at most 10 s; a kinematics file of a few hundred
instances in at most 0.3 s including start-up; 100 % rule coverage.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from p105cli.fileio import write_text_atomically  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
KINEMATIC_FILES = [REPO / "examples" / "four_bar_ap242.stp",
                   REPO / "examples" / "slider_crank_p105_1996_ap214.stp",
                   REPO / "tests" / "data" / "corpus" / "ur5_arm_p105.stp"]


def run_validate(path: Path, repeat: int) -> tuple[float, dict]:
    args = [sys.executable, "-m", "p105cli", "validate", "-f", "json", str(path)]
    if path.stem.endswith("_p105"):
        args[4:4] = ["--schema", "p105"]
    best, report = float("inf"), {}
    for _ in range(repeat):
        t0 = time.perf_counter()
        r = subprocess.run(args, capture_output=True, cwd=REPO)
        elapsed = time.perf_counter() - t0
        if r.returncode not in (0, 1):
            raise RuntimeError(f"{path}: exit {r.returncode}: {r.stderr.decode()[-500:]}")
        best = min(best, elapsed)
        report = json.loads(r.stdout)
    return best, report


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", type=Path, required=True, help="folder of large real STEP files")
    ap.add_argument("--markdown", type=Path, help="write a Markdown page here")
    ap.add_argument("--repeat", type=int, default=3)
    opts = ap.parse_args()
    rows = []
    for path in sorted(opts.corpus.glob("*.step")) + KINEMATIC_FILES:
        seconds, report = run_validate(path, opts.repeat if path.stat().st_size > 10**6 else 2 * opts.repeat)
        s = report["summary"]
        size = path.stat().st_size
        kind = "real CAD, 9 MB" if size > 10**6 else "kinematics"
        limit = 10.0 if size > 10**6 else 0.3
        rows.append((path.name, kind, size / 1e6, seconds, limit, s["rules_evaluated"], s["rules_applicable"],
                     s["errors"], s["warnings"]))
    header = ("file", "kind", "MB", "best s", "target s", "met", "rules evaluated/applicable", "errors", "warnings")
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for name, kind, mb, sec, limit, ev, ap_, err, warn in rows:
        lines.append(f"| {name} | {kind} | {mb:.2f} | {sec:.2f} | {limit:g} | {'met' if sec <= limit else 'NOT MET'} "
                     f"| {ev}/{ap_} | {err} | {warn} |")
    table = "\n".join(lines)
    print(table)
    if opts.markdown:
        cmd = "python bench/bench_validate.py " + " ".join(sys.argv[1:])
        page = (f"# `p105 validate` benchmark\n\nProduced by `{cmd}` on "
                f"{datetime.date.today().isoformat()} ({os.cpu_count()} cores, Python "
                f"{platform.python_version()}). Each time is the real CLI in a fresh interpreter, start-up "
                f"included, best of {opts.repeat} (kinematics files: {2 * opts.repeat}).\n\n{table}\n\n"
                "Conformance (SCH-*) is checked on every instance; WHERE, UNIQUE and global rules on the "
                "kinematic closure (docs/validate.md), so the real CAD files, which hold no kinematics, "
                "have no rules applicable.\n")
        write_text_atomically(opts.markdown, page)
        print(f"wrote {opts.markdown}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
