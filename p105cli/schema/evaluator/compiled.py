"""Facts about a schema's rule and function bodies, worked out once per schema and kept
with it: which values an expression looks at only through their type.

A FUNCTION parameter is *type-only* when the body uses it nowhere but as the argument of
TYPEOF or EXISTS, or as a type-only argument of another function (``type_check_function
(the_type, names, criterion)`` of the long forms). A QUERY is type-only when its condition
uses its variable that way. For a population instance such a use sees no more than the
instance's set of types, so

* a call is memoised on the instance's types, not on its id (one evaluation per type
  combination, not per instance), and
* one evaluation of a QUERY over an extent evaluates its condition once per type
  combination among the elements (the rest of the condition is fixed during the QUERY:
  EXPRESS expressions have no side effects).

``subtype_exclusiveness_representation_item`` runs ``type_check_function`` on every
representation item of the file: 300,000 interpreted calls on a 20 MB assembly, a few
dozen this way. The analysis is conservative: any other use of the name (shadowed or
not) makes it not type-only.
"""

from __future__ import annotations

import weakref
from dataclasses import fields

from ..model import Call, Function, Name, Node, Query

_TYPE_BUILTINS = ("typeof", "exists")


class Compiled:
    """The type-only facts of one schema (see the module docstring)."""

    def __init__(self, schema):
        self._schema = weakref.ref(schema)  # the cache must not keep its schema alive
        self._params: dict = {}  # function name -> frozenset of type-only parameter indices
        self._queries: dict = {}  # id(Query node) -> bool

    def type_only_parameters(self, f: Function) -> frozenset:
        """Indices of the type-only parameters of ``f`` (a FUNCTION of this schema)."""
        got = self._params.get(f.name)
        if got is None:
            self._params[f.name] = frozenset()  # a recursive call assumes nothing
            got = frozenset()
            if not f.declarations and self._schema().functions.get(f.name) is f:
                body = (*f.body, *(c.value for c in f.constants),
                        *(lv.init for lv in f.locals if lv.init is not None))
                got = frozenset(i for i, p in enumerate(f.parameters)
                                if not p.var and self._only_typed(p.name, body, None))
            self._params[f.name] = got
        return got

    def query_type_only(self, node: Query, algos) -> bool:
        """Whether ``node``'s condition sees its variable only through its type."""
        key = id(node)
        got = self._queries.get(key)
        if got is None:
            got = self._queries[key] = self._only_typed(node.variable, (node.condition,), algos)
        return got

    def _only_typed(self, name: str, roots, algos) -> bool:
        stack = list(roots)
        while stack:
            n = stack.pop()
            if type(n) is Name:
                if n.name == name:
                    return False
                continue
            if type(n) is Call:
                typed = self._typed_positions(n, algos)
                for i, a in enumerate(n.args):
                    if i in typed and type(a) is Name and a.name == name:
                        continue
                    stack.append(a)
                continue
            if isinstance(n, Node):
                stack.extend(getattr(n, f.name) for f in fields(n))
            elif type(n) in (list, tuple):
                stack.extend(n)
        return True

    def _typed_positions(self, call: Call, algos):
        name = call.name
        if algos and name in algos:
            return ()  # a nested declaration: not analysed
        schema = self._schema()
        f = schema.functions.get(name)
        if f is not None:
            return self.type_only_parameters(f)
        if name in _TYPE_BUILTINS and len(call.args) == 1 and name not in schema.entities:
            return (0,)
        return ()


_COMPILED: dict = {}


def compiled_for(schema) -> Compiled:
    """The cached Compiled of ``schema`` (kept as long as the schema lives)."""
    key = id(schema)
    entry = _COMPILED.get(key)
    if entry is not None and entry[0]() is schema:
        return entry[1]
    c = Compiled(schema)
    _COMPILED[key] = (weakref.ref(schema, lambda _r, k=key, d=_COMPILED: d.pop(k, None)), c)
    return c
