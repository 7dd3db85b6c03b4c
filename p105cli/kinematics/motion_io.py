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

from p105cli.step.values import ref_id

__all__ = ["MotionInputError", "read_values", "read_poses", "parse_set", "parse_sweep", "LENGTH_UNITS", "ANGLE_UNITS",
           "add_results", "ResultingPath", "resulting_path_request", "controlling_pairs"]

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


# --------------------------------------------------------------------------- analysis results in the model

#: Statuses whose values are a configuration of the mechanism (written into the model).
WRITTEN_STATUSES = ("ok", "out_of_range", "singular", "branch_change")


def _value_units(pair):
    return ["A" if a else "L" for a in pair.type.angle_mask]


def add_results(doc, mech, Q, t, status, *, paths=(), pl=None):
    """A new document: ``doc``'s instances plus the solved configurations as Part 105 analysis
    results, in the layout of ``mech.profile``.

    AP242: per configuration the ``*_pair_value`` instances and a
    ``mechanism_state_representation`` of the mechanism representation; with
    two or more configurations an ``interpolated_configuration_sequence`` of
    ``interpolated_configuration_segment`` (linear between configurations),
    its ``interpolated_configuration_representation`` and a
    ``kinematic_analysis_result``. 1996 layout (AP214 / p105 profiles):
    ``configuration_definition`` per configuration, ``configuration_interpolation``
    between consecutive ones, an ``interpolated_configuration_sequence`` and a
    ``kinematic_analysis_result`` of the mechanism. Values are in the file's
    units; only configurations that could be assembled are written.

    ``paths`` (:class:`ResultingPath`): link frames whose world placements
    through the written configurations become resulting paths (two or more
    configurations, t increasing). AP242: a ``resulting_path`` holding a
    ``kinematic_path_defined_by_nodes`` (point to point), tied to the link
    frame by a ``link_motion_relationship``, each in a
    ``kinematic_analysis_result`` of its own (its result is one
    kinematic_result). 1996: a ``resulting_path`` (a ``motion_link_relationship``
    from a ``founded_kinematic_path`` of a bare ``kinematic_path`` in the
    world context) among the ``contained_kinematic_results``, and then the
    interpolations are ``.LINEAR.`` (WR1 wants a defined interpolation
    exactly when a resulting path is there). Returns ``(document, notes)``."""
    from p105cli.step.jsonmodel import extended

    layout = "ap242" if mech.profile == "ap242" else "1996"
    lf, af = mech.units.length, mech.units.angle
    data = list(doc.records())
    by_id = {rec["id"]: rec for rec in data}
    next_id = max(by_id, default=0) + 1
    added, notes = [], []

    def new(type_name, args):
        nonlocal next_id
        rec = {"id": next_id, "type": type_name, "args": args}
        next_id += 1
        added.append(rec)
        return {"ref": rec["id"]}

    mech_id = mech.ids.get("mechanism")
    if mech_id not in by_id:
        raise ValueError(f"mechanism {mech.name!r}: its mechanism instance is not known; cannot add results")
    slices = mech.value_slices

    def value(p, q):
        if p.kind == "fully_constrained":
            return None
        pair_ref = p.ids.get("pair")
        if pair_ref is None:
            raise ValueError(f"pair {p.name!r} has no instance in the model")
        entity = "universal_pair_value" if p.kind == "homokinetic" else f"{p.kind}_pair_value"
        conv = [float(x) / (af if u == "A" else lf) for u, x in zip(_value_units(p), q)]
        if p.kind == "spherical":
            vals = [{"type": "YPR_ROTATION", "value": conv}]
        elif p.kind == "unconstrained":
            M = p.motion(np.asarray(q, dtype=np.float64))
            o = new("cartesian_point", [f"{p.name} value", [float(x) / lf for x in M[:3, 3]]])
            z = new("direction", ["", [float(x) for x in M[:3, 2]]])
            x = new("direction", ["", [float(x) for x in M[:3, 0]]])
            vals = [new("axis2_placement_3d", [f"{p.name} value", o, z, x])]
        else:
            vals = conv
        ref = {"ref": pair_ref}
        return new(entity, [ref, *vals] if layout == "1996" else [p.name, ref, *vals])

    keep = [i for i, s in enumerate(status) if s in WRITTEN_STATUSES]
    if len(keep) < len(status):
        notes.append(f"{len(status) - len(keep)} configuration(s) that could not be assembled are not written")
    ts = [float(t[i]) if t is not None else float(i) for i in keep]
    states = []
    for i in keep:
        refs = [v for v in (value(p, Q[i, slices[p.name]]) for p in mech.pairs) if v is not None]
        if layout == "ap242":
            states.append(new("mechanism_state_representation",
                              [f"configuration {i}", refs, {"derived": True}, {"ref": mech_id}]))
        else:
            t_value = {"type": "PARAMETER_VALUE", "value": ts[len(states)]}
            states.append(new("configuration_definition", [refs, t_value]))
    if paths and len(states) < 2:
        notes.append("a resulting path needs two or more configurations: none written")
        paths = ()
    if paths and any(b <= a for a, b in zip(ts, ts[1:])):
        notes.append("t does not increase from configuration to configuration: no resulting path written "
                     "(a kinematic path's parameter must increase)")
        paths = ()
    ctx = None
    if len(states) >= 2:
        name = f"{mech.name} solved configurations"
        if layout == "ap242":
            segs = [new("interpolated_configuration_segment",
                        [s, tt, {"enum": "LINEAR_INTERPOLATION_TYPE" if k + 1 < len(states)
                                 else "DISCONTINUOUS_INTERPOLATION_TYPE"}])
                    for k, (s, tt) in enumerate(zip(states, ts))]
            seq = new("interpolated_configuration_sequence", [name, segs])
            ctx = _parameter_context(by_id, by_id[mech_id]["args"][2], f"{mech.name} motion", added, next_id)
            next_id += 1
            new("interpolated_configuration_representation", [name, [seq], ctx])
            new("kinematic_analysis_result", [{"ref": mech_id}, seq])
            if paths:
                from p105cli.kinematics.solver import forward, plan
                pl = pl or plan(mech)
                world = forward(pl, Q[keep])
                for rp in _paths_ap242(doc, mech, paths, world, pl.link_index, ts, ctx, by_id, new, data):
                    new("kinematic_analysis_result", [{"ref": mech_id}, rp])
        else:
            # kinematic_analysis_result WR1 (1996) allows a defined interpolation only
            # together with a resulting path: the samples are joined as "undefined".
            # kinematic_analysis_result WR1 (1996): a defined interpolation exactly when a
            # resulting path is among the results; without one the samples are joined as
            # "undefined", with one linearly (in the pair values, as AP242's segments are).
            law = "LINEAR" if paths else "UNDEFINED"
            steps = [new("configuration_interpolation", [a, b, {"enum": law}])
                     for a, b in zip(states, states[1:])]
            seq = new("interpolated_configuration_sequence", [steps])
            results = [seq]
            if paths:
                from p105cli.kinematics.solver import forward, plan
                world = forward(pl or plan(mech), Q[keep])
                results += _paths_1996(doc, mech, paths, world, (pl or plan(mech)).link_index, by_id, new, data)
            new("kinematic_analysis_result", [{"ref": mech_id}, results])
    elif states:
        notes.append("one configuration: written as a state without an interpolated sequence "
                     "(a sequence needs two)")
    return extended(doc, data, added), notes


def _parameter_context(by_id, ctx_ref, name, added, new_id):
    """A copy of the mechanism's context that is also a geometric_representation_context_with_parameter
    (what an interpolated_configuration_representation needs), as a complex instance."""
    rec = by_id.get(ctx_ref.get("ref") if isinstance(ctx_ref, dict) else None)
    if rec is None:
        raise ValueError("the mechanism representation has no context")
    if "complex" in rec:
        parts = [dict(p) for p in rec["complex"]]
    else:
        parts = [{"type": "geometric_representation_context", "args": rec["args"][2:3]},
                 {"type": "representation_context", "args": rec["args"][:2]}]
    for p in parts:
        if p["type"] == "representation_context":
            p["args"] = [name, *p["args"][1:]]
    parts.append({"type": "geometric_representation_context_with_parameter", "args": [None]})
    parts.sort(key=lambda p: p["type"])
    added.append({"id": new_id, "complex": parts})
    return {"ref": new_id}


# --------------------------------------------------------------------------- resulting paths

class ResultingPath:
    """A link frame whose path through the solved configurations is written as a resulting path:
    ``link`` (name), ``frame`` (a name of ``Link.frames``, a frame instance's name, or None for
    the link frame), ``T_link_frame`` (4x4, link coordinates, metres) and ``pairs`` (names of the
    driven or solved pairs that move it: its controlling joints)."""

    def __init__(self, link, frame, T_link_frame, pairs):
        self.link, self.frame = link, frame
        self.T_link_frame = np.asarray(T_link_frame, dtype=np.float64)
        self.pairs = tuple(pairs)

    def __repr__(self):
        return f"ResultingPath({self.link!r}, {self.frame!r}, pairs={self.pairs!r})"


def controlling_pairs(mech, pl, link: str) -> list:
    """The pairs that move ``link``: those on the tree path from the base, and every pair of a
    closed loop through one of them (its values are solved with them); not the fixed ones."""
    from p105cli.kinematics.solver import _chain

    ks = {k for k, _, _, _ in _chain(pl, link)}
    for loop in pl.loops:
        if any(k in ks for k, _ in loop):
            ks |= {k for k, _ in loop}
    names = {pl.pair_names[k] for k in ks}
    return [p.name for p in mech.pairs if p.name in names and p.kind != "fully_constrained"]


def resulting_path_request(mech, pl, spec: str, *, frame_matrix=None) -> ResultingPath:
    """``LINK`` or ``LINK:FRAME`` (FRAME a name of ``Link.frames``) as a :class:`ResultingPath`;
    ``frame_matrix`` gives the frame's placement when FRAME names a frame that is not in
    ``Link.frames`` (a pair frame a prescribed path uses)."""
    link, frame = spec, None
    if spec not in mech.link_names and ":" in spec:
        link, frame = spec.rsplit(":", 1)
    if link not in mech.link_names:
        raise MotionInputError(f"--resulting-path {spec!r}: {link!r} is not a link of mechanism "
                               f"{mech.name!r} (links: {', '.join(mech.link_names)})")
    frames = mech.link(link).frames
    if frame is None:
        T = np.eye(4) if frame_matrix is None else frame_matrix
    elif frame in frames:
        T = frames[frame]
    elif frame_matrix is not None:
        T = frame_matrix
    else:
        raise MotionInputError(f"--resulting-path {spec!r}: link {link!r} has no frame {frame!r} "
                               f"(frames: {', '.join(frames) or 'none'})")
    pairs = controlling_pairs(mech, pl, link)
    if not pairs:
        raise MotionInputError(f"--resulting-path {spec!r}: link {link!r} does not move (no pair moves it): "
                               "a resulting path needs at least one controlling joint")
    return ResultingPath(link, frame, T, pairs)


def _length_of_context(pop, ctx_id, default: float) -> float:
    from p105cli.kinematics.reader import LENGTH, context_units
    try:
        f = context_units(pop, ctx_id).factor(LENGTH) if ctx_id is not None else None
    except Exception:  # noqa: BLE001 - a context without usable units: the mechanism's own
        f = None
    return f or default


_ref_id = ref_id


def _link_representation(pop, mech, link) -> int:
    """The representation of ``link`` (a kinematic_link_representation), preferring the one that
    holds the link's pair frames."""
    lid = mech.link(link).id
    if lid is None or lid not in pop:
        raise ValueError(f"link {link!r} has no instance in the model; cannot tie a path to it")
    if "kinematic_link_representation" in pop.instance(lid).types:
        return lid
    reps = []
    for inst in pop.usedin(lid):
        if "kinematic_link_representation" in inst.types:
            reps.append(inst.id)
        elif "kinematic_link_representation_relation" in inst.types:
            r = _ref_id(inst.get("geometric_aspects"))
            if r is not None:
                reps.append(r)
    if not reps:
        raise ValueError(f"link {link!r} has no link representation; cannot tie a path to it")
    frames = {p.ids.get("frame_1") for p in mech.pairs if p.link1 == link} | \
             {p.ids.get("frame_2") for p in mech.pairs if p.link2 == link}
    for r in reps:
        if frames & {_ref_id(v) for v in pop.instance(r).get("items") or []}:
            return r
    return reps[0]


def _frame_item(pop, mech, rp, rep_id, by_id, data, new):
    """The placement item of link representation ``#rep_id`` that is ``rp``'s frame: the item of
    that name, else one at the same placement (axis2_placement_3d), else a new axis2_placement_3d
    added to the representation's items (a link frame that no item places yet)."""
    from p105cli.kinematics.geometry_step import placement_from_instance

    rep = pop.instance(rep_id)
    items = [_ref_id(v) for v in rep.get("items") or []]
    placements = [i for i in items if i in pop and "placement" in pop.instance(i).types]
    if rp.frame is not None:
        for i in placements:
            n = pop.instance(i).get("name") or ""
            if rp.frame in (n, f"{n} #{i}", f"#{i}"):
                return i
    lf = _length_of_context(pop, _ref_id(rep.get("context_of_items")), mech.units.length)
    tol = 1e-9 * max(1.0, mech.size())
    for i in placements:
        inst = pop.instance(i)
        if "axis2_placement_3d" not in inst.types:
            continue
        try:
            T = placement_from_instance(pop, inst, lf)
        except Exception:  # noqa: BLE001 - an item that is no usable placement is not the frame
            continue
        if np.abs(T - rp.T_link_frame).max() <= tol:
            return i
    label = rp.frame or f"{rp.link} link frame"
    ref = _axis2(new, rp.T_link_frame, lf, label)
    rec = by_id[rep_id]
    k = next(n for n, r in enumerate(data) if r is rec)
    if "complex" in rec:
        parts = [dict(p) for p in rec["complex"]]
        for p in parts:
            if p["type"] == "representation":
                p["args"] = [p["args"][0], [*p["args"][1], ref], *p["args"][2:]]
        new_rec = {**rec, "complex": parts}
    else:
        new_rec = {**rec, "args": [rec["args"][0], [*rec["args"][1], ref], *rec["args"][2:]]}
    data[k] = by_id[rep_id] = new_rec
    return ref["ref"]


def _axis2(new, T, lf, name):
    o = new("cartesian_point", [name, [_clean(float(x) / lf) for x in T[:3, 3]]])
    z = new("direction", ["", [_clean(float(x)) for x in T[:3, 2]]])
    x = new("direction", ["", [_clean(float(x)) for x in T[:3, 0]]])
    return new("axis2_placement_3d", [name, o, z, x])


def _clean(v: float) -> float:
    return 0.0 if v == 0.0 else v


def _label(rp) -> str:
    if rp.frame is None:
        return f"{rp.link} link frame"
    return rp.frame if rp.frame.startswith(rp.link) else f"{rp.link} {rp.frame}"


def _path_population(doc, mech):
    from p105cli.schema.population import Population
    return Population(doc, mech.profile)


def _paths_ap242(doc, mech, paths, world, link_index, ts, ctx, by_id, new, data) -> list:
    """AP242 resulting paths (refs): per request a kinematic_path_defined_by_nodes of the frame's
    world placements at the configurations, point to point, in the sequence's parameter context."""
    pop = _path_population(doc, mech)
    mech_rep = pop.instance(mech.ids["mechanism"])
    lf = _length_of_context(pop, _ref_id(mech_rep.get("context_of_items")), mech.units.length)
    out = []
    for rp in paths:
        poses = world[:, link_index[rp.link]] @ rp.T_link_frame
        label = _label(rp)
        start = _axis2(new, poses[0], lf, f"{label} at t={ts[0]:g}")
        nodes = [new("point_to_point_path", [tt, {"derived": True}, _axis2(new, T, lf, f"{label} at t={tt:g}")])
                 for T, tt in zip(poses[1:], ts[1:])]
        kpath = new("kinematic_path_defined_by_nodes", [f"{label} resulting path", nodes, ts[0], start])
        joints = [{"ref": mech.pair(n).ids["joint"]} for n in rp.pairs]
        path = new("resulting_path", [f"{label} resulting path", [kpath], ctx, joints])
        rep_id = _link_representation(pop, mech, rp.link)
        frame = _frame_item(pop, mech, rp, rep_id, by_id, data, new)
        lmt = new("link_motion_transformation", [f"{label} motion", None, {"ref": frame}, kpath])
        new("link_motion_relationship", [f"{label} motion", None, {"ref": rep_id}, path, lmt])
        out.append(path)
    return out


def _paths_1996(doc, mech, paths, world, link_index, by_id, new, data=None) -> list:
    """1996 resulting paths (refs): a motion_link_relationship subtype from a founded_kinematic_path
    (a bare kinematic_path: AP214 has no path geometry) in the world context to the link frame."""
    pop = _path_population(doc, mech)
    world_ctx = None
    bp = mech.ids.get("base_placement")
    if bp in pop:
        ground = _ref_id(pop.instance(bp).get("rep_1"))
        if ground in pop:
            world_ctx = _ref_id(pop.instance(ground).get("context_of_items"))
    out = []
    for rp in paths:
        rep_id = _link_representation(pop, mech, rp.link)
        if world_ctx is None:  # no base placement: the world is the base link's frame
            world_ctx = _ref_id(pop.instance(_link_representation(pop, mech, mech.base)).get("context_of_items"))
        label = _label(rp)
        frame = _frame_item(pop, mech, rp, rep_id, by_id, data, new)
        kpath = new("kinematic_path", [f"{label} resulting path"])
        founded = new("founded_kinematic_path", [f"{label} resulting path", [kpath], {"ref": world_ctx}])
        joints = [{"ref": mech.pair(n).ids["joint"]} for n in rp.pairs]
        out.append(new("resulting_path", [f"{label} resulting path", None, founded, {"ref": rep_id},
                                          {"ref": frame}, joints]))
    return out
