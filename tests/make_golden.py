"""Golden outputs of the p105 CLI: every command and format on the corpus and the examples.

Regenerate (after a change of output that is meant; review ``git diff`` of the data):

    python tests/make_golden.py                 # write tests/data/golden_cli/
    python tests/make_golden.py --check         # compare only, as the test does
    python tests/make_golden.py --verify-subprocess   # also run every case as a real
                                                      # `python -m p105cli` process: same bytes?

Each case is one ``p105`` command run in-process (``p105cli.cli.main``) from the
repository root with relative paths, stdin given or empty, stdout and stderr captured;
``tests/exchange/test_golden_cli.py`` runs the cases again and compares. A case's golden file
``tests/data/golden_cli/<id>.json`` (``.json.gz`` when large) holds its arguments,
stdin, exit status, stderr and stdout. ``stdin`` is ``null`` (empty), ``"@<id>"``: the
golden stdout of another case (a pipeline, each stage checked on its own), or ``"<path"``:
a file of the repository.

Paths into the shared data (``../shared``, or ``$P105_SHARED``) are written
``{shared}/...`` in the arguments and in the captured text, so the goldens do not
depend on where that directory is. Cases on shared files are left out when it is
absent. Commands whose output records time (``solve`` without ``--no-timings``,
``validate --timings``) are not cases.

A case that ends with exit 3 (internal error) is refused: that is a bug to fix, not an
output to keep.
"""

from __future__ import annotations

import argparse
import gzip
import io
import json
import os
import subprocess
import sys
import tempfile
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data" / "golden_cli"
INPUTS = DATA / "inputs"
SHARED = Path(os.environ.get("P105_SHARED", ROOT.parent / "shared"))
SHARED_TOKEN = "{shared}"

#: Golden files larger than this (bytes of JSON) are stored gzipped.
GZIP_OVER = 100_000

#: Python's default warning filters (a fresh ``python -m p105cli`` process): a test
#: runner's own filters must not change what a case prints.
_DEFAULT_FILTERS = [("default", DeprecationWarning, "__main__"), ("ignore", DeprecationWarning, None),
                    ("ignore", PendingDeprecationWarning, None), ("ignore", ImportWarning, None),
                    ("ignore", ResourceWarning, None)]

#: Environment variables that change what the CLI writes: ``-f auto`` is github under
#: GitHub Actions; rich output needs a terminal and no CI.
_ENV_OFF = ("GITHUB_ACTIONS",)


@dataclass(frozen=True)
class Case:
    id: str
    args: tuple[str, ...]
    stdin: str | None = None  # None, "@<case id>" (its golden stdout) or "<path" (a file of the repository)

    @property
    def needs_shared(self) -> bool:
        return any(SHARED_TOKEN in a for a in self.args)


# ---------------------------------------------------------------- the cases

CORPUS = "tests/data/corpus"
EXAMPLES = "examples"
CORPUS_STEMS = [f"{m}_{p}" for m in ("four_bar", "slider_crank", "ur5_arm", "gear_train", "rack_and_pinion",
                                     "cam_follower", "spherical_linkage") for p in ("ap214", "p105", "ap242")]
EXAMPLE_STEMS = ["four_bar_ap242", "slider_crank_p105_1996_ap214"]
REPORT_FORMATS = ["text", "json", "jsonl", "sarif", "junit", "github", "gitlab"]

#: The driven pair of each mechanism and a sweep of it (radians), for --set and --sweep.
DRIVES = {"four_bar": ("A", "0.5", "0:6.283185307179586:13"),
          "slider_crank": ("O", "0.5", "0:6.283185307179586:13"),
          "ur5_arm": ("J2", "-1.2", "-1.5:-0.5:5"),
          "gear_train": ("bearing 1", "0.5", "0:3.141592653589793:7"),
          "rack_and_pinion": ("bearing", "0.5", "-1:1:5"),
          "cam_follower": ("shaft", "0.5", "0:6.283185307179586:9"),
          "spherical_linkage": ("input", "0.5", "0:6.283185307179586:13")}


def _file_cases(tag: str, path: str, mechanism: str | None) -> list[Case]:
    """Every command and format that applies to one mechanism file."""
    c = []

    def add(name, *args, stdin=None):
        c.append(Case(f"{name}--{tag}", tuple(args), stdin))

    add("parse", "parse", path)
    add("parse-stream", "parse", "--stream", path)
    add("export-p21", "export", "--to", "p21", path)
    add("export-json", "export", "--to", "json", path)
    for schema in ("ap214", "p105", "ap242"):
        add(f"export-schema-{schema}", "export", "--schema", schema, path)
    add("export-schema-ap242-occt", "export", "--schema", "ap242", "--occt-compat", path)
    add("export-schema-ap242-json", "export", "--schema", "ap242", "--to", "json", path)
    for fmt in ("text", "json"):
        add(f"validate-{fmt}", "validate", "-f", fmt, path)
    if tag.endswith("_p105"):
        add("validate-schema-p105", "validate", "--schema", "p105", "-f", "text", path)
        add("graph-schema-p105", "graph", "--schema", "p105", path)
    add("graph", "graph", path)
    for fmt in ("dot", "graphml", "mermaid"):
        add(f"graph-{fmt}", "graph", "--to", fmt, path)
    add("graph-enrich", "graph", "--enrich", path)
    add("graph-enrich-json", "graph", "--enrich", "--to", "json", path)
    add("interpolate", "interpolate", path)
    add("interpolate-configurations-csv", "interpolate", "--what", "configurations", "--count", "5", "--to", "csv",
        path)
    add("interpolate-paths-csv", "interpolate", "--what", "paths", "--count", "5", "--to", "csv", path)
    add("interpolate-step-rotations", "interpolate", "--step", "0.25", "--quaternion", "wxyz", "--ypr", path)
    add("solve-program-jsonl", "solve", "--program", "--no-timings", "--to", "jsonl", path)
    add("solve-program-count-csv", "solve", "--program", "--count", "5", "--no-timings", "--to", "csv", path)
    if mechanism is not None:
        pair, value, sweep = DRIVES[mechanism]
        add("solve-set-jsonl", "solve", "--set", f"{pair}={value}", "--no-timings", "--to", "jsonl", path)
        add("solve-sweep-csv", "solve", "--sweep", f"{pair}={sweep}", "--no-timings", "--to", "csv", path)
    return c


def _example_cases() -> list[Case]:
    """The example inputs of the other commands (Makefile demo, examples/README.md)."""
    fb, sc = f"{EXAMPLES}/four_bar_ap242.stp", f"{EXAMPLES}/slider_crank_p105_1996_ap214.stp"
    puma, panda = f"{EXAMPLES}/puma560_dh.csv", f"{EXAMPLES}/panda_dh.json"
    c = []

    def add(name, *args, stdin=None):
        c.append(Case(name, tuple(args), stdin))

    # validate: every report format, options, several files, --pass, the rule list
    for tag, path in (("ex-four_bar_ap242", fb), ("ex-slider_crank_p105_1996_ap214", sc),
                      ("ur5_arm_p105", f"{CORPUS}/ur5_arm_p105.stp")):
        for fmt in REPORT_FORMATS:
            if fmt not in ("text", "json"):  # those two are file cases
                add(f"validate-{fmt}--{tag}", "validate", "-f", fmt, path)
    for fmt in ("text", "sarif", "github"):
        add(f"validate-{fmt}--corpus-several", "validate", "-f", fmt, f"{CORPUS}/four_bar_ap214.stp",
            f"{CORPUS}/ur5_arm_p105.stp", f"{CORPUS}/cam_follower_ap242.stp")
    add("validate-select--ur5_arm_p105", "validate", "--select", "SCH-*", f"{CORPUS}/ur5_arm_p105.stp")
    add("validate-ignore--ur5_arm_p105", "validate", "--ignore", "SCH-*", "-f", "json",
        f"{CORPUS}/ur5_arm_p105.stp")
    add("validate-exit-zero--ur5_arm_p105", "validate", "--exit-zero", f"{CORPUS}/ur5_arm_p105.stp")
    add("validate-fail-on-note--ur5_arm_p105", "validate", "--fail-on", "note", "-f", "jsonl",
        f"{CORPUS}/ur5_arm_p105.stp")
    add("validate-pass--ex-four_bar_ap242", "validate", "--pass", fb)
    add("validate-pass-fails--ur5_arm_p105", "validate", "--pass", f"{CORPUS}/ur5_arm_p105.stp")
    add("validate-stdin--ex-four_bar_ap242", "validate", "-f", "json", "-", stdin="@parse--ex-four_bar_ap242")
    for schema in ("ap214", "ap242", "p105"):
        add(f"validate-list-rules-{schema}", "validate", "--list-rules", "--schema", schema)

    # pipelines of the demo: JSON model back to Part 21, stream to Part 21, 1996 -> AP242
    add("export-p21-from-json--ex-four_bar_ap242", "export", "--to", "p21", stdin="@parse--ex-four_bar_ap242")
    add("export-p21-from-stream--ex-slider_crank", "export", "--to", "p21",
        stdin="@parse-stream--ex-slider_crank_p105_1996_ap214")
    add("export-quiet-schema-ap242--ex-slider_crank", "-q", "export", "--schema", "ap242", sc)
    add("validate-stdin-pass--ex-slider_crank-ap242", "validate", "--pass", "-f", "text",
        stdin="@export-quiet-schema-ap242--ex-slider_crank")
    add("graph-stdin--ex-four_bar_ap242-json", "graph", stdin="@parse--ex-four_bar_ap242")
    add("validate-pass-enriched--ex-four_bar_ap242", "validate", "--pass", "-f", "text",
        stdin="@graph-enrich--ex-four_bar_ap242")

    # convert-dh-su: both tables, every output and profile
    for schema in ("ap242", "p105", "ap214"):
        add(f"dh-puma-{schema}", "convert-dh-su", "--convention", "standard", "--schema", schema, puma)
        add(f"dh-panda-{schema}", "convert-dh-su", "--schema", schema, panda)
    add("dh-puma-json", "convert-dh-su", "--convention", "standard", "--to", "json", puma)
    add("dh-puma-modified", "convert-dh-su", "--convention", "modified", puma)
    add("dh-puma-name", "convert-dh-su", "--convention", "standard", "--name", "puma560", puma)
    add("dh-panda-json", "convert-dh-su", "--to", "json", panda)
    add("dh-panda-deg", "convert-dh-su", "--deg", panda)
    add("dh-puma-back-dh", "convert-dh-su", "--to", "dh", stdin="@dh-puma-ap242")
    add("dh-puma-back-dh-json", "convert-dh-su", "--to", "dh-json", stdin="@dh-puma-ap242")
    add("dh-puma-p105-back-dh", "convert-dh-su", "--to", "dh", stdin="@dh-puma-p105")
    add("dh-panda-back-dh-json", "convert-dh-su", "--to", "dh-json", stdin="@dh-panda-ap242")
    add("dh-panda-json-back-dh", "convert-dh-su", "--to", "dh", stdin="@dh-panda-json")
    add("validate-dh-puma", "validate", "-f", "text", "-", stdin="@dh-puma-ap242")
    add("graph-dh-panda", "graph", stdin="@dh-panda-ap242")

    # solve: values, set, sweep, units, branch, model output, inverse analysis, cables
    crank = f"{EXAMPLES}/four_bar_crank.csv"
    for to in ("jsonl", "csv", "model"):
        add(f"solve-values-{to}--ex-four_bar_ap242", "solve", fb, "--values", crank, "--angle-unit", "deg",
            "--no-timings", "--to", to)
    add("solve-values-mm--ex-slider_crank", "solve", sc, "--sweep", "O=0:360:9", "--angle-unit", "deg",
        "--length-unit", "mm", "--no-timings", "--to", "csv")
    add("solve-sweep-model--ex-slider_crank", "solve", sc, "--sweep", "O=0:1.5:4", "--no-timings")
    add("solve-values-stdin--ex-four_bar_ap242", "solve", fb, "--values", "-", "--angle-unit", "deg", "--no-timings",
        "--to", "jsonl", stdin=f"<{crank}")
    add("fail-solve-values-from-solve-output--ex-four_bar_ap242", "solve", fb, "--values", "-", "--no-timings",
        "--to", "jsonl", stdin="@solve-values-jsonl--ex-four_bar_ap242")
    add("parse-stdin--ex-four_bar_ap242", "parse", stdin=f"<{fb}")
    for branch, name in (("initial", "initial"), ("+", "plus"), ("-", "minus")):
        add(f"solve-branch-{name}--ex-four_bar_ap242", "solve", fb, "--sweep", "A=0:6.283185307179586:25",
            "--branch", branch, "--no-timings", "--to", "jsonl")
    add("solve-program-model--ex-four_bar_ap242", "solve", "--program", "--no-timings", fb)
    add("solve-program-count-model--ex-slider_crank", "solve", "--program", "--count", "5", "--no-timings", sc)
    add("solve-program-step--ex-four_bar_ap242", "solve", "--program", "--step", "0.1", "--no-timings", "--to",
        "jsonl", fb)
    add("solve-resulting-path--ex-four_bar_ap242", "solve", fb, "--sweep", "A=0:1.5:4",
        "--resulting-path", "coupler", "--no-timings")
    tool_path = f"{EXAMPLES}/puma560_tool_path.jsonl"
    for to in ("csv", "jsonl", "model"):
        add(f"solve-path-{to}--dh-puma", "solve", "-", "--path", tool_path, "--target-link", "link6",
            "--no-timings", "--to", to, stdin="@dh-puma-ap242")
    scene, keys = f"{EXAMPLES}/cable_scene.json", f"{EXAMPLES}/cable_keypoints.jsonl"
    add("solve-scene", "solve", "--scene", scene, "--keypoints", keys, "--no-timings")
    add("solve-scene-sweep--ex-four_bar_ap242", "solve", fb, "--sweep", "A=0:1.5:4", "--scene", scene,
        "--no-timings", "--to", "jsonl")

    # interpolate on solve's model output (the demo) and on the resulting path
    add("interpolate-configurations-csv--solved-four_bar", "interpolate", "--what", "configurations", "--count",
        "73", "--to", "csv", stdin="@solve-values-model--ex-four_bar_ap242")
    add("interpolate-paths--solved-four_bar", "interpolate", "--what", "paths", "--count", "7",
        stdin="@solve-resulting-path--ex-four_bar_ap242")
    add("interpolate-paths-csv--solved-puma", "interpolate", "--what", "paths", "--step", "0.1", "--to", "csv",
        stdin="@solve-path-model--dh-puma")
    add("interpolate-t--ex-four_bar_ap242", "interpolate", "--t", "0.25", "--t", "0.75", "--no-nodes",
        "--quaternion", "xyzw", fb)
    add("validate-solved--ex-four_bar_ap242", "validate", "-f", "text", "-",
        stdin="@solve-values-model--ex-four_bar_ap242")

    # options not in the file cases: names, streams, targets, tolerances, JSON models in and out
    add("interpolate-path-name--ex-four_bar_ap242", "interpolate", "--path", "coupler point P path", "--count", "3",
        fb)
    add("interpolate-sequence-name--ex-four_bar_ap242", "interpolate", "--sequence", "four_bar configurations",
        "--step", "0.2", "--to", "csv", "--what", "configurations", fb)
    add("interpolate-json-model--ex-four_bar_ap242", "interpolate", "--count", "4", stdin="@parse--ex-four_bar_ap242")
    add("export-stream--ex-four_bar_ap242", "export", "--to", "json", "--stream", fb)
    add("export-schema-stream--ex-slider_crank", "export", "--schema", "ap242", "--to", "json", "--stream", sc)
    add("graph-mechanism--ex-four_bar_ap242", "graph", "--mechanism", "four_bar", "--tol", "1e-6", fb)
    add("solve-json-model--ex-four_bar_ap242", "solve", "-", "--sweep", "A=0:1.5:4", "--no-timings",
        stdin="@parse--ex-four_bar_ap242")
    add("solve-target-frame--ex-four_bar_ap242", "solve", "--program", "--target-frame", "point P", "--mechanism",
        "four_bar", "--tol", "1e-9", "--max-iter", "50", "--no-timings", "--to", "jsonl", fb)
    for stem in ("ur5_arm_p105", "gear_train_ap214", "cam_follower_ap242", "rack_and_pinion_p105"):
        add(f"solve-program-model--{stem}", "solve", "--program", "--no-timings", f"{CORPUS}/{stem}.stp")
    add("fail-scene-csv", "solve", "--scene", scene, "--keypoints", keys, "--no-timings", "--to", "csv")
    add("fail-mechanism-unknown--ex-four_bar_ap242", "graph", "--mechanism", "nine_bar", fb)
    return c


def _failure_cases() -> list[Case]:
    """Exit statuses and messages of bad input and bad usage."""
    c = []

    def add(name, *args, stdin=None):
        c.append(Case(f"fail-{name}", tuple(args), stdin))

    inp = "tests/data/golden_cli/inputs"
    for cmd in (("parse",), ("export", "--schema", "ap242"), ("validate", "-f", "text"), ("graph",),
                ("solve", "--no-timings", "--to", "jsonl"), ("interpolate",)):
        tag = "-".join(cmd[:1])
        add(f"unknown-schema-{tag}", *cmd, f"{inp}/unknown_schema.stp")
        add(f"malformed-{tag}", *cmd, f"{inp}/malformed.stp")
        add(f"missing-file-{tag}", *cmd, "no/such/file.stp")
    add("empty-stdin-parse", "parse")
    add("not-step-parse", "parse", "examples/README.md")
    add("bad-option", "parse", "--no-such-option", "examples/four_bar_ap242.stp")
    add("bad-choice", "export", "--to", "xml", "examples/four_bar_ap242.stp")
    add("no-command", "frobnicate")
    add("solve-unknown-pair", "solve", "examples/four_bar_ap242.stp", "--set", "Z=1", "--to", "jsonl",
        "--no-timings")
    add("solve-bad-sweep", "solve", "examples/four_bar_ap242.stp", "--sweep", "A=0:1", "--no-timings")
    add("solve-no-target-link", "solve", "examples/four_bar_ap242.stp", "--path",
        "examples/puma560_tool_path.jsonl", "--no-timings")
    add("dh-no-convention", "convert-dh-su", "examples/puma560_dh.csv")
    add("dh-to-dh-from-table", "convert-dh-su", "--convention", "standard", "--to", "dh", "examples/puma560_dh.csv")
    add("interpolate-csv-needs-what", "interpolate", "--to", "csv", "examples/four_bar_ap242.stp")
    add("graph-enrich-dot", "graph", "--enrich", "--to", "dot", "examples/four_bar_ap242.stp")
    add("export-occt-without-ap242", "export", "--occt-compat", "examples/four_bar_ap242.stp")
    add("validate-output-is-input", "validate", "-o", "examples/four_bar_ap242.stp", "examples/four_bar_ap242.stp")
    return c


#: Files of the shared external collection (README there) and the commands tried on them;
#: only results other than exit 3 are kept (see the module docstring).
EXTERNAL = {
    "defects/four_bar_low_order_value.stp": "all",
    "defects/four_bar_low_order_pair.stp": "all",
    "defects/four_bar_plus_bad_real.stp": "all",
    "defects/occt_api_four_bar_mechctx411.stp": "all",
    "defects/b3d_spherical_as_low_order.stp": "read",
    "defects/raw8bit.stp": "read",
    "defects/utf8.stp": "read",
    "crashes/D06.stp": "graph",
    "crashes/D12.json": "read",
    "crashes/D13.stp": "read",
    "crashes/D15_sph.stp": "all",
    "crashes/D21.stp": "read",
    "occt_api/": "all",
}

_EXTERNAL_COMMANDS = {
    "read": [("parse", ("parse",)), ("parse-stream", ("parse", "--stream"))],
    "graph": [("graph", ("graph",))],
    "all": [("parse", ("parse",)), ("export-schema-ap214", ("export", "--schema", "ap214")),
            ("export-schema-ap242", ("export", "--schema", "ap242")), ("validate-json", ("validate", "-f", "json")),
            ("graph", ("graph",)), ("interpolate", ("interpolate",)),
            ("solve-jsonl", ("solve", "--no-timings", "--to", "jsonl"))],
}


def _external_cases() -> list[Case]:
    c = []
    for rel, kind in EXTERNAL.items():
        paths = [rel]
        if rel.endswith("/"):
            folder = SHARED / "external" / rel
            paths = sorted(f"{rel}{p.name}" for p in folder.glob("*.stp")) if folder.is_dir() else []
        for r in paths:
            stem = r.rsplit(".", 1)[0].replace("/", "-")
            for name, cmd in _EXTERNAL_COMMANDS[kind]:
                c.append(Case(f"ext-{name}--{stem}", (*cmd, f"{SHARED_TOKEN}/external/{r}")))
    return c


#: Cases that end with an internal error (exit 3) today: bugs, left out until fixed.
INTERNAL_ERRORS: set[str] = set()


def cases() -> list[Case]:
    """Every case, in run order (a case fed by another's stdout comes after it)."""
    out = []
    for stem in CORPUS_STEMS:
        out += _file_cases(stem, f"{CORPUS}/{stem}.stp", stem.rsplit("_", 1)[0])
    mech = {"four_bar_ap242": "four_bar", "slider_crank_p105_1996_ap214": "slider_crank"}
    for stem in EXAMPLE_STEMS:
        out += _file_cases(f"ex-{stem}", f"{EXAMPLES}/{stem}.stp", mech[stem])
    out += _example_cases()
    out += _failure_cases()
    out += _external_cases()
    out = [c for c in out if c.id not in INTERNAL_ERRORS]
    ids = [c.id for c in out]
    dup = {i for i in ids if ids.count(i) > 1}
    if dup:
        raise AssertionError(f"duplicate case ids: {sorted(dup)}")
    return out


# ---------------------------------------------------------------- running a case

def shared_prefix() -> str:
    """How ``{shared}`` is spelled on the command line: relative to the repository root
    when it can be (as a user would type it), else absolute."""
    try:
        return os.path.relpath(SHARED, ROOT)
    except ValueError:
        return str(SHARED)


def command_line(case: Case) -> list[str]:
    prefix = shared_prefix()
    return [a.replace(SHARED_TOKEN, prefix) for a in case.args]


def normalise(text: str) -> str:
    """Captured text with the spelling of the shared directory replaced by ``{shared}``."""
    return text.replace(shared_prefix(), SHARED_TOKEN)


def run_in_process(argv: list[str], stdin: bytes = b"") -> tuple[int, bytes, str]:
    """``p105 ARGV`` through :func:`p105cli.cli.main` in this process, from the repository
    root: (exit status, stdout bytes, stderr text). stdout and stderr are real files (not
    terminals), stdin holds ``stdin``; warnings print as in a fresh process."""
    from p105cli.cli import main

    saved_cwd = os.getcwd()
    saved_streams = sys.stdin, sys.stdout, sys.stderr
    saved_env = {k: os.environ.pop(k) for k in _ENV_OFF if k in os.environ}
    out_file, err_file = tempfile.TemporaryFile(), tempfile.TemporaryFile()
    out = io.TextIOWrapper(out_file, encoding="utf-8", newline="\n")
    err = io.TextIOWrapper(err_file, encoding="utf-8", newline="\n")
    inp = io.TextIOWrapper(io.BytesIO(stdin), encoding="utf-8")
    try:
        os.chdir(ROOT)
        sys.stdin, sys.stdout, sys.stderr = inp, out, err
        with warnings.catch_warnings():
            warnings.resetwarnings()
            for action, category, module in reversed(_DEFAULT_FILTERS):
                if module is None:
                    warnings.filterwarnings(action, category=category)
                else:
                    warnings.filterwarnings(action, category=category, module=module)
            warnings.showwarning = _show_warning
            code = main(list(argv))
        for stream in (out, err):
            stream.flush()
    finally:
        sys.stdin, sys.stdout, sys.stderr = saved_streams
        os.chdir(saved_cwd)
        os.environ.update(saved_env)
        for stream in (out, err, inp):
            try:
                stream.detach()
            except ValueError:  # already detached by the command
                pass
    out_file.seek(0)
    err_file.seek(0)
    stdout, stderr = out_file.read(), err_file.read().decode("utf-8")
    out_file.close()
    err_file.close()
    return int(code), stdout, stderr


def _show_warning(message, category, filename, lineno, file=None, line=None):
    sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))


def run_subprocess(argv: list[str], stdin: bytes = b"") -> tuple[int, bytes, str]:
    """The same as :func:`run_in_process`, as a real ``python -m p105cli`` process."""
    env = {k: v for k, v in os.environ.items() if k not in _ENV_OFF}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    r = subprocess.run([sys.executable, "-m", "p105cli", *argv], input=stdin, capture_output=True, cwd=ROOT,
                       env=env, timeout=600)
    return r.returncode, r.stdout, r.stderr.decode("utf-8")


def run_case(case: Case, golden_stdout_of, runner=run_in_process) -> dict:
    """Run ``case``; ``golden_stdout_of(id)`` gives a stdin named ``@id``."""
    stdin = b""
    if case.stdin is not None and case.stdin.startswith("@"):
        stdin = golden_stdout_of(case.stdin[1:]).encode("utf-8")
    elif case.stdin is not None:
        stdin = (ROOT / case.stdin[1:]).read_bytes()
    code, stdout, stderr = runner(command_line(case), stdin)
    return {"id": case.id, "args": list(case.args), "stdin": case.stdin, "exit": code,
            "stderr": normalise(stderr), "stdout": normalise(stdout.decode("utf-8"))}


# ---------------------------------------------------------------- golden files

def golden_path(case_id: str) -> Path | None:
    for suffix in (".json", ".json.gz"):
        p = DATA / f"{case_id}{suffix}"
        if p.is_file():
            return p
    return None


def load(case_id: str) -> dict:
    p = golden_path(case_id)
    if p is None:
        raise FileNotFoundError(f"no golden file for case {case_id!r}: run python tests/make_golden.py")
    raw = p.read_bytes()
    if p.suffix == ".gz":
        raw = gzip.decompress(raw)
    return json.loads(raw.decode("utf-8"))


def dump(result: dict) -> None:
    text = json.dumps(result, indent=1, ensure_ascii=False) + "\n"
    raw = text.encode("utf-8")
    for suffix in (".json", ".json.gz"):
        (DATA / f"{result['id']}{suffix}").unlink(missing_ok=True)
    if len(raw) > GZIP_OVER:
        buf = io.BytesIO()
        with gzip.GzipFile(filename="", mode="wb", fileobj=buf, mtime=0, compresslevel=9) as gz:
            gz.write(raw)
        (DATA / f"{result['id']}.json.gz").write_bytes(buf.getvalue())
    else:
        (DATA / f"{result['id']}.json").write_bytes(raw)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python tests/make_golden.py", description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="compare with the golden files; write nothing")
    ap.add_argument("--verify-subprocess", action="store_true",
                    help="also run every case as a real process and require the same bytes")
    ap.add_argument("--only", metavar="SUBSTRING", help="only the cases whose id contains SUBSTRING")
    ap.add_argument("--times", type=int, default=0, metavar="N",
                    help="print the N slowest cases and the CPU time per kind of case (the id before '--')")
    args = ap.parse_args(argv)

    all_cases = cases()
    if not SHARED.is_dir():
        print(f"make_golden: {SHARED} is absent: cases on shared files left out", file=sys.stderr)
        all_cases = [c for c in all_cases if not c.needs_shared]
    todo = [c for c in all_cases if args.only is None or args.only in c.id]
    results: dict[str, dict] = {}

    def stdout_of(case_id):
        return results[case_id]["stdout"] if case_id in results else load(case_id)["stdout"]

    refused, differ, mismatched, slow = [], [], [], []
    times: dict[str, float] = {}
    DATA.mkdir(parents=True, exist_ok=True)
    t_all = time.process_time()
    for case in todo:
        t0 = time.process_time()  # CPU time: the machine may be shared
        r = run_case(case, stdout_of)
        dt = time.process_time() - t0
        times[case.id] = dt
        if dt > 1.0:
            slow.append((case.id, dt))
        if r["exit"] == 3:
            refused.append(case.id)
            print(f"REFUSED (exit 3) {case.id}: {' '.join(case.args)}\n  {r['stderr'].strip()[:300]}")
            continue
        results[case.id] = r
        if args.verify_subprocess:
            s = run_case(case, stdout_of, runner=run_subprocess)
            if s != r:
                mismatched.append(case.id)
                print(f"IN-PROCESS != SUBPROCESS {case.id}")
        if args.check:
            try:
                if load(case.id) != r:
                    differ.append(case.id)
            except FileNotFoundError:
                differ.append(case.id)
        else:
            dump(r)
    if not args.check and args.only is None:
        keep = {c.id for c in all_cases if c.id in results}
        for p in DATA.glob("*.json*"):
            if p.name.split(".json")[0] not in keep:
                p.unlink()
    print(f"{len(results)} cases in {time.process_time() - t_all:.1f} s CPU; refused (exit 3): {len(refused)}; "
          f"slow (> 1 s): {', '.join(f'{i} {t:.1f} s' for i, t in slow) or 'none'}")
    if args.times:
        for i, t in sorted(times.items(), key=lambda x: -x[1])[:args.times]:
            print(f"{t:7.3f} s  {i}")
        kinds: dict[str, float] = {}
        for i, t in times.items():
            kinds[i.split("--")[0]] = kinds.get(i.split("--")[0], 0.0) + t
        for k, t in sorted(kinds.items(), key=lambda x: -x[1])[:args.times]:
            print(f"{t:7.3f} s  {k} (all)")
    if args.check:
        print(f"differ from the golden files: {differ or 'none'}")
    if args.verify_subprocess:
        print(f"in-process != subprocess: {mismatched or 'none'}")
    return 1 if differ or mismatched else 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(main())
