"""Scopes of evaluation, control-flow signals and the evaluator's limits.
"""

from __future__ import annotations

from .values import _IND


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
