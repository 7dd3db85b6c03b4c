"""The -o contract: OUT is replaced only by a complete, successful run (``--keep-partial``
keeps what a failed one wrote); a device that refuses the data is exit 2 naming the
path; a p105 killed while writing leaves no temporary file behind once the next one
writes the same OUT."""

from __future__ import annotations

import errno
import os
import resource
import signal
import subprocess
import sys
import time

import pytest

from conftest import EXAMPLES, ROOT, run_cli
from p105cli.cli.contract import ExitCode
from p105cli.fileio import TEMP_MARK, PendingFile, atomic_file, remove_stale_temporaries

from .test_cli_contract import COMMANDS, EXAMPLE, INPUT, JOB

# The four-bar's rocker (pair C) driven to 2.5 rad: no assembly exists (exit 1, a finding).
UNASSEMBLABLE = ["solve", EXAMPLE, "--set", "C=2.5", "--to", "jsonl", "--no-timings"]


def _names(directory) -> list[str]:
    return sorted(p.name for p in directory.iterdir())


def test_a_failed_run_leaves_out_as_it_was(p105, tmp_path):
    out = tmp_path / "out.jsonl"
    r = p105(*UNASSEMBLABLE, "-o", out)
    assert r.returncode == ExitCode.FINDINGS and "not_assemblable" in r.stderr.decode()
    assert _names(tmp_path) == []  # no new file: make runs the rule again
    out.write_text("previous content")
    assert p105(*UNASSEMBLABLE, "-o", out).returncode == ExitCode.FINDINGS
    assert out.read_text() == "previous content" and _names(tmp_path) == ["out.jsonl"]


def test_keep_partial_writes_what_a_failed_run_computed(p105, tmp_path):
    out = tmp_path / "out.jsonl"
    out.write_text("previous content")
    r = p105(*UNASSEMBLABLE, "--keep-partial", "-o", out)
    assert r.returncode == ExitCode.FINDINGS and r.stdout == b""
    assert out.read_bytes() == p105(*UNASSEMBLABLE).stdout
    assert b'"status":{"not_assemblable":1}' in out.read_bytes()
    assert _names(tmp_path) == ["out.jsonl"]


def test_keep_partial_changes_nothing_on_success(p105, tmp_path):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    assert p105("parse", EXAMPLE, "-o", a).returncode == 0
    assert p105("parse", "--keep-partial", EXAMPLE, "-o", b).returncode == 0
    assert a.read_bytes() == b.read_bytes()


@pytest.mark.parametrize("name", sorted(set(COMMANDS) - {"validate"}))
def test_keep_partial_without_o_is_a_usage_error(p105, name):
    r = p105(*JOB[name], "--keep-partial", INPUT.get(name, EXAMPLE))
    assert r.returncode == ExitCode.USAGE and r.stdout == b""
    assert "--keep-partial applies to -o OUT" in r.stderr.decode()


def test_validate_writes_its_report_with_findings(p105, tmp_path):
    # The report is the verdict: a SARIF upload after a failing gate needs it.
    bad = tmp_path / "bad.stp"
    bad.write_text(EXAMPLE.read_text().replace("#183=REVOLUTE_PAIR('B',", "#183=REVOLUTE_PAIR(1,", 1))
    report = tmp_path / "report.txt"
    r = p105("validate", bad, "-o", report)
    assert r.returncode == ExitCode.FINDINGS
    assert "error[" in report.read_text()
    assert "--keep-partial" not in p105("validate", "--help").stdout.decode()


def test_an_input_error_half_way_keeps_the_partial_output_only_when_asked(p105, tmp_path, monkeypatch):
    # The records are written, then the run fails (as a scene found invalid after the motion).
    from p105cli.cli.contract import InputError
    from p105cli.formats import solve_records

    def fail(*args, **kwargs):
        raise InputError("stopped before the summary")

    monkeypatch.setattr(solve_records.Tally, "write_summary", fail)
    sweep = ["solve", EXAMPLE, "--sweep", "A=0:1:5", "--to", "jsonl", "--no-timings"]
    out = tmp_path / "out.jsonl"
    assert p105(*sweep, "-o", out).returncode == ExitCode.USAGE
    assert _names(tmp_path) == []
    r = p105(*sweep, "--keep-partial", "-o", out)
    assert r.returncode == ExitCode.USAGE and "stopped before the summary" in r.stderr.decode()
    lines = out.read_text().splitlines()
    assert len(lines) == 5 and all('"type":"configuration"' in line for line in lines)


# ---------------------------------------------------------------- a device that refuses data

def _file_size_limit(limit: int):
    def apply():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # the write fails with EFBIG instead
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return apply


@pytest.mark.parametrize("name", ["parse", "export", "solve"])
def test_a_full_device_under_o_is_exit_2_naming_the_path(name, tmp_path):
    out = tmp_path / "out"
    out.write_text("old")
    r = subprocess.run([sys.executable, "-m", "p105cli", *map(str, JOB[name]), str(EXAMPLE), "-o", str(out)],
                       capture_output=True, cwd=ROOT, preexec_fn=_file_size_limit(512), timeout=120)
    assert r.returncode == ExitCode.USAGE, r.stderr
    assert r.stderr.decode() == f"p105: error: {out}: cannot write: File too large\n"
    assert out.read_text() == "old" and _names(tmp_path) == ["out"]


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full on this system")
@pytest.mark.parametrize("name", COMMANDS)
def test_a_full_device_on_stdout_is_exit_2(name):
    args = [a for a in JOB[name] if a not in ("-o", os.devnull)] if name != "validate" else ["validate"]
    with open("/dev/full", "wb") as full:
        r = subprocess.run([sys.executable, "-m", "p105cli", *args, str(INPUT.get(name, EXAMPLE))],
                           stdout=full, stderr=subprocess.PIPE, cwd=ROOT, timeout=120)
    assert r.returncode == ExitCode.USAGE, r.stderr
    assert r.stderr.decode().endswith("p105: error: <stdout>: cannot write: No space left on device\n")
    assert b"internal error" not in r.stderr


# ---------------------------------------------------------------- killed while writing

def _temporaries(directory) -> list[str]:
    return [n for n in os.listdir(directory) if TEMP_MARK in n]


def test_a_temporary_left_by_kill_9_is_removed_by_the_next_write(tmp_path):
    out = tmp_path / "out.csv"
    proc = subprocess.Popen([sys.executable, "-m", "p105cli", "solve", str(EXAMPLE), "--sweep",
                             "A=0:6.283185307179586:3000000", "--to", "csv", "-o", str(out)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=ROOT)
    try:
        deadline = time.monotonic() + 60
        while not _temporaries(tmp_path) and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.3)  # some data in it
    finally:
        proc.kill()
        proc.wait()
    left = _temporaries(tmp_path)
    assert len(left) == 1 and left[0].startswith(f".out.csv{TEMP_MARK}") and not out.exists()
    r = run_cli("parse", EXAMPLES / "four_bar_ap242.stp", "-o", out)
    assert r.returncode == 0
    assert _names(tmp_path) == ["out.csv"]


def test_the_temporaries_of_running_processes_are_left_alone(tmp_path):
    target = tmp_path / "out.json"
    mine = PendingFile(target)  # this process: running
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = os.path.join(tmp_path, os.path.basename(mine.temp).replace(f"-{os.getpid()}-", f"-{dead.pid}-"))
    open(stale, "w").close()
    other = tmp_path / ".other.json.p105-x-1-y.tmp"  # another target's: not ours to judge
    other.write_text("")
    assert remove_stale_temporaries(target) == [stale]
    assert sorted(_temporaries(tmp_path)) == sorted([os.path.basename(mine.temp), other.name])
    mine.commit()
    assert target.exists() and os.path.basename(mine.temp) not in os.listdir(tmp_path)


def test_a_full_device_under_atomic_file_names_the_file(tmp_path):
    # the pictures of solve --plot/--animate and the man pages are written with atomic_file:
    # the error carries the path, so main() names it (not <stdout>)
    code = ("import resource, signal, sys\n"
            "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
            "resource.setrlimit(resource.RLIMIT_FSIZE, (100, 100))\n"
            "from p105cli.fileio import atomic_file\n"
            "try:\n"
            "    with atomic_file(sys.argv[1]) as fh:\n"
            "        fh.write('x' * 1000)\n"
            "except OSError as err:\n"
            "    print(err.errno, err.filename)\n")
    target = tmp_path / "picture.svg"
    r = subprocess.run([sys.executable, "-c", code, str(target)], capture_output=True, cwd=ROOT, timeout=60)
    assert r.stdout.decode().split() == [str(errno.EFBIG), str(target)], r.stderr
    assert _names(tmp_path) == []
    with atomic_file(target) as fh:  # and without a limit, it is written
        fh.write("x")
    assert target.read_text() == "x" and _names(tmp_path) == ["picture.svg"]


def test_numpy_warnings_never_reach_stderr():
    # D02/D21 of the shared audit printed "RuntimeWarning: overflow encountered in dot" and
    # "One of rtol or atol is not valid"; what they signal is checked where it matters, and
    # the warnings themselves are not p105 diagnostics (-vv shows them)
    code = ("import sys, numpy as np\n"
            "import p105cli.kinematics.graph as g\n"
            "original = g.analyse\n"
            "def analyse(*a, **k):\n"
            "    np.float64(1e308) * 10.0\n"
            "    np.isclose(1.0, 1.0, atol=float('inf'))\n"
            "    return original(*a, **k)\n"
            "g.analyse = analyse\n"
            "from p105cli.cli import main\n"
            "sys.exit(main(sys.argv[1:]))\n")
    quiet = subprocess.run([sys.executable, "-c", code, "graph", str(EXAMPLE)], capture_output=True, cwd=ROOT,
                           timeout=120)
    assert quiet.returncode == 0 and quiet.stderr == b"", quiet.stderr
    loud = subprocess.run([sys.executable, "-c", code, "-vv", "graph", str(EXAMPLE)], capture_output=True,
                          cwd=ROOT, timeout=120)
    assert loud.returncode == 0 and b"RuntimeWarning: overflow" in loud.stderr
