#!/usr/bin/env python3
"""``p105 validate`` timings and memory against the issue's targets.

Usage (what ``make bench-validate`` runs)::

    python bench/bench_validate.py --corpus ../shared/corpus/big --external ../shared/external \\
        --markdown docs/benchmarks-validate.md

Every run is the real CLI in a fresh interpreter, start-up included, timed from outside:
best wall time and best CPU time (user + sys of the child, from ``os.wait4``) of
``--repeat`` runs, and the child's peak RSS. The children run with byte-code caching on
(``PYTHONPYCACHEPREFIX`` in a temporary folder, one warm-up run first), as an installed
p105 does; the machine is shared, so the wall time includes waiting for a core and the
CPU time is the steadier figure.

Targets (issue 11):

* ``build123d/b3d_four_bar_heavy10.stp`` (383 kB, four plate B-reps) under 1.5 s;
* a generated 20 MB AP242 assembly with a mechanism (``gen_validate_inputs.assembly``)
  under 15 s and under 10x the file size in peak memory;
* a small kinematics file (``examples/four_bar_ap242.stp``) under 0.3 s;
* a generated serial chain of 10,000 revolute pairs within 10 s, with the growth law
  fitted over 1,000, 3,000 and 10,000 pairs;
* diagnostics located in O(1) each: ``crashes/D18_10k_diagnostics.stp`` and the same
  construct with 100,000 diagnostics, growth law fitted;
* real CAD files (9 MB, no kinematics): conformance in at most 10 s (the earlier target).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "bench"))
from p105cli.fileio import write_text_atomically  # noqa: E402

KINEMATIC_FILES = [REPO / "examples" / "four_bar_ap242.stp",
                   REPO / "examples" / "slider_crank_p105_1996_ap214.stp",
                   REPO / "tests" / "data" / "corpus" / "ur5_arm_p105.stp"]
CHAIN_SIZES = (1000, 3000, 10000)


class Runner:
    """Runs ``p105 validate`` in fresh interpreters with a byte-code cache of its own."""

    def __init__(self, cache: Path):
        self.env = dict(os.environ)
        self.env.pop("PYTHONDONTWRITEBYTECODE", None)
        self.env["PYTHONPYCACHEPREFIX"] = str(cache)
        self.env["PYTHONPATH"] = os.pathsep.join([str(REPO), self.env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
        self.warm = False

    def once(self, path: Path):
        """(wall s, CPU s, peak RSS MB, report) of one run."""
        args = [sys.executable, "-m", "p105cli", "validate", "-f", "json", str(path)]
        if path.stem.endswith("_p105"):
            args[4:4] = ["--schema", "p105"]
        with tempfile.TemporaryFile() as out:
            t0 = time.perf_counter()
            proc = subprocess.Popen(args, stdout=out, stderr=subprocess.DEVNULL, cwd=REPO, env=self.env)
            _pid, status, usage = os.wait4(proc.pid, 0)
            wall = time.perf_counter() - t0
            proc.returncode = os.waitstatus_to_exitcode(status)
            if proc.returncode not in (0, 1):
                raise RuntimeError(f"{path}: exit {proc.returncode}")
            out.seek(0)
            report = json.loads(out.read())
        return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024, report

    def best(self, path: Path, repeat: int) -> dict:
        if not self.warm:
            self.once(KINEMATIC_FILES[0])  # compiles the byte code
            self.warm = True
        runs = [self.once(path) for _ in range(repeat)]
        s = runs[-1][3]["summary"]
        return {"file": path.name, "MB": path.stat().st_size / 1e6,
                "wall": min(r[0] for r in runs), "cpu": min(r[1] for r in runs),
                "rss": max(r[2] for r in runs), "rules": f"{s['rules_evaluated']}/{s['rules_applicable']}",
                "errors": s["errors"], "warnings": s["warnings"], "runs": repeat}


def generate(kind: str, size: float, path: Path) -> Path:
    """Write a generated input (``gen_validate_inputs.py``) from a child process: the
    children's peak RSS counts what their parent held when it started them, so the parent
    stays small."""
    with open(path, "wb") as out:
        subprocess.run([sys.executable, str(REPO / "bench" / "gen_validate_inputs.py"), kind, str(size)],
                       stdout=out, check=True, cwd=REPO)
    return path


def exponent(sizes, seconds) -> float:
    """Least-squares slope of log(seconds) against log(size)."""
    xs, ys = [math.log(n) for n in sizes], [math.log(t) for t in seconds]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)


def diagnostics_file(n: int) -> str:
    """``n`` instances of an entity unknown to AP242, one diagnostic each (the D18 construct)."""
    lines = [f"#{i}=REPRESENTATION_ITEM_CHAIN(#{i + 1});" for i in range(1, n)]
    lines.append(f"#{n}=REPRESENTATION_ITEM_CHAIN($);")
    return ("ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\nFILE_NAME('','',(''),(''),'','','');\n"
            "FILE_SCHEMA(('AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF { 1 0 10303 442 1 1 4 }'));\n"
            "ENDSEC;\nDATA;\n" + "\n".join(lines) + "\nENDSEC;\nEND-ISO-10303-21;\n")


def _row(r: dict, target: str) -> str:
    return (f"| {r['file']} | {r['MB']:.2f} | {r['wall']:.2f} | {r['cpu']:.2f} | {r['rss']:.0f} | "
            f"{r['rss'] / max(r['MB'], 1e-9):.1f} | {r['rules']} | {r['errors']} | {r['warnings']} | {target} |")


HEADER = ("| file | MB | best wall s | best CPU s | peak RSS MB | RSS / size | rules evaluated/applicable "
          "| errors | warnings | target |\n|---|---|---|---|---|---|---|---|---|---|")


#: The page's hand-measured section (start-up times, several commands): a rewrite keeps it.
KEPT_SECTION = "## Start-up"

WHERE_THE_TIME_GOES = """## Where the time goes

* **Rules on the kinematic closure** are interpreted from the EXPRESS long form, one AST walk per
  rule and instance (10 to 150 microseconds each). A serial chain has about 22 closure instances
  and 57 rule evaluations per pair, so its time is nearly linear in the pairs; the
  closure no longer pulls in shape geometry, and the super-linear parts (USEDIN of an assembly
  root per occurrence, pairwise set operations) are gone. The geometry functions the placement
  rules call run in Python (`schema/evaluator/natives.py`, each proven equal to the EXPRESS body
  on generated inputs): `cross_product` (`axis2_placement_3d.wr4`, 0.5 ms down to 0.12 ms per
  placement), `dimension_of` of points and directions (the derived `dim` of `wr1`-`wr3`) and
  `collect_joints` (`mechanism_representation.wr1`: the interpreter copied and re-checked the
  whole SET for every pair, quadratic: 0.09 s at 1,000 pairs, 0.7 s at 3,000);
  intersections of string lists with TYPEOF (`ap242_subtype_mandatory_shape_representation`, a
  1,200-name list against every shape representation) match by value with counts instead of
  pairwise (0.75 s of a 1,000-pair chain before). Together: the 1,000-pair chain 6.65 s down to
  5.3 s CPU, 3,000 pairs 24.8 s to 17.2 s, 10,000 pairs 93.1 s to 61.4 s (n^1.15 to n^1.07).
  What is left: at 1,000 pairs the rules take about 3.2 s (the interpreter's walk of some 57
  WHERE rule bodies per pair, 10 to 150 microseconds each, and the global rules over the
  extents), reading, conformance and the kinematics checks the rest. The 10,000-pair target
  needs a sixth of today's 6.1 ms per pair: compiling rule bodies to Python closures (not
  done) and cheaper reading and conformance checks outside the evaluator; the slight
  super-linear growth left is not located yet. The 20 MB assembly gains less: measured back to back on
  the same loaded machine, 22.5 s CPU before these changes and 19.4 s after (the table's
  21.3 s is from a busier moment). Every finding is unchanged: the golden outputs byte for
  byte, and the JSON reports of 80 files of `../shared/external/` and the corpus compared
  with the code before. (The counts of heavy10 and D18 differ from the previous edition of this
  page because of the calibrated rules merged since, not of these changes.)
* **Global rules** run over whole type extents from the population's type index.
  `compatible_dimension` visits every point and direction (with 2D parametric contexts present, as
  in Open CASCADE files, through `using_representations` of each); both run in Python
  (`schema/evaluator/natives.py`), `using_representations` memoised per item, and type-only
  QUERY conditions (`subtype_exclusiveness_representation_item`) are evaluated once per type
  combination (`schema/evaluator/compiled.py`).
* **Memory** of a large assembly: the schema (about 55 MB), the USEDIN back-reference index of the
  whole population, one `Instance` per instance the global rules touch and the memo of
  representations per item; records read by the natives are not kept.
"""


def _verdict(ok: bool) -> str:
    return "**met**" if ok else "**NOT MET**"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", type=Path, required=True, help="folder of large real STEP files")
    ap.add_argument("--external", type=Path, help="../shared/external (heavy10, D18)")
    ap.add_argument("--markdown", type=Path, help="write a Markdown page here")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--chains", default=",".join(map(str, CHAIN_SIZES)),
                    help="numbers of pairs of the generated chains (comma-separated)")
    ap.add_argument("--assembly-mb", type=float, default=20.0)
    opts = ap.parse_args()
    repeat = opts.repeat
    targets: list[str] = []
    sections: list[str] = []
    with tempfile.TemporaryDirectory(prefix="p105-bench-validate-") as tmp:
        tmp = Path(tmp)
        run = Runner(tmp / "pycache")

        # -- the gate on real assemblies
        rows = []
        heavy = opts.external / "build123d" / "b3d_four_bar_heavy10.stp" if opts.external else None
        if heavy is not None and heavy.exists():
            r = run.best(heavy, repeat)
            rows.append(_row(r, "< 1.5 s"))
            targets.append(f"- {_verdict(r['wall'] < 1.5)}: `b3d_four_bar_heavy10.stp` (383 kB, four plate "
                           f"B-reps) under 1.5 s: {r['wall']:.2f} s wall, {r['cpu']:.2f} s CPU.")
        big = generate("assembly", opts.assembly_mb * 1e6, tmp / f"assembly_{opts.assembly_mb:g}MB.stp")
        r = run.best(big, max(1, repeat - 1))
        ratio = r["rss"] / r["MB"]
        rows.append(_row(r, "< 15 s, RSS < 10x"))
        targets.append(f"- {_verdict(r['wall'] < 15)}: generated {r['MB']:.1f} MB AP242 assembly with a "
                       f"mechanism under 15 s: {r['wall']:.1f} s wall, {r['cpu']:.1f} s CPU.")
        targets.append(f"- {_verdict(ratio < 10)}: its peak memory under 10x the file size: "
                       f"{r['rss']:.0f} MB = {ratio:.1f}x.")
        for path in KINEMATIC_FILES:
            r = run.best(path, 2 * repeat)
            rows.append(_row(r, "< 0.3 s" if path == KINEMATIC_FILES[0] else ""))
            if path == KINEMATIC_FILES[0]:
                targets.append(f"- {_verdict(r['wall'] < 0.3)}: a small kinematics file "
                               f"(`{path.name}`) under 0.3 s including start-up: {r['wall']:.2f} s wall, "
                               f"{r['cpu']:.2f} s CPU.")
        for path in sorted(opts.corpus.glob("*.step")):
            r = run.best(path, repeat)
            rows.append(_row(r, "< 10 s"))
        sections.append("## Files\n\n" + HEADER + "\n" + "\n".join(rows) + "\n")

        # -- scale: a serial chain
        sizes = [int(x) for x in opts.chains.split(",") if x]
        rows, walls, cpus = [], [], []
        for n in sizes:
            path = generate("chain", n, tmp / f"chain_{n}.stp")
            r = run.best(path, 1 if n >= 3000 else repeat)
            rows.append(_row(r, "< 10 s" if n == 10000 else ""))
            walls.append(r["wall"])
            cpus.append(r["cpu"])
            print(rows[-1], flush=True)
        if len(sizes) > 1:
            k = exponent(sizes, cpus)
            last = sizes[-1]
            targets.append(f"- {_verdict(walls[-1] < 10)}: a generated chain of {last:,} revolute pairs within "
                           f"10 s: {walls[-1]:.1f} s wall, {cpus[-1]:.1f} s CPU; CPU time grows as "
                           f"n^{k:.2f} over {', '.join(f'{n:,}' for n in sizes)} pairs.")
        sections.append("## Scale: serial chains of revolute pairs (p105's writer, AP242)\n\n" + HEADER + "\n"
                        + "\n".join(rows) + "\n")

        # -- scale: many diagnostics
        rows, counts, cpus = [], [], []
        d18 = opts.external / "crashes" / "D18_10k_diagnostics.stp" if opts.external else None
        inputs = []
        if d18 is not None and d18.exists():
            inputs.append((10_000, d18))
        for n in (10_000, 100_000):
            if n == 10_000 and inputs:
                continue
            path = tmp / f"diagnostics_{n}.stp"
            path.write_text(diagnostics_file(n))
            inputs.append((n, path))
        for n, path in inputs:
            r = run.best(path, repeat)
            rows.append(_row(r, ""))
            counts.append(r["warnings"] + r["errors"])
            cpus.append(r["cpu"])
        k = exponent(counts, cpus)
        targets.append(f"- {_verdict(k < 1.2)}: diagnostics located in O(1) each (an index of line starts): "
                       f"{counts[-1]:,} diagnostics in {cpus[-1]:.2f} s CPU; CPU time grows as n^{k:.2f} from "
                       f"{counts[0]:,} to {counts[-1]:,} diagnostics.")
        sections.append("## Scale: many diagnostics (one SCH-UNKNOWN-ENTITY per instance)\n\n" + HEADER + "\n"
                        + "\n".join(rows) + "\n")

    text = "\n".join(targets) + "\n\n" + "\n".join(sections)
    print(text)
    if opts.markdown:
        cmd = "python bench/bench_validate.py " + " ".join(sys.argv[1:])
        load = os.getloadavg()
        page = (f"# `p105 validate` benchmark\n\nProduced by `{cmd}` on "
                f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC ({os.cpu_count()} cores, "
                f"shared; load average {load[0]:.1f} at the end; Python {platform.python_version()}). Every time "
                f"is the real CLI in a fresh interpreter, start-up included, byte code cached; best wall and "
                f"best CPU (user + sys) of {repeat} runs (kinematics examples {2 * repeat}, files of 3,000 pairs "
                f"and more: 1), peak RSS of the child (the inputs are generated by other "
                f"children, so that no child inherits a large parent's high-water mark). On a shared machine "
                f"the wall time includes waiting for "
                f"a core; the CPU time is the steadier figure.\n\n{text}\n"
                "Conformance (SCH-*) is checked on every instance; WHERE and UNIQUE rules on the kinematic "
                "closure, which stops at shape representations (a link's B-rep is not pulled in), and global "
                "rules over the type extents of the whole population (docs/validate.md). The real CAD files "
                "hold no kinematics, so no rule applies there.\n\n" + WHERE_THE_TIME_GOES)
        old = Path(opts.markdown).read_text() if Path(opts.markdown).exists() else ""
        if KEPT_SECTION in old:  # measured by hand (docs say how): kept as it is
            page += "\n" + old[old.index(KEPT_SECTION):]
        write_text_atomically(opts.markdown, page)
        print(f"wrote {opts.markdown}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
