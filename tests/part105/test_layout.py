"""part105/layout.py: one walk of each layout and THE link names, used by every command.

The bug it fixes (issue 10): two links sharing a name, or a link without any name, were named
one way by the mechanism reader (``graph``) and another by the motion reader (``interpolate``),
so ``solve --program`` found the path on no link and exited 2.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from p105cli.cli import main
from p105cli.part105 import layout
from p105cli.part105.model_file import ModelFile
from p105cli.step import read_step

ROOT = Path(__file__).resolve().parents[2]
FOUR_BAR = ROOT / "examples" / "four_bar_ap242.stp"


def _variant(tmp_path, name: str, edits: dict) -> Path:
    text = FOUR_BAR.read_text()
    for old, new in edits.items():
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / f"{name}.stp"
    path.write_text(text)
    return path


VARIANTS = {
    # the rocker renamed: two links called 'coupler'
    "shared": {"#132=KINEMATIC_LINK('rocker');": "#132=KINEMATIC_LINK('coupler');"},
    # the coupler (the link the path moves) without any name
    "blank": {"#131=KINEMATIC_LINK('coupler');": "#131=KINEMATIC_LINK('');",
              "#178=RIGID_LINK_REPRESENTATION('coupler',": "#178=RIGID_LINK_REPRESENTATION('',"},
}
EXPECTED = {"shared": {129: "frame", 130: "crank", 131: "coupler #131", 132: "coupler #132"},
            "blank": {129: "frame", 130: "crank", 131: "#131", 132: "rocker"}}


def _run(args, capsys) -> tuple:
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def test_the_example_keeps_its_names():
    mf = ModelFile.of(read_step(FOUR_BAR.read_text(), str(FOUR_BAR)))
    (ml,) = layout.mechanisms(mf)
    assert ml.link_names == {129: "frame", 130: "crank", 131: "coupler", 132: "rocker"}
    assert ml.base == 129 and [p.id for p in ml.pairs] == sorted(p.id for p in ml.pairs)
    assert layout.mechanisms(mf) is layout.mechanisms(mf)  # walked once per file
    assert layout.link_name_of_representation(mf, 178) == "coupler"


def test_unique_names():
    assert layout.unique_names({1: "a", 2: "b", 3: "a"}) == {1: "a #1", 2: "b", 3: "a #3"}


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_one_name_for_a_link_everywhere(tmp_path, capsys, variant):
    path = _variant(tmp_path, variant, VARIANTS[variant])
    mf = ModelFile.of(read_step(path.read_text(), str(path)))
    (ml,) = layout.mechanisms(mf)
    assert ml.link_names == EXPECTED[variant]
    moved = EXPECTED[variant][131]  # the path moves the coupler, #131 (representation #178)

    code, out, _ = _run(["graph", path], capsys)
    assert code == 0
    assert {ln["id"]: ln["name"] for ln in json.loads(out)["links"]} == EXPECTED[variant]

    code, out, _ = _run(["interpolate", path], capsys)
    assert code == 0
    frames = [r for r in map(json.loads, out.splitlines()) if r["type"] == "frame"]
    assert frames and {r["link"] for r in frames} == {moved}

    code, out, err = _run(["solve", "--program", "--count", "3", path], capsys)
    assert code == 0, err
    assert out.strip()


def test_validate_warns_about_links_sharing_a_name(tmp_path, capsys):
    path = _variant(tmp_path, "shared", VARIANTS["shared"])
    code, out, _ = _run(["validate", path], capsys)
    found = [line for line in out.splitlines() if "[KIN-LINK-NAME]" in line]
    assert len(found) == 1 and "#132" in found[0] and "'coupler'" in found[0] and "warning" in found[0]
    assert code == 0  # a warning, not an error
    code, out, _ = _run(["validate", FOUR_BAR], capsys)
    assert "KIN-LINK-NAME" not in out


def test_the_rule_is_listed(capsys):
    code, out, _ = _run(["validate", "--list-rules"], capsys)
    assert code == 0 and re.search(r"^KIN-LINK-NAME\b", out, re.M)


@pytest.mark.parametrize("path", [FOUR_BAR, ROOT / "tests" / "data" / "corpus" / "four_bar_ap214.stp"],
                         ids=["ap242", "ap214"])
def test_pair_frames_are_the_frames_of_the_pairs_on_each_link(path):
    # built once for all links (a 10,000-pair chain asked each link for them: n^2); the frames a
    # link's pairs are placed at, and link_frames gives the link's other placements
    mf = ModelFile.of(read_step(path.read_text(), str(path)))
    (ml,) = layout.mechanisms(mf)
    for link in ml.links:
        want = {p.frame_1 for p in ml.pairs if p.link1 == link} | {p.frame_2 for p in ml.pairs if p.link2 == link}
        assert ml.pair_frames(link) == want and want
        assert not set(layout.link_frames(mf, ml, link).values()) & want
