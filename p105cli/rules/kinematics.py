"""Kinematics checks the EXPRESS schema cannot express (``KIN-*``).

ISO 10303-105 states some of its requirements in prose (informal
propositions, the units clause 5.2.5) or leaves them to the application;
the checks here test them on a :class:`~p105cli.schema.population.Population`
of either layout:

* the 1996 layout (profiles ``ap214`` and ``p105``): ``mechanism``,
  ``kinematic_structure``, ``kinematic_joint(first_link, second_link)``,
  link representations found through ``kinematic_link_representation_relation``
  (or, failing that, as the link representation whose items hold the pair's
  ``transform_item_1``/``_2``), separate ``*_pair_range`` and ``*_pair_value``
  instances that point at the pair;
* the AP242 layout (profile ``ap242``): ``mechanism_representation`` with
  ``pair_representation_relationship`` items, ``kinematic_joint(name,
  edge_start, edge_end)``, link representations carrying ``represented_link``,
  ``*_pair_with_range`` subtypes of the pair itself, pair values as items of
  ``mechanism_state_representation``.

Entry points
    ``check_kinematics(pop) -> list[Finding]`` (``Finding`` of
    ``conformance.py``), ``context_units(pop, context_id) -> ContextUnits``
    (the SI factors of one representation context's length and plane-angle
    units).

Only kinematic instances (the Part 105 entities of both layouts,
``KIN_ENTITIES``) and what they reference are decoded: a geometry-only file
costs one look-up per entity name.

Rule ids (stable)

=================  ==========================================================
rule               what it checks
=================  ==========================================================
KIN-UNITS          5.2.5 unit consistency. Each context's length and plane-
                   angle unit is reduced to an SI factor (``si_unit`` with its
                   prefix; ``conversion_based_unit`` chains through
                   ``conversion_factor.value_component`` x
                   ``unit_component``, e.g. DEGREE = pi/180 rad, INCH =
                   25.4 x 1 mm; each step must be a unit of the same kind, the
                   chain must end in the metre or the radian). *Error*: two
                   representations of one mechanism (its link
                   representations, and the other kinematic representations
                   reachable from it: ground, mechanism, topology, state,
                   path, configuration representations) whose contexts give a
                   different factor; a link representation used by a pair
                   whose context is no ``global_unit_assigned_context``, has
                   no length unit (the pair frames are placed in it), or no
                   plane-angle unit when the pair has angles (angular ranges
                   or values, ypr orientations, su_parameters frames, screw,
                   gear, universal or homokinetic pairs) -- the first link's
                   context is the one ``plane_angle_for_pair_in_radian``
                   reads; a context assigning two units of one kind; a unit
                   that is not of its kind (a LENGTH_UNIT in radians, a
                   conversion based on a unit of another kind, a chain that
                   loops, a non-positive conversion factor). *Warning*: a
                   ``context_dependent_unit`` or other unit with no SI
                   conversion (its factor is unknown, so it is not compared);
                   a pair with ranges or values whose first link has no link
                   representation (its units cannot be determined)
KIN-RANGE          Pair values inside their ranges, for every range the
                   schema has: revolute, prismatic, cylindrical, screw,
                   universal, planar, spherical (ypr limits; a
                   ``rotation_about_direction`` orientation is converted by
                   5.5.9 first), spherical with pin, gear, rack and pinion,
                   point on surface / point on planar curve (ypr limits and
                   the trimmed curve or rectangular trimmed surface that
                   bounds the point's parameters, periodic parameters of
                   circles, ellipses, cylinders, cones, spheres and tori
                   read modulo their period), planar curve and surface pair
                   ranges, AP242's low_order_kinematic_pair_with_range.
                   1996: every ``*_pair_range`` against every
                   ``*_pair_value`` of its pair; AP242: every
                   ``*_with_range`` pair against its values. Both are in the
                   units of the pair's first-link context (the second link's
                   when the first has no representation); limits and values
                   are compared, and reported, in radians and metres.
                   ``unlimited_range`` and ``$`` limits bound nothing.
                   *Error*: a value outside a limit (relative tolerance
                   1e-9), a lower limit above its upper limit
KIN-YPR            5.3.7 on every ``ypr_rotation`` value (``input_orientation``
                   of spherical, point-on-surface and point-on-planar-curve
                   pair values: referenced from ``initial_state`` /
                   ``configuration_definition`` in the 1996 layout, items of
                   ``mechanism_state_representation`` in AP242), in radians
                   through the pair's first-link plane-angle unit. *Error*:
                   pitch outside [-pi/2, pi/2], yaw or roll outside
                   (-pi, pi], a non-zero roll at |pitch| = pi/2 (rectangular
                   pitch angle). *Warning*: yaw or roll exactly -pi (the same
                   orientation as +pi, which the interval asks for); a ypr
                   range limit outside the closed interval its angle can
                   take (limits are plane angles, not ypr_rotations, so the
                   standard does not bind them). Bounds are compared with a
                   relative tolerance of 1e-6 (conversion factors written
                   with few digits)
KIN-PLACEMENT      Placements used by kinematic instances (referenced
                   directly: pair frames, link representation items, base
                   placements, path placements, pair values, and the
                   kinematic placement entities themselves). *Error*: an
                   ``axis2_placement_3d`` with a zero or non-finite axis or
                   ref_direction, or with the two parallel (Part 42 WR4);
                   a non-finite location; ``su_parameters`` with a
                   non-finite parameter; a ``rotation_about_direction`` with
                   a zero direction; a ``cartesian_transformation_operator_3d``
                   with a zero axis, linearly dependent axes, a left-handed
                   axis set (a reflection), or a non-positive or non-finite
                   scale. *Warning*: an ``axis2_placement_3d`` whose
                   ref_direction is not orthogonal to its axis or a
                   transformation operator whose axes are not orthogonal
                   (|cos| > 1e-6; Part 42 projects them, so the frame is not
                   the one written), a transformation operator with a scale
                   other than 1 (not a rigid placement). Non-unit directions
                   are fine (normalised)
KIN-LINK-NAME      (warning) two links of one mechanism with the same name (a link
                   is called by its name, else its representation's, else
                   ``#id``: part105/layout.py's rule, which every command
                   uses); p105 then calls each ``<name> #<id>``, which the
                   file's other readers will not
KIN-UNREACHABLE    (warning) links, joints, pairs, pair values, pair ranges,
                   link representations (and their relations), pair
                   representation relationships, structures and states that
                   no ``mechanism`` (1996) or ``mechanism_representation``
                   (AP242) reaches, following references and back references
                   between kinematic instances (and through the rigid
                   placements they share: a 1996 link representation that
                   holds a pair's frames belongs to the pair's mechanism)
=================  ==========================================================

Findings name the instance they are about (``entity``, ``entity_type`` as
in ``conformance.py``: part names joined by ``+`` for a complex instance)
and, where one attribute is at fault, its name in ``attribute``.
"""

from __future__ import annotations

import math
from typing import Optional

from ..part105 import layout
from ..part105.catalogue import KINEMATIC_ENTITIES, LIMITS, RANGE_ON, YPR_NAMES, YPR_REL_TOL
from ..part105.model_file import MISSING, ModelFile
from ..schema.units import ANGLE, KIND_SYMBOL as _KIND_SYMBOL, LENGTH, ContextUnits, UnitReader
from ..schema.values import enum, is_false, is_unlimited, number, ref, untyped
from ..step.values import refs_in as _refs_in
from .conformance import ERROR, WARNING, Finding

__all__ = ["RULES", "KIN_ENTITIES", "ContextUnits", "check_kinematics", "context_units"]

UNITS = "KIN-UNITS"
RANGE = "KIN-RANGE"
YPR = "KIN-YPR"
PLACEMENT = "KIN-PLACEMENT"
UNREACHABLE = "KIN-UNREACHABLE"
LINK_NAME = "KIN-LINK-NAME"

RULES = {  # one sentence each, ready for diagnostics.register_rule
    UNITS: "Length and plane-angle units of a mechanism's representations are missing, "
           "unresolvable or inconsistent (ISO 10303-105 5.2.5).",
    RANGE: "A pair value lies outside its pair range, or a range's lower limit exceeds its "
           "upper limit.",
    YPR: "A ypr_rotation angle is outside its interval, or the roll is not zero at a "
         "rectangular pitch (ISO 10303-105 5.3.7).",
    PLACEMENT: "A placement used by a kinematic entity is degenerate, non-finite, "
               "non-orthogonal or not rigid.",
    UNREACHABLE: "A kinematic entity is not reachable from any mechanism.",
    LINK_NAME: "Two links of a mechanism have the same name: p105 tells them apart by appending "
               "their #id (part105/layout.py's naming rule).",
}

#: Entity names of Part 105 in both layouts (1996 / AP214 and AP242).
KIN_ENTITIES = KINEMATIC_ENTITIES


# Kinds of entity KIN-UNREACHABLE reports (any of these among an instance's types).
_REPORTED = (
    "kinematic_link", "kinematic_joint", "kinematic_pair", "pair_value", "simple_pair_range",
    "kinematic_link_representation", "kinematic_link_representation_relation",
    "pair_representation_relationship", "kinematic_structure", "kinematic_topology_structure",
    "kinematic_topology_directed_structure", "kinematic_topology_network_structure",
    "kinematic_topology_tree_structure", "initial_state", "mechanism_state_representation",
    "pair_actuator",
)
# Placements that tie kinematic instances together for reachability (rigid_placement).
_BRIDGES = ("axis2_placement_3d", "su_parameters")
# Pair types with angle attributes of their own (their first-link context needs an angle unit).
_ANGLE_PAIRS = ("screw_pair", "gear_pair", "universal_pair", "homokinetic_pair")

# lower_limit_<suffix> / upper_limit_<suffix> -> (value attribute, kind, ypr index or None)
_UNIT_KIND = {"A": ANGLE, "L": LENGTH}
_LIMITS = {s: (lim.value_attribute, _UNIT_KIND[lim.unit], lim.ypr_index) for s, lim in LIMITS.items()}
_YPR_NAMES = YPR_NAMES
# range_on_<...> -> value attributes holding the point it bounds
_ON_RANGES = {a: r.value_attributes for a, r in RANGE_ON.items()}
# Curves/surfaces whose parameters are angles, periodic with one turn.
_PERIODIC_CURVES = ("circle", "ellipse")
_PERIODIC_U = ("cylindrical_surface", "conical_surface", "spherical_surface", "toroidal_surface")
_PERIODIC_V = ("toroidal_surface",)

RANGE_TOL = 1e-9     # relative, value against limit (same unit on both sides)
YPR_TOL = YPR_REL_TOL  # relative, ypr angle against +-pi, +-pi/2 (the writer's canonical_ypr uses it too)
ORTHO_TOL = 1e-6     # |cos| between axes that should be orthogonal
FACTOR_TOL = 1e-9    # relative difference of two SI factors that still agree

_MISSING = MISSING  # what the lenient ModelFile gives for an absent attribute


# --------------------------------------------------------------------------- raw values

# the one reading of typed values (schema/values.py)
_ref, _untyped, _num, _enum, _is_false, _is_unlimited = ref, untyped, number, enum, is_false, is_unlimited


def _fmt(x: float) -> str:
    if x == 0.0:
        return "0"
    return f"{x:.6g}"


def _close(a: float, b: float, rel: float = FACTOR_TOL) -> bool:
    return abs(a - b) <= rel * max(abs(a), abs(b))


# --------------------------------------------------------------------------- units

class _Kin:
    """One run of the checks over one population."""

    def __init__(self, pop, scan: bool = True):
        self.pop = pop
        self.schema = pop.schema
        self.out: list = []
        self._seen: set = set()
        self.mf = ModelFile.of(pop, lenient=True)  # the lenient access of the layout walk
        self.units = self.mf.units
        self._pair_units: dict = {}
        self._reps_of_link: dict = {}
        self.refs: dict = {}
        self.back: dict = {}
        ids: set = set()
        if scan:
            ents = self.schema.entities
            for name in KIN_ENTITIES:
                if name in ents:
                    ids.update(pop.ids_of_type(name))
        self.kin = ids
        self.order = sorted(ids)
        for i in self.order:
            rec = self._record(i)
            if rec is None:
                continue
            rs: list = []
            for part in rec.get("complex", (rec,)):
                _refs_in(part.get("args") or [], rs)
            rs = [r for r in dict.fromkeys(rs) if r in pop]
            self.refs[i] = rs
            for r in rs:
                lst = self.back.get(r)
                if lst is None:
                    self.back[r] = [i]
                elif lst[-1] != i:
                    lst.append(i)

    # ---------------------------------------------------------------- access
    def _record(self, i):
        try:
            return self.pop.instance(i).record
        except Exception:  # noqa: BLE001 - an undecodable record is the reader's finding
            return None

    # lenient access: the ModelFile's (an absent attribute is _MISSING, a bad reference None)
    def types(self, i) -> frozenset:
        return self.mf.types(i)

    def is_a(self, i, *names) -> bool:
        return self.mf.is_a(i, *names)

    def get(self, i, attr, default=_MISSING):
        return self.mf.get(i, attr, default)

    def has(self, i, attr) -> bool:
        return self.mf.get(i, attr) is not _MISSING

    def get_ref(self, i, *attrs) -> Optional[int]:
        """The reference of the first of ``attrs`` that ``#i`` has (None if it is no
        reference to an instance of the file)."""
        return self.mf.first_ref(i, *attrs)

    def names(self, i) -> list:
        return self.mf.names(i)

    def label(self, i) -> Optional[str]:
        if i is None:
            return None
        rec = self._record(i)
        if rec is None:
            return None
        parts = rec.get("complex")
        if parts is not None:
            return "+".join(str(p.get("type")) for p in parts)
        return rec.get("type")

    def add(self, rule, severity, message, entity, attribute=None):
        key = (rule, entity, attribute, message)
        if key in self._seen:
            return
        self._seen.add(key)
        self.out.append(Finding(rule, severity, message, entity, self.label(entity), attribute))

    def referrers(self, i, types=(), attr=None) -> list:
        """Kinematic instances referring to ``#i`` (of one of ``types``, through ``attr``)."""
        out = []
        for r in self.back.get(i, ()):
            if types and not self.is_a(r, *types):
                continue
            if attr is not None and self.get_ref(r, attr) != i:
                continue
            out.append(r)
        return out

    # ---------------------------------------------------------------- units
    def context_units(self, ctx: Optional[int]) -> ContextUnits:
        return self.units.context_units(ctx)

    def rep_context(self, rep: Optional[int]) -> Optional[int]:
        if rep is None:
            return None
        return self.get_ref(rep, "context_of_items")

    def rep_units(self, rep) -> ContextUnits:
        return self.context_units(self.rep_context(rep))

    # ---------------------------------------------------------------- structure
    def joint_links(self, joint) -> tuple:
        return layout.joint_links(self.mf, joint)

    def pair_links(self, pair) -> tuple:
        return self.joint_links(self.get_ref(pair, "joint"))

    def link_reps(self, link) -> list:
        """Link representations of ``link`` (1996: through kinematic_link_
        representation_relation; AP242: represented_link)."""
        if link is None:
            return []
        reps = self._reps_of_link.get(link)
        if reps is None:
            reps = self._reps_of_link[link] = layout.link_reps(self.mf, link)
        return reps

    def pair_rep(self, pair, which: int) -> Optional[int]:
        """The link representation of the pair's first (1) or second (2) link."""
        link = self.pair_links(pair)[which - 1]
        frame = self.get_ref(pair, f"transform_item_{which}")
        if link is None and frame is None:
            return None
        return layout.frame_rep(self.mf, link, frame)

    def pair_units(self, pair) -> tuple:
        """(ContextUnits of the pair's first-link context or None, that link representation)."""
        r = self._pair_units.get(pair)
        if r is None:
            rep = self.pair_rep(pair, 1)
            if rep is None:
                rep = self.pair_rep(pair, 2)
            cu = self.rep_units(rep) if rep is not None else None
            r = self._pair_units[pair] = (cu, rep)
        return r

    def values_of(self, pair) -> list:
        return self.referrers(pair, ("pair_value",), "applies_to_pair")

    def range_holders(self) -> list:
        """(holder, pair) for every 1996 *_pair_range and every AP242 pair with range."""
        out = []
        for i in self.order:
            names = self.names(i)
            if not any(n.startswith(("lower_limit_", "range_on_")) for n in names):
                continue
            if self.is_a(i, "kinematic_pair"):
                out.append((i, i))
            else:
                p = self.get_ref(i, "applies_to_pair")
                if p is not None:
                    out.append((i, p))
        return out

    def mechanisms(self) -> list:
        out = []
        for name in ("mechanism", "mechanism_representation"):
            if name in self.schema.entities:
                out.extend(self.pop.ids_of_type(name))
        return sorted(out)

    # ---------------------------------------------------------------- reachability
    def neighbours(self, i) -> list:
        out = [r for r in self.refs.get(i, ()) if r in self.kin or self.is_a(r, *_BRIDGES)]
        out.extend(self.back.get(i, ()))
        return out

    def component(self, start) -> set:
        seen = {start}
        todo = [start]
        while todo:
            for n in self.neighbours(todo.pop()):
                if n not in seen:
                    seen.add(n)
                    todo.append(n)
        return seen


# --------------------------------------------------------------------------- KIN-UNITS

def _mechanism_parts(k: _Kin, mech) -> tuple:
    """(pairs, links, reference link representation) of a mechanism."""
    return layout.mechanism_parts(k.mf, mech)


def _pair_needs_angle(k: _Kin, pair, which: int, holders_of: dict) -> bool:
    if which == 2:
        return k.is_a(k.get_ref(pair, "transform_item_2"), "su_parameters")
    if k.is_a(pair, *_ANGLE_PAIRS) or k.is_a(k.get_ref(pair, "transform_item_1"), "su_parameters"):
        return True
    for h in holders_of.get(pair, ()):
        for n in k.names(h):
            if n.startswith("lower_limit_") or n.startswith("upper_limit_"):
                spec = _LIMITS.get(n[12:])
                if spec and spec[1] == ANGLE and not _is_unlimited(k.get(h, n, None)):
                    return True
    for v in k.values_of(pair):
        names = k.names(v)
        if "input_orientation" in names or any("rotation" in n for n in names):
            return True
    return False


def _check_units(k: _Kin, mechs: list, holders_of: dict, components: dict) -> None:
    groups = []
    for m in mechs:
        pairs, links, base_rep = _mechanism_parts(k, m)
        groups.append((m, pairs, links, base_rep))
    if not mechs:  # no mechanism: the file's pairs and link representations as one group
        pairs = [i for i in k.order if k.is_a(i, "kinematic_pair")]
        links = [i for i in k.order if k.is_a(i, "kinematic_link")]
        groups.append((None, pairs, links, None))
    for mech, pairs, links, base_rep in groups:
        where = f"mechanism #{mech}" if mech is not None else "the file (it has no mechanism)"
        # link representations of the mechanism, in order: base first
        link_reps: list = []
        for ln in links:
            link_reps.extend(k.link_reps(ln))
        for p in pairs:
            for which in (1, 2):
                r = k.pair_rep(p, which)
                if r is not None:
                    link_reps.append(r)
        if mech is None:
            link_reps.extend(i for i in k.order if k.is_a(i, "kinematic_link_representation"))
        link_reps = list(dict.fromkeys(link_reps))
        if base_rep is None and link_reps:
            base_rep = link_reps[0]
        others = []
        if mech is not None:
            for i in sorted(components.get(mech, ())):
                if (i in k.kin and i not in link_reps and k.is_a(i, "representation")
                        and k.rep_context(i) is not None):
                    others.append(i)
        reps = [base_rep] if base_rep is not None else []
        reps += [r for r in link_reps if r != base_rep]
        reps = list(dict.fromkeys(reps + others))
        # problems of the contexts themselves (ambiguous or wrong units)
        for r in reps:
            for sev, ent, msg in k.rep_units(r).problems:
                k.add(UNITS, sev, msg, ent)
        # agreement: the factor most representations share (ties: the base link's) is the
        # mechanism's; every representation with another factor is reported
        for kind in (LENGTH, ANGLE):
            clusters: list = []  # [factor, label, first rep, count]
            for r in reps:
                u = k.rep_units(r).unit(kind)
                if u is None:
                    continue
                for c in clusters:
                    if _close(u[0], c[0]):
                        c[3] += 1
                        break
                else:
                    clusters.append([u[0], u[1], r, 1])
            if len(clusters) < 2:
                continue
            rf, rl, ref_rep, _n = max(clusters, key=lambda c: c[3])  # first of the largest
            for r in reps:
                u = k.rep_units(r).unit(kind)
                if u is None or _close(u[0], rf):
                    continue
                k.add(UNITS, ERROR, f"{kind} unit of context #{k.rep_context(r)} is {u[1]} "
                      f"({_fmt(u[0])} {_KIND_SYMBOL[kind]}) but {rl} ({_fmt(rf)} "
                      f"{_KIND_SYMBOL[kind]}) in context #{k.rep_context(ref_rep)} of "
                      f"representation #{ref_rep} and the other representations of {where}: "
                      "they must share their units (5.2.5)", r, "context_of_items")
        # units the pairs need
        for p in pairs:
            for which in (1, 2):
                rep = k.pair_rep(p, which)
                if rep is None:
                    if which == 1 and (holders_of.get(p) or k.values_of(p)):
                        link = k.pair_links(p)[0]
                        k.add(UNITS, WARNING, f"the first link #{link} of the pair has no link "
                              "representation: the units of its ranges and values are unknown", p)
                    continue
                cu = k.rep_units(rep)
                ctx = cu.context
                if ctx is None:
                    continue
                if not cu.assigned:
                    k.add(UNITS, ERROR, f"context #{ctx} is no global_unit_assigned_context: it "
                          f"gives pair #{p}'s frames no length or plane-angle unit (5.2.5)",
                          rep, "context_of_items")
                    continue
                if cu.count[LENGTH] == 0:
                    k.add(UNITS, ERROR, f"context #{ctx} has no length unit, but pair #{p} places "
                          "its frame in it (5.2.5)", rep, "context_of_items")
                if cu.count[ANGLE] == 0 and _pair_needs_angle(k, p, which, holders_of):
                    k.add(UNITS, ERROR, f"context #{ctx} has no plane-angle unit, but pair #{p} "
                          "has angles read in it (5.2.5, plane_angle_for_pair_in_radian)",
                          rep, "context_of_items")


# --------------------------------------------------------------------------- KIN-RANGE

def _ypr_of(k: _Kin, value, factor: Optional[float]) -> Optional[tuple]:
    """(yaw, pitch, roll) in file units of a pair value's input_orientation, or None."""
    raw = k.get(value, "input_orientation", None)
    r = _ref(raw)
    if r is not None:
        if not k.is_a(r, "rotation_about_direction") or factor is None:
            return None
        d = k.get_ref(r, "direction_of_axis")
        ratios = [_num(x) for x in (_untyped(k.get(d, "direction_ratios", [])) or [])]
        angle = _num(k.get(r, "rotation_angle", None))
        if len(ratios) != 3 or None in ratios or angle is None:
            return None
        try:
            from ..kinematics.placements import convert_spatial_to_ypr_rotation  # numpy only when needed
            ypr = convert_spatial_to_ypr_rotation(ratios, angle, factor)
        except ValueError:
            return None
        return tuple(float(x) for x in ypr)
    vals = _untyped(raw)
    if type(vals) is list and len(vals) == 3:
        nums = [_num(x) for x in vals]
        if None not in nums:
            return tuple(nums)
    return None


def _si(x: float, factor: Optional[float], kind: str) -> str:
    if factor is None:
        return _fmt(x)
    return f"{_fmt(x)} ({_fmt(x * factor)} {_KIND_SYMBOL[kind]})"


def _param(v) -> Optional[float]:
    """The parameter of a trimming select list / parameter_value."""
    v = _untyped(v)
    if type(v) in (int, float):
        return float(v)
    if type(v) is list:
        for x in v:
            if type(x) is dict and str(x.get("type", "")).upper() == "PARAMETER_VALUE":
                return _num(x)
    return None


def _in_arc(t: float, t1: float, t2: float, sense: bool, period: Optional[float]) -> bool:
    tol = RANGE_TOL * max(abs(t1), abs(t2), abs(t), abs(t2 - t1), period or 0.0, 1e-300)
    if period is None or not (period > 0.0):
        lo, hi = min(t1, t2), max(t1, t2)
        return lo - tol <= t <= hi + tol
    span = (t2 - t1) if sense else (t1 - t2)
    if span >= period - tol:
        return True
    span %= period
    off = ((t - t1) if sense else (t1 - t)) % period
    return off <= span + tol or off >= period - tol


def _check_on_range(k: _Kin, holder, pair, attr, rng, value, vattr, afactor) -> None:
    point = k.get_ref(value, vattr)
    if point is None:
        return
    if k.is_a(rng, "trimmed_curve") and k.is_a(point, "point_on_curve"):
        basis = k.get_ref(rng, "basis_curve")
        if basis is None or k.get_ref(point, "basis_curve") != basis:
            return
        t1, t2 = _param(k.get(rng, "trim_1", None)), _param(k.get(rng, "trim_2", None))
        t = _num(k.get(point, "point_parameter", None))
        sense = not _is_false(k.get(rng, "sense_agreement", None))
        if None in (t1, t2, t):
            return
        periodic = afactor and k.is_a(basis, *_PERIODIC_CURVES)
        period = 2.0 * math.pi / afactor if periodic else None
        if not _in_arc(t, t1, t2, sense, period):
            k.add(RANGE, ERROR, f"{vattr} #{point} has parameter {_fmt(t)}, outside "
                  f"{attr} #{rng} of {k.label(holder)} #{holder} (trimmed from {_fmt(t1)} to "
                  f"{_fmt(t2)}{'' if sense else ', against the sense'}) of pair #{pair}",
                  value, vattr)
    elif k.is_a(rng, "rectangular_trimmed_surface") and k.is_a(point, "point_on_surface"):
        basis = k.get_ref(rng, "basis_surface")
        if basis is None or k.get_ref(point, "basis_surface") != basis:
            return
        for p_attr, a1, a2, s_attr, periodic in (
                ("point_parameter_u", "u1", "u2", "usense", _PERIODIC_U),
                ("point_parameter_v", "v1", "v2", "vsense", _PERIODIC_V)):
            t = _num(k.get(point, p_attr, None))
            t1, t2 = _num(k.get(rng, a1, None)), _num(k.get(rng, a2, None))
            sense = not _is_false(k.get(rng, s_attr, None))
            if None in (t, t1, t2):
                continue
            period = (2.0 * math.pi / afactor) if (afactor and k.is_a(basis, *periodic)) else None
            if not _in_arc(t, t1, t2, sense, period):
                k.add(RANGE, ERROR, f"{vattr} #{point} has {p_attr} {_fmt(t)}, outside "
                      f"{attr} #{rng} of {k.label(holder)} #{holder} ({a1} {_fmt(t1)} to "
                      f"{a2} {_fmt(t2)}) of pair #{pair}", value, vattr)


def _check_ranges(k: _Kin, holders: list) -> None:
    for holder, pair in holders:
        cu, _rep = k.pair_units(pair)
        names = k.names(holder)
        values = k.values_of(pair)
        for n in names:
            if n.startswith("range_on_"):
                rng = k.get_ref(holder, n)
                if rng is None:
                    continue
                afactor = cu.factor(ANGLE) if cu else None
                for v in values:
                    for vattr in _ON_RANGES.get(n, ()):
                        if k.has(v, vattr):
                            _check_on_range(k, holder, pair, n, rng, v, vattr, afactor)
                            break
                continue
            if not n.startswith("lower_limit_"):
                continue
            suffix = n[len("lower_limit_"):]
            up = "upper_limit_" + suffix
            if up not in names:
                continue
            spec = _LIMITS.get(suffix)
            if spec is None:
                kind = ANGLE if "rotation" in suffix or suffix in _YPR_NAMES else LENGTH
                vname = suffix if suffix.startswith("actual_") else f"actual_{suffix}"
                spec = (vname, kind, None)
            vattr, kind, idx = spec
            factor = cu.factor(kind) if cu else None
            lo_raw, hi_raw = k.get(holder, n, None), k.get(holder, up, None)
            lo = None if _is_unlimited(lo_raw) else _num(lo_raw)
            hi = None if _is_unlimited(hi_raw) else _num(hi_raw)
            if lo is not None and hi is not None and lo > hi:
                k.add(RANGE, ERROR, f"{n} {_si(lo, factor, kind)} is above {up} "
                      f"{_si(hi, factor, kind)}: the range is empty", holder, n)
                continue
            if lo is None and hi is None:
                continue
            for v in values:
                if idx is None:
                    x = _num(k.get(v, vattr, None))
                    shown = vattr
                else:
                    ypr = _ypr_of(k, v, cu.factor(ANGLE) if cu else None)
                    x = None if ypr is None else ypr[idx]
                    shown = f"{vattr} {_YPR_NAMES[idx]}"
                if x is None:
                    continue
                tol = RANGE_TOL * max(abs(lo or 0.0), abs(hi or 0.0), abs(x),
                                      abs((hi or 0.0) - (lo or 0.0)), 1e-300)
                if lo is not None and x < lo - tol:
                    k.add(RANGE, ERROR, f"{shown} {_si(x, factor, kind)} is below {n} "
                          f"{_si(lo, factor, kind)} of {k.label(holder)} #{holder} "
                          f"(pair #{pair})", v, vattr)
                elif hi is not None and x > hi + tol:
                    k.add(RANGE, ERROR, f"{shown} {_si(x, factor, kind)} is above {up} "
                          f"{_si(hi, factor, kind)} of {k.label(holder)} #{holder} "
                          f"(pair #{pair})", v, vattr)


# --------------------------------------------------------------------------- KIN-YPR

_YPR_BOUNDS = {"yaw": math.pi, "pitch": 0.5 * math.pi, "roll": math.pi}


def _check_ypr(k: _Kin, holders: list) -> None:
    for v in k.order:
        if not k.is_a(v, "pair_value") or not k.has(v, "input_orientation"):
            continue
        raw = k.get(v, "input_orientation", None)
        if _ref(raw) is not None:
            continue  # rotation_about_direction: 5.5.9 gives a canonical ypr_rotation
        vals = _untyped(raw)
        if type(vals) is not list or len(vals) != 3:
            continue
        nums = [_num(x) for x in vals]
        if None in nums:
            continue
        pair = k.get_ref(v, "applies_to_pair")
        cu, _rep = k.pair_units(pair) if pair is not None else (None, None)
        f = cu.factor(ANGLE) if cu else None
        if f is None:
            continue  # no plane-angle unit: KIN-UNITS says so
        rad = [x * f for x in nums]
        for name, x, xr in zip(_YPR_NAMES, nums, rad):
            bound = _YPR_BOUNDS[name]
            tol = YPR_TOL * bound
            if not math.isfinite(xr):
                k.add(YPR, ERROR, f"{name} {_fmt(x)} is not finite", v, "input_orientation")
            elif name == "pitch":
                if abs(xr) > bound + tol:
                    k.add(YPR, ERROR, f"pitch {_si(x, f, ANGLE)} is outside [-pi/2, pi/2] (5.3.7)",
                          v, "input_orientation")
            elif xr > bound + tol or xr < -bound - tol:
                k.add(YPR, ERROR, f"{name} {_si(x, f, ANGLE)} is outside (-pi, pi] (5.3.7)",
                      v, "input_orientation")
            elif xr <= -bound + tol:
                k.add(YPR, WARNING, f"{name} {_si(x, f, ANGLE)} is -pi; 5.3.7 takes {name} in "
                      "(-pi, pi]: write +pi (the same orientation)", v, "input_orientation")
        pitch, roll = rad[1], rad[2]
        half = 0.5 * math.pi
        if (math.isfinite(pitch) and abs(abs(pitch) - half) <= YPR_TOL * half
                and math.isfinite(roll) and abs(roll) > YPR_TOL * math.pi):
            k.add(YPR, ERROR, f"roll {_si(nums[2], f, ANGLE)} is not 0 at pitch "
                  f"{_si(nums[1], f, ANGLE)}: at a rectangular pitch angle the roll must be 0 "
                  "(5.3.7)", v, "input_orientation")
    # ypr limits of ranges
    for holder, pair in holders:
        cu, _rep = k.pair_units(pair)
        f = cu.factor(ANGLE) if cu else None
        if f is None:
            continue
        for name in _YPR_NAMES:
            bound = _YPR_BOUNDS[name]
            for n in (f"lower_limit_{name}", f"upper_limit_{name}"):
                raw = k.get(holder, n, None)
                if raw is _MISSING or _is_unlimited(raw):
                    continue
                x = _num(raw)
                if x is None:
                    continue
                if not abs(x * f) <= bound * (1.0 + YPR_TOL):
                    interval = "[-pi/2, pi/2]" if name == "pitch" else "[-pi, pi]"
                    k.add(YPR, WARNING, f"{n} {_si(x, f, ANGLE)} is outside {interval}, the "
                          f"values a ypr {name} can take (5.3.7)", holder, n)


# --------------------------------------------------------------------------- KIN-PLACEMENT

def _vector(k: _Kin, i, attr) -> Optional[list]:
    v = _untyped(k.get(i, attr, None))
    if type(v) is not list:
        return None
    nums = [_num(x) for x in v]
    return None if None in nums else nums


def _check_placements(k: _Kin) -> None:
    targets: dict = {}
    for i in k.order:
        if k.is_a(i, "su_parameters", "rotation_about_direction", "axis2_placement_3d",
                  "cartesian_transformation_operator_3d"):
            targets[i] = None
        for r in k.refs.get(i, ()):
            if r not in targets and k.is_a(r, "axis2_placement_3d", "su_parameters",
                                             "cartesian_transformation_operator_3d",
                                             "rotation_about_direction"):
                targets[r] = None
    for p in sorted(targets):
        t = k.types(p)
        if "axis2_placement_3d" in t:
            _check_axis2(k, p)
        elif "su_parameters" in t:
            for a in ("a", "alpha", "b", "beta", "c", "gamma"):
                x = _num(k.get(p, a, None))
                if x is not None and not math.isfinite(x):
                    k.add(PLACEMENT, ERROR, f"su_parameters {a} is {x!r}, not a finite number",
                          p, a)
        elif "cartesian_transformation_operator_3d" in t:
            _check_cto3d(k, p)
        elif "rotation_about_direction" in t:
            d = k.get_ref(p, "direction_of_axis")
            ratios = _vector(k, d, "direction_ratios") if d is not None else None
            if ratios is not None and not _nonzero(ratios):
                k.add(PLACEMENT, ERROR, f"direction_of_axis #{d} {_vec(ratios)} is a zero or "
                      "non-finite direction: the rotation has no axis", p, "direction_of_axis")


def _vec(v) -> str:
    return "(" + ", ".join(_fmt(x) for x in v) + ")"


def _nonzero(v) -> bool:
    n = math.fsum(x * x for x in v) if all(math.isfinite(x) for x in v) else float("nan")
    return math.isfinite(n) and n > 0.0 and any(x != 0.0 for x in v)


def _check_axis2(k: _Kin, p) -> None:
    import numpy as np  # imported here: validate of a file without placements never loads numpy

    from ..kinematics.placements import build_axes
    loc = k.get_ref(p, "location")
    coords = _vector(k, loc, "coordinates") if loc is not None else None
    if coords is not None and not all(math.isfinite(x) for x in coords):
        k.add(PLACEMENT, ERROR, f"location #{loc} {_vec(coords)} is not finite", p, "location")
    vecs = {}
    for a in ("axis", "ref_direction"):
        d = k.get_ref(p, a)
        if d is None:
            vecs[a] = None
            continue
        ratios = _vector(k, d, "direction_ratios")
        if ratios is None or len(ratios) != 3:
            return  # 2D or malformed: the schema's checks report it
        if not _nonzero(ratios):
            k.add(PLACEMENT, ERROR, f"{a} #{d} {_vec(ratios)} is a zero or non-finite direction",
                  p, a)
            return
        vecs[a] = ratios
    try:
        build_axes(vecs["axis"], vecs["ref_direction"])
    except ValueError:
        # (an unset axis is z, an unset ref_direction x: ISO 10303-42's defaults)
        k.add(PLACEMENT, ERROR, f"axis {_vec(vecs['axis'] or (0.0, 0.0, 1.0))} and ref_direction "
              f"{_vec(vecs['ref_direction'] or (1.0, 0.0, 0.0))} are parallel: the placement has no x axis "
              "(ISO 10303-42 axis2_placement_3d WR4)", p, "ref_direction")
        return
    if vecs["axis"] is not None and vecs["ref_direction"] is not None:
        z = np.asarray(vecs["axis"]) / np.linalg.norm(vecs["axis"])
        x = np.asarray(vecs["ref_direction"]) / np.linalg.norm(vecs["ref_direction"])
        c = float(abs(z @ x))
        if c > ORTHO_TOL:
            k.add(PLACEMENT, WARNING, f"ref_direction {_vec(vecs['ref_direction'])} is not "
                  f"orthogonal to axis {_vec(vecs['axis'])} (cos = {c:.3g}): ISO 10303-42 "
                  "projects it, so the x axis is not the direction written", p, "ref_direction")


def _check_cto3d(k: _Kin, p) -> None:
    import numpy as np
    axes = {}
    for a in ("axis1", "axis2", "axis3"):
        d = k.get_ref(p, a)
        if d is None:
            continue
        ratios = _vector(k, d, "direction_ratios")
        if ratios is None or len(ratios) != 3:
            return
        if not _nonzero(ratios):
            k.add(PLACEMENT, ERROR, f"{a} #{d} {_vec(ratios)} is a zero or non-finite direction",
                  p, a)
            return
        v = np.asarray(ratios, dtype=float)
        axes[a] = v / np.linalg.norm(v)
    raw_scale = k.get(p, "scale", None)
    scale = None if raw_scale is _MISSING else _num(raw_scale)
    if scale is not None:
        if not math.isfinite(scale) or scale <= 0.0:
            k.add(PLACEMENT, ERROR, f"scale {scale!r} is not a positive finite number", p, "scale")
        elif scale != 1.0 and not _close(scale, 1.0, 1e-12):
            k.add(PLACEMENT, WARNING, f"scale {_fmt(scale)} is not 1: the operator is not a rigid "
                  "placement", p, "scale")
    loc = k.get_ref(p, "local_origin")
    coords = _vector(k, loc, "coordinates") if loc is not None else None
    if coords is not None and not all(math.isfinite(x) for x in coords):
        k.add(PLACEMENT, ERROR, f"local_origin #{loc} {_vec(coords)} is not finite", p,
              "local_origin")
    # Part 42 base_axis(3, axis1, axis2, axis3): z = axis3, x = axis1 projected, y = axis2 projected
    z = axes.get("axis3", np.array([0.0, 0.0, 1.0]))
    x = axes.get("axis1")
    if x is not None and np.linalg.norm(np.cross(z, x)) <= 1e-12:
        k.add(PLACEMENT, ERROR, f"axis1 {_vec(x)} is parallel to "
              f"{'axis3' if 'axis3' in axes else 'the default axis3 (0, 0, 1)'}: the axes are "
              "linearly dependent", p, "axis1")
        return
    if x is None:
        on_x = z[1] == 0.0 and z[2] == 0.0  # Part 42 first_proj_axis default
        x = np.array([0.0, 1.0, 0.0]) if on_x else np.array([1.0, 0.0, 0.0])
    xp = x - (x @ z) * z
    xp = xp / np.linalg.norm(xp)
    y = axes.get("axis2")
    if y is not None:
        yp = y - (y @ z) * z - (y @ xp) * xp
        if np.linalg.norm(yp) <= 1e-12:
            k.add(PLACEMENT, ERROR, "axis2 lies in the plane of axis1 and axis3: the axes are "
                  "linearly dependent", p, "axis2")
            return
        if float(np.cross(z, xp) @ yp) < 0.0:
            k.add(PLACEMENT, ERROR, "axis1, axis2, axis3 are left-handed: the operator is a "
                  "reflection, not a rigid placement", p, "axis2")
            return
    names = sorted(axes)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            c = float(abs(axes[a] @ axes[b]))
            if c > ORTHO_TOL:
                k.add(PLACEMENT, WARNING, f"{a} and {b} are not orthogonal (cos = {c:.3g}): "
                      "ISO 10303-42 orthogonalises them, so the frame is not the one written",
                      p, b)


# --------------------------------------------------------------------------- KIN-UNREACHABLE

def _check_reachability(k: _Kin, mechs: list, components: dict) -> None:
    reached: set = set()
    for m in mechs:
        reached |= components[m]
    why = ("no mechanism reaches it" if mechs else
           "the file has no mechanism (1996: mechanism; AP242: mechanism_representation)")
    for i in k.order:
        if i in reached or not k.is_a(i, *_REPORTED):
            continue
        k.add(UNREACHABLE, WARNING, f"{k.label(i)} #{i} is not part of any mechanism: {why}", i)


# --------------------------------------------------------------------------- KIN-LINK-NAME

def _check_link_names(k: _Kin, mechs: list) -> None:
    for m in mechs:
        _pairs, links, _base = _mechanism_parts(k, m)
        by_name: dict = {}
        for link in links:
            reps = k.link_reps(link)
            by_name.setdefault(layout.link_name(k.mf, link, reps[0] if reps else None), []).append(link)
        for name, same in by_name.items():
            if len(same) < 2:
                continue
            same = sorted(same)
            called = ", ".join(f"'{name} #{x}'" for x in same)
            for link in same[1:]:
                k.add(LINK_NAME, WARNING, f"link name {name!r} is also the name of link #{same[0]} of "
                      f"mechanism #{m}: p105 calls them {called}", link,
                      "name" if k.mf.string(link, "name") else None)


# --------------------------------------------------------------------------- entry points

def check_kinematics(pop) -> list:
    """The ``KIN-*`` findings of a Population (see the module docstring)."""
    k = _Kin(pop)
    if not k.kin:
        return []
    mechs = k.mechanisms()
    components = {m: k.component(m) for m in mechs}
    holders = k.range_holders()
    holders_of: dict = {}
    for h, p in holders:
        holders_of.setdefault(p, []).append(h)
    _check_units(k, mechs, holders_of, components)
    _check_ranges(k, holders)
    _check_ypr(k, holders)
    _check_placements(k)
    _check_reachability(k, mechs, components)
    _check_link_names(k, mechs)
    order = {r: n for n, r in enumerate(RULES)}
    return sorted(k.out, key=lambda f: (f.entity if f.entity is not None else -1,
                                        order.get(f.rule, 99), f.attribute or "", f.message))


def context_units(pop, context_id: int) -> ContextUnits:
    """The length and plane-angle units of representation context ``#context_id``
    (:func:`p105cli.schema.units.context_units`; kept here for the checks' callers)."""
    return UnitReader(pop).context_units(context_id)
