"""cli/options.py: the shared options are one declaration each, and behave alike everywhere."""

from __future__ import annotations

import click
import pytest

from conftest import EXAMPLES
from p105cli.cli import SUBCOMMANDS, cli

FOUR_BAR = EXAMPLES / "four_bar_ap242.stp"


def _command(name):
    return cli.get_command(click.Context(cli), name)


def _option(command, flag):
    return next((p for p in _command(command).params if flag in getattr(p, "opts", ())), None)


@pytest.mark.parametrize("command", sorted(SUBCOMMANDS))
def test_output_option_is_the_same_everywhere(command):
    o = _option(command, "-o")
    assert o is not None and o.opts == ["-o", "--output"] and o.metavar == "OUT" and o.default is None


@pytest.mark.parametrize("command", ["graph", "interpolate", "solve", "validate"])
def test_input_schema_option_offers_the_profiles(command):
    o = _option(command, "--schema")
    assert list(o.type.choices) == ["ap214", "ap242", "p105"] and o.default is None


@pytest.mark.parametrize("command", ["graph", "solve"])
def test_mechanism_option_is_one(command):
    o = _option(command, "--mechanism")
    assert o.name == "mechanism" and o.metavar == "NAME"
    assert o.help == "Analyse the mechanism called NAME (needed when the file has several)."


@pytest.mark.parametrize("command, choices", [
    ("export", ["p21", "json"]), ("graph", ["json", "dot", "graphml", "mermaid", "p21"]),
    ("convert-dh-su", ["p21", "json", "dh", "dh-json"]), ("interpolate", ["jsonl", "csv"]),
    ("solve", ["model", "jsonl", "csv"])])
def test_to_option_has_the_commands_choices(command, choices):
    assert list(_option(command, "--to").type.choices) == choices


@pytest.mark.parametrize("command", ["parse", "export", "graph", "interpolate", "convert-dh-su"])
def test_input_argument_is_file_or_stdin(command):
    arg = next(p for p in _command(command).params if isinstance(p, click.Argument))
    assert arg.name == "input" and arg.default == "-"


@pytest.mark.parametrize("args", [["graph", FOUR_BAR, "--tol", "0"], ["graph", FOUR_BAR, "--tol", "nan"],
                                  ["graph", FOUR_BAR, "--tol", "inf"],   # was exit 3 (internal error)
                                  ["solve", FOUR_BAR, "--tol", "0"], ["solve", FOUR_BAR, "--tol", "inf"],
                                  ["solve", FOUR_BAR, "--tol", "-1e-10"]])
def test_tol_must_be_positive(p105, args):
    r = p105(*args)
    assert r.returncode == 2 and r.stderr.decode().endswith("--tol must be a positive number\n") \
        and r.stdout == b""


def test_output_is_written_atomically_and_never_over_the_input(p105, tmp_path):
    out = tmp_path / "g.dot"
    r = p105("graph", FOUR_BAR, "--to", "dot", "-o", out)
    assert r.returncode == 0 and r.stdout == b"" and out.read_text().startswith("digraph ")
    copy = tmp_path / "m.stp"
    copy.write_bytes(FOUR_BAR.read_bytes())
    r = p105("export", copy, "-o", copy)
    assert r.returncode == 2 and b"p105 never overwrites its input" in r.stderr
    assert copy.read_bytes() == FOUR_BAR.read_bytes()


@pytest.mark.parametrize("command, choices, default", [("export", ["ap214", "p105", "ap242"], None),
                                                        ("convert-dh-su", ["ap242", "p105", "ap214"], "ap242")])
def test_output_schema_option_is_the_layout_written(command, choices, default):
    o = _option(command, "--schema")
    assert list(o.type.choices) == choices and o.default == default
