"""cli/inputs.py: one way to read an input, the same answer from every command."""

from __future__ import annotations

import pytest

from conftest import EXAMPLES

DEEP = "[" * 200_000 + "]" * 200_000

#: Every command that reads a model (or, for convert-dh-su, a DH table or a model).
COMMANDS = [
    ["parse"], ["export"], ["export", "--to", "json"], ["validate"], ["graph"], ["interpolate"], ["solve"],
    ["convert-dh-su", "--convention", "standard"],
    ["convert-dh-su", "--to", "dh", "--convention", "standard"],
    ["convert-dh-su", "--to", "dh-json", "--convention", "standard"],
]

DEEP_TEXTS = {
    # the first line is a whole JSON object: the model reader's stream sniffing decodes it
    "one line": '{"format":"p105/1","header":{},"data":' + DEEP + "}",
    "args": '{"format":"p105/1","header":{},\n"data":[{"id":1,"type":"a","args":' + DEEP + "}]}",
    "dh table": '{"joints":' + DEEP + "}",
}


def _error_lines(r, name):
    text = (r.stdout + r.stderr).decode()
    assert "internal error" not in text and "Traceback" not in text, text
    return [ln for ln in text.splitlines() if "JSON nested too deeply" in ln and name in ln]


@pytest.mark.parametrize("command", COMMANDS, ids=" ".join)
@pytest.mark.parametrize("kind", DEEP_TEXTS)
def test_deeply_nested_json_is_malformed_input_for_every_command(p105, tmp_path, command, kind):
    path = tmp_path / "deep.json"
    path.write_text(DEEP_TEXTS[kind])
    r = p105(*command, path)
    assert r.returncode == 2
    assert _error_lines(r, str(path)), (r.stdout + r.stderr).decode()[-2000:]


@pytest.mark.parametrize("command", COMMANDS, ids=" ".join)
def test_deeply_nested_json_on_stdin_is_named_stdin(p105, command):
    r = p105(*command, "-", input=DEEP_TEXTS["one line"])
    assert r.returncode == 2
    assert _error_lines(r, "<stdin>")


def test_deeply_nested_motion_inputs_name_their_file(p105, tmp_path):
    model = EXAMPLES / "four_bar_ap242.stp"
    deep = tmp_path / "deep.jsonl"
    deep.write_text('{"t": 0, "pairs": ' + DEEP + "}\n")
    for option in (["--values", deep], ["--path", deep, "--target-link", "crank"]):
        r = p105("solve", model, *option, "--to", "jsonl")
        assert r.returncode == 2, r.stderr
        assert r.stderr.decode().startswith(f"p105: error: {deep}:1:"), r.stderr
        assert b"nested too deeply" in r.stderr and b"internal" not in r.stderr


def test_stdin_is_named_stdin(p105):
    r = p105("parse", input="not a model")
    assert r.returncode == 2
    assert r.stderr.decode().startswith("p105: error: <stdin>:1:1: ")


def test_unreadable_file_is_named(p105, tmp_path):
    missing = tmp_path / "missing.stp"
    for command in (["parse"], ["graph"], ["solve"], ["convert-dh-su"], ["interpolate"]):
        r = p105(*command, missing)
        assert r.returncode == 2
        assert r.stderr.decode().startswith(f"p105: error: {missing}: cannot read: "), r.stderr


def test_source_of_falls_back_to_stdin():
    from p105cli.cli.inputs import source_of

    class Doc:
        source = "<input>"
    assert source_of(Doc()) == "<stdin>"
    assert source_of(object()) == "<stdin>"
    Doc.source = "a.stp"
    assert source_of(Doc()) == "a.stp"


@pytest.mark.parametrize("name, text", [("deep.json", '{"cables": ' + DEEP + "}"),
                                        ("deep.toml", "a = " + DEEP + "\n")])
def test_deeply_nested_scene_names_its_file(p105, tmp_path, name, text):
    scene = tmp_path / name
    scene.write_text(text)
    r = p105("solve", "--scene", scene)
    assert r.returncode == 2
    kind = "TOML" if name.endswith(".toml") else "JSON"
    assert r.stderr.decode() == f"p105: error: {scene}: {kind} nested too deeply\n"
