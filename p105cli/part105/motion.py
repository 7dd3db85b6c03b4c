"""Read kinematic paths and configuration sequences from a model file (the sampling maths
is :mod:`p105cli.motion`'s).

Paths: AP242's ``kinematic_path_defined_by_nodes`` (placement_start,
t_start, segments ``point_to_point_path`` / ``linear_path`` /
``circular_path`` / ``curve_based_path`` with their ``placement_end`` and
``t_end``), in the units of the representation that holds them
(``prescribed_path`` / ``resulting_path``, a
``link_motion_representation_along_path``); the link whose frame follows
the path comes from the ``link_motion_relationship``. The AP214 long form
carries ``kinematic_path`` as a bare item without geometry (its clause 6
path elements are not in AP214), so a 1996-layout file has paths with
names only: they are listed, not sampled. AP242's
``kinematic_path_defined_by_curves`` (position and orientation curves) is
reported as unsupported rather than guessed.

Configuration sequences: both layouts (see
:mod:`p105cli.motion.configurations`), pair values decoded by
:mod:`p105cli.part105.pair_values` in SI, keyed by THE pair names.

The link a path moves is named as :mod:`p105cli.part105.layout` names links (the names of the
mechanism read from the same file).
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from ..motion.paths import KinematicPath, PathError, PathSegment
from ..motion.sampling import Plan, SampledModel, SamplingError
from ..schema.units import ANGLE, LENGTH
from ..schema.values import number
from ..step.errors import ModelError
from ..step.values import ref_id
from .layout import link_name_of_representation
from .model_file import ModelFile

__all__ = ["read_paths", "read_configuration_sequences", "MotionReadResult", "sample_model"]

_SEGMENT_KIND = {
    "point_to_point_path": "point_to_point",
    "linear_path": "linear",
    "circular_path": "circular",
    "curve_based_path": "curve_based",
}


class MotionReadResult:
    """Paths read from a model, and what could not be read (``(#id, message)``)."""

    def __init__(self):
        self.paths: list = []
        self.skipped: list = []


_ref = ref_id


def _num(v) -> float:
    x = number(v)
    if x is None:
        raise TypeError(f"not a number: {v!r}")
    return x


def _error(inst_id: int, message: str) -> ModelError:
    return ModelError(f"#{inst_id}: {message}")


def _holder(pop, path_id: int):
    """The representation holding path ``#path_id`` (items), or None."""
    for r in pop.usedin(path_id):
        if "representation" in r.types and "kinematic_path" not in r.types:
            return r
    return None


def _placement(pop, pid: Optional[int], length: float) -> np.ndarray:
    from .geometry import placement_from_instance

    if pid is None or pid not in pop:
        raise ValueError("missing placement")
    return placement_from_instance(pop, pop.instance(pid), length)


def read_paths(doc, profile: str | None = None) -> MotionReadResult:
    """Every kinematic path of the model, SI units. ``doc``: a document, Population or
    ModelFile (the command's one: no population is built then)."""
    mf = ModelFile.of(doc, profile)
    pop = mf.pop
    out = MotionReadResult()
    ents = pop.schema.entities
    if "kinematic_path_defined_by_curves" in ents:
        for i in pop.ids_of_type("kinematic_path_defined_by_curves"):
            out.skipped.append((i, "kinematic_path_defined_by_curves (position and orientation curves) "
                                   "is not supported: its orientation law is not sampled"))
    if "kinematic_path_defined_by_nodes" not in ents:
        for i in pop.ids_of_type("kinematic_path"):
            out.skipped.append((i, "a kinematic_path without geometry (the 1996 layout of AP214 "
                                   "carries none): nothing to sample"))
        return out
    for pid in pop.ids_of_type("kinematic_path_defined_by_nodes"):
        inst = pop.instance(pid)
        holder = _holder(pop, pid)
        ctx = _ref(holder.get("context_of_items")) if holder is not None else None
        units = mf.context_units(ctx) if ctx is not None else None
        length = units.factor(LENGTH) if units is not None else None
        if length is None:
            raise _error(pid, "the path's representation context has no usable length unit")
        angle = units.factor(ANGLE) or 1.0
        try:
            T = _placement(pop, _ref(inst.get("placement_start")), length)
            t = _num(inst.get("t_start"))
        except (TypeError, KeyError, ValueError) as err:
            raise _error(pid, f"placement_start / t_start: {err}") from None
        segments = []
        for sid in mf.refs(pid, "segments"):  # checked: a dangling segment is named
            seg = pop.instance(sid)
            kind = next((k for name, k in _SEGMENT_KIND.items() if name in seg.types), None)
            if kind is None:
                raise _error(sid, f"unknown path segment type {sorted(seg.leaf_types)}")
            try:
                T_end = _placement(pop, _ref(seg.get("placement_end")), length)
                t_end = _num(seg.get("t_end"))
                via = curve = None
                if kind == "circular":
                    from .geometry import point_from_instance
                    via = point_from_instance(pop, pop.instance(_ref(seg.get("via_point"))), length)
                elif kind == "curve_based":
                    from .geometry import curve_from_instance
                    curve = curve_from_instance(pop, pop.instance(_ref(seg.get("path_curve"))), length, angle)
                segments.append(PathSegment(kind, t, t_end, T, T_end, via_point=via, curve=curve,
                                            transition=str((seg.get("transition") or {}).get("enum", ""))
                                            if isinstance(seg.get("transition"), dict) else "",
                                            id=sid))
            except PathError as err:
                raise _error(sid, str(err)) from None
            except (TypeError, KeyError, ValueError) as err:
                raise _error(sid, f"malformed {kind} path segment: {err}") from None
            T, t = T_end, t_end
        role = ""
        link = frame = None
        if holder is not None:
            if "prescribed_path" in holder.types:
                role = "prescribed"
            elif "resulting_path" in holder.types:
                role = "resulting"
            for rel in pop.usedin(holder.id):
                if "link_motion_relationship" in rel.types:
                    link = link_name_of_representation(mf, _ref(rel.get("rep_1")))
                    # the link frame that follows the path: the operator's first item
                    op = _ref(rel.get("transformation_operator"))
                    item = _ref(pop.instance(op).get("transform_item_1")) if op in pop else None
                    if item in pop:
                        frame = mf.string(item, "name") or f"#{item}"
                    break
        # (names through mf.string: a name that is no string, a list, is no name)
        name = mf.string(pid, "name") or (mf.string(holder.id, "name") if holder is not None else "") or f"#{pid}"
        try:
            out.paths.append(KinematicPath(name, segments, link=link, frame=frame, role=role, id=pid,
                                           holder_id=holder.id if holder is not None else None))
        except PathError as err:
            raise _error(pid, str(err)) from None
    return out


# --------------------------------------------------------------------------- configuration sequences

_INTERPOLATION = {
    "LINEAR": "linear", "SYNCHRONOUS": "synchronous", "UNDEFINED": "undefined",
    "LINEAR_INTERPOLATION_TYPE": "linear", "SYNCHRONOUS_INTERPOLATION_TYPE": "synchronous",
    "DISCONTINUOUS_INTERPOLATION_TYPE": "discontinuous", "UNDEFINED_INTERPOLATION_TYPE": "undefined",
}


def _interpolation(inst) -> str:
    v = inst.get("interpolation")
    name = v.get("enum") if isinstance(v, dict) else None
    if name not in _INTERPOLATION:
        raise _error(inst.id, f"interpolation is {v!r}, not an interpolation_type")
    return _INTERPOLATION[name]


def read_configuration_sequences(doc, profile: str | None = None):
    """``(sequences, kinds, skipped)``: every interpolated_configuration_sequence as a
    :class:`ConfigurationSequence` (pair values in SI, keyed by pair name as the
    mechanism reader names them), the pair kinds by name, and ``(#id, message)``
    for sequences that could not be read."""
    from ..motion.configurations import ConfigurationNode, ConfigurationSequence
    from .read_mechanism import PairValueReader

    mf = ModelFile.of(doc, profile)
    pop = mf.pop
    seq_ids = pop.ids_of_type("interpolated_configuration_sequence") \
        if "interpolated_configuration_sequence" in pop.schema.entities else []
    if not seq_ids:
        return [], {}, []
    values = PairValueReader(mf)
    kinds = values.kinds
    out, skipped = [], []
    def at(i, attr):  # the instance #i.attr refers to; a ModelError naming #i if there is none
        return pop.instance(mf.ref(i, attr))

    for sid in seq_ids:
        seq = pop.instance(sid)
        nodes = {}
        if "segments" in seq.explicit_names():  # AP242: segments (state, t_parameter, interpolation)
            for gid in mf.refs(sid, "segments"):
                seg = pop.instance(gid)
                state = at(gid, "state")
                t = mf.number(gid, "t_parameter")
                nodes[t] = ConfigurationNode(t, values.values(mf.refs(state.id, "items")),
                                             _interpolation(seg), mf.string(state.id, "name"), state.id)
            name = mf.string(sid, "name") or f"#{sid}"
            closed = bool(nodes) and list(nodes.values())[-1].interpolation != "discontinuous"
        else:  # 1996: a set of configuration_interpolation(previous, next, interpolation)
            laws = {}
            for cid in mf.refs(sid, "interpolation"):
                ci = pop.instance(cid)
                for attr in ("previous_configuration_definition", "next_configuration_definition"):
                    cd = at(cid, attr)
                    t = mf.number(cd.id, "t_parameter")
                    if t not in nodes:
                        nodes[t] = (values.values(mf.refs(cd.id, "pair_values")), cd.id)
                prev_t = mf.number(at(cid, "previous_configuration_definition").id, "t_parameter")
                laws[prev_t] = _interpolation(ci)
            last = max(nodes) if nodes else None
            nodes = {t: ConfigurationNode(t, vals, laws.get(t, "discontinuous" if t == last else "undefined"),
                                          "", cid)
                     for t, (vals, cid) in nodes.items()}
            name = f"#{sid}"  # the 1996 sequence has no name
            closed = False
        try:
            out.append(ConfigurationSequence(name, tuple(nodes.values()), closed=closed, id=sid))
        except ValueError as err:
            skipped.append((sid, str(err)))
    return out, kinds, skipped


def sample_model(doc, *, what: str = "all", paths=(), sequences=(), plan: Plan = Plan(),
                 profile: str | None = None) -> SampledModel:
    """Read what ``what`` asks for (``doc``: a document, Population or ModelFile) and check
    the request; sampling happens as the records are drawn from the returned
    :class:`~p105cli.motion.sampling.SampledModel`."""
    mf = ModelFile.of(doc, profile)
    out = SampledModel(plan=plan)
    if what in ("all", "paths"):
        read = read_paths(mf)
        out.skipped.extend(read.skipped)
        missing = set(paths) - {p.name for p in read.paths}
        if missing:
            raise SamplingError(f"no path named {', '.join(repr(m) for m in sorted(missing))}")
        out.path_list = [p for p in read.paths if not paths or p.name in paths]
    if what in ("all", "configurations"):
        seqs, kinds, skipped = read_configuration_sequences(mf)
        out.skipped.extend(skipped)
        out.kinds = kinds
        missing = set(sequences) - {q.name for q in seqs}
        if missing:
            raise SamplingError(f"no configuration sequence named {', '.join(repr(m) for m in sorted(missing))}")
        out.sequence_list = [q for q in seqs if not sequences or q.name in sequences]
    # check every requested t against every range before writing anything
    for item in (*out.path_list, *out.sequence_list):
        if plan.t is not None:
            lo, hi = item.t_start, item.t_end
            tol = 1e-12 * max(1.0, abs(lo), abs(hi))
            bad = [t for t in plan.t if not (lo - tol <= t <= hi + tol)]
            if bad:
                raise SamplingError(f"#{item.id} {item.name!r}: t = {bad[0]!r} is outside its range "
                                    f"[{lo!r}, {hi!r}]")
    return out
