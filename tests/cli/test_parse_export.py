"""p105 parse and export in process: the JSON model and Part 21 round trip."""

from __future__ import annotations

from conftest import EXAMPLES

FOUR_BAR = EXAMPLES / "four_bar_ap242.stp"


def test_parse_then_export_gives_the_canonical_part21(p105, tmp_path):
    model = tmp_path / "m.json"
    assert p105("parse", FOUR_BAR, "-o", model).returncode == 0
    once = p105("export", FOUR_BAR).stdout
    assert p105("export", model).stdout == once
    streamed = tmp_path / "s.jsonl"
    assert p105("parse", "--stream", FOUR_BAR, "-o", streamed).returncode == 0
    assert p105("export", streamed).stdout == once


def test_stdin_model(p105):
    r = p105("export", "--to", "json", input=FOUR_BAR.read_bytes())
    assert r.returncode == 0 and r.stdout.startswith(b"{")


def test_stream_needs_json(p105):
    r = p105("export", "--stream", FOUR_BAR)
    assert r.returncode == 2 and b"--stream applies to --to json only" in r.stderr
