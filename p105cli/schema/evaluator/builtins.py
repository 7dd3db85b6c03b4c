"""The built-in functions of EXPRESS: each takes (evaluator, call node, scope).
"""

from __future__ import annotations

import math
import re

from ..instance import Instance
from .values import Agg, BinaryValue, NotEvaluable, _IND, _is_number, _plain


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
    return hiindex(v)


def hiindex(v):
    """HIINDEX of a value: ``?`` for anything but an aggregate."""
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
