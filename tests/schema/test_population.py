"""Schema profiles and the typed instance layer (p105cli.schema.profiles, .population).

Complex instances (the unit and context instances of the probes), the
Part 21 attribute order, USEDIN, types, derived and inverse attributes,
the JSON model as input, and a 9 MB real file."""

from __future__ import annotations

import functools
import io
from pathlib import Path

import pytest

from conftest import CORPUS
import p105cli.schema as schema_pkg
from p105cli.schema import SchemaError
from p105cli.schema.evaluator import INDETERMINATE, Agg, Evaluator
from p105cli.schema.population import Instance, Population
from p105cli.schema.profiles import (
    DATA_DIR, KNOWN_PROFILES, UnknownSchemaError, get_profile, profile_for_header,
)
from p105cli.step import read_json, read_step, write_json


@functools.cache
def evaluator(pop) -> Evaluator:
    """One evaluator per population, as the validator keeps one."""
    return Evaluator(pop)


def derived(inst, name):
    return evaluator(inst.pop).derived_value(inst, name)


def inverse(inst, name):
    return evaluator(inst.pop).inverse_value(inst, name)


def value(inst, name):
    return evaluator(inst.pop).attribute(inst, name)


AUTHORED = CORPUS / "authored"
# the read-only research probes of the shared corpus (examples/ may evolve)
AP214_PROBE = AUTHORED / "probe_p105_1996_ap214.stp"
AP242_PROBE = AUTHORED / "probe_occt_style.stp"
STAR_PROBE = AUTHORED / "probe_standard_star.stp"
BIG = CORPUS / "big" / "Molex_SlimStack_54722-0804_2x40_P0.50mm_Vertical.step"

AP242_NAME = "AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF"


def population(path: Path, profile=None) -> Population:
    if not path.is_file():
        pytest.skip(f"{path} not present")
    return Population(read_step(path.read_text(), str(path)), profile)


@pytest.fixture(scope="module")
def pop214():
    return population(AP214_PROBE)


@pytest.fixture(scope="module")
def pop242():
    return population(AP242_PROBE)


# --------------------------------------------------------------------------
# profiles


def test_known_profiles_and_shipped_schema_files():
    assert KNOWN_PROFILES == ("ap214", "ap242", "p105")
    for name in KNOWN_PROFILES:
        p = get_profile(name)
        assert p.name == name
        assert p.express_path.parent == DATA_DIR
        assert p.express_path.is_file(), p.express_path
    assert get_profile("AP242") is get_profile("ap242")


@pytest.mark.parametrize("schema,profile", [
    ("AUTOMOTIVE_DESIGN { 1 0 10303 214 3 1 1 }", "ap214"),
    ("AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }", "ap214"),
    ("AUTOMOTIVE_DESIGN", "ap214"),
    ("automotive_design_cc2 { 1 2 10303 214 -1 1 5 4 }", "ap214"),
    ("AUTOMOTIVE_DESIGN_CC2", "ap214"),
    (f"{AP242_NAME} {{ 1 0 10303 442 1 1 4 }}", "ap242"),
    (f"{AP242_NAME} {{ 1 0 10303 442 3 1 4 }}", "ap242"),
    (AP242_NAME, "ap242"),
    ("KINEMATIC_STRUCTURE_SCHEMA", "p105"),
])
def test_profile_for_header(schema, profile):
    assert profile_for_header({"file_schema": [schema]}).name == profile


def test_profile_for_header_combinations_and_override():
    both = {"file_schema": ["AUTOMOTIVE_DESIGN", "KINEMATIC_STRUCTURE_SCHEMA",
                            "KINEMATIC_MOTION_REPRESENTATION_SCHEMA"]}
    assert profile_for_header(both).name == "p105"
    extra = {"file_schema": ["AUTOMOTIVE_DESIGN", "SOME_OTHER_SCHEMA"]}
    assert profile_for_header(extra).name == "ap214"
    other = {"file_schema": ["CONFIG_CONTROL_DESIGN"]}
    assert profile_for_header(other, override="p105").name == "p105"
    with pytest.raises(UnknownSchemaError) as err:
        profile_for_header({"file_schema": ["AUTOMOTIVE_DESIGN", AP242_NAME]})
    assert "different profiles" in str(err.value)


@pytest.mark.parametrize("header", [{"file_schema": ["CONFIG_CONTROL_DESIGN"]}, {"file_schema": []},
                                    {}, {"file_schema": ["AP242_MANAGED_MODEL"]}])
def test_unknown_schema_lists_known_profiles(header):
    with pytest.raises(UnknownSchemaError) as err:
        profile_for_header(header)
    msg = str(err.value)
    for name in KNOWN_PROFILES:
        assert name in msg
    assert isinstance(err.value, LookupError)


def test_unknown_profile_name():
    with pytest.raises(UnknownSchemaError, match="known profiles: ap214, ap242, p105"):
        get_profile("ap203")
    with pytest.raises(UnknownSchemaError):
        profile_for_header({"file_schema": ["AUTOMOTIVE_DESIGN"]}, override="nope")


def test_p105_profile_patches_ap214_with_su_parameters():
    ap214 = get_profile("ap214").schema
    p105 = get_profile("p105").schema
    assert ap214 is not p105
    assert ap214.name == p105.name == "automotive_design"
    # AP214's long form has no su_parameters and rigid_placement selects one type
    assert "su_parameters" not in ap214.entities
    assert ap214.types["rigid_placement"].underlying.items == ["axis2_placement_3d"]
    # the 1996 Part 105 schema (5.3.1, 5.4.17)
    assert p105.types["rigid_placement"].underlying.items == ["axis2_placement_3d", "su_parameters"]
    su = p105.entity("su_parameters")
    assert su.supertypes == ["geometric_representation_item"]
    assert [(a.name, a.type.name) for a in su.attributes] == [
        ("a", "length_measure"), ("alpha", "plane_angle_measure"), ("b", "length_measure"),
        ("beta", "plane_angle_measure"), ("c", "length_measure"), ("gamma", "plane_angle_measure")]
    assert [w.label for w in su.where] == ["wr1"]
    assert p105.explicit_attribute_names("su_parameters") == ["name", "a", "alpha", "b", "beta",
                                                              "c", "gamma"]
    assert "su_parameters" in p105.all_subtypes("representation_item")
    assert p105.is_subtype("su_parameters", "geometric_representation_item")
    # same as AP242's declaration
    ap242 = get_profile("ap242").schema
    assert (p105.explicit_attribute_names("su_parameters")
            == ap242.explicit_attribute_names("su_parameters"))
    # the schema object is cached on the profile
    assert get_profile("p105").schema is p105


# --------------------------------------------------------------------------
# types and complex instances


def test_population_profile_from_header(pop214, pop242):
    assert pop214.profile.name == "ap214" and pop214.prefix == "AUTOMOTIVE_DESIGN."
    assert pop242.profile.name == "ap242" and pop242.prefix == AP242_NAME + "."
    assert len(pop214) == 19 and 19 in pop214 and 99 not in pop214
    with pytest.raises(KeyError):
        pop214.instance(99)


def test_complex_unit_instance(pop214):
    mm = pop214.instance(1)  # (LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.))
    assert mm.is_complex
    assert mm.leaf_types == {"length_unit", "si_unit"}
    assert {"length_unit", "si_unit", "named_unit"} <= mm.types
    assert mm.types == pop214.types_of(1)
    assert mm.get("prefix") == {"enum": "MILLI"}
    assert mm.get("name") == {"enum": "METRE"}
    assert mm.get("dimensions") == {"derived": True}
    # external mapping: each part carries its own attributes, in written order
    assert mm.explicit_names() == ["dimensions", "prefix", "name"]
    rad = pop214.instance(2)
    assert rad.get("prefix") is None and rad.get("name") == {"enum": "RADIAN"}
    # the derived dimensions (si_unit re-derives named_unit.dimensions)
    dims = derived(mm, "dimensions")
    assert dims.types == {"dimensional_exponents"}
    ev = evaluator(pop214)
    assert ev.attribute(dims, "length_exponent") == 1.0
    assert ev.attribute(dims, "mass_exponent") == 0.0
    with pytest.raises(SchemaError):
        mm.get("no_such_attribute")


def test_complex_context_instance(pop214):
    ctx = pop214.instance(4)
    assert ctx.leaf_types == {"geometric_representation_context", "global_unit_assigned_context"}
    assert "representation_context" in ctx.types
    assert ctx.get("context_identifier") == "ctx"
    assert ctx.get("context_type") == "3D"
    assert ctx.get("coordinate_space_dimension") == 3
    assert ctx.get("units") == [{"ref": 1}, {"ref": 2}, {"ref": 3}]
    units = value(ctx, "units")
    assert isinstance(units, Agg) and units.kind == "set"
    assert [u.id for u in units] == [1, 2, 3]
    assert all(isinstance(u, Instance) for u in units)
    # INVERSE representation_context.representations_in_context
    reps = inverse(ctx, "representations_in_context")
    assert sorted(r.id for r in reps) == [17, 18]


def test_complex_parts_in_any_order(pop214):
    text = AP214_PROBE.read_text().replace(
        "#1=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));",
        "#1=(SI_UNIT(.MILLI.,.METRE.)LENGTH_UNIT()NAMED_UNIT(*));")
    pop = Population(read_step(text))
    mm = pop.instance(1)
    assert mm.explicit_names() == ["prefix", "name", "dimensions"]
    assert mm.get("name") == {"enum": "METRE"}
    assert mm.leaf_types == {"length_unit", "si_unit"}


def test_types_of_simple_instances(pop214, pop242):
    t = pop242.types_of(15)  # REVOLUTE_PAIR
    assert {"revolute_pair", "low_order_kinematic_pair", "kinematic_pair",
            "geometric_representation_item", "representation_item",
            "item_defined_transformation"} <= t
    assert pop242.leaf_types_of(15) == {"revolute_pair"}
    assert pop214.types_of(14) == {"revolute_pair", "kinematic_pair", "item_defined_transformation"}
    assert pop242.types_of(10) >= {"kinematic_link", "vertex", "topological_representation_item",
                                   "representation_item"}
    assert pop214.types_of(10) == {"kinematic_link"}  # 1996: no supertype
    with pytest.raises(KeyError):
        pop214.types_of(1000)


def test_ids_of_type(pop214, pop242):
    assert pop214.ids_of_type("kinematic_link") == [10, 11]
    assert pop214.ids_of_type("named_unit") == [1, 2, 3]  # complex instances
    assert pop214.ids_of_type("si_unit", subtypes=False) == [1, 2, 3]
    assert pop214.ids_of_type("length_unit") == [1]
    assert pop214.ids_of_type("representation_context") == [4]
    assert pop214.ids_of_type("kinematic_pair") == [14]
    assert pop214.ids_of_type("kinematic_pair", subtypes=False) == []
    assert pop214.ids_of_type("REVOLUTE_PAIR", subtypes=False) == [14]
    assert pop214.ids_of_type("representation") == [17, 18]
    assert pop242.ids_of_type("representation_item")[:3] == [5, 6, 7]
    assert pop242.ids_of_type("no_such_entity") == []
    assert [i.id for i in pop214.instances_of("direction")] == [6, 7]


def test_p21_order_of_simple_instances(pop242):
    pair = pop242.instance(15)
    s = pop242.schema
    assert pair.explicit_names() == [a.name for a in s.p21_attributes("revolute_pair")]
    assert pair.explicit_names() == ["name", "name", "description", "transform_item_1",
                                     "transform_item_2", "joint", "t_x", "t_y", "t_z", "r_x",
                                     "r_y", "r_z"]
    assert pair.get("name") == "j1"  # the first (representation_item.name)
    assert pair.get("representation_item.name") == "j1"
    assert pair.get("item_defined_transformation.name") == "j1"
    assert pair.get("joint") == {"ref": 12}
    assert pair.get("r_z") == {"enum": "T"}
    assert pair.get("TRANSFORM_ITEM_1") == {"ref": 8}
    star = population(STAR_PROBE).instance(15)
    assert star.get("item_defined_transformation.name") == {"derived": True}
    assert star.get("r_z") == {"derived": True}
    assert star.get("description") is None


def test_derived_values_override_the_written_ones(pop242):
    # revolute_pair re-derives the freedoms: the written .T./.F. do not matter
    for pop in (pop242, population(STAR_PROBE)):
        pair = pop.instance(15)
        assert [derived(pair, a) for a in ("t_x", "t_y", "t_z", "r_x", "r_y", "r_z")] == [
            False, False, False, False, False, True]
        # kinematic_pair: item_defined_transformation.name := representation_item.name
        assert value(pair, "name") == "j1"
        assert derived(pair, "name") == "j1"
        assert [r.id for r in derived(pair, "associated_link_representations_1")] == [13]
        assert [r.id for r in derived(pair, "associated_link_representations_2")] == [14]


def test_record_and_offset(pop214):
    inst = pop214.instance(12)
    assert inst.record == {"id": 12, "type": "kinematic_joint", "args": [{"ref": 10}, {"ref": 11}]}
    text = AP214_PROBE.read_text()
    assert text[inst.offset:].startswith("#12=KINEMATIC_JOINT")
    assert inst.line_col[1] == 1
    assert pop214.instance(12) is inst  # cached
    assert repr(inst) == "#12=kinematic_joint"


# --------------------------------------------------------------------------
# USEDIN, inverse attributes


def test_usedin_roles(pop214, pop242):
    ids = lambda insts: [i.id for i in insts]  # noqa: E731
    assert ids(pop214.usedin(10, "AUTOMOTIVE_DESIGN.KINEMATIC_JOINT.FIRST_LINK")) == [12]
    assert ids(pop214.usedin(10, "AUTOMOTIVE_DESIGN.KINEMATIC_JOINT.SECOND_LINK")) == []
    assert ids(pop214.usedin(11, "automotive_design.kinematic_joint.second_link")) == [12]
    assert ids(pop214.usedin(8)) == [14, 17]
    assert ids(pop214.usedin(8, "AUTOMOTIVE_DESIGN.REPRESENTATION.ITEMS")) == [17]
    # a subtype named in the role, with the attribute inherited
    assert ids(pop214.usedin(8, "AUTOMOTIVE_DESIGN.KINEMATIC_LINK_REPRESENTATION.ITEMS")) == [17]
    assert ids(pop214.usedin(8, "AUTOMOTIVE_DESIGN.SHAPE_REPRESENTATION.ITEMS")) == []
    role = "AUTOMOTIVE_DESIGN.ITEM_DEFINED_TRANSFORMATION.TRANSFORM_ITEM_1"
    assert ids(pop214.usedin(8, role)) == [14]
    assert ids(pop214.usedin(14)) == [15, 16]
    assert pop214.usedin(19) == []
    assert pop214.usedin(10, "AUTOMOTIVE_DESIGN.KINEMATIC_JOINT.NO_SUCH") == []
    assert pop214.usedin(10, "AUTOMOTIVE_DESIGN.NO_SUCH.FIRST_LINK") == []
    # AP242: kinematic_joint is an edge; its links are edge_start/edge_end
    assert ids(pop242.usedin(10, f"{AP242_NAME}.KINEMATIC_JOINT.EDGE_START")) == [12]
    assert ids(pop242.usedin(10, f"{AP242_NAME}.EDGE.EDGE_START")) == [12]
    assert ids(pop242.usedin(10)) == [12, 13]
    # a reference inside an aggregate; one entry per (referrer, attribute)
    assert ids(pop242.usedin(12, f"{AP242_NAME}.REPRESENTATION.ITEMS")) == [17]
    assert pop242.roles_of(12) == {f"{AP242_NAME}.KINEMATIC_PAIR.JOINT",
                                   f"{AP242_NAME}.REPRESENTATION.ITEMS"}


def test_usedin_counts_each_role_once_per_referrer(pop214):
    text = AP214_PROBE.read_text().replace("#12=KINEMATIC_JOINT(#10,#11);",
                                           "#12=KINEMATIC_JOINT(#10,#10);")
    pop = Population(read_step(text))
    assert [i.id for i in pop.usedin(10)] == [12, 12]
    assert [i.id for i in pop.usedin(10, "AUTOMOTIVE_DESIGN.KINEMATIC_JOINT.FIRST_LINK")] == [12]
    assert pop.backrefs(10) == [(12, 0), (12, 1)]


def test_inverse_attributes(pop214, pop242):
    joint = pop214.instance(12)
    assert inverse(joint, "structure").id == 13  # single-valued inverse
    assert inverse(pop214.instance(17), "link_representation_relation") is INDETERMINATE
    pair = pop242.instance(15)
    inv = inverse(pair, "link_representation_associations")
    assert isinstance(inv, Agg) and inv.kind == "set" and [i.id for i in inv] == [16]
    with pytest.raises(SchemaError):
        inverse(pair, "joint")  # explicit, not inverse
    with pytest.raises(SchemaError):
        derived(pair, "no_such")


def test_derived_attributes(pop214, pop242):
    pair = pop214.instance(14)
    assert derived(pair, "pair_placement_in_first_link_context").id == 8
    assert derived(pair, "pair_placement_in_second_link_context").id == 9
    assert derived(pop214.instance(17), "link_frame").id == 4
    mech = pop242.instance(18)
    assert [j.id for j in derived(mech, "represented_joints")] == [12]
    state = pop242.instance(20)  # context_of_items derived from the mechanism
    assert derived(state, "context_of_items").id == 4
    assert derived(pop242.instance(8), "dim") == 3


# --------------------------------------------------------------------------
# the JSON model as input


def test_population_from_json_model(pop242):
    sf = read_step(AP242_PROBE.read_text())
    buf = io.StringIO()
    write_json(sf, buf)
    doc = read_json(buf.getvalue())
    pop = Population(doc)
    assert pop.profile.name == "ap242"
    assert pop.ids_of_type("kinematic_link") == [10, 11]
    assert pop.types_of(4) == pop242.types_of(4)
    assert pop.instance(4).get("units") == [{"ref": 1}, {"ref": 2}, {"ref": 3}]
    assert [i.id for i in pop.usedin(10)] == [12, 13]
    assert derived(pop.instance(15), "r_z") is True
    assert pop.instance(1).offset is None
    # and a plain list of records with an explicit profile
    pop2 = Population(doc.data, "ap242")
    assert pop2.instance(12).get("edge_end") == {"ref": 11}


def test_population_with_p105_profile():
    pop = population(AP214_PROBE, "p105")
    assert pop.profile.name == "p105"
    assert "su_parameters" in pop.schema.entities
    assert pop.ids_of_type("kinematic_link") == [10, 11]


# --------------------------------------------------------------------------
# a 9 MB real file


@pytest.mark.skipif(not BIG.is_file(), reason=f"{BIG} not present")
def test_big_file_population_and_ids_of_type():
    text = BIG.read_text()
    sf = read_step(text, str(BIG))
    pop = Population(sf)
    ids = pop.ids_of_type("cartesian_point")
    expected = [sf.index.ids[k] for k, t in enumerate(sf.index.types) if t == "cartesian_point"]
    assert ids == expected and len(ids) > 20000
    assert pop.profile.name == "ap214"
    # complex instances decoded only for their types
    assert len(pop.ids_of_type("named_unit")) >= 3
    p = pop.instance(ids[0])
    assert p.get("coordinates") and len(p.get("coordinates")) == 3
    assert evaluator(pop).where_rule(p, "geometric_representation_item", "wr1") is True


# --------------------------------------------------------------------------
# the population knows nothing of the evaluator


def _imported_modules(path: Path) -> set:
    """Every module a source file imports, at the top or inside a function (relative ones resolved)."""
    import ast
    root = Path(schema_pkg.__file__).parents[2]            # the directory holding p105cli/
    package = list(path.parent.relative_to(root).parts)    # e.g. p105cli, schema, evaluator
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            mod = ".".join(base + ([node.module] if node.module else []))
            out.add(mod)
            out.update(f"{mod}.{a.name}" for a in node.names)
    return out


def test_no_import_between_population_and_evaluator():
    """The evaluator is given a population; neither imports the other, not even lazily."""
    schema_dir = Path(schema_pkg.__file__).parent
    for name in ("population.py", "instance.py"):
        mods = _imported_modules(schema_dir / name)
        assert not any(m.startswith("p105cli.schema.evaluator") for m in mods), (name, mods)
    evaluator_files = sorted((schema_dir / "evaluator").glob("*.py"))
    assert len(evaluator_files) > 5
    for path in evaluator_files:
        mods = _imported_modules(path)
        assert "p105cli.schema.instance" in mods or path.name in (
            "__init__.py", "core.py", "scope.py", "compiled.py"), (path.name, mods)
        assert not any(m.startswith("p105cli.schema.population") for m in mods), (path.name, mods)
