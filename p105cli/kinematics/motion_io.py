"""Readers of motion input for ``p105 solve``: driven pair values and target poses.

Pure I/O and unit conversion, no click. Errors are :class:`MotionInputError`
with ``source:line:column`` in the message.

Driven values (``--values``)
    CSV: a header naming the driven pairs (``name`` for a one-value pair,
    ``name[0]``, ``name[1]``... for the values of a multi-valued pair) and an
    optional ``t`` column; one configuration per row. JSON Lines instead
    (sniffed from a leading ``{``): ``{"t": t, "pairs": {name: value or [values]}}``
    per line. Values are SI (metres) and radians unless units are given.

Target poses (``--path``)
    JSON Lines ``{"t": t, "pose": 4x4}`` (rows of the matrix), or CSV with
    columns ``t,m00,m01,m02,m03,m10,...,m23`` (the last row is implied) or all
    16 entries. Lengths in metres unless a length factor is given.
"""

from __future__ import annotations

import csv
import io
import json
import math
import re

import numpy as np

__all__ = ["MotionInputError", "read_values", "read_poses", "parse_set", "parse_sweep", "LENGTH_UNITS", "ANGLE_UNITS"]

#: SI factor of each accepted unit name.
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3}
ANGLE_UNITS = {"rad": 1.0, "deg": math.pi / 180.0}

_COLUMN = re.compile(r"^(?P<name>.*?)(?:\[(?P<j>\d+)\])?$")


class MotionInputError(ValueError):
    """Malformed motion input; the message names ``source:line:column``."""


def _column_key(label: str):
    m = _COLUMN.match(label.strip())
    name, j = m.group("name").strip(), m.group("j")
    return (name, int(j)) if j is not None else name


def _number(text: str, where: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise MotionInputError(f"{where}: {text.strip()!r} is not a number") from None
    if not math.isfinite(v):
        raise MotionInputError(f"{where}: {text.strip()!r} is not a finite number")
    return v


def _csv_rows(text: str):
    """(line number, [(column, cell)]) of the non-empty CSV rows."""
    reader = csv.reader(io.StringIO(text))
    out = []
    for row in reader:
        line = reader.line_num
        if not row or all(not c.strip() for c in row) or row[0].lstrip().startswith("#"):
            continue
        cols, col = [], 1
        for cell in row:
            cols.append((col, cell))
            col += len(cell) + 1
        out.append((line, cols))
    return out


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
    rows = _csv_rows(text if arr is None else text[:arr[1]])
    if not rows:
        raise MotionInputError(f"{source}:1:1: no header line (expected the driven pair names)")
    hline, header = rows[0]
    keys, tcol = [], None
    for i, (col, label) in enumerate(header):
        if label.strip() == "t":
            if tcol is not None:
                raise MotionInputError(f"{source}:{hline}:{col}: a second 't' column")
            tcol = i
            keys.append(None)
            continue
        if not label.strip():
            raise MotionInputError(f"{source}:{hline}:{col}: empty column name")
        key = _column_key(label)
        if key in keys:
            raise MotionInputError(f"{source}:{hline}:{col}: column {label.strip()!r} given twice")
        keys.append(key)
    if all(k is None for k in keys):
        raise MotionInputError(f"{source}:{hline}:1: no pair column in the header")
    if arr is not None and arr[0].shape[1] == len(keys):
        arr = arr[0]
    else:  # the careful path: every cell checked, errors at LINE:COL
        rows = rows if arr is None else _csv_rows(text)
        data = []
        for line, cells in rows[1:]:
            if len(cells) != len(keys):
                raise MotionInputError(f"{source}:{line}:1: {len(cells)} fields, the header has {len(keys)}")
            data.append([_number(cell, f"{source}:{line}:{col}") for col, cell in cells])
        if not data:
            raise MotionInputError(f"{source}:{hline + 1}:1: no configuration after the header")
        arr = np.array(data, dtype=np.float64)
    t = arr[:, tcol] if tcol is not None else None
    cols = {}
    for i, key in enumerate(keys):
        if key is None:
            continue
        f = 1.0 if is_angle is None else (angle if is_angle(key) else length)
        cols[key] = arr[:, i] * f
    return t, cols


def _jsonl_records(text, source):
    """(line number, record) of the non-blank lines of a JSON Lines text; errors at LINE:COL."""
    for n, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        try:
            yield n, json.loads(line)
        except json.JSONDecodeError as err:
            raise MotionInputError(f"{source}:{n}:{err.colno}: {err.msg}") from None


def _values_jsonl(text, source, *, length, angle, is_angle):
    ts, recs = [], []
    for n, rec in _jsonl_records(text, source):
        if not isinstance(rec, dict) or not isinstance(rec.get("pairs"), dict):
            raise MotionInputError(f"{source}:{n}:1: expected {{\"t\": ..., \"pairs\": {{name: value}}}}")
        ts.append(rec.get("t"))
        recs.append((n, rec["pairs"]))
    if not recs:
        raise MotionInputError(f"{source}:1:1: no configuration")
    names = list(recs[0][1])
    cols = {}
    for n, pairs in recs:
        if list(pairs) != names:
            raise MotionInputError(f"{source}:{n}:1: every line must name the same pairs as line {recs[0][0]}")
        for name, v in pairs.items():
            vals = v if isinstance(v, list) else [v]
            for j, x in enumerate(vals):
                if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
                    raise MotionInputError(f"{source}:{n}:1: pair {name!r}: {x!r} is not a finite number")
                key = (name, j) if isinstance(v, list) else name
                cols.setdefault(key, []).append(float(x))
    out = {}
    for key, vals in cols.items():
        if len(vals) != len(recs):
            raise MotionInputError(f"{source}: pair {key!r}: the number of values changes between lines")
        f = 1.0 if is_angle is None else (angle if is_angle(key) else length)
        out[key] = np.array(vals) * f
    t = None
    if any(x is not None for x in ts):
        if not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in ts):
            raise MotionInputError(f"{source}: 't' must be a number on every line or on none")
        t = np.array(ts, dtype=np.float64)
    return t, out


def parse_set(items, *, length=1.0, angle=1.0, is_angle=None) -> dict:
    """``--set PAIR=VALUE`` (or ``PAIR=V1,V2,...``, ``PAIR[j]=V``) as a dict of SI values."""
    out = {}
    for item in items:
        if "=" not in item:
            raise MotionInputError(f"--set {item!r}: expected PAIR=VALUE")
        label, text = item.rsplit("=", 1)
        key = _column_key(label)
        parts = text.split(",")
        vals = [_number(p, f"--set {item!r}") for p in parts]
        if len(vals) == 1:
            f = 1.0 if is_angle is None else (angle if is_angle(key) else length)
            out[key] = vals[0] * f
        else:
            if isinstance(key, tuple):
                raise MotionInputError(f"--set {item!r}: one value for {label.strip()}")
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
            raise MotionInputError(f"--sweep {item!r}: expected PAIR=START:STOP:COUNT")
        label, text = item.rsplit("=", 1)
        a, b, n = text.split(":")
        start, stop = _number(a, f"--sweep {item!r}"), _number(b, f"--sweep {item!r}")
        try:
            n = int(n)
        except ValueError:
            raise MotionInputError(f"--sweep {item!r}: COUNT must be a whole number") from None
        if not 1 <= n <= max_count:
            raise MotionInputError(f"--sweep {item!r}: COUNT must be between 1 and {max_count}")
        if count is not None and n != count:
            raise MotionInputError(f"--sweep {item!r}: every --sweep needs the same COUNT ({count})")
        count = n
        key = _column_key(label)
        f = 1.0 if is_angle is None else (angle if is_angle(key) else length)
        out[key] = np.linspace(start, stop, n) * f
    return out


def read_poses(text: str, source: str, *, length=1.0):
    """Target poses from JSON Lines or CSV: ``(t (N,) or None, poses (N, 4, 4))`` in metres."""
    if text.lstrip().startswith("{"):
        ts, poses = [], []
        for n, rec in _jsonl_records(text, source):
            T = rec.get("pose") if isinstance(rec, dict) else None
            try:
                T = np.array(T, dtype=np.float64)
            except (TypeError, ValueError):
                T = None
            if T is None or T.shape not in ((4, 4), (3, 4), (16,), (12,)):
                raise MotionInputError(f"{source}:{n}:1: expected {{\"t\": ..., \"pose\": 4x4 matrix}}")
            ts.append(rec.get("t"))
            poses.append(_as_pose(T, f"{source}:{n}:1"))
        if not poses:
            raise MotionInputError(f"{source}:1:1: no pose")
        t = np.array(ts, dtype=np.float64) if all(isinstance(x, (int, float)) for x in ts) else None
    else:
        rows = _csv_rows(text)
        if not rows:
            raise MotionInputError(f"{source}:1:1: no header line")
        hline, header = rows[0]
        labels = [c.strip() for _, c in header]
        m_labels = [x for x in labels if x != "t"]
        want12 = [f"m{i}{j}" for i in range(3) for j in range(4)]
        want16 = [f"m{i}{j}" for i in range(4) for j in range(4)]
        if m_labels not in (want12, want16):
            raise MotionInputError(f"{source}:{hline}:1: expected the columns t,m00,m01,...,m23 (or to m33)")
        tcol = labels.index("t") if "t" in labels else None
        idx = [labels.index(x) for x in m_labels]
        ts, poses = [], []
        for line, cells in rows[1:]:
            if len(cells) != len(labels):
                raise MotionInputError(f"{source}:{line}:1: {len(cells)} fields, the header has {len(labels)}")
            vals = [_number(cell, f"{source}:{line}:{col}") for col, cell in cells]
            if tcol is not None:
                ts.append(vals[tcol])
            poses.append(_as_pose(np.array([vals[i] for i in idx]), f"{source}:{line}:1"))
        if not poses:
            raise MotionInputError(f"{source}:{hline + 1}:1: no pose after the header")
        t = np.array(ts) if tcol is not None else None
    P = np.array(poses)
    P[:, :3, 3] *= length
    return t, P


def _as_pose(T, where) -> np.ndarray:
    T = np.asarray(T, dtype=np.float64)
    if T.size in (12, 16):
        T = T.reshape(-1, 4)
    if T.shape[0] == 3:
        T = np.vstack([T, [0.0, 0.0, 0.0, 1.0]])
    if not np.all(np.isfinite(T)):
        raise MotionInputError(f"{where}: the pose has a value that is not a finite number")
    R = T[:3, :3]
    if np.abs(R.T @ R - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0 or np.abs(T[3] - [0, 0, 0, 1]).max() > 0:
        raise MotionInputError(f"{where}: the pose is not a rigid placement (rotation not orthonormal "
                               "to 1e-6, or last row not 0 0 0 1)")
    # Re-orthonormalise so round-off in the file does not become a pose error.
    U, _, Vt = np.linalg.svd(R)
    T = T.copy()
    T[:3, :3] = U @ Vt
    return T
