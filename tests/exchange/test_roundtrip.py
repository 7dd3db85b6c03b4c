"""Round trip is the promise: Part 21 -> JSON -> Part 21 loses nothing and is a fixed point.

For every Part 21 file of the shared corpus and examples/:
``p105 parse F | p105 export --to p21 | p105 parse`` equals ``p105 parse F``,
and exporting the result again is byte-identical.
"""

from __future__ import annotations

import json

import pytest

from conftest import cli_in_process, corpus_files, p21, same_value

FILES = corpus_files()
# The big real CAD files (several MB each) cost ~10 s apiece: one stays in `make test`,
# the others run with `make test-all` (test_bulk round-trips big files in process too).
_BIG = 2_000_000
_FIRST_BIG = next((p for p in FILES if p.stat().st_size > _BIG), None)
PARAMS = [pytest.param(p, id=p.name, marks=pytest.mark.slow if p.stat().st_size > _BIG and p != _FIRST_BIG
                       else ()) for p in FILES]


@pytest.mark.parametrize("path", PARAMS)
def test_cli_round_trip(path):
    # in this process: the pipeline's stages are the commands; pipes are test_cli_contract's
    first = cli_in_process("parse", path)
    assert first.returncode == 0, first.stderr.decode()
    p21_text = cli_in_process("export", "--to", "p21", "-", input=first.stdout)
    assert p21_text.returncode == 0, p21_text.stderr.decode()
    second = cli_in_process("parse", "-", input=p21_text.stdout)
    assert second.returncode == 0, second.stderr.decode()
    assert second.stdout == first.stdout                         # same JSON, byte for byte
    again = cli_in_process("export", "--to", "p21", "-", input=second.stdout)
    assert again.stdout == p21_text.stdout                        # canonical Part 21 is a fixed point
    # The original file and the JSON agree on what is there (an independent count).
    doc = json.loads(first.stdout)
    text = path.read_bytes().decode("utf-8", "replace")
    assert len(doc["data"]) == _naive_instance_count(text)


def _naive_instance_count(text: str) -> int:
    """Instances counted with a deliberately different method: a character scan."""
    count, in_string, in_comment, i = 0, False, False, text.find("DATA;")
    depth = 0
    while i < len(text):
        c = text[i]
        if in_comment:
            if text.startswith("*/", i):
                in_comment, i = False, i + 1
        elif in_string:
            if c == "'":
                in_string = False
        elif c == "'":
            in_string = True
        elif text.startswith("/*", i):
            in_comment = True
        elif c == "(":
            depth += 1
        elif c == ")":
            depth -= 1
        elif c == "=" and depth == 0:
            count += 1
        i += 1
    return count


@pytest.mark.parametrize("path", FILES[:3], ids=[p.name for p in FILES[:3]])
def test_stream_form_round_trips(path):
    doc = cli_in_process("parse", path)
    stream = cli_in_process("parse", "--stream", path)
    assert stream.returncode == 0
    lines = stream.stdout.decode().splitlines()
    frame = json.loads(lines[0])
    assert frame["stream"] is True and frame["format"] == "p105/1"
    assert [json.loads(line) for line in lines[1:]] == json.loads(doc.stdout)["data"]
    back = cli_in_process("export", "--to", "json", "-", input=stream.stdout)
    assert back.stdout == doc.stdout


def test_generated_file_round_trips_exactly():
    text = p21("\n".join([
        "#1=A('it''s',\"2F\",.T.,$,*,(1,(2.5,-0.)),LENGTH_MEASURE(1.E-320));",
        "#2=(B(#1)C('\\X2\\00E9\\X0\\')D());",
        "#30=E(#2,#30,123456789012345678901234567890);",
    ]))
    first = cli_in_process("parse", "-", input=text)
    assert first.returncode == 0, first.stderr
    back = cli_in_process("export", "-", input=first.stdout)
    again = cli_in_process("parse", "-", input=back.stdout)
    assert same_value(json.loads(again.stdout), json.loads(first.stdout))
    assert again.stdout == first.stdout
