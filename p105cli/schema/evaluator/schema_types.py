"""What the schema says about types: type descriptions, the conversion
of raw Part 21 values to evaluator values, coercion on assignment, and
TYPEOF.
"""

from __future__ import annotations

from ..instance import Instance
from ..model import AggregateType, EnumerationType, Literal, NamedType, SelectType, SimpleType
from .scope import _Scope

_ONLY_INSTANCES = {Instance}
from .values import (
    Agg, BinaryValue, EntityValue, EnumValue, NotEvaluable, TypedValue, _IND, _LOGICAL_ITEMS,
    _bits_of_p21_binary, _copy, _plain, _simple_names,
)


class SchemaTypes:
    """Type descriptions, raw -> value conversion, coercion and TYPEOF (an ``Evaluator`` mixin)."""

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
        if items and set(map(type, items)) == _ONLY_INSTANCES and len(set(map(id, items))) == len(items):
            # distinct population instances (instance equality is identity; a copy of an
            # instance is itself): nothing to drop, found without a Python loop, since
            # `result := result + x` in a REPEAT dedupes the whole set on every assignment
            return list(items)
        out = []
        seen = set()
        for x in items:
            k = self._ikey(x)
            if k in seen:
                continue
            seen.add(k)
            out.append(_copy(x))
        return out

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
