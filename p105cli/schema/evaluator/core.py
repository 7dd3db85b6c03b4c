"""The ``Evaluator``: its state and its public entry points (expressions,
WHERE, UNIQUE and global rules, function calls, attribute values). The
work is done by the mixins of the sibling modules, one per seam.
"""

from __future__ import annotations

from ..model import (
    AggregateInit, AliasStmt, Assignment, AttributeRef, BinaryOp, BuiltinConstant, Call, CaseStmt,
    CompoundStmt, EscapeStmt, GroupRef, IfStmt, IndexRef, Interval, Literal, Name, NullStmt,
    ProcedureCall, Query, RepeatStmt, ReturnStmt, Rule, SchemaError, SelfRef, SkipStmt, UnaryOp,
    UniqueRule, WhereRule,
)
from .algorithms import Algorithms
from .attributes import Attributes
from .compiled import compiled_for
from .expressions import Expressions
from .natives import Natives
from .operators import Operators
from .schema_types import SchemaTypes
from .scope import MAX_CALL_DEPTH, _Scope
from .values import Agg, NotEvaluable, _IND, _plain


class Evaluator(SchemaTypes, Attributes, Expressions, Operators, Algorithms, Natives):
    """Evaluates EXPRESS over one Population (see the package docstring).

    ``population``: the ``Population`` whose instances the rules run over;
    one Evaluator per population keeps the caches (attribute access, memos
    of function calls) for all rules run over it. ``memoize=False`` turns
    off the memos of calls and of type-only QUERY conditions
    (``compiled.py``), ``natives=False`` the Python versions of schema
    functions (``natives.py``): the plain interpreter, for tests."""

    def __init__(self, population, max_depth: int = MAX_CALL_DEPTH,
                 literal_indeterminate_test: bool = False, memoize: bool = True,
                 natives: bool = True):
        self.pop = population
        self.literal_indeterminate_test = literal_indeterminate_test
        self.memoize = memoize
        self.natives = natives
        self._memo: dict = {}
        self.schema = population.schema
        self.compiled = compiled_for(self.schema)  # type-only facts, once per schema
        self.prefix = population.prefix
        self.max_depth = max_depth
        self._depth = 0
        self._steps = 0
        self._infos: dict = {}
        self._keys: dict = {}
        self._tdesc: dict = {}
        self._named_types: dict = {}
        self._select_parents = None
        self._typeof_cache: dict = {}
        self._enum_items = None
        self._constants: dict = {}
        self._derive_active: set = set()
        self._reps_memo: dict = {}  # natives: item id -> ids of the representations using it
        self.anomalies: list = []  # (message) attribute look-ups that found nothing
        d = {}
        for cls, meth in (
            (Literal, self._e_literal), (Name, self._e_name), (SelfRef, self._e_self),
            (BuiltinConstant, self._e_const), (UnaryOp, self._e_unary), (BinaryOp, self._e_binary),
            (Interval, self._e_interval), (AttributeRef, self._e_attr), (GroupRef, self._e_group),
            (IndexRef, self._e_index), (Call, self._e_call), (AggregateInit, self._e_agginit),
            (Query, self._e_query),
        ):
            d[cls] = meth
        self._edispatch = d
        s = {}
        for cls, meth in (
            (NullStmt, self._s_null), (Assignment, self._s_assign), (IfStmt, self._s_if),
            (CaseStmt, self._s_case), (RepeatStmt, self._s_repeat), (ReturnStmt, self._s_return),
            (EscapeStmt, self._s_escape), (SkipStmt, self._s_skip),
            (CompoundStmt, self._s_compound),
            (AliasStmt, self._s_alias), (ProcedureCall, self._s_pcall),
        ):
            s[cls] = meth
        self._sdispatch = s

    # ================================================================ public API
    def eval(self, expr, self_obj=None, ctx: str | None = None, variables: dict | None = None):
        """Evaluate one expression AST with SELF = ``self_obj``."""
        sc = _Scope(self_obj=self_obj, ctx=ctx)
        if variables:
            sc.vars.update(variables)
        return self._run(lambda: self.ev(expr, sc))

    def where_rule(self, instance, entity_name: str, rule):
        """Evaluate WHERE rule ``rule`` (a WhereRule or its label) of entity
        ``entity_name`` on ``instance``: True, False, or None (UNKNOWN or ?,
        which does not violate the rule). Raises NotEvaluable."""
        entity_name = entity_name.lower()
        if not isinstance(rule, WhereRule):
            rule = self.schema.entity(entity_name).where_rule(str(rule))
        sc = _Scope(self_obj=instance, ctx=entity_name)
        return self._logical(self._run(lambda: self.ev(rule.expr, sc)))

    def type_rule(self, value, type_name: str, rule):
        """Evaluate WHERE rule ``rule`` of defined type ``type_name`` with SELF = ``value``."""
        td = self.schema.types[type_name.lower()]
        if not isinstance(rule, WhereRule):
            rule = next(w for w in td.where if w.label == str(rule).lower())
        sc = _Scope(self_obj=value, ctx=None)
        return self._logical(self._run(lambda: self.ev(rule.expr, sc)))

    def applicable_where_rules(self, instance) -> list:
        """(entity name, WhereRule) for every WHERE rule of every entity the
        instance is an instance of (supertypes before subtypes)."""
        s = self.schema
        out = []
        for t in sorted(instance.types, key=lambda t: (len(s.all_supertypes(t))
                                                        if t in s.entities else 0, t)):
            e = s.entities.get(t)
            if e is not None:
                out.extend((t, w) for w in e.where)
        return out

    def check_instance(self, instance) -> list:
        """[(entity, rule label, result or NotEvaluable)] for every applicable WHERE rule."""
        out = []
        for ent, w in self.applicable_where_rules(instance):
            try:
                r = self.where_rule(instance, ent, w)
            except NotEvaluable as err:
                r = err
            out.append((ent, w.label, r))
        return out

    def unique_rule(self, entity_name: str, rule) -> list:
        """Groups (lists of >= 2 Instances, in file order) of instances of
        ``entity_name`` sharing the values of UNIQUE rule ``rule`` (a
        UniqueRule or its label). Instances with a ``?`` among the values
        are not compared."""
        entity_name = entity_name.lower()
        if not isinstance(rule, UniqueRule):
            ent = self.schema.entity(entity_name)
            rule = next(u for u in ent.unique if u.label == str(rule).lower())

        def run():
            groups: dict = {}
            for iid in self.pop.ids_of_type(entity_name):
                inst = self.pop.instance(iid)
                vals = []
                for ua in rule.attributes:
                    v = self._attr(inst, ua.name, ua.supertype, entity_name)
                    if v is _IND:
                        break
                    vals.append(self._key(v))
                else:
                    groups.setdefault(tuple(vals), []).append(inst)
            return [g for g in groups.values() if len(g) > 1]
        return self._run(run)

    def global_rule(self, rule) -> dict:
        """Evaluate a global RULE (a Rule or its name): {label: True/False/None}
        for each of its WHERE rules (unlabelled ones as 'wr<i>')."""
        if not isinstance(rule, Rule):
            rule = self.schema.rules[str(rule).lower()]

        def run():
            sc = _Scope(algos=self._algos_of(rule, None))
            for ent in rule.applies_to:
                sc.vars[ent] = Agg("set", (self.pop.instance(i) for i in self.pop.ids_of_type(ent)))
            self._enter_algorithm(rule, sc)
            self._exec_block(rule.body, sc)
            out = {}
            for i, w in enumerate(rule.where, 1):
                out[w.label or f"wr{i}"] = self._logical(self.ev(w.expr, sc))
            return out
        return self._run(run)

    def call(self, function_name: str, *args):
        """Call a schema function by name with evaluator values."""
        f = self.schema.functions[function_name.lower()]
        return self._run(lambda: self._call_algorithm(f, list(args), None))

    def attribute(self, obj, name: str, group: str | None = None, ctx: str | None = None):
        """The value of attribute ``name`` (explicit, derived or inverse) of
        an Instance or EntityValue; ``group``: the entity of a group
        qualifier (``obj\\group.name``). ``?`` when it has none."""
        return self._run(lambda: self._attr(obj, name.lower(), group and group.lower(), ctx))

    def derived_value(self, instance, name: str):
        key = self._find_key(instance, name.lower(), None, None)
        acc = self._info(instance).access.get(key) if key else None
        if acc is None or acc[0] != "derive":
            raise SchemaError(f"#{getattr(instance, 'id', '?')} has no derived attribute {name!r}")
        return self._run(lambda: self._attr_by_key(instance, key))

    def inverse_value(self, instance, name: str):
        key = self._find_key(instance, name.lower(), None, None)
        acc = self._info(instance).access.get(key) if key else None
        if acc is None or acc[0] != "inverse":
            raise SchemaError(f"#{getattr(instance, 'id', '?')} has no inverse attribute {name!r}")
        return self._run(lambda: self._attr_by_key(instance, key))

    def typeof(self, value) -> set:
        """TYPEOF as a Python set of strings."""
        return set(self._typeof_names(value))

    def _run(self, fn):
        depth = self._depth
        self._steps = 0
        try:
            return fn()
        except RecursionError:
            raise NotEvaluable("evaluation nested too deeply (Python recursion limit)") from None
        finally:
            self._depth = depth
            if depth == 0:
                self._derive_active.clear()

    @staticmethod
    def _logical(v):
        v = _plain(v)
        if v is True or v is False:
            return v
        return None
