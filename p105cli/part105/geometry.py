"""ISO 10303-42 instances <-> :mod:`p105cli.kinematics.geometry` objects (for the higher pairs'
curves and surfaces and the motion paths of Part 105 files).

Reading: :func:`curve_from_instance` and :func:`surface_from_instance` turn
an instance of a :class:`p105cli.schema.population.Population` into a curve
or surface object. Writing: :func:`curve_records` and
:func:`surface_records` turn an object back into p105/1 JSON-model records
(``{"id", "type", "args"}`` or ``{"id", "complex"}``, arguments in Part 21
order, see docs/json-model.md).

Units. ``length_factor`` is the SI value of the file's length unit (metres
per file unit) and ``angle_factor`` the radians per file plane-angle unit,
in both directions: reading multiplies file values by them, writing divides.
Lengths are coordinates, vector magnitudes and radii; angles are the
``semi_angle`` of a cone and the trimming parameters of a trimmed conic
(Part 42 parameterises circles and ellipses by angle in the plane-angle
unit). B-spline knots, polyline parameters and line parameters are
dimensionless and are never scaled.

Supported: cartesian_point, direction, vector, axis2_placement_3d, line,
circle, ellipse, polyline, b_spline_curve_with_knots (and the complex
instance with rational_b_spline_curve), trimmed_curve (trimmed by
parameter values, or by cartesian points on a line, circle or ellipse),
plane, cylindrical_surface, conical_surface, spherical_surface,
toroidal_surface, b_spline_surface_with_knots (and rational). Anything else
raises :class:`p105cli.step.errors.ModelError` naming the ``#id``.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..step.errors import ModelError
from ..schema.values import is_true as _is_true
from ..schema.values import number
from ..step.values import ref_id
from ..kinematics import geometry as G
from ..kinematics.placements import axis2_placement_3d
from .model_file import MAX_MAGNITUDE

__all__ = ["curve_from_instance", "surface_from_instance", "curve_records", "surface_records",
           "CURVE_TYPES", "SURFACE_TYPES"]

CURVE_TYPES = ("line", "circle", "ellipse", "polyline", "b_spline_curve_with_knots", "trimmed_curve")
SURFACE_TYPES = ("plane", "cylindrical_surface", "conical_surface", "spherical_surface", "toroidal_surface",
                 "b_spline_surface_with_knots")


# --------------------------------------------------------------------------- reading

_ref = ref_id


def _num(v, inst, attr) -> float:
    x = number(v)  # typed parameters too, e.g. LENGTH_MEASURE(1.)
    if x is None:
        raise ModelError(f"#{inst.id} ({_kind(inst)}): {attr} is not a number ({v!r})", f"#{inst.id}")
    if not abs(x) <= MAX_MAGNITUDE:  # the same bound as every other number a mechanism is read with
        raise ModelError(f"#{inst.id} ({_kind(inst)}): {attr} holds {x!r}, beyond the magnitudes p105 computes "
                         f"with ({MAX_MAGNITUDE:g})", f"#{inst.id}")
    return x


def _kind(inst) -> str:
    return "+".join(sorted(inst.leaf_types)) or "?"


def _get(inst, attr):
    try:
        return inst.get(attr)
    except Exception as exc:  # SchemaError: no such attribute
        raise ModelError(f"#{inst.id} ({_kind(inst)}): {exc}", f"#{inst.id}") from None


def _deref(pop, inst, attr, value=None):
    v = _get(inst, attr) if value is None else value
    r = _ref(v)
    if r is None or r not in pop:
        raise ModelError(f"#{inst.id} ({_kind(inst)}): {attr} is not a reference to an instance ({v!r})",
                         f"#{inst.id}")
    return pop.instance(r)


def _is(inst, name) -> bool:
    return name in inst.types


def _point(pop, inst, lf) -> np.ndarray:
    if not _is(inst, "cartesian_point"):
        raise ModelError(f"#{inst.id} ({_kind(inst)}) is not a cartesian_point", f"#{inst.id}")
    c = [_num(x, inst, "coordinates") for x in (_get(inst, "coordinates") or [])]
    if len(c) != 3:
        raise ModelError(f"#{inst.id}: only 3D cartesian points are supported (got {len(c)} coordinates)",
                         f"#{inst.id}")
    return np.array(c) * lf


def _direction(inst) -> np.ndarray:
    if not _is(inst, "direction"):
        raise ModelError(f"#{inst.id} ({_kind(inst)}) is not a direction", f"#{inst.id}")
    d = np.array([_num(x, inst, "direction_ratios") for x in (_get(inst, "direction_ratios") or [])])
    if d.shape != (3,) or not np.linalg.norm(d) > 0:
        raise ModelError(f"#{inst.id}: direction_ratios must be 3 numbers, not all zero", f"#{inst.id}")
    return d


def _placement(pop, inst, lf) -> np.ndarray:
    if not _is(inst, "axis2_placement_3d"):
        raise ModelError(f"#{inst.id} ({_kind(inst)}): only axis2_placement_3d positions are supported",
                         f"#{inst.id}")
    loc = _point(pop, _deref(pop, inst, "location"), lf)
    axis = _get(inst, "axis")
    ref = _get(inst, "ref_direction")
    a = _direction(_deref(pop, inst, "axis", axis)) if axis is not None else None
    r = _direction(_deref(pop, inst, "ref_direction", ref)) if ref is not None else None
    try:
        return axis2_placement_3d(loc, a, r)
    except ValueError as exc:
        raise ModelError(f"#{inst.id} (axis2_placement_3d): {exc}", f"#{inst.id}") from None


def placement_from_instance(pop, inst, length_factor: float = 1.0) -> np.ndarray:
    """An ``axis2_placement_3d`` instance as a 4x4 (location scaled by ``length_factor``)."""
    return _placement(pop, inst, length_factor)


def point_from_instance(pop, inst, length_factor: float = 1.0) -> np.ndarray:
    """A 3D ``cartesian_point`` instance as a (3,) array scaled by ``length_factor``."""
    return _point(pop, inst, length_factor)


def _trim_parameter(pop, inst, basis, values, which, lf, af) -> float:
    conic = isinstance(basis, G.Ellipse)
    for v in values or []:
        if isinstance(v, dict) and v.get("type", "").upper() == "PARAMETER_VALUE":
            return _num(v, inst, which) * (af if conic else 1.0)
    for v in values or []:
        r = _ref(v)
        if r is not None and r in pop:
            p = _point(pop, pop.instance(r), lf)
            if isinstance(basis, G.Line):
                d = basis.dir
                return float(np.dot(p - basis.pnt, d) / np.dot(d, d))
            if conic:
                rel = p - basis.c
                return float(np.arctan2(np.dot(rel, basis.y) / basis.b, np.dot(rel, basis.x) / basis.a))
            raise ModelError(f"#{inst.id} (trimmed_curve): {which} is a cartesian point on a "
                             f"{type(basis).__name__}; only parameter values are supported there",
                             f"#{inst.id}")
    raise ModelError(f"#{inst.id} (trimmed_curve): {which} has no parameter value or point", f"#{inst.id}")


def curve_from_instance(pop, inst, length_factor: float = 1.0, angle_factor: float = 1.0):
    """The geometry object of a Part 42 curve instance (see the module docstring)."""
    lf, af = float(length_factor), float(angle_factor)
    try:
        if _is(inst, "line"):
            vec = _deref(pop, inst, "dir")
            d = _direction(_deref(pop, vec, "orientation"))
            mag = _num(_get(vec, "magnitude"), vec, "magnitude")
            return G.Line(_point(pop, _deref(pop, inst, "pnt"), lf), d / np.linalg.norm(d) * mag * lf)
        if _is(inst, "circle"):
            return G.Circle(_placement(pop, _deref(pop, inst, "position"), lf),
                            _num(_get(inst, "radius"), inst, "radius") * lf)
        if _is(inst, "ellipse"):
            return G.Ellipse(_placement(pop, _deref(pop, inst, "position"), lf),
                             _num(_get(inst, "semi_axis_1"), inst, "semi_axis_1") * lf,
                             _num(_get(inst, "semi_axis_2"), inst, "semi_axis_2") * lf)
        if _is(inst, "polyline"):
            pts = [_point(pop, _deref(pop, inst, "points", v), lf) for v in _get(inst, "points") or []]
            return G.Polyline(np.array(pts))
        if _is(inst, "b_spline_curve_with_knots"):
            pts = [_point(pop, _deref(pop, inst, "control_points_list", v), lf)
                   for v in _get(inst, "control_points_list") or []]
            w = None
            if _is(inst, "rational_b_spline_curve"):
                w = [_num(x, inst, "weights_data") for x in _get(inst, "weights_data") or []]
            return G.BSplineCurve(int(_num(_get(inst, "degree"), inst, "degree")), np.array(pts),
                                  [int(_num(m, inst, "knot_multiplicities"))
                                   for m in _get(inst, "knot_multiplicities") or []],
                                  [_num(k, inst, "knots") for k in _get(inst, "knots") or []], w)
        if _is(inst, "trimmed_curve"):
            basis = curve_from_instance(pop, _deref(pop, inst, "basis_curve"), lf, af)
            t1 = _trim_parameter(pop, inst, basis, _get(inst, "trim_1"), "trim_1", lf, af)
            t2 = _trim_parameter(pop, inst, basis, _get(inst, "trim_2"), "trim_2", lf, af)
            return G.TrimmedCurve(basis, t1, t2, _is_true(_get(inst, "sense_agreement")))
    except (ValueError, TypeError) as exc:
        raise ModelError(f"#{inst.id} ({_kind(inst)}): {exc}", f"#{inst.id}") from None
    raise ModelError(f"#{inst.id} ({_kind(inst)}): curve type not supported (supported: "
                     f"{', '.join(CURVE_TYPES)})", f"#{inst.id}")


def surface_from_instance(pop, inst, length_factor: float = 1.0, angle_factor: float = 1.0):
    """The geometry object of a Part 42 surface instance (see the module docstring)."""
    lf, af = float(length_factor), float(angle_factor)
    try:
        if _is(inst, "elementary_surface"):
            pos = _placement(pop, _deref(pop, inst, "position"), lf)
            if _is(inst, "plane"):
                return G.Plane(pos)
            if _is(inst, "cylindrical_surface"):
                return G.CylindricalSurface(pos, _num(_get(inst, "radius"), inst, "radius") * lf)
            if _is(inst, "conical_surface"):
                return G.ConicalSurface(pos, _num(_get(inst, "radius"), inst, "radius") * lf,
                                        _num(_get(inst, "semi_angle"), inst, "semi_angle") * af)
            if _is(inst, "spherical_surface"):
                return G.SphericalSurface(pos, _num(_get(inst, "radius"), inst, "radius") * lf)
            if _is(inst, "toroidal_surface"):
                return G.ToroidalSurface(pos, _num(_get(inst, "major_radius"), inst, "major_radius") * lf,
                                         _num(_get(inst, "minor_radius"), inst, "minor_radius") * lf)
        if _is(inst, "b_spline_surface_with_knots"):
            rows = _get(inst, "control_points_list") or []
            P = np.array([[_point(pop, _deref(pop, inst, "control_points_list", v), lf) for v in row]
                          for row in rows])
            w = None
            if _is(inst, "rational_b_spline_surface"):
                w = np.array([[_num(x, inst, "weights_data") for x in row]
                              for row in _get(inst, "weights_data") or []])

            def ints(a):
                return [int(_num(m, inst, a)) for m in _get(inst, a) or []]

            def reals(a):
                return [_num(k, inst, a) for k in _get(inst, a) or []]

            return G.BSplineSurface(int(_num(_get(inst, "u_degree"), inst, "u_degree")),
                                    int(_num(_get(inst, "v_degree"), inst, "v_degree")), P,
                                    ints("u_multiplicities"), ints("v_multiplicities"),
                                    reals("u_knots"), reals("v_knots"), w)
    except (ValueError, TypeError) as exc:
        raise ModelError(f"#{inst.id} ({_kind(inst)}): {exc}", f"#{inst.id}") from None
    raise ModelError(f"#{inst.id} ({_kind(inst)}): surface type not supported (supported: "
                     f"{', '.join(SURFACE_TYPES)})", f"#{inst.id}")


# --------------------------------------------------------------------------- writing

_F, _T = {"enum": "F"}, {"enum": "T"}
_UNSPEC = {"enum": "UNSPECIFIED"}


def _reals(a) -> list:
    return [float(x) for x in np.asarray(a, dtype=float).ravel()]


class _Writer:
    def __init__(self, new_id: Callable[[], int], lf: float, af: float):
        self.new_id, self.lf, self.af = new_id, float(lf), float(af)
        self.records: list = []

    def add(self, type_, args) -> dict:
        i = self.new_id()
        self.records.append({"id": i, "type": type_, "args": args})
        return {"ref": i}

    def add_complex(self, parts) -> dict:
        i = self.new_id()
        self.records.append({"id": i, "complex": [{"type": t, "args": a} for t, a in parts]})
        return {"ref": i}

    def point(self, p) -> dict:
        return self.add("cartesian_point", ["", _reals(np.asarray(p) / self.lf)])

    def direction(self, d) -> dict:
        return self.add("direction", ["", _reals(d)])

    def placement(self, T) -> dict:
        T = np.asarray(T, dtype=float)
        if T.shape != (4, 4):
            raise ValueError("only unbatched geometry can be written (position must be one 4x4 transform)")
        return self.add("axis2_placement_3d", ["", self.point(T[:3, 3]), self.direction(T[:3, 2]),
                                               self.direction(T[:3, 0])])

    def length(self, x) -> float:
        x = np.asarray(x, dtype=float)
        if x.shape != ():
            raise ValueError("only unbatched geometry can be written (a length is an array)")
        return float(x) / self.lf

    def curve(self, c) -> dict:
        if isinstance(c, G.Line):
            mag = float(np.linalg.norm(c.dir))
            if not mag > 0:
                raise ValueError("line: zero direction vector")
            vec = self.add("vector", ["", self.direction(c.dir / mag), mag / self.lf])
            return self.add("line", ["", self.point(c.pnt), vec])
        if isinstance(c, G.Circle):
            return self.add("circle", ["", self.placement(c.position), self.length(c.radius)])
        if isinstance(c, G.Ellipse):
            return self.add("ellipse", ["", self.placement(c.position), self.length(c.a), self.length(c.b)])
        if isinstance(c, G.Polyline):
            return self.add("polyline", ["", [self.point(p) for p in c.points]])
        if isinstance(c, G.BSplineCurve):
            pts = [self.point(p) for p in c.P]
            mults = [int(m) for m in c.knot_multiplicities]
            knots = _reals(c.knots)
            if c.w is None:
                return self.add("b_spline_curve_with_knots", ["", c.degree, pts, _UNSPEC, _F, _F, mults, knots,
                                                              _UNSPEC])
            return self.add_complex([
                ("bounded_curve", []), ("b_spline_curve", [c.degree, pts, _UNSPEC, _F, _F]),
                ("b_spline_curve_with_knots", [mults, knots, _UNSPEC]), ("curve", []),
                ("geometric_representation_item", []), ("rational_b_spline_curve", [_reals(c.w)]),
                ("representation_item", [""])])
        if isinstance(c, G.TrimmedCurve):
            basis = self.curve(c.basis)
            f = self.af if isinstance(c.basis, G.Ellipse) else 1.0
            return self.add("trimmed_curve", [
                "", basis, [{"type": "PARAMETER_VALUE", "value": c.trim_1 / f}],
                [{"type": "PARAMETER_VALUE", "value": c.trim_2 / f}], _T if c.sense else _F,
                {"enum": "PARAMETER"}])
        raise TypeError(f"cannot write {type(c).__name__} as a Part 42 curve")

    def surface(self, s) -> dict:
        if isinstance(s, G.Plane):
            return self.add("plane", ["", self.placement(s.position)])
        if isinstance(s, G.CylindricalSurface):
            return self.add("cylindrical_surface", ["", self.placement(s.position), self.length(s.radius)])
        if isinstance(s, G.ConicalSurface):
            return self.add("conical_surface", ["", self.placement(s.position), self.length(s.radius),
                                                float(s.semi_angle) / self.af])
        if isinstance(s, G.SphericalSurface):
            return self.add("spherical_surface", ["", self.placement(s.position), self.length(s.radius)])
        if isinstance(s, G.ToroidalSurface):
            return self.add("toroidal_surface", ["", self.placement(s.position), self.length(s.major_radius),
                                                 self.length(s.minor_radius)])
        if isinstance(s, G.BSplineSurface):
            pts = [[self.point(p) for p in row] for row in s.P]
            knots = [[int(m) for m in s.u_multiplicities], [int(m) for m in s.v_multiplicities],
                     _reals(s.u_knots), _reals(s.v_knots)]
            if s.w is None:
                return self.add("b_spline_surface_with_knots", ["", s.pu, s.pv, pts, _UNSPEC, _F, _F, _F,
                                                                *knots, _UNSPEC])
            return self.add_complex([
                ("bounded_surface", []), ("b_spline_surface", [s.pu, s.pv, pts, _UNSPEC, _F, _F, _F]),
                ("b_spline_surface_with_knots", [*knots, _UNSPEC]), ("geometric_representation_item", []),
                ("rational_b_spline_surface", [[_reals(row) for row in s.w]]), ("representation_item", [""]),
                ("surface", [])])
        raise TypeError(f"cannot write {type(s).__name__} as a Part 42 surface")


def curve_records(obj, new_id: Callable[[], int], length_factor: float = 1.0,
                  angle_factor: float = 1.0) -> tuple:
    """``(ref_id, records)``: p105/1 records of a curve object; ``new_id()`` allocates ids.

    The curve's own record is the last one; ``ref_id`` is its id."""
    w = _Writer(new_id, length_factor, angle_factor)
    ref = w.curve(obj)
    return ref["ref"], w.records


def surface_records(obj, new_id: Callable[[], int], length_factor: float = 1.0,
                    angle_factor: float = 1.0) -> tuple:
    """``(ref_id, records)``: p105/1 records of a surface object (see :func:`curve_records`)."""
    w = _Writer(new_id, length_factor, angle_factor)
    ref = w.surface(obj)
    return ref["ref"], w.records
