"""KIN-* checks (p105cli.rules.kinematics): a failing file and its passing twin per rule.

The fixtures are the shared research probes (``probe_p105_1996_ap214.stp``,
``probe_standard_star.stp``) copied here as instance tables and completed
into mechanisms (1996: kinematic_link_representation_relation, product,
kinematic_property_definition, mechanism, initial_state; AP242: the probe
as is), with a second context for the arm link so that the two links of a
mechanism can disagree. Each test edits a copy: ``make(layout, {id: text})``
replaces, adds (new id) or drops (``None``) instances. The generated corpus
and the big geometry files are checked too, when present.
"""

from __future__ import annotations

import math
import os
import re
import time
from pathlib import Path

import pytest

from p105cli.rules.kinematics import RULES, check_kinematics, context_units
from p105cli.schema.evaluator import Evaluator
from p105cli.schema.population import Population
from p105cli.step import read_step

ROOT = Path(__file__).resolve().parents[2]
SHARED = Path(os.environ.get("P105_SHARED", ROOT.parent / "shared"))
CORPUS_DIR = ROOT / "tests" / "data" / "corpus"
BIG_DIR = SHARED / "corpus" / "big"

DEG = math.pi / 180.0

HEAD_1996 = "AUTOMOTIVE_DESIGN { 1 0 10303 214 3 1 1 }"
HEAD_242 = "AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF { 1 0 10303 442 1 1 4 }"

# Shared by both layouts: units, contexts (#4 base link, #40 arm link), frames.
COMMON = {
    1: "(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.))",
    2: "(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.))",
    3: "(NAMED_UNIT(*)SI_UNIT($,.STERADIAN.)SOLID_ANGLE_UNIT())",
    4: "(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNIT_ASSIGNED_CONTEXT((#1,#2,#3))"
       "REPRESENTATION_CONTEXT('ctx','3D'))",
    40: "(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNIT_ASSIGNED_CONTEXT((#1,#2,#3))"
        "REPRESENTATION_CONTEXT('arm ctx','3D'))",
    5: "CARTESIAN_POINT('',(0.,0.,0.))",
    6: "DIRECTION('',(0.,0.,1.))",
    7: "DIRECTION('',(1.,0.,0.))",
    8: "AXIS2_PLACEMENT_3D('frame_base',#5,#6,#7)",
    9: "AXIS2_PLACEMENT_3D('frame_arm',#5,#6,#7)",
    # a degree and an inch, conversion-based units (used by the tests that need them)
    41: "PLANE_ANGLE_MEASURE_WITH_UNIT(PLANE_ANGLE_MEASURE(0.0174532925199433),#2)",
    42: "(CONVERSION_BASED_UNIT('DEGREE',#41)NAMED_UNIT(*)PLANE_ANGLE_UNIT())",
    43: "LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#1)",
    44: "(CONVERSION_BASED_UNIT('INCH',#43)LENGTH_UNIT()NAMED_UNIT(*))",
}

# probe_p105_1996_ap214.stp, completed into a mechanism
L1996 = {**COMMON, **{
    10: "KINEMATIC_LINK()",
    11: "KINEMATIC_LINK()",
    12: "KINEMATIC_JOINT(#10,#11)",
    13: "KINEMATIC_STRUCTURE((#12))",
    14: "REVOLUTE_PAIR('j1',$,#8,#9,#12)",
    15: "REVOLUTE_PAIR_RANGE(#14,PLANE_ANGLE_MEASURE(-1.5),PLANE_ANGLE_MEASURE(1.5))",
    16: "REVOLUTE_PAIR_VALUE(#14,0.5)",
    17: "KINEMATIC_LINK_REPRESENTATION('base_rep',(#8),#4)",
    18: "KINEMATIC_LINK_REPRESENTATION('arm_rep',(#9),#40)",
    19: "KINEMATIC_LINK_REPRESENTATION_RELATION(#10,#17)",
    20: "KINEMATIC_LINK_REPRESENTATION_RELATION(#11,#18)",
    30: "APPLICATION_CONTEXT('automotive_design')",
    31: "PRODUCT_CONTEXT('',#30,'mechanical')",
    32: "PRODUCT('m','m','',(#31))",
    33: "PRODUCT_DEFINITION_FORMATION('1','',#32)",
    34: "PRODUCT_DEFINITION_CONTEXT('part definition',#30,'design')",
    35: "PRODUCT_DEFINITION('design','',#33,#34)",
    36: "KINEMATIC_PROPERTY_DEFINITION('kinematics','',#35,#35)",
    37: "MECHANISM(#13,#10,#36)",
    38: "INITIAL_STATE(#37,(#16))",
}}

# probe_standard_star.stp, with the arm link in its own context (AP242: named_unit.dimensions
# is explicit for conversion-based units)
L242 = {**COMMON, **{
    42: "(CONVERSION_BASED_UNIT('DEGREE',#41)NAMED_UNIT(#45)PLANE_ANGLE_UNIT())",
    44: "(CONVERSION_BASED_UNIT('INCH',#43)LENGTH_UNIT()NAMED_UNIT(#47))",
    45: "DIMENSIONAL_EXPONENTS(0.,0.,0.,0.,0.,0.,0.)",
    47: "DIMENSIONAL_EXPONENTS(1.,0.,0.,0.,0.,0.,0.)",
    10: "KINEMATIC_LINK('base')",
    11: "KINEMATIC_LINK('arm')",
    12: "KINEMATIC_JOINT('j1',#10,#11)",
    13: "RIGID_LINK_REPRESENTATION('base_rep',(#8),#4,#10)",
    14: "RIGID_LINK_REPRESENTATION('arm_rep',(#9),#40,#11)",
    15: "REVOLUTE_PAIR_WITH_RANGE('j1',*,$,#8,#9,#12,*,*,*,*,*,*,-1.5,1.5)",
    16: "PAIR_REPRESENTATION_RELATIONSHIP('j1_rel','j1_rel','',#13,#14,#15)",
    17: "KINEMATIC_TOPOLOGY_STRUCTURE('topo',(#12),#4)",
    18: "MECHANISM_REPRESENTATION('mech',(#16),#4,#17)",
    19: "REVOLUTE_PAIR_VALUE('v',#15,0.5)",
    20: "MECHANISM_STATE_REPRESENTATION('state',(#19),*,#18)",
}}

LAYOUTS = {"1996": (L1996, HEAD_1996), "ap242": (L242, HEAD_242)}
# per layout: (pair id, the instance holding the range, value id, base rep, arm rep)
IDS = {"1996": dict(pair=14, range=15, value=16, base_rep=17, arm_rep=18),
       "ap242": dict(pair=15, range=15, value=19, base_rep=13, arm_rep=14)}


def text_of(table: dict, schema: str) -> str:
    body = "\n".join(f"#{i}={t};" for i, t in sorted(table.items()) if t is not None)
    return ("ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('kin check fixture'),'2;1');\n"
            "FILE_NAME('t.stp','2026-01-01T00:00:00',(''),(''),'','','');\n"
            f"FILE_SCHEMA(('{schema}'));\nENDSEC;\nDATA;\n{body}\nENDSEC;\nEND-ISO-10303-21;\n")


def make(layout: str, edits: dict | None = None) -> str:
    base, schema = LAYOUTS[layout]
    table = dict(base)
    table.update(edits or {})
    return text_of(table, schema)


def pop_of(text: str, profile=None) -> Population:
    return Population(read_step(text, "<test>"), profile)


def pop_of_records(text: str, patches: dict, profile=None) -> Population:
    """A Population over the decoded records of ``text`` with argument ``patches``
    ({id: (argument index, new value)}), as a JSON model could hold them."""
    sf = read_step(text, "<test>")
    records = list(sf.records())
    for rec in records:
        if rec["id"] in patches:
            pos, value = patches[rec["id"]]
            rec["args"][pos] = value
    if profile is None:
        from p105cli.schema.profiles import profile_for_header
        profile = profile_for_header(sf.header)
    return Population(records, profile)


def findings(text: str, rule: str | None = None, profile=None) -> list:
    out = check_kinematics(pop_of(text, profile))
    return [f for f in out if rule is None or f.rule == rule]


def assert_clean(text: str, profile=None) -> None:
    out = findings(text, profile=profile)
    assert out == [], "\n".join(map(str, out))


def numbers(message: str) -> list:
    return [float(x) for x in re.findall(r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?", message)]


# --------------------------------------------------------------------------- fixtures themselves

def test_rule_table():
    assert set(RULES) == {"KIN-UNITS", "KIN-RANGE", "KIN-YPR", "KIN-PLACEMENT", "KIN-UNREACHABLE", "KIN-LINK-NAME"}
    assert all(text.endswith(".") for text in RULES.values())


@pytest.mark.parametrize("layout", LAYOUTS)
def test_fixtures_are_clean(layout):
    assert_clean(make(layout))


@pytest.mark.parametrize("layout", LAYOUTS)
def test_fixtures_conform_to_the_schema(layout):
    assert schema_errors(make(layout)) == []


# --------------------------------------------------------------------------- KIN-UNITS

@pytest.mark.parametrize("layout", LAYOUTS)
def test_units_angle_disagreement(layout):
    ids = IDS[layout]
    arm_in_degrees = {40: COMMON[40].replace("(#1,#2,#3)", "(#1,#42,#3)")}
    out = findings(make(layout, arm_in_degrees), "KIN-UNITS")
    assert [(f.entity, f.severity, f.attribute) for f in out] == [
        (ids["arm_rep"], "error", "context_of_items")]
    assert "plane-angle" in out[0].message and "degree" in out[0].message
    assert math.isclose(numbers(out[0].message.split("degree")[1])[0], DEG, rel_tol=1e-6)
    # twin: both links in degrees (values and ranges are then degrees too)
    both = {4: COMMON[4].replace("(#1,#2,#3)", "(#1,#42,#3)"), **arm_in_degrees}
    assert_clean(make(layout, both))


def test_units_1996_link_representations_found_through_the_pair_frames():
    """Without kinematic_link_representation_relation (as in the 1996 probe), the link
    representation holding the pair's transform_item_1 / _2 is the link's."""
    no_relation = {19: None, 20: None}
    assert_clean(make("1996", no_relation))
    out = findings(make("1996", {**no_relation,
                                 40: COMMON[40].replace("(#1,#2,#3)", "(#1,#42,#3)")}))
    assert [(f.rule, f.entity) for f in out] == [("KIN-UNITS", 18)]


def test_units_pair_without_link_representation_1996():
    # no relation, and the base representation does not hold the pair frame
    lost = {19: None, 20: None, 17: "KINEMATIC_LINK_REPRESENTATION('base_rep',(#5),#4)"}
    out = findings(make("1996", lost), "KIN-UNITS")
    assert [(f.entity, f.severity) for f in out] == [(14, "warning")]
    assert "no link representation" in out[0].message


def test_units_the_odd_one_out_is_reported():
    """Three links: the base link's context is the one that differs."""
    third = {21: "KINEMATIC_LINK()", 22: "KINEMATIC_JOINT(#11,#21)",
             13: "KINEMATIC_STRUCTURE((#12,#22))",
             23: "REVOLUTE_PAIR('j2',$,#9,#24,#22)", 24: "AXIS2_PLACEMENT_3D('f3',#5,#6,#7)",
             25: "KINEMATIC_LINK_REPRESENTATION('third_rep',(#24),#40)",
             26: "KINEMATIC_LINK_REPRESENTATION_RELATION(#21,#25)",
             18: "KINEMATIC_LINK_REPRESENTATION('arm_rep',(#9),#40)"}
    assert_clean(make("1996", third))
    out = findings(make("1996", {**third, 4: COMMON[4].replace("(#1,#2,#3)", "(#44,#2,#3)")}))
    assert [(f.rule, f.entity, f.severity) for f in out] == [("KIN-UNITS", 17, "error")]


@pytest.mark.parametrize("layout", LAYOUTS)
def test_units_length_inch_against_millimetre(layout):
    ids = IDS[layout]
    arm_in_inches = {40: COMMON[40].replace("(#1,#2,#3)", "(#44,#2,#3)")}
    out = findings(make(layout, arm_in_inches), "KIN-UNITS")
    assert [(f.entity, f.severity) for f in out] == [(ids["arm_rep"], "error")]
    assert "inch (0.0254 m)" in out[0].message and "millimetre (0.001 m)" in out[0].message


@pytest.mark.parametrize("layout", LAYOUTS)
def test_units_equal_factors_written_differently_agree(layout):
    # base: SI metre; arm: conversion-based 'MILLIMETRE' x 1000 = the metre -> same factor
    edits = {
        50: "(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT($,.METRE.))",
        51: "LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(1000.),#1)",
        52: "(CONVERSION_BASED_UNIT('METRE IN MM',#51)LENGTH_UNIT()NAMED_UNIT(*))",
        4: COMMON[4].replace("(#1,#2,#3)", "(#50,#2,#3)"),
        40: COMMON[40].replace("(#1,#2,#3)", "(#52,#2,#3)"),
    }
    assert_clean(make(layout, edits))
    edits[51] = "LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(100.),#1)"  # a decimetre: disagrees
    out = findings(make(layout, edits), "KIN-UNITS")
    assert [f.entity for f in out] == [IDS[layout]["arm_rep"]]


@pytest.mark.parametrize("layout", LAYOUTS)
def test_units_missing_angle_unit_where_the_pair_needs_it(layout):
    ids = IDS[layout]
    no_angle = {4: COMMON[4].replace("(#1,#2,#3)", "(#1,#3)"),
                40: COMMON[40].replace("(#1,#2,#3)", "(#1,#3)")}
    out = findings(make(layout, no_angle), "KIN-UNITS")
    # the first link's context is where plane_angle_for_pair_in_radian reads the angles
    assert [(f.entity, f.severity) for f in out] == [(ids["base_rep"], "error")]
    assert "no plane-angle unit" in out[0].message
    # twin: a prismatic pair has lengths only
    if layout == "1996":
        prismatic = {14: "PRISMATIC_PAIR('j1',$,#8,#9,#12)",
                     15: "PRISMATIC_PAIR_RANGE(#14,LENGTH_MEASURE(-10.),LENGTH_MEASURE(10.))",
                     16: "PRISMATIC_PAIR_VALUE(#14,5.)"}
    else:
        prismatic = {15: "PRISMATIC_PAIR_WITH_RANGE('j1',*,$,#8,#9,#12,*,*,*,*,*,*,-10.,10.)",
                     19: "PRISMATIC_PAIR_VALUE('v',#15,5.)"}
    assert_clean(make(layout, {**no_angle, **prismatic}))


@pytest.mark.parametrize("layout", LAYOUTS)
def test_units_missing_length_unit(layout):
    ids = IDS[layout]
    out = findings(make(layout, {40: COMMON[40].replace("(#1,#2,#3)", "(#2,#3)")}), "KIN-UNITS")
    assert [(f.entity, f.severity) for f in out] == [(ids["arm_rep"], "error")]
    assert "no length unit" in out[0].message


@pytest.mark.parametrize("layout", LAYOUTS)
def test_units_context_without_units(layout):
    ids = IDS[layout]
    plain = {40: "(GEOMETRIC_REPRESENTATION_CONTEXT(3)REPRESENTATION_CONTEXT('arm ctx','3D'))"}
    out = findings(make(layout, plain), "KIN-UNITS")
    assert [(f.entity, f.severity) for f in out] == [(ids["arm_rep"], "error")]
    assert "global_unit_assigned_context" in out[0].message


@pytest.mark.parametrize("layout", LAYOUTS)
def test_units_wrong_or_ambiguous_units(layout):
    # a length unit in radians
    out = findings(make(layout, {1: "(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.RADIAN.))"}),
                   "KIN-UNITS")
    assert [(f.entity, f.severity) for f in out] == [(1, "error")]
    # two plane-angle units in one context
    out = findings(make(layout, {40: COMMON[40].replace("(#1,#2,#3)", "(#1,#2,#42,#3)")}),
                   "KIN-UNITS")
    assert [(f.entity, f.severity) for f in out] == [(40, "error")]
    # a degree defined from a length unit
    out = findings(make(layout, {41: "PLANE_ANGLE_MEASURE_WITH_UNIT(PLANE_ANGLE_MEASURE(1.),#1)",
                                 40: COMMON[40].replace("(#1,#2,#3)", "(#1,#42,#3)")}),
                   "KIN-UNITS")
    assert [f.severity for f in out] == ["error"] and "not a plane-angle unit" in out[0].message
    # a context-dependent unit: unknown factor, a warning, nothing compared
    out = findings(make(layout, {
        45: "DIMENSIONAL_EXPONENTS(0.,0.,0.,0.,0.,0.,0.)",
        46: "(CONTEXT_DEPENDENT_UNIT('TURN')NAMED_UNIT(#45)PLANE_ANGLE_UNIT())",
        40: COMMON[40].replace("(#1,#2,#3)", "(#1,#46,#3)")}), "KIN-UNITS")
    assert [(f.entity, f.severity) for f in out] == [(46, "warning")]


def test_unit_factors_numerically():
    edits = {
        # milliradian, arcminute (a degree of a degree), a conversion loop
        60: "(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT(.MILLI.,.RADIAN.))",
        61: "PLANE_ANGLE_MEASURE_WITH_UNIT(PLANE_ANGLE_MEASURE(0.016666666666666666),#42)",
        62: "(CONVERSION_BASED_UNIT('ARCMINUTE',#61)NAMED_UNIT(*)PLANE_ANGLE_UNIT())",
        63: "(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.KILO.,.METRE.))",
        70: COMMON[40].replace("(#1,#2,#3)", "(#63,#60,#3)"),
        71: COMMON[40].replace("(#1,#2,#3)", "(#44,#62,#3)"),
        72: COMMON[40].replace("(#1,#2,#3)", "(#1,#42,#3)"),
    }
    pop = pop_of(make("1996", edits))
    cu = context_units(pop, 70)
    assert cu.length[0] == 1000.0 and cu.angle[0] == 1e-3
    cu = context_units(pop, 71)
    assert math.isclose(cu.length[0], 0.0254, rel_tol=1e-15)
    assert math.isclose(cu.angle[0], DEG / 60.0, rel_tol=1e-14)
    cu = context_units(pop, 72)
    assert cu.angle[1] == "degree" and math.isclose(cu.angle[0], DEG, rel_tol=1e-14)
    assert context_units(pop, 4).length[:2] == (0.001, "millimetre")


def test_unit_factor_matches_the_schema_function():
    """plane_angle_for_pair_in_radian (5.5.7), evaluated from the 1996 EXPRESS, agrees."""
    for units, expected in (("(#1,#2,#3)", 1.0), ("(#1,#42,#3)", DEG)):
        pop = pop_of(make("1996", {4: COMMON[4].replace("(#1,#2,#3)", units)}))
        got = Evaluator(pop).call("plane_angle_for_pair_in_radian", pop.instance(14), 1.0)
        got = getattr(got, "value", got)
        assert math.isclose(float(got), expected, rel_tol=1e-14)
        assert math.isclose(context_units(pop, 4).angle[0], float(got), rel_tol=1e-15)


# --------------------------------------------------------------------------- KIN-RANGE

# (name, 1996 pair, 1996 range, 1996 value template, AP242 pair with range, AP242 value
# template, value attribute, good values, bad values); {0}, {1}, ... are the values.
J = "#8,#9,#12"
UNL = "UNLIMITED_RANGE(.UNLIMITED.)"
STARS = "*,*,*,*,*,*"
PAIR_CASES = [
    ("revolute",
     f"REVOLUTE_PAIR('j1',$,{J})", "REVOLUTE_PAIR_RANGE(#14,-1.,1.)",
     "REVOLUTE_PAIR_VALUE(#14,{0})",
     f"REVOLUTE_PAIR_WITH_RANGE('j1',*,$,{J},{STARS},-1.,1.)",
     "REVOLUTE_PAIR_VALUE('v',#15,{0})",
     "actual_rotation", ("0.5",), ("1.2",)),
    ("prismatic",
     f"PRISMATIC_PAIR('j1',$,{J})",
     "PRISMATIC_PAIR_RANGE(#14,LENGTH_MEASURE(0.),LENGTH_MEASURE(50.))",
     "PRISMATIC_PAIR_VALUE(#14,{0})",
     f"PRISMATIC_PAIR_WITH_RANGE('j1',*,$,{J},{STARS},0.,50.)",
     "PRISMATIC_PAIR_VALUE('v',#15,{0})",
     "actual_translation", ("25.",), ("-3.",)),
    ("cylindrical",
     f"CYLINDRICAL_PAIR('j1',$,{J})",
     f"CYLINDRICAL_PAIR_RANGE(#14,LENGTH_MEASURE(0.),LENGTH_MEASURE(50.),{UNL},"
     "PLANE_ANGLE_MEASURE(1.))",
     "CYLINDRICAL_PAIR_VALUE(#14,{0},{1})",
     f"CYLINDRICAL_PAIR_WITH_RANGE('j1',*,$,{J},{STARS},0.,50.,$,1.)",
     "CYLINDRICAL_PAIR_VALUE('v',#15,{0},{1})",
     "actual_rotation", ("10.", "-100."), ("10.", "1.01")),
    ("screw",
     f"SCREW_PAIR('j1',$,{J},2.)", "SCREW_PAIR_RANGE(#14,-6.,6.)",
     "SCREW_PAIR_VALUE(#14,{0})",
     f"SCREW_PAIR_WITH_RANGE('j1',*,$,{J},2.,-6.,6.)",
     "SCREW_PAIR_VALUE('v',#15,{0})",
     "actual_rotation", ("6.",), ("-6.5",)),
    ("universal",
     f"UNIVERSAL_PAIR('j1',$,{J},$)", "UNIVERSAL_PAIR_RANGE(#14,-1.,1.,-0.5,0.5)",
     "UNIVERSAL_PAIR_VALUE(#14,{0},{1})",
     f"UNIVERSAL_PAIR_WITH_RANGE('j1',*,$,{J},{STARS},$,-1.,1.,-0.5,0.5)",
     "UNIVERSAL_PAIR_VALUE('v',#15,{0},{1})",
     "second_rotation_angle", ("0.9", "-0.5"), ("0.9", "0.6")),
    ("planar",
     f"PLANAR_PAIR('j1',$,{J})",
     f"PLANAR_PAIR_RANGE(#14,{UNL},{UNL},LENGTH_MEASURE(-5.),LENGTH_MEASURE(5.),"
     "LENGTH_MEASURE(0.),LENGTH_MEASURE(8.))",
     "PLANAR_PAIR_VALUE(#14,{0},{1},{2})",
     f"PLANAR_PAIR_WITH_RANGE('j1',*,$,{J},{STARS},$,$,-5.,5.,0.,8.)",
     "PLANAR_PAIR_VALUE('v',#15,{0},{1},{2})",
     "actual_translation_y", ("7.", "5.", "8."), ("7.", "5.", "8.5")),
    ("spherical",
     f"SPHERICAL_PAIR('j1',$,{J})", f"SPHERICAL_PAIR_RANGE(#14,-1.,1.,-0.5,0.5,{UNL},{UNL})",
     "SPHERICAL_PAIR_VALUE(#14,YPR_ROTATION(({0},{1},{2})))",
     f"SPHERICAL_PAIR_WITH_RANGE('j1',*,$,{J},{STARS},-1.,1.,-0.5,0.5,$,$)",
     "SPHERICAL_PAIR_VALUE('v',#15,YPR_ROTATION(({0},{1},{2})))",
     "input_orientation", ("0.9", "0.5", "3."), ("0.9", "-0.6", "0.")),
    ("spherical with pin",
     None, None, None,
     f"SPHERICAL_PAIR_WITH_PIN_AND_RANGE('j1',*,$,{J},{STARS},-1.,1.,$,0.2)",
     "SPHERICAL_PAIR_VALUE('v',#15,YPR_ROTATION(({0},{1},{2})))",
     "input_orientation", ("0.9", "0.", "-3."), ("0.9", "0.", "0.3")),
    ("gear",
     f"GEAR_PAIR('j1',$,{J},20.,30.,0.,0.,0.6666666666666666)",
     "GEAR_PAIR_RANGE(#14,-60.,60.)",
     "GEAR_PAIR_VALUE(#14,{0})",
     f"GEAR_PAIR_WITH_RANGE('j1',*,$,{J},20.,30.,0.,0.,0.6666666666666666,-60.,60.)",
     "GEAR_PAIR_VALUE('v',#15,{0})",
     "actual_rotation_1", ("-59.",), ("61.",)),
    ("rack and pinion",
     f"RACK_AND_PINION_PAIR('j1',$,{J},25.)", "RACK_AND_PINION_PAIR_RANGE(#14,-120.,120.)",
     "RACK_AND_PINION_PAIR_VALUE(#14,{0})",
     f"RACK_AND_PINION_PAIR_WITH_RANGE('j1',*,$,{J},25.,-120.,120.)",
     "RACK_AND_PINION_PAIR_VALUE('v',#15,{0})",
     "actual_displacement", ("120.",), ("-121.",)),
]


def schema_errors(text: str, profile=None) -> list:
    from p105cli.rules.conformance import check_population, step_types_of
    sf = read_step(text, "<t>")
    schema = Population(sf, profile).schema
    return [f for f in check_population(sf.records(), schema, step_types_of(sf, schema))
            if f.severity == "error"]


def pair_edits(layout, case, values):
    name, p96, r96, v96, p242, v242, attr, good, bad = case
    if layout == "1996":
        return {14: p96, 15: r96, 16: v96.format(*values)}
    return {15: p242, 19: v242.format(*values)}


@pytest.mark.parametrize("layout, case", [
    pytest.param(layout, case, id=f"{layout}-{case[0]}")
    for layout in LAYOUTS for case in PAIR_CASES
    if layout == "ap242" or case[1] is not None])  # spherical_pair_with_pin: AP242 only
def test_range_per_pair_type(layout, case):
    ids = IDS[layout]
    attr, good, bad = case[6], case[7], case[8]
    good_text = make(layout, pair_edits(layout, case, good))
    assert_clean(good_text)
    assert schema_errors(good_text) == []
    out = findings(make(layout, pair_edits(layout, case, bad)))
    assert [(f.rule, f.entity, f.severity, f.attribute) for f in out] == [
        ("KIN-RANGE", ids["value"], "error", attr)]


def test_range_low_order_pair_with_range_ap242():
    pair = (f"LOW_ORDER_KINEMATIC_PAIR_WITH_RANGE('j1',*,$,{J},.F.,.F.,.T.,.F.,.F.,.T.,"
            "$,$,$,$,-1.,1.,$,$,$,$,0.,10.)")
    value = "LOW_ORDER_KINEMATIC_PAIR_VALUE('v',#15,0.,0.,{0},0.,0.,{1})"
    assert_clean(make("ap242", {15: pair, 19: value.format("5.", "-1.")}))
    out = findings(make("ap242", {15: pair, 19: value.format("10.5", "0.")}))
    assert [(f.rule, f.attribute) for f in out] == [("KIN-RANGE", "actual_translation_z")]
    out = findings(make("ap242", {15: pair, 19: value.format("1.", "1.5")}))
    assert [(f.rule, f.attribute) for f in out] == [("KIN-RANGE", "actual_rotation_z")]


@pytest.mark.parametrize("layout", LAYOUTS)
def test_range_lower_above_upper(layout):
    ids = IDS[layout]
    swapped = ({15: "REVOLUTE_PAIR_RANGE(#14,PLANE_ANGLE_MEASURE(1.5),PLANE_ANGLE_MEASURE(-1.5))"}
               if layout == "1996" else
               {15: "REVOLUTE_PAIR_WITH_RANGE('j1',*,$,#8,#9,#12,*,*,*,*,*,*,1.5,-1.5)"})
    out = findings(make(layout, swapped), "KIN-RANGE")
    assert [(f.entity, f.severity, f.attribute) for f in out] == [
        (ids["range"], "error", "lower_limit_actual_rotation")]


@pytest.mark.parametrize("layout", LAYOUTS)
def test_range_in_degrees_checked_in_radians(layout):
    """The same physical range and value, once in degrees and once in radians: the same
    verdicts, and the findings give the same radians."""
    ids = IDS[layout]
    deg_units = {4: COMMON[4].replace("(#1,#2,#3)", "(#1,#42,#3)"),
                 40: COMMON[40].replace("(#1,#2,#3)", "(#1,#42,#3)")}

    def files(lo, hi, value, units):
        if layout == "1996":
            e = {15: f"REVOLUTE_PAIR_RANGE(#14,PLANE_ANGLE_MEASURE({lo!r}),"
                     f"PLANE_ANGLE_MEASURE({hi!r}))",
                 16: f"REVOLUTE_PAIR_VALUE(#14,{value!r})"}
        else:
            e = {15: f"REVOLUTE_PAIR_WITH_RANGE('j1',*,$,#8,#9,#12,*,*,*,*,*,*,{lo!r},{hi!r})",
                 19: f"REVOLUTE_PAIR_VALUE('v',#15,{value!r})"}
        return make(layout, {**units, **e})

    # range [-30 deg, 13 deg]; 12.9 deg inside, 14 deg outside (0.2443 rad > 0.2269 rad)
    assert_clean(files(-30.0, 13.0, 12.9, deg_units))
    assert_clean(files(-30.0 * DEG, 13.0 * DEG, 12.9 * DEG, {}))
    out_deg = findings(files(-30.0, 13.0, 14.0, deg_units))
    out_rad = findings(files(-30.0 * DEG, 13.0 * DEG, 14.0 * DEG, {}))
    for out in (out_deg, out_rad):
        assert [(f.rule, f.entity) for f in out] == [("KIN-RANGE", ids["value"])]
        rad = [x for x in numbers(out[0].message)]
        assert any(math.isclose(x, 14.0 * DEG, rel_tol=1e-5) for x in rad)
        assert any(math.isclose(x, 13.0 * DEG, rel_tol=1e-5) for x in rad)
    # 0.5 read as radians would be out of a 13 deg range; read as degrees it is inside
    assert_clean(files(-30.0, 13.0, 0.5, deg_units))
    assert [f.rule for f in findings(files(-30.0 * DEG, 13.0 * DEG, 0.5, {}))] == ["KIN-RANGE"]


DEG_UNITS = {4: COMMON[4].replace("(#1,#2,#3)", "(#1,#42,#3)"),
             40: COMMON[40].replace("(#1,#2,#3)", "(#1,#42,#3)")}


@pytest.mark.parametrize("layout", LAYOUTS)
def test_range_on_pair_curve(layout):
    """point_on_planar_curve_pair range: the trimmed circle bounds the point's parameter
    (degrees, periodic); its ypr limits bound the orientation."""
    def case(t1, t2, sense, t, yaw=0.0):
        e = {**DEG_UNITS, 80: "CIRCLE('cam',#8,40.)",
             81: f"TRIMMED_CURVE('range',#80,(PARAMETER_VALUE({t1!r})),"
                 f"(PARAMETER_VALUE({t2!r})),{sense},.PARAMETER.)",
             82: f"POINT_ON_CURVE('p',#80,{t!r})"}
        ypr = f"YPR_ROTATION(({yaw!r},0.,0.))"
        if layout == "1996":
            e.update({14: f"POINT_ON_PLANAR_CURVE_PAIR('j1',$,{J},#80,.T.)",
                      15: "POINT_ON_PLANAR_CURVE_PAIR_RANGE(#14,#81,PLANE_ANGLE_MEASURE(-90.),"
                          f"PLANE_ANGLE_MEASURE(90.),{UNL},{UNL},{UNL},{UNL})",
                      16: f"POINT_ON_PLANAR_CURVE_PAIR_VALUE(#14,#82,{ypr})"})
        else:
            e.update({15: f"POINT_ON_PLANAR_CURVE_PAIR_WITH_RANGE('j1',*,$,{J},#80,.T.,#81,"
                          "-90.,90.,$,$,$,$)",
                      19: f"POINT_ON_PLANAR_CURVE_PAIR_VALUE('v',#15,#82,{ypr})"})
        return make(layout, e)

    value = IDS[layout]["value"]
    assert schema_errors(case(0.0, 90.0, ".T.", 45.0)) == []
    assert_clean(case(0.0, 90.0, ".T.", 45.0))
    assert_clean(case(300.0, 60.0, ".T.", 10.0))     # wraps through 0
    assert_clean(case(300.0, 60.0, ".T.", 370.0))    # one turn later
    assert_clean(case(60.0, 300.0, ".F.", 0.0))      # against the sense
    for bad in (case(0.0, 90.0, ".T.", 100.0), case(300.0, 60.0, ".T.", 200.0),
                case(60.0, 300.0, ".F.", 180.0)):
        out = findings(bad)
        assert [(f.rule, f.entity, f.attribute) for f in out] == [
            ("KIN-RANGE", value, "actual_point_on_curve")]
    out = findings(case(0.0, 90.0, ".T.", 45.0, yaw=95.0))
    assert [(f.rule, f.attribute) for f in out] == [("KIN-RANGE", "input_orientation")]


@pytest.mark.parametrize("layout", LAYOUTS)
@pytest.mark.parametrize("surface", ["PLANE('s',#8)", "CYLINDRICAL_SURFACE('s',#8,10.)"])
def test_range_on_pair_surface(layout, surface):
    """point_on_surface_pair range: a rectangular trimmed surface bounds (u, v); a cylinder's
    u is an angle (degrees here), read modulo one turn."""
    def case(u, v):
        e = {**DEG_UNITS, 85: surface,
             86: "RECTANGULAR_TRIMMED_SURFACE('r',#85,-30.,30.,0.,5.,.T.,.T.)",
             87: f"POINT_ON_SURFACE('p',#85,{u!r},{v!r})"}
        ypr = "YPR_ROTATION((0.,0.,0.))"
        if layout == "1996":
            e.update({14: f"POINT_ON_SURFACE_PAIR('j1',$,{J},#85)",
                      15: f"POINT_ON_SURFACE_PAIR_RANGE(#14,#86,{','.join([UNL] * 6)})",
                      16: f"POINT_ON_SURFACE_PAIR_VALUE(#14,#87,{ypr})"})
        else:
            e.update({15: f"POINT_ON_SURFACE_PAIR_WITH_RANGE('j1',*,$,{J},#85,#86,$,$,$,$,$,$)",
                      19: f"POINT_ON_SURFACE_PAIR_VALUE('v',#15,#87,{ypr})"})
        return make(layout, e)

    assert schema_errors(case(0.0, 1.0)) == []
    assert_clean(case(-30.0, 5.0))
    periodic = surface.startswith("CYLINDRICAL")
    for u, v, ok in ((340.0, 2.0, periodic), (10.0, 6.0, False), (40.0, 0.0, False)):
        out = findings(case(u, v))
        expected = [] if ok else [("KIN-RANGE", IDS[layout]["value"], "actual_point_on_surface")]
        assert [(f.rule, f.entity, f.attribute) for f in out] == expected, (u, v)


def test_range_rotation_about_direction_converted_first_ap242():
    # about +z by 40 deg: yaw 40 deg (5.5.9), outside a yaw range of [-30, 30] deg
    deg = {4: COMMON[4].replace("(#1,#2,#3)", "(#1,#42,#3)"),
           40: COMMON[40].replace("(#1,#2,#3)", "(#1,#42,#3)")}
    pair = f"SPHERICAL_PAIR_WITH_RANGE('j1',*,$,{J},*,*,*,*,*,*,-30.,30.,$,$,$,$)"
    for angle, ok in ((20.0, True), (40.0, False)):
        text = make("ap242", {**deg, 15: pair, 90: "DIRECTION('',(0.,0.,2.))",
                              91: f"ROTATION_ABOUT_DIRECTION('',#90,{angle!r})",
                              19: "SPHERICAL_PAIR_VALUE('v',#15,#91)"})
        out = findings(text)
        assert [(f.rule, f.entity) for f in out] == ([] if ok else [("KIN-RANGE", 19)])


# --------------------------------------------------------------------------- KIN-YPR

def ypr_file(layout, yaw, pitch, roll, degrees=False):
    units = ({4: COMMON[4].replace("(#1,#2,#3)", "(#1,#42,#3)"),
              40: COMMON[40].replace("(#1,#2,#3)", "(#1,#42,#3)")} if degrees else {})
    ypr = f"YPR_ROTATION(({yaw!r},{pitch!r},{roll!r}))"
    if layout == "1996":
        return make(layout, {**units, 14: f"SPHERICAL_PAIR('j1',$,{J})", 15: None,
                             16: f"SPHERICAL_PAIR_VALUE(#14,{ypr})"})
    return make(layout, {**units, 15: f"SPHERICAL_PAIR('j1',*,$,{J},*,*,*,*,*,*)",
                         19: f"SPHERICAL_PAIR_VALUE('v',#15,{ypr})"})


@pytest.mark.parametrize("layout", LAYOUTS)
def test_ypr_bounds_radians(layout):
    v = IDS[layout]["value"]
    h = math.pi / 2
    for ok in ((0.1, 0.2, 0.3), (math.pi, h, 0.0), (-3.0, -h, 0.0), (math.pi, 0.0, math.pi)):
        assert_clean(ypr_file(layout, *ok))
    for bad, sev in (((0.1, 2.0, 0.3), "error"), ((3.5, 0.0, 0.0), "error"),
                     ((0.0, 0.0, -3.2), "error"), ((-math.pi, 0.0, 0.0), "warning"),
                     ((0.0, h, 0.3), "error"), ((0.0, -h, -1.0), "error")):
        out = findings(ypr_file(layout, *bad))
        assert [(f.rule, f.entity, f.severity, f.attribute) for f in out] == [
            ("KIN-YPR", v, sev, "input_orientation")], bad


@pytest.mark.parametrize("layout", LAYOUTS)
def test_ypr_bounds_in_the_file_unit(layout):
    assert_clean(ypr_file(layout, 180.0, 80.0, -179.0, degrees=True))
    assert_clean(ypr_file(layout, 30.0, 90.0, 0.0, degrees=True))
    assert [f.rule for f in findings(ypr_file(layout, 0.0, 80.0, 0.0))] == ["KIN-YPR"]
    assert [f.severity for f in findings(ypr_file(layout, -180.0, 0.0, 0.0, degrees=True))] == [
        "warning"]
    out = findings(ypr_file(layout, 0.0, -90.0, 5.0, degrees=True))
    assert [f.rule for f in out] == ["KIN-YPR"] and "rectangular" in out[0].message
    out = findings(ypr_file(layout, 0.0, 95.0, 0.0, degrees=True))
    assert [f.rule for f in out] == ["KIN-YPR"]
    assert any(math.isclose(x, 95.0 * DEG, rel_tol=1e-5) for x in numbers(out[0].message))


@pytest.mark.parametrize("layout", LAYOUTS)
def test_ypr_range_limits_outside_their_interval(layout):
    rng = ("SPHERICAL_PAIR_RANGE(#14,-1.,1.,-2.,0.5,UNLIMITED_RANGE(.UNLIMITED.),"
           "UNLIMITED_RANGE(.UNLIMITED.))" if layout == "1996" else
           f"SPHERICAL_PAIR_WITH_RANGE('j1',*,$,{J},*,*,*,*,*,*,-1.,1.,-2.,0.5,$,$)")
    ypr = "YPR_ROTATION((0.,0.,0.))"
    edits = ({14: f"SPHERICAL_PAIR('j1',$,{J})", 15: rng, 16: f"SPHERICAL_PAIR_VALUE(#14,{ypr})"}
             if layout == "1996" else {15: rng, 19: f"SPHERICAL_PAIR_VALUE('v',#15,{ypr})"})
    out = findings(make(layout, edits))
    assert [(f.rule, f.entity, f.severity, f.attribute) for f in out] == [
        ("KIN-YPR", IDS[layout]["range"], "warning", "lower_limit_pitch")]
    assert_clean(make(layout, {**edits, 15: rng.replace("-2.", "-1.5")}))


# --------------------------------------------------------------------------- KIN-PLACEMENT

@pytest.mark.parametrize("layout", LAYOUTS)
def test_placement_axis2(layout):
    # non-unit directions are normalised: fine
    assert_clean(make(layout, {6: "DIRECTION('',(0.,0.,5.))", 7: "DIRECTION('',(0.2,0.,0.))"}))
    cases = (({6: "DIRECTION('',(0.,0.,0.))"}, "error", "axis"),
             ({7: "DIRECTION('',(0.,0.,-3.))"}, "error", "ref_direction"),
             ({7: "DIRECTION('',(1.,0.,1.))"}, "warning", "ref_direction"))
    for edit, sev, attr in cases:
        out = findings(make(layout, edit))
        # both frames share the faulty direction
        assert [(f.rule, f.entity, f.severity, f.attribute) for f in out] == [
            ("KIN-PLACEMENT", 8, sev, attr), ("KIN-PLACEMENT", 9, sev, attr)], edit
    # Part 21 cannot write a non-finite real (the reader refuses 1.E999); a JSON model can
    pop = pop_of_records(make(layout), {5: (1, [0.0, math.inf, 0.0])})
    out = check_kinematics(pop)
    assert [(f.rule, f.entity, f.severity, f.attribute) for f in out] == [
        ("KIN-PLACEMENT", 8, "error", "location"), ("KIN-PLACEMENT", 9, "error", "location")]


def test_placement_su_parameters_ap242():
    su = "SU_PARAMETERS('su',{0},0.,5.,0.,0.,1.5707963267948966)"
    edits = {14: "RIGID_LINK_REPRESENTATION('arm_rep',(#21),#40,#11)",
             15: "REVOLUTE_PAIR_WITH_RANGE('j1',*,$,#8,#21,#12,*,*,*,*,*,*,-1.5,1.5)"}
    text = make("ap242", {**edits, 21: su.format("10.")})
    assert_clean(text)
    out = check_kinematics(pop_of_records(text, {21: (1, math.inf)}))
    assert [(f.rule, f.entity, f.severity, f.attribute) for f in out] == [
        ("KIN-PLACEMENT", 21, "error", "a")]
    out = check_kinematics(pop_of_records(text, {21: (6, math.nan)}))
    assert [(f.rule, f.entity, f.attribute) for f in out] == [("KIN-PLACEMENT", 21, "gamma")]


def test_placement_su_parameters_p105_profile():
    su = "SU_PARAMETERS('su',{0},0.,5.,0.,0.,1.5707963267948966)"
    edits = {18: "KINEMATIC_LINK_REPRESENTATION('arm_rep',(#21),#40)",
             14: "REVOLUTE_PAIR('j1',$,#8,#21,#12)"}
    text = make("1996", {**edits, 21: su.format("10.")})
    assert_clean(text, profile="p105")
    out = check_kinematics(pop_of_records(text, {21: (3, -math.inf)}, profile="p105"))
    assert [(f.rule, f.entity, f.attribute) for f in out] == [("KIN-PLACEMENT", 21, "b")]


def base_placement(axis1="(1.,0.,0.)", axis3="(0.,0.,1.)", axis2="$", scale="1."):
    """The 1996 fixture with a ground representation and its mechanism_base_placement."""
    return make("1996", {
        50: f"DIRECTION('',{axis1})", 51: f"DIRECTION('',{axis3})",
        52: "CARTESIAN_POINT('',(0.,0.,100.))",
        53: (f"DIRECTION('',{axis2})" if axis2 != "$" else None),
        54: (f"CARTESIAN_TRANSFORMATION_OPERATOR_3D('base','base',$,#50,"
             f"{'#53' if axis2 != '$' else '$'},#52,{scale},#51)"),
        55: "KINEMATIC_GROUND_REPRESENTATION('ground',(#8,#54),#4)",
        56: "KINEMATIC_PROPERTY_REPRESENTATION_RELATION(#36,#55)",
        57: "MECHANISM_BASE_PLACEMENT('base placement',$,#55,*,#54,#37)",
    })


def test_placement_cartesian_transformation_operator_1996():
    assert_clean(base_placement())
    assert_clean(base_placement(axis1="(0.,-2.,0.)", axis3="(0.,0.,3.)", axis2="(7.,0.,0.)"))
    cases = ((dict(scale="-1."), "error", "scale"), (dict(scale="2."), "warning", "scale"),
             (dict(axis1="(0.,0.,0.)"), "error", "axis1"),
             (dict(axis1="(0.,0.,-1.)"), "error", "axis1"),
             (dict(axis2="(0.,-1.,0.)"), "error", "axis2"),
             (dict(axis1="(1.,0.,0.1)"), "warning", "axis3"))
    for kw, sev, attr in cases:
        out = findings(base_placement(**kw))
        assert [(f.rule, f.entity, f.severity, f.attribute) for f in out] == [
            ("KIN-PLACEMENT", 54, sev, attr)], kw


def test_placement_rotation_about_direction_zero_axis_ap242():
    edits = {15: f"SPHERICAL_PAIR('j1',*,$,{J},*,*,*,*,*,*)",
             91: "ROTATION_ABOUT_DIRECTION('',#90,0.5)",
             19: "SPHERICAL_PAIR_VALUE('v',#15,#91)"}
    assert_clean(make("ap242", {**edits, 90: "DIRECTION('',(1.,1.,0.))"}))
    out = findings(make("ap242", {**edits, 90: "DIRECTION('',(0.,0.,0.))"}))
    assert [(f.rule, f.entity, f.attribute) for f in out] == [
        ("KIN-PLACEMENT", 91, "direction_of_axis")]


# --------------------------------------------------------------------------- KIN-UNREACHABLE

def test_unreachable_1996():
    orphan = {60: "KINEMATIC_LINK()", 61: "KINEMATIC_LINK()", 62: "KINEMATIC_JOINT(#60,#61)",
              63: "AXIS2_PLACEMENT_3D('o1',#5,#6,#7)", 64: "AXIS2_PLACEMENT_3D('o2',#5,#6,#7)",
              65: "REVOLUTE_PAIR('orphan',$,#63,#64,#62)", 66: "REVOLUTE_PAIR_VALUE(#65,0.1)",
              67: "KINEMATIC_LINK_REPRESENTATION('o_rep',(#63),#4)",
              68: "KINEMATIC_LINK_REPRESENTATION_RELATION(#60,#67)"}
    out = findings(make("1996", orphan))
    assert [(f.rule, f.entity, f.severity) for f in out] == [
        ("KIN-UNREACHABLE", i, "warning") for i in (60, 61, 62, 65, 66, 67, 68)]
    # twin: the same pair on a joint of the mechanism's structure
    joined = {**orphan, 13: "KINEMATIC_STRUCTURE((#12,#62))", 62: "KINEMATIC_JOINT(#11,#60)"}
    joined.pop(61)
    assert_clean(make("1996", joined))


def test_unreachable_ap242():
    out = findings(make("ap242", {30: "KINEMATIC_LINK('orphan')",
                                  31: "REVOLUTE_PAIR_VALUE('stray',#15,0.2)"}))
    # the stray value applies to a pair of the mechanism: reachable (back reference)
    assert [(f.rule, f.entity, f.severity) for f in out] == [("KIN-UNREACHABLE", 30, "warning")]
    assert_clean(make("ap242", {31: "REVOLUTE_PAIR_VALUE('stray',#15,0.2)"}))


@pytest.mark.parametrize("layout", LAYOUTS)
def test_unreachable_without_mechanism(layout):
    drop = {37: None, 38: None} if layout == "1996" else {18: None, 20: None}
    out = findings(make(layout, drop))
    assert out and {f.rule for f in out} == {"KIN-UNREACHABLE"}
    assert all(f.severity == "warning" for f in out)
    assert IDS[layout]["pair"] in {f.entity for f in out}


# --------------------------------------------------------------------------- real files

def corpus():
    return sorted(CORPUS_DIR.glob("*.stp")) if CORPUS_DIR.is_dir() else []


@pytest.mark.skipif(not corpus(), reason="tests/data/corpus is missing")
@pytest.mark.parametrize("path", corpus(), ids=lambda p: p.name)
def test_corpus_files_are_clean(path):
    profile = "p105" if path.stem.endswith("_p105") else None
    assert_clean(path.read_text(encoding="utf-8"), profile=profile)


EXAMPLES_WITH_MECHANISM = [p for p in sorted((ROOT / "examples").glob("*.stp"))
                           if re.search(r"\b(MECHANISM|MECHANISM_REPRESENTATION)\(",
                                        p.read_text(encoding="utf-8"))]


@pytest.mark.skipif(not EXAMPLES_WITH_MECHANISM, reason="no example with a mechanism")
@pytest.mark.parametrize("path", EXAMPLES_WITH_MECHANISM, ids=lambda p: p.name)
def test_examples_are_clean(path):
    assert_clean(path.read_text(encoding="utf-8"))


def corpus_mutation(name, old, new):
    path = CORPUS_DIR / name
    if not path.is_file():
        pytest.skip(f"{path} is missing")
    text = path.read_text(encoding="utf-8")
    if len(re.findall(old, text)) != 1:  # the corpus was regenerated differently
        pytest.skip(f"{old!r} is not in {name} exactly once")
    return re.sub(old, new, text)


def test_corpus_mutations():
    # slider crank (1996, degrees): the wrist pin's value out of its range [-30, 13] deg
    text = corpus_mutation("slider_crank_ap214.stp",
                           r"REVOLUTE_PAIR_RANGE\((#\d+),PLANE_ANGLE_MEASURE\(-30\.\),"
                           r"PLANE_ANGLE_MEASURE\(13\.\)\)",
                           r"REVOLUTE_PAIR_RANGE(\1,PLANE_ANGLE_MEASURE(-30.),"
                           r"PLANE_ANGLE_MEASURE(3.))")
    out = findings(text)
    assert out and {f.rule for f in out} == {"KIN-RANGE"}
    assert all(f.entity_type == "revolute_pair_value" for f in out)
    # four bar (AP242): one link context in radians while the others are in degrees
    text = corpus_mutation("four_bar_ap242.stp",
                           r"GLOBAL_UNIT_ASSIGNED_CONTEXT\(\(#1,#5,#6\)\)REPRESENTATION_CONTEXT\("
                           r"'four_bar link crank'",
                           "GLOBAL_UNIT_ASSIGNED_CONTEXT((#1,#2,#6))REPRESENTATION_CONTEXT("
                           "'four_bar link crank'")
    out = findings(text)
    assert [(f.rule, f.entity_type) for f in out] == [("KIN-UNITS", "rigid_link_representation")]


# --------------------------------------------------------------------------- big geometry file

def big_files():
    return sorted(BIG_DIR.glob("*.step")) if BIG_DIR.is_dir() else []


@pytest.mark.skipif(not big_files(), reason="no big geometry file")
def test_big_geometry_file_is_fast_and_clean():
    path = big_files()[0]
    text = path.read_bytes().decode("latin-1")
    started = time.perf_counter()
    pop = Population(read_step(text, str(path)))
    out = check_kinematics(pop)
    elapsed = time.perf_counter() - started
    assert out == []
    assert elapsed < 2.0, f"{elapsed:.2f} s"
