"""The EXPRESS evaluator (p105cli.schema.evaluator).

Units on a small hand-written schema and population (operators and
precedence, ``?`` propagation, every built-in, QUERY, USEDIN, TYPEOF,
functions with loops, entity constructors), then the real long forms on the
kinematics probes: every WHERE rule of the kinematics instances and of the
instances they reference evaluates (coverage is reported), mutated copies
violate exactly the rules they should, and the 1996 Part 105 functions
(convert_spatial_to_ypr_rotation, unit conversions) agree with the numpy
placements module."""

from __future__ import annotations

import functools
import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import CORPUS, EXAMPLES, SHARED
from p105cli.schema import parse_schema
from p105cli.schema.evaluator import (
    INDETERMINATE, Agg, EntityValue, EnumValue, Evaluator, NotEvaluable, TypedValue,
)
from p105cli.schema.population import Population
from p105cli.step import read_step

TEST_SCHEMA = r"""
SCHEMA test_schema;

TYPE label = STRING; END_TYPE;
TYPE length_measure = REAL; END_TYPE;
TYPE positive_length_measure = length_measure;
WHERE
  wr1 : SELF > 0.0;
END_TYPE;
TYPE colour = ENUMERATION OF (red, green, blue); END_TYPE;
TYPE unlimited_range = ENUMERATION OF (unlimited); END_TYPE;
TYPE range_measure = SELECT (length_measure, unlimited_range); END_TYPE;
TYPE shape_select = SELECT (point, segment); END_TYPE;
TYPE outer_select = SELECT (shape_select); END_TYPE;
TYPE triple = ARRAY [1:3] OF REAL; END_TYPE;

CONSTANT
  unit_name : STRING := 'metre';
  dummy_item : item := item('dummy');
END_CONSTANT;

ENTITY item;
  name : label;
END_ENTITY;

ENTITY point
  SUBTYPE OF (item);
  x : REAL;
  y : REAL;
DERIVE
  norm : REAL := SQRT(x ** 2 + y ** 2);
WHERE
  wr1 : norm >= 0.0;
  wr2 : EXISTS(name);
END_ENTITY;

ENTITY segment
  SUBTYPE OF (item);
  p1 : point;
  p2 : point;
DERIVE
  length : length_measure := distance(p1, p2);
WHERE
  wr1 : p1 :<>: p2;
  wr2 : length > 0.0;
END_ENTITY;

ENTITY polyline
  SUBTYPE OF (item);
  points : LIST [2:?] OF point;
UNIQUE
  ur1 : SELF\item.name;
WHERE
  wr1 : SIZEOF(QUERY(p <* points | p.x < 0.0)) = 0;
  wr2 : SIZEOF(points) = HIINDEX(points);
END_ENTITY;

ENTITY tagged
  SUBTYPE OF (item);
  colour : colour;
  size : OPTIONAL positive_length_measure;
WHERE
  wr1 : colour <> blue;
  wr2 : NOT EXISTS(size) OR (size > 1.0);
END_ENTITY;

ENTITY ranged;
  lo : range_measure;
  hi : range_measure;
WHERE
  wr1 : ('TEST_SCHEMA.UNLIMITED_RANGE' IN TYPEOF(lo)) OR
        ('TEST_SCHEMA.UNLIMITED_RANGE' IN TYPEOF(hi)) XOR (lo < hi);
END_ENTITY;

ENTITY node;
INVERSE
  users : SET [0:?] OF edge FOR ends;
  owner : graph FOR nodes;
END_ENTITY;

ENTITY edge;
  ends : LIST [2:2] OF node;
WHERE
  wr1 : ends[1] :<>: ends[2];
END_ENTITY;

ENTITY graph;
  nodes : SET [1:?] OF node;
END_ENTITY;

ENTITY a_part
  SUPERTYPE OF (b_part ANDOR c_part);
  a1 : INTEGER;
END_ENTITY;

ENTITY b_part
  SUBTYPE OF (a_part);
  b1 : STRING;
DERIVE
  twice : INTEGER := 2 * a1;
END_ENTITY;

ENTITY c_part
  SUBTYPE OF (a_part);
  c1 : REAL;
WHERE
  wr1 : c1 > a1;
END_ENTITY;

ENTITY vec;
  coords : LIST [1:3] OF REAL;
END_ENTITY;

FUNCTION distance(a : point; b : point) : length_measure;
  RETURN (SQRT((a.x - b.x) ** 2 + (a.y - b.y) ** 2));
END_FUNCTION;

FUNCTION fact(n : INTEGER) : INTEGER;
  IF n <= 1 THEN
    RETURN (1);
  END_IF;
  RETURN (n * fact(n - 1));
END_FUNCTION;

FUNCTION sum_to(n : INTEGER; step : INTEGER) : INTEGER;
LOCAL
  s : INTEGER := 0;
END_LOCAL;
  REPEAT i := 1 TO n BY step;
    s := s + i;
  END_REPEAT;
  RETURN (s);
END_FUNCTION;

FUNCTION first_over(vals : LIST OF REAL; limit : REAL) : INTEGER;
LOCAL
  k : INTEGER := 0;
END_LOCAL;
  REPEAT i := 1 TO SIZEOF(vals);
    IF vals[i] <= limit THEN
      SKIP;
    END_IF;
    k := i;
    ESCAPE;
  END_REPEAT;
  RETURN (k);
END_FUNCTION;

FUNCTION count_while(limit : INTEGER) : INTEGER;
LOCAL
  n : INTEGER := 0;
END_LOCAL;
  REPEAT WHILE n < limit;
    n := n + 1;
  END_REPEAT;
  REPEAT UNTIL n >= 2 * limit;
    n := n + 1;
  END_REPEAT;
  RETURN (n);
END_FUNCTION;

FUNCTION colour_code(c : colour) : INTEGER;
  CASE c OF
    red : RETURN (1);
    colour.green : RETURN (2);
    OTHERWISE : RETURN (0);
  END_CASE;
END_FUNCTION;

FUNCTION as_set(b : BAG OF GENERIC : t) : SET OF GENERIC : t;
LOCAL
  s : SET OF GENERIC : t := [];
END_LOCAL;
  REPEAT i := 1 TO HIINDEX(b);
    s := s + b[i];
  END_REPEAT;
  RETURN (s);
END_FUNCTION;

FUNCTION scaled(v : vec; f : REAL) : vec;
LOCAL
  r : vec;
END_LOCAL;
  r := vec(v.coords);
  REPEAT i := 1 TO SIZEOF(r.coords);
    r.coords[i] := r.coords[i] * f;
  END_REPEAT;
  RETURN (r);
END_FUNCTION;

FUNCTION matrix_trace(n : INTEGER) : REAL;
LOCAL
  m : ARRAY [1:3] OF ARRAY [1:3] OF REAL;
  t : REAL := 0.0;
END_LOCAL;
  m := [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]];
  m[2][2] := 50.0;
  REPEAT i := 1 TO n;
    t := t + m[i][i];
  END_REPEAT;
  RETURN (t);
END_FUNCTION;

FUNCTION to_array(lis : LIST OF GENERIC : t; low : INTEGER) : ARRAY [low:?] OF GENERIC : t;
LOCAL
  res : ARRAY [low:low + SIZEOF(lis) - 1] OF GENERIC : t;
END_LOCAL;
  res := [lis[1] : SIZEOF(lis)];
  REPEAT i := 2 TO SIZEOF(lis);
    res[low + i - 1] := lis[i];
  END_REPEAT;
  RETURN (res);
END_FUNCTION;

FUNCTION alias_sum(v : vec) : REAL;
LOCAL
  total : REAL := 0.0;
END_LOCAL;
  ALIAS c FOR v.coords;
    REPEAT i := 1 TO SIZEOF(c);
      total := total + c[i];
    END_REPEAT;
  END_ALIAS;
  RETURN (total);
END_FUNCTION;

FUNCTION with_insert(n : INTEGER) : LIST OF INTEGER;
LOCAL
  l : LIST OF INTEGER := [];
END_LOCAL;
  REPEAT i := 1 TO n;
    INSERT(l, i, 0);
  END_REPEAT;
  REMOVE(l, 1);
  RETURN (l);
END_FUNCTION;

FUNCTION maybe(flag : BOOLEAN) : REAL;
  IF flag THEN
    RETURN (1.0);
  END_IF;
  RETURN (?);
END_FUNCTION;

FUNCTION swap_digits(a : INTEGER; b : INTEGER) : INTEGER;
  PROCEDURE swap(VAR p : INTEGER; VAR q : INTEGER);
  LOCAL
    t : INTEGER;
  END_LOCAL;
    t := p;
    p := q;
    q := t;
  END_PROCEDURE;
  FUNCTION twice(n : INTEGER) : INTEGER;
    RETURN (2 * n);
  END_FUNCTION;
LOCAL
  x : INTEGER := a;
  y : INTEGER := b;
END_LOCAL;
  swap(x, y);
  RETURN (twice(x) * 10 + y);
END_FUNCTION;

FUNCTION poke(v : vec) : REAL;
  v.coords[1] := 99.0;
  RETURN (v.coords[1]);
END_FUNCTION;

FUNCTION forever(n : INTEGER) : INTEGER;
  RETURN (forever(n + 1));
END_FUNCTION;

RULE at_most_two_graphs FOR (graph);
WHERE
  wr1 : SIZEOF(graph) <= 2;
  wr2 : SIZEOF(QUERY(g <* graph | SIZEOF(g.nodes) > 1)) >= 1;
END_RULE;

END_SCHEMA;
"""

TEST_DATA = """ISO-10303-21;
HEADER;
FILE_DESCRIPTION((''),'2;1');
FILE_NAME('t.stp','2026-01-01T00:00:00',(''),(''),'','','');
FILE_SCHEMA(('TEST_SCHEMA'));
ENDSEC;
DATA;
#1=POINT('p1',0.,0.);
#2=POINT('p2',3.,4.);
#3=SEGMENT('s',#1,#2);
#4=SEGMENT('degenerate',#1,#1);
#5=POLYLINE('pl',(#1,#2,#1));
#6=POLYLINE('pl',(#2,#1));
#7=TAGGED('t',.RED.,$);
#8=TAGGED('t2',.BLUE.,POSITIVE_LENGTH_MEASURE(0.5));
#9=RANGED(LENGTH_MEASURE(1.),.UNLIMITED.);
#10=RANGED(LENGTH_MEASURE(2.),LENGTH_MEASURE(1.));
#11=NODE();
#12=NODE();
#13=EDGE((#11,#12));
#14=EDGE((#12,#12));
#15=GRAPH((#11,#12));
#16=(A_PART(1)B_PART('b')C_PART(0.5));
#17=(A_PART(2)C_PART(3.));
#18=VEC((1.,2.,3.));
#19=POINT('neg',-1.,0.);
ENDSEC;
END-ISO-10303-21;
"""


RADIAN = "#2=(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.));"
DEGREE = ("#2=(CONVERSION_BASED_UNIT('DEGREE',#30)NAMED_UNIT(*)PLANE_ANGLE_UNIT());\n"
          "#30=PLANE_ANGLE_MEASURE_WITH_UNIT(PLANE_ANGLE_MEASURE(0.0174532925199433),#31);\n"
          "#31=(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.));")

def mechanism_1996(angle_unit=RADIAN, axis=(0.0, 0.0, 1.0), angle=0.5, skew="$",
                   screw_rotation=3.141592653589793, displacement=5.0, extra=""):
    ax = ",".join(repr(float(x)) if not float(x).is_integer() else f"{x:.1f}" for x in axis)
    return f"""ISO-10303-21;
HEADER;
FILE_DESCRIPTION(('test mechanism, Part 105:1996 layout'),'2;1');
FILE_NAME('mech.stp','2026-01-01T00:00:00',(''),(''),'','','');
FILE_SCHEMA(('AUTOMOTIVE_DESIGN {{ 1 0 10303 214 3 1 1 }}'));
ENDSEC;
DATA;
#1=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));
{angle_unit}
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
#13=KINEMATIC_STRUCTURE((#12,#40,#41,#42,#43,#44));
#14=REVOLUTE_PAIR('j1',$,#8,#9,#12);
#15=REVOLUTE_PAIR_RANGE(#14,-1.5,1.5);
#16=REVOLUTE_PAIR_VALUE(#14,0.5);
#17=KINEMATIC_LINK_REPRESENTATION('base_rep',(#8),#4);
#18=KINEMATIC_LINK_REPRESENTATION('arm_rep',(#9),#4);
#19=KINEMATIC_LINK_REPRESENTATION_ASSOCIATION('',$,#17,#24);
#20=KINEMATIC_LINK_REPRESENTATION_RELATION(#10,#17);
#21=KINEMATIC_LINK_REPRESENTATION_RELATION(#11,#18);
#22=CHARACTERIZED_OBJECT('arm',$);
#23=KINEMATIC_PROPERTY_DEFINITION('kinematics','',#22,#22);
#24=SHAPE_REPRESENTATION('base shape',(#8,#60),#4);
#25=MECHANISM(#13,#10,#23);
#40=KINEMATIC_JOINT(#10,#11);
#41=KINEMATIC_JOINT(#10,#11);
#42=KINEMATIC_JOINT(#10,#11);
#43=KINEMATIC_JOINT(#10,#11);
#44=KINEMATIC_JOINT(#10,#11);
#50=SPHERICAL_PAIR('s',$,#8,#9,#40);
#51=SPHERICAL_PAIR_VALUE(#50,#61);
#52=UNIVERSAL_PAIR('u',$,#8,#9,#41,{skew});
#53=SCREW_PAIR('sc',$,#8,#9,#42,2.);
#54=SCREW_PAIR_VALUE(#53,{screw_rotation!r});
#55=RACK_AND_PINION_PAIR('rp',$,#8,#9,#43,10.);
#56=RACK_AND_PINION_PAIR_VALUE(#55,{displacement!r});
#57=CYLINDRICAL_PAIR('cy',$,#8,#9,#44);
#58=CYLINDRICAL_PAIR_RANGE(#57,.UNLIMITED.,.UNLIMITED.,PLANE_ANGLE_MEASURE(-1.),PLANE_ANGLE_MEASURE(1.));
#59=SPHERICAL_PAIR_VALUE(#50,YPR_ROTATION((0.1,0.2,0.3)));
#60=DIRECTION('axis',({ax}));
#61=ROTATION_ABOUT_DIRECTION(#60,{angle!r});
{extra}
ENDSEC;
END-ISO-10303-21;
"""


# --------------------------------------------------------------------------
# fixtures and helpers

@functools.cache
def evaluator(pop) -> Evaluator:
    """One evaluator per population, as the validator keeps one."""
    return Evaluator(pop)


def derived(inst, name):
    return evaluator(inst.pop).derived_value(inst, name)


def value(inst, name):
    return evaluator(inst.pop).attribute(inst, name)


@pytest.fixture(scope="module")
def tpop():
    return Population(read_step(TEST_DATA), parse_schema(TEST_SCHEMA))


@pytest.fixture(scope="module")
def ev(tpop):
    return evaluator(tpop)


def expr_ast(text: str):
    s = parse_schema(f"SCHEMA x; CONSTANT c : GENERIC := {text}; END_CONSTANT; END_SCHEMA;")
    return s.constants["c"].value


def E(ev, text, self_obj=None, **variables):
    return ev.eval(expr_ast(text), self_obj, variables=variables)


def plain(v):
    if isinstance(v, TypedValue):
        return v.value
    if isinstance(v, Agg):
        return [plain(x) for x in v]
    return v


# --------------------------------------------------------------------------
# operators, precedence, ? propagation


@pytest.mark.parametrize("text,expected", [
    ("2 + 3 * 4", 14), ("(2 + 3) * 4", 20), ("10 - 4 - 3", 3), ("12 / 4 / 3", 1.0),
    ("2 * 3 ** 2", 18), ("-2 ** 2", 4), ("2 ** 3", 8), ("2 ** -1", 0.5), ("7 DIV 2", 3),
    ("7 MOD 3", 1), ("-7 DIV 2", -4), ("-7 MOD 3", 2), ("1 / 2", 0.5), ("-(3)", -3),
    ("1 + 2 = 3", True), ("3 > 2", True), ("3 >= 3", True), ("2 <> 2", False), ("1 = 1.0", True),
    ("NOT FALSE AND FALSE", False), ("TRUE OR FALSE AND FALSE", True),
    ("TRUE XOR TRUE OR TRUE", True), ("FALSE OR TRUE XOR TRUE", False),
    ("TRUE AND UNKNOWN", None), ("FALSE AND UNKNOWN", False), ("TRUE OR UNKNOWN", True),
    ("FALSE OR UNKNOWN", None), ("NOT UNKNOWN", None), ("UNKNOWN XOR TRUE", None),
    ("FALSE < UNKNOWN", True), ("UNKNOWN < TRUE", True),
    ("'A' + 'B' IN ['AB', 'C']", True), ("'ab' + 'cd'", "abcd"), ("'a' < 'b'", True),
    ("{1 < 2 <= 3}", True), ("{1 < 5 <= 3}", False), ("{1 <= 1 < 3}", True),
    ("red < blue", True), ("colour.red = red", True), ("colour.green <> red", True),
    ("%101 = %101", True),
])
def test_operators_and_precedence(ev, text, expected):
    r = E(ev, text)
    assert type(r) is type(expected) and r == expected or r is expected, (text, r)


@pytest.mark.parametrize("text,expected", [
    ("? + 1", INDETERMINATE), ("? * 0", INDETERMINATE), ("-?", INDETERMINATE),
    ("'a' + ?", INDETERMINATE), ("[1, 2] + ?", INDETERMINATE), ("2 ** ?", INDETERMINATE),
    ("? = ?", None), ("? <> 1", None), ("? < 1", None), ("? IN [1]", None), ("1 IN ?", None),
    ("? :=: ?", None), ("? :<>: 1", None), ("NOT ?", INDETERMINATE), ("? AND FALSE", False),
    ("? OR TRUE", True), ("? AND TRUE", None), ("? XOR TRUE", None), ("[1, ?][2]", INDETERMINATE),
    ("[1, 2][3]", INDETERMINATE), ("[1, 2][?]", INDETERMINATE), ("SIZEOF(?)", INDETERMINATE),
    ("EXISTS(?)", False), ("EXISTS(UNKNOWN)", True), ("NVL(?, 2)", 2), ("NVL(1, 2)", 1),
    ("ABS(?)", INDETERMINATE), ("SQRT(-1.0)", INDETERMINATE), ("10 / 0", INDETERMINATE),
    ("QUERY(x <* ? | TRUE)", INDETERMINATE), ("{1 < ? < 3}", None),
    ("? || item('x')", INDETERMINATE),
    ("maybe(FALSE) + 1.0", INDETERMINATE), ("HIINDEX(?)", INDETERMINATE),
])
def test_indeterminate_propagation(ev, text, expected):
    assert E(ev, text) is expected, text


def test_literal_indeterminate_test_option(tpop):
    strict = Evaluator(tpop)
    lenient = Evaluator(tpop, literal_indeterminate_test=True)
    assert E(strict, "maybe(FALSE) = ?") is None
    assert E(lenient, "maybe(FALSE) = ?") is True
    assert E(lenient, "maybe(TRUE) = ?") is False
    assert E(lenient, "maybe(TRUE) <> ?") is True
    assert E(lenient, "maybe(FALSE) = 1.0") is None  # only the literal ? is special


@pytest.mark.parametrize("text,expected", [
    ("ABS(-2)", 2), ("ABS(-2.5)", 2.5), ("ACOS(1.0)", 0.0), ("ASIN(0.0)", 0.0),
    ("ASIN(2.0)", INDETERMINATE), ("ATAN(1.0, 1.0)", math.pi / 4),
    ("ATAN(1.0, -1.0)", -math.pi / 4),
    ("ATAN(1.0, 0.0)", math.pi / 2), ("ATAN(-1.0, 0.0)", -math.pi / 2), ("BLENGTH(%1011)", 4),
    ("COS(0.0)", 1.0), ("EXP(0.0)", 1.0), ("EXISTS(0)", True),
    ("FORMAT(3.5, '8.2F')", "    3.50"), ("FORMAT(17, '5I')", "   17"), ("FORMAT(2, '')", "2"),
    ("HIBOUND(hi_list)", 3), ("HIBOUND([1, 2])", INDETERMINATE), ("HIINDEX([4, 5, 6])", 3),
    ("LENGTH('abc')", 3), ("LOBOUND(hi_list)", 1), ("LOINDEX([5, 6])", 1),
    ("LOG(CONST_E)", 1.0), ("LOG(0.0)", INDETERMINATE), ("LOG2(8.0)", 3.0), ("LOG10(100.0)", 2.0),
    ("NVL(?, 'x')", "x"), ("ODD(3)", True), ("ODD(4)", False), ("SIN(PI / 2.0)", 1.0),
    ("SIZEOF([1, 2, 3])", 3), ("SIZEOF([])", 0), ("SQRT(16.0)", 4.0), ("TAN(0.0)", 0.0),
    ("VALUE('12')", 12), ("VALUE('-1.5E1')", -15.0), ("VALUE('x1')", INDETERMINATE),
    ("VALUE_IN([1, 2], 2)", True), ("VALUE_IN([1, 2], 3)", False),
    ("VALUE_UNIQUE([1, 2, 1])", False), ("VALUE_UNIQUE(['a', 'b'])", True),
    ("'abc' LIKE 'a?c'", True), ("'abc' LIKE 'a*'", True), ("'A1' LIKE '@#'", True),
    ("'a1' LIKE '^#'", False), ("'a.b' LIKE 'a\\.b'", True), ("'abc' LIKE 'b*'", False),
])
def test_builtins(ev, text, expected):
    hi_list = Agg("list", [1, 2, 3], bounds=(1, 3))
    r = E(ev, text, hi_list=hi_list)
    if isinstance(expected, float):
        assert r == pytest.approx(expected, abs=1e-15), text
    else:
        assert r is expected or (type(r) is type(expected) and r == expected), (text, r)


def test_strings_and_binaries_by_index(ev):
    assert E(ev, "s[2]", s="abc") == "b"
    assert E(ev, "s[2:4]", s="abcdef") == "bcd"
    assert E(ev, "s[4]", s="abc") is INDETERMINATE
    assert E(ev, "LENGTH(s + t)", s="ab", t="cde") == 5


def test_aggregates(ev):
    u = E(ev, "a + b", a=Agg("set", [1, 2]), b=Agg("set", [2, 3]))
    assert u.kind == "set" and sorted(u) == [1, 2, 3]
    assert E(ev, "a + 2", a=Agg("set", [1, 2])) == [1, 2]
    assert E(ev, "a + 3", a=Agg("list", [1, 2])) == [1, 2, 3]
    assert E(ev, "0 + a", a=Agg("list", [1, 2])) == [0, 1, 2]
    assert E(ev, "a + b", a=Agg("bag", [1, 2]), b=Agg("bag", [2])) == [1, 2, 2]
    assert E(ev, "[1, 2, 2, 3] - [2]") == [1, 2, 3]
    inter = E(ev, "a * b", a=Agg("set", [1, 2, 3]), b=Agg("set", [3, 2, 9]))
    assert inter.kind == "set" and sorted(inter) == [2, 3]
    assert E(ev, "SIZEOF(['A', 'B'] * TYPEOF(p))", p=TypedValue(1.0, ("length_measure",))) == 0
    assert E(ev, "[1, 2] <= [2, 1, 3]") is True
    assert E(ev, "[1, 4] <= [2, 1, 3]") is False
    assert E(ev, "[2, 1, 3] >= [3]") is True
    assert E(ev, "[1, 2] = [1, 2]") is True
    assert E(ev, "a = b", a=Agg("set", [1, 2]), b=Agg("set", [2, 1])) is True
    assert E(ev, "[1, 2] = [2, 1]") is True  # aggregate initialisers are bags
    assert E(ev, "a = b", a=Agg("list", [1, 2]), b=Agg("list", [2, 1])) is False
    assert E(ev, "[1 : 3, 2]") == [1, 1, 1, 2]
    assert E(ev, "[[1, 2], [3, 4]][2][1]") == 3


def test_query(ev, tpop):
    assert E(ev, "QUERY(x <* [1, 2, 3, 4] | ODD(x))") == [1, 3]
    assert E(ev, "QUERY(x <* [1, ?, 3] | x > 1)") == [3]  # UNKNOWN does not select
    pl = tpop.instance(5)
    r = E(ev, "QUERY(p <* SELF.points | p.x > 1.0)", pl)
    assert [p.id for p in r] == [2]
    # nested query, outer variable visible inside
    assert E(ev, "SIZEOF(QUERY(a <* [1, 2, 3] | SIZEOF(QUERY(b <* [1, 2, 3] | b > a)) = 1))") == 1


def test_typeof(ev, tpop):
    p = tpop.instance(1)
    t = ev.typeof(p)
    assert t == {"TEST_SCHEMA.POINT", "TEST_SCHEMA.ITEM", "TEST_SCHEMA.SHAPE_SELECT",
                 "TEST_SCHEMA.OUTER_SELECT"}
    assert E(ev, "'TEST_SCHEMA.' + 'ITEM' IN TYPEOF(SELF)", p) is True
    assert E(ev, "'TEST_SCHEMA.SEGMENT' IN TYPEOF(SELF)", p) is False
    size = ev.attribute(tpop.instance(8), "size")  # POSITIVE_LENGTH_MEASURE(0.5)
    assert ev.typeof(size) == {"TEST_SCHEMA.POSITIVE_LENGTH_MEASURE", "TEST_SCHEMA.LENGTH_MEASURE",
                               "TEST_SCHEMA.RANGE_MEASURE", "REAL", "NUMBER"}
    hi = ev.attribute(tpop.instance(9), "hi")  # .UNLIMITED. in a select
    assert isinstance(hi, EnumValue) and hi.type == "unlimited_range"
    assert ev.typeof(hi) == {"TEST_SCHEMA.UNLIMITED_RANGE", "TEST_SCHEMA.RANGE_MEASURE"}
    assert ev.typeof(ev.attribute(tpop.instance(7), "colour")) == {"TEST_SCHEMA.COLOUR"}
    assert ev.typeof(ev.attribute(p, "x")) == {"REAL", "NUMBER"}
    assert ev.typeof(ev.attribute(p, "name")) == {"TEST_SCHEMA.LABEL", "STRING"}
    assert ev.typeof(E(ev, "[1]")) == {"BAG"}
    assert ev.typeof(ev.attribute(tpop.instance(5), "points")) == {"LIST"}
    assert set(E(ev, "TYPEOF(1)")) == {"INTEGER", "NUMBER"}
    assert set(E(ev, "TYPEOF(TRUE)")) == {"BOOLEAN", "LOGICAL"}
    assert set(E(ev, "TYPEOF('s')")) == {"STRING"}
    assert list(E(ev, "TYPEOF(?)")) == []
    cx = tpop.instance(16)  # (A_PART(1)B_PART('b')C_PART(0.5))
    assert ev.typeof(cx) == {"TEST_SCHEMA.A_PART", "TEST_SCHEMA.B_PART", "TEST_SCHEMA.C_PART"}
    tri = E(ev, "t", t=Agg("array", [1.0, 2.0, 3.0], dtypes=("triple",)))
    assert ev.typeof(tri) == {"TEST_SCHEMA.TRIPLE", "ARRAY"}


def test_usedin_and_rolesof(ev, tpop):
    n12 = tpop.instance(12)
    assert [e.id for e in E(ev, "USEDIN(SELF, 'TEST_SCHEMA.EDGE.ENDS')", n12)] == [13, 14]
    assert [e.id for e in E(ev, "USEDIN(SELF, '')", n12)] == [13, 14, 15]
    assert E(ev, "SIZEOF(USEDIN(SELF, 'TEST_SCHEMA.GRAPH.NODES'))", n12) == 1
    assert E(ev, "SIZEOF(USEDIN(SELF, 'TEST_SCHEMA.EDGE.NODES'))", n12) == 0
    assert E(ev, "USEDIN(SELF, 'TEST_SCHEMA.EDGE.ENDS')", tpop.instance(18)) == []
    assert set(E(ev, "ROLESOF(SELF)", n12)) == {"TEST_SCHEMA.EDGE.ENDS", "TEST_SCHEMA.GRAPH.NODES"}
    assert E(ev, "USEDIN(?, '')") is INDETERMINATE
    assert E(ev, "USEDIN(item('x'), '')") == []
    # inverse attributes are USEDIN with a type filter
    assert [e.id for e in ev.attribute(n12, "users")] == [13, 14]
    assert ev.attribute(n12, "owner").id == 15


def test_attribute_references(ev, tpop):
    p2, seg = tpop.instance(2), tpop.instance(3)
    assert E(ev, "SELF\\item.name", p2) == "p2"
    assert E(ev, "SELF\\segment.p1", p2) is INDETERMINATE  # not one of its types
    assert E(ev, "SELF.p2.x", seg) == 3.0
    assert E(ev, "p2\\point.y", seg) == 4.0  # unqualified names are SELF's attributes
    assert E(ev, "norm", p2) == 5.0  # derived
    assert plain(E(ev, "length", seg)) == 5.0  # derived through a function
    assert E(ev, "SELF.no_such_attribute", seg) is INDETERMINATE
    cx = tpop.instance(16)
    assert E(ev, "a1 + c1", cx) == 1.5 and E(ev, "twice", cx) == 2 and E(ev, "b1", cx) == "b"
    assert ev.attribute(cx, "a1", group="b_part") == 1


def test_functions_with_loops(ev):
    assert E(ev, "fact(5)") == 120
    assert E(ev, "sum_to(10, 3)") == 1 + 4 + 7 + 10
    assert E(ev, "sum_to(0, 1)") == 0
    assert E(ev, "sum_to(?, 1)") == 0  # a REPEAT with a ? bound is not executed
    assert E(ev, "first_over([1.0, 5.0, 7.0], 4.0)") == 2  # SKIP and ESCAPE
    assert E(ev, "first_over([1.0], 4.0)") == 0
    assert E(ev, "count_while(3)") == 6  # WHILE and UNTIL
    assert E(ev, "colour_code(green)") == 2 and E(ev, "colour_code(red)") == 1
    assert E(ev, "colour_code(blue)") == 0  # OTHERWISE
    s = E(ev, "as_set([1, 2, 2, 3])")
    assert s.kind == "set" and sorted(s) == [1, 2, 3]
    assert E(ev, "matrix_trace(3)") == 1.0 + 50.0 + 9.0  # nested aggregate assignment
    arr = E(ev, "to_array([7, 8, 9], 0)")  # declared ARRAY [low:...] takes its lower index
    assert arr.kind == "array" and arr.lo == 0 and list(arr) == [7, 8, 9]
    assert E(ev, "HIINDEX(to_array([7, 8, 9], 0))") == 2
    assert E(ev, "LOINDEX(to_array([7, 8, 9], 5))") == 5
    assert E(ev, "to_array([7, 8, 9], 0)[0]") == 7
    assert E(ev, "alias_sum(vec([1.0, 2.0, 4.0]))") == 7.0
    assert E(ev, "with_insert(3)") == [2, 1]  # INSERT at the head, REMOVE the first
    assert E(ev, "maybe(TRUE)") == 1.0
    assert E(ev, "maybe(FALSE)") is INDETERMINATE


def test_nested_procedure_with_var_parameters(ev):
    assert E(ev, "swap_digits(1, 2)") == 41  # swap(VAR x, VAR y) writes back; nested twice()


@settings(max_examples=60, deadline=None)
@given(st.recursive(st.integers(-9, 9).map(str),
                    lambda inner: st.tuples(inner, st.sampled_from(["+", "-", "*"]), inner).map(
                        lambda t: f"{t[0]} {t[1]} {t[2]}") | inner.map(lambda x: f"({x})"),
                    max_leaves=8))
def test_integer_arithmetic_matches_python(text):
    """Precedence and left associativity of + - * agree with Python's."""
    ev = Evaluator(Population([], parse_schema("SCHEMA s; END_SCHEMA;")))
    assert E(ev, text) == eval(text)  # noqa: S307 - digits and + - * ( ) only


def test_entity_constructors(ev, tpop):
    v = E(ev, "item('x') || point(3.0, 4.0)")
    assert isinstance(v, EntityValue)
    assert v.types == {"item", "point"}
    assert E(ev, "(item('x') || point(3.0, 4.0)).norm") == 5.0
    assert E(ev, "(item('x') || point(3.0, 4.0))\\item.name") is not INDETERMINATE
    scaled = E(ev, "scaled(vec([1.0, 2.0]), 2.0)")  # assignment to an attribute element
    assert list(ev.attribute(scaled, "coords")) == [2.0, 4.0]
    # the argument itself is not modified
    assert E(ev, "v.coords", v=tpop.instance(18)) == [1.0, 2.0, 3.0]
    assert E(ev, "scaled(SELF, 10.0).coords", tpop.instance(18)) == [10.0, 20.0, 30.0]
    assert list(ev.attribute(tpop.instance(18), "coords")) == [1.0, 2.0, 3.0]
    assert plain(E(ev, "dummy_item.name")) == "dummy"  # constant built by a constructor
    assert E(ev, "unit_name") == "metre"
    with pytest.raises(NotEvaluable):
        E(ev, "point(1.0, 2.0, 3.0, 4.0)")


def test_not_evaluable(ev, tpop):
    with pytest.raises(NotEvaluable, match="unknown name"):
        E(ev, "no_such_name + 1")
    with pytest.raises(NotEvaluable, match="unknown function"):
        E(ev, "no_such_function(1)")
    with pytest.raises(NotEvaluable, match="nested"):
        E(ev, "forever(1)")
    with pytest.raises(NotEvaluable, match="SELF"):
        E(ev, "SELF.x")
    with pytest.raises(NotEvaluable):
        E(ev, "'a' * 2")
    with pytest.raises(NotEvaluable, match="population instance"):
        E(ev, "poke(SELF)", tpop.instance(18))  # the file's data are never modified
    assert list(ev.attribute(tpop.instance(18), "coords")) == [1.0, 2.0, 3.0]
    assert E(ev, "poke(vec([1.0]))") == 99.0


def test_where_unique_and_global_rules(ev, tpop):
    got = {(i, ent, lab): r for i in tpop.ids()
           for ent, lab, r in ev.check_instance(tpop.instance(i))}
    assert got[(1, "point", "wr1")] is True and got[(1, "point", "wr2")] is True
    assert got[(3, "segment", "wr1")] is True and got[(3, "segment", "wr2")] is True
    assert got[(4, "segment", "wr1")] is False and got[(4, "segment", "wr2")] is False
    assert got[(5, "polyline", "wr1")] is True
    assert got[(7, "tagged", "wr1")] is True and got[(7, "tagged", "wr2")] is True  # NOT EXISTS
    assert got[(8, "tagged", "wr1")] is False and got[(8, "tagged", "wr2")] is False
    assert got[(9, "ranged", "wr1")] is None  # (FALSE OR TRUE) XOR UNKNOWN
    assert got[(10, "ranged", "wr1")] is False
    assert got[(13, "edge", "wr1")] is True and got[(14, "edge", "wr1")] is False
    assert got[(16, "c_part", "wr1")] is False and got[(17, "c_part", "wr1")] is True
    assert got[(19, "point", "wr1")] is True
    pl_bad = tpop.instance(5)
    assert ev.where_rule(pl_bad, "polyline", "wr1") is True
    assert ev.where_rule(tpop.instance(1), "POINT", "WR1") is True
    groups = ev.unique_rule("polyline", "ur1")
    assert [[i.id for i in g] for g in groups] == [[5, 6]]
    assert ev.unique_rule("polyline", tpop.schema.entity("polyline").unique[0]) == groups
    assert ev.global_rule("at_most_two_graphs") == {"wr1": True, "wr2": True}
    size = ev.attribute(tpop.instance(8), "size")
    assert ev.type_rule(size, "positive_length_measure", "wr1") is True
    assert ev.type_rule(TypedValue(-1.0, ("positive_length_measure",)),
                        "positive_length_measure", "wr1") is False
    assert all("no attribute" in a for a in ev.anomalies)


# --------------------------------------------------------------------------
# the kinematics probes against the real long forms

KINEMATICS_NAMES = SHARED / "schema" / "kinematics_entity_names_union.txt"
PROBES = sorted((CORPUS / "authored").glob("*.stp")) + sorted(EXAMPLES.glob("*.stp"))
# the project's generated corpus (<mechanism>_<profile>.stp), when present
GENERATED = sorted((Path(__file__).resolve().parents[1] / "data" / "corpus").glob("*.stp"))
P105_1996 = CORPUS / "authored" / "probe_p105_1996_ap214.stp"
STAR = CORPUS / "authored" / "probe_standard_star.stp"
AP242_NAME = "AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF"
needs_probes = pytest.mark.skipif(not P105_1996.is_file() or not STAR.is_file(),
                                  reason="shared corpus probes not present")


def kinematics_names() -> set:
    if KINEMATICS_NAMES.is_file():
        return {ln.strip().lower() for ln in KINEMATICS_NAMES.read_text().splitlines()
                if ln.strip() and not ln.startswith("#")}
    # fallback: the kinematics entities of the examples
    return {"kinematic_link", "kinematic_joint", "kinematic_pair", "revolute_pair",
            "revolute_pair_range", "revolute_pair_value", "kinematic_structure",
            "kinematic_link_representation", "kinematic_link_representation_association",
            "rigid_link_representation", "pair_representation_relationship",
            "kinematic_topology_structure", "mechanism_representation",
            "mechanism_state_representation", "su_parameters", "pair_value"}


def kinematic_closure(pop) -> list:
    """Instances of a kinematics entity and every instance they reference (transitively)."""
    names = kinematics_names()
    todo = [i for i in pop.ids() if pop.types_of(i) & names]
    seen = set(todo)
    while todo:
        rec = pop.instance(todo.pop()).record
        stack = [rec.get("args", [])] + [p["args"] for p in rec.get("complex", [])]
        while stack:
            for v in stack.pop():
                if isinstance(v, list):
                    stack.append(v)
                elif isinstance(v, dict) and "ref" in v:
                    r = v["ref"]
                    if r in pop and r not in seen:
                        seen.add(r)
                        todo.append(r)
    return sorted(seen)


def all_results(pop, ev=None) -> dict:
    ev = ev or evaluator(pop)
    out = {}
    for i in pop.ids():
        for ent, lab, r in ev.check_instance(pop.instance(i)):
            out[(i, ent, lab)] = r
    return out


def violations(text: str, profile=None, **options) -> dict:
    pop = Population(read_step(text), profile)
    ev = Evaluator(pop, **options)
    return {k: r for k, r in all_results(pop, ev).items() if r is not True}


def profile_of(path: Path):
    return "p105" if path.stem.endswith("_p105") else None


@pytest.mark.parametrize("path", PROBES + GENERATED, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_where_rule_coverage_on_probes(path, record_property, capsys):
    pop = Population(read_step(path.read_text(), str(path)), profile_of(path))
    ev = evaluator(pop)
    applicable = evaluated = 0
    not_evaluable = []
    instances = kinematic_closure(pop)
    assert instances, "no kinematics instances found"
    for iid in instances:
        for ent, rule in ev.applicable_where_rules(pop.instance(iid)):
            applicable += 1
            try:
                r = ev.where_rule(pop.instance(iid), ent, rule)
            except NotEvaluable as err:
                not_evaluable.append(f"#{iid} {ent}.{rule.label}: {err}")
                continue
            assert r in (True, False, None)
            evaluated += 1
    coverage = evaluated / applicable
    record_property("where_rule_coverage", f"{evaluated}/{applicable}")
    with capsys.disabled():
        print(f"\n  {path.name} [{pop.profile.name}]: "
              f"WHERE rules evaluated {evaluated}/{applicable}"
              f" = {coverage:.0%} over {len(instances)} kinematics (+ referenced) instances")
    assert not not_evaluable, not_evaluable
    assert coverage == 1.0
    assert applicable > 20


@pytest.mark.parametrize("path", PROBES + GENERATED, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_derived_and_inverse_attributes_of_probes_evaluate(path):
    pop = Population(read_step(path.read_text(), str(path)), profile_of(path))
    ev = evaluator(pop)
    n = 0
    for iid in kinematic_closure(pop):
        inst = pop.instance(iid)
        info = ev._info(inst)
        for key, acc in info.access.items():
            if acc[0] in ("derive", "inverse"):
                ev.attribute(inst, key[1], group=key[0])  # raises NotEvaluable on failure
                n += 1
    assert n > 10


@needs_probes
def test_findings_of_the_1996_probe():
    """What the long form's rules say about the hand-written 1996 probe."""
    found = violations(P105_1996.read_text())
    assert found == {
        # unique_link_usage: no mechanism uses the structure
        (10, "kinematic_link", "wr2"): False,
        (11, "kinematic_link", "wr2"): False,
        # rep_2 of the association must not be a kinematic link representation
        (19, "kinematic_link_representation_association", "wr2"): False,
    }
    # coordinated_pair_link_representation tests `link_rep = ?`, which is
    # UNKNOWN by ISO 10303-11; read as the authors meant, the pair rules fail
    # too (the probe has no kinematic_link_representation_relation)
    lenient = violations(P105_1996.read_text(), literal_indeterminate_test=True)
    assert set(lenient) - set(found) == {(14, "kinematic_pair", "wr1"),
                                         (14, "kinematic_pair", "wr2")}


@needs_probes
def test_findings_of_the_ap242_probes():
    for path in (STAR, CORPUS / "authored" / "probe_occt_style.stp"):
        assert violations(path.read_text()) == {
            # both link representations share one context
            (16, "representation_relationship_with_transformation", "wr1"): False,
            # su_parameters #21 is in no representation: not used, no dimension
            (21, "representation_item", "wr1"): False,
            (21, "su_parameters", "wr1"): None,
        }, path


FIXED_1996 = ("#19=KINEMATIC_LINK_REPRESENTATION_ASSOCIATION('',$,#17,#18);",
              """#19=KINEMATIC_LINK_REPRESENTATION_ASSOCIATION('',$,#17,#24);
#20=KINEMATIC_LINK_REPRESENTATION_RELATION(#10,#17);
#21=KINEMATIC_LINK_REPRESENTATION_RELATION(#11,#18);
#22=CHARACTERIZED_OBJECT('arm',$);
#23=KINEMATIC_PROPERTY_DEFINITION('kinematics','',#22,#22);
#24=SHAPE_REPRESENTATION('base shape',(#8),#4);
#25=MECHANISM(#13,#10,#23);""")


def fixed_1996() -> str:
    return P105_1996.read_text().replace(*FIXED_1996)


def fixed_ap242() -> str:
    return STAR.read_text().replace(
        "#14=RIGID_LINK_REPRESENTATION('arm_rep',(#9),#4,#11);",
        "#14=RIGID_LINK_REPRESENTATION('arm_rep',(#9,#21),#22,#11);\n"
        "#22=(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNIT_ASSIGNED_CONTEXT((#1,#2,#3))"
        "REPRESENTATION_CONTEXT('ctx2','3D'));")


@needs_probes
def test_completed_probes_satisfy_every_rule():
    assert violations(fixed_1996()) == {}
    assert violations(fixed_1996(), literal_indeterminate_test=True) == {}
    assert violations(fixed_1996(), "p105") == {}
    assert violations(fixed_ap242()) == {}


@needs_probes
@pytest.mark.parametrize("old,new,expected", [
    # kinematic_joint.wr1: first_link :<>: second_link
    ("#12=KINEMATIC_JOINT(#10,#11);", "#12=KINEMATIC_JOINT(#10,#10);",
     {(12, "kinematic_joint", "wr1"), (11, "kinematic_link", "wr1"), (11, "kinematic_link", "wr2"),
      (14, "kinematic_pair", "wr2")}),
    # revolute_pair_range.wr1: lower < upper unless one is unlimited
    ("#15=REVOLUTE_PAIR_RANGE(#14,-1.5,1.5);", "#15=REVOLUTE_PAIR_RANGE(#14,1.5,-1.5);",
     {(15, "revolute_pair_range", "wr1")}),
    # kinematic_link_representation.wr1: items are rigid placements or operators
    ("#18=KINEMATIC_LINK_REPRESENTATION('arm_rep',(#9),#4);",
     "#18=KINEMATIC_LINK_REPRESENTATION('arm_rep',(#9,#5),#4);",
     {(18, "kinematic_link_representation", "wr1")}),
    # kinematic_pair.wr2: the placement must be in the second link's representation
    ("#18=KINEMATIC_LINK_REPRESENTATION('arm_rep',(#9),#4);",
     "#18=KINEMATIC_LINK_REPRESENTATION('arm_rep',(#8),#4);\n#26=SHAPE_REPRESENTATION('',(#9),#4);",
     {(14, "kinematic_pair", "wr2")}),
    # mechanism.wr1: the base takes part in a joint of the structure
    ("#25=MECHANISM(#13,#10,#23);",
     "#25=MECHANISM(#13,#26,#23);\n#26=KINEMATIC_LINK();",
     {(25, "mechanism", "wr1"), (26, "kinematic_link", "wr1"), (26, "kinematic_link", "wr2")}),
    # kinematic_link.wr2 (unique_link_usage): two mechanisms on one structure
    ("#25=MECHANISM(#13,#10,#23);", "#25=MECHANISM(#13,#10,#23);\n#26=MECHANISM(#13,#11,#23);",
     {(10, "kinematic_link", "wr2"), (11, "kinematic_link", "wr2")}),
])
def test_mutated_1996_probe_violates_the_rule(old, new, expected):
    text = fixed_1996()
    assert old in text
    found = violations(text.replace(old, new))
    assert {k for k, r in found.items() if r is False} == expected
    assert all(r is False for r in found.values())


@needs_probes
@pytest.mark.parametrize("old,new,expected", [
    ("#12=KINEMATIC_JOINT('j1',#10,#11);", "#12=KINEMATIC_JOINT('j1',#10,#10);",
     {(12, "kinematic_joint", "wr1"), (11, "representation_item", "wr1"),
      (16, "pair_representation_relationship", "wr4")}),
    # pair_representation_relationship.wr1..wr4 and the placements' representations
    ("#16=PAIR_REPRESENTATION_RELATIONSHIP('j1_rel','j1_rel','',#13,#14,#15);",
     "#16=PAIR_REPRESENTATION_RELATIONSHIP('j1_rel','j1_rel','',#14,#13,#15);",
     {(16, "pair_representation_relationship", "wr1"),
      (16, "pair_representation_relationship", "wr2"),
      (16, "pair_representation_relationship", "wr3"),
      (16, "pair_representation_relationship", "wr4"),
      (16, "representation_relationship_with_transformation", "wr2")}),
    ("#15=REVOLUTE_PAIR('j1',*,$,#8,#9,#12,*,*,*,*,*,*);",
     "#15=REVOLUTE_PAIR_WITH_RANGE('j1',*,$,#8,#9,#12,*,*,*,*,*,*,1.0,-1.0);",
     {(15, "revolute_pair_with_range", "wr1")}),
    ("#15=REVOLUTE_PAIR('j1',*,$,#8,#9,#12,*,*,*,*,*,*);",
     "#15=REVOLUTE_PAIR_WITH_RANGE('j1',*,$,#8,#9,#12,*,*,*,*,*,*,$,-1.0);", set()),
    # kinematic_topology_structure.wr1: no oriented edges among the items
    ("#17=KINEMATIC_TOPOLOGY_STRUCTURE('topo',(#12),#4);",
     "#17=KINEMATIC_TOPOLOGY_STRUCTURE('topo',(#12,#30),#4);\n#30=ORIENTED_EDGE('',*,*,#12,.T.);",
     {(17, "kinematic_topology_structure", "wr1"), (18, "mechanism_representation", "wr1")}),
])
def test_mutated_ap242_probe_violates_the_rule(old, new, expected):
    text = fixed_ap242()
    assert old in text
    found = violations(text.replace(old, new))
    assert {k for k, r in found.items() if r is False} == expected, found


@needs_probes
def test_unlimited_range_bound():
    """revolute_pair_range.wr1 is `unlimited(lo) OR unlimited(hi) XOR lo < hi`:
    with one bound .UNLIMITED. the comparison is UNKNOWN, so TRUE XOR UNKNOWN
    is UNKNOWN (not a violation); a typed bound is compared."""
    text = fixed_1996()
    found = violations(text.replace("#15=REVOLUTE_PAIR_RANGE(#14,-1.5,1.5);",
                                    "#15=REVOLUTE_PAIR_RANGE(#14,.UNLIMITED.,-1.5);"))
    assert found == {(15, "revolute_pair_range", "wr1"): None}
    pop = Population(read_step(text.replace("#15=REVOLUTE_PAIR_RANGE(#14,-1.5,1.5);",
                                            "#15=REVOLUTE_PAIR_RANGE(#14,.UNLIMITED.,-1.5);")))
    lo = value(pop.instance(15), "lower_limit_actual_rotation")
    assert isinstance(lo, EnumValue) and lo.type == "unlimited_range"
    assert "AUTOMOTIVE_DESIGN.ROTATIONAL_RANGE_MEASURE" in evaluator(pop).typeof(lo)
    typed = text.replace("#15=REVOLUTE_PAIR_RANGE(#14,-1.5,1.5);",
                         "#15=REVOLUTE_PAIR_RANGE(#14,PLANE_ANGLE_MEASURE(2.),"
                         "PLANE_ANGLE_MEASURE(1.));")
    assert violations(typed) == {(15, "revolute_pair_range", "wr1"): False}


@needs_probes
def test_su_parameters_need_the_p105_profile():
    """A 1996 file placing a pair with su_parameters is valid only against
    the 1996 Part 105 schema (the p105 profile), not AP214's long form."""
    text = fixed_1996().replace("#9=AXIS2_PLACEMENT_3D('frame_arm',#5,#6,#7);",
                                "#9=SU_PARAMETERS('frame_arm',1.,0.,0.,0.,0.,0.);")
    assert violations(text, "p105") == {}
    assert violations(text) == {(18, "kinematic_link_representation", "wr1"): False}
    pop = Population(read_step(text), "p105")
    assert "AUTOMOTIVE_DESIGN.RIGID_PLACEMENT" in evaluator(pop).typeof(pop.instance(9))
    assert derived(pop.instance(9), "dim") == 3


# --------------------------------------------------------------------------
# the 1996 Part 105 functions, evaluated from the long form


def test_1996_pairs_rules_and_derived_values():
    pop = Population(read_step(mechanism_1996()), "p105")
    assert {k: r for k, r in all_results(pop).items() if r is not True} == {}
    assert plain(derived(pop.instance(51), "actual_orientation")) == [0.5, 0.0, 0.0]
    ypr = derived(pop.instance(59), "actual_orientation")  # given as YPR_ROTATION
    assert plain(ypr) == [0.1, 0.2, 0.3] and ypr.lo == 1
    assert "AUTOMOTIVE_DESIGN.YPR_ROTATION" in evaluator(pop).typeof(ypr)
    # screw: pitch * angle_in_radian / 2 * PI, exactly as written in the schema
    assert plain(derived(pop.instance(54), "actual_translation")) == pytest.approx(math.pi ** 2)
    # rack and pinion: -displacement / pinion_radius, in the file's angle unit
    assert plain(derived(pop.instance(56), "actual_rotation")) == pytest.approx(-0.5)
    assert plain(derived(pop.instance(52), "skew_angle")) == 0.0  # NVL(input_skew_angle, 0.0)


def test_1996_functions_convert_degrees():
    pop = Population(read_step(mechanism_1996(DEGREE, angle=30.0, skew="100.")), "p105")
    assert {k: r for k, r in all_results(pop).items() if r is not True} == {
        (52, "universal_pair", "wr1"): False}  # COS(100 degrees) < 0
    assert plain(derived(pop.instance(51), "actual_orientation")) == pytest.approx([30.0, 0.0, 0.0])
    assert plain(derived(pop.instance(56), "actual_rotation")) == pytest.approx(-0.5 * 180 / math.pi)
    pop = Population(read_step(mechanism_1996(DEGREE, skew="30.")), "p105")
    assert evaluator(pop).where_rule(pop.instance(52), "universal_pair", "wr1") is True


@pytest.mark.parametrize("axis,angle", [
    ((0.3, -0.5, 0.8), 1.1), ((1, 0, 0), -2.0), ((-1, 0, 0), 0.7), ((0, -1, 0), 2.5),
    ((0, 1, 0), -0.4), ((0, 0, -1), math.pi), ((0, 0, 1), 7.0), ((1, 0, 1), math.pi / 2),
    ((0.0, 0.6, 0.8), -3.0), ((2.0, -1.0, 0.5), 0.0), ((-0.2, 0.9, -0.1), 4.0),
])
def test_convert_spatial_to_ypr_rotation_matches_placements(axis, angle):
    """The long form's convert_spatial_to_ypr_rotation (loops, ATAN, arrays,
    normalise with `dummy_gri || direction(...)`) run by the evaluator agrees
    with the numpy implementation in kinematics/placements.py."""
    np = pytest.importorskip("numpy")
    from p105cli.kinematics.placements import convert_spatial_to_ypr_rotation
    pop = Population(read_step(mechanism_1996(axis=axis, angle=angle)), "p105")
    got = plain(derived(pop.instance(51), "actual_orientation"))
    want = [float(x) for x in convert_spatial_to_ypr_rotation(axis, angle)]
    assert np.allclose(got, want, atol=1e-12), (got, want)
    assert evaluator(pop).where_rule(pop.instance(61), "rotation_about_direction", "wr1") is True


@needs_probes
def test_unique_and_global_rules_on_the_long_form():
    text = fixed_1996().replace("#25=MECHANISM(#13,#10,#23);",
                                "#25=MECHANISM(#13,#10,#23);\n#26=PRISMATIC_PAIR('p',$,#8,#9,#12);")
    pop = Population(read_step(text))
    ev = evaluator(pop)
    groups = ev.unique_rule("kinematic_pair", "ur1")  # one pair per joint
    assert [[i.id for i in g] for g in groups] == [[14, 26]]
    assert ev.unique_rule("kinematic_link_representation_relation", "ur1") == []
    for name in pop.schema.rules:
        ev.global_rule(name)  # every global rule evaluates
    assert ev.global_rule("application_protocol_definition_required") == {"wr1": False}
