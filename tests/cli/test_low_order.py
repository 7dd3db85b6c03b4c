"""graph, solve, interpolate and export on files whose pairs or values are AP242's generic
low-order ones (the shared defects collection), in process.

Independent truth: ``examples/four_bar_ap242.stp``, the file both defects were made from
(same mechanism, same configurations), run through the same commands.
"""

from __future__ import annotations

import json
import re

import pytest

from conftest import EXAMPLES, SHARED

DEFECTS = SHARED / "external" / "defects"
SOURCE = EXAMPLES / "four_bar_ap242.stp"
#: Solve's records hold the time each took: not part of the result.
TIMINGS = {"seconds", "seconds_per_configuration"}


def _defect(name):
    path = DEFECTS / f"{name}.stp"
    if not path.exists():
        pytest.skip(f"{path} is absent (the shared external collection is not beside the checkout)")
    return path


def _numbers_close(a, b, path="") -> list:
    """Where JSON values ``a`` and ``b`` differ (reals by more than 1e-9: the defects hold the
    source's 12-digit reals at 17 digits)."""
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            return [f"{path}: keys {sorted(a)} != {sorted(b)}"]
        return [d for k in a if k not in TIMINGS for d in _numbers_close(a[k], b[k], f"{path}.{k}")]
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} != {len(b)} items"]
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in _numbers_close(x, y, f"{path}[{i}]")]
    if isinstance(a, float) or isinstance(b, float):
        return [] if abs(a - b) <= 1e-9 else [f"{path}: {a} != {b}"]
    return [] if a == b else [f"{path}: {a!r} != {b!r}"]


@pytest.mark.parametrize("name", ("four_bar_low_order_value", "four_bar_low_order_pair"))
@pytest.mark.parametrize("command", (("solve", "--to", "jsonl"), ("graph",), ("interpolate",)))
def test_the_defects_give_the_source_four_bars_results(p105, name, command):
    got = p105(*command, _defect(name))
    want = p105(*command, SOURCE)
    assert (got.returncode, want.returncode) == (0, 0), got.stderr.decode()
    assert b"warning" not in got.stderr
    if command[0] == "graph":
        g = json.loads(got.stdout)
        assert g["mobility"] == 1 and [j["freedoms"] for j in g["joints"]] == [1, 1, 1, 1]
        records_got, records_want = [g], [json.loads(want.stdout)]
    else:
        records_got = [json.loads(line) for line in got.stdout.decode().splitlines()]
        records_want = [json.loads(line) for line in want.stdout.decode().splitlines()]
    assert _numbers_close(records_got, records_want) == []


def test_a_locked_component_of_a_value_is_a_warning_naming_it(p105, tmp_path):
    """The crank pivot's value with actual_translation_z = 5 mm: solve reads the rotation, warns
    once naming the value, and the results are the source's."""
    text = _defect("four_bar_low_order_value").read_text()
    text, n = re.subn(r"(#207=LOW_ORDER_KINEMATIC_PAIR_VALUE\('A',#182,0\.,0\.,)0\.", r"\g<1>5.", text)
    assert n == 1
    path = tmp_path / "shifted.stp"
    path.write_text(text)
    got = p105("solve", "--to", "jsonl", path)
    assert got.returncode == 0
    warnings = [line for line in got.stderr.decode().splitlines() if "warning" in line]
    assert warnings == [f"p105: warning: {path}: #207: low_order_kinematic_pair_value gives actual_translation_z "
                        "= 5, which the revolute pair #182 cannot move (its freedoms lock it); read as 0 (the "
                        "value projected onto the pair's freedoms)"]
    want = p105("solve", "--to", "jsonl", SOURCE)
    assert _numbers_close([json.loads(x) for x in got.stdout.decode().splitlines()],
                          [json.loads(x) for x in want.stdout.decode().splitlines()]) == []


def _generic_source(tmp_path):
    """The example with pin B as a generic low-order pair with flags t_x and r_z (no named pair
    has them): a pin that may also slide along its frame's x axis."""
    text = SOURCE.read_text()
    text, n = re.subn(r"#183=REVOLUTE_PAIR\('B',\*,'crank-coupler pin',(#\d+,#\d+,#\d+),\*,\*,\*,\*,\*,\*\);",
                      r"#183=LOW_ORDER_KINEMATIC_PAIR('B',*,'pin',\1,.T.,.F.,.F.,.F.,.F.,.T.);", text)
    assert n == 1
    text = re.sub(r"REVOLUTE_PAIR_VALUE\('B',#183,([-0-9.E]+)\)",
                  r"LOW_ORDER_KINEMATIC_PAIR_VALUE('B',#183,0.,0.,0.,0.,0.,\1)", text)
    src = tmp_path / "generic.stp"
    src.write_text(text)
    return src


def test_graph_and_solve_count_and_move_only_the_flags(p105, tmp_path):
    """Mobility 2 (the slide adds one), pin B two freedoms; every solved configuration keeps
    the four locked components exactly 0."""
    src = _generic_source(tmp_path)
    g = json.loads(p105("graph", src).stdout)
    assert g["mobility"] == 2 and [j["freedoms"] for j in g["joints"]] == [1, 2, 1, 1]
    got = p105("solve", "--to", "jsonl", "--program", src)  # the example's two-configuration program
    assert got.returncode == 0, got.stderr.decode()
    configs = [r for r in map(json.loads, got.stdout.decode().splitlines()) if r["type"] == "configuration"]
    assert len(configs) > 1
    for r in configs:
        b = r["pairs"]["B"]
        assert len(b) == 6 and [b[i] for i in (1, 2, 3, 4)] == [0.0, 0.0, 0.0, 0.0]


def test_export_to_1996_refuses_a_generic_pair_no_named_pair_has(p105, tmp_path):
    """Flags t_x and r_z: AP242 writes it (exit 0), the 1996 layout cannot (exit 1, the pair
    named, nothing on stdout, -o left alone)."""
    src = _generic_source(tmp_path)
    assert p105("export", "--schema", "ap242", src).returncode == 0
    target = tmp_path / "out.stp"
    target.write_text("before")
    for schema in ("ap214", "p105"):
        got = p105("export", "--schema", schema, src, "-o", target)
        assert got.returncode == 1 and got.stdout == b""
        assert f"p105: error: {src}: #183: pair 'B': a low_order_kinematic_pair with t_x = TRUE".encode() in got.stderr
        assert target.read_text() == "before"


@pytest.mark.parametrize("name", ("four_bar_low_order_value", "four_bar_low_order_pair"))
def test_solve_to_model_writes_values_validate_passes(p105, tmp_path, name):
    """The results added to the model: a generic pair's values are low_order_kinematic_pair_value
    (revolute_pair_value applies to a revolute_pair only), the named pairs' their own; the file
    validates clean."""
    out = tmp_path / "solved.stp"
    got = p105("solve", "--to", "model", _defect(name), "-o", out)
    assert got.returncode == 0, got.stderr.decode()
    text = out.read_text()
    generic = name.endswith("_pair")  # pin B (#183) is the generic pair there
    added = re.findall(r"#\d+=(\w+)\('B',#183,", text)
    assert added and set(added) == ({"LOW_ORDER_KINEMATIC_PAIR_VALUE"} if generic else
                                    {"REVOLUTE_PAIR_VALUE", "LOW_ORDER_KINEMATIC_PAIR_VALUE"})
    check = p105("validate", out)
    assert check.returncode == 0, check.stdout.decode()
