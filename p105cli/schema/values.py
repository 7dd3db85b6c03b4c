"""Typed-value readers: the one reading of an attribute value as a number, enumeration,
logical, reference, list or unlimited limit.

Values are what :meth:`p105cli.schema.population.Instance.get` returns: Python numbers,
strings, lists, ``{"ref": id}``, ``{"enum": "T"}``, typed values ``{"type": "LENGTH_MEASURE",
"value": 2.0}`` (possibly nested: a select of a defined type of a measure), ``None`` for
``$``, ``{"derived": True}`` for ``*``.

One behaviour, everywhere: these readers are lenient. They unwrap every level of typed
value and return ``None`` (or ``False``) when the value is not of the kind asked for; they
never raise. A caller that needs the value says so itself, with its own message naming the
instance and attribute (``part105.model_file.ModelFile`` does that for the model readers).
Booleans are not numbers here (``True`` is no REAL).
"""

from __future__ import annotations

from typing import Optional

from ..step.values import ref_id

__all__ = ["untyped", "number", "numbers", "enum", "is_true", "is_false", "is_unlimited", "ref", "refs"]

#: The id a reference value ``{"ref": id}`` names, else None (step.values' one reading).
ref = ref_id


def untyped(v):
    """``v`` without its typed-value wrappers (``LENGTH_MEASURE(2.)`` -> 2.0), every level."""
    while type(v) is dict and "type" in v and "value" in v:
        v = v["value"]
    return v


def number(v) -> Optional[float]:
    """A REAL/INTEGER value (typed or not) as a float, else None."""
    v = untyped(v)
    if type(v) in (int, float):
        return float(v)
    return None


def numbers(v) -> Optional[list]:
    """A list of REAL/INTEGER values as floats; None if ``v`` is no list or one item is no number."""
    v = untyped(v)
    if type(v) is not list:
        return None
    out = [number(x) for x in v]
    return None if None in out else out


def enum(v) -> Optional[str]:
    """An enumeration value's name in upper case (``.T.`` -> ``"T"``), else None."""
    v = untyped(v)
    if type(v) is dict and "enum" in v:
        return str(v["enum"]).upper()
    return None


def is_true(v) -> bool:
    """``.T.`` (or a Python True)."""
    v = untyped(v)
    return v is True or enum(v) == "T"


def is_false(v) -> bool:
    """``.F.`` (or a Python False)."""
    v = untyped(v)
    return v is False or enum(v) == "F"


def is_unlimited(v) -> bool:
    """``$`` (AP242's OPTIONAL limit) or ``UNLIMITED_RANGE(.UNLIMITED.)`` (1996)."""
    if v is None:
        return True
    if type(v) is dict and str(v.get("type", "")).upper() == "UNLIMITED_RANGE":
        return True
    return enum(v) == "UNLIMITED"


def refs(v) -> list:
    """The ids of the references in an aggregate value, in order (non-references skipped)."""
    v = untyped(v)
    if type(v) is not list:
        return []
    out = []
    for x in v:
        r = ref_id(x)
        if r is not None:
            out.append(r)
    return out
