"""export --schema never writes, with exit 0, a file that validate rejects (issue 11).

Every corpus file, every example and every file of ../shared/external/ that holds a mechanism
is converted to every profile through the CLI (in process) and the output validated in process:

* exit 0: the output passes ``validate`` (no error);
* exit 1: stderr says, naming the file, what cannot be repaired, and nothing is written;
* exit 2: the input is refused with a reason naming the file (malformed input, an unsupported
  feature); nothing is written.

Independent truth: the validator (the schema's long form and its rules), which knows nothing
of the converter. Cases slower than a few seconds are ``slow``.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from conftest import EXAMPLES, ROOT, cli_in_process
from p105cli.rules.validate import validate_document
from p105cli.step import read_step

CORPUS = ROOT / "tests" / "data" / "corpus"
EXTERNAL = Path(os.environ.get("P105_SHARED", ROOT.parent / "shared")) / "external"
PROFILES = ("ap214", "ap242", "p105")

#: Conversions whose source or output takes more than a few seconds to read or validate.
SLOW = {"b3d_four_bar_heavy10"}

def _holds_mechanism(path: Path) -> bool:
    text = path.read_bytes()
    return b"MECHANISM(" in text or b"MECHANISM_REPRESENTATION(" in text


def _sources() -> list:
    files = sorted(CORPUS.glob("*.stp")) + sorted(EXAMPLES.glob("*.stp"))
    if EXTERNAL.is_dir():
        # crashes/ holds the reproducers of internal errors: their regression tests are the
        # robustness branch's (issue 11, item 5)
        files += sorted(p for p in EXTERNAL.rglob("*.stp")
                        if p.parent.name != "crashes" and _holds_mechanism(p))
    return files


def _label(path: Path) -> str:
    try:
        return str(path.relative_to(ROOT))
    except ValueError:
        return f"external/{path.relative_to(EXTERNAL)}"


def _cases() -> list:
    out = []
    for path in _sources():
        for profile in PROFILES:
            marks = []
            if path.stem in SLOW:
                marks.append(pytest.mark.slow)
            out.append(pytest.param(path, profile, id=f"{_label(path)}-{profile}", marks=marks))
    if not EXTERNAL.is_dir():
        out.append(pytest.param(None, None, id="external", marks=pytest.mark.skip(
            reason=f"{EXTERNAL} is absent (the shared external files sit beside the checkout)")))
    return out


@pytest.mark.parametrize("path, profile", _cases())
def test_export_schema_writes_what_validate_passes_or_says_why_not(path, profile, tmp_path):
    out = tmp_path / f"out_{profile}.stp"
    proc = cli_in_process("export", "--schema", profile, str(path), "-o", str(out))
    err = proc.stderr.decode()
    assert proc.returncode in (0, 1, 2), err  # 3 would be a bug
    if proc.returncode != 0:
        assert not out.exists(), "a failed export left its output"
        errors = [line for line in err.splitlines() if line.startswith("p105: error: ")]
        assert errors and str(path) in errors[0], err  # a stated reason, naming the file
        return
    doc = read_step(out.read_text(), str(out))
    started = time.perf_counter()
    result = validate_document(doc, doc.source, "p105" if profile == "p105" else None)
    seconds = time.perf_counter() - started
    bad = [f"{d.rule} #{d.entity}: {d.message[:200]}" for d in result.diagnostics if d.severity == "error"]
    assert not bad, f"export --schema {profile} exited 0 but validate rejects the output:\n" + "\n".join(bad)
    assert result.readable
    if path.stem not in SLOW:
        assert seconds < 30.0  # generous: a regression of the gate, not of the converter
