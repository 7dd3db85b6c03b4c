"""Read mechanisms from a Part 21 / p105/1 JSON model into the schema-neutral model.

The file is read through :class:`~p105cli.part105.model_file.ModelFile` (profile chosen once,
population built once), its topology walked by :mod:`p105cli.part105.layout` (which also
names links and pairs) and its pair values read by :mod:`p105cli.part105.pair_values`.

``read_mechanisms(doc, profile=None) -> list[Mechanism]`` builds one
:class:`~p105cli.kinematics.model.Mechanism` per mechanism of the file
(1996 layout: ``mechanism``; AP242 layout: ``mechanism_representation``),
in file order; ``read_mechanism(doc, profile=None, name=None)`` returns the
only one, or the one called ``name``. ``doc`` is what
:func:`p105cli.cli.inputs.load_document` gives (a ``StepFile`` or a
``JsonDocument``), a :class:`~p105cli.schema.population.Population` or a
:class:`~p105cli.part105.model_file.ModelFile`.
The profile (``"ap214"``, ``"p105"``, ``"ap242"``) comes from FILE_SCHEMA
unless given; a file whose FILE_SCHEMA says AP214 but that holds
``su_parameters`` is read with the ``p105`` profile (AP214's long form
lacks the entity, ISO 10303-105:1996 has it).

What is read, per layout (docs/model.md has the full mapping):

===================  =================================  ==================================
model                1996 layout (ap214, p105)          AP242 layout
===================  =================================  ==================================
mechanism            ``mechanism``                      ``mechanism_representation``
name                 id of the product whose            its ``name``
                     kinematic property it is, else
                     ``#id``
link                 ``kinematic_link`` (no name: the   ``kinematic_link`` (its name, else
                     link representation's name, else   the representation's, else
                     ``#id``); representation through   ``#id``); ``rigid_link_representation``
                     ``kinematic_link_representation_   (``represented_link``)
                     relation``
pair, joint          the structure's joints, each with  the representation's
                     the one pair whose ``joint`` it    ``pair_representation_relationship``
                     is; ``first_link``/``second_link``  items; ``edge_start``/``edge_end``
pair frames          ``transform_item_1/2``: axis2_placement_3d or su_parameters, in the
                     link representation's context (length and plane-angle unit)
range                separate ``*_pair_range``          ``*_pair_with_range`` subtypes
                     (``UNLIMITED_RANGE`` = None)       (``$`` = None)
actuation            ``pair_actuator``                  ``actuated_kinematic_pair``
base, placement      ``mechanism.base``,                ``kinematic_property_mechanism_
                     ``mechanism_base_placement``       representation.base``; placement
                     (a cartesian transformation        from the assembly that places the
                     operator in the ground's           base link's product (identity when
                     context)                           there is none)
initial state        ``initial_state.pair_values``      ``mechanism_state_representation``
                                                        named "initial..." (else the first)
===================  =================================  ==================================

Pair parameters are SI (``pitch``, ``radius_first_link``, ``gear_ratio``,
``pinion_radius``, ``input_skew_angle``, ``layout`` of prismatic pairs,
the flags of AP242's generic low-order pair, and ``su_1``/``su_2``: the
frames' Sheth-Uicker parameters when the file gives them so). Higher pairs
carry their curves/surfaces (read by :mod:`p105cli.part105.geometry`)
in the coordinates of the pair frame they belong to (``curve``,
``surface``, ``curve_1``/``curve_2``, ``surface_1``/``surface_2``) and
``orientation``; their point parameters are converted with the Part 42
parameter units of the curve or surface (angles on conics, ...).

Units: every length and plane angle is converted with the units of the
context it is given in (``schema.units.context_units``): pair frames in
their link representation's context; pair parameters, ranges and values in
the first link's context (``plane_angle_for_pair_in_radian`` of 5.5.7);
higher-pair geometry in the context of the representation holding it; the
base placement in the ground's (1996) or assembly's (AP242).
``Mechanism.units`` are the base link representation's units. A unit is
required only where a value of its kind is read.

docs/model.md describes the mapping in full.

Errors (a dangling reference, a pair without a joint, a unit with no SI
conversion, a degenerate placement, an unsupported pair type) raise
:class:`~p105cli.step.errors.ModelError` whose message starts with the
``#id`` of the instance at fault (``err.instance_id`` holds it).

A science module: no click here.
"""

from __future__ import annotations

import math
import re
from typing import Optional

import numpy as np

from ..kinematics import placements as pl
from ..kinematics import spatial
from ..kinematics.model import Link, Mechanism, Pair, Units
from ..kinematics.freedoms import FREEDOM_NAMES, motion_in_words
from ..kinematics.pairs import LOW_ORDER, low_order_components, named_low_order
from ..schema.model import Literal
from ..schema.values import is_true as _is_true
from ..schema.values import is_unlimited as _is_unlimited
from ..schema.values import number as _num
from ..step.errors import ModelError
from . import geometry
from . import layout as lay
from .catalogue import GENERIC_LOW_ORDER, GEOMETRY_ATTRIBUTES, HIGHER_KINDS, RANGE_ON, limit_attributes, \
    pair_kind_of_entity, range_on_values
from .model_file import ContextScale, ModelFile, model_error
from .pair_values import PairValueFormat, is_angle as _is_angle, on_curve, surface_parameter_factors

__all__ = ["read_mechanisms", "read_mechanism", "PairValueReader", "choose_mechanism"]

_GEOMETRY_ATTRS = GEOMETRY_ATTRIBUTES


def _restated(e: ModelError, default_id) -> ModelError:
    """geometry's ``#id (type): message`` as this module's ``#id: type: message``."""
    m = re.match(r"#(\d+) \(([^)]*)\): (.*)", e.message, re.S)
    if m:
        return model_error(int(m.group(1)), f"{m.group(2)}: {m.group(3)}")
    return model_error(default_id, e.message)


class _PairRead:
    """What reading one pair gives: the Pair (without its initial value), the scale of its
    values (the first link's context) and its geometry."""

    def __init__(self, pair: Pair, scale: ContextScale, geometry: dict):
        self.pair, self.scale, self.geometry = pair, scale, geometry


class _Reader:
    def __init__(self, mf: ModelFile):
        self.d = mf
        self.profile = mf.profile
        self.layout = mf.layout
        self.values = PairValueFormat(mf)
        # pair instance id -> _PairRead, shared by every reader of this file
        self.pairs_by_id: dict = mf.cached("read_mechanism.pairs", dict)

    def mechanisms(self) -> list:
        return [self._build(ml) for ml in lay.mechanisms(self.d)]

    # ---------------------------------------------------------------- pairs
    def pair(self, pl_: lay.PairLayout) -> _PairRead:
        """The pair ``pl_`` read once per file."""
        got = self.pairs_by_id.get(pl_.id)
        if got is None:
            got = self.pairs_by_id[pl_.id] = self._pair(pl_)
        return got

    def _pair(self, pl_: lay.PairLayout) -> _PairRead:
        d = self.d
        p = pl_.id
        kind, entity = self._pair_kind(p)
        generic = entity in GENERIC_LOW_ORDER and kind != "low_order"  # a named pair's flags
        f1, f2 = pl_.frame_1, pl_.frame_2
        s1, s2 = d.scale(pl_.rep_1), d.scale(pl_.rep_2)
        P1 = d.placement(f1, s1)
        P2 = d.placement(f2, s2)
        ids = {"pair": p, "joint": pl_.joint, "frame_1": f1, "frame_2": f2}
        if pl_.range is not None and pl_.range != p:
            ids["range"] = pl_.range
        if pl_.actuator is not None:
            ids["actuator"] = pl_.actuator
        if pl_.relationship is not None:
            ids["relationship"] = pl_.relationship
        if self.layout == "ap242":
            self._explicit_derived(p, entity)
        params = self._params(p, kind, s1, generic)
        for key, f, sc in (("su_1", f1, s1), ("su_2", f2, s2)):
            if d.is_a(f, "su_parameters"):  # kept so that a writer can give the frame back as written
                params[key] = d.su(f, sc)
        geometry = {}
        if kind in HIGHER_KINDS:
            geometry = self._higher_geometry(p, kind, (P1, P2), (pl_.rep_1, pl_.rep_2), ids)
            params.update({k: obj for k, (obj, _scale, _inst) in geometry.items()})
            if "orientation" in d.names(p):
                params["orientation"] = _is_true(d.get(p, "orientation"))
        lower = upper = ()
        if pl_.range is not None:
            lower, upper = self._limits(pl_.range, kind, s1, geometry,
                                        self._generic_names(kind) if generic else None)
        ordered = {k: ids[k] for k in ("pair", "joint", "frame_1", "frame_2", "curve", "surface", "curve_1",
                                       "curve_2", "surface_1", "surface_2", "range", "actuator",
                                       "relationship") if k in ids}
        pair = Pair(pl_.name, kind, "", "", P1, P2, params=params, lower=lower, upper=upper,
                    actuated=pl_.actuated, joint=pl_.joint_name or pl_.name,
                    description=pl_.description, ids=ordered)
        return _PairRead(pair, s1, geometry)

    def _link_description(self, rep) -> str:
        """The description of the product whose shape the link representation is associated
        with (kinematic_link_representation_association -> shape -> product), else ''. A label
        only: an incomplete chain gives ''."""
        d = self.d
        try:
            for assoc in d.usedin(rep, "representation_relationship.rep_1"):
                if not d.is_a(assoc, "kinematic_link_representation_association"):
                    continue
                shape = d.ref(assoc, "rep_2", optional=True)
                for sdr in d.usedin(shape, "property_definition_representation.used_representation"):
                    pds = d.ref(sdr, "definition", optional=True)
                    pd = d.ref(pds, "definition", optional=True) if pds is not None else None
                    if pd is None or not d.is_a(pd, "product_definition"):
                        continue
                    pdf = d.ref(pd, "formation", optional=True)
                    prod = d.ref(pdf, "of_product", optional=True) if pdf is not None else None
                    text = (d.string(prod, "description") if prod is not None else "") or \
                        d.string(pd, "description")
                    if text:
                        return text
        except ModelError:
            return ""
        return ""

    def _pair_kind(self, p) -> tuple:
        d = self.d
        names = sorted(n for n in d.leaf_types(p) if n != "actuated_kinematic_pair")
        for n in names:
            k = pair_kind_of_entity(n)
            if k == "low_order":  # AP242's generic pair: its flags say which pair it is
                k = named_low_order(self._flags(p)) or k
            if k is not None:
                return k, n
        # a supertype name that is a pair (e.g. an instance of a subtype we do not know)
        shown = "+".join(names) or "kinematic_pair"
        raise model_error(p, f"{shown}: this pair type is not supported by the kinematics model "
                     "(see docs/model.md)")

    def _explicit_derived(self, p, entity) -> None:
        """Lenient reading: the freedom flags and the transformation's name of an AP242 pair,
        which AP242 derives (``*``), written explicitly (Open CASCADE's and build123d's writers
        do). The pair moves as its entity says; one deviation names what the file writes, and
        says plainly where it contradicts the standard (the DERIVE clauses of the schema)."""
        d = self.d
        written = []
        conflicts = []
        derived = _derived_flags(d.schema, entity)
        if derived is not None:
            raw = [d.get(p, f"low_order_kinematic_pair.{f}", None) for f in FREEDOM_NAMES]
            if any(v is not None and not (type(v) is dict and v.get("derived")) for v in raw):
                written.append("the freedom flags t_x .. r_z")
                says = tuple(_is_true(v) for v in raw)
                if says != derived:
                    conflicts.append(_motion_conflict(says, derived, entity))
        name = d.get(p, "item_defined_transformation.name", None)
        if isinstance(name, str):
            written.append("item_defined_transformation.name")
            own = d.string(p, "representation_item.name")
            if name != own:
                conflicts.append(f"the file names its transformation {name!r}, AP242 derives the pair's own "
                                 f"name {own!r}")
        if written:
            if conflicts:
                d.deviation(p, f"{d.label(p)} writes {' and '.join(written)} where AP242 derives them, and "
                            f"contradicts the derivation: {'; '.join(conflicts)} (read as AP242 derives)")
            else:
                d.deviation(p, f"{d.label(p)} writes {' and '.join(written)} where AP242 derives them (*); "
                            "the values agree with the derivation (read anyway)")

    def _flags(self, p) -> tuple:
        """The freedom flags (t_x, ..., r_z) of a generic low_order_kinematic_pair."""
        return tuple(_is_true(self.d.get(p, f"low_order_kinematic_pair.{f}")) for f in FREEDOM_NAMES)

    def _generic_names(self, kind) -> tuple:
        """The generic low-order value (and limit) names that give a ``kind`` pair's values."""
        return tuple(LOW_ORDER.value_names[c] for c in low_order_components(kind, self.layout))

    def _params(self, p, kind, s: ContextScale, generic: bool = False) -> dict:
        d = self.d
        out: dict = {}
        if generic:  # a generic pair read as the named pair of its flags: no attributes of its own
            if kind in ("universal", "homokinetic"):
                out["input_skew_angle"] = None
            elif kind == "prismatic":
                out["layout"] = self.layout
            return out
        if kind == "prismatic":
            out["layout"] = self.layout
        elif kind == "screw":
            out["pitch"] = d.number(p, "pitch") * s.length
        elif kind == "gear":
            out["radius_first_link"] = d.number(p, "radius_first_link") * s.length
            out["radius_second_link"] = d.number(p, "radius_second_link") * s.length
            for a in ("bevel", "helical_angle"):
                x = d.number(p, a, optional=True)
                out[a] = 0.0 if x is None else x * s.angle
            out["gear_ratio"] = d.number(p, "gear_ratio")
        elif kind == "rack_and_pinion":
            out["pinion_radius"] = d.number(p, "pinion_radius") * s.length
        elif kind == "low_order":  # AP242's generic pair: which of its six freedoms are free
            out.update(zip(FREEDOM_NAMES, self._flags(p)))
        elif kind in ("universal", "homokinetic"):
            x = d.number(p, "input_skew_angle", optional=True)
            out["input_skew_angle"] = None if x is None else x * s.angle
        return out

    def _limits(self, holder, kind, s: ContextScale, geometry: dict, limit_names=None) -> tuple:
        """Per value (lower, upper) limits; ``limit_names``: the value names whose limit
        attributes bound them, when not the kind's own (a generic low-order pair's)."""
        from ..kinematics.pairs import PAIR_KINDS

        d = self.d
        names = set(d.pop.instance(holder).explicit_names())
        t = PAIR_KINDS.get(kind)
        value_names = t.value_names if t is not None else ()
        on = {}  # value name -> (lower, upper) from a trimmed curve / surface
        for attr, spec in RANGE_ON.items():
            if attr not in names:
                continue
            rng = d.ref(holder, attr, optional=True)
            if rng is None:
                continue
            if spec.geometry not in geometry:
                continue
            for vname, lim in zip(range_on_values(attr, kind),
                                  self._parameter_range(holder, attr, rng, geometry[spec.geometry])):
                on[vname] = lim
        lower, upper = [], []
        for v, bounded in zip(value_names, limit_names or value_names):
            lo = hi = None
            if v in on:
                lo, hi = on[v]
            ab = limit_attributes(bounded)
            if ab is not None and ab[0] in names and ab[1] in names:
                f = s.angle if _is_angle(bounded) else s.length
                lo = self._limit(holder, ab[0], f)
                hi = self._limit(holder, ab[1], f)
            lower.append(lo)
            upper.append(hi)
        return tuple(lower), tuple(upper)

    def _limit(self, holder, attr, factor: float) -> Optional[float]:
        raw = self.d.get(holder, attr)
        if _is_unlimited(raw):
            return None
        x = _num(raw)
        if x is None or not math.isfinite(x):
            raise model_error(holder, f"{attr} is {raw!r}, not a finite number or UNLIMITED")
        return x * factor

    def _higher_geometry(self, p, kind, frames, reps, ids) -> dict:
        """``{params key: (geometry object in its pair frame, scale of its context, instance id)}``
        for the curves/surfaces of a higher pair."""
        d = self.d
        out: dict = {}
        names = d.pop.instance(p).explicit_names()
        gs = geometry
        for attr, (key, which) in _GEOMETRY_ATTRS.items():
            if attr not in names:
                continue
            g = d.ref(p, attr)
            ids[key] = g
            holder_rep, T_link_geom = self._geometry_placement(g, reps[which - 1], frames[which - 1])
            s = d.scale(holder_rep)
            T_pair_geom = spatial.inverse(frames[which - 1]) @ T_link_geom
            fn = gs.surface_from_instance if "surface" in key else gs.curve_from_instance
            try:
                obj = fn(d.pop, d.pop.instance(g), s.length, s.angle)
            except ModelError as e:
                raise _restated(e, g) from None
            out[key] = (obj.transformed(T_pair_geom), s, g)
        return out

    # point parameters: Part 42 parameterises conics (and the angular parameters of
    # surfaces of revolution) by plane angle, planes and the axial parameter of cylinders
    # and cones by length; lines, polylines and B-splines are dimensionless

    def _parameter_range(self, holder, attr, rng, entry) -> list:
        """[(lower, upper), ...] of the point parameter(s) a trimmed curve or rectangular
        trimmed surface range allows (a full turn of a periodic parameter: unlimited)."""
        d = self.d
        obj, s, g = entry
        if d.is_a(rng, "trimmed_curve"):
            basis = d.ref(rng, "basis_curve")
            allowed = {g} | ({d.ref(g, "basis_curve")} if d.is_a(g, "trimmed_curve") else set())
            if basis not in allowed:
                raise model_error(holder, f"{attr} #{rng} trims #{basis}, not the pair's curve #{g}")
            gs = geometry
            try:
                tc = gs.curve_from_instance(d.pop, d.pop.instance(rng), s.length, s.angle)
            except ModelError as e:
                raise _restated(e, rng) from None
            per = getattr(tc.basis, "period", None)
            span = tc.bounds[1]
            if per and span >= per * (1.0 - 1e-12):
                return [(None, None)]
            # the range runs from trim_1 along the basis in its sense; the pair curve's own
            # parameter runs along the basis too, or against it for a trimmed pair curve
            sign = 1.0 if tc.sense else -1.0
            if getattr(obj, "sense", True) is False:
                sign = -sign
            a = on_curve(tc.trim_1, obj)
            b = a + sign * span
            return [(min(a, b), max(a, b))]
        if d.is_a(rng, "rectangular_trimmed_surface"):
            if d.ref(rng, "basis_surface") != g:
                raise model_error(holder, f"{attr} #{rng} trims another surface than the pair's #{g}")
            fu, fv = surface_parameter_factors(d, g, s)
            u = sorted((d.number(rng, "u1") * fu, d.number(rng, "u2") * fu))
            v = sorted((d.number(rng, "v1") * fv, d.number(rng, "v2") * fv))
            return [tuple(u), tuple(v)]
        raise model_error(holder, f"{attr} #{rng} is no trimmed_curve or rectangular_trimmed_surface")

    def _geometry_placement(self, g, link_rep, frame_T) -> tuple:
        """(representation whose context gives g's units, T_link_geometry): the link
        representation itself, or a frame background representation associated to a frame
        of the link (1996)."""
        d = self.d
        for r in d.usedin(g, "representation.items"):
            if r == link_rep:
                return r, np.eye(4)
            if d.is_a(r, "kinematic_frame_background_representation"):
                for assoc in d.usedin(r, "representation_relationship.rep_2"):
                    if not d.is_a(assoc, "kinematic_frame_background_representation_association"):
                        continue
                    if d.ref(assoc, "rep_1") != link_rep:
                        continue
                    kfbt = d.ref(assoc, "transformation_operator")
                    X = d.ref(kfbt, "transformator")
                    return r, d.placement(X, d.scale(link_rep))
        return link_rep, np.eye(4)

    # ---------------------------------------------------------------- assembling
    def _build(self, ml: lay.MechanismLayout) -> Mechanism:
        d = self.d
        names = ml.link_names
        links = []
        for link in ml.link_order:
            rep = ml.links[link]
            frames = {}
            if rep is not None:
                s = d.scale(rep)
                for fname, i in lay.link_frames(d, ml, link).items():
                    frames[fname] = d.placement(i, s)
            links.append(Link(names[link], id=link, frames=frames,
                              description=self._link_description(rep) if rep is not None else ""))
        pairs = []
        initial = {}
        for pl_ in ml.pairs:
            r = self.pair(pl_)
            p = r.pair
            pair = Pair(p.name, p.kind, names[pl_.link1], names[pl_.link2], p.P1, p.P2, params=p.params,
                        lower=p.lower, upper=p.upper, actuated=p.actuated, joint=p.joint,
                        description=p.description, ids=p.ids)
            v = ml.values.get(pl_.id)
            if v is not None:
                initial[pair.name] = self.values.read(v, pair, r.scale, r.geometry)
                pair = Pair(pair.name, pair.kind, pair.link1, pair.link2, pair.P1, pair.P2,
                            params=pair.params, lower=pair.lower, upper=pair.upper,
                            actuated=pair.actuated, joint=pair.joint, description=pair.description,
                            ids={**pair.ids, "value": v})
            pairs.append(pair)
        T_world_base = np.eye(4)
        if ml.base_placement is not None:
            op, r1, r2 = ml.base_placement
            if d.is_a(op, "item_defined_transformation"):
                T_world_base = d.item_defined_transformation(op, d.scale(r1), d.scale(r2))
            else:
                T_world_base = d.placement(op, d.scale(r2))
        base_rep = ml.links.get(ml.base)
        units = d.scale(base_rep).units() if base_rep is not None else Units()
        return Mechanism(ml.name, links, pairs, names[ml.base], T_world_base=T_world_base,
                         initial=initial, units=units, profile=self.profile,
                         description=ml.description, ids=dict(ml.ids))


def _derived_flags(schema, entity: str) -> Optional[tuple]:
    """The freedom flags (t_x .. r_z) the schema's DERIVE clauses give ``entity`` (its own or a
    supertype's), None when it derives none (the generic low_order_kinematic_pair states them)."""
    found: dict = {}
    todo, seen = [entity], set()
    while todo:
        e = schema.entities.get(todo.pop(0))
        if e is None or e.name in seen:
            continue
        seen.add(e.name)
        for a in e.derived:
            if a.supertype == "low_order_kinematic_pair" and isinstance(a.expr, Literal):
                found.setdefault(a.name, a.expr.value is True)  # the most specific clause wins
        todo.extend(e.supertypes)
    return tuple(found[f] for f in FREEDOM_NAMES) if all(f in found for f in FREEDOM_NAMES) else None


def _motion_conflict(says: tuple, derived: tuple, entity: str) -> str:
    """What the file's flags say against what AP242 derives, in the domain's words."""
    if sum(says) == sum(derived) == 1 and not any(says[3:]) and not any(derived[3:]):
        return (f"file says the slider moves along {'xyz'[says.index(1)]}; AP242 derives "
                f"{'xyz'[derived.index(1)]} for a {entity}")
    return f"file says the pair allows {motion_in_words(says)}; AP242 derives {motion_in_words(derived)} for a {entity}"


# --------------------------------------------------------------------------- entry points

def read_mechanisms(doc, profile: str | None = None) -> list:
    """Every mechanism of ``doc`` as a :class:`~p105cli.kinematics.model.Mechanism`, in file order.

    ``doc``: a StepFile, JsonDocument, Population or ModelFile; ``profile``: ``"ap214"``,
    ``"p105"``, ``"ap242"`` or None (from FILE_SCHEMA). Raises ModelError
    (message starting with the ``#id`` at fault) for a model that cannot be
    read, :class:`~p105cli.schema.profiles.UnknownSchemaError` for an unknown
    schema."""
    mf = ModelFile.of(doc, profile)
    try:
        return _Reader(mf).mechanisms()
    except ModelError as e:
        e.source = getattr(doc, "source", None) or e.source
        raise


class PairValueReader:
    """Reads ``*_pair_value`` instances of a model (configurations of its motion program or
    analysis results) in SI, keyed by THE pair names (:mod:`p105cli.part105.layout`, the
    names :func:`read_mechanisms` gives). Reads only the pairs the values apply to."""

    def __init__(self, doc, profile: str | None = None):
        self.mf = ModelFile.of(doc, profile)
        self._reader = _Reader(self.mf)
        self._layouts = {p.id: p for ml in lay.mechanisms(self.mf) for p in ml.pairs}

    @property
    def kinds(self) -> dict:
        """``{pair name: pair kind}`` of every pair of every mechanism."""
        return {p.name: self._reader._pair_kind(p.id)[0] for p in self._layouts.values()}

    def values(self, value_ids) -> dict:
        """``{pair name: values}`` of the pair value instances ``value_ids``."""
        d = self.mf
        out = {}
        for v in value_ids:
            p = d.ref(v, "applies_to_pair", types=("kinematic_pair",))
            pl_ = self._layouts.get(p)
            if pl_ is None:
                raise model_error(v, f"applies to pair #{p}, which belongs to no mechanism of the file")
            r = self._reader.pair(pl_)
            out[pl_.name] = self._reader.values.read(v, r.pair, r.scale, r.geometry)
        return out


def read_mechanism(doc, profile: str | None = None, name: str | None = None) -> Mechanism:
    """The one mechanism of ``doc``, or the one called ``name``; ModelError otherwise."""
    mechs = read_mechanisms(doc, profile)
    try:
        return choose_mechanism(mechs, name)
    except ModelError as e:
        e.source = getattr(doc, "source", None) or e.source
        raise


def choose_mechanism(mechs: list, name: Optional[str]) -> Mechanism:
    """The one of ``mechs``, or the one called ``name``; ModelError otherwise."""
    if name is not None:
        found = [m for m in mechs if m.name == name]
        if len(found) == 1:
            return found[0]
        known = ", ".join(repr(m.name) for m in mechs) or "none"
        if not found:
            raise model_error(None, f"no mechanism named {name!r} (the file has: {known})")
        raise model_error(None, f"{len(found)} mechanisms are named {name!r}")
    if not mechs:
        raise model_error(None, "the file has no mechanism (1996 layout: mechanism; AP242: "
                          "mechanism_representation)")
    if len(mechs) > 1:
        raise model_error(None, f"the file has {len(mechs)} mechanisms ("
                          + ", ".join(repr(m.name) for m in mechs) + "); choose one by name")
    return mechs[0]
