"""Pair values: ``*_pair_value`` instances as SI tuples, one reader per pair-value family.

Families (ISO 10303-105 5.5; both layouts write them alike):

* low pairs with scalar values (revolute, prismatic, screw, cylindrical, universal,
  homokinetic, planar, gear, rack and pinion, AP242's low_order pair): their attributes in
  :attr:`PairType.value_names` order, each converted by its unit (``value_units``: plane
  angle or length) in the first link's context (``plane_angle_for_pair_in_radian``, 5.5.7);
* spherical pairs (with or without pin): ``input_orientation``, a ypr_rotation or a
  rotation_about_direction (converted by 5.5.9), as yaw, pitch, roll;
* the unconstrained pair: ``actual_placement`` as x, y, z, yaw, pitch, roll;
* AP242's ``low_order_kinematic_pair_value`` (any low-order pair may have one: the revolute,
  prismatic, ... pairs are subtypes of ``low_order_kinematic_pair`` there) is read by its own
  type: its six components (tx, ty, tz, rx, ry, rz) give the pair's values through
  ``kinematics.pairs.low_order_components`` (the one table); a component the pair's
  freedoms lock that is not 0 is left out with a warning naming the value (the value
  projected onto the pair's freedoms, :meth:`ModelFile.deviation`); on a pair without
  low-order freedoms (screw, gear, rack and pinion, higher pairs) it is an error;
* higher pairs: points on the pair's curves/surfaces (``point_on_curve`` /
  ``point_on_surface`` on the pair's geometry, their parameters converted with the Part 42
  parameter units of the curve or surface) and their ypr or rotation.

``PairValueFormat(mf).read(value_id, pair, scale, geometry)`` reads one value; ``pair`` needs
``kind`` and ``value_names`` (a ``Pair`` or ``PairType``), ``scale`` the first link's
:class:`~p105cli.part105.model_file.ContextScale`, ``geometry`` the pair's geometry as the
mechanism reader gives it (``{key: (object in its pair frame, scale, instance id)}``).
"""

from __future__ import annotations

from ..kinematics import placements as pl
from ..schema.values import number as _num
from ..schema.values import ref as _ref
from ..schema.values import untyped as _untyped
from .catalogue import HIGHER_KINDS, HIGHER_PAIR_VALUES
from .model_file import ContextScale, ModelFile, model_error

__all__ = ["PairValueFormat", "is_angle", "curve_parameter_factor", "surface_parameter_factors", "on_curve"]


def is_angle(value_name: str) -> bool:
    """A pair value attribute is a plane angle (``kinematics.pairs.VALUE_UNITS``, the one rule)."""
    from ..kinematics.pairs import VALUE_UNITS

    return VALUE_UNITS[value_name] == "A"


_is_angle = is_angle

#: A component of a low-order value below this (SI: m or rad) is 0: a projection that drops
#: it changes nothing worth a warning.
_LOCKED_COMPONENT = 1e-12


class PairValueFormat:
    """Reads ``*_pair_value`` instances of one model file in SI."""

    def __init__(self, mf: ModelFile):
        self.d = mf

    def read(self, v, pair, s: ContextScale, geometry: dict) -> tuple:
        """The values (SI, in ``pair.value_names`` order) of pair value ``#v``."""
        return self._value(v, pair, s, geometry)

    def _value(self, v, pair, s: ContextScale, geometry: dict) -> tuple:
        d = self.d
        kind = pair.kind
        if d.is_a(v, "low_order_kinematic_pair_value"):  # read by the value's type, not the pair's
            return self._low_order(v, pair, s)
        if kind in ("spherical", "spherical_with_pin"):
            return self._ypr(v, s)
        if kind == "unconstrained":
            pp = d.ref(v, "actual_placement")
            T = d.placement(pp, s)
            ypr = pl.ypr_from_matrix(T)
            return (*(float(x) for x in T[:3, 3]), *(float(a) for a in ypr))
        if kind in HIGHER_KINDS:
            return self._higher_value(v, pair, s, geometry)
        out = []
        for name in pair.value_names:
            x = d.number(v, name)
            out.append(x * (s.angle if _is_angle(name) else s.length))
        return tuple(out)

    def _low_order(self, v, pair, s: ContextScale) -> tuple:
        """A low_order_kinematic_pair_value as the values of ``pair``: its components through
        the pair's freedoms; locked components that are not 0 are projected away (warning)."""
        from ..kinematics.pairs import LOW_ORDER, LOW_ORDER_NAMED, low_order_components

        d = self.d
        kind = pair.kind
        params = getattr(pair, "params", None) or {}
        x = [d.number(v, n) * (s.angle if _is_angle(n) else s.length) for n in LOW_ORDER.value_names]
        if kind == "low_order":
            locked = LOW_ORDER.locked(params)
            comps = tuple(i for i in range(6) if not locked[i])
        elif kind in LOW_ORDER_NAMED:
            comps = low_order_components(kind, params.get("layout", "ap242"))
        else:
            raise model_error(v, f"low_order_kinematic_pair_value applies to a {kind} pair, which has no "
                                 "low-order freedoms (t_x .. r_z) to read it by; write its own "
                                 f"{kind}_pair_value")
        dropped = [i for i in range(6) if i not in comps and abs(x[i]) > _LOCKED_COMPONENT]
        if dropped:
            pair_id = d.ref_value(v, "applies_to_pair")
            said = ", ".join(f"{LOW_ORDER.value_names[i]} = {d.number(v, LOW_ORDER.value_names[i]):g}"
                             for i in dropped)
            d.deviation(v, f"low_order_kinematic_pair_value gives {said}, which the {kind} pair "
                               f"#{pair_id} cannot move (its freedoms lock it); read as 0 (the value "
                               "projected onto the pair's freedoms)")
        if kind == "low_order":
            return tuple(x[i] if i in comps else 0.0 for i in range(6))
        return tuple(x[i] for i in comps)

    def _ypr(self, v, s: ContextScale) -> tuple:
        d = self.d
        raw = d.get(v, "input_orientation")
        r = _ref(raw)
        if r is not None:
            if r not in d.pop:
                raise model_error(v, f"input_orientation refers to #{r}, which is not in the file")
            if not d.is_a(r, "rotation_about_direction"):
                raise model_error(v, f"input_orientation #{r} is no rotation_about_direction")
            direction = d.direction(r, "direction_of_axis")
            if direction is None:
                raise model_error(r, "rotation_about_direction has no direction_of_axis")
            angle = d.number(r, "rotation_angle")
            try:
                ypr = pl.convert_spatial_to_ypr_rotation(direction, angle, s.angle)
            except ValueError as e:
                raise model_error(r, str(e)) from None
            return tuple(float(x) * s.angle for x in ypr)
        vals = _untyped(raw)
        nums = [_num(x) for x in vals] if type(vals) is list else []
        if len(nums) != 3 or None in nums:
            raise model_error(v, f"input_orientation is {raw!r}, not a ypr_rotation or rotation_about_direction")
        return tuple(x * s.angle for x in nums)

    def _curve_parameter_factor(self, c, s: ContextScale) -> float:
        d = self.d
        if d.is_a(c, "trimmed_curve"):
            return self._curve_parameter_factor(d.ref(c, "basis_curve"), s)
        return s.angle if d.is_a(c, "circle", "ellipse") else 1.0

    def _surface_parameter_factors(self, g, s: ContextScale) -> tuple:
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

    @staticmethod
    def _on_curve(t_si: float, obj) -> float:
        """A basis-curve parameter (SI) as the parameter of the geometry object ``obj``."""
        from ..kinematics.geometry import TrimmedCurve

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
            raise model_error(v, f"{attr} #{pt} lies on #{basis}, not on the pair's curve #{g}")
        t = d.number(pt, "point_parameter") * self._curve_parameter_factor(basis, s)
        return self._on_curve(t, obj)

    def _point_on_surface(self, v, attr, entry) -> tuple:
        d = self.d
        obj, s, g = entry
        pt = d.ref(v, attr, types=("point_on_surface",))
        basis = d.ref(pt, "basis_surface")
        if basis != g:
            raise model_error(v, f"{attr} #{pt} lies on #{basis}, not on the pair's surface #{g}")
        fu, fv = self._surface_parameter_factors(basis, s)
        return d.number(pt, "point_parameter_u") * fu, d.number(pt, "point_parameter_v") * fv

    def _higher_value(self, v, pair, s: ContextScale, geometry: dict) -> tuple:
        d = self.d
        spec = HIGHER_PAIR_VALUES.get(pair.kind)
        if spec is None:
            raise model_error(v, f"values of {pair.kind} pairs are not read")
        out: list = []
        for attr, family, key in spec:
            if family == "point" and key.startswith("curve"):
                out.append(self._point_on_curve(v, attr, geometry[key]))
            elif family == "point":
                out.extend(self._point_on_surface(v, attr, geometry[key]))
            elif family == "ypr":
                out.extend(self._ypr(v, s))
            else:  # "A": a plane angle
                out.append(d.number(v, attr) * s.angle)
        return tuple(out)


def curve_parameter_factor(mf: ModelFile, c, s: ContextScale) -> float:
    """SI per file unit of the parameter of curve ``#c`` (Part 42 parameterises conics by
    plane angle; lines, polylines and B-splines are dimensionless)."""
    return PairValueFormat(mf)._curve_parameter_factor(c, s)


def surface_parameter_factors(mf: ModelFile, g, s: ContextScale) -> tuple:
    """SI per file unit of the (u, v) parameters of surface ``#g``."""
    return PairValueFormat(mf)._surface_parameter_factors(g, s)


def on_curve(t_si: float, obj) -> float:
    """A basis-curve parameter (SI) as the parameter of the geometry object ``obj``."""
    return PairValueFormat._on_curve(t_si, obj)


# =========================================================================== writing
# The writing direction (part105.emit and part105.results write values, part105.convert copies
# them): which entity a pair's value is, where its pair and name go in each layout, and the
# value attributes in order. The numbers are converted by the caller's own rule for reals (the
# emitter tidies them through its Builder, the results writer divides by the file unit), so
# the bytes of both stay as they were.

def value_entity(kind: str) -> str:
    """The ``*_pair_value`` entity of a pair kind (a homokinetic pair's is universal_pair_value,
    AP242's generic pair's low_order_kinematic_pair_value)."""
    if kind == "low_order":
        return "low_order_kinematic_pair_value"
    return "universal_pair_value" if kind == "homokinetic" else f"{kind}_pair_value"


def is_generic_low_order(mf: ModelFile, pair_id) -> bool:
    """Whether pair ``#pair_id`` is AP242's generic low_order_kinematic_pair (whatever kind its
    flags make it): its values are low_order_kinematic_pair_value (the named pairs' value
    entities apply only to the named pair entities)."""
    from .catalogue import GENERIC_LOW_ORDER

    try:
        return bool(mf.leaf_types(pair_id) & GENERIC_LOW_ORDER)
    except (KeyError, TypeError):
        return False


def low_order_components_of(kind: str, q, layout: str = "ap242") -> tuple:
    """A low-order pair's values ``q`` (SI, in the kind's value order) as the six components
    (tx, ty, tz, rx, ry, rz) of a low_order_kinematic_pair_value; the reading's inverse."""
    from ..kinematics.pairs import low_order_components

    if kind == "low_order":
        return tuple(float(x) for x in q)
    out = [0.0] * 6
    for c, x in zip(low_order_components(kind, layout), q):
        out[c] = float(x)
    return tuple(out)


def low_order_value_arguments(kind: str, rest: list, layout: str = "ap242"):
    """A low_order_kinematic_pair_value's arguments after its pair (file units) as the value
    of a named ``kind`` pair: ``(entity, arguments)``, or None when the kind's value is no
    list of numbers and angles (an unconstrained pair's placement, a fully constrained pair's
    nothing). Locked components are left out (the reading's projection)."""
    from ..kinematics.pairs import LOW_ORDER_NAMED, low_order_components
    from .builder import typed

    if kind == "low_order":
        return value_entity(kind), list(rest)
    if kind not in LOW_ORDER_NAMED or kind in ("unconstrained", "fully_constrained"):
        return None
    picked = [rest[c] for c in low_order_components(kind, layout)]
    if kind in ("spherical", "spherical_with_pin"):
        return value_entity(kind), [typed("ypr_rotation", picked)]
    return value_entity(kind), picked


def value_arguments(layout: str, name: str, pair_ref, values) -> list:
    """The arguments of a ``*_pair_value``: the pair, then the values (1996); the value's name,
    the pair, then the values (AP242, where a pair value is a representation_item)."""
    return [pair_ref, *values] if layout == "1996" else [name, pair_ref, *values]


def scalar_values(units, q, angle, length) -> list:
    """Scalar pair values ``q`` (SI, in value order) in the file: ``angle(x)`` for a plane angle,
    ``length(x)`` for the rest (``units`` is ``PairType.value_units``)."""
    return [angle(x) if u == "A" else length(x) for u, x in zip(units, q)]


def ypr_values(ypr, angle) -> list:
    """A ``ypr_rotation``'s three values in the file (``angle(x)`` from radians): THE way p105
    writes a ypr triple. It is the canonical triple of 5.3.7
    (:func:`p105cli.kinematics.placements.canonical_ypr`: roll 0 at a rectangular pitch),
    whatever triple the analysis produced or the user drove, so validate accepts it."""
    from p105cli.kinematics.placements import canonical_ypr
    from .catalogue import YPR_REL_TOL
    return [angle(x) for x in canonical_ypr(*ypr, YPR_REL_TOL)]


def value_attributes(mf: ModelFile, v) -> tuple:
    """``(pair id, [raw value of each of the value entity's own attributes, in order])`` of pair
    value ``#v``, in file units (what a converter copies into the other layout); the pair id is
    None when ``applies_to_pair`` names none."""
    inst = mf.pop.instance(v)
    own = [inst.raw(n) for n, slot in enumerate(inst.layout.slots)
           if slot.entity not in ("representation_item", "pair_value")]
    return mf.ref_value(v, "applies_to_pair"), own


__all__ += ["value_entity", "is_generic_low_order", "low_order_components_of", "low_order_value_arguments",
            "value_arguments", "scalar_values", "ypr_values", "value_attributes"]
