"""Schema conformance (p105cli.rules.conformance): one minimal file per rule
id against the AP242 and AP214 long forms, each violating exactly that rule
next to a passing twin; supertype-expression semantics on small schemas;
the authored probes; the big real AP214 files (no false findings, time)."""

from __future__ import annotations

import re
import zlib
from pathlib import Path

import pytest

from conftest import CORPUS, p21
from p105cli.schema import load_schema, parse_schema
from p105cli.step import decode_bytes, read_step
from p105cli.rules.conformance import (
    RULES, Finding, check_instance, check_population, checker_for, step_types_of,
)

SCHEMA_DIR = CORPUS.parent / "schema"
AP214 = SCHEMA_DIR / "AP214E3_2010_automotive_design_longform.exp"
AP242 = SCHEMA_DIR / "AP242_N10962_mim_lf.exp"
AUTHORED = CORPUS / "authored"
BIG = CORPUS / "big"

pytestmark = pytest.mark.skipif(not AP242.is_file() or not AP214.is_file(),
                                reason=f"{SCHEMA_DIR} not present")


@pytest.fixture(scope="module")
def schemas():
    return {"ap242": load_schema(AP242), "ap214": load_schema(AP214)}


def findings_of(text: str, schema) -> list[Finding]:
    sf = read_step(text)
    return list(check_population(sf.records(), schema, step_types_of(sf, schema)))


def edit(base: str, lines: dict) -> str:
    """``base`` with instance #n replaced by ``lines[n]`` (appended when new)."""
    out = base
    for iid, line in lines.items():
        pat = re.compile(rf"^#{iid}=.*$", re.M)
        if pat.search(out):
            out = pat.sub(lambda _m: line, out)
        else:
            out += "\n" + line
    return out


# The AP242 probe written as the standard says (derived slots are '*').
BASE_242 = """\
#1=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));
#2=(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.));
#3=(NAMED_UNIT(*)SI_UNIT($,.STERADIAN.)SOLID_ANGLE_UNIT());
#4=(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNIT_ASSIGNED_CONTEXT((#1,#2,#3))REPRESENTATION_CONTEXT('ctx','3D'));
#5=CARTESIAN_POINT('',(0.,0.,0.));
#6=DIRECTION('',(0.,0.,1.));
#7=DIRECTION('',(1.,0.,0.));
#8=AXIS2_PLACEMENT_3D('frame_base',#5,#6,#7);
#9=AXIS2_PLACEMENT_3D('frame_arm',#5,#6,#7);
#10=KINEMATIC_LINK('base');
#11=KINEMATIC_LINK('arm');
#12=KINEMATIC_JOINT('j1',#10,#11);
#13=RIGID_LINK_REPRESENTATION('base_rep',(#8),#4,#10);
#14=RIGID_LINK_REPRESENTATION('arm_rep',(#9),#4,#11);
#15=REVOLUTE_PAIR('j1',*,$,#8,#9,#12,*,*,*,*,*,*);
#16=PAIR_REPRESENTATION_RELATIONSHIP('j1_rel','j1_rel','',#13,#14,#15);
#17=KINEMATIC_TOPOLOGY_STRUCTURE('topo',(#12),#4);
#18=MECHANISM_REPRESENTATION('mech',(#16),#4,#17);
#19=REVOLUTE_PAIR_VALUE('v',#15,0.5);
#20=MECHANISM_STATE_REPRESENTATION('state',(#19),*,#18);
#21=SU_PARAMETERS('su',0.,0.,0.,0.,0.,0.);"""

# The Part 105:1996 probe in AP214.
BASE_214 = """\
#1=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));
#2=(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.));
#3=(NAMED_UNIT(*)SI_UNIT($,.STERADIAN.)SOLID_ANGLE_UNIT());
#4=(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNIT_ASSIGNED_CONTEXT((#1,#2,#3))REPRESENTATION_CONTEXT('ctx','3D'));
#5=CARTESIAN_POINT('',(0.,0.,0.));
#6=DIRECTION('',(0.,0.,1.));
#7=DIRECTION('',(1.,0.,0.));
#8=AXIS2_PLACEMENT_3D('frame_base',#5,#6,#7);
#9=AXIS2_PLACEMENT_3D('frame_arm',#5,#6,#7);
#10=KINEMATIC_LINK();
#11=KINEMATIC_LINK();
#12=KINEMATIC_JOINT(#10,#11);
#13=KINEMATIC_STRUCTURE((#12));
#14=REVOLUTE_PAIR('j1',$,#8,#9,#12);
#15=REVOLUTE_PAIR_RANGE(#14,PLANE_ANGLE_MEASURE(-1.5),PLANE_ANGLE_MEASURE(1.5));
#16=REVOLUTE_PAIR_VALUE(#14,0.5);
#17=KINEMATIC_LINK_REPRESENTATION('base_rep',(#8),#4);
#18=KINEMATIC_LINK_REPRESENTATION('arm_rep',(#9),#4);
#19=KINEMATIC_LINK_REPRESENTATION_ASSOCIATION('',$,#17,#18);"""

LOW_ORDER = "LOW_ORDER_KINEMATIC_PAIR('j2',*,$,#8,#9,#12,{})"
DIMS = "#23=DIMENSIONAL_EXPONENTS(1.,0.,0.,0.,0.,0.,0.);"

# (schema, rule, severity, instance, attribute, bad edits, good edits)
CASES = [
    # ---------------------------------------------------------------- AP242
    ("ap242", "SCH-UNKNOWN-ENTITY", "error", 21, None,
     {21: "#21=SU_PARAMETRES('su',0.,0.,0.,0.,0.,0.);"}, {}),
    ("ap242", "SCH-ABSTRACT", "error", 22, None,
     {22: "#22=KINEMATIC_PAIR('j2',*,$,#8,#9,#12);"},
     {22: "#22=" + LOW_ORDER.format(".F.,.F.,.F.,.F.,.F.,.T.") + ";"}),
    ("ap242", "SCH-ARITY", "error", 19, None,
     {19: "#19=REVOLUTE_PAIR_VALUE('v',#15);"}, {}),
    ("ap242", "SCH-ARITY", "error", 15, None,  # the Part 105:1996 layout in an AP242 file
     {15: "#15=REVOLUTE_PAIR('j1',$,#8,#9,#12);"}, {}),
    ("ap242", "SCH-DERIVED", "error", 19, "actual_rotation",  # '*' on an explicit attribute
     {19: "#19=REVOLUTE_PAIR_VALUE('v',#15,*);"}, {}),
    ("ap242", "SCH-DERIVED", "error", 15, "r_x",  # '$' on a derived slot
     {15: "#15=REVOLUTE_PAIR('j1',*,$,#8,#9,#12,*,*,*,$,*,*);"}, {}),
    ("ap242", "SCH-OPTIONAL", "error", 19, "actual_rotation",
     {19: "#19=REVOLUTE_PAIR_VALUE('v',#15,$);"}, {}),
    ("ap242", "SCH-OPTIONAL", "error", 15, "transform_item_2",
     {15: "#15=REVOLUTE_PAIR('j1',*,$,#8,$,#12,*,*,*,*,*,*);"}, {}),
    ("ap242", "SCH-TYPE", "error", 19, "actual_rotation",  # STRING for REAL
     {19: "#19=REVOLUTE_PAIR_VALUE('v',#15,'0.5');"}, {}),
    ("ap242", "SCH-TYPE", "error", 19, "actual_rotation",  # INTEGER for REAL
     {19: "#19=REVOLUTE_PAIR_VALUE('v',#15,1);"}, {}),
    ("ap242", "SCH-TYPE", "error", 19, "actual_rotation",  # typed parameter, no SELECT
     {19: "#19=REVOLUTE_PAIR_VALUE('v',#15,PLANE_ANGLE_MEASURE(0.5));"}, {}),
    ("ap242", "SCH-TYPE", "error", 19, "applies_to_pair",  # a joint is not a revolute_pair
     {19: "#19=REVOLUTE_PAIR_VALUE('v',#12,0.5);"}, {}),
    ("ap242", "SCH-TYPE", "error", 15, "transform_item_1",  # not in SELECT rigid_placement
     {15: "#15=REVOLUTE_PAIR('j1',*,$,#5,#9,#12,*,*,*,*,*,*);"},
     {15: "#15=REVOLUTE_PAIR('j1',*,$,#21,#9,#12,*,*,*,*,*,*);"}),  # su_parameters is
    ("ap242", "SCH-TYPE", "error", 22, "t_x",  # BOOLEAN takes no .U.
     {22: "#22=" + LOW_ORDER.format(".U.,.F.,.F.,.F.,.F.,.T.") + ";"},
     {22: "#22=" + LOW_ORDER.format(".T.,.F.,.F.,.F.,.F.,.T.") + ";"}),
    ("ap242", "SCH-TYPE", "error", 1, "si_unit.name",  # not an si_unit_name
     {1: "#1=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.FOOT.));"}, {}),
    ("ap242", "SCH-TYPE", "error", 22, "value_component",  # LABEL is not a measure_value
     {22: "#22=MEASURE_WITH_UNIT(LABEL('x'),#1);"},
     {22: "#22=MEASURE_WITH_UNIT(LENGTH_MEASURE(1.),#1);"}),
    ("ap242", "SCH-TYPE", "error", 22, "value_component",  # untyped: fits many measures
     {22: "#22=MEASURE_WITH_UNIT(1.,#1);"},
     {22: "#22=MEASURE_WITH_UNIT(LENGTH_MEASURE(1.),#1);"}),
    ("ap242", "SCH-TYPE", "error", 22, "value_component",  # typed value of the wrong kind
     {22: "#22=MEASURE_WITH_UNIT(LENGTH_MEASURE('1'),#1);"},
     {22: "#22=MEASURE_WITH_UNIT(LENGTH_MEASURE(1.),#1);"}),
    ("ap242", "SCH-DANGLING", "error", 19, "applies_to_pair",
     {19: "#19=REVOLUTE_PAIR_VALUE('v',#99,0.5);"}, {}),
    ("ap242", "SCH-DANGLING", "error", 17, "items",  # inside an aggregate
     {17: "#17=KINEMATIC_TOPOLOGY_STRUCTURE('topo',(#12,#98),#4);"}, {}),
    ("ap242", "SCH-BOUNDS", "error", 5, "coordinates",  # LIST [1:3]
     {5: "#5=CARTESIAN_POINT('',(0.,0.,0.,0.));"}, {}),
    ("ap242", "SCH-BOUNDS", "error", 17, "items",  # SET [1:?]
     {17: "#17=KINEMATIC_TOPOLOGY_STRUCTURE('topo',(),#4);"}, {}),
    ("ap242", "SCH-SET-UNIQUE", "error", 17, "items",
     {17: "#17=KINEMATIC_TOPOLOGY_STRUCTURE('topo',(#12,#12),#4);"}, {}),
    ("ap242", "SCH-COMPLEX", "error", 1, None,  # not in alphabetical order
     {1: "#1=(NAMED_UNIT(*)LENGTH_UNIT()SI_UNIT(.MILLI.,.METRE.));"}, {}),
    ("ap242", "SCH-COMPLEX", "error", 1, None,  # supertype named_unit missing
     {1: "#1=(LENGTH_UNIT()SI_UNIT(.MILLI.,.METRE.));"}, {}),
    ("ap242", "SCH-COMPLEX", "error", 1, None,  # ONEOF(length_unit, ..., plane_angle_unit, ...)
     {1: "#1=(LENGTH_UNIT()NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT(.MILLI.,.METRE.));"}, {}),
    ("ap242", "SCH-COMPLEX", "error", 1, "si_unit",  # a part's parameter count
     {1: "#1=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.METRE.));"}, {}),
    ("ap242", "SCH-COMPLEX", "error", 1, None,  # a part that is no entity of the schema
     {1: "#1=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.)X_UNIT());"}, {}),
    ("ap242", "SCH-COMPLEX", "error", 1, None,  # a part listed twice
     {1: "#1=(LENGTH_UNIT()NAMED_UNIT(*)NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));"}, {}),
    ("ap242", "SCH-COMPLEX", "warning", 22, None,  # one leaf: internal mapping expected
     {22: "#22=(LENGTH_UNIT()NAMED_UNIT(#23));", 23: DIMS},
     {22: "#22=LENGTH_UNIT(#23);", 23: DIMS}),
    # ---------------------------------------------------------------- AP214
    ("ap214", "SCH-UNKNOWN-ENTITY", "error", 20, None,  # an AP242 name
     {20: "#20=KINEMATIC_TOPOLOGY_STRUCTURE('topo',(#12),#4);"}, {}),
    ("ap214", "SCH-ABSTRACT", "error", 20, None,
     {20: "#20=GENERIC_LITERAL();"}, {20: "#20=BOOLEAN_LITERAL(.T.);"}),
    ("ap214", "SCH-ARITY", "error", 12, None,
     {12: "#12=KINEMATIC_JOINT(#10);"}, {}),
    ("ap214", "SCH-ARITY", "error", 19, None,  # the AP242 layout in an AP214 file
     {19: "#19=REVOLUTE_PAIR_VALUE('v',#14,0.5);"}, {19: "#19=REVOLUTE_PAIR_VALUE(#14,0.5);"}),
    ("ap214", "SCH-DERIVED", "error", 14, "description",
     {14: "#14=REVOLUTE_PAIR('j1',*,#8,#9,#12);"}, {}),
    ("ap214", "SCH-OPTIONAL", "error", 14, "name",
     {14: "#14=REVOLUTE_PAIR($,$,#8,#9,#12);"}, {}),
    ("ap214", "SCH-TYPE", "error", 15, "lower_limit_actual_rotation",  # not in the SELECT
     {15: "#15=REVOLUTE_PAIR_RANGE(#14,LENGTH_MEASURE(-1.5),PLANE_ANGLE_MEASURE(1.5));"},
     {15: "#15=REVOLUTE_PAIR_RANGE(#14,.UNLIMITED.,PLANE_ANGLE_MEASURE(1.5));"}),
    ("ap214", "SCH-TYPE", "error", 15, "upper_limit_actual_rotation",  # enum item of the SELECT
     {15: "#15=REVOLUTE_PAIR_RANGE(#14,PLANE_ANGLE_MEASURE(-1.5),.UNBOUNDED.);"},
     {15: "#15=REVOLUTE_PAIR_RANGE(#14,PLANE_ANGLE_MEASURE(-1.5),UNLIMITED_RANGE(.UNLIMITED.));"}),
    ("ap214", "SCH-TYPE", "error", 12, "second_link",
     {12: "#12=KINEMATIC_JOINT(#10,#13);"}, {}),
    ("ap214", "SCH-DANGLING", "error", 16, "applies_to_pair",
     {16: "#16=REVOLUTE_PAIR_VALUE(#99,0.5);"}, {}),
    ("ap214", "SCH-BOUNDS", "error", 13, "joints",
     {13: "#13=KINEMATIC_STRUCTURE(());"}, {}),
    ("ap214", "SCH-BOUNDS", "error", 6, "direction_ratios",  # LIST [2:3]
     {6: "#6=DIRECTION('',(1.));"}, {}),
    ("ap214", "SCH-SET-UNIQUE", "error", 13, "joints",
     {13: "#13=KINEMATIC_STRUCTURE((#12,#12));"}, {}),
    ("ap214", "SCH-COMPLEX", "error", 2, None,
     {2: "#2=(NAMED_UNIT(*)SI_UNIT($,.RADIAN.)PLANE_ANGLE_UNIT());"}, {}),
]


def _case_id(case):
    schema, rule, _sev, iid, attr, bad, _good = case
    # a digest, not hash(): ids must be the same in every process (pytest-xdist workers)
    return f"{schema}-{rule}-#{iid}-{attr or ''}-{zlib.crc32(str(bad).encode()) % 10000}"


@pytest.mark.parametrize("base", ["ap242", "ap214"])
def test_bases_are_clean(schemas, base):
    body = BASE_242 if base == "ap242" else BASE_214
    assert findings_of(p21(body), schemas[base]) == []


@pytest.mark.parametrize("case", CASES, ids=[_case_id(c) for c in CASES])
def test_rule_and_twin(schemas, case):
    name, rule, severity, iid, attr, bad, good = case
    base = BASE_242 if name == "ap242" else BASE_214
    schema = schemas[name]
    got = findings_of(p21(edit(base, bad)), schema)
    assert [(f.rule, f.severity, f.entity, f.attribute) for f in got] == \
        [(rule, severity, iid, attr)], got
    assert got[0].message and got[0].entity_type
    assert findings_of(p21(edit(base, good)), schema) == []


def test_every_rule_has_a_case():
    assert {c[1] for c in CASES} == set(RULES)
    for c in CASES:
        assert c[1] in RULES


def test_messages_are_specific(schemas):
    s = schemas["ap242"]
    (f,) = findings_of(p21(edit(BASE_242, {19: "#19=REVOLUTE_PAIR_VALUE('v',#12,0.5);"})), s)
    assert "#12 is a kinematic_joint" in f.message and "revolute_pair" in f.message
    (f,) = findings_of(p21(edit(BASE_242, {5: "#5=CARTESIAN_POINT('',(0.,0.,0.,0.));"})), s)
    assert "4 elements" in f.message and "[1:3]" in f.message
    (f,) = findings_of(p21(edit(BASE_242, {17: "#17=KINEMATIC_TOPOLOGY_STRUCTURE('t',(#12,#10),#4);"})), s)
    assert f.rule == "SCH-TYPE" and f.attribute == "items" and f.message.startswith("[1]: ")
    (f,) = findings_of(p21(edit(BASE_242, {15: "#15=REVOLUTE_PAIR('j1',*,$,#8,#9,#12);"})), s)
    assert "12 parameters" in f.message and "*t_x" in f.message and "found 6" in f.message
    (f,) = findings_of(p21(edit(BASE_242, {1: "#1=(NAMED_UNIT(*)LENGTH_UNIT()SI_UNIT(.MILLI.,.METRE.));"})), s)
    assert "LENGTH_UNIT NAMED_UNIT SI_UNIT" in f.message
    assert f.entity_type == "named_unit+length_unit+si_unit"


def test_check_instance_direct(schemas):
    s = schemas["ap242"]
    types = {5: frozenset({"cartesian_point", "point", "geometric_representation_item",
                           "representation_item"})}
    rec = {"id": 1, "type": "vertex_point", "args": ["", {"ref": 5}]}
    assert check_instance(rec, s, types.get) == []
    rec = {"id": 1, "type": "vertex_point", "args": ["", {"ref": 6}]}
    (f,) = check_instance(rec, s, types.get)
    assert (f.rule, f.attribute, f.entity, f.entity_type) == ("SCH-DANGLING", "vertex_geometry", 1,
                                                               "vertex_point")
    # a reference to an instance of a type the schema does not know is not
    # reported again here (its own instance carries SCH-UNKNOWN-ENTITY)
    assert check_instance({"id": 1, "type": "vertex_point", "args": ["", {"ref": 7}]}, s,
                          {7: frozenset({"mystery"})}.get) == []


# --------------------------------------------------------------------------
# small schemas: supertype expressions, aggregates, selects

SMALL = """
SCHEMA small;
TYPE len = REAL; END_TYPE;
TYPE ang = REAL; END_TYPE;
TYPE count = INTEGER; END_TYPE;
TYPE colour = ENUMERATION OF (red, green); END_TYPE;
TYPE inner_sel = SELECT (len, colour, pt); END_TYPE;
TYPE outer_sel = SELECT (inner_sel, count); END_TYPE;
TYPE two_reals = SELECT (len, ang); END_TYPE;
ENTITY pt; x : REAL; END_ENTITY;
ENTITY root ABSTRACT SUPERTYPE OF (ONEOF(a, b) AND ONEOF(c, d)); r : INTEGER; END_ENTITY;
ENTITY a SUBTYPE OF (root); END_ENTITY;
ENTITY b SUBTYPE OF (root); END_ENTITY;
ENTITY c SUBTYPE OF (root); END_ENTITY;
ENTITY d SUBTYPE OF (root); END_ENTITY;
ENTITY z SUPERTYPE OF (ONEOF(p, q) ANDOR ONEOF(q, r) ANDOR s); END_ENTITY;
ENTITY p SUBTYPE OF (z); END_ENTITY;
ENTITY q SUBTYPE OF (z); END_ENTITY;
ENTITY r SUBTYPE OF (z); END_ENTITY;
ENTITY s SUBTYPE OF (z); END_ENTITY;
ENTITY t SUBTYPE OF (z); END_ENTITY;
ENTITY holder;
  n : INTEGER;
  by_expr : LIST [1:n] OF REAL;
  arr : ARRAY [1:3] OF OPTIONAL INTEGER;
  ulist : LIST OF UNIQUE pt;
  pts : BAG OF pt;
  sel : outer_sel;
  amb : two_reals;
  logic : LOGICAL;
  bits : BINARY;
  num : NUMBER;
  nested : LIST [1:2] OF LIST [2:2] OF INTEGER;
  opt : OPTIONAL STRING;
END_ENTITY;
END_SCHEMA;
"""

TYPES = {1: frozenset({"pt"}), 2: frozenset({"pt"}), 3: frozenset({"a", "root"})}
GOOD = [3, [1.0, 2.0, 3.0], [1, None, 3], [{"ref": 1}, {"ref": 2}], [{"ref": 1}, {"ref": 1}],
        {"type": "LEN", "value": 1.0}, {"type": "ANG", "value": 1.0}, {"enum": "U"},
        {"binary": "0FF"}, 2, [[1, 2], [3, 4]], None]


@pytest.fixture(scope="module")
def small():
    return parse_schema(SMALL)


def _holder(small, index=None, value=None):
    args = list(GOOD)
    if index is not None:
        args[index] = value
    return check_instance({"id": 9, "type": "holder", "args": args}, small, TYPES.get)


@pytest.mark.parametrize("combo,ok", [
    (["a", "c", "root"], True),
    (["a", "d", "root"], True),
    (["a", "root"], False),            # AND: one of c, d needed too
    (["a", "b", "c", "root"], False),  # ONEOF(a, b)
    (["p", "r", "z"], True),
    (["q", "z"], True),
    (["p", "q", "z"], False),          # ONEOF(p, q)
    (["q", "r", "z"], False),          # ONEOF(q, r)
    (["p", "r", "s", "t", "z"], True),  # t: not in the expression, free
])
def test_supertype_expressions(small, combo, ok):
    parts = [{"type": n, "args": [1] if n == "root" else []} for n in sorted(combo, key=str.upper)]
    got = check_instance({"id": 1, "complex": parts}, small, TYPES.get)
    errors = [f for f in got if f.severity == "error"]
    assert (errors == []) == ok, got
    assert all(f.rule == "SCH-COMPLEX" for f in errors)


def test_simple_instance_against_supertype_expression(small):
    (f,) = check_instance({"id": 1, "type": "a", "args": [1]}, small, TYPES.get)
    assert f.rule == "SCH-COMPLEX" and "cannot be instantiated alone" in f.message
    assert check_instance({"id": 1, "type": "p", "args": []}, small, TYPES.get) == []
    (f,) = check_instance({"id": 1, "type": "root", "args": [1]}, small, TYPES.get)
    assert f.rule == "SCH-ABSTRACT"
    got = check_instance({"id": 1, "complex": [{"type": "root", "args": [1]}]}, small, TYPES.get)
    assert [(f.rule, f.severity) for f in got] == [("SCH-ABSTRACT", "error"),
                                                   ("SCH-COMPLEX", "warning")]


def test_small_holder_good(small):
    assert _holder(small) == []
    # an untyped value accepted when exactly one defined type of the select fits
    assert _holder(small, 5, {"enum": "RED"}) == []
    assert _holder(small, 5, 7) == []  # only count is an INTEGER
    assert _holder(small, 5, {"ref": 1}) == []  # pt through the nested select
    assert _holder(small, 5, {"type": "COLOUR", "value": {"enum": "GREEN"}}) == []
    assert _holder(small, 9, 2.5) == []  # NUMBER


@pytest.mark.parametrize("index,value,rule,needle", [
    (2, [1, 2, 3, 4], "SCH-BOUNDS", "ARRAY [1:3]"),
    (2, [1, None, {"derived": True}], "SCH-DERIVED", "[2]"),
    (3, [{"ref": 1}, {"ref": 1}], "SCH-SET-UNIQUE", "[1] = [0]"),
    (3, [{"ref": 1}, None], "SCH-OPTIONAL", "[1]"),
    (5, {"type": "INNER_SEL", "value": 1.0}, "SCH-TYPE", "not a defined type of select"),
    (5, {"type": "LEN", "value": "x"}, "SCH-TYPE", "LEN(...)"),
    (5, {"ref": 3}, "SCH-TYPE", "#3 is an a"),
    (5, {"ref": 4}, "SCH-DANGLING", "#4"),
    (5, "text", "SCH-TYPE", "not a value of select outer_sel"),
    (6, 1.0, "SCH-TYPE", "ambiguous"),
    (7, {"enum": "X"}, "SCH-TYPE", "LOGICAL"),
    (8, "0FF", "SCH-TYPE", "BINARY"),
    (9, "2", "SCH-TYPE", "NUMBER"),
    (10, [[1, 2], [3]], "SCH-BOUNDS", "[1]: 1 element"),
    (10, [[1, 2], [3, 4.0]], "SCH-TYPE", "[1]: [1]: expected INTEGER"),
    (11, 5, "SCH-TYPE", "STRING"),
])
def test_small_holder_bad(small, index, value, rule, needle):
    got = _holder(small, index, value)
    assert [f.rule for f in got] == [rule], got
    assert needle in got[0].message, got[0].message


def test_expression_bounds_are_counted_not_checked(small):
    stats = checker_for(small).stats
    before = stats["bounds_skipped"]
    assert _holder(small, 1, [1.0] * 10) == []  # n = 3: [1:n] is not evaluated
    assert stats["bounds_skipped"] == before + 1


# --------------------------------------------------------------------------
# the authored probes


def _file_findings(path: Path, schema):
    return findings_of(decode_bytes(path.read_bytes()), schema)


needs_authored = pytest.mark.skipif(not AUTHORED.is_dir(), reason="corpus/authored not present")


@needs_authored
def test_probe_standard_star_is_clean(schemas):
    assert _file_findings(AUTHORED / "probe_standard_star.stp", schemas["ap242"]) == []


@needs_authored
def test_probe_occt_style_values_where_the_standard_derives_are_left_to_derived(schemas):
    # explicit values in derived slots are compared with the derivation by rules/derived.py
    # (tests/rules/test_derived.py); the instance-level check neither passes nor fails them
    assert _file_findings(AUTHORED / "probe_occt_style.stp", schemas["ap242"]) == []


@pytest.mark.parametrize("name,iid,line", [
    ("ap242", 15, "#15=REVOLUTE_PAIR('j1',*,$,#8,#9,#12,*,*,*,*,*,.T.);"),
    ("ap242", 15, "#15=REVOLUTE_PAIR('j1','j1',$,#8,#9,#12,*,*,*,*,*,*);"),
    ("ap242", 20, "#20=MECHANISM_STATE_REPRESENTATION('state',(#19),#4,#18);"),
    ("ap214", 1, "#1=(LENGTH_UNIT()NAMED_UNIT(#23)SI_UNIT(.MILLI.,.METRE.));"),
])
def test_explicit_values_in_derived_slots_are_not_conformance_findings(schemas, name, iid, line):
    base = BASE_242 if name == "ap242" else BASE_214
    assert findings_of(p21(edit(base, {iid: line, 23: DIMS})), schemas[name]) == []


@needs_authored
def test_probe_p105_1996_ap214_is_clean(schemas):
    # REVOLUTE_PAIR_RANGE(#14,-1.5,1.5): untyped values of SELECT
    # rotational_range_measure; accepted (and counted) as only
    # plane_angle_measure fits, where Part 21 asks for PLANE_ANGLE_MEASURE(-1.5)
    stats = checker_for(schemas["ap214"]).stats
    before = dict(stats)
    assert _file_findings(AUTHORED / "probe_p105_1996_ap214.stp", schemas["ap214"]) == []
    assert stats["untyped_select_values"] - before["untyped_select_values"] == 2


@needs_authored
def test_probe_p105_1996_against_ap242_is_full_of_findings(schemas):
    got = _file_findings(AUTHORED / "probe_p105_1996_ap214.stp", schemas["ap242"])
    rules = {f.rule for f in got}
    assert {"SCH-ARITY", "SCH-UNKNOWN-ENTITY", "SCH-ABSTRACT"} <= rules


# --------------------------------------------------------------------------
# big real files: no false findings, and fast

BIG_FILES = sorted(BIG.glob("*.step")) if BIG.is_dir() else []
# These AUTOMOTIVE_DESIGN_CC2 files use two entities the AP214 long form
# (edition 3) no longer has: unknown to the schema p105 checks with, and
# reported (validate makes them warnings: the declared schema, a draft p105
# has no long form of, may know them; tests/rules/test_validate.py).
EXPECTED_UNKNOWN = {"mechanical_context", "product_type"}


@pytest.mark.parametrize("path", BIG_FILES, ids=[p.name[:24] for p in BIG_FILES])
def test_big_real_files(schemas, path):
    schema = schemas["ap214"]
    sf = read_step(decode_bytes(path.read_bytes()), str(path))
    got = list(check_population(sf.records(), schema, step_types_of(sf, schema)))
    assert {(f.rule, f.entity_type) for f in got} <= {("SCH-UNKNOWN-ENTITY", n)
                                                       for n in EXPECTED_UNKNOWN}


# --------------------------------------------------------------------------
# robustness: any decoded value anywhere gives findings, never an exception

from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

_scalar = st.one_of(
    st.integers(-5, 5), st.floats(allow_nan=False, width=32), st.text(max_size=3), st.none(),
    st.builds(lambda i: {"ref": i}, st.integers(0, 6)),
    st.sampled_from([{"enum": "T"}, {"enum": "F"}, {"enum": "U"}, {"enum": "METRE"},
                     {"derived": True}, {"binary": "0FF"}]),
)
_value = st.recursive(
    _scalar,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4),
        st.builds(lambda t, v: {"type": t, "value": v},
                  st.sampled_from(["LENGTH_MEASURE", "LABEL", "PLANE_ANGLE_MEASURE", "NOPE"]),
                  inner)),
    max_leaves=8)
_NAMES = ["revolute_pair", "si_unit", "named_unit", "length_unit", "cartesian_point",
          "measure_with_unit", "kinematic_topology_structure", "representation_context",
          "b_spline_curve_with_knots", "kinematic_pair", "nonsense"]
_TYPES_OF = {1: frozenset({"cartesian_point", "point", "geometric_representation_item",
                           "representation_item"}),
             2: frozenset({"kinematic_joint", "edge", "topological_representation_item",
                           "representation_item"}),
             3: frozenset({"mystery"})}.get


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=st.sampled_from(_NAMES), args=st.lists(_value, max_size=14),
       parts=st.lists(st.tuples(st.sampled_from(_NAMES), st.lists(_value, max_size=4)),
                      min_size=1, max_size=4))
def test_never_raises(schemas, name, args, parts):
    s = schemas["ap242"]
    for rec in ({"id": 7, "type": name, "args": args},
                {"id": 8, "complex": [{"type": n, "args": a} for n, a in parts]}):
        for f in check_instance(rec, s, _TYPES_OF):
            assert f.rule in RULES and f.severity in ("error", "warning") and f.message
