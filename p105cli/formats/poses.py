"""Pose files: the one reader of ``{t, pose}`` samples (``solve --path`` targets,
``solve --keypoints`` cable end points).

JSON Lines (the first line that is neither blank nor a ``#`` comment is an object)
    ``{"t": t, "pose": M}`` per line, ``M`` the 4x4 matrix as 4 rows, the top 3 rows,
    or 16 or 12 numbers row by row.
CSV
    A header ``t,m00,m01,m02,m03,m10,...,m23`` (the last row 0 0 0 1 implied) or up
    to ``m33`` (16 entries), with or without the ``t`` column; or no header, the
    columns then told by their count: 13 (t and m00..m23), 17 (t and m00..m33),
    12 or 16 (no t).

``t`` is optional: on every sample or on none (then a sample's time is its index,
:meth:`PoseSamples.times`). A given bottom row must be 0 0 0 1 (to 1e-6), the
rotation orthonormal (to 1e-6, re-orthonormalised so round-off in a file does not
become a pose error). Blank lines and ``#`` comment lines are skipped. Errors are
:class:`~.text.FormatError` naming ``FILE:LINE:COL``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .text import FormatError, csv_rows, is_jsonl, jsonl_records, number

__all__ = ["FormatError", "PoseSamples", "read_poses", "parse_poses", "parse_pose_file", "TOL"]

#: How far a file's rotation may be from orthonormal, and its bottom row from 0 0 0 1.
TOL = 1e-6

_M12 = [f"m{i}{j}" for i in range(3) for j in range(4)]
_M16 = [f"m{i}{j}" for i in range(4) for j in range(4)]
#: Headerless CSV: (has t, matrix entries) by the number of columns.
_BY_COUNT = {13: (True, 12), 17: (True, 16), 12: (False, 12), 16: (False, 16)}


@dataclass(frozen=True)
class PoseSamples:
    """Poses read from a file: ``t`` (N,) or None when the file gives none, ``poses``
    (N, 4, 4) rigid placements, ``lines`` the line of each sample."""

    t: np.ndarray | None
    poses: np.ndarray
    lines: tuple

    def times(self) -> np.ndarray:
        """The samples' times: as given, else their indices 0, 1, 2..."""
        return self.t if self.t is not None else np.arange(len(self.poses), dtype=np.float64)


def read_poses(text: str, source: str, *, length: float = 1.0):
    """``(t (N,) or None, poses (N, 4, 4))`` of a pose file, translations times ``length``."""
    samples = parse_poses(text, source, length=length)
    return samples.t, samples.poses


def parse_pose_file(path: str, *, length: float = 1.0) -> PoseSamples:
    """The samples of the pose file at ``path`` (read and decoded as every input is; an
    unreadable file raises OSError)."""
    from ..step import decode_bytes

    with open(path, "rb") as fh:
        text = decode_bytes(fh.read())
    return parse_poses(text, path, length=length)


def parse_poses(text: str, source: str, *, length: float = 1.0) -> PoseSamples:
    """The samples of a pose file (JSON Lines or CSV, sniffed), translations times ``length``."""
    rows = _jsonl(text, source) if is_jsonl(text) else _csv(text, source)
    ts, poses, lines = [], [], []
    for line, t, T, where in rows:
        ts.append(t)
        poses.append(_rigid(T, where))
        lines.append(line)
    if not poses:
        raise FormatError(f"{source}:1:1: no pose")
    given = [t is not None for t in ts]
    if any(given) and not all(given):
        line = lines[given.index(not given[0])]
        raise FormatError(f"{source}:{line}:1: 't' must be given on every line or on none")
    P = np.array(poses)
    P[:, :3, 3] *= length
    return PoseSamples(np.array(ts, dtype=np.float64) if given[0] else None, P, tuple(lines))


def _time(t, where: str):
    if t is None:
        return None
    if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t):
        raise FormatError(f"{where}: t must be a finite number")
    return float(t)


def _jsonl(text, source):
    for n, rec in jsonl_records(text, source):
        T = rec.get("pose") if isinstance(rec, dict) else None
        try:
            T = np.array(T, dtype=np.float64)
        except (TypeError, ValueError):
            T = None
        if T is None or T.shape not in ((4, 4), (3, 4), (16,), (12,)):
            raise FormatError(f"{source}:{n}:1: expected {{\"t\": ..., \"pose\": 4x4 matrix}}")
        yield n, _time(rec.get("t"), f"{source}:{n}:1"), T.reshape(-1, 4), f"{source}:{n}:1"


def _csv(text, source):
    rows = csv_rows(text)
    if not rows:
        raise FormatError(f"{source}:1:1: no pose")
    width, tcol, idx, body, expected = _csv_layout(rows, source)
    for line, cells in body:
        if len(cells) != width:
            raise FormatError(f"{source}:{line}:1: {len(cells)} fields, {expected}")
        vals = [number(cell, f"{source}:{line}:{col}") for col, cell in cells]
        if len(idx) == 16:
            _bottom_row(vals, idx, cells, f"{source}:{line}")
        yield line, None if tcol is None else vals[tcol], np.array([vals[i] for i in idx]).reshape(-1, 4), \
            f"{source}:{line}:1"


def _csv_layout(rows, source):
    """``(columns, t column or None, matrix columns, data rows, what a row must match)`` from
    the header, or from the first row's width when there is none."""
    hline, first = rows[0]
    labels = [c.strip() for _, c in first]
    if all(_is_number(x) for x in labels):   # no header: the columns by their count
        if len(labels) not in _BY_COUNT:
            raise FormatError(f"{source}:{hline}:1: {len(labels)} fields; a pose row has 13 (t,m00,...,m23) "
                              "or 17 (to m33), or 12 or 16 without t")
        has_t, k = _BY_COUNT[len(labels)]
        idx = list(range(int(has_t), int(has_t) + k))
        return len(labels), (0 if has_t else None), idx, rows, f"line {hline} has {len(labels)}"
    m_labels = [x for x in labels if x != "t"]
    if m_labels not in (_M12, _M16) or labels.count("t") > 1:
        raise FormatError(f"{source}:{hline}:1: expected the columns t,m00,m01,...,m23 (or to m33)")
    if len(rows) == 1:
        raise FormatError(f"{source}:{hline + 1}:1: no pose after the header")
    tcol = labels.index("t") if "t" in labels else None
    return len(labels), tcol, [labels.index(x) for x in m_labels], rows[1:], f"the header has {len(labels)}"


def _bottom_row(vals, idx, cells, where):
    """The given bottom row of a 16-column row must be 0 0 0 1; the cell at fault is named."""
    for j, i in enumerate(idx[12:]):
        if abs(vals[i] - (1.0 if j == 3 else 0.0)) > TOL:
            raise FormatError(f"{where}:{cells[i][0]}: the last row of a pose must be 0 0 0 1 "
                              f"(m3{j} is {cells[i][1].strip()})")


def _is_number(cell: str) -> bool:
    try:
        float(cell)
        return True
    except ValueError:
        return False


def _rigid(T, where) -> np.ndarray:
    """A 4x4 rigid placement from 3 or 4 rows; the rotation re-orthonormalised."""
    if not np.all(np.isfinite(T)):
        raise FormatError(f"{where}: the pose has a value that is not a finite number")
    if T.shape[0] == 4 and np.abs(T[3] - [0.0, 0.0, 0.0, 1.0]).max() > TOL:
        raise FormatError(f"{where}: the last row of a pose must be 0 0 0 1")
    R = T[:3, :3]
    err = float(np.abs(R.T @ R - np.eye(3)).max())
    if err > TOL or np.linalg.det(R) < 0:
        raise FormatError(f"{where}: the pose is not a rigid placement (rotation not orthonormal to "
                          f"{TOL:g}: |R^T R - I| = {err:.2g}, or not proper)")
    U, _, Vt = np.linalg.svd(R)
    out = np.eye(4)
    out[:3, :3] = U @ Vt
    out[:3, 3] = T[:3, 3]
    return out
