"""Read mechanisms from a Part 21 / p105/1 JSON model into the schema-neutral model.

``read_mechanisms(doc, profile=None) -> list[Mechanism]`` builds one
:class:`~p105cli.kinematics.model.Mechanism` per mechanism of the file
(1996 layout: ``mechanism``; AP242 layout: ``mechanism_representation``),
in file order; ``read_mechanism(doc, profile=None, name=None)`` returns the
only one, or the one called ``name``. ``doc`` is what
:func:`p105cli.cli.contract.load_document` gives (a ``StepFile`` or a
``JsonDocument``) or a :class:`~p105cli.schema.population.Population`.
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
carry their curves/surfaces (read by :mod:`p105cli.kinematics.geometry_step`)
in the coordinates of the pair frame they belong to (``curve``,
``surface``, ``curve_1``/``curve_2``, ``surface_1``/``surface_2``) and
``orientation``; their point parameters are converted with the Part 42
parameter units of the curve or surface (angles on conics, ...).

Units: every length and plane angle is converted with the units of the
context it is given in (``rules.kinematics.context_units``): pair frames in
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

from ..part105.catalogue import GEOMETRY_ATTRIBUTES as _GEOMETRY_ATTRS
from ..part105.catalogue import HIGHER_KINDS as _HIGHER_KINDS
from ..part105.catalogue import HIGHER_PAIR_ENTITIES, RANGE_ON, limit_attributes, pair_kind_of_entity, range_on_values
from ..schema.units import ANGLE, LENGTH, ContextUnits, context_units
# one reading of typed values, references and unlimited limits, shared with the KIN-* checks
from ..schema.values import is_true as _is_true
from ..schema.values import is_unlimited as _is_unlimited
from ..schema.values import number as _num
from ..schema.values import ref as _ref
from ..schema.values import untyped as _untyped
from ..step.errors import ModelError
from . import placements as pl
from .model import Link, Mechanism, Pair, Units

__all__ = ["read_mechanisms", "read_mechanism", "PairValueReader", "population", "HIGHER_PAIR_ENTITIES",
           "pair_kind_of_entity"]

_MISSING = object()


def _error(iid, message: str) -> ModelError:
    err = ModelError(f"#{iid}: {message}" if iid is not None else message)
    err.instance_id = iid
    return err


def _restated(e: ModelError, default_id) -> ModelError:
    """geometry_step's ``#id (type): message`` as this module's ``#id: type: message``."""
    m = re.match(r"#(\d+) \(([^)]*)\): (.*)", e.message, re.S)
    if m:
        return _error(int(m.group(1)), f"{m.group(2)}: {m.group(3)}")
    return _error(default_id, e.message)


def _is_angle(value_name: str) -> bool:
    from .pairs import VALUE_UNITS

    return VALUE_UNITS[value_name] == "A"


# --------------------------------------------------------------------------- units of a context

class _Scale:
    """SI factors of one representation's context; a missing unit is an error
    only when a value of its kind is read."""

    _WORDS = {LENGTH: "length", ANGLE: "plane-angle"}

    def __init__(self, rd: "_Doc", rep: Optional[int]):
        self.rep = rep
        self.ctx = rd.ref(rep, "context_of_items") if rep is not None else None
        self.cu = rd.context_units(self.ctx)
        self._length = self._angle = None

    def _factor(self, kind) -> float:
        cu = self.cu
        u = cu.unit(kind)
        if u is not None:
            return float(u[0])
        word = self._WORDS[kind]
        if self.rep is None:
            raise _error(None, f"no representation gives the {word} unit")
        if self.ctx is None:
            raise _error(self.rep, f"representation has no context: its {word} unit is unknown")
        for _sev, ent, msg in cu.problems:
            if word in msg:
                raise _error(ent, msg)
        if not cu.assigned:
            raise _error(self.ctx, f"context is no global_unit_assigned_context: it gives no {word} "
                         f"unit to representation #{self.rep} (ISO 10303-105 5.2.5)")
        raise _error(self.ctx, f"context assigns no {word} unit, but representation #{self.rep} "
                     f"has {word} values (ISO 10303-105 5.2.5)")

    @property
    def length(self) -> float:
        if self._length is None:
            self._length = self._factor(LENGTH)
        return self._length

    @property
    def angle(self) -> float:
        if self._angle is None:
            self._angle = self._factor(ANGLE)
        return self._angle

    def units(self) -> Units:
        """The model's Units of this context (SI for a kind it does not give)."""
        lu, au = self.cu.length, self.cu.angle
        return Units(length=float(lu[0]) if lu else 1.0, angle=float(au[0]) if au else 1.0,
                     length_name=lu[1] if lu else "metre", angle_name=au[1] if au else "radian")


# --------------------------------------------------------------------------- the population

class _Doc:
    """Checked access to a Population: every reference is resolved or reported."""

    def __init__(self, pop):
        self.pop = pop
        self.schema = pop.schema
        self._units: dict = {}
        self._scales: dict = {}

    # ---------------------------------------------------------------- basics
    def types(self, i) -> frozenset:
        try:
            return self.pop.types_of(i)
        except KeyError:
            return frozenset()

    def is_a(self, i, *names) -> bool:
        t = self.types(i)
        return any(n in t for n in names)

    def leaf_types(self, i) -> frozenset:
        return self.pop.leaf_types_of(i)

    def label(self, i) -> str:
        return "+".join(sorted(self.leaf_types(i)))

    def get(self, i, attr, default=_MISSING):
        """The raw value of explicit attribute ``attr`` of ``#i``."""
        try:
            inst = self.pop.instance(i)
        except KeyError:
            raise _error(i, "instance is not in the file") from None
        try:
            return inst.get(attr)
        except Exception:  # noqa: BLE001 - no such attribute for this instance's types
            if default is not _MISSING:
                return default
            raise _error(i, f"{self.label(i)} has no attribute {attr!r}") from None

    def ref(self, i, attr, *, optional: bool = False, types=None) -> Optional[int]:
        """The id ``#i.attr`` refers to; a ModelError naming ``#i`` when it is unset
        (unless ``optional``), dangling, or not of one of ``types``."""
        v = self.get(i, attr)
        if v is None or (type(v) is dict and v.get("derived")):
            if optional:
                return None
            raise _error(i, f"{self.label(i)} has no {attr} (it is unset)")
        r = _ref(v)
        if r is None:
            raise _error(i, f"{attr} of {self.label(i)} is not a reference")
        if r not in self.pop:
            raise _error(i, f"{attr} of {self.label(i)} refers to #{r}, which is not in the file")
        if types and not self.is_a(r, *types):
            raise _error(i, f"{attr} of {self.label(i)} refers to #{r} ({self.label(r)}), which is "
                         f"no {' or '.join(types)}")
        return r

    def refs(self, i, attr, *, types=None) -> list:
        """The ids of the aggregate attribute ``#i.attr`` (each checked like :meth:`ref`)."""
        v = _untyped(self.get(i, attr))
        if v is None:
            return []
        if type(v) is not list:
            raise _error(i, f"{attr} of {self.label(i)} is not a list")
        out = []
        for x in v:
            r = _ref(x)
            if r is None:
                raise _error(i, f"{attr} of {self.label(i)} holds {x!r}, not a reference")
            if r not in self.pop:
                raise _error(i, f"{attr} of {self.label(i)} refers to #{r}, which is not in the file")
            if types and not self.is_a(r, *types):
                raise _error(i, f"{attr} of {self.label(i)} refers to #{r} ({self.label(r)}), which "
                             f"is no {' or '.join(types)}")
            out.append(r)
        return out

    def number(self, i, attr, *, optional: bool = False) -> Optional[float]:
        v = self.get(i, attr)
        if v is None and optional:
            return None
        x = _num(v)
        if x is None or not math.isfinite(x):
            raise _error(i, f"{attr} of {self.label(i)} is {v!r}, not a finite number")
        return x

    def string(self, i, *attrs) -> str:
        """The first of ``attrs`` that is a string (derived and unset ones skipped), else ''."""
        for a in attrs:
            v = _untyped(self.get(i, a, None))
            if isinstance(v, str):
                return v
        return ""

    def usedin(self, i, role: str) -> list:
        """Ids of the instances referring to ``#i`` through ``role`` (entity.attribute), in file order."""
        ent = role.split(".")[0]
        if ent not in self.schema.entities:
            return []
        return [inst.id for inst in self.pop.usedin(i, role)]

    def ids_of_type(self, entity: str) -> list:
        if entity not in self.schema.entities:
            return []
        return self.pop.ids_of_type(entity)

    # ---------------------------------------------------------------- units
    def context_units(self, ctx):
        cu = self._units.get(ctx)
        if cu is None:
            cu = context_units(self.pop, ctx) if ctx is not None else ContextUnits(None)
            self._units[ctx] = cu
        return cu

    def scale(self, rep) -> _Scale:
        s = self._scales.get(rep)
        if s is None:
            s = self._scales[rep] = _Scale(self, rep)
        return s

    # ---------------------------------------------------------------- geometry
    def vector(self, i, attr) -> list:
        v = _untyped(self.get(i, attr))
        if type(v) is not list or not v:
            raise _error(i, f"{attr} of {self.label(i)} is not a list of numbers")
        out = [_num(x) for x in v]
        if None in out or not all(math.isfinite(x) for x in out):
            raise _error(i, f"{attr} of {self.label(i)} is {v!r}, not a list of finite numbers")
        return out

    def direction(self, i, attr) -> Optional[list]:
        d = self.ref(i, attr, optional=True, types=("direction",))
        return None if d is None else self.vector(d, "direction_ratios")

    def placement(self, i, scale: _Scale) -> np.ndarray:
        """``#i`` (axis2_placement_3d, su_parameters or cartesian_transformation_operator_3d)
        as a 4x4 transform in metres; lengths and angles in ``scale``'s units."""
        t = self.types(i)
        if "su_parameters" in t and "su_parameters" not in self.schema.entities:
            raise _error(i, f"su_parameters is not part of the {self._profile_name()} profile; read "
                         "the file with profile p105 (ISO 10303-105:1996) or ap242")
        try:
            if "axis2_placement_3d" in t:
                loc = self.ref(i, "location", types=("cartesian_point",))
                xyz = self.vector(loc, "coordinates")
                if len(xyz) != 3:
                    raise _error(loc, f"location of #{i} has {len(xyz)} coordinates, not 3")
                f = scale.length
                return pl.axis2_placement_3d([c * f for c in xyz], self.direction(i, "axis"),
                                             self.direction(i, "ref_direction"))
            if "su_parameters" in t:
                return pl.su_parameters(*self.su(i, scale))
            if "cartesian_transformation_operator_3d" in t:
                return self._cto3d(i, scale)
            if "item_defined_transformation" in t:
                return self.item_defined_transformation(i, scale, scale)
        except ValueError as e:  # degenerate axes (Part 42 WR) from placements
            raise _error(i, f"{self.label(i)} is not a valid placement: {e}") from None
        raise _error(i, f"{self.label(i) or 'instance'} is not a placement (axis2_placement_3d or "
                     "su_parameters)")

    def _profile_name(self) -> str:
        p = getattr(self.pop, "profile", None)
        return getattr(p, "name", None) or str(self.schema.name)

    def su(self, i, scale: _Scale) -> tuple:
        """``(a, alpha, b, beta, c, gamma)`` of su_parameters ``#i`` in SI."""
        lf, af = scale.length, scale.angle
        a, alpha, b, beta, c, gamma = (self.number(i, n) for n in ("a", "alpha", "b", "beta", "c", "gamma"))
        return (a * lf, alpha * af, b * lf, beta * af, c * lf, gamma * af)

    def _cto3d(self, i, scale: _Scale) -> np.ndarray:
        """Part 42 ``cartesian_transformation_operator_3d`` as a rigid 4x4 (scale must be 1)."""
        axes = {a: self.direction(i, a) for a in ("axis1", "axis2", "axis3")}
        raw_scale = self.get(i, "scale", None)
        s = _num(raw_scale) if raw_scale is not None else 1.0
        if s is None or not math.isfinite(s) or abs(s - 1.0) > 1e-12:
            raise _error(i, f"scale {raw_scale!r} of the transformation operator is not 1: it is not "
                         "a rigid placement")
        R = pl.build_axes(axes["axis3"], axes["axis1"])  # Part 42 base_axis: z, then x projected
        if axes["axis2"] is not None:
            y = np.asarray(axes["axis2"], float)
            if float(R[:, 1] @ y) <= 0.0:
                raise _error(i, "axis1, axis2, axis3 are left-handed or degenerate: the operator is "
                             "not a rigid placement")
        loc = self.ref(i, "local_origin", types=("cartesian_point",))
        xyz = self.vector(loc, "coordinates")
        return pl.transform(R, [c * scale.length for c in xyz])

    def item_defined_transformation(self, i, scale1: _Scale, scale2: _Scale) -> np.ndarray:
        """``T_rep2_rep1`` of an item_defined_transformation: ``T(item_2) @ inv(T(item_1))``."""
        a = self.ref(i, "transform_item_1")
        b = self.ref(i, "transform_item_2")
        return self.placement(b, scale2) @ pl.inverse(self.placement(a, scale1))


# --------------------------------------------------------------------------- reading one mechanism

class _Mech:
    """Pieces of one mechanism collected by the layout readers, assembled by ``_Reader._build``."""

    def __init__(self, name, mid):
        self.name = name
        self.description = ""
        self.ids = {"mechanism": mid}
        self.links: dict = {}  # link id -> representation id or None (ordered)
        self.link_names: dict = {}
        self.base: Optional[int] = None
        self.T_world_base = np.eye(4)
        self.pairs: list = []  # dicts
        self.values: dict = {}  # pair id -> value id

    def add_pair(self, pair: dict) -> None:
        self.pairs.append(pair)
        for link, rep in zip((pair["link1"], pair["link2"]), pair["reps"]):
            if self.links.get(link) is None:  # the representation that holds the link's pair frames
                self.links[link] = rep


class _Reader:
    def __init__(self, pop, profile: str):
        self.d = _Doc(pop)
        self.profile = profile
        self.layout = "ap242" if profile == "ap242" else "1996"
        self._geometry_step = _MISSING
        self.pairs_by_id: dict = {}  # pair instance id -> (Pair, _Scale of its values, geometry)

    # ---------------------------------------------------------------- entry
    def mechanisms(self) -> list:
        d = self.d
        out = []
        if self.layout == "1996":
            for m in d.ids_of_type("mechanism"):
                out.append(self._read_1996(m))
        else:
            for m in d.ids_of_type("mechanism_representation"):
                out.append(self._read_ap242(m))
        return out

    # ---------------------------------------------------------------- 1996 layout
    def _read_1996(self, m) -> Mechanism:
        d = self.d
        struct = d.ref(m, "structure_definition", types=("kinematic_structure",))
        base = d.ref(m, "base", types=("kinematic_link",))
        prop = d.ref(m, "containing_property", optional=True)
        mm = _Mech(self._name_1996(m, prop), m)
        mm.ids["structure"] = struct
        if prop is not None:
            mm.ids["property"] = prop
            mm.description = d.string(prop, "description")
        mm.base = base
        mm.links[base] = None
        joints = d.refs(struct, "joints", types=("kinematic_joint",))
        for j in joints:
            pairs = d.usedin(j, "kinematic_pair.joint")
            if not pairs:
                self._no_pair(j)
            if len(pairs) > 1:
                raise _error(j, f"kinematic_joint has {len(pairs)} pairs "
                             f"({', '.join(f'#{p}' for p in pairs)}); Part 105 ties one pair to a joint")
            l1 = d.ref(j, "first_link", types=("kinematic_link",))
            l2 = d.ref(j, "second_link", types=("kinematic_link",))
            mm.add_pair(self._pair(pairs[0], j, l1, l2))
        # base placement: mechanism_base_placement (a transformation operator in the ground's context)
        for bp in d.usedin(m, "mechanism_base_placement.base_of_mechanism"):
            ground = d.ref(bp, "rep_1")
            op = d.ref(bp, "transformation_operator")
            mm.T_world_base = d.placement(op, d.scale(ground))
            mm.ids["base_placement"] = bp
            mm.ids["ground"] = ground
            break
        # initial state
        for st in d.usedin(m, "initial_state.applies_to_mechanism"):
            mm.ids["initial_state"] = st
            for v in d.refs(st, "pair_values", types=("pair_value",)):
                p = d.ref(v, "applies_to_pair", types=("kinematic_pair",))
                mm.values.setdefault(p, v)
            break
        return self._build(mm)

    def _no_pair(self, j):
        """A joint of the structure with no pair: report a pair whose joint reference is
        unset or dangling first (that is the likely cause), else the joint."""
        d = self.d
        for p in d.ids_of_type("kinematic_pair"):
            raw = d.get(p, "joint", None)
            r = _ref(raw)
            if r is None or r not in d.pop:
                d.ref(p, "joint", types=("kinematic_joint",))  # raises, naming the pair
        raise _error(j, "kinematic_joint has no kinematic_pair: its motion is unknown")

    def _name_1996(self, m, prop) -> str:
        """The id of the product whose kinematic property the mechanism is, else its name, else #id."""
        d = self.d
        if prop is not None:
            pd = d.ref(prop, "definition", optional=True)
            if pd is not None and d.is_a(pd, "product_definition"):
                pdf = d.ref(pd, "formation", optional=True)
                if pdf is not None and d.is_a(pdf, "product_definition_formation"):
                    prod = d.ref(pdf, "of_product", optional=True)
                    if prod is not None:
                        name = d.string(prod, "id") or d.string(prod, "name")
                        if name:
                            return name
        return f"#{m}"

    # ---------------------------------------------------------------- AP242 layout
    def _read_ap242(self, m) -> Mechanism:
        d = self.d
        mm = _Mech(d.string(m, "name") or f"#{m}", m)
        topo = d.ref(m, "represented_topology", optional=True)
        if topo is not None:
            mm.ids["structure"] = topo
        base_rep = None
        for kp in d.usedin(m, "kinematic_property_mechanism_representation.used_representation"):
            mm.ids["property"] = kp
            base_rep = d.ref(kp, "base", types=("kinematic_link_representation",))
            pdk = d.ref(kp, "definition", optional=True)
            if pdk is not None:
                mm.description = d.string(pdk, "description")
                mm.ids["product_definition_kinematics"] = pdk
            break
        for prr in d.refs(m, "items", types=("pair_representation_relationship",)):
            p = d.ref(prr, "transformation_operator", types=("kinematic_pair",))
            j = d.ref(p, "joint", types=("kinematic_joint",))
            l1 = d.ref(j, "edge_start", types=("kinematic_link",))
            l2 = d.ref(j, "edge_end", types=("kinematic_link",))
            rep1 = d.ref(prr, "rep_1", types=("kinematic_link_representation",))
            rep2 = d.ref(prr, "rep_2", types=("kinematic_link_representation",))
            pair = self._pair(p, j, l1, l2, reps=(rep1, rep2))
            pair["ids"]["relationship"] = prr
            mm.add_pair(pair)
        if topo is not None and d.is_a(topo, "kinematic_topology_structure"):
            for j in d.refs(topo, "items"):  # links of joints without a pair
                if d.is_a(j, "kinematic_joint"):
                    for a in ("edge_start", "edge_end"):
                        mm.links.setdefault(d.ref(j, a, types=("kinematic_link",)), None)
        if base_rep is not None:
            base = d.ref(base_rep, "represented_link", types=("kinematic_link",))
            mm.links.setdefault(base, base_rep)
        elif mm.links:
            base = next(iter(mm.links))  # no kinematic property: the first pair's first link
        else:
            raise _error(m, "mechanism_representation has no pairs and no base link")
        mm.base = base
        if mm.links.get(base) is None and base_rep is not None:
            mm.links[base] = base_rep
        T = self._assembly_placement(mm, base)
        if T is not None:
            mm.T_world_base = T
        # initial state: the mechanism_state_representation named "initial..." (else the first)
        states = d.usedin(m, "mechanism_state_representation.represented_mechanism")
        if states:
            named = [s for s in states if "initial" in d.string(s, "name").lower()]
            st = (named or states)[0]
            mm.ids["initial_state"] = st
            for v in d.refs(st, "items"):
                if not d.is_a(v, "pair_value"):
                    continue
                p = d.ref(v, "applies_to_pair", types=("kinematic_pair",))
                mm.values.setdefault(p, v)
        return self._build(mm)

    def _assembly_placement(self, mm: _Mech, base) -> Optional[np.ndarray]:
        """AP242: the base link's placement in the mechanism's assembly, from the shape
        representation relationship of the base link's product occurrence; None if absent."""
        d = self.d
        rep = mm.links.get(base)
        if rep is None:
            return None
        pdk = mm.ids.get("product_definition_kinematics")
        assembly_pd = d.ref(pdk, "definition", optional=True) if pdk is not None else None
        for klra in d.usedin(rep, "representation_relationship.rep_1"):
            if not d.is_a(klra, "kinematic_link_representation_association"):
                continue
            for cd in d.usedin(klra, "context_dependent_kinematic_link_representation.representation_relation"):
                pdrk = d.ref(cd, "represented_product_relation", optional=True)
                nauo = d.ref(pdrk, "definition", optional=True) if pdrk is not None else None
                if nauo is None or not d.is_a(nauo, "product_definition_relationship"):
                    continue
                if assembly_pd is not None and d.ref(nauo, "relating_product_definition",
                                                     optional=True) != assembly_pd:
                    continue
                for pds in d.usedin(nauo, "property_definition.definition"):
                    for cdsr in d.usedin(pds, "context_dependent_shape_representation."
                                              "represented_product_relation"):
                        rel = d.ref(cdsr, "representation_relation", optional=True)
                        if not d.is_a(rel, "representation_relationship_with_transformation"):
                            continue
                        op = d.ref(rel, "transformation_operator")
                        r1, r2 = d.ref(rel, "rep_1"), d.ref(rel, "rep_2")
                        mm.ids["base_placement"] = op
                        if d.is_a(op, "item_defined_transformation"):
                            return d.item_defined_transformation(op, d.scale(r1), d.scale(r2))
                        return d.placement(op, d.scale(r2))
        return None

    # ---------------------------------------------------------------- links
    def _link_reps(self, link) -> list:
        d = self.d
        reps = []
        for rel in d.usedin(link, "kinematic_link_representation_relation.topological_aspects"):
            reps.append(d.ref(rel, "geometric_aspects"))
        reps.extend(d.usedin(link, "kinematic_link_representation.represented_link"))
        return list(dict.fromkeys(reps))

    def _rep_links(self, rep) -> list:
        """The links ``rep`` represents (1996: through the relation; AP242: represented_link)."""
        d = self.d
        out = [d.ref(rel, "topological_aspects") for rel in
               d.usedin(rep, "kinematic_link_representation_relation.geometric_aspects")]
        r = d.get(rep, "represented_link", None)
        if _ref(r) is not None:
            out.append(d.ref(rep, "represented_link"))
        return out

    def _frame_rep(self, pair, which: int, link, frame, hint) -> int:
        """The link representation of ``link`` that places ``frame`` (the pair's frame on it)."""
        d = self.d
        cands = [] if hint is None or link not in self._rep_links(hint) else [hint]
        cands += self._link_reps(link)
        for r in cands:
            if frame in d.refs(r, "items"):
                return r
        for r in d.usedin(frame, "representation.items"):
            if d.is_a(r, "kinematic_link_representation"):
                others = [x for x in self._rep_links(r) if x != link]
                if others:
                    raise _error(pair, f"transform_item_{which} #{frame} is placed in #{r}, the "
                                 f"representation of link #{others[0]}, not of its "
                                 f"{'first' if which == 1 else 'second'} link #{link}")
                return r
        if cands:
            return cands[0]
        raise _error(frame, f"pair frame of link #{link} is in no link representation: its units "
                     "are unknown")

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

    # ---------------------------------------------------------------- pairs
    def _pair_kind(self, p) -> tuple:
        d = self.d
        names = sorted(n for n in d.leaf_types(p) if n != "actuated_kinematic_pair")
        for n in names:
            k = pair_kind_of_entity(n)
            if k is not None:
                return k, n
        # a supertype name that is a pair (e.g. an instance of a subtype we do not know)
        shown = "+".join(names) or "kinematic_pair"
        raise _error(p, f"{shown}: this pair type is not supported by the kinematics model "
                     "(see docs/model.md)")

    def _pair(self, p, j, l1, l2, reps=(None, None)) -> dict:
        d = self.d
        if not d.is_a(p, "kinematic_pair"):
            raise _error(p, f"{d.label(p)} is not a kinematic_pair")
        kind, entity = self._pair_kind(p)
        pj = d.ref(p, "joint", types=("kinematic_joint",))
        if pj != j:
            raise _error(p, f"pair's joint is #{pj}, not #{j}")
        f1 = d.ref(p, "transform_item_1")
        f2 = d.ref(p, "transform_item_2")
        rep1 = self._frame_rep(p, 1, l1, f1, reps[0])
        rep2 = self._frame_rep(p, 2, l2, f2, reps[1])
        s1, s2 = d.scale(rep1), d.scale(rep2)
        P1 = d.placement(f1, s1)
        P2 = d.placement(f2, s2)
        ids = {"pair": p, "joint": j, "frame_1": f1, "frame_2": f2}
        params = self._params(p, kind, s1)
        for key, f, sc in (("su_1", f1, s1), ("su_2", f2, s2)):
            if d.is_a(f, "su_parameters"):  # kept so that a writer can give the frame back as written
                params[key] = d.su(f, sc)
        geometry = {}
        if kind in _HIGHER_KINDS:
            geometry = self._higher_geometry(p, kind, (P1, P2), (rep1, rep2), ids)
            params.update({k: obj for k, (obj, _scale, _inst) in geometry.items()})
            if "orientation" in d.pop.instance(p).explicit_names():
                params["orientation"] = _is_true(d.get(p, "orientation"))
        # ranges
        lower = upper = ()
        holder = None
        if self.layout == "1996":
            for r in d.usedin(p, "simple_pair_range.applies_to_pair"):
                holder = r
                ids["range"] = r
                break
        elif any(n.startswith(("lower_limit_", "range_on_")) for n in
                 d.pop.instance(p).explicit_names()):
            holder = p
        if holder is not None:
            lower, upper = self._limits(holder, kind, s1, geometry)
        # actuation
        actuated = False
        if d.is_a(p, "actuated_kinematic_pair"):
            actuated = True
        for a in d.usedin(p, "pair_actuator.actuated_pair"):
            actuated = True
            ids["actuator"] = a
            break
        joint_name = d.string(j, "name")
        return {"id": p, "kind": kind, "entity": entity, "link1": l1, "link2": l2, "P1": P1, "P2": P2,
                "params": params, "lower": lower, "upper": upper, "actuated": actuated,
                "name": d.string(p, "representation_item.name", "item_defined_transformation.name",
                                 "name"),
                "description": d.string(p, "item_defined_transformation.description", "description"),
                "joint_name": joint_name, "ids": ids, "scale": s1, "geometry": geometry,
                "reps": (rep1, rep2)}

    def _params(self, p, kind, s: _Scale) -> dict:
        d = self.d
        out: dict = {}
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
            for f in ("t_x", "t_y", "t_z", "r_x", "r_y", "r_z"):
                out[f] = _is_true(d.get(p, f"low_order_kinematic_pair.{f}"))
        elif kind in ("universal", "homokinetic"):
            x = d.number(p, "input_skew_angle", optional=True)
            out["input_skew_angle"] = None if x is None else x * s.angle
        return out

    def _limits(self, holder, kind, s: _Scale, geometry: dict) -> tuple:
        from .pairs import PAIR_KINDS

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
        for v in value_names:
            lo = hi = None
            if v in on:
                lo, hi = on[v]
            ab = limit_attributes(v)
            if ab is not None and ab[0] in names and ab[1] in names:
                f = s.angle if _is_angle(v) else s.length
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
            raise _error(holder, f"{attr} is {raw!r}, not a finite number or UNLIMITED")
        return x * factor

    # ---------------------------------------------------------------- pair values
    def _value(self, v, pair: Pair, s: _Scale, geometry: dict) -> tuple:
        d = self.d
        kind = pair.kind
        if kind in ("spherical", "spherical_with_pin"):
            return self._ypr(v, s)
        if kind == "unconstrained":
            pp = d.ref(v, "actual_placement")
            T = d.placement(pp, s)
            ypr = pl.ypr_from_matrix(T)
            return (*(float(x) for x in T[:3, 3]), *(float(a) for a in ypr))
        if kind in _HIGHER_KINDS:
            return self._higher_value(v, pair, s, geometry)
        out = []
        for name in pair.value_names:
            x = d.number(v, name)
            out.append(x * (s.angle if _is_angle(name) else s.length))
        return tuple(out)

    def _ypr(self, v, s: _Scale) -> tuple:
        d = self.d
        raw = d.get(v, "input_orientation")
        r = _ref(raw)
        if r is not None:
            if r not in d.pop:
                raise _error(v, f"input_orientation refers to #{r}, which is not in the file")
            if not d.is_a(r, "rotation_about_direction"):
                raise _error(v, f"input_orientation #{r} is no rotation_about_direction")
            direction = d.direction(r, "direction_of_axis")
            if direction is None:
                raise _error(r, "rotation_about_direction has no direction_of_axis")
            angle = d.number(r, "rotation_angle")
            try:
                ypr = pl.convert_spatial_to_ypr_rotation(direction, angle, s.angle)
            except ValueError as e:
                raise _error(r, str(e)) from None
            return tuple(float(x) * s.angle for x in ypr)
        vals = _untyped(raw)
        nums = [_num(x) for x in vals] if type(vals) is list else []
        if len(nums) != 3 or None in nums:
            raise _error(v, f"input_orientation is {raw!r}, not a ypr_rotation or rotation_about_direction")
        return tuple(x * s.angle for x in nums)

    # ---------------------------------------------------------------- higher pairs
    def _geometry_module(self):
        if self._geometry_step is _MISSING:
            try:
                from . import geometry_step  # noqa: F401 - provided by the higher-pair work
                self._geometry_step = geometry_step
            except ImportError:
                self._geometry_step = None
        return self._geometry_step

    def _higher_geometry(self, p, kind, frames, reps, ids) -> dict:
        """``{params key: (geometry object in its pair frame, scale of its context, instance id)}``
        for the curves/surfaces of a higher pair."""
        d = self.d
        out: dict = {}
        names = d.pop.instance(p).explicit_names()
        gs = self._geometry_module()
        for attr, (key, which) in _GEOMETRY_ATTRS.items():
            if attr not in names:
                continue
            g = d.ref(p, attr)
            ids[key] = g
            holder_rep, T_link_geom = self._geometry_placement(g, reps[which - 1], frames[which - 1])
            s = d.scale(holder_rep)
            T_pair_geom = pl.inverse(frames[which - 1]) @ T_link_geom
            if gs is None:
                raise _error(g, f"{kind} pairs need Part 42 geometry reading "
                             "(p105cli.kinematics.geometry_step), which is not available")
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
    def _curve_parameter_factor(self, c, s: _Scale) -> float:
        d = self.d
        if d.is_a(c, "trimmed_curve"):
            return self._curve_parameter_factor(d.ref(c, "basis_curve"), s)
        return s.angle if d.is_a(c, "circle", "ellipse") else 1.0

    def _surface_parameter_factors(self, g, s: _Scale) -> tuple:
        d = self.d
        if d.is_a(g, "rectangular_trimmed_surface"):
            return self._surface_parameter_factors(d.ref(g, "basis_surface"), s)
        if d.is_a(g, "plane"):
            return s.length, s.length
        if d.is_a(g, "cylindrical_surface", "conical_surface"):
            return s.angle, s.length
        if d.is_a(g, "spherical_surface", "toroidal_surface"):
            return s.angle, s.angle
        return 1.0, 1.0

    def _on_curve(self, t_si: float, obj) -> float:
        """A basis-curve parameter (SI) as the parameter of the geometry object ``obj``."""
        from .geometry import TrimmedCurve

        if isinstance(obj, TrimmedCurve):
            sgn = 1.0 if obj.sense else -1.0
            t = sgn * (t_si - obj.trim_1)
            per = getattr(obj.basis, "period", None)
            return t % per if per else t
        return t_si

    def _point_on_curve(self, v, attr, entry) -> float:
        d = self.d
        obj, s, g = entry
        pt = d.ref(v, attr, types=("point_on_curve",))
        basis = d.ref(pt, "basis_curve")
        allowed = {g}
        if d.is_a(g, "trimmed_curve"):
            allowed.add(d.ref(g, "basis_curve"))
        if basis not in allowed:
            raise _error(v, f"{attr} #{pt} lies on #{basis}, not on the pair's curve #{g}")
        t = d.number(pt, "point_parameter") * self._curve_parameter_factor(basis, s)
        return self._on_curve(t, obj)

    def _point_on_surface(self, v, attr, entry) -> tuple:
        d = self.d
        obj, s, g = entry
        pt = d.ref(v, attr, types=("point_on_surface",))
        basis = d.ref(pt, "basis_surface")
        if basis != g:
            raise _error(v, f"{attr} #{pt} lies on #{basis}, not on the pair's surface #{g}")
        fu, fv = self._surface_parameter_factors(basis, s)
        return d.number(pt, "point_parameter_u") * fu, d.number(pt, "point_parameter_v") * fv

    def _higher_value(self, v, pair: Pair, s: _Scale, geometry: dict) -> tuple:
        d = self.d
        kind = pair.kind
        if kind == "point_on_planar_curve":
            return (self._point_on_curve(v, "actual_point_on_curve", geometry["curve"]), *self._ypr(v, s))
        if kind == "point_on_surface":
            return (*self._point_on_surface(v, "actual_point_on_surface", geometry["surface"]),
                    *self._ypr(v, s))
        if kind == "sliding_curve":
            return (self._point_on_curve(v, "actual_point_on_curve_1", geometry["curve_1"]),
                    self._point_on_curve(v, "actual_point_on_curve_2", geometry["curve_2"]))
        if kind == "rolling_curve":
            return (self._point_on_curve(v, "actual_point_on_curve_1", geometry["curve_1"]),)
        if kind == "sliding_surface":
            return (*self._point_on_surface(v, "actual_point_on_surface_1", geometry["surface_1"]),
                    *self._point_on_surface(v, "actual_point_on_surface_2", geometry["surface_2"]),
                    d.number(v, "actual_rotation") * s.angle)
        if kind == "rolling_surface":
            return (*self._point_on_surface(v, "actual_point_on_surface", geometry["surface_1"]),
                    d.number(v, "actual_rotation") * s.angle)
        raise _error(v, f"values of {kind} pairs are not read")

    def _parameter_range(self, holder, attr, rng, entry) -> list:
        """[(lower, upper), ...] of the point parameter(s) a trimmed curve or rectangular
        trimmed surface range allows (a full turn of a periodic parameter: unlimited)."""
        d = self.d
        obj, s, g = entry
        if d.is_a(rng, "trimmed_curve"):
            basis = d.ref(rng, "basis_curve")
            allowed = {g} | ({d.ref(g, "basis_curve")} if d.is_a(g, "trimmed_curve") else set())
            if basis not in allowed:
                raise _error(holder, f"{attr} #{rng} trims #{basis}, not the pair's curve #{g}")
            gs = self._geometry_module()
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
            a = self._on_curve(tc.trim_1, obj)
            b = a + sign * span
            return [(min(a, b), max(a, b))]
        if d.is_a(rng, "rectangular_trimmed_surface"):
            if d.ref(rng, "basis_surface") != g:
                raise _error(holder, f"{attr} #{rng} trims another surface than the pair's #{g}")
            fu, fv = self._surface_parameter_factors(g, s)
            u = sorted((d.number(rng, "u1") * fu, d.number(rng, "u2") * fu))
            v = sorted((d.number(rng, "v1") * fv, d.number(rng, "v2") * fv))
            return [tuple(u), tuple(v)]
        raise _error(holder, f"{attr} #{rng} is no trimmed_curve or rectangular_trimmed_surface")

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
    def _build(self, mm: _Mech) -> Mechanism:
        d = self.d
        # link representations and names
        for link in list(mm.links):
            if mm.links[link] is None:
                reps = self._link_reps(link)
                mm.links[link] = reps[0] if reps else None
        order = [mm.base] + sorted(x for x in mm.links if x != mm.base)
        raw_names = {}
        for link in order:
            rep = mm.links[link]
            raw_names[link] = (d.string(link, "name") or (d.string(rep, "name") if rep is not None else "")
                               or f"#{link}")
        names = _unique(raw_names)
        links = []
        used_frames: dict = {}
        for pr in mm.pairs:
            used_frames.setdefault(pr["link1"], set()).add(pr["ids"]["frame_1"])
            used_frames.setdefault(pr["link2"], set()).add(pr["ids"]["frame_2"])
        for link in order:
            rep = mm.links[link]
            frames = {}
            if rep is not None:
                items = [i for i in d.refs(rep, "items")
                         if i not in used_frames.get(link, ()) and d.is_a(i, "axis2_placement_3d",
                                                                           "su_parameters")]
                fnames = _unique({i: d.string(i, "name") or f"#{i}" for i in items})
                for i in items:
                    frames[fnames[i]] = d.placement(i, d.scale(rep))
            links.append(Link(names[link], id=link, frames=frames,
                              description=self._link_description(rep) if rep is not None else ""))
        # pairs
        pnames = _unique({pr["id"]: pr["name"] or pr["joint_name"] or f"#{pr['id']}" for pr in mm.pairs})
        pairs = []
        initial = {}
        for pr in mm.pairs:
            pair = Pair(pnames[pr["id"]], pr["kind"], names[pr["link1"]], names[pr["link2"]], pr["P1"],
                        pr["P2"], params=pr["params"], lower=pr["lower"], upper=pr["upper"],
                        actuated=pr["actuated"], joint=pr["joint_name"] or pnames[pr["id"]],
                        description=pr["description"], ids=pr["ids"])
            v = mm.values.get(pr["id"])
            if v is not None:
                initial[pair.name] = self._value(v, pair, pr["scale"], pr["geometry"])
                pair = Pair(pair.name, pair.kind, pair.link1, pair.link2, pair.P1, pair.P2,
                            params=pair.params, lower=pair.lower, upper=pair.upper,
                            actuated=pair.actuated, joint=pair.joint, description=pair.description,
                            ids={**pair.ids, "value": v})
            pairs.append(pair)
            self.pairs_by_id[pr["id"]] = (pair, pr["scale"], pr["geometry"])
        base_rep = mm.links.get(mm.base)
        units = d.scale(base_rep).units() if base_rep is not None else Units()
        return Mechanism(mm.name, links, pairs, names[mm.base], T_world_base=mm.T_world_base,
                         initial=initial, units=units, profile=self.profile,
                         description=mm.description, ids=mm.ids)


def _unique(raw: dict) -> dict:
    """Names made unique deterministically: a name used more than once gets `` #id``."""
    count: dict = {}
    for n in raw.values():
        count[n] = count.get(n, 0) + 1
    return {k: (n if count[n] == 1 else f"{n} #{k}") for k, n in raw.items()}


# --------------------------------------------------------------------------- entry points

def population(doc, profile: str | None = None):
    """``(Population, profile name)`` for ``doc``: FILE_SCHEMA's profile unless
    ``profile`` is given, a 1996-layout AP214 file holding su_parameters read as
    ``p105``. Every command that reads mechanisms chooses its profile here."""
    return _population(doc, profile)


def _population(doc, profile):
    from ..schema.population import Population
    from ..schema.profiles import get_profile, profile_for_header

    if isinstance(doc, Population):
        name = doc.profile.name if doc.profile is not None else profile
        return doc, (name or "ap214")
    if profile is not None and not isinstance(profile, str):
        profile = profile.name  # a Profile
    if profile is None:
        prof = profile_for_header(getattr(doc, "header", {}))
        if prof.name == "ap214":
            # AP214's long form has no su_parameters; a 1996 file using them is read as p105
            probe = Population(doc, prof)
            if probe.ids_of_type("su_parameters"):
                prof = get_profile("p105")
            else:
                return probe, "ap214"
    else:
        prof = get_profile(profile)
    return Population(doc, prof), prof.name


def read_mechanisms(doc, profile: str | None = None) -> list:
    """Every mechanism of ``doc`` as a :class:`~p105cli.kinematics.model.Mechanism`, in file order.

    ``doc``: a StepFile, JsonDocument or Population; ``profile``: ``"ap214"``,
    ``"p105"``, ``"ap242"`` or None (from FILE_SCHEMA). Raises ModelError
    (message starting with the ``#id`` at fault) for a model that cannot be
    read, :class:`~p105cli.schema.profiles.UnknownSchemaError` for an unknown
    schema."""
    pop, name = _population(doc, profile)
    try:
        return _Reader(pop, name).mechanisms()
    except ModelError as e:
        e.source = getattr(doc, "source", None) or e.source
        raise


class PairValueReader:
    """Reads ``*_pair_value`` instances of a model (configurations of its motion
    program or analysis results) in SI, keyed by the pair names of
    :attr:`mechanisms` (the same names :func:`read_mechanisms` gives)."""

    def __init__(self, doc, profile: str | None = None):
        pop, name = _population(doc, profile)
        self._reader = _Reader(pop, name)
        self.mechanisms = self._reader.mechanisms()

    def values(self, value_ids) -> dict:
        """``{pair name: values}`` of the pair value instances ``value_ids``."""
        r = self._reader
        out = {}
        for v in value_ids:
            p = r.d.ref(v, "applies_to_pair", types=("kinematic_pair",))
            if p not in r.pairs_by_id:
                raise _error(v, f"applies to pair #{p}, which belongs to no mechanism of the file")
            pair, scale, geometry = r.pairs_by_id[p]
            out[pair.name] = r._value(v, pair, scale, geometry)
        return out


def read_mechanism(doc, profile: str | None = None, name: str | None = None) -> Mechanism:
    """The one mechanism of ``doc``, or the one called ``name``; ModelError otherwise."""
    mechs = read_mechanisms(doc, profile)
    try:
        return _choose(mechs, name)
    except ModelError as e:
        e.source = getattr(doc, "source", None) or e.source
        raise


def _choose(mechs: list, name: Optional[str]) -> Mechanism:
    if name is not None:
        found = [m for m in mechs if m.name == name]
        if len(found) == 1:
            return found[0]
        known = ", ".join(repr(m.name) for m in mechs) or "none"
        if not found:
            raise _error(None, f"no mechanism named {name!r} (the file has: {known})")
        raise _error(None, f"{len(found)} mechanisms are named {name!r}")
    if not mechs:
        raise _error(None, "the file has no mechanism (1996 layout: mechanism; AP242: "
                     "mechanism_representation)")
    if len(mechs) > 1:
        raise _error(None, f"the file has {len(mechs)} mechanisms ("
                     + ", ".join(repr(m.name) for m in mechs) + "); choose one by name")
    return mechs[0]
