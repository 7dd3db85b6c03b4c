"""The evaluator's speed-ups give the plain interpreter's answers: the Python
``using_representations`` (natives.py), the type-only facts compiled once per schema
(compiled.py) and the population's type index."""

from __future__ import annotations

import pytest

from conftest import EXAMPLES, SHARED
from p105cli.schema.evaluator import Evaluator
from p105cli.schema.evaluator.compiled import compiled_for
from p105cli.schema.population import Population
from p105cli.schema.evaluator.scope import _MISSING as Missing
from p105cli.schema.profiles import get_profile
from p105cli.step import read_step

B3D = SHARED / "external" / "build123d" / "b3d_revolute.stp"
needs_b3d = pytest.mark.skipif(not B3D.exists(), reason="../shared/external/build123d not present")

AP242_HEADER = ("ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n"
                "FILE_NAME('t.stp','',(''),(''),'','','');\n"
                "FILE_SCHEMA(('AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF { 1 0 10303 442 1 1 4 }'));\n"
                "ENDSEC;\n")


def _pop(text: str) -> Population:
    return Population(read_step(text, "t.stp"))


def _ids(agg) -> list:
    return [x.id for x in agg]


@needs_b3d
def test_native_using_representations_is_the_express_function_in_the_same_order():
    pop = _pop(B3D.read_text())
    fast, plain = Evaluator(pop), Evaluator(pop, natives=False)
    items = pop.ids_of_type("cartesian_point") + pop.ids_of_type("direction") + pop.ids_of_type("edge_curve")
    assert len(items) > 200
    several = 0
    for iid in items[::3]:
        inst = pop.instance(iid)
        got = fast.call("using_representations", inst)
        assert _ids(got) == _ids(plain.call("using_representations", inst)), iid
        assert got.kind == "set"
        several += len(got) > 1
    assert several  # some items are used by more than one representation


def test_a_reference_cycle_among_items_is_left_to_the_interpreter():
    # #1 and #2 use each other; both sit in representation #3 (and #2 in #5)
    text = AP242_HEADER + """DATA;
#1=GEOMETRIC_CURVE_SET('a',(#2));
#2=GEOMETRIC_CURVE_SET('b',(#1));
#3=REPRESENTATION('r',(#1),#4);
#4=REPRESENTATION_CONTEXT('c','t');
#5=REPRESENTATION('s',(#2),#4);
#6=CARTESIAN_POINT('p',(0.,0.,0.));
#7=GEOMETRIC_CURVE_SET('d',(#6));
#8=REPRESENTATION('u',(#7),#4);
ENDSEC;
END-ISO-10303-21;
"""
    pop = _pop(text)
    fast, plain = Evaluator(pop), Evaluator(pop, natives=False)
    for iid in (1, 2, 6, 7):
        inst = pop.instance(iid)
        assert _ids(fast.call("using_representations", inst)) == \
            _ids(plain.call("using_representations", inst)), iid
    assert sorted(_ids(fast.call("using_representations", pop.instance(1)))) == [3, 5]
    assert _ids(fast.call("using_representations", pop.instance(6))) == [8]


def test_type_only_parameters_and_queries_are_found_conservatively():
    schema = get_profile("ap242").schema
    compiled = compiled_for(schema)
    assert compiled is compiled_for(schema)  # once per schema
    assert compiled.type_only_parameters(schema.functions["type_check_function"]) == frozenset({0})
    # these look at their argument's attributes or users, not only its type
    assert compiled.type_only_parameters(schema.functions["dimension_of"]) == frozenset()
    assert compiled.type_only_parameters(schema.functions["using_representations"]) == frozenset()
    rule = schema.rules["subtype_exclusiveness_representation_item"]
    query = rule.where[0].expr.left.args[0]
    assert compiled.query_type_only(query, None)


@pytest.mark.parametrize("name", ["four_bar_ap242.stp", "slider_crank_p105_1996_ap214.stp"])
def test_global_rules_give_the_plain_interpreters_results(name):
    pop = _pop((EXAMPLES / name).read_text())
    fast = Evaluator(pop)
    plain = Evaluator(pop, memoize=False, natives=False)
    rules = pop.schema.rules
    checked = 0
    for rname in sorted(rules):
        if not any(pop.ids_of_type(e) for e in rules[rname].applies_to):
            continue
        assert fast.global_rule(rules[rname]) == plain.global_rule(rules[rname]), rname
        checked += 1
    assert checked > 10


def test_where_rules_of_every_instance_give_the_plain_interpreters_results():
    pop = _pop((EXAMPLES / "four_bar_ap242.stp").read_text())
    fast = Evaluator(pop)
    plain = Evaluator(pop, memoize=False, natives=False)
    for inst in pop.instances():
        assert fast.check_instance(inst) == plain.check_instance(inst), inst


@pytest.mark.parametrize("name", ["four_bar_ap242.stp", "slider_crank_p105_1996_ap214.stp"])
def test_type_extents_from_the_index_are_a_scan_of_the_population(name):
    pop = _pop((EXAMPLES / name).read_text())
    for entity in ("representation_item", "cartesian_point", "kinematic_pair", "named_unit",
                   "representation", "si_unit", "no_such_entity"):
        for subtypes in (True, False):
            scan = [i for i in pop.ids()
                    if entity in (pop.types_of(i) if subtypes else pop.leaf_types_of(i))]
            assert pop.ids_of_type(entity, subtypes) == scan, (entity, subtypes)
    assert pop.ids_of_type("named_unit")  # complex unit instances are found


def test_aggregate_operators_on_instances_count_occurrences_by_identity():
    from p105cli.schema import parse_schema
    from p105cli.schema.evaluator import Agg
    pop = _pop((EXAMPLES / "four_bar_ap242.stp").read_text())
    ev = Evaluator(pop)
    a, b, c = (pop.instance(i) for i in pop.ids_of_type("cartesian_point")[:3])

    def run(text, **variables):
        s = parse_schema(f"SCHEMA x; CONSTANT k : GENERIC := {text}; END_CONSTANT; END_SCHEMA;")
        return ev.eval(s.constants["k"].value, variables=variables)

    assert list(run("p - q", p=Agg("bag", [a, b, b, c, b]), q=Agg("bag", [b, b]))) == [a, c, b]
    assert list(run("p - q", p=Agg("set", [a, b, c]), q=Agg("set", [c, a]))) == [b]
    assert list(run("p * q", p=Agg("bag", [a, b, b, c]), q=Agg("bag", [b, c, b, b]))) == [b, b, c]
    assert list(run("p * q", p=Agg("set", [c, b, a]), q=Agg("bag", [a, c]))) == [c, a]
    assert run("p IN q", p=b, q=Agg("set", [a, c])) is False
    assert run("p IN q", p=b, q=Agg("set", [a, "b", b])) is True
    assert list(run("p + q", p=Agg("set", [a, b]), q=Agg("set", [b, c, a]))) == [a, b, c]
    assert list(run("p + q", p=Agg("set", [a, b]), q=c)) == [a, b, c]
    assert list(run("p + q", p=Agg("set", [a, b]), q=b)) == [a, b]
    # with a simple value among them the value comparison still applies
    assert list(run("p - q", p=Agg("bag", [a, 1, 2.0]), q=Agg("bag", [2, a]))) == [1]
    # strings (TYPEOF against a long form's list of type names) match by value, occurrences counted
    assert list(run("p * q", p=Agg("bag", ["x", "y", "y", "z"]), q=Agg("bag", ["y", "z", "y", "y"]))) \
        == ["y", "y", "z"]
    assert list(run("p * q", p=Agg("set", ["z", "y", "x"]), q=Agg("set", ["x", "z"]))) == ["z", "x"]
    assert list(run("p - q", p=Agg("bag", ["x", "y", "y", "z", "y"]), q=Agg("bag", ["y", "y"]))) \
        == ["x", "z", "y"]
    assert list(run("p - q", p=Agg("bag", ["x", "y"]), q="y")) == ["x"]
    assert list(run("p * q", p=Agg("set", ["a", "B"]), q=Agg("set", ["b", "A"]))) == []  # case counts
    assert list(run("p * q", p=Agg("set", ["a", 1]), q=Agg("set", [1, "a"]))) == ["a", 1]
    assert run("SIZEOF(['P.A', 'P.B', 'P.C'] * TYPEOF(p))", p=a) == 0


def _compatible_dimension(pop, **kw):
    return Evaluator(pop, **kw).global_rule(pop.schema.rules["compatible_dimension"])


@needs_b3d
def test_native_check_geometric_dimension_with_parametric_contexts():
    # build123d/OCCT files hold 2D parametric contexts: the rule goes through
    # using_representations for every point and direction
    text = B3D.read_text()
    assert "PARAMETRIC_REPRESENTATION_CONTEXT" in text
    pop = _pop(text)
    assert _compatible_dimension(pop) == _compatible_dimension(pop, natives=False) == {"wr1": True}
    # a 3D point written with two coordinates in a 3D representation breaks it
    import re
    m = re.search(r"^#(\d+) = CARTESIAN_POINT\('',\(([^,]+),([^,]+),([^)]+)\)\);$", text, re.M)
    assert m
    broken = text.replace(m.group(0), f"#{m.group(1)} = CARTESIAN_POINT('',({m.group(2)},{m.group(3)}));")
    pop = _pop(broken)
    assert _compatible_dimension(pop) == _compatible_dimension(pop, natives=False) == {"wr1": False}


def test_native_check_geometric_dimension_with_one_dimensionality():
    text = (EXAMPLES / "four_bar_ap242.stp").read_text()
    pop = _pop(text)
    assert _compatible_dimension(pop) == _compatible_dimension(pop, natives=False) == {"wr1": True}
    broken = _pop(text.replace("DIRECTION('',(0.,0.,1.));", "DIRECTION('',(0.,1.));", 1))
    assert _compatible_dimension(broken) == _compatible_dimension(broken, natives=False) == {"wr1": False}


def test_peek_reads_an_attribute_as_get_does_without_keeping_the_record():
    text = (EXAMPLES / "four_bar_ap242.stp").read_text()
    pop, reference = _pop(text), _pop(text)
    for iid in pop.ids_of_type("cartesian_point") + pop.ids_of_type("direction"):
        for attr in ("name", "coordinates", "direction_ratios"):
            try:
                expected = reference.instance(iid).get(attr)
            except Exception as err:  # not an attribute of this entity: the same refusal
                with pytest.raises(type(err)):
                    pop.peek(iid, attr)
                continue
            assert pop.peek(iid, attr) == expected
            if attr == "name":
                assert iid not in pop._instances  # nothing kept


def _value_form(v):
    """An evaluator value spelled out completely (kinds, bounds, defined types, the parts and
    types of entity values, instance ids), so that two values compare equal only when every
    detail is the same; floats by their exact repr (0.0 and -0.0 differ)."""
    from p105cli.schema.evaluator import Agg, EntityValue, TypedValue
    from p105cli.schema.instance import Instance
    if type(v) is Agg:
        return ("agg", v.kind, v.lo, v.dtypes, v.bounds, [_value_form(x) for x in v])
    if type(v) is EntityValue:
        return ("entity", sorted(v.types), sorted(v.leaf_types),
                [(k, [(n, _value_form(x)) for n, x in a.items()]) for k, a in v.parts.items()])
    if type(v) is TypedValue:
        return ("typed", v.dtypes, _value_form(v.value))
    if type(v) is Instance:
        return ("instance", v.id)
    if type(v) is float:
        return ("float", repr(v))
    return (type(v).__name__, repr(v))


def _directions():
    """Direction ratios for cross_product: random 3D ones, parallel and anti-parallel pairs,
    zero vectors, 2D ones, tiny and huge components (underflow and overflow of the sum of
    squares), negative zeros and integers."""
    import random
    rng = random.Random(105)
    out = [(0., 0., 1.), (1., 0., 0.), (0., 1., 0.), (0., 0., -1.), (2., 0., 0.), (0., 0., 0.),
           (-0., 0., 1.), (1., 0.), (0., 1.), (0., 0.), (1e-200, 0., 0.), (1e200, 1e200, 0.),
           (1e-160, 1e-160, 1e-160), (3, 4, 0), (0.6, 0.8, 0.), (-0.6, -0.8, -0.)]
    for _ in range(40):
        out.append(tuple(rng.choice((rng.uniform(-5, 5), 0.0, rng.randint(-2, 2) * 1.0))
                         for _ in range(3)))
    out.append(tuple(2.5 * x for x in out[-1]))  # parallel to the one before
    return out


def _real(x) -> str:
    """A Part 21 real (``1.E-200``), or an integer as written."""
    if not isinstance(x, float):
        return str(x)
    mantissa, _, exponent = repr(x).upper().partition("E")
    if "." not in mantissa:
        mantissa += "."
    return mantissa + ("E" + exponent if exponent else "")


@pytest.mark.parametrize("profile", ["ap242", "ap214"])
def test_native_cross_product_is_the_express_function_on_many_directions(profile):
    dirs = _directions()
    header = AP242_HEADER if profile == "ap242" else AP242_HEADER.replace(
        "AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF { 1 0 10303 442 1 1 4 }",
        "AUTOMOTIVE_DESIGN { 1 0 10303 214 3 1 1 1 }")
    lines = [f"#{i}=DIRECTION('d',({','.join(_real(x) for x in d)}));"
             for i, d in enumerate(dirs, 1)]
    lines.append(f"#{len(dirs) + 1}=CARTESIAN_POINT('p',(0.,0.,0.));")
    pop = _pop(header + "DATA;\n" + "\n".join(lines) + "\nENDSEC;\nEND-ISO-10303-21;\n")
    assert pop.schema.name.lower().startswith("automotive" if profile == "ap214" else "ap242")
    fast, plain = Evaluator(pop, memoize=False), Evaluator(pop, memoize=False, natives=False)
    args = [pop.instance(i) for i in range(1, len(dirs) + 2)]
    natively = 0
    for a in args:
        for b in args:
            got = fast.call("cross_product", a, b)
            assert _value_form(got) == _value_form(plain.call("cross_product", a, b)), (a.id, b.id)
            natively += fast._cross_product(pop.schema.functions["cross_product"], [a, b]) \
                is not Missing
    assert natively > len(args) ** 2 // 2  # most pairs take the Python path


def test_native_cross_product_results_decide_axis2_placement_3d_wr4():
    # parallel axes break WR4; a 2D direction leaves it UNKNOWN (?); others pass
    text = AP242_HEADER + """DATA;
#1=CARTESIAN_POINT('',(0.,0.,0.));
#2=DIRECTION('',(0.,0.,1.));
#3=DIRECTION('',(1.,0.,0.));
#4=DIRECTION('',(0.,0.,-3.));
#5=DIRECTION('',(1.,0.));
#6=AXIS2_PLACEMENT_3D('',#1,#2,#3);
#7=AXIS2_PLACEMENT_3D('',#1,#2,#4);
#8=AXIS2_PLACEMENT_3D('',#1,#2,#5);
ENDSEC;
END-ISO-10303-21;
"""
    pop = _pop(text)
    fast, plain = Evaluator(pop), Evaluator(pop, memoize=False, natives=False)
    got = [fast.where_rule(pop.instance(i), "axis2_placement_3d", "wr4") for i in (6, 7, 8)]
    assert got == [plain.where_rule(pop.instance(i), "axis2_placement_3d", "wr4") for i in (6, 7, 8)]
    assert got == [True, False, None]


@pytest.mark.parametrize("profile", ["ap242", "ap214"])
def test_native_dimension_of_is_the_express_function(profile):
    header = AP242_HEADER if profile == "ap242" else AP242_HEADER.replace(
        "AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF { 1 0 10303 442 1 1 4 }",
        "AUTOMOTIVE_DESIGN { 1 0 10303 214 3 1 1 1 }")
    text = header + """DATA;
#1=CARTESIAN_POINT('',(0.,0.,0.));
#2=CARTESIAN_POINT('',(1.,2.));
#3=CARTESIAN_POINT('',(5.));
#4=DIRECTION('',(0.,0.,1.));
#5=DIRECTION('',(0.,1.));
#6=DIRECTION('',(0.,0.,0.));
#7=VECTOR('',#4,2.);
#8=AXIS2_PLACEMENT_3D('',#1,#4,$);
#9=(GEOMETRIC_REPRESENTATION_CONTEXT(2)REPRESENTATION_CONTEXT('c','t'));
#10=REPRESENTATION('r',(#8,#11),#9);
#11=AXIS2_PLACEMENT_2D('',#2,#5);
#12=CARTESIAN_POINT('',$);
#13=DIRECTION('',(0.,0.,1.,0.));
ENDSEC;
END-ISO-10303-21;
"""
    pop = _pop(text)
    fast, plain = Evaluator(pop, memoize=False), Evaluator(pop, memoize=False, natives=False)
    f = pop.schema.functions["dimension_of"]
    natively = []
    for iid in range(1, 14):
        if iid in (9, 10):
            continue
        inst = pop.instance(iid)
        got = fast.call("dimension_of", inst)
        assert _value_form(got) == _value_form(plain.call("dimension_of", inst)), iid
        if fast._dimension_of(f, [inst]) is not Missing:
            natively.append(iid)
    assert natively == [1, 2, 3, 4, 5, 6, 13]
    assert [_value_form(fast.call("dimension_of", pop.instance(i)))[2] for i in (1, 2, 3, 8, 11)] \
        == [("int", "3"), ("int", "2"), ("int", "1"), ("int", "2"), ("int", "2")]


@pytest.mark.parametrize("edit", [
    None,
    ("'crank-coupler pin',#149,#153,#134,", "'crank-coupler pin',#149,#153,#133,"),  # a joint twice
    ("'coupler-rocker pin',#157,#161,#135,", "'coupler-rocker pin',#157,#161,$,"),  # no joint: ?
    ("#190=MECHANISM_REPRESENTATION('four_bar',(#186,#187,#188,#189)",
     "#190=MECHANISM_REPRESENTATION('four_bar',(#189,#186,#189,#188)"),  # order, a pair twice
])
def test_native_collect_joints_is_the_express_function(edit):
    text = (EXAMPLES / "four_bar_ap242.stp").read_text()
    if edit:
        assert edit[0] in text
        text = text.replace(edit[0], edit[1])
    pop = _pop(text)
    fast, plain = Evaluator(pop, memoize=False), Evaluator(pop, memoize=False, natives=False)
    mech = pop.instance(190)
    items = fast.attribute(mech, "items")
    got = fast.call("collect_joints", items)
    assert _value_form(got) == _value_form(plain.call("collect_joints", plain.attribute(mech, "items")))
    native = fast._collect_joints(pop.schema.functions["collect_joints"], [items])
    assert (native is Missing) == (edit is not None and "$" in edit[1])
    expected = {None: [133, 134, 135, 136], 1: [133, 135, 136], 3: [136, 133, 135]}
    if native is not Missing:
        index = None if edit is None else (1 if "#133," in edit[1] else 3)
        assert [j.id for j in got] == expected[index]
    assert fast.where_rule(mech, "mechanism_representation", "wr1") == \
        plain.where_rule(mech, "mechanism_representation", "wr1")
