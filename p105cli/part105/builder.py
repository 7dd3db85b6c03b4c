"""A small builder of p105/1 JSON-model records for authored Part 21 files.

``Builder.add(type, *args)`` appends a simple instance and returns its
reference (``{"ref": n}``); ``Builder.add_complex([(type, args), ...])``
appends a complex instance with its partial entities sorted alphabetically,
as the Part 21 external mapping requires. Ids are allocated 1, 2, 3, ... in
creation order, so the same calls give the same file.

Values are the JSON model's: ``int``, ``float``, ``str``, ``None`` (``$``),
:data:`DERIVED` (``*``), references ``{"ref": n}``, enumerations
(:func:`enum`, :data:`TRUE`, :data:`FALSE`), typed parameters
(:func:`typed`) and lists. numpy scalars and tuples are converted; reals
are tidied (``-0.0`` and values within 1e-12 of zero become ``0.0``,
values within 1e-11 of an integer become that integer) so that files do
not carry round-off noise.

The helpers on top write what every mechanism file needs: points,
directions, ``axis2_placement_3d``, the units (millimetre, radian, the
degree as a conversion-based unit of the radian, steradian), the
uncertainty, complex representation contexts, and products with their
definitions and shapes.
"""

from __future__ import annotations

import math
from numbers import Integral, Real

import numpy as np

__all__ = [
    "DERIVED", "TRUE", "FALSE", "DEGREE_FACTOR", "Builder", "enum", "typed", "boolean", "tidy",
]

#: The ``*`` of Part 21 (an attribute re-declared as derived).
DERIVED = {"derived": True}

#: The conversion factor written for the degree (radians per degree), as CAD
#: systems write it.
DEGREE_FACTOR = 0.0174532925199433


def enum(name: str) -> dict:
    """An enumeration value, e.g. ``enum("milli")`` -> ``.MILLI.``."""
    return {"enum": name.upper()}


TRUE = enum("T")
FALSE = enum("F")


def boolean(flag: bool) -> dict:
    return TRUE if flag else FALSE


def typed(type_name: str, value) -> dict:
    """A typed parameter, e.g. ``typed("length_measure", 1e-7)`` -> ``LENGTH_MEASURE(1.E-07)``."""
    return {"type": type_name.upper(), "value": tidy(value)}


def _tidy_real(x: float) -> float:
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"{x!r} cannot be written to Part 21")
    if abs(x) < 1e-12:
        return 0.0
    r = round(x)
    if abs(x - r) < 1e-11:
        return float(r)
    return x


def tidy(value):
    """The JSON-model form of ``value`` (see the module docstring)."""
    if value is None or isinstance(value, (str, dict)) and not isinstance(value, bool):
        if isinstance(value, dict) and "value" in value:
            return {"type": value["type"], "value": tidy(value["value"])}
        return value
    if isinstance(value, bool):
        return boolean(value)
    if isinstance(value, Integral):
        return int(value)
    if isinstance(value, Real):
        return _tidy_real(value)
    if isinstance(value, (list, tuple, np.ndarray)):
        return [tidy(v) for v in value]
    raise TypeError(f"cannot write {type(value).__name__} {value!r}")


def real(x) -> float:
    """A tidied real (for arguments that must be reals even when integral)."""
    return _tidy_real(x)


class Builder:
    """Collects JSON-model records with automatic ids.

    ``angle_factor`` converts radians to the plane-angle unit of the file's
    contexts (the degree by default): every plane-angle argument goes through
    :meth:`angle`.
    """

    def __init__(self, angle_factor: float = 180.0 / math.pi):
        self.data: list[dict] = []
        self.angle_factor = angle_factor
        self._units: dict | None = None

    # ------------------------------------------------------------ records
    def _next_id(self) -> int:
        return len(self.data) + 1

    def add(self, etype: str, *args) -> dict:
        """Append ``#n=ETYPE(args);`` and return ``{"ref": n}``."""
        iid = self._next_id()
        self.data.append({"id": iid, "type": etype.lower(), "args": [tidy(a) for a in args]})
        return {"ref": iid}

    def add_complex(self, parts) -> dict:
        """Append a complex instance; ``parts`` are ``(type, args)`` in any order."""
        iid = self._next_id()
        items = sorted(((t.lower(), [tidy(a) for a in args]) for t, args in parts), key=lambda p: p[0])
        names = [t for t, _ in items]
        if len(set(names)) != len(names):
            raise ValueError(f"complex instance names a partial entity twice: {names}")
        self.data.append({"id": iid, "complex": [{"type": t, "args": a} for t, a in items]})
        return {"ref": iid}

    def angle(self, radians) -> float | list:
        """Radians in the file's plane-angle unit."""
        if isinstance(radians, (list, tuple, np.ndarray)):
            return [self.angle(r) for r in radians]
        return real(float(radians) * self.angle_factor)

    # ------------------------------------------------------------ geometry
    def point(self, xyz, name: str = "") -> dict:
        return self.add("cartesian_point", name, [real(c) for c in np.asarray(xyz, float)[:3]])

    def direction(self, v, name: str = "") -> dict:
        v = np.asarray(v, float)[:3]
        n = float(np.linalg.norm(v))
        if n == 0.0:
            raise ValueError("zero direction")
        return self.add("direction", name, [real(c) for c in v / n])

    def axis2(self, T, name: str = "") -> dict:
        """``AXIS2_PLACEMENT_3D`` of the 4x4 rigid transform ``T`` (origin, z axis, x axis)."""
        T = np.asarray(T, float)
        return self.add("axis2_placement_3d", name, self.point(T[:3, 3]),
                        self.direction(T[:3, 2]), self.direction(T[:3, 0]))

    def cartesian_transformation_operator_3d(self, T, name: str = "") -> dict:
        """``CARTESIAN_TRANSFORMATION_OPERATOR_3D`` of the rigid transform ``T`` (scale 1)."""
        T = np.asarray(T, float)
        return self.add("cartesian_transformation_operator_3d", name, name, None,
                        self.direction(T[:3, 0]), self.direction(T[:3, 1]), self.point(T[:3, 3]),
                        1.0, self.direction(T[:3, 2]))

    def polyline(self, points, name: str = "") -> dict:
        """A polyline; a two-point one gets its midpoint (wireframe shapes need more than two)."""
        pts = [np.asarray(p, float) for p in points]
        if len(pts) == 2:
            pts.insert(1, (pts[0] + pts[1]) / 2.0)
        return self.add("polyline", name, [self.point(p) for p in pts])

    def circle(self, T, radius: float, name: str = "") -> dict:
        """A circle in the plane z = 0 of the placement ``T``; its parameter is an angle
        (Part 42) measured from the placement's x axis, in the file's plane-angle unit."""
        return self.add("circle", name, self.axis2(T), real(radius))

    # ------------------------------------------------------------ units and contexts
    def units(self, *, cbu_dimensions_explicit: bool, length_prefix: str | None = "milli",
              angle: str = "degree", uncertainty: float = 1e-7, degree_factor: float = DEGREE_FACTOR) -> dict:
        """Millimetre, radian, degree (conversion-based), steradian and the length
        uncertainty, written once per file; returns a dict of references.

        ``cbu_dimensions_explicit``: the degree's ``named_unit.dimensions`` is a
        ``DIMENSIONAL_EXPONENTS`` instance (AP242, and what CAD systems write)
        or ``*`` where the schema derives it (the AP214 ed3 long form re-declares
        it as DERIVE in ``conversion_based_unit``).

        ``length_prefix`` (an SI prefix such as ``"milli"``, or None for the
        metre), ``angle`` (``"degree"`` or ``"radian"``), ``uncertainty``
        (in that length unit) and ``degree_factor`` (radians per degree as
        written) choose other global units (the model writer);
        the defaults are the corpus's. The keys of the returned dict stay
        ``mm`` (the length unit) and ``deg`` (the plane-angle unit in use).
        """
        if self._units is not None:
            raise RuntimeError("Builder.units: the units are already written")
        prefix = enum(length_prefix) if length_prefix else None
        mm = self.add_complex([("length_unit", []), ("named_unit", [DERIVED]),
                               ("si_unit", [prefix, enum("metre")])])
        rad = self.add_complex([("named_unit", [DERIVED]), ("plane_angle_unit", []),
                                ("si_unit", [None, enum("radian")])])
        if angle == "degree":
            factor = self.add("plane_angle_measure_with_unit", typed("plane_angle_measure", degree_factor), rad)
            if cbu_dimensions_explicit:
                dims = self.add("dimensional_exponents", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
            else:
                dims = DERIVED
            deg = self.add_complex([("conversion_based_unit", ["DEGREE", factor]), ("named_unit", [dims]),
                                    ("plane_angle_unit", [])])
        elif angle == "radian":
            deg = rad
        else:
            raise ValueError(f"Builder.units: plane-angle unit {angle!r} (degree or radian)")
        sr = self.add_complex([("named_unit", [DERIVED]), ("si_unit", [None, enum("steradian")]),
                               ("solid_angle_unit", [])])
        unc = self.add("uncertainty_measure_with_unit", typed("length_measure", uncertainty), mm,
                       "distance_accuracy_value", "confusion accuracy")
        self._units = {"mm": mm, "rad": rad, "deg": deg, "sr": sr, "uncertainty": unc}
        return self._units

    def context(self, identifier: str, context_type: str = "3D", *, with_parameter: bool = False) -> dict:
        """A 3D ``GEOMETRIC_REPRESENTATION_CONTEXT`` with global units (mm, degree,
        steradian) and uncertainty: a complex instance; with ``with_parameter``
        also ``GEOMETRIC_REPRESENTATION_CONTEXT_WITH_PARAMETER`` (parameter unit
        ``$``, a dimensionless path parameter). :meth:`units` must come first."""
        if self._units is None:
            raise RuntimeError("Builder.context: write the units first (Builder.units)")
        u = self._units
        parts = [("geometric_representation_context", [3]),
                 ("global_uncertainty_assigned_context", [[u["uncertainty"]]]),
                 ("global_unit_assigned_context", [[u["mm"], u["deg"], u["sr"]]]),
                 ("representation_context", [identifier, context_type])]
        if with_parameter:
            parts.append(("geometric_representation_context_with_parameter", [None]))
        return self.add_complex(parts)

    # ------------------------------------------------------------ products
    def product_frame(self, application: str, schema_name: str, year: int) -> dict:
        """Application context and protocol, product and product-definition contexts."""
        app = self.add("application_context", application)
        self.add("application_protocol_definition", "international standard", schema_name, year, app)
        pc = self.add("product_context", "", app, "mechanical")
        pdc = self.add("product_definition_context", "part definition", app, "design")
        return {"app": app, "product_context": pc, "pd_context": pdc}

    def part(self, frame: dict, pid: str, name: str, description: str, shape_items: list, context: dict,
             shape_name: str | None = None, shape_type: str = "shape_representation") -> dict:
        """PRODUCT, its formation and definition, the definition's shape and a
        shape representation (``shape_type``) of ``shape_items`` in ``context``."""
        product = self.add("product", pid, name, description, [frame["product_context"]])
        pdf = self.add("product_definition_formation", "1", "", product)
        pd = self.add("product_definition", "design", description, pdf, frame["pd_context"])
        pds = self.add("product_definition_shape", "", "", pd)
        shape = self.add(shape_type, shape_name or name, shape_items, context)
        self.add("shape_definition_representation", pds, shape)
        return {"product": product, "pd": pd, "pds": pds, "shape": shape}

    def assembly_usage(self, assembly: dict, component: dict, uid: str, name: str,
                       item_in_component: dict, item_in_assembly: dict) -> dict:
        """NEXT_ASSEMBLY_USAGE_OCCURRENCE and its placement (a context-dependent
        shape representation whose transformation maps the component's
        ``item_in_component`` onto ``item_in_assembly``)."""
        nauo = self.add("next_assembly_usage_occurrence", uid, name, "", assembly["pd"], component["pd"], None)
        idt = self.add("item_defined_transformation", "", "", item_in_component, item_in_assembly)
        rel = self.add_complex([("representation_relationship", ["", "", component["shape"], assembly["shape"]]),
                                ("representation_relationship_with_transformation", [idt]),
                                ("shape_representation_relationship", [])])
        pds = self.add("product_definition_shape", "", "", nauo)
        self.add("context_dependent_shape_representation", rel, pds)
        return {"nauo": nauo, "pds": pds}
