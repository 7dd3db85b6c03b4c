"""Walking values of the JSON model (see docs/json-model.md)."""

from __future__ import annotations


def ref_id(value):
    """The instance id of a reference value ``{"ref": n}``, else None (one rule for every
    reader of the model: entity references are the only dicts with an int "ref")."""
    if type(value) is dict:
        r = value.get("ref")
        if type(r) is int:
            return r
    return None


def refs_in(value, out: list | None = None) -> list:
    """Append every referenced instance id in ``value`` to ``out``, in written order.

    Iterative, so deeply nested values cannot exhaust the stack; typed
    parameters are looked into.
    """
    if out is None:
        out = []
    stack = [value]
    while stack:
        v = stack.pop()
        t = type(v)
        if t is list:
            stack.extend(reversed(v))
        elif t is dict:
            r = v.get("ref")
            if r is not None:
                out.append(r)
            elif "value" in v:
                stack.append(v["value"])
    return out


def record_refs(record: dict) -> list:
    """Every id referenced by an instance record (simple or complex), in written order."""
    out: list = []
    for part in record.get("complex", (record,)):
        refs_in(part["args"], out)
    return out
