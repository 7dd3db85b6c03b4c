"""The operators of EXPRESS: comparisons (value and instance equality,
IN, LIKE, subset) and arithmetic (numbers, strings, aggregates, ``||``).
"""

from __future__ import annotations

from ..instance import Instance
from ..model import EnumerationType
from .values import (
    Agg, BinaryValue, EntityValue, EnumValue, NotEvaluable, TypedValue, _IND, _LOGICAL_ORDER,
    _copy, _is_entity, _is_number, _like_regex, _plain, _tname, _union_kind,
)


class Operators:
    """Comparisons and arithmetic (an ``Evaluator`` mixin)."""

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
            # instance equality of entities is identity (neither Instance nor EntityValue
            # defines __eq__, and no other value equals one): the list's own search
            return e in agg
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
            drop = _entity_counts(b if tb is Agg else [b])
            if drop is not None:  # entities only: remove the first occurrences by identity
                out = []
                for y in a:
                    n = drop.get(id(y))
                    if n:
                        drop[id(y)] = n - 1
                    else:
                        out.append(y)
                return Agg(a.kind, out)
            drop = _string_counts(b if tb is Agg else [b], a)
            if drop is not None:  # strings only: remove the first occurrences by value
                out = []
                for y in a:
                    n = drop.get(y)
                    if n:
                        drop[y] = n - 1
                    else:
                        out.append(y)
                return Agg(a.kind, out)
            out = list(a)
            for x in (b if tb is Agg else [b]):
                for j, y in enumerate(out):
                    if self._inst_eq(x, y):
                        del out[j]
                        break
            return Agg(a.kind, out)
        if op == "*":
            if ta is Agg and tb is Agg:
                kind = "set" if "set" in (a.kind, b.kind) else "bag"
                left = _entity_counts(a)
                have = _entity_counts(b) if left is not None else None
                if have is not None:  # entities only: match occurrences by identity
                    out = []
                    for x in a:
                        n = have.get(id(x))
                        if n:
                            have[id(x)] = n - 1
                            out.append(x)
                    return Agg(kind, self._dedupe(out) if kind == "set" else out)
                have = _string_counts(b, a)
                if have is not None:  # strings only: match occurrences by value
                    out = []
                    for x in a:
                        n = have.get(x)
                        if n:
                            have[x] = n - 1
                            out.append(x)
                    return Agg(kind, self._dedupe(out) if kind == "set" else out)
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


def _string_counts(items, other):
    """{string: occurrences} of ``items`` when every element of ``items`` and ``other`` is a
    plain string (instance equality of strings is Python's ``==``: TYPEOF sets against the
    long forms' lists of type names), else None."""
    counts: dict = {}
    for x in items:
        if type(x) is not str:
            return None
        counts[x] = counts.get(x, 0) + 1
    for y in other:
        if type(y) is not str:
            return None
    return counts


def _entity_counts(items):
    """{id: occurrences} of ``items`` when every one is an entity (instance equality is then
    identity), else None."""
    counts: dict = {}
    for x in items:
        if not _is_entity(x):
            return None
        counts[id(x)] = counts.get(id(x), 0) + 1
    return counts
