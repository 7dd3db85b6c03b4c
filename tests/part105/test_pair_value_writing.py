"""part105.pair_values, writing direction: the value entity and its arguments per layout.

Independent truth: the EXPRESS long forms (the Part 21 attribute order of each written
``*_pair_value`` entity in AP214 and AP242) and a corpus file's own text.
"""

from __future__ import annotations

import re

import pytest

from conftest import ROOT
from p105cli.part105.catalogue import PROFILES
from p105cli.part105.emit import SUPPORTED_KINDS
from p105cli.part105.model_file import ModelFile
from p105cli.part105.pair_values import scalar_values, value_arguments, value_attributes, value_entity
from p105cli.schema.population import Population
from p105cli.step import read_step

WRITTEN = [k for k in SUPPORTED_KINDS if k != "fully_constrained"]  # no value entity


@pytest.mark.parametrize("profile", ["ap214", "ap242"])
@pytest.mark.parametrize("kind", WRITTEN)
def test_the_arguments_follow_the_schema_order_of_the_value_entity(profile, kind):
    layout = PROFILES[profile]["layout"]
    if kind == "low_order" and layout == "1996":
        pytest.skip("the generic low-order pair is AP242's only (the 1996 writers refuse it)")
    slots = Population([], profile).layout_for(value_entity(kind)).slots
    assert slots, f"{value_entity(kind)} is not an entity of {profile}"
    own = [s for s in slots if s.entity not in ("representation_item", "pair_value")]
    args = value_arguments(layout, "NAME", "PAIR", ["V"] * len(own))
    assert len(args) == len(slots)
    names = [f"{s.entity}.{s.name}" for s in slots]
    assert names[args.index("PAIR")] == "pair_value.applies_to_pair"
    if layout == "ap242":
        assert names[args.index("NAME")] == "representation_item.name"
    else:
        assert "NAME" not in args


def test_scalar_values_convert_each_value_by_its_unit():
    assert scalar_values("ALA", [1.0, 2.0, 3.0], lambda x: ("a", x), lambda x: ("l", x)) == \
        [("a", 1.0), ("l", 2.0), ("a", 3.0)]


def test_value_attributes_are_the_file_units_after_the_pair():
    path = ROOT / "tests" / "data" / "corpus" / "cam_follower_ap214.stp"
    text = path.read_text()
    curve = re.search(r"^#(\d+)=POINT_ON_PLANAR_CURVE_PAIR_VALUE\(#(\d+),#(\d+),YPR_ROTATION\(\(([^)]*)\)\)\);$",
                      text, re.M)
    prism = re.search(r"^#(\d+)=PRISMATIC_PAIR_VALUE\(#(\d+),([^)]*)\);$", text, re.M)
    assert curve and prism
    mf = ModelFile(read_step(text, str(path)), "ap214")
    pair, own = value_attributes(mf, int(curve[1]))
    assert pair == int(curve[2])
    assert own == [{"ref": int(curve[3])}, {"type": "YPR_ROTATION", "value": [float(x) for x in curve[4].split(",")]}]
    assert value_attributes(mf, int(prism[1])) == (int(prism[2]), [float(prism[3])])
