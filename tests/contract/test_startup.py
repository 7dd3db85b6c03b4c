"""Start-up: what a command imports in a fresh interpreter. Every command pays its imports
on each run (a CI gate runs validate once per file), so nothing is imported that the command
does not use; only a process shows it."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from conftest import EXAMPLES, ROOT

FOUR_BAR = EXAMPLES / "four_bar_ap242.stp"

# Modules with a real import cost that the command at hand never uses.
NEVER = ("scipy", "rich", "matplotlib")
NO_SCHEMA = ("p105cli.schema", "numpy")
NOT_AFTER_CACHE = ("p105cli.schema.parser", "p105cli.schema.tokenizer")  # a cached schema is not parsed
WRITES_NOTHING = ("tempfile",)  # only -o and the schema cache write files


def _modules_after(tmp_path, *args) -> set:
    out = tmp_path / "modules.json"
    code = ("import json, sys\nfrom p105cli.cli import main\ncode = main(sys.argv[2:])\n"
            "open(sys.argv[1], 'w').write(json.dumps(sorted(sys.modules)))\nsys.exit(code)\n")
    env = {k: v for k, v in os.environ.items() if k != "CI"}
    r = subprocess.run([sys.executable, "-c", code, str(out), *map(str, args)], cwd=ROOT, env=env,
                       capture_output=True, timeout=120)
    assert r.returncode == 0, r.stderr.decode()
    return set(json.loads(out.read_text()))


def _loaded(modules: set, names) -> list:
    return sorted(m for m in modules for n in names if m == n or m.startswith(n + "."))


@pytest.mark.parametrize("args", [("--version",), ("--help",), ("validate", "--help")])
def test_version_and_help_import_no_command_work(tmp_path, args):
    modules = _modules_after(tmp_path, *args)
    assert _loaded(modules, (*NEVER, *NO_SCHEMA, *WRITES_NOTHING, "p105cli.step")) == []


def test_parse_reads_no_schema(tmp_path):
    modules = _modules_after(tmp_path, "parse", FOUR_BAR)
    assert "p105cli.step.reader" in modules
    assert _loaded(modules, (*NEVER, *NO_SCHEMA, *WRITES_NOTHING)) == []


@pytest.mark.parametrize("command", ["validate", "graph"])
def test_schema_commands_load_the_cached_schema_without_the_parser(tmp_path, command):
    _modules_after(tmp_path, command, FOUR_BAR)  # the schema cache is filled if it was empty
    modules = _modules_after(tmp_path, command, FOUR_BAR)
    assert "p105cli.schema.express" in modules
    assert _loaded(modules, (*NEVER, *NOT_AFTER_CACHE, *WRITES_NOTHING)) == []
