"""Denavit-Hartenberg tables as files: CSV and JSON, read and written.

CSV: a header ``name,type,a,alpha,d,theta,offset`` (any order; optional
``lower,upper`` columns limit q), one joint per line; JSON: ``{"convention",
"joints": [...], "base"?: 4x4, "tool"?: 4x4, "name"?, "angle_unit"?}``. Numbers
may be ``pi``, ``k*pi/m``. The table itself and its maths (Annex F) are
:mod:`p105cli.kinematics.dh`. Errors are :class:`DHTableError` naming
``FILE:LINE:COL`` or ``FILE:/json/pointer``.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np

from p105cli.kinematics.dh import (
    COLUMNS, CONVENTIONS, DEG, JOINT_TYPES, OPTIONAL_COLUMNS, DHJoint, DHTable,
)

__all__ = ["DHTableError", "looks_like_dh", "read_csv", "read_json", "write_csv", "write_json", "is_identity",
           "COLUMNS"]

_PI = math.pi
#: The joint type a table may spell, and its letter.
_TYPE_NAMES = {"r": "R", "revolute": "R", "p": "P", "prismatic": "P"}


class DHTableError(ValueError):
    """A DH table that cannot be read; ``str()`` says where (``FILE:LINE:COL`` or ``FILE:/pointer``)."""

    def __init__(self, message: str, source: str = "<input>", line: int = 0, column: int = 0,
                 pointer: str = ""):
        super().__init__(message)
        self.message, self.source, self.line, self.column, self.pointer = message, source, line, column, pointer

    def __str__(self) -> str:
        if self.line:
            return f"{self.source}:{self.line}:{max(self.column, 1)}: {self.message}"
        if self.pointer:
            return f"{self.source}:{self.pointer}: {self.message}"
        return f"{self.source}: {self.message}"



# ------------------------------------------------------------------ reading tables

_REAL = r"(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_NUMBER = re.compile(rf"""^\s*(?P<sign>[-+]?)\s*(?:
        (?P<num>{_REAL})
      | (?:(?P<mul>{_REAL})\s*\*\s*)?pi(?:\s*/\s*(?P<div>{_REAL}))?
    )\s*$""", re.X | re.I)


def _number(text: str) -> float:
    """A finite real: a decimal number, or ``[k*]pi[/m]`` with an optional sign."""
    m = _NUMBER.match(text)
    if not m:
        raise ValueError(f"{text.strip()!r} is not a number (decimal, or pi, k*pi, pi/m, k*pi/m)")
    if m.group("num") is not None:
        v = float(m.group("num"))
    else:
        v = (float(m.group("mul")) if m.group("mul") else 1.0) * _PI
        if m.group("div"):
            div = float(m.group("div"))
            if div == 0.0:
                raise ValueError(f"{text.strip()!r}: division by zero")
            v /= div
    if not math.isfinite(v):
        raise ValueError(f"{text.strip()!r} is not a finite number")
    return -v if m.group("sign") == "-" else v


def _row_to_joint(get, deg: bool, where) -> DHJoint:
    """A DHJoint from a row accessor ``get(column) -> (text or None)``; errors via ``where(col, msg)``."""
    name = (get("name") or "").strip()
    if not name:
        raise where("name", "the joint needs a name")
    ttext = (get("type") or "").strip()
    jt = _TYPE_NAMES.get(ttext.lower())
    if jt is None:
        raise where("type", f"joint {name!r}: type must be R (revolute) or P (prismatic), got {ttext!r}")
    angle = DEG if deg else 1.0
    scale = {"a": 1.0, "alpha": angle, "d": 1.0, "theta": angle,
             "offset": angle if jt == "R" else 1.0,
             "lower": angle if jt == "R" else 1.0, "upper": angle if jt == "R" else 1.0}
    unused = "theta" if jt == "R" else "d"
    used = "d" if jt == "R" else "theta"
    vals = {}
    for col in ("a", "alpha", "d", "theta", "offset", "lower", "upper"):
        text = get(col)
        if text is None or not str(text).strip():
            if col in ("a", "alpha", used):
                raise where(col, f"joint {name!r}: {col} is missing")
            vals[col] = None if col in OPTIONAL_COLUMNS else 0.0
            continue
        try:
            vals[col] = _number(str(text)) * scale[col]
        except ValueError as err:
            raise where(col, f"joint {name!r}: {col}: {err}") from None
    if vals[unused] != 0.0:
        var = "theta = q + offset" if jt == "R" else "d = q + offset"
        raise where(unused, f"joint {name!r} is {JOINT_TYPES[jt]}: its joint variable gives {var}, so "
                            f"{unused} must be empty or 0 (a constant goes in the offset column)")
    lo, up = vals["lower"], vals["upper"]
    if lo is not None and up is not None and lo > up:
        raise where("lower", f"joint {name!r}: lower limit {lo:g} is above the upper limit {up:g}")
    return DHJoint(name, jt, vals["a"], vals["alpha"], vals["d"], vals["theta"], vals["offset"], lo, up)


def _csv_fields(line: str):
    """``[(text, column)]`` of one CSV line (RFC 4180 quotes; column 1-based)."""
    out, i, n = [], 0, len(line)
    while True:
        start = i
        if i < n and line[i] == '"':
            buf, i = [], i + 1
            while True:
                if i >= n:
                    raise ValueError((start + 1, "unterminated quoted field"))
                if line[i] == '"':
                    if i + 1 < n and line[i + 1] == '"':
                        buf.append('"')
                        i += 2
                        continue
                    i += 1
                    break
                buf.append(line[i])
                i += 1
            j = line.find(",", i)
            if line[i:j if j >= 0 else n].strip():
                raise ValueError((i + 1, "text after a closing quote"))
            out.append(("".join(buf), start + 1))
            i = n if j < 0 else j
        else:
            j = line.find(",", i)
            out.append((line[i:j if j >= 0 else n], start + 1))
            i = n if j < 0 else j
        if i >= n:
            return out
        i += 1  # the comma


def looks_like_dh(text: str) -> str | None:
    """``"csv"`` or ``"json"`` when ``text`` looks like a DH table, else None."""
    head = text.lstrip(" \t\r\n\ufeff")
    if head.startswith("{"):
        try:
            obj = json.loads(text.lstrip("\ufeff"))
        except ValueError:
            return None
        return "json" if isinstance(obj, dict) and "joints" in obj else None
    for line in text.splitlines():
        s = line.strip().lstrip("\ufeff")
        if not s or s.startswith("#"):
            continue
        try:
            cols = {f.strip().lower() for f, _ in _csv_fields(s)}
        except ValueError:
            return None
        return "csv" if {"name", "type"} <= cols else None
    return None


def read_csv(text: str, convention: str, *, deg: bool = False, source: str = "<input>",
             base=None, tool=None, name: str = "dh_arm") -> DHTable:
    """A DH table from CSV with the header ``name,type,a,alpha,d,theta,offset`` (any order;
    optional ``lower,upper`` columns limit q). Blank lines and lines starting with ``#`` are
    skipped. Angles in radians, or degrees with ``deg``; numbers may be ``pi``, ``k*pi/m``.
    Raises DHTableError naming ``source:line:column``."""
    if convention not in CONVENTIONS:
        raise ValueError(f"DH convention must be one of {CONVENTIONS}, got {convention!r}")
    header, joints, names = None, [], {}
    lineno = 0
    for lineno, raw in enumerate(text.lstrip("\ufeff").splitlines(), start=1):
        line = raw.rstrip("\r")
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        try:
            fields = _csv_fields(line)
        except ValueError as err:
            col, msg = err.args[0]
            raise DHTableError(msg, source, lineno, col) from None
        if header is None:
            header = {}
            for text_, col in fields:
                key = text_.strip().lower()
                if key not in COLUMNS + OPTIONAL_COLUMNS:
                    raise DHTableError(f"unknown column {text_.strip()!r}; the header is "
                                       f"{','.join(COLUMNS)} (optional: {','.join(OPTIONAL_COLUMNS)})",
                                       source, lineno, col)
                if key in header:
                    raise DHTableError(f"column {key!r} appears twice", source, lineno, col)
                header[key] = len(header)
            missing = [c for c in COLUMNS if c not in header]
            if missing:
                raise DHTableError(f"the header lacks column(s) {', '.join(missing)}; it must name "
                                   f"{','.join(COLUMNS)}", source, lineno, 1)
            continue
        if len(fields) != len(header):
            raise DHTableError(f"{len(fields)} fields, the header has {len(header)}", source, lineno,
                               fields[min(len(fields), len(header)) - 1][1])

        def get(col, fields=fields):
            i = header.get(col)
            return None if i is None else fields[i][0]

        def where(col, msg, fields=fields, lineno=lineno):
            i = header.get(col)
            return DHTableError(msg, source, lineno, fields[i][1] if i is not None else 1)

        j = _row_to_joint(get, deg, where)
        if j.name in names:
            raise DHTableError(f"joint name {j.name!r} is used twice (first on line {names[j.name]})",
                               source, lineno, fields[header["name"]][1])
        names[j.name] = lineno
        joints.append(j)
    if header is None:
        raise DHTableError(f"no header line ({','.join(COLUMNS)})", source, max(lineno, 1), 1)
    if not joints:
        raise DHTableError("the table has no joints", source, max(lineno, 1), 1)
    return DHTable(convention, joints, np.eye(4) if base is None else base,
                   np.eye(4) if tool is None else tool, name=name)


def _rigid(value, pointer: str, source: str, tol: float = 1e-9) -> np.ndarray:
    try:
        T = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        T = None
    if T is None or T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise DHTableError("expected a 4x4 matrix of numbers (rows)", source, pointer=pointer)
    R = T[:3, :3]
    if (np.abs(T[3] - (0.0, 0.0, 0.0, 1.0)).max() > tol or np.abs(R.T @ R - np.eye(3)).max() > tol
            or np.linalg.det(R) < 0.0):
        raise DHTableError("not a rigid transform (rotation block orthonormal with det +1, last row "
                           "0 0 0 1)", source, pointer=pointer)
    return T


def read_json(text: str, convention: str | None = None, *, deg: bool = False,
              source: str = "<input>") -> DHTable:
    """A DH table from JSON ``{"convention", "joints": [{name, type, a, alpha, d, theta,
    offset, lower?, upper?}], "base"?: 4x4, "tool"?: 4x4, "name"?, "angle_unit"?}``.

    ``convention`` (the command line's) must agree with the file's when both
    are given; one of them must be. ``angle_unit`` ("radian"/"degree") in the
    file overrides ``deg`` and must agree with it when ``deg`` is set.
    Raises DHTableError naming ``source:/json/pointer``."""
    try:
        obj = json.loads(text.lstrip("\ufeff"))
    except ValueError as err:
        raise DHTableError(f"not valid JSON: {err}", source) from None
    if not isinstance(obj, dict):
        raise DHTableError("a JSON DH table is an object", source, pointer="/")
    conv = obj.get("convention")
    if conv is not None and conv not in CONVENTIONS:
        raise DHTableError(f"convention must be one of {', '.join(CONVENTIONS)}, got {conv!r}", source,
                           pointer="/convention")
    if conv is not None and convention is not None and conv != convention:
        raise DHTableError(f"the file says convention {conv!r}, the command line {convention!r}", source,
                           pointer="/convention")
    conv = conv or convention
    if conv is None:
        raise DHTableError("no DH convention: give --convention standard|modified or \"convention\" in "
                           "the file", source, pointer="/convention")
    unit = obj.get("angle_unit")
    if unit is not None:
        if unit not in ("radian", "degree"):
            raise DHTableError(f"angle_unit must be 'radian' or 'degree', got {unit!r}", source,
                               pointer="/angle_unit")
        if deg and unit != "degree":
            raise DHTableError("--deg, but the file says its angles are in radians", source,
                               pointer="/angle_unit")
        deg = unit == "degree"
    rows = obj.get("joints")
    if not isinstance(rows, list) or not rows:
        raise DHTableError("\"joints\" must be a non-empty list of joints", source, pointer="/joints")
    joints, names = [], set()
    known = set(COLUMNS + OPTIONAL_COLUMNS)
    for i, row in enumerate(rows):
        ptr = f"/joints/{i}"
        if not isinstance(row, dict):
            raise DHTableError("a joint is an object", source, pointer=ptr)
        extra = sorted(set(row) - known)
        if extra:
            raise DHTableError(f"unknown key {extra[0]!r} (keys: {', '.join(COLUMNS + OPTIONAL_COLUMNS)})",
                               source, pointer=f"{ptr}/{extra[0]}")
        for key, v in row.items():
            if v is not None and not isinstance(v, (str, int, float)) or isinstance(v, bool):
                raise DHTableError("expected a number or a string", source, pointer=f"{ptr}/{key}")

        def get(col, row=row):
            v = row.get(col)
            return None if v is None else str(v) if not isinstance(v, float) else repr(v)

        def where(col, msg, ptr=ptr):
            return DHTableError(msg, source, pointer=f"{ptr}/{col}")

        j = _row_to_joint(get, deg, where)
        if j.name in names:
            raise DHTableError(f"joint name {j.name!r} is used twice", source, pointer=f"{ptr}/name")
        names.add(j.name)
        joints.append(j)
    base = _rigid(obj["base"], "/base", source) if obj.get("base") is not None else np.eye(4)
    tool = _rigid(obj["tool"], "/tool", source) if obj.get("tool") is not None else np.eye(4)
    name = obj.get("name") or "dh_arm"
    if not isinstance(name, str):
        raise DHTableError("name must be a string", source, pointer="/name")
    return DHTable(conv, joints, base, tool, name=name)


# ------------------------------------------------------------------ writing tables

def is_identity(T) -> bool:
    """Whether a 4x4 is exactly the identity (what a table without base or tool has)."""
    return bool(np.array_equal(np.asarray(T), np.eye(4)))


def _num(x: float) -> str:
    return repr(float(x) + 0.0)


def _out_values(j: DHJoint, deg: bool) -> dict:
    angle = 1.0 / DEG if deg else 1.0
    lin_or_ang = angle if j.type == "R" else 1.0
    out = {"name": j.name, "type": j.type, "a": j.a, "alpha": j.alpha * angle, "d": j.d,
           "theta": j.theta * angle, "offset": j.offset * lin_or_ang}
    out["lower"] = None if j.lower is None else j.lower * lin_or_ang
    out["upper"] = None if j.upper is None else j.upper * lin_or_ang
    return out


def write_csv(table: DHTable, out, *, deg: bool = False) -> None:
    """Write the table as CSV (``read_csv``'s format; lower/upper only when some joint has
    a limit). Base and tool are not part of the CSV format."""
    limits = any(j.lower is not None or j.upper is not None for j in table.joints)
    cols = COLUMNS + (OPTIONAL_COLUMNS if limits else ())
    out.write(",".join(cols) + "\n")
    for j in table.joints:
        v = _out_values(j, deg)
        name = v["name"]
        if any(c in name for c in ',"\n') or name != name.strip():
            v["name"] = '"' + name.replace('"', '""') + '"'
        cells = [v[c] if c in ("name", "type") else ("" if v[c] is None else _num(v[c])) for c in cols]
        out.write(",".join(cells) + "\n")


def write_json(table: DHTable, out, *, deg: bool = False) -> None:
    """Write the table as JSON (``read_json``'s format, with base, tool and angle_unit)."""
    rows = []
    for j in table.joints:
        v = _out_values(j, deg)
        rows.append({k: (val if k in ("name", "type") or val is None else float(val) + 0.0)
                     for k, val in v.items() if not (k in OPTIONAL_COLUMNS and val is None)})
    # One joint and one matrix row per line: diffable, and still plain JSON.
    def matrix(T):
        return "[\n" + ",\n".join("  " + json.dumps([float(x) + 0.0 for x in r]) for r in T) + "]"

    out.write("{\n")
    out.write(f' "name": {json.dumps(table.name)},\n "convention": {json.dumps(table.convention)},\n')
    out.write(f' "angle_unit": {json.dumps("degree" if deg else "radian")},\n')
    out.write(' "joints": [\n' + ",\n".join("  " + json.dumps(r) for r in rows) + "],\n")
    out.write(f' "base": {matrix(table.base)},\n "tool": {matrix(table.tool)}\n}}\n')
