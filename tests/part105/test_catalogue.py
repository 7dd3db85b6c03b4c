"""part105/catalogue.py: the standard's vocabulary as data, checked against the EXPRESS."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from p105cli.kinematics.pairs import PAIR_KINDS, PAIRS, VALUE_UNITS
from p105cli.part105 import catalogue as c
from p105cli.schema.profiles import get_profile

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def schemas():
    return {name: get_profile(name).schema for name in ("ap214", "ap242")}


def test_kinematic_entities_exist_in_a_long_form(schemas):
    known = set(schemas["ap214"].entities) | set(schemas["ap242"].entities)
    assert c.KINEMATIC_ENTITIES <= known
    assert "configuration_definition" in c.KINEMATIC_ENTITIES  # Part 105:1996, in AP214's long form
    assert len(c.KINEMATIC_ENTITIES) == 139


def test_pair_entities_both_ways(schemas):
    for entity, t in PAIRS.items():
        assert c.pair_kind_of_entity(entity) == t.kind
        layouts = [lay for lay, s in (("1996", "ap214"), ("ap242", "ap242")) if entity in schemas[s].entities]
        assert layouts, entity
        written = {c.pair_entity(t.kind, lay, w) for lay in layouts for w in (False, True)}
        assert entity in written
    for entity, kind in c.HIGHER_PAIR_ENTITIES.items():
        assert c.pair_kind_of_entity(entity) == kind
        assert kind in PAIR_KINDS
    assert c.pair_kind_of_entity("kinematic_link") is None
    assert c.pair_entity("revolute", "1996", True) == "revolute_pair"
    assert c.range_entity("revolute") in schemas["ap214"].entities


def test_higher_pair_geometry_attributes_are_the_pairs(schemas):
    for kind, spec in c.HIGHER_PAIR_GEOMETRY.items():
        schema = schemas["ap242"]
        names, todo = set(), [f"{kind}_pair"]
        while todo:  # the attributes of the pair entity and its supertypes
            ent = schema.entities[todo.pop()]
            names |= {a.name for a in ent.attributes}
            todo.extend(ent.supertypes)
        for attr, key, which in spec:
            assert key in PAIR_KINDS[kind].param_names and which in (1, 2)
            assert attr in names
        assert ("orientation" in PAIR_KINDS[kind].param_names) == (kind in c.HIGHER_PAIR_ORIENTATION) or \
            kind == "point_on_planar_curve"


def test_limits_cover_every_limit_of_the_schemas():
    suffixes = set()
    for name in ("kinematics_subset_AP214E3_P105_1996.exp", "kinematics_subset_AP242_N10962.exp"):
        path = ROOT.parent / "shared" / "schema" / name
        if not path.exists():
            pytest.skip("shared schema subsets not present")
        suffixes |= set(re.findall(r"lower_limit_([a-z_0-9]+)", path.read_text().lower()))
    assert suffixes == set(c.LIMITS)
    for suffix, lim in c.LIMITS.items():
        value = c.YPR_NAMES[lim.ypr_index] if lim.ypr_index is not None else lim.value_attribute
        assert VALUE_UNITS[value] == lim.unit
        assert c.limit_attributes(value) == (f"lower_limit_{suffix}", f"upper_limit_{suffix}")
    assert c.limit_attributes("point_parameter") is None


def test_range_on_values_are_pair_values():
    for attr, r in c.RANGE_ON.items():
        assert attr.startswith("range_on_")
        for v in r.values:
            assert VALUE_UNITS[v] == "P"
    assert c.range_on_values("range_on_surface_1", "rolling_surface") == ("point_parameter_u", "point_parameter_v")
    assert c.range_on_values("range_on_surface_1", "sliding_surface") == ("point_parameter_u_1", "point_parameter_v_1")


def test_choose_profile():
    assert c.choose_profile("ap214", True) == "p105"
    assert c.choose_profile("ap214", False) == "ap214"
    assert c.choose_profile("ap242", True) == "ap242"
    assert c.choose_profile("p105", False) == "p105"


def test_higher_pair_values_are_the_value_entities_attributes(schemas):
    schema = schemas["ap242"]
    for kind, spec in c.HIGHER_PAIR_VALUES.items():
        ent = schema.entities[f"{kind}_pair_value"]
        names = {a.name for a in ent.attributes}
        n = 0
        for attr, family, key in spec:
            assert attr in names
            assert family in ("point", "ypr", "A")
            if family == "point":
                assert key in {k for _a, k, _w in c.HIGHER_PAIR_GEOMETRY[kind]}
                n += 1 if key.startswith("curve") else 2
            else:
                n += 3 if family == "ypr" else 1
        assert n == len(PAIR_KINDS[kind].value_names)  # the model's values, in order
