"""Evaluator values: the types EXPRESS values take in Python, and helpers on them.

``int``, ``float``, ``str``; ``True``/``False``/``None`` for TRUE/FALSE/
UNKNOWN; ``INDETERMINATE`` for ``?``; ``Agg`` for aggregates; ``Instance``
(``schema/instance.py``) for instances of the population; ``EntityValue``,
``EnumValue``, ``TypedValue``, ``BinaryValue`` and ``TypeRef`` below.
Three-valued logic, copies, type names and LIKE patterns live
here too.
"""

from __future__ import annotations

import re

from ..instance import Instance
from ..model import Literal


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


def _copy(v):
    if type(v) is Agg:
        if Agg in set(map(type, v)):
            return Agg(v.kind, [_copy(x) for x in v], v.lo, v.dtypes, v.bounds)
        return Agg(v.kind, v, v.lo, v.dtypes, v.bounds)  # flat: the list's own copy
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
