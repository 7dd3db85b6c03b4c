"""Driven pair values: ``solve --values FILE``, ``--set`` and ``--sweep`` into driven columns.

``--values`` files
    CSV: a header naming the driven pairs (``name`` for a one-value pair,
    ``name[0]``, ``name[1]``... for the values of a multi-valued pair) and an
    optional ``t`` column; one configuration per row. JSON Lines instead
    (sniffed from a leading ``{``): ``{"t": t, "pairs": {name: value or [values]}}``
    per line. Values are SI (metres) and radians unless units are given.

:func:`driven_columns` applies the rules of driving a mechanism: the pairs and
value indices must exist, a multi-valued pair is driven by its values one by
one, no angle beyond :data:`MAX_TURNS` turns, and with nothing given the
actuated pairs hold their initial values. Errors are :class:`FormatError` naming
``source:line:column`` (or the option) and the pair.
"""

from __future__ import annotations

import io
import math
import re

import numpy as np

from .text import FormatError, csv_rows, jsonl_records, number

__all__ = ["FormatError", "LENGTH_UNITS", "ANGLE_UNITS", "MAX_TURNS", "read_values", "parse_set", "parse_sweep",
           "angle_checker", "key_label", "driven_columns"]

#: SI factor of each accepted unit name.
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3}
ANGLE_UNITS = {"rad": 1.0, "deg": math.pi / 180.0}

#: Driven angles beyond this many turns are refused (double precision keeps ~1e-9 rad there).
MAX_TURNS = 1e6

_COLUMN = re.compile(r"^(?P<name>.*?)(?:\[(?P<j>\d+)\])?$")


def _column_key(label: str):
    m = _COLUMN.match(label.strip())
    name, j = m.group("name").strip(), m.group("j")
    return (name, int(j)) if j is not None else name


def key_label(key) -> str:
    """``name`` or ``name[j]``, as the user writes a driven column."""
    return f"{key[0]}[{key[1]}]" if isinstance(key, tuple) else key


def _fast_table(text: str):
    """``(values (N, k), end of the header line)`` of a plain numeric CSV table read by
    numpy's C parser, or None when anything is unusual (quotes, comments after the header,
    a cell that is not a finite number, ragged rows): then the careful parser runs and
    names the LINE:COL at fault. Both parse numbers with correct rounding."""
    pos = 0
    while True:  # the header: the first line that is neither blank nor a comment
        end = text.find("\n", pos)
        line = text[pos:] if end < 0 else text[pos:end]
        if line.strip() and not line.lstrip().startswith("#"):
            break
        if end < 0:
            return None
        pos = end + 1
    if end < 0:
        return None
    body = text[end + 1:]
    if '"' in body or "#" in body or not body.strip():
        return None
    try:
        arr = np.loadtxt(io.StringIO(body), delimiter=",", ndmin=2, dtype=np.float64)
    except ValueError:
        return None
    if arr.size == 0 or not np.all(np.isfinite(arr)):
        return None
    return arr, end + 1


def read_values(text: str, source: str, *, length=1.0, angle=1.0, is_angle=None):
    """Driven values from CSV or JSON Lines text.

    Returns ``(t, columns)``: ``t`` an (N,) array or None, ``columns`` a dict
    ``{name or (name, j): (N,) array}`` in SI. ``is_angle(key) -> bool`` says
    which columns are angles (converted with ``angle``; the others with
    ``length``); without it every value is taken as given.
    """
    if text.lstrip().startswith("{"):
        return _values_jsonl(text, source, length=length, angle=angle, is_angle=is_angle)
    arr = _fast_table(text)
    rows = csv_rows(text if arr is None else text[:arr[1]])
    if not rows:
        raise FormatError(f"{source}:1:1: no header line (expected the driven pair names)")
    hline, header = rows[0]
    keys, tcol = [], None
    for i, (col, label) in enumerate(header):
        if label.strip() == "t":
            if tcol is not None:
                raise FormatError(f"{source}:{hline}:{col}: a second 't' column")
            tcol = i
            keys.append(None)
            continue
        if not label.strip():
            raise FormatError(f"{source}:{hline}:{col}: empty column name")
        key = _column_key(label)
        if key in keys:
            raise FormatError(f"{source}:{hline}:{col}: column {label.strip()!r} given twice")
        keys.append(key)
    if all(k is None for k in keys):
        raise FormatError(f"{source}:{hline}:1: no pair column in the header")
    if arr is not None and arr[0].shape[1] == len(keys):
        arr = arr[0]
    else:  # the careful path: every cell checked, errors at LINE:COL
        rows = rows if arr is None else csv_rows(text)
        data = []
        for line, cells in rows[1:]:
            if len(cells) != len(keys):
                raise FormatError(f"{source}:{line}:1: {len(cells)} fields, the header has {len(keys)}")
            data.append([number(cell, f"{source}:{line}:{col}") for col, cell in cells])
        if not data:
            raise FormatError(f"{source}:{hline + 1}:1: no configuration after the header")
        arr = np.array(data, dtype=np.float64)
    t = arr[:, tcol] if tcol is not None else None
    cols = {}
    for i, key in enumerate(keys):
        if key is None:
            continue
        f = 1.0 if is_angle is None else (angle if is_angle(key) else length)
        cols[key] = arr[:, i] * f
    return t, cols


def _values_jsonl(text, source, *, length, angle, is_angle):
    ts, recs = [], []
    for n, rec in jsonl_records(text, source, comments=False):
        if not isinstance(rec, dict) or not isinstance(rec.get("pairs"), dict):
            raise FormatError(f"{source}:{n}:1: expected {{\"t\": ..., \"pairs\": {{name: value}}}}")
        ts.append(rec.get("t"))
        recs.append((n, rec["pairs"]))
    if not recs:
        raise FormatError(f"{source}:1:1: no configuration")
    names = list(recs[0][1])
    cols = {}
    for n, pairs in recs:
        if list(pairs) != names:
            raise FormatError(f"{source}:{n}:1: every line must name the same pairs as line {recs[0][0]}")
        for name, v in pairs.items():
            vals = v if isinstance(v, list) else [v]
            for j, x in enumerate(vals):
                if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
                    raise FormatError(f"{source}:{n}:1: pair {name!r}: {x!r} is not a finite number")
                key = (name, j) if isinstance(v, list) else name
                cols.setdefault(key, []).append(float(x))
    out = {}
    for key, vals in cols.items():
        if len(vals) != len(recs):
            raise FormatError(f"{source}: pair {key!r}: the number of values changes between lines")
        f = 1.0 if is_angle is None else (angle if is_angle(key) else length)
        out[key] = np.array(vals) * f
    t = None
    if any(x is not None for x in ts):
        if not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in ts):
            raise FormatError(f"{source}: 't' must be a number on every line or on none")
        t = np.array(ts, dtype=np.float64)
    return t, out


def parse_set(items, *, length=1.0, angle=1.0, is_angle=None) -> dict:
    """``--set PAIR=VALUE`` (or ``PAIR=V1,V2,...``, ``PAIR[j]=V``) as a dict of SI values."""
    out = {}
    for item in items:
        if "=" not in item:
            raise FormatError(f"--set {item!r}: expected PAIR=VALUE")
        label, text = item.rsplit("=", 1)
        key = _column_key(label)
        parts = text.split(",")
        vals = [number(p, f"--set {item!r}") for p in parts]
        if len(vals) == 1:
            f = 1.0 if is_angle is None else (angle if is_angle(key) else length)
            out[key] = vals[0] * f
        else:
            if isinstance(key, tuple):
                raise FormatError(f"--set {item!r}: one value for {label.strip()}")
            for j, v in enumerate(vals):
                k = (key, j)
                f = 1.0 if is_angle is None else (angle if is_angle(k) else length)
                out[k] = v * f
    return out


def parse_sweep(items, *, length=1.0, angle=1.0, is_angle=None, max_count=100_000_000) -> dict:
    """``--sweep PAIR=START:STOP:COUNT`` as ``{key: (COUNT,) SI values}`` (all the same COUNT)."""
    out, count = {}, None
    for item in items:
        if "=" not in item or item.rsplit("=", 1)[1].count(":") != 2:
            raise FormatError(f"--sweep {item!r}: expected PAIR=START:STOP:COUNT")
        label, text = item.rsplit("=", 1)
        a, b, n = text.split(":")
        start, stop = number(a, f"--sweep {item!r}"), number(b, f"--sweep {item!r}")
        try:
            n = int(n)
        except ValueError:
            raise FormatError(f"--sweep {item!r}: COUNT must be a whole number") from None
        if not 1 <= n <= max_count:
            raise FormatError(f"--sweep {item!r}: COUNT must be between 1 and {max_count}")
        if count is not None and n != count:
            raise FormatError(f"--sweep {item!r}: every --sweep needs the same COUNT ({count})")
        count = n
        key = _column_key(label)
        f = 1.0 if is_angle is None else (angle if is_angle(key) else length)
        out[key] = np.linspace(start, stop, n) * f
    return out


def angle_checker(mech):
    """``is_angle(key)`` for the driven columns of ``mech``: True for an angle, False for a
    length; a FormatError for a pair or value index the mechanism does not have."""
    def is_angle(key):
        name, j = key if isinstance(key, tuple) else (key, 0)
        try:
            p = mech.pair(name)
        except KeyError:
            raise FormatError(f"{name!r} is not a pair of mechanism {mech.name!r} "
                              f"(pairs: {', '.join(mech.pair_names)})") from None
        mask = p.type.angle_mask
        if j >= len(mask):
            raise FormatError(f"pair {name!r} has {len(mask)} value(s); {key_label(key)} does not exist")
        return mask[j] if isinstance(key, tuple) or len(mask) == 1 else mask[0]
    return is_angle


def driven_columns(mech, values=None, sets=(), sweeps=(), *, length=1.0, angle=1.0):
    """``(t or None, {pair or (pair, j): (N,) or (N, k) SI values}, notes)`` from a --values
    file (``(text, source)`` or None), --sweep and --set items, in the given units.

    Without any of them: the actuated pairs at their initial values, one configuration.
    ``notes`` are remarks for the user (a driven pair without actuator)."""
    is_angle = angle_checker(mech)
    t, cols = _columns(values, sets, sweeps, length, angle, is_angle)
    driven = {}
    for key, v in cols.items():
        driven[_driven_key(mech, key, v, is_angle)] = v
    if not driven:
        q0 = mech.initial_vector()
        return t, {p.name: q0[None, mech.value_slices[p.name]] for p in mech.pairs if p.actuated}, []
    named = {k[0] if isinstance(k, tuple) else k for k in driven}
    actuators = any(q.actuated for q in mech.pairs)
    notes = [f"pair {p.name!r} is driven but has no actuator in the model"
             for p in mech.pairs if p.name in named and not p.actuated and actuators]
    return t, driven, notes


def _columns(values, sets, sweeps, length, angle, is_angle):
    """``(t, {key: (N,) SI})``: --values or --sweep, and --set held in every configuration."""
    t, cols = None, {}
    if values is not None:
        text, source = values
        t, cols = read_values(text, source, length=length, angle=angle, is_angle=is_angle)
    elif sweeps:
        cols = parse_sweep(sweeps, length=length, angle=angle, is_angle=is_angle)
    fixed = parse_set(sets, length=length, angle=angle, is_angle=is_angle)
    n = len(next(iter(cols.values()))) if cols else 1
    for key, v in fixed.items():
        if key in cols:
            raise FormatError(f"--set {key_label(key)}: the pair is in --values too")
        cols[key] = np.full(n, v)
    return t, cols


def _driven_key(mech, key, v, is_angle):
    """The key a driven column has for the solver (``name[0]`` of a one-value pair is ``name``);
    a FormatError for an angle beyond :data:`MAX_TURNS` or a multi-valued pair driven as one."""
    from p105cli.part105.model_file import MAX_MAGNITUDE
    # the bound of every number a mechanism is read with (fuzz: a slider driven to 1e300 overflowed
    # the contact point of a cam in the loop closure, exit 3)
    if np.size(v) and not float(np.max(np.abs(v))) <= MAX_MAGNITUDE:
        raise FormatError(f"{key_label(key)}: {float(np.max(np.abs(v))):.3g} is beyond the magnitudes p105 "
                          f"computes with ({MAX_MAGNITUDE:g})")
    # an angle of a million turns has no digits left for its position within the turn
    if is_angle(key) and np.size(v) and float(np.max(np.abs(v))) > MAX_TURNS * 2.0 * math.pi:
        raise FormatError(f"{key_label(key)}: an angle of {float(np.max(np.abs(v))):.3g} rad is more than "
                          f"{MAX_TURNS:.0e} turns: its position within a turn is lost to rounding")
    if not isinstance(key, tuple) and mech.pair(key).value_count > 1:
        raise FormatError(f"pair {key!r} has {mech.pair(key).value_count} values: name them "
                          f"{key}[0], {key}[1], ...")
    if isinstance(key, tuple) and mech.pair(key[0]).value_count == 1 and key[1] == 0:
        return key[0]
    return key
