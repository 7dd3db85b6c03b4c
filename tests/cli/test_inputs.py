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


# --------------------------------------------------------------- a syntax error anywhere
CORPUS_FOUR_BAR = EXAMPLES.parent / "tests" / "data" / "corpus" / "four_bar_ap242.stp"
#: Every command that reads a model through cli.inputs (validate reports in its own format).
MODEL_COMMANDS = [
    ["parse"], ["export"], ["export", "--schema", "ap214"], ["export", "--schema", "ap242"], ["graph"],
    ["solve"], ["interpolate"], ["convert-dh-su", "--to", "dh", "--convention", "standard"],
]


def _with_syntax_error(tmp_path):
    """The four-bar with a ')' missing in a point no mechanism reads (line 29)."""
    lines = CORPUS_FOUR_BAR.read_text().splitlines(keepends=True)
    assert lines[28] == "#22=CARTESIAN_POINT('',(30.,-15.,0.));\n"
    lines[28] = "#22=CARTESIAN_POINT('',(30.,-15.,0.);\n"
    path = tmp_path / "bad.stp"
    path.write_text("".join(lines))
    return path


@pytest.mark.parametrize("command", MODEL_COMMANDS, ids=" ".join)
def test_a_syntax_error_in_any_instance_is_reported_by_every_command(p105, tmp_path, command):
    # the instance is decoded by no analysis: the lazy reading never saw it, and the
    # commands went on to analyse the rest of the file (or said "no mechanism")
    path = _with_syntax_error(tmp_path)
    r = p105(*command, path)
    assert r.returncode == 2
    assert r.stderr.decode() == f"p105: error: {path}:29:37: expected ',' or ')', found ';'\n"
    v = p105("validate", path)
    assert v.returncode == 2 and f"{path}:29:37: error[P21-SYNTAX]" in v.stdout.decode()


def test_checking_every_instance_records_no_warning_twice(p105, tmp_path):
    # a string with an unknown escape: one warning, however many times the file is decoded
    text = CORPUS_FOUR_BAR.read_text().replace("#21=CARTESIAN_POINT('',", "#21=CARTESIAN_POINT('\\Q',", 1)
    path = tmp_path / "warn.stp"
    path.write_text(text)
    parse = p105("parse", path).stderr.decode().splitlines()
    export = p105("export", path).stderr.decode().splitlines()
    assert len(parse) == 1 and "warning" in parse[0] and export == parse


@pytest.mark.parametrize("cut", [3000, -30])
def test_a_truncated_file_is_the_same_syntax_error_for_every_command(p105, tmp_path, cut):
    path = tmp_path / "cut.stp"
    path.write_bytes(CORPUS_FOUR_BAR.read_bytes()[:cut])
    errors = {" ".join(c): p105(*c, path) for c in MODEL_COMMANDS}
    assert {r.returncode for r in errors.values()} == {2}
    assert len({r.stderr for r in errors.values()}) == 1
    assert b"is not terminated by ';'" in errors["parse"].stderr


def test_a_dangling_reference_is_a_finding_of_validate_and_an_error_naming_it_elsewhere(p105, tmp_path):
    text = CORPUS_FOUR_BAR.read_text()
    old = "#134=KINEMATIC_JOINT('B',#130,#131);"
    assert old in text
    path = tmp_path / "dangling.stp"
    path.write_text(text.replace(old, "#134=KINEMATIC_JOINT('B',#130,#9131);"))
    assert p105("parse", path).returncode == 0
    v = p105("validate", path)  # was exit 3: KeyError 9131 in the rules' closure
    assert v.returncode == 1 and "error[SCH-DANGLING]" in v.stdout.decode() and "#9131" in v.stdout.decode()
    for command in (["graph"], ["solve"], ["interpolate"], ["export", "--schema", "ap214"]):
        r = p105(*command, path)
        assert r.returncode == 2, command
        assert (f"{path}: #134: edge_end of kinematic_joint refers to #9131, which is not in the file"
                in r.stderr.decode()), command
