#!/usr/bin/env python3
"""Fuzz every command for internal errors: ``make fuzz-commands`` (``P105_FUZZ_SECONDS``).

Seeds: the corpus (``tests/data/corpus``), the examples and the small files of
``../shared/external`` (when present); DH tables for ``convert-dh-su``. Each round takes
a seed, mutates it (byte flips, truncation, a deleted or duplicated instance, swapped
references, a renamed entity type, a number replaced; for DH tables: a cell replaced, a
row deleted or duplicated, truncation) and runs every command on it in this process
(``make_golden.run_in_process``): parse, validate, graph, export --schema ap214|ap242,
solve (initial, --program, --set), interpolate, convert-dh-su. A command must end with
exit 0, 1 or 2 and no traceback; anything else is a crash: the input is saved under
``build/fuzz-commands/`` with the command line, and the run exits 1 at the end.

Random with a seed (``P105_FUZZ_SEED``, default the time), printed so a run can be
repeated. Not a pytest module (pytest does not collect ``fuzz_*.py``); the crashes it
found are regression tests in ``tests/cli/test_fuzz_regressions.py``.
"""

from __future__ import annotations

import os
import random
import re
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path[:0] = [str(ROOT), str(HERE)]

import make_golden  # noqa: E402  (after the path)

SECONDS = float(os.environ.get("P105_FUZZ_SECONDS", "120"))
SHARED = Path(os.environ.get("P105_SHARED", ROOT.parent / "shared"))
OUT = ROOT / "build" / "fuzz-commands"
MAX_SEED_BYTES = 200_000  # bigger external files make rounds slow without reaching new code

_INSTANCE = re.compile(r"^#\d+\s*=.*?;\s*$", re.M | re.S)
_REF = re.compile(r"#(\d+)")
_TYPE = re.compile(r"(?<=[=(])\s*([A-Z][A-Z0-9_]*)\s*(?=\()")
_NUMBER = re.compile(r"(?<![#\w])[-+]?\d+\.\d*(?:E[-+]?\d+)?")
_NAME = re.compile(r"'([^'\n]{1,40})'")
ODD_NUMBERS = ["0.", "-0.", "1.E300", "-1.E300", "1.E-300", "1E999", "NaN", "$", "*", "1", "''", "#0", ".T."]


def seeds() -> tuple[list[Path], list[Path]]:
    """(model files, DH tables)."""
    models = sorted((ROOT / "tests" / "data" / "corpus").glob("*.stp")) + sorted((ROOT / "examples").glob("*.stp"))
    ext = SHARED / "external"
    if ext.is_dir():
        models += sorted(p for p in ext.rglob("*") if p.suffix.lower() in (".stp", ".step", ".json")
                         and p.is_file() and p.stat().st_size <= MAX_SEED_BYTES
                         and "scene" not in p.name)
    tables = [ROOT / "examples" / "puma560_dh.csv", ROOT / "examples" / "panda_dh.json"]
    return models, tables


# ---------------------------------------------------------------- mutations
def _instances(text: str) -> list[re.Match]:
    return list(_INSTANCE.finditer(text))


def flip_bytes(rng, data: bytes) -> bytes:
    b = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        if b:
            b[rng.randrange(len(b))] = rng.choice(b"();,#'$*.=/\\ \n0123456789EAZ\xff")
    return bytes(b)


def truncate(rng, data: bytes) -> bytes:
    return data[:rng.randrange(len(data) + 1)]


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
        out.append((r.start(1), r.end(1), rng.choice(ids + ["0", "999999"])))
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
    names = sorted({t.group(1) for t in types}) + ["FOO", "REVOLUTE_PAIR", "KINEMATIC_PAIR", "MECHANISM"]
    m = rng.choice(types)
    return text[:m.start(1)] + rng.choice(names) + text[m.end(1):]


def replace_number(rng, text: str) -> str:
    nums = list(_NUMBER.finditer(text))
    if not nums:
        return text
    m = rng.choice(nums)
    return text[:m.start()] + rng.choice(ODD_NUMBERS + [m.group(0) + "0" * 3]) + text[m.end():]


TEXT_MUTATIONS = [delete_instance, duplicate_instance, swap_references, rename_type, replace_number]


def mutate_model(rng, data: bytes) -> bytes:
    for _ in range(rng.choice((1, 1, 1, 2, 3))):
        kind = rng.random()
        if kind < 0.15:
            data = flip_bytes(rng, data)
        elif kind < 0.22:
            data = truncate(rng, data)
        else:
            text = data.decode("utf-8", "replace")
            data = rng.choice(TEXT_MUTATIONS)(rng, text).encode("utf-8")
    return data


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
                      "revolute", "prismatic", m.group(0) * 2])
    return (text[:m.start()] + new + text[m.end():]).encode()


# ---------------------------------------------------------------- commands
def model_commands(rng, path: str, text: str) -> list[list[str]]:
    cmds = [["parse", path], ["validate", path], ["graph", path], ["graph", "--enrich", path],
            ["export", "--schema", "ap214", path], ["export", "--schema", "ap242", path],
            ["solve", "--no-timings", "--to", "jsonl", path],
            ["solve", "--program", "--count", "3", "--no-timings", "--to", "jsonl", path],
            ["interpolate", path],
            ["convert-dh-su", "--to", "dh", "--convention", "standard", path]]
    names = [m.group(1) for m in _NAME.finditer(text)]
    for name in rng.sample(names, min(2, len(names))):  # pair names among them, sometimes
        if "=" not in name and "," not in name:
            cmds.append(["solve", "--set", f"{name}=0.5", "--no-timings", "--to", "jsonl", path])
    return cmds


def table_commands(path: str) -> list[list[str]]:
    return [["convert-dh-su", "--convention", conv, *to, path]
            for conv in ("standard", "modified") for to in ((), ("--to", "json"))]


def is_crash(code: int, stderr: str) -> bool:
    return code not in (0, 1, 2) or "Traceback" in stderr or "internal error" in stderr


def main() -> int:
    seed = int(os.environ.get("P105_FUZZ_SEED", str(int(time.time()))))
    rng = random.Random(seed)
    models, tables = seeds()
    print(f"fuzz_commands: seed {seed}, {len(models)} model seeds, {len(tables)} DH tables, {SECONDS:g} s")
    OUT.mkdir(parents=True, exist_ok=True)
    work = OUT / "work"
    work.mkdir(exist_ok=True)
    crashes: dict[str, tuple] = {}
    inputs = runs = 0
    end = time.monotonic() + SECONDS
    while time.monotonic() < end:
        if rng.random() < 0.12:
            src = rng.choice(tables)
            data = mutate_table(rng, src.read_bytes())
            path = work / f"input{src.suffix}"
            path.write_bytes(data)
            cmds = table_commands(str(path))
        else:
            src = rng.choice(models)
            data = mutate_model(rng, src.read_bytes())
            path = work / f"input{src.suffix}"
            path.write_bytes(data)
            cmds = model_commands(rng, str(path), data.decode("utf-8", "replace"))
        inputs += 1
        for argv in cmds:
            if time.monotonic() >= end:
                break
            runs += 1
            try:
                code, _out, err = make_golden.run_in_process(argv)
            except BaseException as exc:  # noqa: BLE001 - what main() let through is a crash too
                code, err = -1, f"Traceback: {type(exc).__name__}: {exc}"
            if is_crash(code, err):
                lines = err.strip().splitlines() or [f"exit {code}"]
                last = next((ln for ln in lines if "internal error" in ln or "Traceback" in ln), lines[-1])
                key = f"{argv[0]} {argv[1] if len(argv) > 2 else ''}: {last[:160]}"
                if key not in crashes:
                    name = f"crash{len(crashes):03d}{path.suffix}"
                    (OUT / name).write_bytes(data)
                    crashes[key] = (name, src.name, [*argv[:-1], name])
                    print(f"CRASH {name} (from {src.name}): p105 {' '.join(argv[:-1])} {name}\n  {last}",
                          flush=True)
    print(f"fuzz_commands: {inputs} inputs, {runs} command runs, {len(crashes)} distinct crashes"
          + (f" (saved in {OUT})" if crashes else ""))
    return 1 if crashes else 0


if __name__ == "__main__":
    sys.exit(main())
