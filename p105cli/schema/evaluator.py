"""An evaluator of EXPRESS (ISO 10303-11) expressions and algorithms over a Population.

It runs the ASTs of ``model.py`` -- WHERE and UNIQUE rules, DERIVE and
INVERSE attributes, function and procedure bodies, global RULEs -- against
the instances of a ``Population``.

Values
    ``int``, ``float``, ``str``; ``True``/``False``/``None`` for the LOGICAL
    values TRUE/FALSE/UNKNOWN; ``INDETERMINATE`` for ``?``; ``Agg`` (a list
    with the aggregate kind, lower index and defined type names) for
    aggregates; ``Instance`` for instances of the population and
    ``EntityValue`` for entity values built in memory by entity constructors
    and ``||``; ``EnumValue`` for enumeration items; ``TypedValue`` for a
    simple value of a defined type (so that TYPEOF knows the type);
    ``BinaryValue`` for BINARY.

Semantics followed (ISO 10303-11, 1994 with the 2004 additions)
    * ``?`` propagates: arithmetic, string and aggregate operators, indexing
      and attribute references on ``?`` give ``?``; comparisons, IN and
      instance comparisons with a ``?`` operand give UNKNOWN; the logical
      operators treat ``?`` as UNKNOWN (Kleene three-valued logic). EXISTS
      and NVL test for ``?``; TYPEOF(?) is the empty set; SIZEOF, HIINDEX,
      ... of ``?`` are ``?``. An index out of bounds gives ``?``.
    * IF, WHILE and QUERY conditions select only on TRUE; UNTIL stops on TRUE.
      A REPEAT whose bounds or increment are ``?`` is not executed.
    * IN, set union/difference/intersection and UNIQUE use instance
      equality (``:=:``); ``=`` is value equality (entity instances are
      compared attribute by attribute), as are VALUE_IN and VALUE_UNIQUE.
    * An entity constructor ``e(args)`` builds a partial entity value with
      the attributes declared in ``e`` itself; ``||`` joins partial values
      into a complex one (``dummy_gri || direction(...)``).
    * TYPEOF gives upper-case ``'SCHEMA.NAME'`` strings for every entity
      type, defined type and SELECT type the value belongs to (SELECTs
      transitively), plus the unqualified simple and aggregation type names.
    * Assigning to a variable, binding a parameter and returning from a
      function coerce aggregates to the declared kind (a SET drops instance
      duplicates, an ARRAY takes its declared lower index) and wrap simple
      values of defined types. Aggregates are values: assignment copies.
    * ``ATAN(v1, v2)`` is ``atan(v1/v2)`` in [-pi/2, pi/2] (the schemas fix
      the quadrant themselves); DIV and MOD are Python's floor division and
      modulo (``a = (a DIV b) * b + a MOD b``).

Results of rules: ``True``, ``False`` or ``None`` (UNKNOWN or ``?``, which
does not violate a rule). A construct that cannot be evaluated raises
``NotEvaluable(reason)``.

A science module: no click, rich or numpy here.
"""

from __future__ import annotations

import math
import re

from .model import (
    AggregateInit, AggregateType, AliasStmt, Assignment, AttributeRef, BinaryOp,
    BuiltinConstant, Call, CaseStmt, CompoundStmt, EnumerationType, EscapeStmt, Function,
    GroupRef, IfStmt, IndexRef, Interval, Literal, Name, NamedType, NullStmt,
    Procedure, ProcedureCall, Query, RepeatStmt, ReturnStmt, Rule, SchemaError, SelectType,
    SelfRef, SimpleType, SkipStmt, TypeDecl, UnaryOp, UniqueRule, WhereRule,
)
from .population import Instance, Population

__all__ = ["Evaluator", "NotEvaluable", "INDETERMINATE", "Agg", "EntityValue", "EnumValue",
           "TypedValue", "BinaryValue", "TypeRef"]


class NotEvaluable(Exception):
    """A construct the evaluator cannot evaluate; ``reason`` says which."""

    def __init__(self, reason: str, line: int = 0):
        super().__init__(reason)
        self.reason = reason
        self.line = line

    def __str__(self) -> str:
        return f"{self.reason} (schema line {self.line})" if self.line else self.reason


class _Indeterminate:
    __slots__ = ()

    def __repr__(self) -> str:
        return "?"

    def __bool__(self) -> bool:
        return False

    def __reduce__(self):
        return "INDETERMINATE"


INDETERMINATE = _Indeterminate()
_IND = INDETERMINATE


class Agg(list):
    """An EXPRESS aggregate value. ``kind``: list, set, bag or array;
    ``lo``: index of the first element (1, or an ARRAY's lower bound);
    ``dtypes``: defined type names (most specific first) when the value is
    of a defined aggregate type; ``bounds``: declared (lower, upper) bounds
    when known (upper None for ``?``)."""

    __slots__ = ("kind", "lo", "dtypes", "bounds")

    def __init__(self, kind: str = "list", items=(), lo: int = 1, dtypes=(), bounds=None):
        super().__init__(items)
        self.kind = kind
        self.lo = lo
        self.dtypes = tuple(dtypes)
        self.bounds = bounds

    def __repr__(self) -> str:
        return f"{self.kind.upper()}{list.__repr__(self)}"


class EnumValue:
    """An enumeration item; equal to any item of the same name."""

    __slots__ = ("item", "type")

    def __init__(self, item: str, type_name: str | None = None):
        self.item = item.lower()
        self.type = type_name

    def __eq__(self, other):
        return isinstance(other, EnumValue) and other.item == self.item

    def __hash__(self):
        return hash(("enum", self.item))

    def __repr__(self) -> str:
        return f".{self.item.upper()}."


class TypedValue:
    """A simple value of a defined type: ``dtypes`` lists the defined type
    names from the most specific (e.g. ('positive_length_measure',
    'length_measure')); ``value`` is the plain value."""

    __slots__ = ("value", "dtypes")

    def __init__(self, value, dtypes):
        self.value = value
        self.dtypes = tuple(dtypes)

    def __eq__(self, other):
        if isinstance(other, TypedValue):
            other = other.value
        return self.value == other

    def __hash__(self):
        return hash(self.value)

    def __repr__(self) -> str:
        return f"{self.dtypes[0].upper()}({self.value!r})" if self.dtypes else repr(self.value)


class BinaryValue:
    """A BINARY value as a string of '0'/'1' digits."""

    __slots__ = ("bits",)

    def __init__(self, bits: str):
        self.bits = bits

    def __eq__(self, other):
        return isinstance(other, BinaryValue) and other.bits == self.bits

    def __hash__(self):
        return hash(("binary", self.bits))

    def __repr__(self) -> str:
        return f"%{self.bits}"


class TypeRef:
    """A type or entity name used as a value (``si_prefix.milli``)."""

    __slots__ = ("name",)

    def __init__(self, name: str):
        self.name = name

    def __repr__(self) -> str:
        return f"TypeRef({self.name})"


class EntityValue:
    """An entity value built in memory (entity constructor, ``||``).

    ``parts`` maps each entity whose constructor contributed to a dict of
    that entity's own explicit attributes."""

    __slots__ = ("parts", "types", "leaf_types")

    def __init__(self, parts: dict, types: frozenset, leaf_types: frozenset):
        self.parts = parts
        self.types = types
        self.leaf_types = leaf_types

    def __repr__(self) -> str:
        return "(" + "".join(f"{p.upper()}({', '.join(map(repr, a.values()))})"
                             for p, a in self.parts.items()) + ")"


def _plain(v):
    return v.value if type(v) is TypedValue else v


def _is_entity(v) -> bool:
    return type(v) is Instance or type(v) is EntityValue


def _is_number(v) -> bool:
    t = type(v)
    return t is int or t is float


# --------------------------------------------------------------------------
# scopes and control-flow signals


class _Scope:
    __slots__ = ("vars", "decl", "parent", "self_obj", "ctx", "algos")

    def __init__(self, parent=None, self_obj=_IND, ctx=None, algos=None):
        self.vars: dict = {}
        self.decl: dict = {}  # variable name -> declared TypeSpec
        self.parent = parent
        if parent is not None:
            self.self_obj = parent.self_obj if self_obj is _IND else self_obj
            self.ctx = parent.ctx if ctx is None else ctx
            self.algos = parent.algos if algos is None else algos
        else:
            self.self_obj = None if self_obj is _IND else self_obj
            self.ctx = ctx
            self.algos = algos  # nested FUNCTION/PROCEDURE/TYPE declarations: name -> decl

    def find(self, name):
        s = self
        while s is not None:
            if name in s.vars:
                return s
            s = s.parent
        return None


class _Alias:
    __slots__ = ("expr", "scope")

    def __init__(self, expr, scope):
        self.expr = expr
        self.scope = scope


class _Return:
    __slots__ = ("value",)

    def __init__(self, value):
        self.value = value


_ESCAPE = object()
_SKIP = object()
_MISSING = object()

MAX_CALL_DEPTH = 120
MAX_STEPS = 5_000_000


class _AttrInfo:
    """How to obtain each attribute of an entity type set."""

    __slots__ = ("access", "names")

    def __init__(self, access, names):
        # (entity, attr) -> ('explicit',) | ('derive', ent, decl) | ('inverse', ent, decl)
        self.access = access
        self.names = names  # local name -> (entity, attr)


# --------------------------------------------------------------------------
# the evaluator


class Evaluator:
    """Evaluates EXPRESS over one Population (see the module docstring)."""

    def __init__(self, population: Population, max_depth: int = MAX_CALL_DEPTH,
                 literal_indeterminate_test: bool = False, memoize: bool = True):
        self.pop = population
        self.literal_indeterminate_test = literal_indeterminate_test
        self.memoize = memoize
        self._memo: dict = {}
        self.schema = population.schema
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

    # ================================================================ type machinery
    def _named(self, name: str) -> NamedType:
        t = self._named_types.get(name)
        if t is None:
            t = self._named_types[name] = NamedType(name)
        return t

    def _tinfo(self, t):
        """Normalised description of a TypeSpec (cached by identity)."""
        k = id(t)
        d = self._tdesc.get(k)
        if d is not None and d[0] is t:
            return d[1]
        d = self._describe(t)
        self._tdesc[k] = (t, d)
        return d

    def _describe(self, t):
        s = self.schema
        if isinstance(t, SimpleType):
            return ("simple", t.name, t)
        if isinstance(t, AggregateType):
            return ("agg", (), t)
        if isinstance(t, NamedType):
            name = t.name
            if name in s.entities:
                return ("entity", name)
            chain = []
            cur = name
            seen = set()
            while True:
                td = s.types.get(cur)
                if td is None or cur in seen:
                    return ("defined", tuple(chain or [name]), None) if chain else ("unknown", name)
                seen.add(cur)
                u = td.underlying
                if isinstance(u, SelectType):
                    if chain:
                        return ("defined", tuple(chain), NamedType(cur))
                    return ("select", cur, u)
                if isinstance(u, EnumerationType):
                    if chain:
                        return ("defined", tuple(chain), NamedType(cur))
                    return ("enum", cur, u)
                chain.append(cur)
                if isinstance(u, NamedType):
                    if u.name in s.entities:
                        return ("defined", tuple(chain), u)
                    cur = u.name
                    continue
                if isinstance(u, AggregateType):
                    return ("agg", tuple(chain), u)
                return ("defined", tuple(chain), u)
        return ("generic",)

    def _select_parent_map(self) -> dict:
        if self._select_parents is None:
            par: dict = {}
            for name, td in self.schema.types.items():
                u = td.underlying
                if isinstance(u, SelectType):
                    for it in u.items:
                        par.setdefault(it, set()).add(name)
                    if u.based_on:
                        par.setdefault(name, set()).add(u.based_on)
                elif isinstance(u, EnumerationType) and u.based_on:
                    par.setdefault(name, set()).add(u.based_on)
            self._select_parents = par
        return self._select_parents

    def _selects_of(self, names) -> set:
        par = self._select_parent_map()
        out: set = set()
        stack = list(names)
        while stack:
            n = stack.pop()
            for p in par.get(n, ()):
                if p not in out:
                    out.add(p)
                    stack.append(p)
        return out

    def _enum_index(self) -> dict:
        if self._enum_items is None:
            idx: dict = {}
            for name, td in self.schema.types.items():
                u = td.underlying
                if isinstance(u, EnumerationType):
                    for it in u.items:
                        idx.setdefault(it, []).append(name)
            self._enum_items = idx
        return self._enum_items

    def _enum_types_in(self, tname: str, item: str, seen=None):
        """An enumeration type reachable from type ``tname`` containing ``item``."""
        td = self.schema.types.get(tname)
        if td is None:
            return None
        seen = seen or set()
        if tname in seen:
            return None
        seen.add(tname)
        u = td.underlying
        if isinstance(u, EnumerationType):
            if item in u.items:
                return tname
            # extensible enumerations: items added by BASED_ON extensions
            for n2, td2 in self.schema.types.items():
                u2 = td2.underlying
                if isinstance(u2, EnumerationType) and u2.based_on == tname and item in u2.items:
                    return tname
            return None
        if isinstance(u, SelectType):
            for it in u.items:
                r = self._enum_types_in(it, item, seen)
                if r is not None:
                    return r
            return None
        if isinstance(u, NamedType):
            return self._enum_types_in(u.name, item, seen)
        return None

    # ---------------------------------------------------------------- raw -> value
    def convert(self, raw, t, owner=None):
        """A raw record value (JSON-shaped) as an evaluator value of declared type ``t``."""
        if raw is None:
            return _IND
        tr = type(raw)
        if tr is dict:
            r = raw.get("ref")
            if r is not None:
                try:
                    return self.pop.instance(r)
                except KeyError:
                    return _IND
            if "enum" in raw:
                return self._conv_enum(raw["enum"], t)
            if "derived" in raw:
                return _IND
            if "binary" in raw:
                return BinaryValue(_bits_of_p21_binary(raw["binary"]))
            if "type" in raw:
                return self.convert(raw.get("value"), self._named(str(raw["type"]).lower()), owner)
            return _IND
        d = self._tinfo(t) if t is not None else ("generic",)
        kind = d[0]
        if tr is list:
            if kind == "agg":
                at = d[2]
                lo = self._agg_lo(at, owner) if at.kind == "array" else 1
                return Agg(at.kind, (self.convert(x, at.element, owner) for x in raw), lo, d[1],
                           self._bounds(at))
            if kind == "defined" and isinstance(d[2], AggregateType):
                at = d[2]
                return Agg(at.kind, (self.convert(x, at.element, owner) for x in raw), 1, d[1])
            return Agg("list", (self.convert(x, None, owner) for x in raw))
        if kind == "defined":
            base = d[2]
            if isinstance(base, SimpleType):
                raw = self._simple(raw, base)
            return TypedValue(raw, d[1])
        if kind == "simple":
            return self._simple(raw, d[2])
        return raw

    @staticmethod
    def _simple(raw, st):
        if st.name == "real" and type(raw) is int:
            return float(raw)
        return raw

    def _conv_enum(self, item: str, t):
        it = str(item).lower()
        d = self._tinfo(t) if t is not None else ("generic",)
        kind = d[0]
        if kind == "simple" and d[1] in ("boolean", "logical"):
            return _LOGICAL_ITEMS.get(it, _IND)
        if kind == "enum":
            return EnumValue(it, d[1])
        if kind == "select":
            et = self._enum_types_in(d[1], it)
            if et is not None:
                return EnumValue(it, et)
        if (kind == "defined" and isinstance(d[2], SimpleType)
                and d[2].name in ("boolean", "logical")):
            v = _LOGICAL_ITEMS.get(it, _IND)
            return TypedValue(v, d[1]) if v is not _IND else _IND
        if it in _LOGICAL_ITEMS:
            return _LOGICAL_ITEMS[it]
        types = self._enum_index().get(it)
        return EnumValue(it, types[0] if types and len(types) == 1 else None)

    def _bounds(self, at: AggregateType):
        def lit(e):
            if e is None:
                return None
            if isinstance(e, Literal) and e.kind == "integer":
                return e.value
            return None
        return (lit(at.lower), lit(at.upper))

    def _agg_lo(self, at: AggregateType, owner=None, sc=None) -> int:
        e = at.lower
        if e is None:
            return 1
        if isinstance(e, Literal) and e.kind == "integer":
            return e.value
        try:
            scope = sc if sc is not None else _Scope(self_obj=owner)
            v = _plain(self.ev(e, scope))
            return v if type(v) is int else 1
        except NotEvaluable:
            return 1

    def _coerce(self, v, t, sc=None):
        """Adapt ``v`` to declared type ``t`` (aggregate kind, defined types)."""
        if v is _IND or t is None:
            return v
        d = self._tinfo(t)
        kind = d[0]
        if kind == "agg":
            if type(v) is not Agg:
                return v
            at = d[2]
            k = at.kind if at.kind != "aggregate" else v.kind
            if k == "set":
                items = self._dedupe(v)
            else:
                items = [_copy(x) for x in v]
            lo = self._agg_lo(at, sc.self_obj if sc else None, sc) if k == "array" else 1
            return Agg(k, items, lo, d[1] or v.dtypes, self._bounds(at))
        if kind == "defined":
            base = d[2]
            if type(v) is Agg and isinstance(base, AggregateType):
                out = self._coerce(v, base, sc)
                out.dtypes = d[1]
                return out
            if type(v) in (int, float, str, bool) or v is None or type(v) is BinaryValue:
                if isinstance(base, SimpleType) and base.name == "real" and type(v) is int:
                    v = float(v)
                return TypedValue(v, d[1])
            return v
        if kind == "simple":
            if d[1] == "real" and type(v) is int:
                return float(v)
            if type(v) is TypedValue:
                return v
        return v

    def _dedupe(self, items) -> list:
        out = []
        seen = set()
        for x in items:
            k = self._ikey(x)
            if k in seen:
                continue
            seen.add(k)
            out.append(_copy(x))
        return out

    # ---------------------------------------------------------------- attributes
    def _info(self, obj) -> _AttrInfo:
        types = obj.types
        info = self._infos.get(types)
        if info is None:
            info = self._infos[types] = self._make_info(types)
        return info

    def _make_info(self, types) -> _AttrInfo:
        s = self.schema
        known = s.most_specific_first(types)
        access: dict = {}
        override: dict = {}
        names: dict = {}
        for t in known:
            e = s.entities[t]
            for a in e.attributes:
                if a.supertype is None:
                    access[(t, a.name)] = ("explicit",)
            for a in e.derived:
                if a.supertype is None:
                    access[(t, a.name)] = ("derive", t, a)
            for a in e.inverse:
                if a.supertype is None:
                    access[(t, a.name)] = ("inverse", t, a)
        for t in known:
            e = s.entities[t]
            for a in e.derived:
                if a.supertype is not None:
                    k = self._resolve_key(a.supertype, a.name)
                    if k is not None:
                        override.setdefault(k, ("derive", t, a))
            for a in e.inverse:
                if a.supertype is not None:
                    k = self._resolve_key(a.supertype, a.name)
                    if k is not None:
                        override.setdefault(k, ("inverse", t, a))
        access.update(override)
        for t in known:
            e = s.entities[t]
            for a in (*e.attributes, *e.derived, *e.inverse):
                if a.supertype is None:
                    names.setdefault(a.name, (t, a.name))
                else:
                    k = self._resolve_key(a.supertype, a.name)
                    if k is not None:
                        names.setdefault(a.local_name, k)
        return _AttrInfo(access, names)

    def _resolve_key(self, entity: str, name: str):
        ck = (entity, name)
        if ck in self._keys:
            return self._keys[ck]
        k = None
        if entity in self.schema.entities:
            r = self.schema.resolve_attribute(entity, name)
            if r is not None:
                k = (r[0], r[1].name)
        self._keys[ck] = k
        return k

    def _find_key(self, obj, name, group, ctx):
        types = obj.types
        if group is not None:
            if group not in types:
                return None
            return self._resolve_key(group, name)
        if ctx is not None and ctx in types:
            k = self._resolve_key(ctx, name)
            if k is not None:
                return k
        return self._info(obj).names.get(name)

    def _attr(self, obj, name, group=None, ctx=None):
        if obj is _IND:
            return _IND
        to = type(obj)
        if to is Instance or to is EntityValue:
            key = self._find_key(obj, name, group, ctx)
            if key is None:
                self._anomaly(f"{obj!r} has no attribute {name}"
                              + (f" as {group}" if group else ""))
                return _IND
            return self._attr_by_key(obj, key)
        if to is TypeRef:
            return self._qualified_enum(obj.name, name)
        return _IND

    def _anomaly(self, msg: str) -> None:
        if len(self.anomalies) < 1000:
            self.anomalies.append(msg)

    def _qualified_enum(self, tname: str, item: str):
        td = self.schema.types.get(tname)
        if td is not None:
            et = self._enum_types_in(tname, item)
            if et is not None:
                return EnumValue(item, et)
        raise NotEvaluable(f"{tname}.{item} is not an enumeration item")

    def _attr_by_key(self, obj, key):
        info = self._info(obj)
        acc = info.access.get(key)
        if acc is None:
            return _IND
        kind = acc[0]
        if kind == "explicit":
            if type(obj) is Instance:
                cache = obj._values
                v = cache.get(key, _MISSING)
                if v is not _MISSING:
                    return v
                lay = obj.layout
                i = lay.by_key.get(key)
                if i is None:
                    v = _IND
                else:
                    v = self.convert(obj.raw(i), lay.slots[i].type, obj)
                cache[key] = v
                return v
            part = obj.parts.get(key[0])
            if part is None:
                return _IND
            return part.get(key[1], _IND)
        if kind == "derive":
            return self._derive(obj, key, acc[1], acc[2])
        return self._inverse(obj, key, acc[1], acc[2])

    def _derive(self, obj, key, ent, decl):
        is_inst = type(obj) is Instance
        if is_inst:
            dkey = ("derive",) + key
            v = obj._values.get(dkey, _MISSING)
            if v is not _MISSING:
                return v
            marker = (obj.id, key)
        else:
            marker = (id(obj), key)
        if marker in self._derive_active:
            raise NotEvaluable(f"derived attribute {ent}.{decl.name} depends on itself",
                               decl.line)
        self._derive_active.add(marker)
        try:
            sc = _Scope(self_obj=obj, ctx=ent)
            v = self._coerce(self.ev(decl.expr, sc), decl.type, sc)
        finally:
            self._derive_active.discard(marker)
        if is_inst:
            obj._values[dkey] = v
        return v

    def _inverse(self, obj, key, ent, decl):
        if type(obj) is not Instance:
            return Agg(decl.aggregate, ()) if decl.aggregate else _IND
        ikey = ("inverse",) + key
        v = obj._values.get(ikey, _MISSING)
        if v is not _MISSING:
            return v
        target_ent = decl.entity
        for_ent = decl.for_entity or target_ent
        rk = self._resolve_key(for_ent, decl.for_attribute)
        users = []
        if rk is not None:
            seen = set()
            pop = self.pop
            for rid, slot in pop.backrefs(obj.id):
                if slot < 0 or rid not in pop or rid in seen:
                    continue
                if target_ent not in pop.types_of(rid):
                    continue
                slots = pop._layout_of_id(rid).slots
                if slot < len(slots) and slots[slot].key == rk:
                    seen.add(rid)
                    users.append(pop.instance(rid))
        if decl.aggregate:
            v = Agg(decl.aggregate, users)
        else:
            v = users[0] if users else _IND
        obj._values[ikey] = v
        return v

    # ================================================================ expressions
    def ev(self, node, sc):
        try:
            fn = self._edispatch[type(node)]
        except KeyError:
            raise NotEvaluable(f"cannot evaluate {type(node).__name__}",
                               getattr(node, "line", 0)) from None
        return fn(node, sc)

    def _e_literal(self, node, sc):
        k = node.kind
        if k == "indeterminate":
            return _IND
        if k == "binary":
            return BinaryValue(str(node.value))
        return node.value

    def _e_self(self, node, sc):
        if sc.self_obj is None:
            raise NotEvaluable("SELF outside an entity or type", node.line)
        return sc.self_obj

    def _e_const(self, node, sc):
        return math.pi if node.name == "pi" else math.e

    def _e_name(self, node, sc):
        name = node.name
        s = sc
        while s is not None:
            v = s.vars.get(name, _MISSING)
            if v is not _MISSING:
                if type(v) is _Alias:
                    return self.ev(v.expr, v.scope)
                return v
            s = s.parent
        obj = sc.self_obj
        if obj is not None and (type(obj) is Instance or type(obj) is EntityValue):
            key = self._find_key(obj, name, None, sc.ctx)
            if key is not None:
                return self._attr_by_key(obj, key)
        schema = self.schema
        if name in schema.constants:
            return self._constant(name)
        if name in self._enum_index():
            types = self._enum_index()[name]
            return EnumValue(name, types[0])
        if name in schema.types or name in schema.entities:
            return TypeRef(name)
        algos = sc.algos
        if algos and name in algos and isinstance(algos[name], TypeDecl):
            return TypeRef(name)
        raise NotEvaluable(f"unknown name {name!r}", node.line)

    def _constant(self, name):
        v = self._constants.get(name, _MISSING)
        if v is _MISSING:
            self._constants[name] = _IND  # a constant defined by itself is ?
            c = self.schema.constants[name]
            v = self._coerce(self.ev(c.value, _Scope()), c.type)
            self._constants[name] = v
        return v

    def _e_unary(self, node, sc):
        v = _plain(self.ev(node.operand, sc))
        op = node.op
        if op == "not":
            if v is True:
                return False
            if v is False:
                return True
            if v is None:
                return None
            return _IND if v is _IND else None
        if v is _IND:
            return _IND
        if not _is_number(v):
            return _IND
        return -v if op == "-" else v

    def _e_interval(self, node, sc):
        lo = self.ev(node.low, sc)
        it = self.ev(node.item, sc)
        hi = self.ev(node.high, sc)
        a = self._compare(node.op1, lo, it)
        if a is False:
            return False
        b = self._compare(node.op2, it, hi)
        return _and3(a, b)

    def _e_binary(self, node, sc):
        op = node.op
        if op == "and":
            a = _l3(self.ev(node.left, sc))
            if a is False:
                return False
            return _and3(a, _l3(self.ev(node.right, sc)))
        if op == "or":
            a = _l3(self.ev(node.left, sc))
            if a is True:
                return True
            return _or3(a, _l3(self.ev(node.right, sc)))
        if op == "in" and type(node.right) is Call and node.right.name == "typeof" and \
                len(node.right.args) == 1 and self._lookup_algorithm("typeof", sc) is None:
            # 'SCHEMA.X' IN TYPEOF(v), the commonest test of all: no set built
            left = _plain(self.ev(node.left, sc))
            if left is _IND:
                return None
            return left in self._typeof_names(self.ev(node.right.args[0], sc))
        left = self.ev(node.left, sc)
        right = self.ev(node.right, sc)
        if self.literal_indeterminate_test and (op == "=" or op == "<>") and (
                _is_ind_literal(node.right) or _is_ind_literal(node.left)):
            r = _plain(left) is _IND and _plain(right) is _IND
            return r if op == "=" else not r
        if op == "xor":
            a, b = _l3(left), _l3(right)
            if a is None or b is None:
                return None
            return a is not b
        if op in _CMP_OPS:
            return self._compare(op, left, right)
        if op == "in":
            return self._in(left, right)
        if op == ":=:":
            return self._inst_eq(left, right)
        if op == ":<>:":
            r = self._inst_eq(left, right)
            return None if r is None else not r
        if op == "like":
            return self._like(left, right)
        if op == "||":
            return self._combine(left, right, node)
        return self._arith(op, left, right, node)

    # ---------------------------------------------------------------- comparisons
    def _compare(self, op, a, b):
        if a is _IND or b is _IND:
            return None
        a, b = _plain(a), _plain(b)
        if a is _IND or b is _IND:
            return None
        if op == "=" or op == "<>":
            r = self._value_eq(a, b, 0)
            if r is None:
                return None
            return r if op == "=" else not r
        ta, tb = type(a), type(b)
        if type(a) is Agg and type(b) is Agg:
            if op == "<=":
                return self._subset(a, b)
            if op == ">=":
                return self._subset(b, a)
            return None
        if _is_number(a) and _is_number(b):
            pass
        elif ta is str and tb is str:
            pass
        elif (a is None or ta is bool) and (b is None or tb is bool):
            a, b = _LOGICAL_ORDER[a], _LOGICAL_ORDER[b]
        elif ta is EnumValue and tb is EnumValue:
            a, b = self._enum_pos(a), self._enum_pos(b)
            if a is None or b is None:
                return None
        elif ta is BinaryValue and tb is BinaryValue:
            a, b = a.bits, b.bits
        else:
            return None
        if op == "<":
            return a < b
        if op == ">":
            return a > b
        if op == "<=":
            return a <= b
        return a >= b

    def _enum_pos(self, e):
        td = self.schema.types.get(e.type or "")
        if td is not None and isinstance(td.underlying, EnumerationType):
            items = td.underlying.items
            if e.item in items:
                return items.index(e.item)
        return None

    def _value_eq(self, a, b, depth):
        a, b = _plain(a), _plain(b)
        if a is _IND or b is _IND:
            return None
        if a is b:
            return True
        ta, tb = type(a), type(b)
        if _is_number(a) and _is_number(b):
            return a == b
        if ta is bool or tb is bool or a is None or b is None:
            return (ta is bool or a is None) and (tb is bool or b is None) and a is b
        if ta is Agg and tb is Agg:
            if len(a) != len(b):
                return False
            if a.kind in ("set", "bag") or b.kind in ("set", "bag"):
                rest = list(b)
                unknown = False
                for x in a:
                    for j, y in enumerate(rest):
                        r = self._value_eq(x, y, depth + 1)
                        if r:
                            del rest[j]
                            break
                        if r is None:
                            unknown = True
                    else:
                        return None if unknown else False
                return True
            res = True
            for x, y in zip(a, b):
                r = self._value_eq(x, y, depth + 1)
                if r is False:
                    return False
                if r is None:
                    res = None
            return res
        if _is_entity(a) and _is_entity(b):
            if depth > 12:
                return None
            if a.types != b.types:
                return False
            info = self._info(a)
            res = True
            for key, acc in info.access.items():
                if acc[0] != "explicit":
                    continue
                r = self._value_eq(self._attr_by_key(a, key), self._attr_by_key(b, key), depth + 1)
                if r is False:
                    return False
                if r is None:
                    res = None
            return res
        if ta is not tb:
            return False
        return a == b

    def _inst_eq(self, a, b):
        if a is _IND or b is _IND:
            return None
        if _is_entity(a) or _is_entity(b):
            return a is b
        if type(a) is Agg and type(b) is Agg:
            if len(a) != len(b):
                return False
            if a.kind in ("set", "bag") or b.kind in ("set", "bag"):
                ka = sorted(map(repr, (self._ikey(x) for x in a)))
                kb = sorted(map(repr, (self._ikey(x) for x in b)))
                return ka == kb
            res = True
            for x, y in zip(a, b):
                r = self._inst_eq(x, y)
                if r is False:
                    return False
                if r is None:
                    res = None
            return res
        return self._value_eq(a, b, 0)

    def _ikey(self, v):
        """A hashable key: equal keys <=> instance equal (for simple values, value equal)."""
        t = type(v)
        if t is Instance:
            return ("#", v.id)
        if t is EntityValue:
            return ("@", id(v))
        if t is TypedValue:
            return self._ikey(v.value)
        if t is Agg:
            keys = [self._ikey(x) for x in v]
            if v.kind in ("set", "bag"):
                keys.sort(key=repr)
            return ("agg", tuple(keys))
        if t is bool or v is None:
            return ("logical", v)
        if v is _IND:
            return ("?",)
        if t is float and v.is_integer():
            return int(v)
        return v

    _key = _ikey

    def _in(self, e, agg):
        if agg is _IND or e is _IND:
            return None
        agg = _plain(agg)
        if type(agg) is not Agg:
            if type(agg) is str and type(_plain(e)) is str:
                return _plain(e) in agg
            return None
        if _is_entity(e):
            for x in agg:
                if x is e:
                    return True
            return False
        pe = _plain(e)
        if type(pe) is str:
            unknown = False
            for x in agg:
                tx = type(x)
                if tx is str:
                    if x == pe:
                        return True
                elif tx is TypedValue:
                    if x.value == pe:
                        return True
                elif x is _IND:
                    unknown = True
            return None if unknown else False
        unknown = False
        for x in agg:
            r = self._inst_eq(e, x)
            if r:
                return True
            if r is None:
                unknown = True
        return None if unknown else False

    def _subset(self, a, b):
        for x in a:
            r = self._in(x, b)
            if r is not True:
                return r
        return True

    def _like(self, s, pattern):
        s, pattern = _plain(s), _plain(pattern)
        if s is _IND or pattern is _IND:
            return None
        if type(s) is not str or type(pattern) is not str:
            return None
        return _like_regex(pattern).fullmatch(s) is not None

    # ---------------------------------------------------------------- arithmetic
    def _arith(self, op, a, b, node):
        if a is _IND or b is _IND:
            return _IND
        a, b = _plain(a), _plain(b)
        if a is _IND or b is _IND:
            return _IND
        ta, tb = type(a), type(b)
        if ta is Agg or tb is Agg:
            return self._agg_op(op, a, b, node)
        if _is_number(a) and _is_number(b):
            try:
                if op == "+":
                    return a + b
                if op == "-":
                    return a - b
                if op == "*":
                    return a * b
                if op == "/":
                    return a / b
                if op == "div":
                    return int(a // b)
                if op == "mod":
                    return a % b
                if op == "**":
                    r = a ** b
                    return _IND if isinstance(r, complex) else r
            except (ZeroDivisionError, OverflowError, ValueError):
                return _IND
        if op == "+":
            if ta is str and tb is str:
                return a + b
            if ta is BinaryValue and tb is BinaryValue:
                return BinaryValue(a.bits + b.bits)
        raise NotEvaluable(f"operator {op.upper()} on {_tname(a)} and {_tname(b)}", node.line)

    def _agg_op(self, op, a, b, node):
        ta, tb = type(a), type(b)
        if op == "+":
            if ta is Agg and tb is Agg:
                kind = _union_kind(a.kind, b.kind)
                if kind == "set":
                    return Agg("set", self._dedupe([*a, *b]))
                return Agg(kind, [*a, *b])
            if ta is Agg:
                if a.kind == "set":
                    if self._in(b, a) is True:
                        return Agg("set", list(a))
                    return Agg("set", [*a, b])
                return Agg(a.kind if a.kind != "array" else "list", [*a, b])
            # element + aggregate
            if b.kind == "set":
                if self._in(a, b) is True:
                    return Agg("set", list(b))
                return Agg("set", [a, *b])
            return Agg(b.kind if b.kind != "array" else "list", [a, *b])
        if op == "-":
            if ta is not Agg:
                raise NotEvaluable("element - aggregate", node.line)
            out = list(a)
            for x in (b if tb is Agg else [b]):
                for j, y in enumerate(out):
                    if self._inst_eq(x, y):
                        del out[j]
                        break
            return Agg(a.kind, out)
        if op == "*":
            if ta is Agg and tb is Agg:
                rest = list(b)
                out = []
                for x in a:
                    for j, y in enumerate(rest):
                        if self._inst_eq(x, y):
                            out.append(x)
                            del rest[j]
                            break
                kind = "set" if "set" in (a.kind, b.kind) else "bag"
                return Agg(kind, self._dedupe(out) if kind == "set" else out)
        raise NotEvaluable(f"operator {op.upper()} on {_tname(a)} and {_tname(b)}", node.line)

    def _combine(self, a, b, node):
        if a is _IND or b is _IND:
            return _IND
        if type(a) is not EntityValue or type(b) is not EntityValue:
            raise NotEvaluable("|| on a population instance (only in-memory entity values "
                               "can be combined)", node.line)
        parts = {k: {n: _copy(x) for n, x in v.items()} for k, v in a.parts.items()}
        for k, v in b.parts.items():
            parts[k] = {n: _copy(x) for n, x in v.items()}
        types, leaf = self.pop.resolve_types(parts)
        return EntityValue(parts, types, leaf)

    # ---------------------------------------------------------------- references
    def _e_attr(self, node, sc):
        base = node.base
        if type(base) is GroupRef:
            obj = self.ev(base.base, sc)
            return self._attr(obj, node.attribute, base.entity, None)
        obj = self.ev(base, sc)
        ctx = sc.ctx if type(base) is SelfRef else None
        return self._attr(obj, node.attribute, None, ctx)

    def _e_group(self, node, sc):
        obj = self.ev(node.base, sc)
        if obj is _IND:
            return _IND
        if _is_entity(obj) and node.entity not in obj.types:
            return _IND
        return obj

    def _e_index(self, node, sc):
        base = _plain(self.ev(node.base, sc))
        i = _plain(self.ev(node.index, sc))
        if base is _IND or i is _IND:
            return _IND
        if type(i) is float and i.is_integer():
            i = int(i)
        if type(i) is not int:
            return _IND
        if node.upper is not None:
            j = _plain(self.ev(node.upper, sc))
            if j is _IND:
                return _IND
            if type(base) is str:
                return base[i - 1:j] if 1 <= i <= j <= len(base) else _IND
            if type(base) is BinaryValue:
                return BinaryValue(base.bits[i - 1:j]) if 1 <= i <= j <= len(base.bits) else _IND
            return _IND
        tb = type(base)
        if tb is Agg:
            k = i - base.lo
            if 0 <= k < len(base):
                return base[k]
            return _IND
        if tb is str:
            return base[i - 1] if 1 <= i <= len(base) else _IND
        if tb is BinaryValue:
            return BinaryValue(base.bits[i - 1]) if 1 <= i <= len(base.bits) else _IND
        return _IND

    def _e_agginit(self, node, sc):
        out = Agg("bag")
        for el in node.elements:
            v = self.ev(el.value, sc)
            if el.repeat is not None:
                n = _plain(self.ev(el.repeat, sc))
                if n is _IND or type(n) is not int:
                    return _IND
                out.extend(_copy(v) for _ in range(max(n, 0)))
            else:
                out.append(v)
        return out

    def _e_query(self, node, sc):
        agg = _plain(self.ev(node.aggregate, sc))
        if agg is _IND:
            return _IND
        if type(agg) is not Agg:
            raise NotEvaluable(f"QUERY over {_tname(agg)}", node.line)
        inner = _Scope(sc)
        var = node.variable
        out = []
        for x in agg:
            inner.vars[var] = x
            if _l3(self.ev(node.condition, inner)) is True:
                out.append(x)
        return Agg(agg.kind if agg.kind != "array" else "list", out)

    # ---------------------------------------------------------------- calls
    def _lookup_algorithm(self, name, sc):
        algos = sc.algos
        if algos:
            d = algos.get(name)
            if d is not None and isinstance(d, (Function, Procedure)):
                return d
        return self.schema.functions.get(name) or self.schema.procedures.get(name)

    def _e_call(self, node, sc):
        name = node.name
        f = self._lookup_algorithm(name, sc)
        if f is not None and isinstance(f, Function):
            args = [self.ev(a, sc) for a in node.args]
            # functions have no side effects on the population: results are
            # kept for arguments that are plain values or population instances
            key = self._memo_key(f, args)
            if key is not None:
                v = self._memo.get(key, _MISSING)
                if v is not _MISSING:
                    return v
            v = self._call_algorithm(f, args, sc)
            if key is not None and _memo_safe(v):
                self._memo[key] = v
            return v
        if name in self.schema.entities:
            return self._construct(name, [self.ev(a, sc) for a in node.args], node)
        b = _BUILTINS.get(name)
        if b is not None:
            return b(self, node, sc)
        if name in self.schema.types:
            args = [self.ev(a, sc) for a in node.args]
            if len(args) == 1:
                return self._coerce(args[0], self._named(name))
        raise NotEvaluable(f"unknown function {name!r}", node.line)

    def _memo_key(self, f, args):
        if not self.memoize:
            return None
        keys = []
        for a in args:
            if not _memo_safe(a):
                return None
            keys.append(_mkey(a))
        return (id(f), tuple(keys))

    def _algos_of(self, decl, sc):
        nested = getattr(decl, "declarations", None)
        outer = sc.algos if sc is not None else None
        if not nested:
            return outer
        d = dict(outer) if outer else {}
        for x in nested:
            d[x.name] = x
        return d

    def _enter_algorithm(self, decl, sc):
        for c in decl.constants:
            sc.vars[c.name] = self._coerce(self.ev(c.value, sc), c.type, sc)
            sc.decl[c.name] = c.type
        for lv in decl.locals:
            if lv.init is not None:
                v = self._coerce(_copy(self.ev(lv.init, sc)), lv.type, sc)
            else:
                v = _IND
            sc.vars[lv.name] = v
            sc.decl[lv.name] = lv.type

    def _call_algorithm(self, f, args, caller_sc, var_targets=None):
        self._depth += 1
        if self._depth > self.max_depth:
            raise NotEvaluable(f"calls nested deeper than {self.max_depth} (in {f.name})", f.line)
        try:
            sc = _Scope(algos=self._algos_of(f, caller_sc))
            params = f.parameters
            for i, p in enumerate(params):
                v = args[i] if i < len(args) else _IND
                if not p.var:
                    v = _copy(v)
                sc.vars[p.name] = self._coerce(v, p.type, sc) if not p.var else v
                sc.decl[p.name] = p.type
            self._enter_algorithm(f, sc)
            sig = self._exec_block(f.body, sc)
            if isinstance(f, Procedure):
                return [sc.vars.get(p.name, _IND) for p in params]
            v = sig.value if isinstance(sig, _Return) else _IND
            return self._coerce(v, f.return_type, sc)
        finally:
            self._depth -= 1

    def _construct(self, name, args, node):
        e = self.schema.entities[name]
        own = [a for a in e.attributes if a.supertype is None]
        if len(args) > len(own):
            raise NotEvaluable(f"entity constructor {name} with {len(args)} arguments "
                               f"for {len(own)} attributes", node.line)
        vals = {}
        for i, a in enumerate(own):
            v = args[i] if i < len(args) else _IND
            vals[a.name] = self._coerce(_copy(v), a.type)
        parts = {name: vals}
        types, leaf = self.pop.resolve_types([name])
        return EntityValue(parts, types, leaf)

    # ================================================================ statements
    def _exec_block(self, stmts, sc):
        sd = self._sdispatch
        for st in stmts:
            self._steps += 1
            if self._steps > MAX_STEPS:
                raise NotEvaluable(f"more than {MAX_STEPS} statements executed (endless loop?)",
                                   st.line)
            sig = sd[type(st)](st, sc)
            if sig is not None:
                return sig
        return None

    def _s_null(self, st, sc):
        return None

    def _s_assign(self, st, sc):
        self._assign(st.target, self.ev(st.value, sc), sc)
        return None

    def _assign(self, target, value, sc):
        tt = type(target)
        if tt is Name:
            s = sc.find(target.name)
            if s is None:
                raise NotEvaluable(f"assignment to undeclared {target.name!r}", target.line)
            cur = s.vars[target.name]
            if type(cur) is _Alias:
                return self._assign(cur.expr, value, cur.scope)
            s.vars[target.name] = self._coerce(_copy(value), s.decl.get(target.name), s)
            return
        if tt is IndexRef:
            self._check_owned(target.base, sc)
            container = _plain(self.ev(target.base, sc))
            i = _plain(self.ev(target.index, sc))
            if target.upper is not None:
                raise NotEvaluable("assignment to a subrange", target.line)
            if type(container) is not Agg or type(i) is not int:
                raise NotEvaluable("indexed assignment to a non-aggregate or with a "
                                   "non-integer index", target.line)
            k = i - container.lo
            if 0 <= k < len(container):
                container[k] = _copy(value)
            elif container.kind == "array" and k >= 0:
                container.extend(_IND for _ in range(k - len(container) + 1))
                container[k] = _copy(value)
            else:
                raise NotEvaluable(f"index {i} out of bounds in assignment", target.line)
            return
        if tt is AttributeRef:
            base = target.base
            group = None
            if type(base) is GroupRef:
                group = base.entity
                base = base.base
            obj = self.ev(base, sc)
            if type(obj) is not EntityValue:
                raise NotEvaluable("assignment to an attribute of a population instance",
                                   target.line)
            key = self._find_key(obj, target.attribute, group, None)
            if key is None or key[0] not in obj.parts:
                raise NotEvaluable(f"assignment to unknown attribute {target.attribute}",
                                   target.line)
            obj.parts[key[0]][key[1]] = _copy(value)
            return
        raise NotEvaluable(f"assignment to {tt.__name__}", target.line)

    def _check_owned(self, node, sc):
        """Refuse to modify an aggregate that belongs to a population instance."""
        while type(node) in (IndexRef, AttributeRef, GroupRef):
            if type(node) is AttributeRef:
                base = node.base.base if type(node.base) is GroupRef else node.base
                if type(self.ev(base, sc)) is Instance:
                    raise NotEvaluable("assignment into an attribute of a population instance",
                                       node.line)
            node = node.base

    def _s_if(self, st, sc):
        c = _l3(self.ev(st.condition, sc))
        if c is True:
            return self._exec_block(st.then_body, sc)
        if st.else_body:
            return self._exec_block(st.else_body, sc)
        return None

    def _s_case(self, st, sc):
        sel = self.ev(st.selector, sc)
        if sel is not _IND:
            for action in st.actions:
                for lab in action.labels:
                    if self._value_eq(sel, self.ev(lab, sc), 0) is True:
                        return self._exec_block([action.body], sc)
        if st.otherwise is not None:
            return self._exec_block([st.otherwise], sc)
        return None

    def _s_repeat(self, st, sc):
        inner = _Scope(sc)
        if st.variable is not None:
            start = _plain(self.ev(st.start, sc))
            end = _plain(self.ev(st.end, sc))
            inc = _plain(self.ev(st.increment, sc)) if st.increment is not None else 1
            if start is _IND or end is _IND or inc is _IND:
                return None
            if not (_is_number(start) and _is_number(end) and _is_number(inc)) or inc == 0:
                raise NotEvaluable("REPEAT bounds are not numbers (or increment 0)", st.line)
            i = start
            var = st.variable

            def more(i):
                return i <= end if inc > 0 else i >= end
        else:
            i = var = None

            def more(i):
                return True
        while more(i):
            if var is not None:
                inner.vars[var] = i
            if st.while_cond is not None and _l3(self.ev(st.while_cond, inner)) is not True:
                break
            sig = self._exec_block(st.body, inner)
            if sig is _ESCAPE:
                break
            if sig is not None and sig is not _SKIP:
                return sig
            if st.until_cond is not None and _l3(self.ev(st.until_cond, inner)) is True:
                break
            if var is not None:
                i = i + inc
            else:
                self._steps += 1
                if self._steps > MAX_STEPS:
                    raise NotEvaluable("endless REPEAT", st.line)
        return None

    def _s_return(self, st, sc):
        return _Return(self.ev(st.value, sc) if st.value is not None else None)

    def _s_escape(self, st, sc):
        return _ESCAPE

    def _s_skip(self, st, sc):
        return _SKIP

    def _s_compound(self, st, sc):
        return self._exec_block(st.body, sc)

    def _s_alias(self, st, sc):
        inner = _Scope(sc)
        inner.vars[st.name] = _Alias(st.target, sc)
        return self._exec_block(st.body, inner)

    def _s_pcall(self, st, sc):
        name = st.name
        if st.builtin or (name in ("insert", "remove")
                          and self._lookup_algorithm(name, sc) is None):
            return self._builtin_procedure(st, sc)
        p = self._lookup_algorithm(name, sc)
        if p is None or not isinstance(p, Procedure):
            raise NotEvaluable(f"unknown procedure {name!r}", st.line)
        args = [self.ev(a, sc) for a in st.args]
        finals = self._call_algorithm(p, args, sc)
        for prm, arg_expr, final in zip(p.parameters, st.args, finals):
            if prm.var:
                self._assign(arg_expr, final, sc)
        return None

    def _builtin_procedure(self, st, sc):
        args = st.args
        lst = _plain(self.ev(args[0], sc))
        if type(lst) is not Agg:
            if lst is _IND:
                return None
            raise NotEvaluable(f"{st.name.upper()} on a non-aggregate", st.line)
        if st.name == "insert":
            e = self.ev(args[1], sc)
            p = _plain(self.ev(args[2], sc))
            if type(p) is not int or not 0 <= p <= len(lst):
                raise NotEvaluable("INSERT position out of range", st.line)
            lst.insert(p, _copy(e))
        else:
            p = _plain(self.ev(args[1], sc))
            if type(p) is not int or not 1 <= p <= len(lst):
                raise NotEvaluable("REMOVE position out of range", st.line)
            del lst[p - 1]
        return None

    # ================================================================ TYPEOF
    def _typeof(self, v) -> Agg:
        return Agg("set", sorted(self._typeof_names(v)))

    def _typeof_names(self, v) -> frozenset:
        if v is _IND:
            return frozenset()
        t = type(v)
        if t is Instance or t is EntityValue:
            key = v.types
            r = self._typeof_cache.get(key)
            if r is None:
                names = set(v.types)
                names |= self._selects_of(names)
                r = self._typeof_cache[key] = frozenset(self.prefix + n.upper() for n in names)
            return r
        out: set = set()
        base: list = []
        if t is TypedValue:
            base.extend(v.dtypes)
            out |= _simple_names(v.value)
        elif t is Agg:
            base.extend(v.dtypes)
            out.add(v.kind.upper())
        elif t is EnumValue:
            if v.type:
                base.append(v.type)
        else:
            out |= _simple_names(v)
        if base:
            names = set(base) | self._selects_of(base)
            out |= {self.prefix + n.upper() for n in names}
        return frozenset(out)


# --------------------------------------------------------------------------
# helpers


_LOGICAL_ITEMS = {"t": True, "f": False, "u": None, "true": True, "false": False,
                  "unknown": None}
_LOGICAL_ORDER = {False: 0, None: 1, True: 2}
_CMP_OPS = frozenset(("=", "<>", "<", ">", "<=", ">="))


def _is_ind_literal(node) -> bool:
    return type(node) is Literal and node.kind == "indeterminate"


def _l3(v):
    v = _plain(v)
    if v is True or v is False:
        return v
    return None


def _and3(a, b):
    if a is False or b is False:
        return False
    if a is True and b is True:
        return True
    return None


def _or3(a, b):
    if a is True or b is True:
        return True
    if a is False and b is False:
        return False
    return None


def _union_kind(a, b):
    if a == "set" and b == "set":
        return "set"
    if a == "list" and b == "list":
        return "list"
    if "set" in (a, b) and "bag" not in (a, b) and "list" not in (a, b):
        return "set"
    if a == "set" or (a == "array" and b == "set"):
        return "set"
    return "bag" if "bag" in (a, b) or a != b else a


def _memo_safe(v) -> bool:
    """True for values that cannot be changed after the fact (no in-memory
    entity values inside): plain values, population instances, enumeration
    items, and aggregates of those."""
    t = type(v)
    if t is Agg:
        return all(_memo_safe(x) for x in v)
    return t is not EntityValue and t is not _Alias


def _mkey(v):
    """A memo key telling apart everything a function could tell apart."""
    t = type(v)
    if t is Instance:
        return ("#", v.id)
    if t is Agg:
        return ("agg", v.kind, v.lo, v.dtypes, tuple(_mkey(x) for x in v))
    if t is TypedValue:
        return ("typed", v.dtypes, _mkey(v.value))
    if t is EnumValue:
        return ("enum", v.item, v.type)
    return (t.__name__, v if t is not _Indeterminate else None)


def _copy(v):
    if type(v) is Agg:
        return Agg(v.kind, [_copy(x) for x in v], v.lo, v.dtypes, v.bounds)
    return v


def _tname(v) -> str:
    if v is _IND:
        return "?"
    if type(v) is Agg:
        return v.kind.upper()
    if _is_entity(v):
        return "entity " + "+".join(sorted(v.leaf_types))
    return type(v).__name__


def _simple_names(v) -> set:
    t = type(v)
    if t is bool or v is None:
        return {"LOGICAL", "BOOLEAN"} if t is bool else {"LOGICAL"}
    if t is int:
        return {"INTEGER", "NUMBER"}
    if t is float:
        return {"REAL", "NUMBER"}
    if t is str:
        return {"STRING"}
    if t is BinaryValue:
        return {"BINARY"}
    return set()


def _bits_of_p21_binary(s: str) -> str:
    """Part 21 binary ``"3FF"`` (first digit: unused leading bits) -> '0'/'1' string."""
    if not s:
        return ""
    pad = int(s[0], 16)
    bits = "".join(f"{int(c, 16):04b}" for c in s[1:])
    return bits[pad:]


_LIKE_CACHE: dict = {}


def _like_regex(pattern: str):
    r = _LIKE_CACHE.get(pattern)
    if r is not None:
        return r
    out = []
    i = 0
    n = len(pattern)
    while i < n:
        c = pattern[i]
        if c == "\\" and i + 1 < n:
            out.append(re.escape(pattern[i + 1]))
            i += 2
            continue
        out.append({
            "@": "[A-Za-z]", "^": "[A-Z]", "?": ".", "&": ".*", "#": "[0-9]",
            "$": "[^ ]*", "*": ".*", "!": "[a-z]",
        }.get(c, re.escape(c)))
        i += 1
    r = _LIKE_CACHE[pattern] = re.compile("".join(out), re.S)
    return r


# --------------------------------------------------------------------------
# built-in functions: each takes (evaluator, call node, scope)


def _args(ev, node, sc, n=None):
    vals = [ev.ev(a, sc) for a in node.args]
    if n is not None and len(vals) != n:
        raise NotEvaluable(f"{node.name.upper()} takes {n} argument(s)", node.line)
    return vals


def _num1(fn):
    def f(ev, node, sc):
        (v,) = _args(ev, node, sc, 1)
        v = _plain(v)
        if v is _IND or not _is_number(v):
            return _IND
        try:
            r = fn(v)
        except (ValueError, OverflowError, ZeroDivisionError):
            return _IND
        return _IND if r is None else r
    return f


def _b_atan(ev, node, sc):
    vals = [_plain(x) for x in _args(ev, node, sc)]
    if any(x is _IND or not _is_number(x) for x in vals):
        return _IND
    if len(vals) == 1:
        return math.atan(vals[0])
    if len(vals) != 2:
        raise NotEvaluable("ATAN takes 2 arguments", node.line)
    v1, v2 = vals
    if v2 == 0:
        if v1 == 0:
            return _IND
        return math.pi / 2 if v1 > 0 else -math.pi / 2
    return math.atan(v1 / v2)


def _b_blength(ev, node, sc):
    (v,) = _args(ev, node, sc, 1)
    v = _plain(v)
    return len(v.bits) if type(v) is BinaryValue else _IND


def _b_exists(ev, node, sc):
    (v,) = _args(ev, node, sc, 1)
    return _plain(v) is not _IND


def _b_format(ev, node, sc):
    vals = [_plain(x) for x in _args(ev, node, sc)]
    v = vals[0]
    fmt = vals[1] if len(vals) > 1 else ""
    if v is _IND or not _is_number(v):
        return _IND
    if type(fmt) is str and fmt:
        m = re.fullmatch(r"\s*([+-]?)(\d*)(?:\.(\d+))?\s*([IFE])\s*", fmt)
        if m:
            sign, width, prec, kind = m.groups()
            width = width or ""
            spec = ("+" if sign == "+" else "") + width
            if kind == "I":
                return format(int(round(v)), spec + "d")
            spec += ("." + prec if prec else "") + ("f" if kind == "F" else "E")
            return format(float(v), spec)
    if type(v) is int:
        return str(v)
    return repr(float(v))


def _b_hibound(ev, node, sc):
    (v,) = _args(ev, node, sc, 1)
    v = _plain(v)
    if type(v) is not Agg:
        return _IND
    if v.kind == "array":
        return v.lo + len(v) - 1
    if v.bounds and v.bounds[1] is not None:
        return v.bounds[1]
    return _IND


def _b_lobound(ev, node, sc):
    (v,) = _args(ev, node, sc, 1)
    v = _plain(v)
    if type(v) is not Agg:
        return _IND
    if v.kind == "array":
        return v.lo
    if v.bounds and v.bounds[0] is not None:
        return v.bounds[0]
    return 0


def _b_hiindex(ev, node, sc):
    (v,) = _args(ev, node, sc, 1)
    v = _plain(v)
    if type(v) is not Agg:
        return _IND
    return v.lo + len(v) - 1 if v.kind == "array" else len(v)


def _b_loindex(ev, node, sc):
    (v,) = _args(ev, node, sc, 1)
    v = _plain(v)
    if type(v) is not Agg:
        return _IND
    return v.lo if v.kind == "array" else 1


def _b_length(ev, node, sc):
    (v,) = _args(ev, node, sc, 1)
    v = _plain(v)
    return len(v) if type(v) is str else _IND


def _b_nvl(ev, node, sc):
    v, sub = _args(ev, node, sc, 2)
    return sub if _plain(v) is _IND else v


def _b_odd(ev, node, sc):
    (v,) = _args(ev, node, sc, 1)
    v = _plain(v)
    if type(v) is not int:
        return _IND
    return v % 2 == 1


def _b_rolesof(ev, node, sc):
    (v,) = _args(ev, node, sc, 1)
    if type(v) is not Instance:
        return Agg("set", ()) if v is not _IND else _IND
    return Agg("set", sorted(ev.pop.roles_of(v.id)))


def _b_sizeof(ev, node, sc):
    (v,) = _args(ev, node, sc, 1)
    v = _plain(v)
    if type(v) is not Agg:
        return _IND
    return len(v)


def _b_typeof(ev, node, sc):
    (v,) = _args(ev, node, sc, 1)
    return ev._typeof(v)


def _b_usedin(ev, node, sc):
    t, r = _args(ev, node, sc, 2)
    r = _plain(r)
    if t is _IND or r is _IND:
        return _IND
    if type(t) is not Instance:
        return Agg("bag", ())
    return Agg("bag", ev.pop.usedin(t.id, r or None))


def _b_value(ev, node, sc):
    (v,) = _args(ev, node, sc, 1)
    v = _plain(v)
    if type(v) is not str:
        return _IND
    s = v.strip()
    try:
        if re.fullmatch(r"[+-]?\d+", s):
            return int(s)
        return float(s)
    except ValueError:
        return _IND


def _b_value_in(ev, node, sc):
    c, v = _args(ev, node, sc, 2)
    c = _plain(c)
    if c is _IND or v is _IND:
        return None
    if type(c) is not Agg:
        return None
    unknown = False
    for x in c:
        r = ev._value_eq(x, v, 0)
        if r:
            return True
        if r is None:
            unknown = True
    return None if unknown else False


def _b_value_unique(ev, node, sc):
    (c,) = _args(ev, node, sc, 1)
    c = _plain(c)
    if type(c) is not Agg:
        return None
    items = list(c)
    unknown = False
    for i in range(len(items)):
        for j in range(i + 1, len(items)):
            r = ev._value_eq(items[i], items[j], 0)
            if r:
                return False
            if r is None:
                unknown = True
    return None if unknown else True


def _log(x):
    return math.log(x) if x > 0 else None


def _log2(x):
    return math.log2(x) if x > 0 else None


def _log10(x):
    return math.log10(x) if x > 0 else None


def _sqrt(x):
    return math.sqrt(x) if x >= 0 else None


def _asin(x):
    return math.asin(x) if -1 <= x <= 1 else None


def _acos(x):
    return math.acos(x) if -1 <= x <= 1 else None


_BUILTINS = {
    "abs": _num1(abs), "acos": _num1(_acos), "asin": _num1(_asin), "atan": _b_atan,
    "blength": _b_blength, "cos": _num1(math.cos), "exists": _b_exists, "exp": _num1(math.exp),
    "format": _b_format, "hibound": _b_hibound, "hiindex": _b_hiindex, "length": _b_length,
    "lobound": _b_lobound, "loindex": _b_loindex, "log": _num1(_log), "log2": _num1(_log2),
    "log10": _num1(_log10), "nvl": _b_nvl, "odd": _b_odd, "rolesof": _b_rolesof,
    "sin": _num1(math.sin), "sizeof": _b_sizeof, "sqrt": _num1(_sqrt), "tan": _num1(math.tan),
    "typeof": _b_typeof, "usedin": _b_usedin, "value": _b_value, "value_in": _b_value_in,
    "value_unique": _b_value_unique,
}
