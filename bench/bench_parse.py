#!/usr/bin/env python3
"""Parser throughput benchmark: p105 against Open CASCADE on large STEP files.

Usage (this is what ``make bench-parse`` runs)::

    python bench/bench_parse.py --corpus ../shared/corpus/big --markdown docs/benchmarks-parse.md

For every ``*.step`` / ``*.stp`` file of the corpus, and side by side in one
run, five ways of reading it are timed:

``index``
    ``p105cli.step.decode_bytes`` + ``read_step``: read the frame and index
    every instance (id, entity type, span); nothing is decoded.
``index+kin``
    the same, then decode only the instances of kinematics entity types
    (the names in ``kinematics_entity_names_union.txt``) and everything they
    reference, transitively. This is what the kinematics filters need.
``parse-json``
    the real CLI end to end: ``python -m p105cli parse FILE -o OUT.json``
    (interpreter start-up and JSON writing included).
``occt``
    Open CASCADE ``STEPControl_Reader().ReadFile(path)`` through
    cadquery-ocp (ReadFile only: the import and shape transfer are excluded).
``naive``
    ``text.split(';')`` over the DATA section and a regex for id and type on
    each piece: the floor any pure-Python reader competes with (it is wrong
    for ``;`` inside strings, which is why it is only a floor).

Each measurement runs in a fresh interpreter (this script re-invoked with
``--child``), so that its peak RSS (``ru_maxrss`` read inside the child) is
not polluted by earlier work; the growth over the child's own baseline,
taken just before the file is read, is reported next to the absolute peak.
Times are the best of ``--repeat`` runs; repeats are interleaved across
files and kinds so that slow drift of the machine hits all of them alike.
Cold start of the CLI (``--help`` and parsing a small example) is measured
as the best of ``--cold-repeat`` runs.

A plain table goes to stdout; ``--markdown PATH`` also writes a Markdown
page (atomically). Missed targets are reported, not fatal: the exit status
is non-zero only when a measurement crashes.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
import platform
import re
import shlex
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
from p105cli.fileio import write_text_atomically  # noqa: E402  (the repo checkout, not an install)
RESULT_MARKER = "@@BENCH-RESULT@@ "
NAMES_FILE = "kinematics_entity_names_union.txt"
SMALL_EXAMPLE = REPO / "examples" / "four_bar_ap242.stp"
MB = 1e6  # throughput and sizes are in MB = 10^6 bytes

KINDS = ("index", "index+kin", "parse-json", "occt", "naive")
KIND_TITLES = {
    "index": "p105 index (decode_bytes + read_step)",
    "index+kin": "p105 index + kinematics decode",
    "parse-json": "p105 parse to JSON (CLI, end to end)",
    "occt": "Open CASCADE STEPControl_Reader.ReadFile",
    "naive": "naive pure-Python split",
}

# Targets (kept next to the numbers, in stdout and in the Markdown page).
TARGET_KIN_VS_OCCT = 2.0     # index + kinematics decode throughput >= 2x OCCT ReadFile
TARGET_PARSE_VS_OCCT = 1.0   # full parse throughput >= 1x OCCT ReadFile
TARGET_RSS_PER_SIZE = 4.0    # index peak RSS growth <= 4x file size
TARGET_COLD_MS = 150.0       # cold start < 150 ms

EXIT_UNAVAILABLE = 3  # a child could not run its measurement (e.g. OCP missing): skipped, not a crash


# --------------------------------------------------------------------------
# Child side: one measurement in a fresh interpreter
# --------------------------------------------------------------------------

def _maxrss_bytes() -> int:
    """Peak RSS of this process so far, in bytes.

    On Linux ``ru_maxrss`` survives fork + exec: a child starts with the
    high-water mark of the process that spawned it. ``VmHWM`` in
    /proc/self/status is the same peak for this program's own address
    space only, so it is used when available and ``ru_maxrss`` otherwise.
    """
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    import resource
    kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return kb if sys.platform == "darwin" else kb * 1024


def _child_index(path: str, names_path: str) -> dict:
    from p105cli.step import decode_bytes, read_step
    base = _maxrss_bytes()
    c0 = time.process_time()
    t0 = time.perf_counter()
    with open(path, "rb") as fh:
        raw = fh.read()
    text = decode_bytes(raw)
    del raw
    sf = read_step(text, path)
    elapsed = time.perf_counter() - t0
    return {"seconds": elapsed, "cpu_seconds": time.process_time() - c0, "base_rss": base,
            "peak_rss": _maxrss_bytes(), "instances": len(sf)}


def _refs(value, out: list) -> None:
    """Append every ``{"ref": n}`` instance id found anywhere in a decoded value."""
    if isinstance(value, list):
        for item in value:
            _refs(item, out)
    elif isinstance(value, dict):
        ref = value.get("ref")
        if isinstance(ref, int) and len(value) == 1:
            out.append(ref)
            return
        for item in value.values():
            _refs(item, out)


def _load_names(names_path: str) -> list[str]:
    with open(names_path, encoding="utf-8") as fh:
        names = [line.strip().lower() for line in fh]
    return [n for n in names if n and not n.startswith("#")]


def _child_index_kin(path: str, names_path: str) -> dict:
    from p105cli.step import decode_bytes, read_step
    names = _load_names(names_path)
    base = _maxrss_bytes()
    c0 = time.process_time()
    t0 = time.perf_counter()
    with open(path, "rb") as fh:
        raw = fh.read()
    text = decode_bytes(raw)
    del raw
    sf = read_step(text, path)
    t_index = time.perf_counter() - t0
    decoded: dict[int, dict] = {}
    pending: list[int] = []
    slots = sf.slots_of_type(*names)
    for k in slots:
        rec = sf._decode_slot(k)
        decoded[rec["id"]] = rec
        _refs(rec.get("args", rec), pending)
    while pending:
        n = pending.pop()
        if n in decoded:
            continue
        try:
            rec = sf.record(n)
        except KeyError:  # a dangling reference is the file's problem, not the benchmark's
            decoded[n] = {}
            continue
        decoded[n] = rec
        _refs(rec.get("args", rec), pending)
    elapsed = time.perf_counter() - t0
    return {"seconds": elapsed, "cpu_seconds": time.process_time() - c0, "index_seconds": t_index,
            "base_rss": base, "peak_rss": _maxrss_bytes(),
            "instances": len(sf), "kinematics": len(slots), "decoded": len(decoded)}


def _child_occt(path: str, names_path: str) -> dict:
    try:
        from OCP.IFSelect import IFSelect_ReturnStatus
        from OCP.STEPControl import STEPControl_Reader
    except ImportError as err:
        print(f"OCP (cadquery-ocp) is not importable: {err}", file=sys.stderr)
        sys.exit(EXIT_UNAVAILABLE)
    reader = STEPControl_Reader()
    base = _maxrss_bytes()
    c0 = time.process_time()
    t0 = time.perf_counter()
    status = reader.ReadFile(path)
    elapsed = time.perf_counter() - t0
    cpu = time.process_time() - c0
    if status != IFSelect_ReturnStatus.IFSelect_RetDone:
        raise RuntimeError(f"ReadFile returned {status}")
    try:
        entities = reader.StepModel().NbEntities()
    except Exception:  # noqa: BLE001 - the count is a sanity check only
        entities = None
    return {"seconds": elapsed, "cpu_seconds": cpu, "base_rss": base, "peak_rss": _maxrss_bytes(),
            "instances": entities}


_DATA_START = re.compile(r"\bDATA\s*(?:\([^;]*\))?\s*;")
_DATA_END = re.compile(r"\bENDSEC\s*;")
_NAIVE_INSTANCE = re.compile(r"#(\d+)\s*=\s*(\w+)")


def _child_naive(path: str, names_path: str) -> dict:
    from array import array
    base = _maxrss_bytes()
    c0 = time.process_time()
    t0 = time.perf_counter()
    with open(path, "rb") as fh:
        raw = fh.read()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    del raw
    start = _DATA_START.search(text)
    if start is None:
        raise RuntimeError("no DATA section")
    end = _DATA_END.search(text, start.end())
    stop = end.start() if end else len(text)
    ids = array("q")
    types = []
    search = _NAIVE_INSTANCE.search
    for piece in text[start.end():stop].split(";"):
        m = search(piece)
        if m is not None:
            ids.append(int(m.group(1)))
            types.append(m.group(2).lower())
    elapsed = time.perf_counter() - t0
    return {"seconds": elapsed, "cpu_seconds": time.process_time() - c0, "base_rss": base,
            "peak_rss": _maxrss_bytes(), "instances": len(ids)}


def _child_facts(path: str, names_path: str) -> dict:
    """Versions that need an import (kept out of the parent process)."""
    facts = {}
    try:
        from OCP.Standard import Standard_Version  # not bound in every cadquery-ocp build
        facts["occt"] = str(Standard_Version.String_s())
    except Exception:  # noqa: BLE001
        try:
            import OCP
            facts["ocp"] = getattr(OCP, "__version__", None)
        except ImportError:
            pass
    return facts


CHILD_KINDS = {
    "index": _child_index,
    "index+kin": _child_index_kin,
    "occt": _child_occt,
    "naive": _child_naive,
    "facts": _child_facts,
}


def child_main(argv: list[str]) -> int:
    kind, path, names_path = argv
    sys.path.insert(0, str(REPO))  # the p105cli of this tree, installed or not
    result = CHILD_KINDS[kind](path, names_path)
    sys.stdout.write("\n" + RESULT_MARKER + json.dumps(result) + "\n")
    sys.stdout.flush()
    return 0


# --------------------------------------------------------------------------
# Parent side: run children, collect, report
# --------------------------------------------------------------------------

@dataclass
class Sample:
    seconds: float
    base_rss: int | None
    peak_rss: int
    extra: dict = field(default_factory=dict)


@dataclass
class Cell:
    """All the repeats of one (file, kind) measurement."""
    samples: list[Sample] = field(default_factory=list)
    error: str | None = None
    skipped: str | None = None

    @property
    def ok(self) -> bool:
        return bool(self.samples) and self.error is None and self.skipped is None

    @property
    def best(self) -> float:
        return min(s.seconds for s in self.samples)

    @property
    def peak_rss(self) -> int:
        return max(s.peak_rss for s in self.samples)

    @property
    def growth(self) -> int | None:
        if any(s.base_rss is None for s in self.samples):
            return None
        return max(s.peak_rss - s.base_rss for s in self.samples)

    def extra(self, key):
        return self.samples[-1].extra.get(key) if self.samples else None

    @property
    def best_cpu(self) -> float | None:
        """CPU seconds of the fastest run (well below its wall time = the machine was busy)."""
        fastest = min(self.samples, key=lambda s: s.seconds)
        return fastest.extra.get("cpu_seconds")


class MeasurementError(Exception):
    pass


class Unavailable(Exception):
    pass


def _run_wait4(cmd: list[str], timeout: float, **kwargs) -> tuple[float, int, int, str, str, float]:
    """Run cmd; return (wall s, exit status, peak RSS bytes of that child, stdout, stderr, its cpu s)."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=out, stderr=err, stdin=subprocess.DEVNULL, **kwargs)
        deadline = t0 + timeout
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if time.perf_counter() > deadline:
                proc.kill()
                pid, status, usage = os.wait4(proc.pid, 0)
                proc.returncode = -9
                raise MeasurementError(f"timed out after {timeout:.0f} s: {shlex.join(cmd)}")
            time.sleep(0.0005)
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        rss = usage.ru_maxrss if sys.platform == "darwin" else usage.ru_maxrss * 1024
        return (wall, proc.returncode, rss, out.read().decode("utf-8", "replace"),
                err.read().decode("utf-8", "replace"), usage.ru_utime + usage.ru_stime)


TIME_BIN = "/usr/bin/time"


def gnu_time_works() -> bool:
    """True if GNU time (``-f %M -o FILE``) can report a child's peak RSS."""
    if not os.access(TIME_BIN, os.X_OK):
        return False
    with tempfile.TemporaryDirectory(prefix="bench_parse.") as d:
        out = Path(d) / "t"
        try:
            res = subprocess.run([TIME_BIN, "-f", "%M", "-o", str(out), "true"], capture_output=True, timeout=30)
            return res.returncode == 0 and out.read_text().strip().splitlines()[-1].isdigit()
        except (OSError, subprocess.SubprocessError, IndexError):
            return False


def run_cli(cmd: list[str], timeout: float, use_time: bool) -> tuple[float, int, int, str, float | None]:
    """Run a CLI command from the repo root: (wall s, exit status, peak RSS bytes, stderr, cpu s).

    With GNU time the peak RSS is that of a process forked from the small
    ``time`` program, so it is the command's own; without it, the rusage
    from ``os.wait4`` also carries this process's high-water mark (an upper bound).
    """
    if not use_time:
        wall, code, rss, _, err, cpu = _run_wait4(cmd, timeout, cwd=str(REPO))
        return wall, code, rss, err, cpu
    fd, tfile = tempfile.mkstemp(prefix="bench_parse.time.")
    os.close(fd)
    try:
        wall, code, _, _, err, _ = _run_wait4([TIME_BIN, "-f", "%M %U %S", "-o", tfile, *cmd], timeout,
                                              cwd=str(REPO))
        lines = Path(tfile).read_text().strip().splitlines()
        try:
            kb, user, system = lines[-1].split()
            return wall, code, int(kb) * 1024, err, float(user) + float(system)
        except (IndexError, ValueError):
            return wall, code, 0, err, None
    finally:
        os.unlink(tfile)


def run_child(kind: str, path: Path, names: Path, timeout: float) -> Sample:
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", kind, str(path), str(names)]
    _, code, _, out, err, _ = _run_wait4(cmd, timeout, cwd=str(REPO))
    if code == EXIT_UNAVAILABLE:
        raise Unavailable(err.strip().splitlines()[-1] if err.strip() else "unavailable")
    lines = [ln for ln in out.splitlines() if ln.startswith(RESULT_MARKER)]
    if code != 0 or not lines:
        tail = "\n".join(err.strip().splitlines()[-6:])
        raise MeasurementError(f"{kind} on {path.name}: exit status {code}\n{tail}")
    data = json.loads(lines[-1][len(RESULT_MARKER):])
    if kind == "facts":
        return Sample(0.0, None, 0, data)
    seconds, base, peak = data.pop("seconds"), data.pop("base_rss", None), data.pop("peak_rss")
    return Sample(seconds, base, peak, data)


def run_parse_json(path: Path, out_json: Path, timeout: float, baseline_rss: int | None,
                   use_time: bool) -> Sample:
    cmd = [sys.executable, "-m", "p105cli", "parse", str(path), "-o", str(out_json)]
    wall, code, rss, err, cpu = run_cli(cmd, timeout, use_time)
    if code != 0:
        tail = "\n".join(err.strip().splitlines()[-6:])
        raise MeasurementError(f"parse-json on {path.name}: exit status {code}\n{tail}")
    size = out_json.stat().st_size
    if size == 0:
        raise MeasurementError(f"parse-json on {path.name}: empty output")
    out_json.unlink()
    return Sample(wall, baseline_rss, rss, {"json_bytes": size, "cpu_seconds": cpu})


def measure_cold(cmd: list[str], repeat: int, timeout: float, use_time: bool) -> Cell:
    """Best-of-`repeat` wall time of a whole process, plus one more run for its peak RSS."""
    cell = Cell()
    try:
        _, code, rss, err, _ = run_cli(cmd, timeout, use_time)
        if code != 0:
            cell.error = f"exit status {code}: {err.strip()[-400:]}"
            return cell
        for _ in range(repeat):
            # Timed without the GNU time wrapper: nothing but the command itself.
            wall, code, _, _, err, _ = _run_wait4(cmd, timeout, cwd=str(REPO))
            if code != 0:
                cell.error = f"exit status {code}: {err.strip()[-400:]}"
                return cell
            cell.samples.append(Sample(wall, None, rss))
    except MeasurementError as exc:
        cell.error = str(exc)
    return cell


# --------------------------------------------------------------------------
# Formatting
# --------------------------------------------------------------------------

def _mb(n: int | None) -> str:
    return "n/a" if n is None else f"{n / MB:.1f}"


def _label(path: Path, taken: set[str]) -> str:
    label = "_".join(path.stem.split("_")[:2])
    if label in taken:
        label = path.stem
    taken.add(label)
    return label


def _ratio(occt: Cell, cell: Cell) -> float | None:
    if not (occt.ok and cell.ok):
        return None
    return occt.best / cell.best


def _fmt_ratio(r: float | None) -> str:
    return "n/a" if r is None else f"{r:.2f}x"


@dataclass
class Run:
    files: list[Path]
    labels: dict[Path, str]
    cells: dict[tuple[Path, str], Cell]
    cold: dict[str, Cell]
    facts: dict
    repeat: int
    cold_repeat: int
    names_path: Path
    n_names: int
    gnu_time: bool

    def size(self, f: Path) -> int:
        return f.stat().st_size

    def cell(self, f: Path, kind: str) -> Cell:
        return self.cells[(f, kind)]

    def aggregate(self, kind: str) -> tuple[float | None, float | None]:
        """(MB/s over all files, ratio to OCCT) from the sums of best times."""
        cells = [self.cell(f, kind) for f in self.files]
        if not all(c.ok for c in cells):
            return None, None
        total = sum(self.size(f) for f in self.files)
        secs = sum(c.best for c in cells)
        occ = [self.cell(f, "occt") for f in self.files]
        ratio = (sum(c.best for c in occ) / secs) if all(c.ok for c in occ) else None
        return total / MB / secs, ratio

    def worst_ratio(self, kind: str) -> tuple[float | None, str | None]:
        worst, where = None, None
        for f in self.files:
            r = _ratio(self.cell(f, "occt"), self.cell(f, kind))
            if r is None:
                return None, None
            if worst is None or r < worst:
                worst, where = r, self.labels[f]
        return worst, where


def target_lines(run: Run) -> list[tuple[str, str | None, str]]:
    """(target, met / not met / unknown, detail) for each target."""
    rows = []

    def speed_target(kind, goal, title):
        worst, where = run.worst_ratio(kind)
        _, agg = run.aggregate(kind)
        if worst is None:
            rows.append((title, None, "not measured (a measurement failed or was skipped)"))
            return
        met = worst >= goal
        detail = f"worst file {worst:.2f}x ({where}), all files {agg:.2f}x"
        if not met:
            detail += f"; gap: needs {goal / worst:.2f}x more speed on {where}"
        rows.append((title, met, detail))

    speed_target("index+kin", TARGET_KIN_VS_OCCT,
                 f"index + kinematics decode >= {TARGET_KIN_VS_OCCT:g}x OCCT ReadFile throughput")
    speed_target("parse-json", TARGET_PARSE_VS_OCCT,
                 f"full parse to JSON (CLI, end to end) >= {TARGET_PARSE_VS_OCCT:g}x OCCT ReadFile throughput")

    title = f"index peak RSS growth <= {TARGET_RSS_PER_SIZE:g}x file size"
    worst, where = None, None
    for f in run.files:
        c = run.cell(f, "index")
        if not c.ok or c.growth is None:
            worst = None
            break
        r = c.growth / run.size(f)
        if worst is None or r > worst:
            worst, where = r, run.labels[f]
    if worst is None:
        rows.append((title, None, "not measured"))
    else:
        met = worst <= TARGET_RSS_PER_SIZE
        detail = f"worst file {worst:.2f}x ({where})"
        if not met:
            detail += f"; gap: {worst - TARGET_RSS_PER_SIZE:.2f}x file size over"
        rows.append((title, met, detail))

    title = f"cold start < {TARGET_COLD_MS:g} ms"
    timed = {name: c for name, c in run.cold.items() if not name.startswith("(reference)")}
    if not timed or not all(c.ok for c in timed.values()):
        rows.append((title, None, "not measured"))
    else:
        slowest = max(timed, key=lambda n: timed[n].best)
        ms = timed[slowest].best * 1000
        met = ms < TARGET_COLD_MS
        detail = f"slowest: `{slowest}` {ms:.0f} ms"
        if not met:
            detail += f"; gap: {ms - TARGET_COLD_MS:.0f} ms over"
        rows.append((title, met, detail))
    return rows


def _verdict(met: bool | None) -> str:
    return {True: "met", False: "NOT MET", None: "unknown"}[met]


def kind_columns(run: Run, kind: str, f: Path) -> dict[str, str]:
    """The cells of one table row (file `f`, measurement `kind`)."""
    c = run.cell(f, kind)
    size = run.size(f)
    row = {"file": run.labels[f], "MB": f"{size / MB:.2f}"}
    if c.skipped:
        row["best s"] = f"skipped ({c.skipped})"
        return row
    if not c.ok:
        row["best s"] = "FAILED"
        return row
    row["best s"] = f"{c.best:.3f}"
    if c.best_cpu is not None:
        row["cpu s"] = f"{c.best_cpu:.3f}"
    row["MB/s"] = f"{size / MB / c.best:.1f}"
    row["vs OCCT"] = _fmt_ratio(_ratio(run.cell(f, "occt"), c))
    row["peak RSS MB"] = _mb(c.peak_rss)
    if kind == "parse-json":
        row["growth MB*"] = _mb(c.growth)
    else:
        row["growth MB"] = _mb(c.growth)
    if c.growth is not None:
        row["growth/size"] = f"{c.growth / size:.2f}x"
    inst = c.extra("instances")
    if inst is not None:
        row["instances"] = f"{inst:,}"
    if kind == "index+kin":
        row["kin. inst."] = str(c.extra("kinematics"))
        row["decoded"] = str(c.extra("decoded"))
        row["index s"] = f"{c.extra('index_seconds'):.3f}"
    if kind == "parse-json":
        row["JSON MB"] = _mb(c.extra("json_bytes"))
    return row


def _plain_table(rows: list[dict[str, str]]) -> str:
    cols: list[str] = []
    for r in rows:
        cols += [k for k in r if k not in cols]
    widths = {c: max(len(c), *(len(r.get(c, "")) for r in rows)) for c in cols}
    out = ["  ".join(c.ljust(widths[c]) for c in cols),
           "  ".join("-" * widths[c] for c in cols)]
    out += ["  ".join(r.get(c, "").ljust(widths[c]) for c in cols) for r in rows]
    return "\n".join(out)


def _md_table(rows: list[dict[str, str]]) -> str:
    cols: list[str] = []
    for r in rows:
        cols += [k for k in r if k not in cols]
    out = ["| " + " | ".join(cols) + " |", "|" + "|".join("---" for _ in cols) + "|"]
    out += ["| " + " | ".join(r.get(c, "") for c in cols) + " |" for r in rows]
    return "\n".join(out)


def summary_rows(run: Run) -> list[dict[str, str]]:
    rows = []
    for kind in KINDS:
        mbps, ratio = run.aggregate(kind)
        row = {"measurement": KIND_TITLES[kind]}
        for f in run.files:
            c = run.cell(f, kind)
            row[run.labels[f] + " MB/s"] = f"{run.size(f) / MB / c.best:.1f}" if c.ok else "n/a"
        row["all files MB/s"] = "n/a" if mbps is None else f"{mbps:.1f}"
        row["vs OCCT"] = _fmt_ratio(ratio)
        rows.append(row)
    return rows


def cold_rows(run: Run) -> list[dict[str, str]]:
    rows = []
    for name, c in run.cold.items():
        if c.ok:
            ms = c.best * 1000
            ref = name.startswith("(reference)")
            verdict = "" if ref else ("met" if ms < TARGET_COLD_MS else "NOT MET")
            rows.append({"command": f"`{name}`", "best ms": f"{ms:.0f}",
                         "median ms": f"{sorted(s.seconds for s in c.samples)[len(c.samples) // 2] * 1000:.0f}",
                         "peak RSS MB": _mb(c.peak_rss),
                         f"< {TARGET_COLD_MS:g} ms": verdict})
        else:
            rows.append({"command": f"`{name}`", "best ms": "FAILED"})
    return rows


def print_report(run: Run) -> None:
    keep = ("file", "kind", "MB", "best s", "cpu s", "MB/s", "vs OCCT", "peak RSS MB", "growth MB", "growth MB*",
            "growth/size", "instances")
    rows = []
    for f in run.files:
        for kind in KINDS:
            row = kind_columns(run, kind, f)
            row = {"file": row.pop("file"), "kind": kind, **row}
            if "growth MB*" in row:
                row["growth MB"] = row.pop("growth MB*") + "*"
            rows.append({k: v for k, v in row.items() if k in keep})
    print()
    print(f"load average (1/5/15 min): {run.facts.get('load_before', '?')} before, {_loadavg()} now")
    print("Aggregate throughput, all files (sum of best times)")
    print(_plain_table([{"kind": k, "MB/s": r["all files MB/s"], "vs OCCT": r["vs OCCT"]}
                        for k, r in zip(KINDS, summary_rows(run))]))
    print()
    print(f"Parser throughput, best of {run.repeat} (MB = 10^6 bytes; vs OCCT = throughput ratio)")
    print(_plain_table(rows))
    print("  * parse-json growth is over the CLI's own peak RSS when parsing the small example")
    print()
    print(f"Cold start, best of {run.cold_repeat}")
    print(_plain_table([{k: v.strip("`") for k, v in r.items()} for r in cold_rows(run)]))
    print()
    print("Targets")
    for title, met, detail in target_lines(run):
        print(f"  [{_verdict(met):>7}] {title}: {detail}")
    for (f, kind), c in run.cells.items():
        if c.error:
            print(f"\nFAILED {kind} on {f.name}:\n{c.error}", file=sys.stderr)
    for name, c in run.cold.items():
        if c.error:
            print(f"\nFAILED cold start `{name}`:\n{c.error}", file=sys.stderr)


def _loadavg() -> str:
    try:
        return " / ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        return "unknown"


def machine_facts(facts: dict) -> list[tuple[str, str]]:
    from importlib import metadata
    cpu = "unknown"
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.lower().startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    mem = None
    try:
        with open("/proc/meminfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("MemTotal:"):
                    mem = int(line.split()[1]) * 1024
                    break
    except OSError:
        pass
    try:
        ocp_pkg = metadata.version("cadquery-ocp")
    except metadata.PackageNotFoundError:
        ocp_pkg = None
    if facts.get("occt"):
        occt = f"Open CASCADE {facts['occt']}" + (f" (cadquery-ocp {ocp_pkg})" if ocp_pkg else "")
    elif ocp_pkg:
        occt = f"cadquery-ocp {ocp_pkg} (OCP {facts.get('ocp') or '?'}; Standard_Version is not bound in this build)"
    else:
        occt = "not installed"
    try:
        sys.path.insert(0, str(REPO))
        from p105cli import __version__ as p105_version
    except Exception:  # noqa: BLE001
        p105_version = "?"
    commit = "?"
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True,
                                text=True, timeout=10).stdout.strip() or "?"
    except (OSError, subprocess.SubprocessError):
        pass
    return [
        ("CPU", cpu),
        ("nproc", str(os.cpu_count()) if not hasattr(os, "sched_getaffinity")
         else f"{len(os.sched_getaffinity(0))}"),
        ("memory", "unknown" if mem is None else f"{mem / 2**30:.1f} GiB"),
        ("OS", platform.platform()),
        ("Python", f"{platform.python_implementation()} {platform.python_version()} ({sys.executable})"),
        ("OCCT", occt),
        ("load average (1/5/15 min)", f"{facts.get('load_before', '?')} before the run, {_loadavg()} after"),
        ("p105", f"{p105_version} (commit {commit}; the working tree may have uncommitted changes)"),
    ]


def markdown(run: Run, command: str) -> str:
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    L: list[str] = []
    L.append("# Parser benchmarks")
    L.append("")
    L.append("Generated by `bench/bench_parse.py` (`make bench-parse`); do not edit by hand. Produced by:")
    L.append("")
    L.append("```sh")
    L.append(command)
    L.append("```")
    L.append("")
    L.append(f"Date: {now}. Times are the best of {run.repeat} runs, each in a fresh process. "
             "MB = 10^6 bytes; **vs OCCT** is the throughput ratio to Open CASCADE `ReadFile` on "
             "the same file (above 1 = faster than OCCT).")
    L.append("")
    L.append("## Machine")
    L.append("")
    for k, v in machine_facts(run.facts):
        L.append(f"- **{k}**: {v}")
    L.append("")
    L.append("## Corpus")
    L.append("")
    L.append("| label | file | bytes |")
    L.append("|---|---|---|")
    for f in run.files:
        L.append(f"| {run.labels[f]} | `{f.name}` | {run.size(f):,} |")
    L.append("")
    L.append("## At a glance")
    L.append("")
    L.append(_md_table(summary_rows(run)))
    L.append("")
    for kind in KINDS:
        L.append(f"## {KIND_TITLES[kind]}")
        L.append("")
        L.append(KIND_NOTES[kind].format(n_names=run.n_names, names=run.names_path.name))
        L.append("")
        L.append(_md_table([kind_columns(run, kind, f) for f in run.files]))
        L.append("")
    L.append("## Cold start")
    L.append("")
    L.append(f"Wall time of the whole process, best of {run.cold_repeat} (the median is shown too). "
             "The `(reference)` row is the bare interpreter, the floor no Python CLI can go under.")
    L.append("")
    L.append(_md_table(cold_rows(run)))
    L.append("")
    L.append("## Targets")
    L.append("")
    for title, met, detail in target_lines(run):
        L.append(f"- **{_verdict(met)}**: {title}. {detail[0].upper() + detail[1:]}.")
    L.append("")
    L.append("## How measured")
    L.append("")
    cli_rss = ("reported by GNU `/usr/bin/time -f %M`, which wraps those runs (its fork + exec adds about "
               "a millisecond to the parse-to-JSON wall times; cold-start times are taken without it and "
               "their RSS from one extra wrapped run)" if run.gnu_time else
               "the `ru_maxrss` of `os.wait4` (GNU time was not available), which includes the benchmark "
               "process's own high-water mark: an upper bound")
    L.append(HOW_MEASURED.format(repeat=run.repeat, cold_repeat=run.cold_repeat, cli_rss=cli_rss))
    L.append("")
    return "\n".join(L)


KIND_NOTES = {
    "index": ("Read the bytes, `decode_bytes`, `read_step(text, path)`: the frame is checked and every "
              "instance is indexed (id, type, span); nothing is decoded. *growth* is the peak RSS over the "
              "child's baseline just before reading the file; the target is growth/size <= "
              f"{TARGET_RSS_PER_SIZE:g}x."),
    "index+kin": ("Index, then decode the instances whose type is one of the {n_names} kinematics entities in "
                  "`{names}` (`sf.slots_of_type`, `sf._decode_slot`) and, transitively, every instance they "
                  "reference (`sf.record`). **These files contain no kinematics** (0 kinematics instances), "
                  "so this is the index time plus one pass over the type list: it shows the cost the "
                  "kinematics filters pay on a big non-kinematic file, not decoding speed."),
    "parse-json": ("`python -m p105cli parse FILE -o OUT.json`, timed from outside: interpreter start-up, "
                   "imports, indexing, decoding every instance and writing the JSON are all included. "
                   "Peak RSS is that of the CLI process (see *How measured*); *growth MB\\** is over the "
                   "peak RSS of the same CLI parsing the small `examples/four_bar_ap242.stp`."),
    "occt": ("`STEPControl_Reader().ReadFile(path)` via cadquery-ocp: only `ReadFile` is timed (the `OCP` "
             "import, ~250 MB of shared libraries, is excluded from time and growth), and no shape transfer "
             "is done. *instances* is `StepModel().NbEntities()`."),
    "naive": ("Read, decode, `text.split(';')` over the DATA section and `#(\\d+)\\s*=\\s*(\\w+)` on each "
              "piece, keeping ids and types: the floor a pure-Python reader competes with. It is not a "
              "correct reader: a `;` inside a string splits an instance, and complex instances "
              "(`#n=(A(...)B(...))`) have no single type, so the regex misses them; its instance count "
              "is a sanity check only (here it is short by exactly the files' complex instances)."),
}

HOW_MEASURED = """\
- Each measurement runs in a fresh interpreter (`bench_parse.py --child KIND FILE`), so its peak RSS
  belongs to that measurement alone. The peak is read inside the child from `VmHWM` in `/proc/self/status`
  (falling back to `resource.getrusage(RUSAGE_SELF).ru_maxrss`): on Linux `ru_maxrss` survives fork + exec,
  so a child's `ru_maxrss` starts at the *parent's* high-water mark, while `VmHWM` counts only the child's
  own address space. *growth* = peak after the work minus the child's peak just before it reads the file
  (after its imports). The RSS columns show the highest of the runs; times the best of {repeat}.
- Peak RSS of the CLI processes (parse to JSON, cold start) is {cli_rss}.
- Repeats are interleaved (repeat 1 of every file and kind, then repeat 2, ...) so drift affects all alike.
  All files are read once before timing starts, so every run reads from the page cache.
- In-process times (`time.perf_counter`) include reading the file from the page cache and decoding the
  bytes, except OCCT's, which is `ReadFile` alone (it reads the file itself).
- "parse to JSON" is timed around the subprocess and so includes interpreter start-up (see *Cold start*),
  while OCCT's time excludes loading OCCT: the comparison is deliberately unfavourable to p105.
- Cold start: best of {cold_repeat} whole-process runs with stdout to /dev/null; the `.venv/bin/p105`
  console script is measured too when it exists.
- *cpu s* is the CPU time (user + system) of the fastest run, over the same span as *best s* (for the CLI,
  of the whole process). Well below *best s* means the run waited for a CPU: the machine was busy (see the
  load average above) and the wall times are pessimistic.
- Targets compare the worst file, not the average; the all-files ratio (sum of best times) is given too."""


# --------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------

def _default_names(corpus: Path) -> Path:
    for cand in (corpus.parent.parent / "schema" / NAMES_FILE,
                 REPO.parent / "shared" / "schema" / NAMES_FILE):
        if cand.is_file():
            return cand
    return corpus.parent.parent / "schema" / NAMES_FILE


def write_atomic(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomically(path, text)


def parse_args(argv: list[str]) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--corpus", type=Path, required=True, help="directory of .step/.stp files")
    ap.add_argument("--markdown", type=Path, help="also write the results as a Markdown page here")
    ap.add_argument("--repeat", type=int, default=3, help="runs per measurement; the best time is kept (3)")
    ap.add_argument("--cold-repeat", type=int, default=10, help="runs per cold-start command (10)")
    ap.add_argument("--names", type=Path, help=f"kinematics entity names (default: CORPUS/../../schema/{NAMES_FILE})")
    ap.add_argument("--timeout", type=float, default=600, help="seconds allowed for one run (600)")
    args = ap.parse_args(argv)
    if args.repeat < 1 or args.cold_repeat < 1:
        ap.error("--repeat and --cold-repeat must be at least 1")
    return args


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--child"]:
        return child_main(argv[1:])
    args = parse_args(argv)
    corpus = args.corpus
    files = sorted(p for p in corpus.iterdir() if p.suffix.lower() in (".step", ".stp") and p.is_file()) \
        if corpus.is_dir() else []
    if not files:
        print(f"bench_parse: no .step/.stp files in {corpus}", file=sys.stderr)
        return 2
    names = args.names or _default_names(corpus)
    if not names.is_file():
        print(f"bench_parse: kinematics names file not found: {names} (use --names)", file=sys.stderr)
        return 2
    n_names = len(_load_names(str(names)))

    taken: set[str] = set()
    labels = {f: _label(f, taken) for f in files}
    cells = {(f, k): Cell() for f in files for k in KINDS}

    for f in files:  # warm the page cache so no run pays for the disk (in chunks: keep this process small)
        with open(f, "rb") as fh:
            while fh.read(1 << 20):
                pass
    use_time = gnu_time_works()
    facts: dict = {"load_before": _loadavg()}

    def log(msg):
        print(msg, file=sys.stderr, flush=True)

    # Cold start first: it also gives the CLI's baseline RSS for parse-json.
    cold: dict[str, Cell] = {}
    py = sys.executable
    small = str(SMALL_EXAMPLE.relative_to(REPO))
    cold_cmds = {
        "(reference) python3 -c pass": [py, "-c", "pass"],
        "python3 -m p105cli --help": [py, "-m", "p105cli", "--help"],
        f"python3 -m p105cli parse {small}": [py, "-m", "p105cli", "parse", small],
    }
    console = REPO / ".venv" / "bin" / "p105"
    if console.exists():
        cold_cmds[".venv/bin/p105 --help"] = [str(console), "--help"]
        cold_cmds[f".venv/bin/p105 parse {small}"] = [str(console), "parse", small]
    for name, cmd in cold_cmds.items():
        log(f"cold start: {name}")
        cold[name] = measure_cold(cmd, args.cold_repeat, args.timeout, use_time)
    small_cell = cold[f"python3 -m p105cli parse {small}"]
    cli_baseline = small_cell.peak_rss if small_cell.ok else None

    try:
        facts.update(run_child("facts", files[0], names, args.timeout).extra)
    except (MeasurementError, Unavailable) as exc:
        log(f"warning: could not read library versions: {exc}")

    with tempfile.TemporaryDirectory(prefix="bench_parse.") as scratch:
        out_json = Path(scratch) / "out.json"
        for rep in range(args.repeat):
            for f in files:
                for kind in KINDS:
                    c = cells[(f, kind)]
                    if c.error or c.skipped:
                        continue
                    log(f"[{rep + 1}/{args.repeat}] {kind:<10} {labels[f]}")
                    try:
                        if kind == "parse-json":
                            s = run_parse_json(f, out_json, args.timeout, cli_baseline, use_time)
                        else:
                            s = run_child(kind, f, names, args.timeout)
                    except Unavailable as exc:
                        c.skipped = str(exc)
                        continue
                    except (MeasurementError, json.JSONDecodeError, KeyError) as exc:
                        c.error = str(exc)
                        continue
                    c.samples.append(s)

    run = Run(files, labels, cells, cold, facts, args.repeat, args.cold_repeat, names, n_names, use_time)
    print_report(run)

    crashed = [k for k, c in cells.items() if c.error] + [n for n, c in cold.items() if c.error]
    if args.markdown:
        if crashed:
            log(f"\nbench_parse: {len(crashed)} measurement(s) crashed; not writing {args.markdown}")
        else:
            command = shlex.join(getattr(sys, "orig_argv", [sys.executable, *sys.argv]))
            write_atomic(args.markdown, markdown(run, command))
            log(f"\nwrote {args.markdown}")
    return 1 if crashed else 0


if __name__ == "__main__":
    sys.exit(main())
