"""The EXPRESS parser: recursive descent over the tokens of ``tokenizer.py``
into the data model of ``model.py`` (see ``express.py`` for the grammar
followed and the leniencies).
"""

from __future__ import annotations

from .model import (
    AggregateElement, AggregateInit, AggregateType, AliasStmt, Assignment, AttributeRef, BinaryOp,
    BuiltinConstant, Call, CaseAction, CaseStmt, CompoundStmt, Constant, DerivedAttribute, Entity,
    EnumerationType, EscapeStmt, ExplicitAttribute, Function, GenericType, GroupRef, IfStmt,
    IndexRef, Interface, Interval, InverseAttribute, Literal, LocalVariable, Name, NamedType,
    NullStmt, Parameter, Procedure, ProcedureCall, Query, RepeatStmt, ReturnStmt, Rule, Schema,
    SelectType, SelfRef, SimpleType, SkipStmt, SubtypeConstraint, SupertypeOp, TypeDecl, UnaryOp,
    UniqueAttribute, UniqueRule, WhereRule,
)
from .tokenizer import ExpressSyntaxError, K_BIN, K_EOF, K_INT, K_REAL, K_STR, _line_col, tokenize

BUILTIN_FUNCTIONS = frozenset(
    "abs acos asin atan blength cos exists exp format hibound hiindex length lobound "
    "loindex log log2 log10 nvl odd rolesof sin sizeof sqrt tan typeof usedin value "
    "value_in value_unique".split())
BUILTIN_PROCEDURES = frozenset(("insert", "remove"))


REL_OPS = frozenset(("=", "<>", "<", ">", "<=", ">=", ":=:", ":<>:", "in", "like"))
ADD_OPS = frozenset(("+", "-", "or", "xor"))
MUL_OPS = frozenset(("*", "/", "div", "mod", "and", "||"))
SIMPLE_TYPES = frozenset(("integer", "real", "number", "logical", "boolean", "string", "binary"))
AGG_KINDS = frozenset(("list", "set", "bag", "array"))
ENTITY_SECTIONS = frozenset(("derive", "inverse", "unique", "where", "end_entity"))
STMT_KEYWORDS = frozenset(("if", "case", "repeat", "return", "escape", "skip", "begin", "alias"))

# words that can never be a name in an expression or a declaration
RESERVED = frozenset("""
abstract aggregate alias and andor array as bag based_on begin binary boolean by case
constant derive div else end end_alias end_case end_constant end_entity end_function
end_if end_local end_procedure end_repeat end_rule end_schema end_subtype_constraint
end_type entity enumeration escape extensible fixed for from function generic
generic_entity if in integer inverse like list local logical mod not number of oneof
optional or otherwise procedure query real reference renamed repeat return rule schema
select self set skip string subtype subtype_constraint supertype then to total_over type
unique until use var where while with xor true false unknown pi const_e
""".split())


class _Parser:
    def __init__(self, text: str, filename: str):
        self.text = text
        self.filename = filename
        self.keys, self.vals, self.poss, self.lines = tokenize(text, filename)
        # a second end marker: one-token look-ahead never runs off the end
        self.keys.append(K_EOF)
        self.vals.append(None)
        self.poss.append(self.poss[-1])
        self.lines.append(self.lines[-1])
        self.i = 0
        self.calls: list = []
        self.function_names: set = set()
        self.entity_names: set = set()

    # ------------------------------------------------------------ helpers
    def error(self, expected: str, i: int | None = None):
        if i is None:
            i = self.i
        key = self.keys[i]
        if key == K_EOF:
            found = "end of file"
        elif key.startswith("\0"):
            found = f"{key[1:]} literal"
        else:
            found = repr(self.text[self.poss[i]:self.poss[i] + len(key)]) if key else repr(key)
        line, col = _line_col(self.text, self.poss[i])
        raise ExpressSyntaxError(f"expected {expected}, found {found}", self.filename, line, col)

    def expect(self, key: str) -> int:
        i = self.i
        if self.keys[i] != key:
            self.error(f"{key.upper() if key.isalpha() or '_' in key else repr(key)}")
        self.i = i + 1
        return self.lines[i]

    def accept(self, key: str) -> bool:
        if self.keys[self.i] == key:
            self.i += 1
            return True
        return False

    def ident(self, what: str = "an identifier") -> str:
        i = self.i
        k = self.keys[i]
        if k[:1].isalpha() and k not in RESERVED:
            self.i = i + 1
            return k
        self.error(what)

    def ident_list(self, what: str = "an identifier") -> list:
        out = [self.ident(what)]
        while self.accept(","):
            out.append(self.ident(what))
        return out

    def paren_ident_list(self, what: str = "an identifier") -> list:
        self.expect("(")
        out = self.ident_list(what)
        self.expect(")")
        return out

    def is_label(self) -> bool:
        k = self.keys[self.i]
        return k[:1].isalpha() and k not in RESERVED and self.keys[self.i + 1] == ":"

    # ------------------------------------------------------------ top level
    def parse_file(self) -> list:
        schemas = []
        if self.keys[self.i] != "schema":
            # a bare list of declarations (e.g. an extracted subset)
            s = Schema(None, line=self.lines[self.i])
            self.schema_body(s, K_EOF)
            schemas.append(s)
        else:
            while self.keys[self.i] == "schema":
                schemas.append(self.schema())
            if self.keys[self.i] != K_EOF:
                self.error("SCHEMA or end of file")
        self.resolve_calls()
        for s in schemas:
            _link(s)
        return schemas

    def schema(self) -> Schema:
        line = self.expect("schema")
        name = self.ident("a schema name")
        version = None
        if self.keys[self.i] == K_STR:
            version = self._string_value(self.vals[self.i])
            self.i += 1
        self.expect(";")
        s = Schema(name, version, line=line)
        self.schema_body(s, "end_schema")
        self.expect("end_schema")
        self.expect(";")
        return s

    def schema_body(self, s: Schema, end: str) -> None:
        while True:
            k = self.keys[self.i]
            if k == end:
                return
            start = self.i + 1  # the declaration's name, for a duplicate's message
            if k == "entity":
                self._add(s.entities, self.entity_decl(), "entity", start)
            elif k == "type":
                self._add(s.types, self.type_decl(), "type", start)
            elif k == "function":
                self._add(s.functions, self.function_decl(), "function", start)
            elif k == "rule":
                self._add(s.rules, self.rule_decl(), "rule", start)
            elif k == "procedure":
                self._add(s.procedures, self.procedure_decl(), "procedure", start)
            elif k == "constant":
                for c in self.constant_block():
                    self._add(s.constants, c, "constant", None)
            elif k == "subtype_constraint":
                self._add(s.subtype_constraints, self.subtype_constraint_decl(),
                          "subtype constraint", start)
            elif k in ("use", "reference"):
                s.interfaces.append(self.interface())
            else:
                self.error("ENTITY, TYPE, FUNCTION, PROCEDURE, RULE, CONSTANT, SUBTYPE_CONSTRAINT, "
                           "USE, REFERENCE or " + (end.upper() if end != K_EOF else "end of file"))

    def _add(self, table: dict, decl, what: str, name_index) -> None:
        if decl.name in table:
            if name_index is not None:
                line, col = _line_col(self.text, self.poss[name_index])
            else:
                line, col = decl.line, 1
            raise ExpressSyntaxError(
                f"duplicate {what} {decl.name!r} (first declared on line {table[decl.name].line})",
                self.filename, line, col)
        table[decl.name] = decl

    def interface(self) -> Interface:
        line = self.lines[self.i]
        kind = self.keys[self.i]
        self.i += 1
        self.expect("from")
        schema = self.ident("a schema name")
        items = []
        if self.accept("("):
            while True:
                n = self.ident("a declaration name")
                alias = self.ident("an alias") if self.accept("as") else None
                items.append((n, alias))
                if not self.accept(","):
                    break
            self.expect(")")
        self.expect(";")
        return Interface(kind, schema, items, line)

    # ------------------------------------------------------------ constants
    def constant_block(self) -> list:
        self.expect("constant")
        out = []
        while self.keys[self.i] != "end_constant":
            line = self.lines[self.i]
            name = self.ident("a constant name or END_CONSTANT")
            self.expect(":")
            t = self.parse_type()
            self.expect(":=")
            v = self.expression()
            self.expect(";")
            out.append(Constant(name, t, v, line))
        self.expect("end_constant")
        self.expect(";")
        return out

    # ------------------------------------------------------------ types
    def type_decl(self) -> TypeDecl:
        line = self.expect("type")
        name = self.ident("a type name")
        self.expect("=")
        u = self.underlying_type()
        self.expect(";")
        where = self.where_clause() if self.keys[self.i] == "where" else []
        self.expect("end_type")
        self.expect(";")
        return TypeDecl(name, u, where, line)

    def underlying_type(self):
        line = self.lines[self.i]
        extensible = generic_entity = False
        if self.accept("extensible"):
            extensible = True
            if self.accept("generic_entity"):
                generic_entity = True
            if self.keys[self.i] not in ("select", "enumeration"):
                self.error("SELECT or ENUMERATION after EXTENSIBLE")
        k = self.keys[self.i]
        if k == "select":
            self.i += 1
            items: list = []
            based_on = None
            if self.keys[self.i] == "(":
                items = self.paren_ident_list("a type name")
            elif self.accept("based_on"):
                based_on = self.ident("a type name")
                if self.accept("with"):
                    items = self.paren_ident_list("a type name")
            return SelectType(items, extensible, generic_entity, based_on, line)
        if k == "enumeration":
            if generic_entity:
                self.error("SELECT after GENERIC_ENTITY")
            self.i += 1
            items = []
            based_on = None
            if self.accept("of"):
                items = self.paren_ident_list("an enumeration item")
            elif self.accept("based_on"):
                based_on = self.ident("a type name")
                if self.accept("with"):
                    items = self.paren_ident_list("an enumeration item")
            elif not extensible:
                self.error("OF or BASED_ON")
            return EnumerationType(items, extensible, based_on, line)
        return self.parse_type()

    def bound_spec(self):
        self.expect("[")
        lo = self.expression()
        self.expect(":")
        hi = self.expression()
        self.expect("]")
        return lo, hi

    def parse_type(self):
        """Any type reference: simple, named, aggregation (with or without
        bounds), AGGREGATE, GENERIC, GENERIC_ENTITY."""
        i = self.i
        k = self.keys[i]
        line = self.lines[i]
        if k in AGG_KINDS:
            self.i += 1
            lo = hi = None
            if self.keys[self.i] == "[":
                lo, hi = self.bound_spec()
            self.expect("of")
            optional = unique = False
            if k == "array" and self.accept("optional"):
                optional = True
            if k in ("array", "list") and self.accept("unique"):
                unique = True
            el = self.parse_type()
            return AggregateType(k, el, lo, hi, optional, unique, None, line)
        if k in SIMPLE_TYPES:
            self.i += 1
            width = None
            fixed = False
            if k in ("string", "binary", "real") and self.keys[self.i] == "(":
                self.i += 1
                width = self.expression()
                self.expect(")")
                if k != "real" and self.accept("fixed"):
                    fixed = True
            return SimpleType(k, width, fixed, line)
        if k == "aggregate":
            self.i += 1
            label = self.ident("a type label") if self.accept(":") else None
            self.expect("of")
            el = self.parse_type()
            return AggregateType("aggregate", el, None, None, False, False, label, line)
        if k in ("generic", "generic_entity"):
            self.i += 1
            label = self.ident("a type label") if self.accept(":") else None
            return GenericType(k, label, line)
        if k[:1].isalpha() and k not in RESERVED:
            self.i += 1
            return NamedType(k, line)
        self.error("a type")

    # ------------------------------------------------------------ entities
    def entity_decl(self) -> Entity:
        line = self.expect("entity")
        name = self.ident("an entity name")
        self.entity_names.add(name)
        ent = Entity(name, line=line)
        while True:
            k = self.keys[self.i]
            if k == "abstract":
                self.i += 1
                ent.abstract = True
                if self.accept("supertype"):
                    if self.accept("of"):
                        self.expect("(")
                        ent.supertype_expr = self.supertype_expression()
                        self.expect(")")
            elif k == "supertype":
                self.i += 1
                self.expect("of")
                self.expect("(")
                ent.supertype_expr = self.supertype_expression()
                self.expect(")")
            elif k == "subtype":
                self.i += 1
                self.expect("of")
                ent.supertypes = self.paren_ident_list("an entity name")
            else:
                break
        self.expect(";")
        keys = self.keys
        while keys[self.i] not in ENTITY_SECTIONS:
            ent.attributes.extend(self.explicit_attr())
        if self.accept("derive"):
            while keys[self.i] not in ENTITY_SECTIONS:
                ent.derived.append(self.derived_attr())
        if self.accept("inverse"):
            while keys[self.i] not in ENTITY_SECTIONS:
                ent.inverse.append(self.inverse_attr())
        if self.accept("unique"):
            while keys[self.i] not in ENTITY_SECTIONS:
                ent.unique.append(self.unique_rule())
        if keys[self.i] == "where":
            ent.where = self.where_clause()
        if keys[self.i] != "end_entity":
            self.error("an attribute, DERIVE, INVERSE, UNIQUE, WHERE or END_ENTITY"
                       if keys[self.i] not in ENTITY_SECTIONS else "END_ENTITY")
        self.i += 1
        self.expect(";")
        return ent

    def supertype_expression(self):
        line = self.lines[self.i]
        ops = [self.supertype_factor()]
        while self.accept("andor"):
            ops.append(self.supertype_factor())
        return ops[0] if len(ops) == 1 else SupertypeOp("andor", ops, line)

    def supertype_factor(self):
        line = self.lines[self.i]
        ops = [self.supertype_term()]
        while self.accept("and"):
            ops.append(self.supertype_term())
        return ops[0] if len(ops) == 1 else SupertypeOp("and", ops, line)

    def supertype_term(self):
        line = self.lines[self.i]
        if self.accept("oneof"):
            self.expect("(")
            ops = [self.supertype_expression()]
            while self.accept(","):
                ops.append(self.supertype_expression())
            self.expect(")")
            return SupertypeOp("oneof", ops, line)
        if self.accept("("):
            e = self.supertype_expression()
            self.expect(")")
            return e
        return self.ident("an entity name, ONEOF or '('")

    def attribute_decl(self):
        """attribute_id | SELF\\entity.attribute [RENAMED id] -> (name, supertype, renamed, line)"""
        line = self.lines[self.i]
        if self.accept("self"):
            self.expect("\\")
            sup = self.ident("an entity name")
            self.expect(".")
            name = self.ident("an attribute name")
            renamed = self.ident("an attribute name") if self.accept("renamed") else None
            return name, sup, renamed, line
        return self.ident("an attribute name"), None, None, line

    def explicit_attr(self) -> list:
        decls = [self.attribute_decl()]
        while self.accept(","):
            decls.append(self.attribute_decl())
        self.expect(":")
        optional = self.accept("optional")
        t = self.parse_type()
        self.expect(";")
        return [ExplicitAttribute(n, t, optional, s, r, line) for n, s, r, line in decls]

    def derived_attr(self) -> DerivedAttribute:
        name, sup, ren, line = self.attribute_decl()
        self.expect(":")
        t = self.parse_type()
        self.expect(":=")
        e = self.expression()
        self.expect(";")
        return DerivedAttribute(name, t, e, sup, ren, line)

    def inverse_attr(self) -> InverseAttribute:
        name, sup, ren, line = self.attribute_decl()
        self.expect(":")
        agg = lo = hi = None
        if self.keys[self.i] in ("set", "bag"):
            agg = self.keys[self.i]
            self.i += 1
            if self.keys[self.i] == "[":
                lo, hi = self.bound_spec()
            self.expect("of")
        ent = self.ident("an entity name")
        self.expect("for")
        a = self.ident("an attribute name")
        for_ent = None
        if self.accept("."):
            for_ent, a = a, self.ident("an attribute name")
        self.expect(";")
        return InverseAttribute(name, ent, a, agg, lo, hi, for_ent, sup, ren, line)

    def unique_rule(self) -> UniqueRule:
        line = self.lines[self.i]
        label = None
        if self.is_label():
            label = self.keys[self.i]
            self.i += 2
        attrs = []
        while True:
            aline = self.lines[self.i]
            if self.accept("self"):
                self.expect("\\")
                sup = self.ident("an entity name")
                self.expect(".")
                attrs.append(UniqueAttribute(self.ident("an attribute name"), sup, aline))
            else:
                attrs.append(UniqueAttribute(self.ident("an attribute name"), None, aline))
            if not self.accept(","):
                break
        self.expect(";")
        return UniqueRule(label, attrs, line)

    def where_clause(self) -> list:
        self.expect("where")
        out = []
        keys = self.keys
        while True:
            k = keys[self.i]
            if k in ("end_entity", "end_type", "end_rule", "end_subtype_constraint") or k == K_EOF:
                break
            line = self.lines[self.i]
            label = None
            if self.is_label():
                label = k
                self.i += 2
            e = self.expression()
            self.expect(";")
            out.append(WhereRule(label, e, line))
        return out

    def subtype_constraint_decl(self) -> SubtypeConstraint:
        line = self.expect("subtype_constraint")
        name = self.ident("a constraint name")
        self.expect("for")
        ent = self.ident("an entity name")
        self.expect(";")
        sc = SubtypeConstraint(name, ent, line=line)
        if self.accept("abstract"):
            self.expect("supertype")
            self.expect(";")
            sc.abstract = True
        if self.accept("total_over"):
            sc.total_over = self.paren_ident_list("an entity name")
            self.expect(";")
        if self.keys[self.i] != "end_subtype_constraint":
            sc.expr = self.supertype_expression()
            self.expect(";")
        self.expect("end_subtype_constraint")
        self.expect(";")
        return sc

    # ------------------------------------------------------------ algorithms
    def formal_parameters(self, allow_var: bool) -> list:
        out = []
        self.expect("(")
        while True:
            var = allow_var and self.accept("var")
            line = self.lines[self.i]
            names = self.ident_list("a parameter name")
            self.expect(":")
            t = self.parse_type()
            out.extend(Parameter(n, t, var, line) for n in names)
            if not self.accept(";"):
                break
        self.expect(")")
        return out

    def algorithm_head(self, decl) -> None:
        while True:
            k = self.keys[self.i]
            if k == "function":
                decl.declarations.append(self.function_decl())
            elif k == "procedure":
                decl.declarations.append(self.procedure_decl())
            elif k == "entity":
                decl.declarations.append(self.entity_decl())
            elif k == "type":
                decl.declarations.append(self.type_decl())
            elif k == "subtype_constraint":
                decl.declarations.append(self.subtype_constraint_decl())
            elif k == "constant":
                decl.constants.extend(self.constant_block())
            elif k == "local":
                self.i += 1
                while self.keys[self.i] != "end_local":
                    line = self.lines[self.i]
                    names = self.ident_list("a variable name or END_LOCAL")
                    self.expect(":")
                    t = self.parse_type()
                    init = self.expression() if self.accept(":=") else None
                    self.expect(";")
                    decl.locals.extend(LocalVariable(n, t, init, line) for n in names)
                self.i += 1
                self.expect(";")
            else:
                return

    def function_decl(self) -> Function:
        line = self.expect("function")
        name = self.ident("a function name")
        self.function_names.add(name)
        params = self.formal_parameters(False) if self.keys[self.i] == "(" else []
        self.expect(":")
        rt = self.parse_type()
        self.expect(";")
        f = Function(name, params, rt, line=line)
        self.algorithm_head(f)
        f.body = self.statements(("end_function",))
        self.i += 1
        self.expect(";")
        return f

    def procedure_decl(self) -> Procedure:
        line = self.expect("procedure")
        name = self.ident("a procedure name")
        params = self.formal_parameters(True) if self.keys[self.i] == "(" else []
        self.expect(";")
        p = Procedure(name, params, line=line)
        self.algorithm_head(p)
        p.body = self.statements(("end_procedure",))
        self.i += 1
        self.expect(";")
        return p

    def rule_decl(self) -> Rule:
        line = self.expect("rule")
        name = self.ident("a rule name")
        self.expect("for")
        applies = self.paren_ident_list("an entity name")
        self.expect(";")
        r = Rule(name, applies, line=line)
        self.algorithm_head(r)
        r.body = self.statements(("where", "end_rule"))
        if self.keys[self.i] == "where":
            r.where = self.where_clause()
        self.expect("end_rule")
        self.expect(";")
        return r

    # ------------------------------------------------------------ statements
    def statements(self, terminators: tuple) -> list:
        out = []
        keys = self.keys
        stmt = self.statement
        while True:
            k = keys[self.i]
            if k in terminators:
                return out
            if k == K_EOF or (k in RESERVED and k not in STMT_KEYWORDS):
                self.error("a statement or " + " or ".join(t.upper() for t in terminators))
            out.append(stmt())

    def statement(self):
        i = self.i
        k = self.keys[i]
        line = self.lines[i]
        if k == ";":
            self.i += 1
            return NullStmt(line)
        if k == "if":
            self.i += 1
            cond = self.expression()
            self.expect("then")
            then = self.statements(("else", "end_if"))
            els = None
            if self.accept("else"):
                els = self.statements(("end_if",))
            self.i += 1
            self.expect(";")
            return IfStmt(cond, then, els, line)
        if k == "case":
            self.i += 1
            sel = self.expression()
            self.expect("of")
            actions = []
            other = None
            while True:
                k2 = self.keys[self.i]
                if k2 == "end_case":
                    break
                if k2 == "otherwise":
                    self.i += 1
                    self.expect(":")
                    other = self.statement()
                    break
                aline = self.lines[self.i]
                labels = [self.expression()]
                while self.accept(","):
                    labels.append(self.expression())
                self.expect(":")
                actions.append(CaseAction(labels, self.statement(), aline))
            self.expect("end_case")
            self.expect(";")
            return CaseStmt(sel, actions, other, line)
        if k == "repeat":
            self.i += 1
            var = start = end = inc = w = u = None
            if self.keys[self.i + 1] == ":=":
                var = self.ident("a loop variable")
                self.i += 1
                start = self.expression()
                self.expect("to")
                end = self.expression()
                if self.accept("by"):
                    inc = self.expression()
            if self.accept("while"):
                w = self.expression()
            if self.accept("until"):
                u = self.expression()
            self.expect(";")
            body = self.statements(("end_repeat",))
            self.i += 1
            self.expect(";")
            return RepeatStmt(var, start, end, inc, w, u, body, line)
        if k == "return":
            self.i += 1
            v = None if self.keys[self.i] == ";" else self.expression()
            self.expect(";")
            return ReturnStmt(v, line)
        if k == "escape":
            self.i += 1
            self.expect(";")
            return EscapeStmt(line)
        if k == "skip":
            self.i += 1
            self.expect(";")
            return SkipStmt(line)
        if k == "begin":
            self.i += 1
            body = self.statements(("end",))
            self.i += 1
            self.expect(";")
            return CompoundStmt(body, line)
        if k == "alias":
            self.i += 1
            name = self.ident("an alias name")
            self.expect("for")
            target = self.primary()
            self.expect(";")
            body = self.statements(("end_alias",))
            self.i += 1
            self.expect(";")
            return AliasStmt(name, target, body, line)
        if not (k[:1].isalpha() and k not in RESERVED) or k in ("self", "true", "false", "unknown"):
            self.error("a statement")
        target = self.primary()
        if self.accept(":="):
            v = self.expression()
            self.expect(";")
            return Assignment(target, v, line)
        if isinstance(target, Call):
            if self.calls and self.calls[-1] is target:
                self.calls.pop()
            self.expect(";")
            return ProcedureCall(target.name, target.args, target.name in BUILTIN_PROCEDURES, line)
        if isinstance(target, Name):
            self.expect(";")
            return ProcedureCall(target.name, [], target.name in BUILTIN_PROCEDURES, line)
        self.error("':='")

    # ------------------------------------------------------------ expressions
    def expression(self):
        left = self.simple_expression()
        k = self.keys[self.i]
        if k in REL_OPS:
            line = self.lines[self.i]
            self.i += 1
            left = BinaryOp(k, left, self.simple_expression(), line)
        return left

    def simple_expression(self):
        left = self.term()
        keys = self.keys
        while keys[self.i] in ADD_OPS:
            k = keys[self.i]
            line = self.lines[self.i]
            self.i += 1
            left = BinaryOp(k, left, self.term(), line)
        return left

    def term(self):
        left = self.factor()
        keys = self.keys
        while keys[self.i] in MUL_OPS:
            k = keys[self.i]
            line = self.lines[self.i]
            self.i += 1
            left = BinaryOp(k, left, self.factor(), line)
        return left

    def factor(self):
        left = self.simple_factor()
        if self.keys[self.i] == "**":
            line = self.lines[self.i]
            self.i += 1
            left = BinaryOp("**", left, self.simple_factor(), line)
        return left

    def simple_factor(self):
        i = self.i
        k = self.keys[i]
        line = self.lines[i]
        if k == "(":
            self.i += 1
            e = self.expression()
            self.expect(")")
            return self.qualifiers(e)
        if k == "-" or k == "+" or k == "not":
            self.i += 1
            return UnaryOp(k, self.simple_factor(), line)
        if k == "[":
            self.i += 1
            els = []
            if self.keys[self.i] != "]":
                while True:
                    eline = self.lines[self.i]
                    v = self.expression()
                    rep = self.expression() if self.accept(":") else None
                    els.append(AggregateElement(v, rep, eline))
                    if not self.accept(","):
                        break
            self.expect("]")
            return self.qualifiers(AggregateInit(els, line))
        if k == "{":
            self.i += 1
            low = self.simple_expression()
            op1 = self.keys[self.i]
            if op1 not in ("<", "<="):
                self.error("'<' or '<=' in an interval")
            self.i += 1
            item = self.simple_expression()
            op2 = self.keys[self.i]
            if op2 not in ("<", "<="):
                self.error("'<' or '<=' in an interval")
            self.i += 1
            high = self.simple_expression()
            self.expect("}")
            return Interval(low, op1, item, op2, high, line)
        if k == "query":
            self.i += 1
            self.expect("(")
            var = self.ident("a query variable")
            self.expect("<*")
            agg = self.simple_expression()
            self.expect("|")
            cond = self.expression()
            self.expect(")")
            return self.qualifiers(Query(var, agg, cond, line))
        return self.primary()

    def primary(self):
        i = self.i
        k = self.keys[i]
        line = self.lines[i]
        if k[:1] == "\0":
            v = self.vals[i]
            if k == K_INT:
                node = Literal("integer", v, line)
            elif k == K_REAL:
                node = Literal("real", v, line)
            elif k == K_STR:
                node = (Literal("string", v[1], line, True) if isinstance(v, tuple)
                        else Literal("string", v, line))
            elif k == K_BIN:
                node = Literal("binary", v, line)
            else:
                self.error("an expression")
            self.i = i + 1
            return node
        if k == "?":
            self.i = i + 1
            return Literal("indeterminate", None, line)
        if not k[:1].isalpha():
            self.error("an expression")
        self.i = i + 1
        if k == "true":
            return Literal("logical", True, line)
        if k == "false":
            return Literal("logical", False, line)
        if k == "unknown":
            return Literal("logical", None, line)
        if k == "self":
            node = SelfRef(line)
        elif k == "const_e" or k == "pi":
            node = BuiltinConstant(k, line)
        elif k in RESERVED:
            self.i = i
            self.error("an expression")
        elif self.keys[i + 1] == "(":
            self.i += 1
            args = []
            if self.keys[self.i] != ")":
                args.append(self.expression())
                while self.accept(","):
                    args.append(self.expression())
            self.expect(")")
            node = Call(k, args, line)
            self.calls.append(node)
        else:
            node = Name(k, line)
        return self.qualifiers(node)

    def qualifiers(self, node):
        keys = self.keys
        while True:
            k = keys[self.i]
            if k == ".":
                line = self.lines[self.i]
                self.i += 1
                node = AttributeRef(node, self.ident("an attribute name"), line)
            elif k == "\\":
                line = self.lines[self.i]
                self.i += 1
                node = GroupRef(node, self.ident("an entity name"), line)
            elif k == "[":
                line = self.lines[self.i]
                self.i += 1
                idx = self.expression()
                hi = self.expression() if self.accept(":") else None
                self.expect("]")
                node = IndexRef(node, idx, hi, line)
            else:
                return node

    @staticmethod
    def _string_value(v):
        return v[1] if isinstance(v, tuple) else v

    # ------------------------------------------------------------ resolution
    def resolve_calls(self) -> None:
        ents, funcs = self.entity_names, self.function_names
        for c in self.calls:
            n = c.name
            if n in funcs:
                c.kind = "function"
            elif n in ents:
                c.kind = "entity"
            elif n in BUILTIN_FUNCTIONS:
                c.kind = "builtin"
            else:
                c.kind = "unknown"


def _link(s: Schema) -> None:
    """Compute the derived parts of the model (subtypes)."""
    ents = s.entities
    for e in ents.values():
        e.subtypes = []
    for e in ents.values():
        for sup in e.supertypes:
            se = ents.get(sup)
            if se is not None:
                se.subtypes.append(e.name)


# --------------------------------------------------------------------------
# public entry points


def parse_schemas(text: str, filename: str = "<string>") -> list:
    """Every schema of an EXPRESS text (a bare declaration list gives one
    schema named None). Raises ExpressSyntaxError."""
    p = _Parser(text, filename)
    try:
        return p.parse_file()
    except RecursionError:
        i = min(p.i, len(p.poss) - 1)
        line, col = _line_col(text, p.poss[i])
        raise ExpressSyntaxError("expression or statement nested too deeply", filename,
                                 line, col) from None
