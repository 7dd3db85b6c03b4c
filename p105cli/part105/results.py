"""Analysis results and resulting paths into a model: the solved configurations of ``p105 solve``
as Part 105 instances added to the input model, in its layout.

``add_results(doc, mech, Q, t, status, paths=..., pl=...)`` gives ``(document, notes)``
(``model_with_results`` for a solver result); ``resulting_path_request`` turns
``LINK[:FRAME]`` into a :class:`ResultingPath`, ``resulting_path_requests`` the requests of a
``solve`` run (an error is a :class:`ResultingPathError`). ``doc`` is the command's one
ModelFile: no second population is built to place the results. Link placements come from the solver's forward kinematics
(:func:`p105cli.kinematics.solver.forward`); the model's records are decoded once.
"""

from __future__ import annotations

import numpy as np

__all__ = ["WRITTEN_STATUSES", "add_results", "model_with_results", "ResultingPath", "ResultingPathError",
           "controlling_pairs", "resulting_path_request", "resulting_path_requests"]


class ResultingPathError(ValueError):
    """A resulting path was asked for that the mechanism cannot have (unknown link or frame, a
    link no pair moves)."""


#: Statuses whose values are a configuration of the mechanism (written into the model).
WRITTEN_STATUSES = ("ok", "out_of_range", "singular", "branch_change")


def add_results(doc, mech, Q, t, status, *, paths=(), pl=None):
    """A new document: ``doc``'s instances plus the solved configurations as Part 105 analysis
    results, in the layout of ``mech.profile``. ``doc``: the ModelFile ``mech`` was read from
    (its population is the one the results are placed by), or a document.

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

    from p105cli.kinematics.pairs import LOW_ORDER

    from .pair_values import is_generic_low_order, low_order_components_of, scalar_values, value_arguments, \
        value_entity, ypr_values

    from .model_file import ModelFile

    given = doc if isinstance(doc, ModelFile) else None
    doc = given.doc if given is not None else doc
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
    typed_model = []

    def model_file():
        """The model typed by its schema, over the records as read (built once, when needed)."""
        if not typed_model:
            typed_model.append(given.lenient() if given is not None else _model_file(doc, mech, data))
        return typed_model[0]

    def value(p, q):
        if p.kind == "fully_constrained":
            return None
        pair_ref = p.ids.get("pair")
        if pair_ref is None:
            raise ValueError(f"pair {p.name!r} has no instance in the model")
        conv = scalar_values(p.type.value_units, q, lambda x: float(x) / af, lambda x: float(x) / lf)
        if is_generic_low_order(model_file(), pair_ref):  # a generic pair's value, whatever its flags name
            vals = scalar_values(LOW_ORDER.value_units, low_order_components_of(p.kind, q, layout),
                                 lambda x: float(x) / af, lambda x: float(x) / lf)
            return new(value_entity("low_order"), value_arguments(layout, p.name, {"ref": pair_ref}, vals))
        if p.kind == "spherical":
            vals = [{"type": "YPR_ROTATION", "value": ypr_values(q, lambda x: float(x) / af)}]
        elif p.kind == "unconstrained":
            M = p.motion(np.asarray(q, dtype=np.float64))
            o = new("cartesian_point", [f"{p.name} value", [float(x) / lf for x in M[:3, 3]]])
            z = new("direction", ["", [float(x) for x in M[:3, 2]]])
            x = new("direction", ["", [float(x) for x in M[:3, 0]]])
            vals = [new("axis2_placement_3d", [f"{p.name} value", o, z, x])]
        else:
            vals = conv
        return new(value_entity(p.kind), value_arguments(layout, p.name, {"ref": pair_ref}, vals))

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
            ctx = _parameter_context(model_file(), mech_id, f"{mech.name} motion", added, next_id)
            next_id += 1
            new("interpolated_configuration_representation", [name, [seq], ctx])
            new("kinematic_analysis_result", [{"ref": mech_id}, seq])
            if paths:
                from p105cli.kinematics.solver import forward, plan
                pl = pl or plan(mech)
                world = forward(pl, Q[keep])
                for rp in _paths_ap242(model_file(), mech, paths, world, pl.link_index, ts, ctx, by_id, new, data):
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
                pl = pl or plan(mech)
                world = forward(pl, Q[keep])
                results += _paths_1996(model_file(), mech, paths, world, pl.link_index, by_id, new, data)
            new("kinematic_analysis_result", [{"ref": mech_id}, results])
    elif states:
        notes.append("one configuration: written as a state without an interpolated sequence "
                     "(a sequence needs two)")
    return extended(doc, data, added), notes


def _parameter_context(mf, mech_id, name, added, new_id):
    """A copy of the mechanism's context that is also a geometric_representation_context_with_parameter
    (what an interpolated_configuration_representation needs), as a complex instance."""
    ctx = mf.ref(mech_id, "context_of_items")
    if ctx is None:
        raise ValueError("the mechanism representation has no context")
    inst = mf.pop.instance(ctx)
    if inst.is_complex:  # the same parts, named ``name``
        parts = [{**p, "args": list(p["args"])} for p in inst.record["complex"]]
        slot = inst.layout.slots[inst.layout.by_name["context_identifier"][0]]
        parts[slot.part]["args"][slot.pos] = name
    else:  # a geometric_representation_context as the parts of a complex instance
        parts = [{"type": "geometric_representation_context",
                  "args": [mf.get(ctx, "coordinate_space_dimension", None)]},
                 {"type": "representation_context", "args": [name, mf.get(ctx, "context_type", None)]}]
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
        raise ResultingPathError(f"--resulting-path {spec!r}: {link!r} is not a link of mechanism "
                               f"{mech.name!r} (links: {', '.join(mech.link_names)})")
    frames = mech.link(link).frames
    if frame is None:
        T = np.eye(4) if frame_matrix is None else frame_matrix
    elif frame in frames:
        T = frames[frame]
    elif frame_matrix is not None:
        T = frame_matrix
    else:
        raise ResultingPathError(f"--resulting-path {spec!r}: link {link!r} has no frame {frame!r} "
                               f"(frames: {', '.join(frames) or 'none'})")
    pairs = controlling_pairs(mech, pl, link)
    if not pairs:
        raise ResultingPathError(f"--resulting-path {spec!r}: link {link!r} does not move (no pair moves it): "
                               "a resulting path needs at least one controlling joint")
    return ResultingPath(link, frame, T, pairs)


def resulting_path_requests(mech, pl, specs, motion) -> list:
    """The link frames whose resulting paths go into the model: ``specs`` (``LINK[:FRAME]``,
    ``solve --resulting-path``), else the target of an inverse analysis (``motion``: a
    :class:`~p105cli.motion.analysis.Motion`). Raises :class:`ResultingPathError`."""
    if specs:
        return [resulting_path_request(mech, pl, spec) for spec in dict.fromkeys(specs)]
    if motion.inverse:
        spec = motion.link if motion.frame_name is None or motion.frame is None \
            else f"{motion.link}:{motion.frame_name}"
        return [resulting_path_request(mech, pl, spec, frame_matrix=motion.frame)]
    return []


def model_with_results(model, mech, result, t, paths=()):
    """``(document, notes)``: ``model`` (the ModelFile ``mech`` was read from) with the
    analysis ``result`` (a :class:`~p105cli.kinematics.solver.MotionResult` or
    :class:`~p105cli.kinematics.solver.PathResult`: ``Q``, ``status``, ``plan``) at parameters ``t`` added (:func:`add_results`); a ValueError
    names what cannot be written."""
    return add_results(model, mech, result.Q, t, result.status, paths=paths, pl=result.plan)


def _length_of_context(mf, ctx_id, default: float) -> float:
    from p105cli.schema.units import LENGTH
    try:
        f = mf.context_units(ctx_id).factor(LENGTH) if ctx_id is not None else None
    except Exception:  # noqa: BLE001 - a context without usable units: the mechanism's own
        f = None
    return f or default


def _link_representation(mf, mech, link) -> int:
    """The representation of ``link`` (as :func:`p105cli.part105.layout.link_reps` finds them),
    preferring the one that holds the link's pair frames."""
    from .layout import link_reps

    lid = mech.link(link).id
    if lid is None or lid not in mf:
        raise ValueError(f"link {link!r} has no instance in the model; cannot tie a path to it")
    if mf.is_a(lid, "kinematic_link_representation"):
        return lid
    reps = link_reps(mf, lid)
    if not reps:
        raise ValueError(f"link {link!r} has no link representation; cannot tie a path to it")
    frames = {p.ids.get("frame_1") for p in mech.pairs if p.link1 == link} | \
             {p.ids.get("frame_2") for p in mech.pairs if p.link2 == link}
    for r in reps:
        if frames & set(mf.refs(r, "items")):
            return r
    return reps[0]


def _frame_item(mf, mech, rp, rep_id, by_id, data, new):
    """The placement item of link representation ``#rep_id`` that is ``rp``'s frame: the item of
    that name, else one at the same placement (axis2_placement_3d), else a new axis2_placement_3d
    added to the representation's items (a link frame that no item places yet)."""
    from .geometry import placement_from_instance

    placements = [i for i in mf.refs(rep_id, "items") if mf.is_a(i, "placement")]
    if rp.frame is not None:
        for i in placements:
            n = mf.get(i, "name", None) or ""
            if rp.frame in (n, f"{n} #{i}", f"#{i}"):
                return i
    lf = _length_of_context(mf, mf.ref(rep_id, "context_of_items"), mech.units.length)
    tol = 1e-9 * max(1.0, mech.size())
    for i in placements:
        if not mf.is_a(i, "axis2_placement_3d"):
            continue
        try:
            T = placement_from_instance(mf.pop, mf.pop.instance(i), lf)
        except Exception:  # noqa: BLE001 - an item that is no usable placement is not the frame
            continue
        if np.abs(T - rp.T_link_frame).max() <= tol:
            return i
    label = rp.frame or f"{rp.link} link frame"
    ref = _axis2(new, rp.T_link_frame, lf, label)
    rec = by_id[rep_id]  # as written so far (an earlier path may have added an item)
    k = next(n for n, r in enumerate(data) if r is rec)
    lay = mf.pop.instance(rep_id).layout
    slot = lay.slots[lay.by_name["items"][0]]
    if "complex" in rec:
        parts = [dict(p) for p in rec["complex"]]
        args = parts[slot.part]["args"] = list(parts[slot.part]["args"])
        new_rec = {**rec, "complex": parts}
    else:
        args = list(rec["args"])
        new_rec = {**rec, "args": args}
    args[slot.pos] = [*args[slot.pos], ref]
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


def _model_file(doc, mech, data):
    """The model, typed, over the records already decoded (``data``, as the model has them
    before any is changed: none is decoded twice); lenient access."""
    from p105cli.schema.population import Population
    from p105cli.schema.profiles import profile_for_header

    from .model_file import ModelFile

    pop = Population(list(data), mech.profile or profile_for_header(getattr(doc, "header", {}) or {}))
    return ModelFile(pop, lenient=True)


def _paths_ap242(mf, mech, paths, world, link_index, ts, ctx, by_id, new, data) -> list:
    """AP242 resulting paths (refs): per request a kinematic_path_defined_by_nodes of the frame's
    world placements at the configurations, point to point, in the sequence's parameter context."""
    lf = _length_of_context(mf, mf.ref(mech.ids["mechanism"], "context_of_items"), mech.units.length)
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
        rep_id = _link_representation(mf, mech, rp.link)
        frame = _frame_item(mf, mech, rp, rep_id, by_id, data, new)
        lmt = new("link_motion_transformation", [f"{label} motion", None, {"ref": frame}, kpath])
        new("link_motion_relationship", [f"{label} motion", None, {"ref": rep_id}, path, lmt])
        out.append(path)
    return out


def _paths_1996(mf, mech, paths, world, link_index, by_id, new, data) -> list:
    """1996 resulting paths (refs): a motion_link_relationship subtype from a founded_kinematic_path
    (a bare kinematic_path: AP214 has no path geometry) in the world context to the link frame."""
    world_ctx = None
    bp = mech.ids.get("base_placement")
    if bp in mf:
        ground = mf.ref(bp, "rep_1")
        if ground in mf:
            world_ctx = mf.ref(ground, "context_of_items")
    out = []
    for rp in paths:
        rep_id = _link_representation(mf, mech, rp.link)
        if world_ctx is None:  # no base placement: the world is the base link's frame
            world_ctx = mf.ref(_link_representation(mf, mech, mech.base), "context_of_items")
        label = _label(rp)
        frame = _frame_item(mf, mech, rp, rep_id, by_id, data, new)
        kpath = new("kinematic_path", [f"{label} resulting path"])
        founded = new("founded_kinematic_path", [f"{label} resulting path", [kpath], {"ref": world_ctx}])
        joints = [{"ref": mech.pair(n).ids["joint"]} for n in rp.pairs]
        out.append(new("resulting_path", [f"{label} resulting path", None, founded, {"ref": rep_id},
                                          {"ref": frame}, joints]))
    return out
