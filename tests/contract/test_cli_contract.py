"""The CLI contract, checked for every registered subcommand."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from conftest import EXAMPLES, HEADER, ROOT, p21, run_cli
from p105cli.cli import SUBCOMMANDS, main
from p105cli.cli.contract import ExitCode

COMMANDS = sorted(SUBCOMMANDS)
EXAMPLE = EXAMPLES / "four_bar_ap242.stp"
# Arguments that make each subcommand do its main job on EXAMPLE.
# validate --pass is a data filter too: the input on stdout when it passes; its report goes to -o.
JOB = {"parse": ["parse"], "export": ["export", "--to", "p21"],
       "validate": ["validate", "--pass", "-o", os.devnull],
       "graph": ["graph", "--enrich"],
       "interpolate": ["interpolate", "--what", "paths"],
       "convert-dh-su": ["convert-dh-su", "--convention", "standard"],
       "solve": ["solve", "--to", "jsonl", "--no-timings"]}
# Commands that read something other than a model: the input their JOB reads instead of
# EXAMPLE, and a writer of a big one (tmp_path -> path) for the closed-pipe and Ctrl-C tests.
INPUT = {"convert-dh-su": EXAMPLES / "puma560_dh.csv"}
BIG_INPUT = {"convert-dh-su": lambda tmp_path: _big_dh_table(tmp_path)}
# Long-running jobs with a large output, for the closed-pipe and Ctrl-C tests: by default a
# command's JOB on a big point cloud; commands that need a mechanism get a big job on EXAMPLE.
LONG_JOB = {"interpolate": ["interpolate", "--what", "paths", "--step", "1e-7"],
            "solve": ["solve", "--sweep", "A=0:6.283185307179586:2000000", "--to", "jsonl"]}
# Commands whose stdout is a model derived from the input (validate's analogues are in test_validate.py).
MODEL_WRITERS = ["export", "parse"]


def test_every_registered_subcommand_has_a_contract_job():
    assert set(JOB) == set(COMMANDS)


def test_group_help_documents_exit_codes():
    r = run_cli("--help")
    assert r.returncode == 0
    out = r.stdout.decode()
    for code in ("0", "1", "2", "3", "130"):
        assert f"\n    {code} " in out
    for name in COMMANDS:
        assert name in out


@pytest.mark.parametrize("name", COMMANDS)
def test_subcommand_help_documents_exit_codes(name):
    r = run_cli(name, "--help")
    assert r.returncode == 0 and b"Exit status" in r.stdout


@pytest.mark.parametrize("name", COMMANDS)
def test_reads_file_and_stdin_the_same(name):
    example = INPUT.get(name, EXAMPLE)
    from_file = run_cli(*JOB[name], example)
    from_stdin = run_cli(*JOB[name], input=example.read_bytes())
    dash = run_cli(*JOB[name], "-", input=example.read_bytes())
    assert from_file.returncode == 0, from_file.stderr
    assert from_file.stdout == from_stdin.stdout == dash.stdout
    assert from_file.stderr == b""


@pytest.mark.parametrize("name", MODEL_WRITERS)
def test_sniffs_json_input_too(name):
    model = run_cli("parse", EXAMPLE).stdout
    direct = run_cli(*JOB[name], EXAMPLE)
    via_json = run_cli(*JOB[name], "-", input=model)
    assert via_json.returncode == 0, via_json.stderr
    assert via_json.stdout == direct.stdout


@pytest.mark.parametrize("name", COMMANDS)
def test_deterministic_output(name):
    example = INPUT.get(name, EXAMPLE)
    assert run_cli(*JOB[name], example).stdout == run_cli(*JOB[name], example).stdout


@pytest.mark.parametrize("name", COMMANDS)
def test_missing_file_is_exit_2_with_the_name(name):
    r = run_cli(*JOB[name], "no/such/file.stp")
    assert r.returncode == ExitCode.USAGE
    assert b"no/such/file.stp" in r.stderr and b"Traceback" not in r.stderr


@pytest.mark.parametrize("name", MODEL_WRITERS)
def test_malformed_input_is_exit_2_with_line_and_column(name):
    r = run_cli(*JOB[name], input=p21("#1=A(1);\n#2=B(1 2);"))
    assert r.returncode == ExitCode.USAGE
    assert r.stderr.decode().startswith("p105: error: <stdin>:9:8: ")
    assert b"Traceback" not in r.stderr


@pytest.mark.parametrize("name", COMMANDS)
def test_unknown_input_format_is_exit_2(name):
    r = run_cli(*JOB[name], input=b"hello world")
    assert r.returncode == ExitCode.USAGE and b"neither a Part 21 file" in r.stderr


@pytest.mark.parametrize("name", COMMANDS)
def test_usage_error_is_exit_2(name):
    r = run_cli(name, "--no-such-option")
    assert r.returncode == ExitCode.USAGE and b"Traceback" not in r.stderr


@pytest.mark.parametrize("name", MODEL_WRITERS)
def test_output_file_is_written_atomically(name, tmp_path):
    out = tmp_path / "out"
    r = run_cli(*JOB[name], EXAMPLE, "-o", out)
    assert r.returncode == 0 and r.stdout == b""          # data went to the file, not stdout
    assert out.read_bytes() == run_cli(*JOB[name], EXAMPLE).stdout
    # A failure half-way (an instance that only breaks when decoded) leaves the old file alone.
    out.write_bytes(b"previous content")
    bad = tmp_path / "bad.stp"
    bad.write_text(p21("\n".join(f"#{i}=A({i});" for i in range(1, 2000)) + "\n#5000=B(1 2);"))
    r = run_cli(*JOB[name], bad, "-o", out)
    assert r.returncode == ExitCode.USAGE, r.stderr
    assert out.read_bytes() == b"previous content"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.stp", "out"]  # no temp left


@pytest.mark.parametrize("name", COMMANDS)
def test_output_into_a_missing_directory_is_exit_2(name, tmp_path):
    r = run_cli(*JOB[name], INPUT.get(name, EXAMPLE), "-o", tmp_path / "nope" / "out")
    assert r.returncode == ExitCode.USAGE and b"cannot write" in r.stderr


@pytest.mark.parametrize("name", COMMANDS)
def test_input_is_never_overwritten(name, tmp_path):
    src = tmp_path / "model.stp"
    example = INPUT.get(name, EXAMPLE)
    src.write_bytes(example.read_bytes())
    r = run_cli(*JOB[name], src, "-o", src)
    assert r.returncode == ExitCode.USAGE and b"never overwrites its input" in r.stderr
    assert src.read_bytes() == example.read_bytes()


def _big_model(tmp_path, n=150_000):
    big = tmp_path / "big.stp"
    header = HEADER.replace("TEST_SCHEMA", "AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF")
    big.write_text(p21("\n".join(f"#{i}=CARTESIAN_POINT('',({i}.,2.,3.));" for i in range(1, n)), header))
    return big


def _big_dh_table(tmp_path, n=5000):
    big = tmp_path / "big_dh.csv"
    big.write_text("name,type,a,alpha,d,theta,offset\n"
                   + "".join(f"J{i},{'RP'[i % 2]},0.1,pi/2,{'0.05,' if i % 2 == 0 else ',0.3'},0.1\n"
                             for i in range(n)))
    return big


@pytest.mark.parametrize("name", COMMANDS)
def test_closed_pipe_ends_quietly(name, tmp_path):
    big = (BIG_INPUT[name](tmp_path) if name in BIG_INPUT else EXAMPLE if name in LONG_JOB
           else _big_model(tmp_path))
    cmd = f"{sys.executable} -m p105cli {' '.join(LONG_JOB.get(name, JOB[name]))} {big} " \
          "| head -c 100 > /dev/null; " \
          f"echo ${{PIPESTATUS[0]}}"
    r = subprocess.run(["bash", "-c", cmd], capture_output=True, cwd=ROOT, timeout=120)
    assert r.stderr == b""
    assert r.stdout.strip() == str(int(ExitCode.BROKEN_PIPE)).encode()


def _default_sigint():
    # A parent that ignores SIGINT (a pytest-xdist worker, a background job, nohup) passes
    # that on, and Python then installs no KeyboardInterrupt handler: give the child the
    # default disposition a user's terminal gives it.
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.parametrize("name", COMMANDS)
def test_ctrl_c_is_exit_130_without_traceback(name, tmp_path):
    big = (BIG_INPUT[name](tmp_path) if name in BIG_INPUT else EXAMPLE if name in LONG_JOB
           else _big_model(tmp_path, 400_000))
    proc = subprocess.Popen([sys.executable, "-m", "p105cli", *LONG_JOB.get(name, JOB[name]), big,
                             "-o", tmp_path / "o"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT,
                            preexec_fn=_default_sigint)
    time.sleep(1.0)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == ExitCode.INTERRUPTED, err
    assert b"Traceback" not in err and b"interrupted" in err
    assert not (tmp_path / "o").exists()


def test_dangling_reference_is_a_warning_naming_the_instance():
    r = run_cli("parse", input=p21("#1=A(#2);\n#2=B(#99);"))
    assert r.returncode == 0
    assert r.stderr.decode() == "p105: warning: <stdin>: #2: reference to #99, which is not in the file\n"
    q = run_cli("-q", "parse", input=p21("#1=A(#2);\n#2=B(#99);"))
    assert q.stderr == b""


def test_version_and_show_versions():
    from p105cli import __version__
    r = run_cli("--version")
    assert r.returncode == 0 and r.stdout.decode().strip() == f"p105 {__version__}"
    r = run_cli("--show-versions")
    assert r.returncode == 0
    names = [line.split()[0] for line in r.stdout.decode().splitlines()]
    assert names == ["p105", "python", "click", "numpy", "scipy", "rich"]


def test_internal_error_is_exit_3_and_traceback_only_with_v(monkeypatch, capsys):
    import p105cli.step.jsonmodel as jm

    def boom(*a, **k):
        raise RuntimeError("simulated bug")

    monkeypatch.setattr(jm, "write_json", boom)
    monkeypatch.setattr("p105cli.step.write_json", boom)
    assert main(["parse", str(EXAMPLE), "-o", os.devnull]) == ExitCode.INTERNAL
    err = capsys.readouterr().err
    assert "internal error" in err and "simulated bug" in err and "Traceback" not in err
    assert main(["-v", "parse", str(EXAMPLE), "-o", os.devnull]) == ExitCode.INTERNAL
    assert "Traceback" in capsys.readouterr().err


def test_module_and_console_script_agree():
    r = subprocess.run([sys.executable, "-c", "import sys; from p105cli.cli import main; sys.exit(main())",
                        "parse", str(EXAMPLE)], capture_output=True, cwd=ROOT)
    assert r.returncode == 0 and r.stdout == run_cli("parse", EXAMPLE).stdout


@pytest.mark.parametrize("args", [["validate"], ["graph"], ["solve"], ["interpolate"], ["export", "--schema", "ap242"],
                                  ["convert-dh-su", "--convention", "standard", "--to", "dh"]])
def test_unknown_file_schema_is_exit_2_naming_the_file(args, tmp_path):
    """Commands that interpret a model need its schema: an unknown one is the input's fault."""
    f = tmp_path / "other.stp"
    f.write_text(p21("#1=CARTESIAN_POINT('',(0.,0.,0.));", HEADER.replace("TEST_SCHEMA", "CONFIG_CONTROL_DESIGN")))
    r = run_cli(*args, f)
    assert r.returncode == ExitCode.USAGE, r.stderr
    said = r.stderr + (r.stdout if args[0] == "validate" else b"")  # validate's report is its data
    assert b"other.stp" in said and b"CONFIG_CONTROL_DESIGN" in said and b"Traceback" not in r.stderr
