"""Evaluation of expression nodes: literals, names, unary and binary
operators (dispatching to ``operators``), and references (attributes,
groups, indexes, aggregate initialisers, QUERY).
"""

from __future__ import annotations

import math

from ..instance import Instance
from ..model import Call, GroupRef, SelfRef, TypeDecl
from .scope import _Alias, _MISSING, _Scope
from .values import (
    Agg, BinaryValue, EntityValue, EnumValue, NotEvaluable, TypeRef, _CMP_OPS, _IND, _and3, _copy,
    _is_entity, _is_ind_literal, _is_number, _l3, _or3, _plain, _tname,
)


class Expressions:
    """The evaluation of expression nodes and references (an ``Evaluator`` mixin)."""

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
        cond = node.condition
        out = []
        if self.memoize and len(agg) > 1 and self.compiled.query_type_only(node, sc.algos):
            by_types: dict = {}  # the condition sees an instance's types only (compiled.py)
            for x in agg:
                if type(x) is Instance:
                    keep = by_types.get(x.types)
                    if keep is None:
                        inner.vars[var] = x
                        keep = by_types[x.types] = _l3(self.ev(cond, inner)) is True
                else:
                    inner.vars[var] = x
                    keep = _l3(self.ev(cond, inner)) is True
                if keep:
                    out.append(x)
        else:
            for x in agg:
                inner.vars[var] = x
                if _l3(self.ev(cond, inner)) is True:
                    out.append(x)
        return Agg(agg.kind if agg.kind != "array" else "list", out)
