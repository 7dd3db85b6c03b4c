"""Calls of functions, procedures and entity constructors, and the
execution of statements.
"""

from __future__ import annotations

from ..instance import Instance
from ..model import AttributeRef, Function, GroupRef, IndexRef, Name, Procedure
from .builtins import _BUILTINS
from .scope import MAX_STEPS, _Alias, _ESCAPE, _MISSING, _Return, _SKIP, _Scope
from .values import (
    Agg, EntityValue, EnumValue, NotEvaluable, TypedValue, _IND, _Indeterminate, _copy, _is_number,
    _l3, _plain,
)


MEMO_MAX_AGGREGATE = 1000


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


class Algorithms:
    """Calls of algorithms and constructors, and statements (an ``Evaluator`` mixin)."""

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
        typed = self.compiled.type_only_parameters(f)
        keys = []
        for i, a in enumerate(args):
            if type(a) is Agg and len(a) > MEMO_MAX_AGGREGATE:
                return None  # a whole extent: its key would cost as much as the call
            if not _memo_safe(a):
                return None
            if i in typed and type(a) is Instance:
                keys.append(("types", a.types))  # the body sees no more than its types
            else:
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
        if type(f) is Function:
            v = self._native_call(f, args)
            if v is not _MISSING:
                return v
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
