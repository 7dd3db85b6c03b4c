"""Pair values: ``*_pair_value`` instances as SI tuples, one reader per pair-value family.

Families (ISO 10303-105 5.5; both layouts write them alike):

* low pairs with scalar values (revolute, prismatic, screw, cylindrical, universal,
  homokinetic, planar, gear, rack and pinion, AP242's low_order pair): their attributes in
  :attr:`PairType.value_names` order, each converted by its unit (``value_units``: plane
  angle or length) in the first link's context (``plane_angle_for_pair_in_radian``, 5.5.7);
* spherical pairs (with or without pin): ``input_orientation``, a ypr_rotation or a
  rotation_about_direction (converted by 5.5.9), as yaw, pitch, roll;
* the unconstrained pair: ``actual_placement`` as x, y, z, yaw, pitch, roll;
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
    """The ``*_pair_value`` entity of a pair kind (a homokinetic pair's is universal_pair_value)."""
    return "universal_pair_value" if kind == "homokinetic" else f"{kind}_pair_value"


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


__all__ += ["value_entity", "value_arguments", "scalar_values", "ypr_values", "value_attributes"]
