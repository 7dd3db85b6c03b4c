"""The EXPRESS reader (p105cli.schema): constructs, precedence, the two long
forms, the Part 21 attribute order against the reference lists, the cache."""

from __future__ import annotations

import os
import pickle
import re
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from p105cli.schema import (
    PARSER_VERSION, ExpressSyntaxError, SchemaError, load_schema, parse_schema, parse_schemas,
)
from p105cli.schema import model as M
from p105cli.schema.express import strip_comments, tokenize

SCHEMA_DIR = Path(os.environ.get("P105_SHARED", Path(__file__).resolve().parents[3]
                                  / "shared")) / "schema"
AP214 = SCHEMA_DIR / "AP214E3_2010_automotive_design_longform.exp"
AP242 = SCHEMA_DIR / "AP242_N10962_mim_lf.exp"
ORDER_214 = SCHEMA_DIR / "p21_argument_order_AP214E3_P105_1996.txt"
ORDER_242 = SCHEMA_DIR / "p21_argument_order_AP242_N10962.txt"
SUBSET_214 = SCHEMA_DIR / "kinematics_subset_AP214E3_P105_1996.exp"
SUBSET_242 = SCHEMA_DIR / "kinematics_subset_AP242_N10962.exp"

needs_schemas = pytest.mark.skipif(not AP242.is_file() or not AP214.is_file(),
                                   reason=f"{SCHEMA_DIR} not present")


def wrap(body: str) -> str:
    return f"SCHEMA test_schema;\n{body}\nEND_SCHEMA;\n"


def strip_lines(node):
    """A copy of an AST with every ``line`` set to 0 (structure only)."""
    if isinstance(node, list):
        return [strip_lines(x) for x in node]
    if isinstance(node, tuple):
        return tuple(strip_lines(x) for x in node)
    if isinstance(node, dict):
        return {k: strip_lines(v) for k, v in node.items()}
    if hasattr(node, "__dataclass_fields__"):
        kw = {}
        for f in node.__dataclass_fields__:
            if f.startswith("_"):
                continue
            v = getattr(node, f)
            kw[f] = 0 if f == "line" else strip_lines(v)
        return type(node)(**kw)
    return node


def expr(text: str):
    """Parse one expression (as a constant's value) and drop line numbers."""
    s = parse_schema(wrap(f"CONSTANT c : GENERIC := {text}; END_CONSTANT;"))
    return strip_lines(s.constants["c"].value)


N, L, B, U = M.Name, M.Literal, M.BinaryOp, M.UnaryOp


def lit(v):
    return L("integer", v, 0)


# --------------------------------------------------------------------------
# lexical level


def test_comments_nested_tail_and_in_strings():
    text = ("(* outer (* nested *) still comment ENTITY fake; *)\n"
            "SCHEMA s; -- tail ENTITY fake2;\n"
            "CONSTANT k : STRING := '(* not a comment -- nor this'; END_CONSTANT;\n"
            "END_SCHEMA; (* trailing *)")
    s = parse_schema(text)
    assert s.name == "s"
    assert s.constants["k"].value == L("string", "(* not a comment -- nor this", 3)
    assert not s.entities


def test_comment_blanking_keeps_positions():
    text = "a (* x\n y *) b -- z\nc"
    clean = strip_comments(text)
    assert len(clean) == len(text)
    assert clean.split("\n")[1].strip() == "b"
    keys, vals, poss, lines = tokenize(text)
    assert keys[:3] == ["a", "b", "c"]
    assert lines[:3] == [1, 2, 3]


def test_case_insensitive_keywords_lower_identifiers():
    s = parse_schema("schema Mixed_Case;\nEnTiTy Foo_Bar;\n  The_Attr : InTeGeR;\nend_entity;\nEND_schema;")
    assert s.name == "mixed_case"
    e = s.entities["foo_bar"]
    assert [a.name for a in e.attributes] == ["the_attr"]
    assert e.attributes[0].type == M.SimpleType("integer", line=3)


def test_literals():
    assert expr("42") == lit(42)
    assert expr("4.5E-2") == L("real", 0.045, 0)
    assert expr("1.") == L("real", 1.0, 0)
    assert expr("'it''s'") == L("string", "it's", 0)
    assert expr('"00000041000000C9"') == L("string", "A\u00c9", 0, True)
    assert expr("%0101") == L("binary", "0101", 0)
    assert expr("?") == L("indeterminate", None, 0)
    assert expr("TRUE") == L("logical", True, 0)
    assert expr("FALSE") == L("logical", False, 0)
    assert expr("UNKNOWN") == L("logical", None, 0)
    assert expr("SELF") == M.SelfRef(0)
    assert expr("PI") == M.BuiltinConstant("pi", 0)
    assert expr("CONST_E") == M.BuiltinConstant("const_e", 0)


# --------------------------------------------------------------------------
# expressions


def test_precedence_levels():
    a, b, c = N("a"), N("b"), N("c")
    assert expr("a + b * c") == B("+", a, B("*", b, c))
    assert expr("a * b + c") == B("+", B("*", a, b), c)
    assert expr("a - b - c") == B("-", B("-", a, b), c)
    assert expr("NOT a AND b") == B("and", U("not", a), b)
    assert expr("a OR b AND c") == B("or", a, B("and", b, c))
    assert expr("a XOR b OR c") == B("or", B("xor", a, b), c)
    assert expr("a = b + c") == B("=", a, B("+", b, c))
    assert expr("a + b <> c") == B("<>", B("+", a, b), c)
    assert expr("-a ** 2") == B("**", U("-", a), lit(2))
    assert expr("a * b ** 2") == B("*", a, B("**", b, lit(2)))
    assert expr("a + b || c") == B("+", a, B("||", b, c))
    assert expr("a DIV b MOD c") == B("mod", B("div", a, b), c)
    assert expr("a / b") == B("/", a, b)
    assert expr("a :=: b") == B(":=:", a, b)
    assert expr("a :<>: b") == B(":<>:", a, b)
    assert expr("a IN [1, b : 3]") == B("in", a, M.AggregateInit(
        [M.AggregateElement(lit(1)), M.AggregateElement(b, lit(3))], 0))
    assert expr("a LIKE 'A*'") == B("like", a, L("string", "A*", 0))
    assert expr("(a OR b) AND c") == B("and", B("or", a, b), c)
    assert expr("a <= b") == B("<=", a, b)
    assert expr("a >= b") == B(">=", a, b)
    assert expr("+a") == U("+", a)


def test_relational_is_not_associative():
    with pytest.raises(ExpressSyntaxError):
        expr("a = b = c")


def test_qualifiers_calls_query_interval():
    e = expr("SELF\\placement.location[1].coordinates[2:3]")
    assert e == M.IndexRef(M.AttributeRef(M.IndexRef(M.AttributeRef(M.GroupRef(
        M.SelfRef(0), "placement", 0), "location", 0), lit(1), None, 0), "coordinates", 0),
        lit(2), lit(3), 0)
    e = expr("SIZEOF(QUERY(x <* s | x.v > 0)) = 1")
    assert e == B("=", M.Call("sizeof", [M.Query("x", N("s"), B(">", M.AttributeRef(N("x"), "v", 0),
                                                                   lit(0)), 0)], 0, "builtin"), lit(1))
    e = expr("{0 <= SELF < 24}")
    assert e == M.Interval(lit(0), "<=", M.SelfRef(0), "<", lit(24), 0)
    e = expr("f(a, 2)[1]")
    assert e == M.IndexRef(M.Call("f", [N("a"), lit(2)], 0, "unknown"), lit(1), None, 0)
    e = expr("f()")
    assert e == M.Call("f", [], 0, "unknown")
    assert expr("[]") == M.AggregateInit([], 0)
    assert expr("si_prefix.milli") == M.AttributeRef(N("si_prefix"), "milli", 0)


def test_call_kinds_resolved():
    s = parse_schema(wrap("""
ENTITY pt; x : REAL; END_ENTITY;
FUNCTION mk(v : REAL) : pt; RETURN (pt(v) || other(v)); END_FUNCTION;
FUNCTION other(v : REAL) : GENERIC; RETURN (ABS(v)); END_FUNCTION;
"""))
    ret = s.functions["mk"].body[0].value
    assert ret.left.kind == "entity" and ret.right.kind == "function"
    assert s.functions["other"].body[0].value.kind == "builtin"


# hypothesis: random expression trees, printed with minimal parentheses from
# the precedence table, must parse back to the same tree.
_LEVEL = {"**": 2, "*": 4, "/": 4, "div": 4, "mod": 4, "and": 4, "||": 4,
          "+": 5, "-": 5, "or": 5, "xor": 5,
          "=": 6, "<>": 6, "<": 6, ">": 6, "<=": 6, ">=": 6, ":=:": 6, ":<>:": 6, "in": 6,
          "like": 6}


def _show(node) -> str:
    if isinstance(node, M.Literal):
        return str(node.value)
    if isinstance(node, M.Name):
        return node.name
    if isinstance(node, M.UnaryOp):
        inner = _show(node.operand)
        if not isinstance(node.operand, (M.Literal, M.Name)):
            inner = f"({inner})"
        return f"{node.op.upper()} {inner}" if node.op == "not" else f"{node.op}{inner}"
    lv = _LEVEL[node.op]

    def side(child, right):
        s = _show(child)
        if isinstance(child, M.BinaryOp):
            cl = _LEVEL[child.op]
            if cl > lv or (cl == lv and (right or lv in (2, 6))):
                return f"({s})"
        elif isinstance(child, M.UnaryOp) and lv == 2 and right:
            return f"({s})"
        return s
    op = node.op.upper() if node.op.isalpha() else node.op
    return f"{side(node.left, False)} {op} {side(node.right, True)}"


_leaf = st.one_of(st.integers(0, 99).map(lambda v: L("integer", v, 0)),
                  st.sampled_from("abcxyz").map(lambda n: N(n, 0)))
_tree = st.recursive(
    _leaf,
    lambda kids: st.one_of(
        st.builds(lambda op, a, b: B(op, a, b, 0), st.sampled_from(sorted(_LEVEL)), kids, kids),
        st.builds(lambda op, a: U(op, a, 0), st.sampled_from(["-", "+", "not"]), kids)),
    max_leaves=12)


@settings(max_examples=150, deadline=None)
@given(_tree)
def test_precedence_roundtrip(tree):
    assert expr(_show(tree)) == tree


# --------------------------------------------------------------------------
# declarations


def test_types():
    s = parse_schema(wrap("""
TYPE label = STRING(80) FIXED; END_TYPE;
TYPE bits = BINARY(8); END_TYPE;
TYPE r3 = REAL(6); END_TYPE;
TYPE hour = INTEGER;
WHERE
  WR1: {0 <= SELF < 24};
  SELF <> 13;
END_TYPE;
TYPE pts = LIST [2:?] OF UNIQUE point; END_TYPE;
TYPE grid = ARRAY [1:n] OF OPTIONAL UNIQUE SET [0:3] OF BAG OF INTEGER; END_TYPE;
TYPE colour = ENUMERATION OF (Red, green); END_TYPE;
TYPE more_colour = EXTENSIBLE ENUMERATION BASED_ON colour WITH (blue); END_TYPE;
TYPE open_enum = EXTENSIBLE ENUMERATION; END_TYPE;
TYPE thing = SELECT (point, label); END_TYPE;
TYPE ext = EXTENSIBLE GENERIC_ENTITY SELECT (point); END_TYPE;
TYPE ext2 = SELECT BASED_ON ext WITH (line); END_TYPE;
"""))
    t = s.types
    assert strip_lines(t["label"].underlying) == M.SimpleType("string", lit(80), True, 0)
    assert t["label"].line == 3 and t["label"].underlying.width.line == 3
    assert strip_lines(t["bits"].underlying) == M.SimpleType("binary", lit(8), False, 0)
    assert strip_lines(t["r3"].underlying) == M.SimpleType("real", lit(6), False, 0)
    w = t["hour"].where
    assert [x.label for x in w] == ["wr1", None]
    assert isinstance(w[0].expr, M.Interval) and w[0].line == 8 and w[1].line == 9
    pts = t["pts"].underlying
    assert (pts.kind, pts.lower, pts.upper, pts.unique) == ("list", L("integer", 2, 11),
                                                           L("indeterminate", None, 11), True)
    g = strip_lines(t["grid"].underlying)
    assert g == M.AggregateType("array", M.AggregateType(
        "set", M.AggregateType("bag", M.SimpleType("integer")), lit(0), lit(3)),
        lit(1), N("n"), True, True)
    assert t["colour"].underlying.items == ["red", "green"]
    mc = t["more_colour"].underlying
    assert (mc.extensible, mc.based_on, mc.items) == (True, "colour", ["blue"])
    assert t["open_enum"].underlying == M.EnumerationType([], True, None, 15)
    assert t["thing"].underlying.items == ["point", "label"]
    ext = t["ext"].underlying
    assert (ext.extensible, ext.generic_entity, ext.items) == (True, True, ["point"])
    e2 = t["ext2"].underlying
    assert (e2.based_on, e2.items, e2.extensible) == ("ext", ["line"], False)


ENTITIES = wrap("""
ENTITY root
  ABSTRACT SUPERTYPE OF (ONEOF(a, b) ANDOR c AND d);
  name : label;
  tags : OPTIONAL LIST [1:?] OF UNIQUE label;
END_ENTITY;
ENTITY a SUBTYPE OF (root);
  x, y : REAL;
DERIVE
  len : REAL := SQRT(x ** 2 + y ** 2);
  SELF\\root.name : label := 'a';
INVERSE
  users : SET [0:?] OF user FOR used;
  owner : user FOR root.owned;
  mine : BAG OF user FOR used;
UNIQUE
  UR1: x, SELF\\root.name;
  y;
WHERE
  WR1: x > 0;
  len < 10;
END_ENTITY;
ENTITY b SUPERTYPE OF (ONEOF(b1, b2)) SUBTYPE OF (root);
  SELF\\root.name RENAMED title : STRING;
END_ENTITY;
ENTITY c ABSTRACT SUBTYPE OF (root); END_ENTITY;
ENTITY d SUBTYPE OF (root); END_ENTITY;
ENTITY user; used : root; END_ENTITY;
ENTITY ab SUBTYPE OF (a, b); z : INTEGER; END_ENTITY;
ENTITY b1 SUBTYPE OF (b); END_ENTITY;
ENTITY b2 SUBTYPE OF (b); END_ENTITY;
""")


def test_entity_model():
    s = parse_schema(ENTITIES)
    root = s.entities["root"]
    assert root.abstract and root.supertypes == []
    assert root.supertype_expr == M.SupertypeOp("andor", [
        M.SupertypeOp("oneof", ["a", "b"], 4), M.SupertypeOp("and", ["c", "d"], 4)], 4)
    assert root.subtypes == ["a", "b", "c", "d"]
    assert root.attributes[1].optional
    assert root.attributes[1].type.kind == "list" and root.attributes[1].type.unique
    a = s.entities["a"]
    assert [x.name for x in a.attributes] == ["x", "y"]
    assert [(d.name, d.supertype) for d in a.derived] == [("len", None), ("name", "root")]
    assert strip_lines(a.derived[0].expr) == M.Call("sqrt", [B("+", B("**", N("x"), lit(2)),
                                                                  B("**", N("y"), lit(2)))], 0, "builtin")
    inv = a.inverse
    assert (inv[0].aggregate, inv[0].entity, inv[0].for_attribute, inv[0].for_entity) == (
        "set", "user", "used", None)
    assert strip_lines(inv[0].lower) == lit(0)
    assert (inv[1].aggregate, inv[1].for_entity, inv[1].for_attribute) == (None, "root", "owned")
    assert (inv[2].aggregate, inv[2].lower) == ("bag", None)
    assert a.unique[0].label == "ur1"
    assert a.unique[0].attributes == [M.UniqueAttribute("x", None, 18),
                                      M.UniqueAttribute("name", "root", 18)]
    assert a.unique[1].label is None
    assert [w.label for w in a.where] == ["wr1", None]
    assert a.where_rule("WR1").line == 21
    b = s.entities["b"]
    assert b.supertype_expr == M.SupertypeOp("oneof", ["b1", "b2"], 24)
    assert (b.attributes[0].name, b.attributes[0].supertype, b.attributes[0].renamed) == (
        "name", "root", "title")
    assert s.entities["c"].abstract and not s.entities["d"].abstract
    assert s.all_supertypes("ab") == ["a", "root", "b"]
    assert s.all_subtypes("b") == ["ab", "b1", "b2"]
    assert s.is_subtype("ab", "root") and s.is_subtype("b1", "b1")
    assert not s.is_subtype("b1", "b1", proper=True) and not s.is_subtype("root", "a")
    with pytest.raises(SchemaError):
        s.entity("nope")


def test_p21_attributes_small():
    s = parse_schema(ENTITIES)
    assert s.explicit_attribute_names("root") == ["name", "tags"]
    assert s.explicit_attribute_names("a") == ["*name", "tags", "x", "y"]
    assert s.explicit_attribute_names("ab") == ["*name", "tags", "x", "y", "z"]
    slots = s.p21_attributes("b")
    assert [str(x) for x in slots] == ["name", "tags"]
    assert slots[0].renamed == "title" and slots[0].type.name == "string"
    assert slots[0].entity == "root"
    assert s.p21_attributes("a")[0].derived_in == "a"
    assert s.explicit_attribute_names("user") == ["used"]


def test_algorithms():
    s = parse_schema(wrap("""
CONSTANT
  two : INTEGER := 2;
  names : SET OF STRING := ['a', 'b'];
END_CONSTANT;
FUNCTION f(a, b : INTEGER; c : AGGREGATE : t OF GENERIC : t) : LIST [0:?] OF GENERIC : t;
  FUNCTION inner(q : REAL) : REAL; RETURN (q); END_FUNCTION;
  CONSTANT k : REAL := 1.5; END_CONSTANT;
  LOCAL
    i, j : INTEGER := 0;
    r : LIST OF GENERIC : t := [];
  END_LOCAL;
  IF a > b THEN
    RETURN (r);
  ELSE
    ;
  END_IF;
  CASE a OF
    1, 2 : i := 1;
    3 : BEGIN j := 2; END;
    OTHERWISE : ESCAPE;
  END_CASE;
  REPEAT i := 1 TO HIINDEX(c) BY 2 WHILE i < 10 UNTIL j > 3;
    IF i = 3 THEN SKIP; END_IF;
    r[i] := c[i];
    INSERT(r, c[i], 0);
  END_REPEAT;
  REPEAT UNTIL TRUE; ESCAPE; END_REPEAT;
  ALIAS e FOR c[1].x; e := 1; END_ALIAS;
  p(a, b);
  noargs;
  RETURN (r);
END_FUNCTION;
PROCEDURE p(VAR x : INTEGER; y : REAL);
  x := x + 1;
END_PROCEDURE;
PROCEDURE noargs; END_PROCEDURE;
RULE all_named FOR (thing, other);
  LOCAL n : INTEGER := 0; END_LOCAL;
  n := SIZEOF(thing);
WHERE
  WR1: n = 0;
  SIZEOF(other) >= 0;
END_RULE;
"""))
    assert [c.name for c in s.constants.values()] == ["two", "names"]
    f = s.functions["f"]
    assert [(p.name, p.var) for p in f.parameters] == [("a", False), ("b", False), ("c", False)]
    assert f.parameters[2].type == M.AggregateType("aggregate", M.GenericType("generic", "t", 7),
                                                   label="t", line=7)
    assert f.return_type.kind == "list" and f.return_type.element == M.GenericType("generic", "t", 7)
    assert [d.name for d in f.declarations] == ["inner"]
    assert [c.name for c in f.constants] == ["k"]
    assert [(v.name, strip_lines(v.init)) for v in f.locals] == [
        ("i", lit(0)), ("j", lit(0)), ("r", M.AggregateInit([], 0))]
    body = strip_lines(f.body)
    assert isinstance(body[0], M.IfStmt) and body[0].then_body == [M.ReturnStmt(N("r"), 0)]
    assert body[0].else_body == [M.NullStmt(0)]
    case = body[1]
    assert case.actions[0].labels == [lit(1), lit(2)]
    assert case.actions[0].body == M.Assignment(N("i"), lit(1), 0)
    assert case.actions[1].body == M.CompoundStmt([M.Assignment(N("j"), lit(2), 0)], 0)
    assert case.otherwise == M.EscapeStmt(0)
    rep = body[2]
    assert (rep.variable, rep.start, rep.increment) == ("i", lit(1), lit(2))
    assert rep.end == M.Call("hiindex", [N("c")], 0, "builtin")
    assert rep.while_cond == B("<", N("i"), lit(10)) and rep.until_cond == B(">", N("j"), lit(3))
    assert rep.body[0] == M.IfStmt(B("=", N("i"), lit(3)), [M.SkipStmt(0)], None, 0)
    assert rep.body[1] == M.Assignment(M.IndexRef(N("r"), N("i"), None, 0),
                                       M.IndexRef(N("c"), N("i"), None, 0), 0)
    assert rep.body[2] == M.ProcedureCall("insert", [N("r"), M.IndexRef(N("c"), N("i"), None, 0),
                                                     lit(0)], True, 0)
    assert body[3] == M.RepeatStmt(None, None, None, None, None, L("logical", True, 0),
                                   [M.EscapeStmt(0)], 0)
    assert body[4] == M.AliasStmt("e", M.AttributeRef(M.IndexRef(N("c"), lit(1), None, 0), "x", 0),
                                  [M.Assignment(N("e"), lit(1), 0)], 0)
    assert body[5] == M.ProcedureCall("p", [N("a"), N("b")], False, 0)
    assert body[6] == M.ProcedureCall("noargs", [], False, 0)
    p = s.procedures["p"]
    assert [(x.name, x.var) for x in p.parameters] == [("x", True), ("y", False)]
    assert s.procedures["noargs"].parameters == [] and s.procedures["noargs"].body == []
    r = s.rules["all_named"]
    assert r.applies_to == ["thing", "other"]
    assert [w.label for w in r.where] == ["wr1", None]
    assert len(r.body) == 1 and r.locals[0].name == "n"
    # every node knows its line
    assert f.line == 7 and f.body[1].actions[1].line == 21 and r.where[1].line == 44
    assert f.body[2].body[2].line == 27 and s.procedures["p"].body[0].line == 36


def test_interfaces_subtype_constraint_and_bare_declarations():
    s = parse_schema("""SCHEMA s 'version 1';
USE FROM other_schema (a AS b, c);
REFERENCE FROM third;
ENTITY e ABSTRACT; END_ENTITY;
SUBTYPE_CONSTRAINT sc FOR e;
  ABSTRACT SUPERTYPE;
  TOTAL_OVER (f, g);
  ONEOF(f, g);
END_SUBTYPE_CONSTRAINT;
END_SCHEMA;""")
    assert s.version == "version 1"
    assert [(i.kind, i.schema, i.items) for i in s.interfaces] == [
        ("use", "other_schema", [("a", "b"), ("c", None)]), ("reference", "third", [])]
    sc = s.subtype_constraints["sc"]
    assert (sc.entity, sc.abstract, sc.total_over) == ("e", True, ["f", "g"])
    assert sc.expr == M.SupertypeOp("oneof", ["f", "g"], 8)
    bare = parse_schemas("TYPE t = INTEGER; END_TYPE; ENTITY e; END_ENTITY;")
    assert len(bare) == 1 and bare[0].name is None and list(bare[0].entities) == ["e"]
    two = parse_schemas("SCHEMA a; END_SCHEMA; SCHEMA b; END_SCHEMA;")
    assert [x.name for x in two] == ["a", "b"]
    with pytest.raises(SchemaError):
        parse_schema("SCHEMA a; END_SCHEMA; SCHEMA b; END_SCHEMA;")
    assert parse_schema("SCHEMA a; END_SCHEMA; SCHEMA b; END_SCHEMA;", name="B").name == "b"


@pytest.mark.parametrize("text, where, expected", [
    ("ENTITY a;\n  x : INTEGER\nEND_ENTITY;", (4, 1), "expected ';'"),
    ("ENTITY a;\n  x : ;\nEND_ENTITY;", (3, 7), "expected a type"),
    ("FUNCTION f : INTEGER;\n  RETURN (1 + );\nEND_FUNCTION;", (3, 15), "expected an expression"),
    ("TYPE t = INTEGER; WHERE a < # 1; END_TYPE;", (2, 29), "unexpected character '#'"),
    ("(* never closed", (2, 1), "unterminated comment"),
    ("ENTITY a; END_ENTITY; ENTITY a; END_ENTITY;", (2, 30), "duplicate entity 'a'"),
    ("FUNCTION f : INTEGER; IF x THEN RETURN (1); END_FUNCTION;", (2, 45),
     "expected a statement or ELSE or END_IF"),
    ("ENTITY a; DERIVE x : INTEGER := 1; y : REAL; END_ENTITY;", (2, 44), "expected ':='"),
    ("(* c *) ENTITY a; (* d *) x : ; END_ENTITY;", (2, 31), "expected a type"),
    ("CONSTANT c : STRING := 'abc; END_CONSTANT;", (2, 24), "unterminated string literal"),
    ("CONSTANT c : INTEGER := " + "(" * 3000 + "1" + ")" * 3000 + "; END_CONSTANT;", None,
     "nested too deeply"),
    ("ENTITY a SUBTYPE OF (); END_ENTITY;", (2, 22), "expected an entity name"),
    ("ENTITY a; x : SET [1:?] INTEGER; END_ENTITY;", (2, 25), "expected OF"),
    ("RULE r FOR (a); WHERE a > 1 END_RULE;", (2, 29), "expected ';'"),
])
def test_syntax_errors_name_file_line_col(text, where, expected):
    with pytest.raises(ExpressSyntaxError) as ei:
        parse_schema(wrap(text), "demo.exp")
    e = ei.value
    if where is not None:
        assert (e.line, e.column) == where, str(e)
        assert str(e).startswith(f"demo.exp:{where[0]}:{where[1]}: ")
    assert expected in str(e)


# --------------------------------------------------------------------------
# the real long forms


@pytest.fixture(scope="module")
def ap214():
    return parse_schema(AP214.read_text(encoding="utf-8", errors="replace"), str(AP214))


@pytest.fixture(scope="module")
def ap242():
    return parse_schema(AP242.read_text(encoding="utf-8", errors="replace"), str(AP242))


def _regex_count(path: Path, pattern: str) -> int:
    return len(re.findall(pattern, path.read_text(encoding="utf-8", errors="replace"),
                          re.I | re.M))


def _all_decls(schema, kind):
    """Top-level and nested declarations of one kind."""
    out = []

    def walk(decls):
        for d in decls:
            if isinstance(d, kind):
                out.append(d)
            walk(getattr(d, "declarations", []))

    walk(list(schema.functions.values()) + list(schema.procedures.values())
         + list(schema.rules.values()))
    out += [d for d in list(schema.entities.values()) + list(schema.types.values())
            if isinstance(d, kind)]
    return out


@needs_schemas
@pytest.mark.parametrize("which", ["ap214", "ap242"])
def test_long_form_counts_match_naive_regex(which, request):
    s = request.getfixturevalue(which)
    path = AP214 if which == "ap214" else AP242
    assert len(s.entities) == _regex_count(path, r"^\s*ENTITY\s+\w+") == len(_all_decls(s, M.Entity))
    assert len(s.types) == _regex_count(path, r"^\s*TYPE\s+\w+\s*=")
    assert len(_all_decls(s, M.Function)) == _regex_count(path, r"^\s*FUNCTION\s+\w+")
    assert len(_all_decls(s, M.Procedure)) == _regex_count(path, r"^\s*PROCEDURE\s+\w+")
    assert len(s.rules) == _regex_count(path, r"^\s*END_RULE\s*;")
    # the whole file was consumed: every entity has its END_ENTITY
    assert len(s.entities) == _regex_count(path, r"^\s*END_ENTITY\s*;")


@needs_schemas
def test_long_form_counts_match_ap242_header(ap242):
    head = AP242.read_text(encoding="utf-8", errors="replace")[:3000]
    declared = {k.lower(): int(v.replace(",", ""))
                for k, v in re.findall(r"\(\*\s+(\w+):\s+([\d,]+)\s+\*\)", head)}
    assert declared["entities"] == len(ap242.entities) == 2140
    assert declared["types"] == len(ap242.types)
    assert declared["functions"] == len(ap242.functions)  # top level only
    assert declared["rules"] == len(ap242.rules)
    assert declared["constants"] == len(ap242.constants)
    assert declared["procedures"] == len(ap242.procedures) == 0
    assert ap242.name == "ap242_managed_model_based_3d_engineering_mim_lf"


@needs_schemas
def test_long_form_calls_all_resolve(ap214, ap242):
    for s in (ap214, ap242):
        unknown = set()

        def walk(x):
            if isinstance(x, M.Call) and x.kind == "unknown":
                unknown.add(x.name)
            if isinstance(x, list):
                for y in x:
                    walk(y)
            elif hasattr(x, "__dataclass_fields__") and not isinstance(x, M.Schema):
                for f in x.__dataclass_fields__:
                    walk(getattr(x, f))
        for table in (s.entities, s.types, s.functions, s.rules, s.constants, s.procedures):
            for d in table.values():
                walk(d)
        assert not unknown


@needs_schemas
def test_long_form_redeclarations_all_resolve(ap214, ap242):
    for s in (ap214, ap242):
        count = 0
        for e in s.entities.values():
            for a in (*e.attributes, *e.derived, *e.inverse):
                if a.supertype is not None:
                    count += 1
                    assert s.is_subtype(e.name, a.supertype, proper=True), (e.name, a.supertype)
                    owner, decl = s.resolve_attribute(a.supertype, a.name)
                    assert isinstance(decl, M.ExplicitAttribute) and decl.supertype is None
        assert count > 50
        for name in s.entities:  # every entity has a computable Part 21 layout
            s.p21_attributes(name)


def _reference_orders(path: Path):
    out = []
    for line in path.read_text(encoding="utf-8").splitlines():
        if not line.strip():
            continue
        m = re.fullmatch(r"(\w+)(\s*\[ABSTRACT\])?\((.*)\)", line.strip())
        assert m, line
        args = [a.strip() for a in m.group(3).split(",")] if m.group(3).strip() else []
        out.append((m.group(1).lower(), bool(m.group(2)), args))
    return out


@needs_schemas
@pytest.mark.parametrize("which, ref", [("ap214", ORDER_214), ("ap242", ORDER_242)])
def test_p21_attributes_match_reference_lists(which, ref, request):
    s = request.getfixturevalue(which)
    rows = _reference_orders(ref)
    assert len(rows) == {"ap214": 78, "ap242": 110}[which]
    mismatches = []
    for name, abstract, expected in rows:
        got = [str(a) for a in s.p21_attributes(name)]
        if got != expected or s.entities[name].abstract != abstract:
            mismatches.append((name, expected, got))
    assert not mismatches


@needs_schemas
def test_spot_checks_ap242(ap242):
    s = ap242
    assert s.all_supertypes("revolute_pair") == [
        "low_order_kinematic_pair", "kinematic_pair", "geometric_representation_item",
        "representation_item", "item_defined_transformation"]
    assert s.is_subtype("revolute_pair", "representation_item")
    assert "revolute_pair_with_range" in s.entities["revolute_pair"].subtypes
    slots = s.p21_attributes("REVOLUTE_PAIR")
    flags = {a.name: a for a in slots if a.name in ("t_x", "t_y", "t_z", "r_x", "r_y", "r_z")}
    assert len(flags) == 6 and all(a.derived and a.derived_in == "revolute_pair"
                                   for a in flags.values())
    rp = s.entities["revolute_pair"]
    assert strip_lines(rp.derived[5]) == M.DerivedAttribute(
        "r_z", M.SimpleType("boolean"), L("logical", True, 0), "low_order_kinematic_pair")
    lo = s.p21_attributes("low_order_kinematic_pair")
    assert not any(a.derived for a in lo if a.name.startswith(("t_", "r_")))
    kp = s.entities["kinematic_pair"]
    assert kp.abstract
    assert kp.supertype_expr.op == "andor"
    assert kp.supertype_expr.operands[0] == M.SupertypeOp(
        "oneof", ["high_order_kinematic_pair", "low_order_kinematic_pair_with_motion_coupling",
                  "low_order_kinematic_pair"], kp.line + 1)
    assert kp.inverse[0].name == "link_representation_associations"
    kj = s.entities["kinematic_joint"]
    assert strip_lines(kj.where_rule("wr1").expr) == B(":<>:", N("edge_start"), N("edge_end"))
    assert kj.unique[0].label == "ur1"
    assert [a.name for a in kj.unique[0].attributes] == ["edge_start", "edge_end"]
    assert kj.attributes[0].supertype == "edge" and kj.attributes[0].type.name == "kinematic_link"
    slots = s.p21_attributes("kinematic_joint")
    assert [(a.name, a.type.name) for a in slots] == [
        ("name", "label"), ("edge_start", "kinematic_link"), ("edge_end", "kinematic_link")]
    su = s.entities["su_parameters"]
    assert [a.name for a in su.attributes] == ["a", "alpha", "b", "beta", "c", "gamma"]
    assert s.explicit_attribute_names("su_parameters") == [
        "name", "a", "alpha", "b", "beta", "c", "gamma"]
    f = s.functions["plane_angle_for_pair_in_radian"]
    assert [(p.name, p.type.name) for p in f.parameters] == [
        ("pair", "kinematic_pair"), ("angle", "plane_angle_measure")]
    assert f.return_type.name == "plane_angle_measure"
    assert isinstance(f.body[-1], M.CaseStmt) and f.body[-1].otherwise is not None
    assert "rigid_placement" in s.types
    assert s.types["rigid_placement"].underlying.items == ["axis2_placement_3d", "su_parameters"]


@needs_schemas
def test_spot_checks_ap214(ap214):
    s = ap214
    assert s.name == "automotive_design"
    kj = s.entities["kinematic_joint"]
    assert kj.supertypes == []
    assert [a.name for a in kj.attributes] == ["first_link", "second_link"]
    assert strip_lines(kj.where_rule("wr1").expr) == B(":<>:", N("first_link"), N("second_link"))
    assert kj.inverse[0].for_attribute == "joints"
    # su_parameters belongs to the 2014+ Part 105 (AP242), not to the 1996 one
    assert "su_parameters" not in s.entities
    assert s.types["rigid_placement"].underlying.items == ["axis2_placement_3d"]
    assert s.explicit_attribute_names("revolute_pair") == [
        "name", "description", "transform_item_1", "transform_item_2", "joint"]
    assert s.explicit_attribute_names("mechanism_base_placement") == [
        "name", "description", "rep_1", "*rep_2", "transformation_operator", "base_of_mechanism"]
    f = s.functions["plane_angle_for_pair_in_radian"]
    assert [p.name for p in f.parameters] == ["pair", "angle"]


@needs_schemas
@pytest.mark.parametrize("subset, full", [(SUBSET_214, "ap214"), (SUBSET_242, "ap242")])
def test_kinematics_subsets_parse_as_bare_declarations(subset, full, request):
    s = parse_schema(subset.read_text(encoding="utf-8"), str(subset))
    assert s.name is None
    big = request.getfixturevalue(full)
    assert len(s.entities) == {"ap214": 78, "ap242": 110}[full]
    for name, e in s.entities.items():  # extracted verbatim: same declarations
        assert strip_lines(e.attributes) == strip_lines(big.entities[name].attributes)
        assert strip_lines(e.where) == strip_lines(big.entities[name].where)


# --------------------------------------------------------------------------
# cache


@needs_schemas
def test_cache_roundtrip(tmp_path, monkeypatch, ap242):
    # Load times belong to the benchmarks, not to unit tests.
    monkeypatch.setenv("P105_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr("p105cli.schema.express.COMPILED_DIR", tmp_path / "no-compiled")  # the user cache only
    cold = load_schema(AP242)
    files = list((tmp_path / "cache").iterdir())
    assert len(files) == 1 and files[0].name.startswith(f"express-v{PARSER_VERSION}-")
    assert files[0].suffix == ".pickle"  # no temporary file left behind
    warm = load_schema(AP242)
    assert warm is not cold
    assert warm == cold == ap242
    assert warm.source == str(AP242)
    assert warm.explicit_attribute_names("revolute_pair") == cold.explicit_attribute_names(
        "revolute_pair")


def test_cache_key_and_corrupt_entry(tmp_path, monkeypatch):
    monkeypatch.setenv("P105_CACHE_DIR", str(tmp_path / "c"))
    monkeypatch.setattr("p105cli.schema.express.COMPILED_DIR", tmp_path / "no-compiled")  # the user cache only
    src = tmp_path / "s.exp"
    src.write_text(wrap("ENTITY a; x : INTEGER; END_ENTITY;"))
    s1 = load_schema(src)
    [entry] = list((tmp_path / "c").iterdir())
    entry.write_bytes(b"not a pickle")
    assert load_schema(src) == s1  # rebuilt
    assert pickle.loads(entry.read_bytes())[2][0] == s1
    src.write_text(wrap("ENTITY a; x : INTEGER; y : REAL; END_ENTITY;"))
    s2 = load_schema(src)  # different bytes, different key
    assert s2.explicit_attribute_names("a") == ["x", "y"]
    assert len(list((tmp_path / "c").iterdir())) == 2
    assert load_schema(src, cache=False) == s2


def test_unwritable_cache_dir_is_not_an_error(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    monkeypatch.setenv("P105_CACHE_DIR", str(blocker / "sub"))
    monkeypatch.setattr("p105cli.schema.express.COMPILED_DIR", tmp_path / "no-compiled")  # the user cache only
    src = tmp_path / "s.exp"
    src.write_text(wrap("ENTITY a; END_ENTITY;"))
    assert list(load_schema(src).entities) == ["a"]


def test_no_click_or_numpy_import():
    import subprocess
    import sys
    code = ("import sys, p105cli.schema as s; "
            "print(any(m in sys.modules for m in ('click', 'numpy')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=Path(__file__).resolve().parents[2])
    assert out.stdout.strip() == "False", out.stderr


def test_compiled_package_schemas_are_used_before_the_user_cache(tmp_path, monkeypatch):
    import p105cli.schema.express as express
    monkeypatch.setattr(express, "COMPILED_DIR", tmp_path / "compiled")
    monkeypatch.setenv("P105_CACHE_DIR", str(tmp_path / "user"))
    (tmp_path / "compiled").mkdir()
    stale = tmp_path / "compiled" / "express-v1-0123.pickle"  # an older parser's
    stale.write_bytes(b"old")
    written = express.compile_package_schemas()
    assert len(written) == 2 and all(p.parent == tmp_path / "compiled" for p in written)
    assert sorted((tmp_path / "compiled").iterdir()) == sorted(written)  # the stale one is gone
    data_dir = Path(express.__file__).resolve().parent / "data"
    schema = express.load_schema(data_dir / "AP242_N10962_mim_lf.exp")
    assert "revolute_pair" in schema.entities
    assert not (tmp_path / "user").exists()      # served from the compiled form, nothing rebuilt


DEFERRING = wrap("""
ENTITY a;
  x : INTEGER;
  y : REAL;
DERIVE
  z : REAL := x * y;
WHERE
  wr1: x > 0;
END_ENTITY;
ENTITY b SUBTYPE OF (a);
DERIVE
  SELF\\a.y : REAL := 2.0;
END_ENTITY;
FUNCTION twice(v : INTEGER) : INTEGER;
  LOCAL w : INTEGER := v; END_LOCAL;
  RETURN (w + v);
END_FUNCTION;
RULE positive FOR (a);
WHERE
  wr1: SIZEOF(QUERY(i <* a | twice(i.x) < 0)) = 0;
END_RULE;
""")


def test_cache_defers_bodies_until_read():
    import threading

    from p105cli.schema.express import _encode
    parsed = parse_schema(DEFERRING)
    loaded = pickle.loads(_encode(parsed))
    ent, f, rule = loaded.entities["a"], loaded.functions["twice"], loaded.rules["positive"]
    # Read without decoding: the type graph, derivations' names, what a rule applies to.
    assert loaded.all_supertypes("b") == ["a"] and loaded.entities["a"].subtypes == ["b"]
    assert [d.name for d in ent.derived] == ["z"] and rule.applies_to == ["a"]
    assert all("_deferred" in o.__dict__ for o in (ent, f, rule, ent.derived[0]))
    assert "where" not in ent.__dict__ and "body" not in f.__dict__
    # The first read decodes the instance's deferred fields, once, also with threads racing.
    got = []
    threads = [threading.Thread(target=lambda: got.append(f.body)) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(got) == 8 and all(b is got[0] for b in got)
    assert "_deferred" not in f.__dict__ and f.line == parsed.functions["twice"].line
    assert f == parsed.functions["twice"]
    # Still-encoded parts survive another pickling (a copy sent to another process) as they are.
    again = pickle.loads(pickle.dumps(loaded))
    assert "_deferred" in again.entities["a"].__dict__
    assert again == loaded == parsed
    assert again.p21_attributes("b") == parsed.p21_attributes("b")
    assert again.entities["a"].where_rule("WR1").expr == parsed.entities["a"].where[0].expr
    with pytest.raises(AttributeError):
        again.functions["twice"].no_such_field  # noqa: B018


def test_cache_filled_by_processes_at_once(tmp_path):
    # make -j: several processes find the cache empty and write the same entry together.
    import subprocess
    import sys
    src = tmp_path / "s.exp"
    src.write_text(DEFERRING)
    code = ("import sys; from p105cli.schema import load_schema; "
            "s = load_schema(sys.argv[1]); print(s.functions['twice'].parameters[0].name)")
    env = {**os.environ, "P105_CACHE_DIR": str(tmp_path / "cache")}
    procs = [subprocess.Popen([sys.executable, "-c", code, str(src)], stdout=subprocess.PIPE,
                              env=env, cwd=Path(__file__).resolve().parents[2]) for _ in range(4)]
    assert [p.communicate(timeout=60)[0].strip() for p in procs] == [b"v"] * 4
    assert [p.returncode for p in procs] == [0] * 4
    [entry] = list((tmp_path / "cache").iterdir())  # one entry, no temporary file left
    assert entry.name.startswith(f"express-v{PARSER_VERSION}-") and entry.suffix == ".pickle"
    assert pickle.loads(entry.read_bytes())[2][0] == parse_schema(DEFERRING)
