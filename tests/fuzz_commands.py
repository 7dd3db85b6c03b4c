#!/usr/bin/env python3
"""Fuzz every command for internal errors: ``make fuzz`` / ``make fuzz-commands`` (``P105_FUZZ_SECONDS``).

Seeds: the corpus (``tests/data/corpus``), the examples and the small files of
``../shared/external`` (when present); DH tables for ``convert-dh-su``; the cable scene and
its key points. Each round takes a seed and mutates it at one of three levels:

* bytes: flips, truncation;
* Part 21 tokens and grammar: a deleted, duplicated or renumbered instance, swapped or
  out-of-range references, a renamed entity type, an argument replaced by another kind of
  value (number, string, enumeration, ``$``, ``*``, a list, a huge id), deleted or added,
  a list nested;
* the p105/1 JSON model (what ``p105 parse`` writes of the seed): a key deleted, a value
  retyped, a key duplicated, references swapped, odd numbers (2**63, 1e308, -0.0, NaN),
  deep nesting;

and runs every command on it in this process (``make_golden.run_in_process``): parse,
validate (and --pass), graph (json, --enrich, --to dot|graphml|mermaid), export --schema
ap214|ap242|p105 and --to p21|json, solve (initial, --program, --set, --sweep, --values,
--to model|jsonl|csv), interpolate (and its --what, --to), convert-dh-su; solve --scene
for mutated scenes and key points. A run is a crash when it ends with an exit status other
than 0, 1 or 2, with a traceback or "internal error", with a Python warning on stderr, with
NaN or Infinity in JSON or CSV output, or when a failed run (``-o``) changed its output
file or left a temporary file. Crashes are saved under
``build/fuzz-commands/`` with the command line; the run exits 1 at the end if any.

``make fuzz`` runs the reader fuzzer (``tests/fuzz_reader.py``) for a share of the time
too (``--reader-share``). Random with a seed (``P105_FUZZ_SEED``, default the time),
printed so that a run can be repeated; ``P105_FUZZ_ROUNDS`` bounds the number of inputs
(the fixed-seed run of the test suite uses it). Not a pytest module (pytest does not
collect ``fuzz_*.py``); the crashes it found are regression tests in
``tests/cli/test_fuzz_regressions.py``, and the record of runs is docs/fuzzing.md.
"""

from __future__ import annotations

import argparse
import collections
import copy
import csv
import io
import json
import os
import random
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path[:0] = [str(ROOT), str(HERE)]

import make_golden  # noqa: E402  (after the path)

SHARED = Path(os.environ.get("P105_SHARED", ROOT.parent / "shared"))
OUT = ROOT / "build" / "fuzz-commands"
MAX_SEED_BYTES = 200_000  # bigger external files make rounds slow without reaching new code
COMMAND_SECONDS = 60  # a command using more CPU time is reported as slow (not a crash)

_INSTANCE = re.compile(r"^#\d+\s*=.*?;\s*$", re.M | re.S)
_REF = re.compile(r"#(\d+)")
_TYPE = re.compile(r"(?<=[=(])\s*([A-Z][A-Z0-9_]*)\s*(?=\()")
_NUMBER = re.compile(r"(?<![#\w])[-+]?\d+\.\d*(?:E[-+]?\d+)?")
_NAME = re.compile(r"'([^'\n]{1,40})'")
_PAIR_NAME = re.compile(r"PAIR\('([^'\n]{1,40})'")
# One argument token of a Part 21 parameter list (strings with '' inside, refs, enums, numbers, $, *).
_TOKEN = re.compile(r"'(?:[^']|'')*'|#\d+|\.[A-Z_][A-Z0-9_]*\.|[-+]?\d+(?:\.\d*)?(?:E[-+]?\d+)?|\$|\*")
ODD_NUMBERS = ["0.", "-0.", "1.E300", "-1.E300", "1.E-300", "1E999", "NaN", "$", "*", "1", "''", "#0", ".T.",
               "5.E-324", "1.7976931348623157E308", "-1.E-320", "3.14159265358979", "1.5707963267948966"]
ODD_TOKENS = ["$", "*", "()", "(())", "''", "'x'", ".T.", ".F.", ".U.", ".BOGUS.", "0", "-1", "0.", "-0.",
              "1.E308", "-1.E308", "1.E-308", "#0", "#9223372036854775808", "#18446744073709551617",
              "9223372036854775808", "(1.,2.)", "(#1,#1)", "\"0FF\"", "PLANE_ANGLE_MEASURE(0.)",
              "LENGTH_MEASURE(1.E300)", "POSITIVE_LENGTH_MEASURE(-1.)"]
ODD_JSON = [None, True, False, 0, -1, 1.5, -0.0, 1e308, -1e308, 5e-324, 2 ** 63, -(2 ** 63) - 1, 2 ** 64, "", "x",
            [], {}, [[]], {"ref": 0}, {"ref": -1}, {"ref": 2 ** 63}, {"ref": "1"}, {"enum": "BOGUS"},
            {"derived": True}, {"type": "LENGTH_MEASURE", "value": 1e308}, {"type": "X"}, "NaN", "\ud800"]


class Slow(BaseException):
    """A command used more than COMMAND_SECONDS of CPU (a BaseException: main() does not catch it)."""


# ---------------------------------------------------------------- seeds

class Seeds:
    """The inputs mutated: model files, DH tables, scenes and key points."""

    def __init__(self):
        self.models = sorted((ROOT / "tests" / "data" / "corpus").glob("*.stp")) \
            + sorted((ROOT / "examples").glob("*.stp"))
        ext = SHARED / "external"
        if ext.is_dir():
            self.models += sorted(p for p in ext.rglob("*") if p.suffix.lower() in (".stp", ".step", ".json")
                                  and p.is_file() and p.stat().st_size <= MAX_SEED_BYTES
                                  and "scene" not in p.name)
        # Files with a mechanism reach the analyses: drawn more often than plain CAD files.
        self.kinematic = [p for p in self.models if p.suffix.lower() != ".json"
                          and re.search(rb"MECHANISM|KINEMATIC", p.read_bytes()[:MAX_SEED_BYTES], re.I)]
        self.tables = [ROOT / "examples" / "puma560_dh.csv", ROOT / "examples" / "panda_dh.json"]
        self.scene = ROOT / "examples" / "cable_scene.json"
        self.keypoints = ROOT / "examples" / "cable_keypoints.jsonl"
        self._json: dict[Path, object] = {}

    def json_model(self, path: Path):
        """The p105/1 JSON model of a Part 21 seed (as ``p105 parse`` writes it), or None."""
        if path not in self._json:
            from p105cli.step import StepError, decode_bytes, read_json, read_step, write_json
            try:
                raw = decode_bytes(path.read_bytes())
                doc = read_json(raw, str(path)) if raw.lstrip().startswith("{") else read_step(raw, str(path))
                out = io.StringIO()
                write_json(doc, out)
                self._json[path] = json.loads(out.getvalue())
            except (StepError, ValueError, RecursionError):
                self._json[path] = None
        return copy.deepcopy(self._json[path])


# ---------------------------------------------------------------- bytes

def flip_bytes(rng, data: bytes) -> bytes:
    b = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        if b:
            b[rng.randrange(len(b))] = rng.choice(b"();,#'$*.=/\\ \n0123456789EAZ\xff")
    return bytes(b)


def truncate(rng, data: bytes) -> bytes:
    return data[:rng.randrange(len(data) + 1)]


# ---------------------------------------------------------------- Part 21 tokens and grammar

def _instances(text: str) -> list[re.Match]:
    return list(_INSTANCE.finditer(text))


def delete_instance(rng, text: str) -> str:
    inst = _instances(text)
    if not inst:
        return text
    m = rng.choice(inst)
    return text[:m.start()] + text[m.end():]


def duplicate_instance(rng, text: str) -> str:
    inst = _instances(text)
    if not inst:
        return text
    m = rng.choice(inst)
    other = rng.choice(inst)  # same id twice, or an instance moved under another's id
    body = m.group(0)
    if rng.random() < 0.5:
        body = _REF.sub(lambda r: "#" + _REF.match(other.group(0)).group(1), body, count=1)
    return text[:m.end()] + "\n" + body + text[m.end():]


def swap_references(rng, text: str) -> str:
    refs = list(_REF.finditer(text))
    if len(refs) < 2:
        return text
    ids = [r.group(1) for r in refs]
    out = []
    last = 0
    for r in rng.sample(refs, min(len(refs), rng.randint(1, 6))):
        out.append((r.start(1), r.end(1), rng.choice(ids + ["0", "999999", "9223372036854775807"])))
    out.sort()
    pieces = []
    for a, b, new in out:
        if a < last:
            continue
        pieces += [text[last:a], new]
        last = b
    return "".join(pieces) + text[last:]


def rename_type(rng, text: str) -> str:
    types = list(_TYPE.finditer(text))
    if not types:
        return text
    names = sorted({t.group(1) for t in types}) + ["FOO", "REVOLUTE_PAIR", "KINEMATIC_PAIR", "MECHANISM",
                                                     "LOW_ORDER_KINEMATIC_PAIR", "GEAR_PAIR", "UNIVERSAL_PAIR"]
    m = rng.choice(types)
    return text[:m.start(1)] + rng.choice(names) + text[m.end(1):]


def replace_number(rng, text: str) -> str:
    nums = list(_NUMBER.finditer(text))
    if not nums:
        return text
    m = rng.choice(nums)
    return text[:m.start()] + rng.choice(ODD_NUMBERS + [m.group(0) + "0" * 3]) + text[m.end():]


def _one_argument(rng, text: str):
    """``(instance, its argument tokens, one of them)`` of a random instance, or None."""
    inst = _instances(text)
    if not inst:
        return None
    m = rng.choice(inst)
    tokens = list(_TOKEN.finditer(m.group(0), m.group(0).find("=") + 1))
    return (m, tokens, rng.choice(tokens)) if tokens else None


def replace_argument(rng, text: str) -> str:
    """One argument of one instance becomes another kind of value, or goes, or is doubled."""
    found = _one_argument(rng, text)
    if found is None:
        return text
    m, tokens, t = found
    body = m.group(0)
    pool = ODD_TOKENS + [u.group(0) for u in tokens]
    kind = rng.random()
    if kind < 0.6:
        new = body[:t.start()] + rng.choice(pool) + body[t.end():]
    elif kind < 0.8:  # the argument deleted with a comma next to it
        after = body[t.end():]
        new = body[:t.start()] + (after[1:] if after.startswith(",") else after)
        if not after.startswith(","):
            new = new[:t.start()].rstrip(",") + new[t.start():]
    else:  # one more argument
        new = body[:t.end()] + "," + rng.choice(pool) + body[t.end():]
    return text[:m.start()] + new + text[m.end():]


def nest_argument(rng, text: str) -> str:
    """An argument wrapped in one or many list levels."""
    found = _one_argument(rng, text)
    if found is None:
        return text
    m, _, t = found
    depth = rng.choice((1, 1, 2, 3, 300))
    body = m.group(0)
    new = body[:t.start()] + "(" * depth + t.group(0) + ")" * depth + body[t.end():]
    return text[:m.start()] + new + text[m.end():]


def renumber_instance(rng, text: str) -> str:
    """An instance's id changed (its referrers now dangle), or made huge."""
    inst = _instances(text)
    if not inst:
        return text
    m = rng.choice(inst)
    new_id = rng.choice(["0", "1", "999999", "9223372036854775807", "9223372036854775808"])
    body = re.sub(r"^#\d+", "#" + new_id, m.group(0), count=1)
    return text[:m.start()] + body + text[m.end():]


TEXT_MUTATIONS = [delete_instance, duplicate_instance, swap_references, rename_type, replace_number,
                  replace_argument, replace_argument, nest_argument, renumber_instance]


def mutate_model(rng, data: bytes) -> bytes:
    for _ in range(rng.choice((1, 1, 1, 2, 3))):
        kind = rng.random()
        if kind < 0.12:
            data = flip_bytes(rng, data)
        elif kind < 0.18:
            data = truncate(rng, data)
        else:
            text = data.decode("utf-8", "replace")
            data = rng.choice(TEXT_MUTATIONS)(rng, text).encode("utf-8", "surrogatepass")
    return data


# ---------------------------------------------------------------- the JSON model

def _containers(obj) -> list:
    """Every dict and list in ``obj`` (iteratively: a mutated model may be deep)."""
    out, stack = [], [obj]
    while stack:
        x = stack.pop()
        if isinstance(x, (dict, list)):
            out.append(x)
            stack.extend(x.values() if isinstance(x, dict) else x)
    return out


def _slot(rng, doc):
    """(container, key or index) of a random value in ``doc``."""
    cs = [c for c in _containers(doc) if c]
    if not cs:
        return None
    c = rng.choice(cs)
    return c, rng.choice(list(c.keys()) if isinstance(c, dict) else range(len(c)))


def json_delete_key(rng, doc):
    cs = [c for c in _containers(doc) if isinstance(c, dict) and c]
    if cs:
        c = rng.choice(cs)
        del c[rng.choice(list(c))]
    return doc


def json_retype(rng, doc):
    s = _slot(rng, doc)
    if s:
        c, k = s
        c[k] = copy.deepcopy(rng.choice(ODD_JSON))
    return doc


def json_swap_refs(rng, doc):
    refs = [c for c in _containers(doc) if isinstance(c, dict) and isinstance(c.get("ref"), int)]
    ids = [r["ref"] for r in refs] + [0, 999999, 2 ** 63 - 1]
    for r in rng.sample(refs, min(len(refs), rng.randint(1, 4))):
        r["ref"] = rng.choice(ids)
    return doc


def json_odd_number(rng, doc):
    nums = [(c, k) for c in _containers(doc)
            for k in (c.keys() if isinstance(c, dict) else range(len(c)))
            if type(c[k]) in (int, float)]
    if nums:
        c, k = rng.choice(nums)
        c[k] = rng.choice([1e308, -1e308, 5e-324, -0.0, 2 ** 63, 2 ** 64, -(2 ** 63), 0, 1e16, float("nan"),
                           float("inf"), c[k] * 1e6])
    return doc


def json_deep(rng, doc):
    """A value nested in thousands of lists (spliced into the text by _dump: json.dumps recurses)."""
    s = _slot(rng, doc)
    if s:
        c, k = s
        c[k] = {"__deep__": rng.choice((2, 50, 1500, 5000, 100000))}
    return doc


def json_duplicate_record(rng, doc):
    data = doc.get("data") if isinstance(doc, dict) else None
    if isinstance(data, list) and data:
        rec = copy.deepcopy(rng.choice(data))
        if isinstance(rec, dict) and rng.random() < 0.5 and data and isinstance(data[0], dict):
            rec["id"] = rng.choice(data).get("id")
        data.insert(rng.randrange(len(data) + 1), rec)
    return doc


JSON_MUTATIONS = [json_delete_key, json_retype, json_retype, json_swap_refs, json_odd_number, json_deep,
                  json_duplicate_record]


def _dump(rng, doc) -> bytes:
    text = json.dumps(doc, allow_nan=True, separators=(",", ":"))
    text = re.sub(r'\{"__deep__":(\d+)\}', lambda m: "[" * int(m.group(1)) + "1" + "]" * int(m.group(1)), text)
    if rng.random() < 0.15:  # a key twice in one object (json.dumps cannot write that)
        keys = list(re.finditer(r'\{"(id|type|args|ref|format|data|header)":', text))
        if keys:
            m = rng.choice(keys)
            text = text[:m.end()] + rng.choice(['1,"' + m.group(1) + '":', '"x","' + m.group(1) + '":',
                                                  'null,"' + m.group(1) + '":']) + text[m.end():]
    return text.encode("utf-8", "surrogatepass")


def mutate_json_model(rng, doc) -> bytes:
    for _ in range(rng.choice((1, 1, 2, 3))):
        doc = rng.choice(JSON_MUTATIONS)(rng, doc)
    data = _dump(rng, doc)
    if rng.random() < 0.1:
        data = flip_bytes(rng, data) if rng.random() < 0.5 else truncate(rng, data)
    return data


# ---------------------------------------------------------------- DH tables, scenes, key points

def mutate_table(rng, data: bytes) -> bytes:
    text = data.decode("utf-8", "replace")
    kind = rng.random()
    if kind < 0.2:
        return flip_bytes(rng, data)
    if kind < 0.3:
        return truncate(rng, data)
    lines = text.splitlines(keepends=True)
    if kind < 0.5 and len(lines) > 1:
        k = rng.randrange(1, len(lines))
        if rng.random() < 0.5:
            del lines[k]
        else:
            lines.insert(k, lines[k])
        return "".join(lines).encode()
    cells = list(re.finditer(r"-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?|\"[a-z_]+\"|[a-z_]+", text))
    if not cells:
        return data
    m = rng.choice(cells)
    new = rng.choice(["", "nan", "inf", "-inf", "1e400", "0", "-1", "x", '"', "null", "[]", "{}", "1,2",
                      "revolute", "prismatic", "1e308", "-0", m.group(0) * 2])
    return (text[:m.start()] + new + text[m.end():]).encode()


def mutate_scene(rng, data: bytes) -> bytes:
    try:
        doc = json.loads(data)
    except ValueError:
        return data
    for _ in range(rng.choice((1, 1, 2))):
        doc = rng.choice([json_delete_key, json_retype, json_odd_number])(rng, doc)
    return _dump(rng, doc)


def mutate_keypoints(rng, data: bytes) -> bytes:
    lines = data.decode("utf-8", "replace").splitlines(keepends=True)
    kind = rng.random()
    if kind < 0.3 and lines:
        k = rng.randrange(len(lines))
        try:
            rec = json.loads(lines[k])
            rec = rng.choice([json_delete_key, json_retype, json_odd_number])(rng, rec)
            lines[k] = _dump(rng, rec).decode("utf-8", "replace") + "\n"
        except ValueError:
            pass
    elif kind < 0.5 and len(lines) > 1:
        k = rng.randrange(len(lines))
        if rng.random() < 0.5:
            del lines[k]
        else:
            lines.insert(k, lines[k])
    else:
        return mutate_table(rng, data)
    return "".join(lines).encode("utf-8", "replace")


# ---------------------------------------------------------------- commands

def model_commands(rng, path: str, text: str, work: Path) -> list[list[str]]:
    """Every command on one model input; pairs are named from the input's strings."""
    cmds = [["parse", path], ["parse", "--stream", path], ["validate", path], ["validate", "-f", "json", path],
            ["graph", path], ["graph", "--enrich", path],
            ["export", "--schema", rng.choice(["ap214", "p105"]), path], ["export", "--schema", "ap242", path],
            ["export", "--to", rng.choice(["p21", "json"]), path],
            ["solve", "--no-timings", "--to", "jsonl", path],
            ["solve", "--program", "--count", "3", "--no-timings", "--to", "jsonl", path],
            ["solve", "--no-timings", "--to", rng.choice(["model", "csv"]), path],
            ["interpolate", path],
            ["interpolate", "--what", rng.choice(["paths", "configurations"]), "--count", "5", "--to",
             rng.choice(["jsonl", "csv"]), path],
            ["graph", "--to", rng.choice(["dot", "graphml", "mermaid"]), path],
            ["validate", "--pass", "-o", os.devnull, path],
            ["convert-dh-su", "--to", "dh", "--convention", "standard", path]]
    names = [m.group(1) for m in (_PAIR_NAME if rng.random() < 0.8 else _NAME).finditer(text)]
    names = [n for n in names if "=" not in n and "," not in n and ":" not in n]
    for name in rng.sample(names, min(2, len(names))):  # pair names among them, sometimes
        value = rng.choice(["0.5", "-3", "1e300", "0", "1.5707963267948966", "0.5,0.1,0.2"])
        cmds.append(["solve", "--set", f"{name}={value}", "--no-timings", "--to", "jsonl", path])
    if names:
        name = rng.choice(names)
        cmds.append(["solve", "--sweep", f"{name}={rng.choice(['0:1:3', '-1e3:1e3:4', '0:0:2'])}", "--no-timings",
                     "--to", "csv", path])
        values = work / "values.csv"
        with open(values, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["t", name])
            for t in range(3):
                w.writerow([t, rng.choice(["0.1", "0.2", "-0.5", "2", "1e200", ""])])
        cmds.append(["solve", "--values", str(values), "--no-timings", "--to", "jsonl", path])
    if rng.random() < 0.3:  # -o: a failed run must leave the target as it was (checked in run_one)
        cmds.append(["solve", "--no-timings", "--to", "jsonl", "-o", str(work / "out.jsonl"), path])
    return cmds


def table_commands(path: str) -> list[list[str]]:
    return [["convert-dh-su", "--convention", conv, *to, path]
            for conv in ("standard", "modified") for to in ((), ("--to", "json"))]


def scene_commands(scene: str, keypoints: str) -> list[list[str]]:
    return [["solve", "--scene", scene, "--keypoints", keypoints, "--no-timings"]]


# ---------------------------------------------------------------- one run and its checks

_PY_WARNING = re.compile(r"^\S*:\d+: \w*Warning: ")  # what warnings.showwarning prints
_NONFINITE_CSV = re.compile(r"(?:^|,)\s*[-+]?(?:nan|inf|infinity)\s*(?:,|$)", re.I | re.M)


def _reject_constant(name):
    raise ValueError(f"{name} in JSON output")


def _json_problem(text: str) -> str | None:
    try:
        json.loads(text, parse_constant=_reject_constant)
    except ValueError as err:  # (a truncated output of a failed run does not parse: not ours to judge)
        return str(err) if "in JSON output" in str(err) else None
    return None


def output_problem(argv: list[str], out: bytes) -> str | None:
    """What is wrong with a command's stdout: NaN or Infinity in JSON, JSON Lines or CSV output."""
    if not out:
        return None
    text = out.decode("utf-8", "replace")
    if text.lstrip()[:1] in ("{", "["):
        whole = _json_problem(text)
        if whole is not None:
            return whole
        for line in text.splitlines():  # JSON Lines (a document's lines do not parse alone: skipped)
            problem = _json_problem(line) if line.strip() else None
            if problem is not None:
                return problem
    elif "--to" in argv and argv[argv.index("--to") + 1] == "csv" and _NONFINITE_CSV.search(text):
        return "NaN or inf in CSV output"
    return None


def run_one(argv: list[str]) -> tuple[int, bytes, str, float]:
    """Run ``p105 ARGV`` in this process with a limit of COMMAND_SECONDS of CPU time (the wall
    clock of a fuzzer at low priority on a busy machine says little): (status, stdout, stderr,
    seconds)."""
    def alarm(signum, frame):
        raise Slow()

    start = time.monotonic()
    if threading.current_thread() is not threading.main_thread():  # signals: the main thread's only
        code, out, err = make_golden.run_in_process(argv)
        return code, out, err, time.monotonic() - start
    previous = signal.signal(signal.SIGPROF, alarm)
    signal.setitimer(signal.ITIMER_PROF, COMMAND_SECONDS)
    try:
        code, out, err = make_golden.run_in_process(argv)
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGPROF, previous)
    return code, out, err, time.monotonic() - start


def crash_reason(argv, code: int, out: bytes, err: str) -> str | None:
    if code not in (0, 1, 2):
        return f"exit {code}"
    for line in err.splitlines():
        if "Traceback" in line or "internal error" in line or _PY_WARNING.search(line):
            return line
    return output_problem(argv, out)


class Fuzzer:
    def __init__(self, seed: int, out_dir: Path = OUT, log=print):
        self.seed, self.rng, self.out_dir, self.log = seed, random.Random(seed), Path(out_dir), log
        self.seeds = Seeds()
        self.work = self.out_dir / "work"
        self.work.mkdir(parents=True, exist_ok=True)
        self.crashes: dict[str, tuple] = {}
        self.slow: list[str] = []
        self.inputs = self.runs = 0
        self.kinds = collections.Counter()  # inputs per mutation level
        self.status = collections.Counter()  # (command, exit status) -> runs

    def next_input(self) -> tuple[Path, bytes, list[list[str]], str]:
        rng = self.rng
        r = rng.random()
        if r < 0.08:
            src = rng.choice(self.seeds.tables)
            data = mutate_table(rng, src.read_bytes())
            path = self.work / f"input{src.suffix}"
            path.write_bytes(data)
            return src, data, table_commands(str(path)), "table"
        if r < 0.13:
            scene, keys = self.work / "scene.json", self.work / "keypoints.jsonl"
            s, k = self.seeds.scene.read_bytes(), self.seeds.keypoints.read_bytes()
            if rng.random() < 0.6:
                s = mutate_scene(rng, s)
            else:
                k = mutate_keypoints(rng, k)
            scene.write_bytes(s)
            keys.write_bytes(k)
            return self.seeds.scene, s + b"\n--- keypoints\n" + k, scene_commands(str(scene), str(keys)), "scene"
        src = rng.choice(self.seeds.kinematic if rng.random() < 0.75 and self.seeds.kinematic else self.seeds.models)
        doc = self.seeds.json_model(src) if r < 0.38 else None
        if doc is not None:
            data, kind, suffix = mutate_json_model(rng, doc), "json-model", ".json"
        else:
            data, kind, suffix = mutate_model(rng, src.read_bytes()), "part21", src.suffix
        path = self.work / f"input{suffix}"
        path.write_bytes(data)
        return src, data, model_commands(rng, str(path), data.decode("utf-8", "replace"), self.work), kind

    def round(self, end: float | None) -> None:
        src, data, cmds, kind = self.next_input()
        self.inputs += 1
        self.kinds[kind] += 1
        for argv in cmds:
            if end is not None and time.monotonic() >= end:
                return
            self.run(argv, src, data, kind)

    def run(self, argv, src, data, kind) -> None:
        self.runs += 1
        target = Path(argv[argv.index("-o") + 1]) if "-o" in argv else None
        if target is not None and target.exists() and not target.is_file():
            target = None  # /dev/null: written straight through, nothing to check
        before = target.read_bytes() if target is not None and target.exists() else None
        try:
            code, out, err, _ = run_one(argv)
        except Slow:
            self.slow.append(" ".join(argv[:-1]))
            self._save(f"slow: {argv[0]} {argv[1] if len(argv) > 2 else ''}", argv, src, data, kind,
                       f"over {COMMAND_SECONDS} s of CPU")
            return
        except BaseException as exc:  # noqa: BLE001 - what main() let through is a crash too
            code, out, err = -1, b"", f"Traceback: {type(exc).__name__}: {exc}"
        self.status[(argv[0], code)] += 1
        reason = crash_reason(argv, code, out, err)
        if reason is None and target is not None:
            after = target.read_bytes() if target.exists() else None
            if code != 0 and after != before:
                reason = f"-o {target.name} changed by a run that exited {code}"
            elif any(".p105-" in n for n in os.listdir(target.parent)):
                reason = "a temporary file left next to -o"
        if reason is not None:
            self._save(f"{argv[0]} {argv[1] if len(argv) > 2 else ''}: {reason[:160]}", argv, src, data, kind,
                       reason)

    def _save(self, key, argv, src, data, kind, reason) -> None:
        if key in self.crashes:
            return
        suffix = Path(argv[-1]).suffix
        name = f"crash{len(self.crashes):03d}{suffix}"
        (self.out_dir / name).write_bytes(data)
        command = [*argv[:-1], name]
        for k, arg in enumerate(command[:-1]):  # the files the command reads besides the input (--values)
            if arg.startswith(str(self.work)) and os.path.isfile(arg) and command[k - 1] != "-o":
                kept = f"{Path(name).stem}-{Path(arg).name}"
                (self.out_dir / kept).write_bytes(Path(arg).read_bytes())
                command[k] = kept
        self.crashes[key] = (name, src.name, command, reason)
        self.log(f"CRASH {name} ({kind} from {src.name}): p105 {' '.join(command)}\n  {reason}")

    def summary(self) -> dict:
        return {"seed": self.seed, "inputs": self.inputs, "command_runs": self.runs,
                "inputs_by_kind": dict(self.kinds),
                "runs_by_command_and_status": {f"{c} -> {s}": n for (c, s), n in sorted(self.status.items())},
                "crashes": {k: {"file": v[0], "seed_file": v[1], "command": v[2], "reason": v[3]}
                            for k, v in self.crashes.items()},
                "slow": self.slow}


def fuzz(seed: int, seconds: float | None = None, rounds: int | None = None, out_dir: Path = OUT,
         log=print) -> Fuzzer:
    """Run the fuzzer for ``seconds`` or ``rounds`` inputs (whichever ends first)."""
    f = Fuzzer(seed, out_dir, log)
    end = None if seconds is None else time.monotonic() + seconds
    while (end is None or time.monotonic() < end) and (rounds is None or f.inputs < rounds):
        f.round(end)
    return f


def _reader(seconds: float) -> int:
    """The reader fuzzer in its own process (atheris ends the process it runs in)."""
    env = dict(os.environ, P105_FUZZ_SECONDS=str(max(1, int(seconds))))
    return subprocess.call([sys.executable, str(HERE / "fuzz_reader.py")], env=env, cwd=ROOT)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reader-share", type=float, default=0.0,
                    help="the share of P105_FUZZ_SECONDS given to tests/fuzz_reader.py first (make fuzz: 0.2)")
    args = ap.parse_args(argv)
    seconds = float(os.environ.get("P105_FUZZ_SECONDS", "120"))
    rounds = int(os.environ["P105_FUZZ_ROUNDS"]) if os.environ.get("P105_FUZZ_ROUNDS") else None
    seed = int(os.environ.get("P105_FUZZ_SEED") or int(time.time()))
    reader_failed = 0
    if args.reader_share > 0:
        reader_failed = _reader(seconds * args.reader_share)
        seconds *= 1 - args.reader_share
    seeds = Seeds()
    print(f"fuzz_commands: seed {seed}, {len(seeds.models)} model seeds, {len(seeds.tables)} DH tables, "
          f"{seconds:g} s" + (f", at most {rounds} inputs" if rounds else ""), flush=True)
    OUT.mkdir(parents=True, exist_ok=True)
    f = fuzz(seed, seconds, rounds, OUT, log=lambda s: print(s, flush=True))
    summary = f.summary()
    (OUT / f"summary-{seed}.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(f"fuzz_commands: {f.inputs} inputs ({', '.join(f'{n} {k}' for k, n in sorted(f.kinds.items()))}), "
          f"{f.runs} command runs, {len(f.crashes)} distinct crashes, {len(f.slow)} slow"
          + (f" (saved in {OUT})" if f.crashes or f.slow else "") + f"; summary-{seed}.json")
    return 1 if f.crashes or reader_failed else 0


if __name__ == "__main__":
    sys.exit(main())
