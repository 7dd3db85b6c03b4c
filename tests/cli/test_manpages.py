"""The committed man pages in man/ are complete and exactly what `make man` generates."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import click
import pytest

from p105cli import manpages
from p105cli.cli import cli
from p105cli.cli.contract import ExitCode

ROOT = Path(__file__).resolve().parents[2]
MAN = ROOT / "man"

REQUIRED_SECTIONS = ("NAME", "SYNOPSIS", "DESCRIPTION", "OPTIONS", "EXIT STATUS",
                     "STANDARD INPUT", "STANDARD OUTPUT", "EXAMPLES")


def _pages():
    """(page key, command, context, committed path) for the group and every subcommand."""
    root = click.Context(cli, info_name="p105", **cli.context_settings)
    pages = [("p105", cli, root, MAN / "p105.1")]
    for name in cli.list_commands(root):
        cmd = cli.get_command(root, name)
        ctx = click.Context(cmd, info_name=name, parent=root, **cmd.context_settings)
        pages.append((name, cmd, ctx, MAN / f"p105-{name}.1"))
    return pages


PAGES = _pages()
IDS = [page for page, *_ in PAGES]


def _sections(text: str) -> dict[str, str]:
    sections: dict[str, list[str]] = {}
    current = None
    for line in text.splitlines():
        match = re.match(r'\.SH\s+(.*)$', line)
        if match:
            current = match.group(1).strip().strip('"')
            sections[current] = []
        elif current is not None:
            sections[current].append(line)
    return {name: "\n".join(lines) for name, lines in sections.items()}


def _roff_flag(flag: str) -> str:
    return flag.replace("-", "\\-")


def test_every_registered_subcommand_has_a_page():
    from p105cli.cli import SUBCOMMANDS
    assert (MAN / "p105.1").is_file()
    for name in SUBCOMMANDS:
        assert (MAN / f"p105-{name}.1").is_file(), f"no man page for `p105 {name}`: run make man"


def test_every_registered_subcommand_has_hand_written_text():
    from p105cli.cli import SUBCOMMANDS
    for name in ["p105", *SUBCOMMANDS]:
        entry = manpages.PAGES.get(name)
        assert entry, f"p105cli/manpages.py PAGES has no entry for {name!r}"
        assert entry.get("examples"), f"PAGES[{name!r}] has no examples"
        assert entry.get("stdin") and entry.get("stdout"), f"PAGES[{name!r}] lacks stdin/stdout text"


@pytest.mark.parametrize("page,cmd,ctx,path", PAGES, ids=IDS)
def test_page_has_required_sections(page, cmd, ctx, path):
    sections = _sections(path.read_text(encoding="utf-8"))
    for name in REQUIRED_SECTIONS:
        assert name in sections, f"{path.name}: no {name} section"
        assert sections[name].strip(), f"{path.name}: empty {name} section"


@pytest.mark.parametrize("page,cmd,ctx,path", PAGES, ids=IDS)
def test_every_option_is_documented(page, cmd, ctx, path):
    options = _sections(path.read_text(encoding="utf-8"))["OPTIONS"]
    params = [p for p in cmd.get_params(ctx) if isinstance(p, click.Option) and not p.hidden]
    assert params
    for param in params:
        for flag in param.opts + param.secondary_opts:
            assert re.search(rf"\\fB{re.escape(_roff_flag(flag))}\\fR", options), \
                f"{path.name}: option {flag} missing from OPTIONS"
        if param.help:
            first_word = param.help.split()[0]
            assert first_word in options


@pytest.mark.parametrize("page,cmd,ctx,path", PAGES, ids=IDS)
def test_exit_codes_documented(page, cmd, ctx, path):
    exit_status = _sections(path.read_text(encoding="utf-8"))["EXIT STATUS"]
    codes = re.findall(r"^\\fB(\d+)\\fR$", exit_status, flags=re.M)
    for code in (0, 1, 2, 3, 130):
        assert str(code) in codes, f"{path.name}: exit code {code} missing from EXIT STATUS"
    assert sorted(map(int, codes)) == sorted(int(c) for c in ExitCode)


def test_pages_are_roff_clean():
    for _, _, _, path in PAGES:
        text = path.read_text(encoding="ascii")     # non-ASCII must be escaped
        lines = text.splitlines()
        assert lines[1].startswith(".TH "), path.name
        for line in lines:
            # Text lines never start with a quote or an unintended request.
            assert not line.startswith("'"), f"{path.name}: {line!r}"
            if line.startswith("."):
                assert re.match(r'\.(\\"|[A-Za-z]{1,2}\b)', line), f"{path.name}: {line!r}"
        assert not re.search(r"(?<!\\)--", text), f"{path.name}: unescaped -- (write \\-\\-)"
        assert "2026" not in text and not re.search(r"\b20\d\d-\d\d-\d\d\b", text)


def test_committed_pages_match_generator(tmp_path):
    """`make man` is the only way the pages change: regenerate and compare bytes."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    subprocess.run([sys.executable, "-m", "p105cli.manpages", str(tmp_path)],
                   cwd=ROOT, env=env, check=True, capture_output=True)
    generated = sorted(p.name for p in tmp_path.iterdir())
    committed = sorted(p.name for p in MAN.glob("p105*.1"))
    assert generated == committed, "man/ is out of date: run make man"
    for name in generated:
        assert (tmp_path / name).read_bytes() == (MAN / name).read_bytes(), \
            f"man/{name} differs from the generator: run make man"


def test_generation_is_deterministic_and_idempotent(tmp_path):
    first = manpages.render_all()
    assert manpages.render_all() == first
    manpages.write_pages(str(tmp_path))
    assert manpages.write_pages(str(tmp_path)) == []        # nothing rewritten


def test_stale_generated_pages_are_removed(tmp_path):
    manpages.write_pages(str(tmp_path))
    stale = tmp_path / "p105-gone.1"
    stale.write_text(manpages.GENERATED_MARK + "\n.TH GONE 1\n", encoding="utf-8")
    mine = tmp_path / "p105-mine.1"
    mine.write_text(".TH MINE 1\n", encoding="utf-8")
    manpages.write_pages(str(tmp_path))
    assert not stale.exists()
    assert mine.exists()


def test_escaping():
    assert manpages.esc_code("a\\b --to -o") == "a\\eb \\-\\-to \\-o"
    assert manpages.esc("Unix-style; use --to or - for stdin") == \
        "Unix-style; use \\-\\-to or \\- for stdin"
    assert manpages.esc("`p105 export --to p21`") == "\\fBp105 export \\-\\-to p21\\fR"
    assert manpages.esc("caf\u00e9") == "caf\\[u00E9]"
    assert manpages.prose(".hidden request") == ["\\&.hidden request"]
    assert manpages.prose("'quoted start") == ["\\&'quoted start"]
