"""Write a :class:`~p105cli.kinematics.model.Mechanism` as Part 105 data, in any profile.

``write_mechanism(mech, profile, *, source=None, occt_compat=False)``
returns ``(JsonDocument, diagnostics)``.

Profiles (the corpus's, :data:`p105cli.corpus.writers.PROFILES`):

* ``ap214`` - the Part 105:1996 layout as AP214's long form carries it
  (FILE_SCHEMA AUTOMOTIVE_DESIGN; pair frames are axis2_placement_3d only);
* ``p105`` - the same layout with ``su_parameters`` allowed;
* ``ap242`` - the AP242 (Part 105 ed. 2) layout.

Two modes:

* ``source=None``: a complete, self-contained file: the units of
  ``mech.units``, contexts, one product per link and the mechanism
  assembly (links placed at the initial state), link representations, the
  pairs with their ranges and actuation (and the higher pairs' curves and
  surfaces), the base (placement), the initial state and, in AP242, the
  loops. Built with the corpus's :class:`~p105cli.part105.builder.Builder`
  (units, contexts, placements, products are written by the same code).
* ``source`` = the document the mechanism was read from: a *conversion*.
  Every instance outside the kinematic structure (products, shapes,
  geometry, units, contexts) is kept with its id; the kinematic instances
  are rewritten in the target layout; new instances get the ids of the
  source instances they replace where the role is the same (pair, joint,
  link, range, actuator, initial-state values), else ids above the source's
  maximum; references are remapped. Supporting items that only the old
  kinematic instances used (a replaced pair frame, the 1996 base
  placement's operator) go with them.

The motion program's configuration sequences are converted between the
layouts; other kinematic instances the writer does not produce (paths,
programs, results) are kept as they are when the target has their
entities and all they refer to is still there with the same type (a
same-layout conversion keeps them), else left out.

Nothing is dropped silently: whatever the target layout cannot say, and
every kinematic instance of the source that is neither re-expressed nor
kept, is one diagnostic string naming the ``#id``. See docs/conversion.md
for the layout differences and choices.

``occt_compat`` (AP242): Open CASCADE's reader misreads the standard ``*``
of derived attributes: it takes the derived freedom flags of a
``low_order_kinematic_pair`` subtype as all TRUE, the derived name of a
pair as missing, the derived context of a mechanism state as missing; it
reads a typed ``YPR_ROTATION`` orientation as a bad real, and it does not
know the ``actuated_kinematic_pair`` complex instance, ``kinematic_loop``
or the interpolated configuration entities. With ``occt_compat`` the flags
(``.T.``/``.F.``, the values the schema derives), the pair's name and the
state's context are written explicitly, orientations as the equal
``rotation_about_direction``, and actuation, loops and configuration
sequences are left out (a diagnostic each): the file loads in Open
CASCADE with an empty check list, at the price of SCH-* conformance
findings for the explicit values where the schema says ``*``.

SI inside the model; the writer converts to the file's units (``mech.units``,
or the source's units in a conversion).
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from p105cli.part105.builder import DERIVED, FALSE, TRUE, Builder, enum, real, typed
from p105cli.part105.catalogue import APPLICATION as _APPLICATION, PROFILES as _CATALOGUE_PROFILES
from p105cli.step.values import record_refs as _rec_refs, ref_id

from .dh import Z_TO_X
from .pairs import PAIR_KINDS
from .placements import compose, inverse

__all__ = ["PROFILES", "write_mechanism", "SUPPORTED_KINDS"]

#: Schema profiles the writer knows: layout, su_parameters allowed, FILE_SCHEMA.
PROFILES = {k: dict(v) for k, v in _CATALOGUE_PROFILES.items()}

#: Per pair kind: the unit of each value ("A" plane angle, "L" length), in value order.
_WRITTEN_LOW_KINDS = ("revolute", "prismatic", "screw", "cylindrical", "spherical", "universal", "homokinetic",
                      "planar", "unconstrained", "fully_constrained", "gear", "rack_and_pinion")
_VALUE_UNITS = {k: "".join(PAIR_KINDS[k].value_units) for k in _WRITTEN_LOW_KINDS}
#: Higher pairs: their geometry (params key, which pair frame it is given in), in the order of
#: the pair's attributes; whether an ``orientation`` flag follows.
_GEOMETRY = {
    "point_on_planar_curve": ((("curve", 1),), True),
    "point_on_surface": ((("surface", 1),), False),
    "sliding_curve": ((("curve_1", 1), ("curve_2", 2)), True),
    "rolling_curve": ((("curve_1", 1), ("curve_2", 2)), True),
    "sliding_surface": ((("surface_1", 1), ("surface_2", 2)), True),
    "rolling_surface": ((("surface_1", 1), ("surface_2", 2)), True),
}
_CURVE_PAIRS = tuple(_GEOMETRY)
#: Higher pair values: ("point", geometry key) for a point on that curve/surface (1 or 2
#: model values), "ypr" for an orientation (3 values), "A" for a plane angle.
_HIGHER_VALUES = {
    "point_on_planar_curve": (("point", "curve"), "ypr"),
    "point_on_surface": (("point", "surface"), "ypr"),
    "sliding_curve": (("point", "curve_1"), ("point", "curve_2")),
    "rolling_curve": (("point", "curve_1"),),
    "sliding_surface": (("point", "surface_1"), ("point", "surface_2"), "A"),
    "rolling_surface": (("point", "surface_1"), "A"),
}
#: Higher pairs whose limits are written: a trimmed curve / rectangular trimmed surface of the
#: pair's geometry for the point parameter(s), and yaw, pitch, roll limits.
_HIGHER_RANGES = ("point_on_planar_curve", "point_on_surface")
#: Model-only parameters of higher pairs that the file cannot carry (with their defaults).
_NOT_IN_FILE = {"reference_parameter_1": 0.0, "reference_parameter_2": 0.0, "point_on_surface_2": None}
SUPPORTED_KINDS = (*_VALUE_UNITS, *_CURVE_PAIRS)

#: AP242: the derived freedom flags (t_x, t_y, t_z, r_x, r_y, r_z) of the low-order pairs,
#: which are also the freedoms an actuated pair drives. Screw, gear and rack-and-pinion
#: pairs are low_order_kinematic_pair_with_motion_coupling subtypes (no flags).
_FLAGS = {
    "revolute": (0, 0, 0, 0, 0, 1), "prismatic": (1, 0, 0, 0, 0, 0), "cylindrical": (0, 0, 1, 0, 0, 1),
    "spherical": (0, 0, 0, 1, 1, 1), "universal": (0, 0, 0, 1, 0, 1), "homokinetic": (0, 0, 0, 1, 0, 1),
    "planar": (1, 1, 0, 0, 0, 1), "unconstrained": (1, 1, 1, 1, 1, 1), "fully_constrained": (0,) * 6,
}
_COUPLED_DOF = {"screw": (0, 0, 0, 0, 0, 1), "gear": (0, 0, 0, 0, 0, 1), "rack_and_pinion": (1, 0, 0, 0, 0, 0)}

#: Pair kinds with a range entity in each layout (1996 ``*_pair_range``, AP242 ``*_with_range``).
_RANGE_1996 = {"revolute", "prismatic", "screw", "cylindrical", "spherical", "universal", "homokinetic",
               "planar", "gear", "rack_and_pinion"}
_RANGE_242 = {"revolute", "prismatic", "screw", "cylindrical", "spherical", "universal", "planar", "gear",
              "rack_and_pinion", "point_on_planar_curve", "point_on_surface"}

# The mechanism's own instances (one mechanism per converted file).
_MECHANISM_TYPES = frozenset((
    "kinematic_structure", "kinematic_topology_structure", "kinematic_property_definition",
    "kinematic_property_representation_relation", "kinematic_ground_representation", "mechanism",
    "mechanism_base_placement", "mechanism_representation", "product_definition_kinematics",
    "kinematic_property_mechanism_representation", "product_definition_relationship_kinematics",
    "context_dependent_kinematic_link_representation",
))
_LOOP_TYPES = frozenset((
    "kinematic_loop", "oriented_joint", "kinematic_topology_network_structure", "kinematic_topology_tree_structure",
    "kinematic_topology_directed_structure", "kinematic_topology_substructure",
))
# Items of the kinematics list that are plain geometry here: kept unless orphaned.
_GEOMETRY_TYPES = frozenset(("su_parameters", "rotation_about_direction"))


def write_mechanism(mech, profile: str, *, source=None, occt_compat: bool = False):
    """``(JsonDocument, diagnostics)``: ``mech`` in ``profile`` (see the module docstring)."""
    from p105cli.step import DataSection
    from p105cli.step.jsonmodel import JsonDocument

    profile = profile.lower()
    if profile not in PROFILES:
        raise ValueError(f"unknown profile {profile!r} (one of {', '.join(PROFILES)})")
    diags: list[str] = []
    if occt_compat and PROFILES[profile]["layout"] != "ap242":
        diags.append(f"--occt-compat applies to AP242 output only; ignored for {profile}")
        occt_compat = False
    other = []
    if source is None:
        header, data = _standalone(mech, profile, occt_compat, diags)
        name = "<generated>"
    else:
        header, data = _Conversion(mech, profile, source, occt_compat, diags).run()
        name = getattr(source, "source", "<input>")
        sections = list(getattr(source, "sections", ()) or ())
        if len(sections) > 1 or any(sec.parameters is not None for sec in sections):
            diags.append(f"the source's {len(sections)} DATA section(s) and their parameters are written as one "
                         "DATA section without parameters")
        for sec in getattr(source, "other_sections", ()) or ():
            if sec.get("keyword") == "SIGNATURE":
                diags.append("the SIGNATURE section is left out: it signs the source's bytes, not the converted file")
                continue
            other.append({**sec, "after_data": min(int(sec.get("after_data", 1)), 1)})
    scene = getattr(source, "scene", None) if source is not None else None
    return JsonDocument(header, [DataSection(None, len(data))], data, other, name, scene), diags


# ------------------------------------------------------------------ id allocation

class _IdBuilder(Builder):
    """A Builder whose ids continue above ``start`` and can take a freed source id
    (:meth:`reuse`) so that a converted instance keeps its name."""

    def __init__(self, angle_factor: float, start: int = 0, free=()):
        super().__init__(angle_factor)
        self._counter = start
        self._free = set(free)
        self._want: int | None = None

    def _next_id(self) -> int:
        want, self._want = self._want, None
        if want is not None and want in self._free:
            self._free.discard(want)
            return want
        self._counter += 1
        return self._counter

    def reuse(self, iid):
        """Give the next instance the id ``iid`` when that source id is free."""
        self._want = iid if isinstance(iid, int) else None
        return self


# ------------------------------------------------------------------ unit helpers

def _unit_choice(units) -> tuple[str | None, str, list[str]]:
    """(SI prefix or None, angle unit name, notes) that rebuild ``units``."""
    notes = []
    prefixes = {1.0: None, 1e-3: "milli", 1e-2: "centi", 1e-1: "deci", 1e3: "kilo", 1e-6: "micro"}
    prefix = None
    for f, p in prefixes.items():
        if math.isclose(units.length, f, rel_tol=1e-12):
            prefix = p
            break
    else:
        notes.append(f"length unit {units.length_name!r} ({units.length} m) is not an SI-prefixed metre: "
                     "written in millimetres")
        prefix = "milli"
    if math.isclose(units.angle, math.pi / 180.0, rel_tol=1e-12):
        angle = "degree"
    elif math.isclose(units.angle, 1.0, rel_tol=1e-12):
        angle = "radian"
    else:
        notes.append(f"plane-angle unit {units.angle_name!r} is neither radian nor degree: written in degrees")
        angle = "degree"
    return prefix, angle, notes


_PREFIX_FACTOR = {None: 1.0, "milli": 1e-3, "centi": 1e-2, "deci": 1e-1, "kilo": 1e3, "micro": 1e-6}


# ------------------------------------------------------------------ the kinematic writer

class _Kin:
    """Writes the kinematic instances of ``mech`` in one layout, given the supporting
    instances (contexts, shapes, product definitions) as references."""

    def __init__(self, mech, profile, b: _IdBuilder, length_factor: float, occt_compat: bool, diags: list):
        self.mech, self.profile, self.b = mech, profile, b
        self.prof = PROFILES[profile]
        self.layout = self.prof["layout"]
        self.lf = length_factor  # metres per file length unit
        self.occt = occt_compat
        self.diags = diags
        # supporting references, filled by the caller
        self.world_ctx = None
        self.world_origin = None  # 1996 ground item (created when None)
        self.link_ctx = {}
        self.link_shape = {}
        self.link_pd = {}
        self.link_nauo = {}
        self.assembly_pd = None
        self.extra_items = defaultdict(list)  # link -> other items of its representation
        self.frame_reuse = {}  # (pair name, 0|1) -> reference of an existing placement
        self.ids = {}  # role -> {key: source id} for stable ids
        self.curve_reuse = {}  # (pair name, geometry key) -> the source's curve/surface, usable as it is
        self.record_of = lambda ref: None  # a context record by reference (to copy it)
        self.curves = {}  # (pair name, geometry key) -> reference

    # -- numbers
    def L(self, x):
        return real(float(x) / self.lf)

    def A(self, x):
        return self.b.angle(float(x))

    def value(self, unit, x):
        return self.A(x) if unit == "A" else self.L(x)

    def axis2(self, T, name=""):
        T = np.array(T, float)
        T[:3, 3] /= self.lf
        return self.b.axis2(T, name)

    def _reuse(self, role, key):
        return self.b.reuse(self.ids.get(role, {}).get(key))

    # -- pair frames in the target layout
    def target_frames(self, p):
        P1, P2 = np.asarray(p.P1), np.asarray(p.P2)
        if p.kind == "prismatic":
            src = p.params.get("layout", "1996")
            if src != self.layout:
                R = Z_TO_X if self.layout == "ap242" else inverse(Z_TO_X)
                return compose(P1, R), compose(P2, R), True
        return P1, P2, False

    def pair_frame_items(self):
        self.pair_items = {}
        per_link = {ln.name: [] for ln in self.mech.links}
        for p in self.mech.pairs:
            F1, F2, turned = self.target_frames(p)
            items = []
            for which, (T, link) in enumerate(((F1, p.link1), (F2, p.link2))):
                ref = None if turned else self.frame_reuse.get((p.name, which))
                su = p.params.get(f"su_{which + 1}")
                if ref is None and su is not None and not turned and self.prof["su"]:
                    a, alpha, bb, beta, c, gamma = (float(x) for x in su)
                    ref = self.b.add("su_parameters", f"{p.name} on {link}", self.L(a), self.A(alpha),
                                     self.L(bb), self.A(beta), self.L(c), self.A(gamma))
                if ref is None:
                    ref = self.axis2(T, f"{p.name} on {link}")
                items.append(ref)
                if ref not in per_link[link]:
                    per_link[link].append(ref)
            self.pair_items[p.name] = tuple(items)
        for ln in self.mech.links:
            for item in self.extra_items.get(ln.name, []):
                if item not in per_link[ln.name]:
                    per_link[ln.name].append(item)
        return per_link

    # -- pair attributes common to both layouts
    def own_params(self, p):
        prm = p.params
        if p.kind == "screw":
            return [self.L(prm["pitch"])]
        if p.kind in ("universal", "homokinetic"):
            skew = prm.get("input_skew_angle")
            return [None if skew is None else self.A(skew)]
        if p.kind == "gear":
            return [self.L(prm["radius_first_link"]), self.L(prm["radius_second_link"]),
                    self.A(prm.get("bevel", 0.0)), self.A(prm.get("helical_angle", 0.0)),
                    real(prm["gear_ratio"])]
        if p.kind == "rack_and_pinion":
            return [self.L(prm["pinion_radius"])]
        if p.kind in _CURVE_PAIRS:
            keys, oriented = _GEOMETRY[p.kind]
            own = [self.curves[(p.name, key)] for key, _ in keys]
            return own + ([TRUE if prm.get("orientation", True) else FALSE] if oriented else [])
        return []

    # -- higher pairs: the pair curve and points on it
    def write_geometry(self, obj):
        """Records of a curve or surface object (metres, radians) in file units; its reference."""
        from . import geometry as G
        from .geometry_step import curve_records, surface_records

        surface = isinstance(obj, (G.Plane, G.CylindricalSurface, G.ConicalSurface, G.SphericalSurface,
                                   G.ToroidalSurface, G.BSplineSurface))
        fn = surface_records if surface else curve_records
        ref, records = fn(obj, self.b._next_id, self.lf, 1.0 / self.b.angle_factor)
        self.b.data.extend(records)
        return {"ref": ref}

    def pair_geometry(self, p, in_link: bool):
        """``{key: (reference, which)}``: the pair's curves/surfaces, the source's where they can
        stay as they are, else written anew, in link coordinates (AP242: items of the link
        representation) or in their pair frame (1996: items of a frame background)."""
        out = {}
        for key, which in _GEOMETRY[p.kind][0]:
            ref = self.curve_reuse.get((p.name, key))
            if ref is None:
                obj = p.params[key]
                if in_link:
                    obj = obj.transformed(np.asarray(p.P1 if which == 1 else p.P2))
                ref = self.write_geometry(obj)
            self.curves[(p.name, key)] = ref
            out[key] = (ref, which)
        return out

    def point_on(self, p, key, params):
        """A point_on_curve / point_on_surface of the pair's geometry ``key`` at the model's
        parameters (SI): conics and the angular parameters of surfaces of revolution are plane
        angles, planes and the axial parameter of cylinders and cones lengths, the rest plain
        numbers (Part 42)."""
        from . import geometry as G

        obj = p.params[key]
        if "curve" in key:
            (t,) = params
            basis = obj.basis if isinstance(obj, G.TrimmedCurve) else obj
            if isinstance(obj, G.TrimmedCurve):  # the model's parameter runs along the trimmed curve
                t = obj.trim_1 + (t if obj.sense else -t)
            u = self.A(t) if isinstance(basis, (G.Circle, G.Ellipse)) else real(t)
            return self.b.add("point_on_curve", f"{p.name} point", self.curves[(p.name, key)], u)
        u, v = params
        if isinstance(obj, G.Plane):
            uv = self.L(u), self.L(v)
        elif isinstance(obj, (G.CylindricalSurface, G.ConicalSurface)):
            uv = self.A(u), self.L(v)
        elif isinstance(obj, (G.SphericalSurface, G.ToroidalSurface)):
            uv = self.A(u), self.A(v)
        else:
            uv = real(u), real(v)
        return self.b.add("point_on_surface", f"{p.name} point", self.curves[(p.name, key)], *uv)

    def higher_values(self, p, q):
        """The arguments of a higher pair's value after the pair; points go into the frame
        backgrounds in the 1996 layout."""
        q = list(q)
        out = []
        for item in _HIGHER_VALUES[p.kind]:
            if item == "ypr":
                out.append(self.orientation(q[:3]))
                q = q[3:]
            elif item == "A":
                out.append(self.A(q.pop(0)))
            else:
                key = item[1]
                n = 1 if "curve" in key else 2
                point = self.point_on(p, key, q[:n])
                q = q[n:]
                if self.layout == "1996":
                    which = dict(_GEOMETRY[p.kind][0])[key]
                    self.background_items[(p.name, which)].append(point)
                out.append(point)
        return out

    def higher_range(self, p):
        """``(trimmed geometry, [yaw, pitch, roll limits as arguments])`` of a point-on-curve or
        point-on-surface pair with limits, or None (with a diagnostic when they cannot be
        written). The trimmed geometry still has to be put in a representation."""
        from . import geometry as G

        if p.kind not in _HIGHER_RANGES or not self.has_range(p):
            return None
        where = p.ids.get("range") or p.ids.get("pair")
        n = 1 if p.kind == "point_on_planar_curve" else 2
        key = _GEOMETRY[p.kind][0][0][0]
        obj = p.params[key]
        lo, hi = list(p.lower[:n]), list(p.upper[:n])
        b = self.b
        if n == 1:
            conic = isinstance(obj, (G.Circle, G.Ellipse))
            if isinstance(obj, G.TrimmedCurve):
                self.diags.append(_at(where, f"pair {p.name!r}: limits on a trimmed pair curve are not written"))
                return None
            if lo == [None] and hi == [None] and conic:
                lo, hi = [0.0], [2.0 * math.pi]  # the whole closed curve
            if None in lo or None in hi:
                self.diags.append(_at(where, f"pair {p.name!r}: an open point parameter range cannot be written "
                                             "(a trimmed curve has two ends); limits not written"))
                return None
            conv = self.A if conic else real
            item = b.add("trimmed_curve", f"{p.name} range", self.curves[(p.name, key)],
                         [typed("parameter_value", conv(lo[0]))], [typed("parameter_value", conv(hi[0]))], TRUE,
                         enum("parameter"))
        else:
            if None in lo or None in hi:
                self.diags.append(_at(where, f"pair {p.name!r}: an open point parameter range cannot be written "
                                             "(a rectangular trimmed surface has four sides); limits not written"))
                return None
            if isinstance(obj, G.Plane):
                cu, cv = self.L, self.L
            elif isinstance(obj, (G.CylindricalSurface, G.ConicalSurface)):
                cu, cv = self.A, self.L
            elif isinstance(obj, (G.SphericalSurface, G.ToroidalSurface)):
                cu, cv = self.A, self.A
            else:
                cu = cv = real
            item = b.add("rectangular_trimmed_surface", f"{p.name} range", self.curves[(p.name, key)],
                         cu(lo[0]), cu(hi[0]), cv(lo[1]), cv(hi[1]), TRUE, TRUE)
        limits = []
        for x, y in zip(p.lower[n:], p.upper[n:]):
            for v in (x, y):
                if self.layout == "1996":
                    limits.append(typed("unlimited_range", enum("unlimited")) if v is None
                                  else typed("plane_angle_measure", self.A(v)))
                else:
                    limits.append(None if v is None else self.A(v))
        return item, limits

    def orientation(self, ypr):
        """A pair's orientation (yaw, pitch, roll in SI): the typed ypr_rotation, or for Open
        CASCADE (which reads that select as a real) the equal rotation_about_direction."""
        if not self.occt:
            return typed("ypr_rotation", [self.A(x) for x in ypr])
        from .graph import rotation_vector
        from .placements import ypr_rotation

        phi = np.asarray(rotation_vector(ypr_rotation(*ypr)), float)
        angle = float(np.linalg.norm(phi))
        axis = phi / angle if angle > 0.0 else np.array([0.0, 0.0, 1.0])
        if axis[2] < 0 or (axis[2] == 0 and (axis[1] < 0 or axis[1] == 0 and axis[0] < 0)):
            axis, angle = -axis, -angle
        return self.b.add("rotation_about_direction", "", self.b.direction(axis), self.A(angle))

    def copy_context(self, ctx, identifier):
        """A new context like ``ctx`` (same units and uncertainty) named ``identifier``."""
        rec = self.record_of(ctx)
        if rec is None or "complex" not in rec:
            return ctx
        parts = []
        for part in rec["complex"]:
            args = part["args"]
            if part["type"] == "representation_context":
                args = [identifier, *args[1:]]
            parts.append((part["type"], args))
        return self.b.add_complex(parts)

    def has_range(self, p):
        return any(v is not None for v in (*p.lower, *p.upper))

    def range_args(self, p):
        out = []
        for unit, lo, hi in zip(_VALUE_UNITS[p.kind], p.lower, p.upper):
            for v in (lo, hi):
                if self.layout == "1996":
                    if v is None:
                        out.append(typed("unlimited_range", enum("unlimited")))
                    else:
                        tname = "plane_angle_measure" if unit == "A" else "length_measure"
                        out.append(typed(tname, self.value(unit, v)))
                else:
                    out.append(None if v is None else self.value(unit, v))
        return out

    def flags(self, kind):
        if kind not in _FLAGS:
            return []
        if self.occt:
            return [TRUE if f else FALSE for f in _FLAGS[kind]]
        return [DERIVED] * 6

    def pair_value(self, p, pair_ref, q):
        """The ``*_pair_value`` of ``p`` at ``q`` (SI), or None for a pair without values."""
        b = self.b
        kind = p.kind
        if kind == "fully_constrained":
            return None
        entity = "universal_pair_value" if kind == "homokinetic" else f"{kind}_pair_value"
        if kind in _CURVE_PAIRS:
            vals = self.higher_values(p, q)
        elif kind == "spherical":
            vals = [self.orientation(q)]
        elif kind == "unconstrained":
            M = p.motion(np.asarray(q, float))
            vals = [self.axis2(M, f"{p.name} value")]
            if self.layout == "1996":  # a representation item must be in a representation (WR1)
                self.b.add("representation", f"{p.name} value", vals, self.link_ctx[p.link1])
        else:
            vals = [self.value(u, x) for u, x in zip(_VALUE_UNITS[kind], q)]
        self._reuse("value", p.name)
        if self.layout == "1996":
            return b.add(entity, pair_ref, *vals)
        return b.add(entity, p.name, pair_ref, *vals)

    def check_kinds(self):
        ok = []
        for p in self.mech.pairs:
            if p.kind in _CURVE_PAIRS:
                if self.has_range(p) and p.kind not in _HIGHER_RANGES:
                    self.diags.append(_at(p.ids.get("range") or p.ids.get("pair"),
                                          f"pair {p.name!r}: the limits of {p.kind} pairs are not written yet"))
                for key, default in _NOT_IN_FILE.items():
                    if key in p.params and p.params[key] is not None and p.params[key] != default:
                        self.diags.append(_at(p.ids.get("pair"), f"pair {p.name!r}: {key} has no attribute in "
                                                                 "the file; not written"))
                ok.append(p)
                continue
            if p.kind not in _VALUE_UNITS:
                self.diags.append(_at(p.ids.get("pair"), f"pair {p.name!r}: {p.kind} pairs are not written "
                                                         "by p105 yet; the pair and its joint are left out"))
                continue
            ok.append(p)
        return ok

    # ------------------------------------------------------------ 1996 layout
    def write_1996(self):
        b, mech = self.b, self.mech
        pairs_ok = self.check_kinds()
        links = {}
        for ln in mech.links:
            self._reuse("link", ln.name)
            links[ln.name] = b.add("kinematic_link")
        joints = {}
        for p in pairs_ok:
            self._reuse("joint", p.name)
            joints[p.name] = b.add("kinematic_joint", links[p.link1], links[p.link2])
        b.reuse(mech.ids.get("structure"))
        structure = b.add("kinematic_structure", list(joints.values()))

        per_link = self.pair_frame_items()
        link_rep = {}
        for ln in mech.links:
            items = self._frames_only(ln.name, per_link[ln.name])
            self._reuse("link_rep", ln.name)
            rep = b.add("kinematic_link_representation", ln.name, items, self.link_ctx[ln.name])
            link_rep[ln.name] = rep
            b.add("kinematic_link_representation_relation", links[ln.name], rep)
            if self.link_shape.get(ln.name) is not None:
                self._reuse("klra", ln.name)
                b.add("kinematic_link_representation_association", f"{ln.name} shape", None, rep,
                      self.link_shape[ln.name])
        self.link_rep = link_rep

        self.background_items = defaultdict(list)  # (pair name, 1|2) -> items
        self.higher_ranges = {}
        for p in pairs_ok:
            if p.kind in _CURVE_PAIRS:
                for key, (ref, which) in self.pair_geometry(p, in_link=False).items():
                    self.background_items[(p.name, which)].append(ref)
                rng = self.higher_range(p)
                if rng is not None:
                    self.higher_ranges[p.name] = rng
                    self.background_items[(p.name, 1)].append(rng[0])
        pairs = {}
        for p in pairs_ok:
            f1, f2 = self.pair_items[p.name]
            self._reuse("pair", p.name)
            pairs[p.name] = b.add(f"{p.kind}_pair", p.name, p.description, f1, f2, joints[p.name],
                                  *self.own_params(p))

        T = np.array(mech.T_world_base, float)
        T[:3, 3] /= self.lf
        base = mech.base
        cto = b.cartesian_transformation_operator_3d(T, f"base placement of {base}")
        if self.world_origin is None:
            self.world_origin = b.axis2(np.eye(4), "world")
        ground = b.add("kinematic_ground_representation", "ground", [self.world_origin, cto], self.world_ctx)
        kpd = b.add("kinematic_property_definition", "kinematics", mech.description, self.assembly_pd,
                    self.link_pd.get(base, self.assembly_pd))
        b.add("kinematic_property_representation_relation", kpd, ground)
        b.reuse(mech.ids.get("mechanism"))
        mechanism = b.add("mechanism", structure, links[base], kpd)
        b.reuse(mech.ids.get("base_placement"))
        b.add("mechanism_base_placement", "base placement", None, ground, DERIVED, cto, mechanism)

        for p in pairs_ok:
            if self.has_range(p) and p.kind not in _RANGE_1996 and p.kind not in _CURVE_PAIRS:
                self.diags.append(_at(p.ids.get("range") or p.ids.get("pair"),
                                      f"pair {p.name!r}: the 1996 layout has no range for a {p.kind} pair; its "
                                      "limits are not written"))
            elif self.has_range(p) and p.kind in _RANGE_1996:
                self._reuse("range", p.name)
                b.add(f"{'universal' if p.kind == 'homokinetic' else p.kind}_pair_range", pairs[p.name],
                      *self.range_args(p))
            elif p.name in self.higher_ranges:
                item, limits = self.higher_ranges[p.name]
                self._reuse("range", p.name)
                b.add(f"{p.kind}_pair_range", pairs[p.name], item, *limits)
        for p in pairs_ok:
            if p.actuated:
                self._reuse("actuator", p.name)
                b.add("pair_actuator", pairs[p.name], f"{p.name} drive")
        # initial_state's WR1 wants a value for every joint: a pair the state does not give is
        # at 0 (as Mechanism.initial_vector says)
        values = []
        if mech.initial:
            for p in pairs_ok:
                if p.kind == "fully_constrained":
                    self.diags.append(f"pair {p.name!r}: a fully constrained pair has no value entity, so the "
                                      "1996 initial_state cannot give one for its joint (its WR1)")
                    continue
                q = mech.initial.get(p.name, (0.0,) * p.value_count)
                values.append(self.pair_value(p, pairs[p.name], q))
        self.initial_values = values
        if values:
            b.reuse(mech.ids.get("initial_state"))
            b.add("initial_state", mechanism, values)
        self.pairs = pairs
        self.mechanism_ref = mechanism

    def finish(self):
        if self.layout == "1996":
            self.backgrounds_1996()

    def backgrounds_1996(self):
        """A 1996 pair curve or surface (and the points on it) lives in a kinematic frame
        background placed at its pair frame: a representation item must be in a representation
        (its WR1) and a link representation holds placements only (its WR1). The
        kinematic_frame_based_transformation is the one item of a plain representation in
        the link's context, for the same reason."""
        b = self.b
        for p in self.mech.pairs:
            for which in (1, 2):
                if (p.name, which) not in self.background_items:
                    continue
                frame = self.pair_items[p.name][which - 1]
                link = p.link1 if which == 1 else p.link2
                tag = p.name if which == 1 else f"{p.name} ({link})"
                ctx = self.copy_context(self.link_ctx[link], f"{self.mech.name} {tag} background")
                bg = b.add("kinematic_frame_background_representation", f"{tag} background",
                           self.background_items[(p.name, which)], ctx)
                kfbt = b.add("kinematic_frame_based_transformation", f"{tag} background placement",
                             f"{tag} background placement", None, frame)
                b.add("representation", f"{tag} background placement", [kfbt], self.link_ctx[link])
                b.add("kinematic_frame_background_representation_association", f"{tag} background", None,
                      self.link_rep[link], bg, kfbt)

    def _frames_only(self, link, items):
        """A 1996 link representation holds placements only (its WR1)."""
        if self.layout != "1996":
            return items
        keep = []
        for item in items:
            t = self.item_types.get(item["ref"]) if hasattr(self, "item_types") else None
            if t is not None and not t & {"axis2_placement_3d", "su_parameters"}:
                self.diags.append(f"#{item['ref']}: {'+'.join(sorted(t))} of link {link!r} is not a placement; "
                                  "a 1996 link representation holds placements only (left out)")
                continue
            keep.append(item)
        return keep

    # ------------------------------------------------------------ AP242 layout
    def write_ap242(self):
        b, mech = self.b, self.mech
        pairs_ok = self.check_kinds()
        links = {}
        for ln in mech.links:
            self._reuse("link", ln.name)
            links[ln.name] = b.add("kinematic_link", ln.name)
        joints = {}
        for p in pairs_ok:
            self._reuse("joint", p.name)
            joints[p.name] = b.add("kinematic_joint", p.joint or p.name, links[p.link1], links[p.link2])
        b.reuse(mech.ids.get("structure"))
        topology = b.add("kinematic_topology_structure", f"{mech.name} topology", list(joints.values()),
                         self.world_ctx)

        per_link = self.pair_frame_items()
        self.higher_ranges = {}
        for p in pairs_ok:
            if p.kind in _CURVE_PAIRS:
                for key, (ref, which) in self.pair_geometry(p, in_link=True).items():
                    link = p.link1 if which == 1 else p.link2
                    if ref not in per_link[link]:
                        per_link[link].append(ref)
                rng = self.higher_range(p)
                if rng is not None:
                    self.higher_ranges[p.name] = rng
                    per_link[p.link1].append(rng[0])
        link_rep, klra = {}, {}
        for ln in mech.links:
            self._reuse("link_rep", ln.name)
            rep = b.add("rigid_link_representation", ln.name, per_link[ln.name], self.link_ctx[ln.name],
                        links[ln.name])
            link_rep[ln.name] = rep
            if self.link_shape.get(ln.name) is not None:
                self._reuse("klra", ln.name)
                klra[ln.name] = b.add("kinematic_link_representation_association", f"{ln.name} shape", None,
                                      rep, self.link_shape[ln.name])
        self.link_rep = link_rep

        pairs = {}
        for p in pairs_ok:
            pairs[p.name] = self._pair_242(p, joints[p.name])
        prr = [b.add("pair_representation_relationship", p.name, p.name, p.description, link_rep[p.link1],
                     link_rep[p.link2], pairs[p.name]) for p in pairs_ok]
        b.reuse(mech.ids.get("mechanism"))
        mech_rep = b.add("mechanism_representation", mech.name, prr, self.world_ctx, topology)
        self._loops_242(joints, topology)
        pdk = b.add("product_definition_kinematics", "kinematics", mech.description, self.assembly_pd)
        b.add("kinematic_property_mechanism_representation", pdk, mech_rep, link_rep[mech.base])
        for ln in mech.links:
            if ln.name in klra and self.link_nauo.get(ln.name) is not None:
                pdrk = b.add("product_definition_relationship_kinematics", ln.name, f"kinematic link {ln.name}",
                             self.link_nauo[ln.name])
                b.add("context_dependent_kinematic_link_representation", klra[ln.name], pdrk)
        values = [v for v in (self.pair_value(p, pairs[p.name], mech.initial[p.name])
                              for p in pairs_ok if p.name in mech.initial) if v is not None]
        self.initial_values = values
        self.initial_state = None
        if values:
            b.reuse(mech.ids.get("initial_state"))
            self.initial_state = b.add("mechanism_state_representation", "initial state", values,
                                       self.world_ctx if self.occt else DERIVED, mech_rep)
        self.pairs = pairs
        self.mechanism_ref = mech_rep

    # ------------------------------------------------------------ configuration sequences
    def configuration_sequence(self, name, configs, motion_ctx=None):
        """Write one interpolated configuration sequence. ``configs`` is a list of
        ``(values, t, interpolation)``: ``values`` a list of ``(pair name, entity, numbers)``
        (the value's arguments after its pair, in file units, which a conversion keeps) or
        None for the initial state; ``interpolation`` from this configuration to the next
        (``linear``, ``synchronous``, ``undefined``, ``discontinuous``)."""
        b = self.b
        written = []
        for k, (values, t, interp) in enumerate(configs):
            if values is None:
                refs = list(self.initial_values)
            else:
                refs = []
                for pname, entity, rest in values:
                    pair = self.pairs[pname]
                    rest = list(rest)
                    for j, x in enumerate(rest):
                        if isinstance(x, tuple) and x[0] == "point":  # a point on the pair's geometry
                            _, key, entity_p, numbers = x
                            rest[j] = self.b.add(entity_p, f"{pname} point", self.curves[(pname, key)], *numbers)
                            if self.layout == "1996":
                                which = dict(_GEOMETRY[self.mech.pair(pname).kind][0])[key]
                                self.background_items[(pname, which)].append(rest[j])
                    refs.append(b.add(entity, pair, *rest) if self.layout == "1996"
                                else b.add(entity, pname, pair, *rest))
            written.append((refs, t, interp))
        if self.layout == "1996":
            defs = [b.add("configuration_definition", refs, typed("parameter_value", real(t)))
                    for refs, t, _ in written]
            steps = [b.add("configuration_interpolation", c0, c1,
                           enum({"linear": "linear", "synchronous": "synchronous"}.get(interp, "undefined")))
                     for c0, c1, (_, _, interp) in zip(defs, defs[1:], written)]
            sequence = b.add("interpolated_configuration_sequence", steps)
            b.add("kinematic_control", self.mechanism_ref, [sequence])
            return
        segments = []
        for k, (refs, t, interp) in enumerate(written):
            if configs[k][0] is None and self.initial_state is not None:
                state = self.initial_state
            else:
                state = b.add("mechanism_state_representation", f"configuration {k}", refs,
                              self.world_ctx if self.occt else DERIVED, self.mechanism_ref)
            kind = interp if k + 1 < len(written) else "discontinuous"
            segments.append(b.add("interpolated_configuration_segment", state, real(t),
                                  enum(f"{kind}_interpolation_type")))
        sequence = b.add("interpolated_configuration_sequence", name, segments)
        b.add("interpolated_configuration_representation", name, [sequence], motion_ctx)

    def _loops_242(self, joints, topology):
        """The independent loops (p105cli.kinematics.graph) as kinematic_loops of oriented
        joints in a kinematic_topology_network_structure; none for a tree."""
        self.loops_written = False
        try:
            from .graph import analyse

            loops = [loop for loop in analyse(self.mech).loops if all(name in joints for name, _ in loop)]
        except Exception:  # a pair whose motion is unknown: the loops are left to `p105 graph`
            return
        if not loops:
            return
        if self.occt:
            self.diags.append(f"{len(loops)} kinematic loop(s) not written (--occt-compat: Open CASCADE does "
                              "not read kinematic_loop); `p105 graph` derives them")
            return
        b = self.b
        refs = []
        for k, loop in enumerate(loops, start=1):
            edges = [b.add("oriented_joint", "", DERIVED, DERIVED, joints[name], TRUE if fwd else FALSE)
                     for name, fwd in loop]
            refs.append(b.add("kinematic_loop", f"loop {k}", edges))
        b.add("kinematic_topology_network_structure", f"{self.mech.name} loops", refs, self.world_ctx, topology)
        self.loops_written = True

    def _pair_242(self, p, joint):
        b = self.b
        f1, f2 = self.pair_items[p.name]
        with_range = (p.name in self.higher_ranges if p.kind in _CURVE_PAIRS  # (else reported already)
                      else self.has_range(p))
        if with_range and p.kind not in _RANGE_242:
            self.diags.append(_at(p.ids.get("range"), f"pair {p.name!r}: AP242 has no range for a {p.kind} pair; "
                                                      "its limits are not written"))
            with_range = False
        plain = f"{p.kind}_pair"
        ranged = f"{p.kind}_pair_with_range"
        entity = ranged if with_range else plain
        flags = self.flags(p.kind)
        own = self.own_params(p)
        if p.kind in _CURVE_PAIRS:
            range_args = [self.higher_ranges[p.name][0], *self.higher_ranges[p.name][1]] if with_range else []
        else:
            range_args = self.range_args(p) if with_range else []
        name2 = p.name if self.occt else DERIVED
        actuated = p.actuated
        if actuated and self.occt:
            self.diags.append(_at(p.ids.get("actuator") or p.ids.get("pair"),
                                  f"pair {p.name!r}: actuation not written (--occt-compat: Open CASCADE does not "
                                  "read the actuated_kinematic_pair complex instance)"))
            actuated = False
        if actuated and p.kind not in _FLAGS and p.kind not in _COUPLED_DOF:
            self.diags.append(_at(p.ids.get("pair"), f"pair {p.name!r}: actuation not written (which freedoms an "
                                                     f"actuated {p.kind} pair drives is not defined)"))
            actuated = False
        self._reuse("pair", p.name)
        if not actuated:
            return b.add(entity, p.name, name2, p.description, f1, f2, joint, *flags, *own, *range_args)
        dofs = _FLAGS.get(p.kind) or _COUPLED_DOF[p.kind]
        directions = [enum("bidirectional") if f else enum("not_actuated") for f in dofs]
        parts = [("actuated_kinematic_pair", directions), ("geometric_representation_item", []),
                 ("item_defined_transformation", [DERIVED, p.description, f1, f2]), ("kinematic_pair", [joint]),
                 ("representation_item", [p.name])]
        if p.kind in _FLAGS:
            parts.append(("low_order_kinematic_pair", flags))
        else:
            parts.append(("low_order_kinematic_pair_with_motion_coupling", []))
        if p.kind == "homokinetic":
            parts += [("universal_pair", own), ("homokinetic_pair", [])]
        else:
            parts.append((plain, own))
        if with_range:
            parts.append((ranged, range_args))
        return b.add_complex(parts)


def _at(iid, message: str) -> str:
    return f"#{iid}: {message}" if isinstance(iid, int) else message


# ------------------------------------------------------------------ self-contained files

def _forward_poses(mech) -> dict:
    """``{link: T_base_link}`` at the initial state, by the solver's forward kinematics
    (:func:`p105cli.kinematics.solver.link_poses`) along the spanning tree from the base (a
    loop's closing pair is not used; a part not connected to the base is placed from its
    first link). A pair whose motion is not a function of its values (a rolling surface
    pair) places its second link at its first's."""
    from .solver import link_poses, plan

    pl = plan(mech)
    X, _, _ = link_poses(pl, mech.initial_vector(), unsupported="identity")
    return {ln: X[i] for ln, i in pl.link_index.items()}


def _standalone(mech, profile, occt_compat, diags):
    prof = PROFILES[profile]
    prefix, angle, notes = _unit_choice(mech.units)
    diags.extend(notes)
    lf = _PREFIX_FACTOR[prefix]
    degree = mech.units.angle if angle == "degree" and not notes else math.pi / 180.0
    angle_factor = 1.0 / degree if angle == "degree" else 1.0
    b = _IdBuilder(angle_factor)
    b.units(cbu_dimensions_explicit=prof["cbu_dimensions_explicit"], length_prefix=prefix, angle=angle,
            uncertainty=1e-10 / lf, degree_factor=degree)
    k = _Kin(mech, profile, b, lf, occt_compat, diags)
    k.record_of = lambda ref: next((r for r in b.data if r["id"] == _ref_of(ref)), None)
    key = mech.name
    k.world_ctx = b.context(f"{key} world")
    k.link_ctx = {ln.name: b.context(f"{key} link {ln.name}") for ln in mech.links}

    app, schema_name, year = _APPLICATION[prof["layout"]]
    pf = b.product_frame(app, schema_name, year)
    origins, parts = {}, {}
    for ln in mech.links:
        origins[ln.name] = b.axis2(np.eye(4), f"{ln.name} link frame")
        parts[ln.name] = b.part(pf, f"{key}-{ln.name}", ln.name, ln.description, [origins[ln.name]],
                                k.link_ctx[ln.name], shape_name=f"{ln.name} shape")
        k.link_shape[ln.name] = parts[ln.name]["shape"]
        k.link_pd[ln.name] = parts[ln.name]["pd"]
        k.extra_items[ln.name] = [k.axis2(T, fname) for fname, T in ln.frames.items()]
    poses = _forward_poses(mech)
    world = b.axis2(np.eye(4), "world")
    placements = {ln.name: k.axis2(compose(mech.T_world_base, poses[ln.name]), f"{ln.name} placement")
                  for ln in mech.links}
    assembly = b.part(pf, key, mech.name, mech.description, [world, *placements.values()], k.world_ctx,
                      shape_name=f"{key} assembly")
    k.assembly_pd = assembly["pd"]
    k.world_origin = world
    for n, ln in enumerate(mech.links, start=1):
        usage = b.assembly_usage(assembly, parts[ln.name], f"{key}.{n}", ln.name, origins[ln.name],
                                 placements[ln.name])
        k.link_nauo[ln.name] = usage["nauo"]
    products = [assembly["product"], *(parts[ln.name]["product"] for ln in mech.links)]
    b.add("product_related_product_category", "part", None, products)
    if prof["layout"] == "1996":
        org = b.add("organization", "p105cli", "p105cli", None)
        b.add("applied_organization_assignment", org, b.add("organization_role", "id owner"), products)
    _write_kinematics(k, diags)
    k.finish()
    header = {
        "file_description": {"description": [f"mechanism {mech.name}; {prof['label']}"],
                             "implementation_level": "2;1"},
        "file_name": {"name": f"{mech.name}.stp", "time_stamp": "", "author": [""], "organization": [""],
                      "preprocessor_version": "p105cli", "originating_system": "p105cli", "authorization": ""},
        "file_schema": [prof["schema"]],
    }
    return header, b.data


def _write_kinematics(k: _Kin, diags):
    mech = k.mech
    if k.layout == "1996":
        k.write_1996()
    else:
        k.write_ap242()
    if mech.paths:
        diags.append(f"mechanism {mech.name!r}: {len(mech.paths)} path(s) of the motion program are not written")


def _fmt(v) -> str:
    return "(" + ", ".join(f"{x:.6g}" for x in v) + ")"


# ------------------------------------------------------------------ conversion

def _types(rec) -> frozenset:
    if "complex" in rec:
        return frozenset(p["type"] for p in rec["complex"])
    return frozenset((rec["type"],))


def _args(rec, etype=None) -> list:
    if "complex" in rec:
        for p in rec["complex"]:
            if p["type"] == etype:
                return p["args"]
        return []
    return rec["args"]


_ref_of = ref_id


_LINK_REP_TYPES = frozenset(("kinematic_link_representation", "rigid_link_representation",
                             "linear_flexible_link_representation"))
_DIMENSIONS = {"length_unit": (1, 0, 0, 0, 0, 0, 0), "mass_unit": (0, 1, 0, 0, 0, 0, 0),
               "time_unit": (0, 0, 1, 0, 0, 0, 0), "plane_angle_unit": (0,) * 7, "solid_angle_unit": (0,) * 7,
               "ratio_unit": (0,) * 7}


class _Conversion:
    def __init__(self, mech, profile, source, occt_compat, diags):
        self.mech, self.profile, self.src, self.occt, self.diags = mech, profile, source, occt_compat, diags
        self.prof = PROFILES[profile]
        self.records = {r["id"]: r for r in source.records()}
        self.order = list(self.records)
        self.types = {i: _types(r) for i, r in self.records.items()}
        self.extra_drop: set = set()  # non-kinematic source instances re-expressed (configurations)
        self.quiet: set = set()  # instances that may lose their last user without a diagnostic
        self.refs = {i: _rec_refs(r) for i, r in self.records.items()}  # computed once: files can be big
        self.referrers = defaultdict(list)
        for i, refs in self.refs.items():
            for t in refs:
                self.referrers[t].append(i)

    # -- lookups in the source
    def of_type(self, *names):
        names = set(names)
        return [i for i in self.order if self.types[i] & names]

    def referring(self, target, etype, position, part=None):
        """Ids of ``etype`` instances whose argument ``position`` refers to ``target``."""
        out = []
        for i in self.referrers.get(target, ()):
            if etype in self.types[i]:
                a = _args(self.records[i], part or etype)
                if position < len(a) and _ref_of(a[position]) == target:
                    out.append(i)
        return out

    def _link_rep(self, ln):
        iid = ln.id
        if iid in self.records:
            t = self.types[iid]
            if t & _LINK_REP_TYPES:
                return iid
            if "kinematic_link" in t:
                for r in self.referring(iid, "kinematic_link_representation_relation", 0):
                    return _ref_of(self.records[r]["args"][1])
                for r in self.referring(iid, "rigid_link_representation", 3):
                    return r
        for i in self.of_type(*_LINK_REP_TYPES):
            if _args(self.records[i], next(iter(self.types[i] & _LINK_REP_TYPES)))[0] == ln.name:
                return i
        return None

    def _kin_link(self, ln, rep):
        if ln.id in self.records and "kinematic_link" in self.types[ln.id]:
            return ln.id
        if rep is None:
            return None
        if "rigid_link_representation" in self.types[rep]:
            return _ref_of(self.records[rep]["args"][3])
        for r in self.referring(rep, "kinematic_link_representation_relation", 1):
            return _ref_of(self.records[r]["args"][0])
        return None

    def _pair_id(self, p):
        iid = p.ids.get("pair")
        if iid in self.records:
            return iid
        for i in self.order:
            if any(t.endswith("_pair") or t.endswith("_pair_with_range") for t in self.types[i]):
                a = _args(self.records[i], "representation_item") if "complex" in self.records[i] \
                    else self.records[i]["args"]
                if a and a[0] == p.name:
                    return i
        return None

    def _pair_frames(self, pid):
        rec = self.records[pid]
        if "complex" in rec:
            a = _args(rec, "item_defined_transformation")
            return _ref_of(a[2]), _ref_of(a[3])
        a = rec["args"]
        if "kinematic_joint" in self.types.get(_ref_of(a[4]) or -1, ()):  # 1996: name, description, t1, t2, joint
            return _ref_of(a[2]), _ref_of(a[3])
        return _ref_of(a[3]), _ref_of(a[4])

    def _shape_of(self, rep):
        for r in self.referring(rep, "kinematic_link_representation_association", 2):
            return _ref_of(self.records[r]["args"][3])
        return None

    def _nauo_of(self, shape):
        for r in self.referrers.get(shape, ()):
            if "representation_relationship" in self.types[r] and "complex" in self.records[r]:
                if _ref_of(_args(self.records[r], "representation_relationship")[2]) != shape:
                    continue
                for c in self.referring(r, "context_dependent_shape_representation", 0):
                    pds = _ref_of(self.records[c]["args"][1])
                    if pds in self.records:
                        return _ref_of(self.records[pds]["args"][2])
        return None

    def _pd_of(self, shape):
        for r in self.referring(shape, "shape_definition_representation", 1):
            pds = _ref_of(self.records[r]["args"][0])
            if pds in self.records:
                return _ref_of(self.records[pds]["args"][2])
        return None

    # -- the conversion
    def run(self):
        from p105cli.part105.catalogue import KINEMATIC_ENTITIES

        recs = self.records
        kin_names = KINEMATIC_ENTITIES - _GEOMETRY_TYPES
        self.kin = {i for i in self.order if self.types[i] & kin_names}
        self.consumed: set = set()
        self.ids = defaultdict(dict)
        self.b = b = _IdBuilder(1.0 / self.mech.units.angle, start=max(recs, default=0), free=self.kin)
        self.k = k = _Kin(self.mech, self.profile, b, self.mech.units.length, self.occt, self.diags)
        k.item_types = self.types
        k.ids = self.ids
        k.record_of = lambda ref: recs.get(_ref_of(ref)) or next(
            (r for r in b.data if r["id"] == _ref_of(ref)), None)

        old_rep = self._links()
        pair_items = self._pairs()
        pair_items |= self._higher_pairs()
        for ln in self.mech.links:  # named frames and other items of the link representations
            rep = old_rep[ln.name]
            rtype = next(iter(self.types[rep] & _LINK_REP_TYPES))
            items = [_ref_of(x) for x in _args(recs[rep], rtype)[1]]
            k.extra_items[ln.name] = [{"ref": i} for i in items if i not in pair_items and i is not None]
        self._initial_state()
        mech_ids = self._mechanism()
        self._supporting()

        _write_kinematics(k, self.diags)
        self._sequences(k, self.ids, self.consumed)
        k.finish()
        if getattr(k, "loops_written", False):
            self.consumed.update(self.of_type("kinematic_loop", "oriented_joint",
                                              "kinematic_topology_network_structure"))
        header = _target_header(self.src.header, self.prof)
        out = self._assemble()
        base_placement = mech_ids.get("base_placement")
        if (self.prof["layout"] == "ap242" and base_placement in self.kin
                and "mechanism_base_placement" in self.types[base_placement]):
            self._check_base(header, out, base_placement)
        return header, out

    # -- what the source says, role by role
    def _links(self) -> dict:
        """Each link's representation, context, shape, product definition and assembly usage."""
        k, recs, ids = self.k, self.records, self.ids
        old_rep = {}
        for ln in self.mech.links:
            rep = self._link_rep(ln)
            if rep is None:
                raise _model_error(f"link {ln.name!r}: no link representation in the source", ln.id)
            old_rep[ln.name] = rep
            rtype = next(iter(self.types[rep] & _LINK_REP_TYPES))
            k.link_ctx[ln.name] = _args(recs[rep], rtype)[2]
            shape = self._shape_of(rep)
            k.link_shape[ln.name] = None if shape is None else {"ref": shape}
            if shape is not None:
                pd, nauo = self._pd_of(shape), self._nauo_of(shape)
                if pd is not None:
                    k.link_pd[ln.name] = {"ref": pd}
                if nauo is not None:
                    k.link_nauo[ln.name] = {"ref": nauo}
            kl = self._kin_link(ln, rep)
            ids["link"][ln.name] = kl
            ids["link_rep"][ln.name] = rep
            self.consumed.update(x for x in (rep, kl) if x is not None)
            klras = self.referring(rep, "kinematic_link_representation_association", 2)
            if klras:
                ids["klra"][ln.name] = klras[0]
            self.consumed.update(klras)
            self.consumed.update(self.referring(rep, "kinematic_link_representation_relation", 1))
        return old_rep

    def _pairs(self) -> set:
        """Pairs: frames (reused when unchanged), joint, range, actuator; returns the source's
        pair frames (not items the link representations carry over)."""
        k, recs, ids = self.k, self.records, self.ids
        frames = set()
        for p in self.mech.pairs:
            pid = self._pair_id(p)
            if pid is None:
                continue
            self.consumed.add(pid)
            ids["pair"][p.name] = pid
            for which, f in enumerate(self._pair_frames(pid)):
                if f is None:
                    continue
                frames.add(f)
                t = self.types.get(f, ())
                if "axis2_placement_3d" in t or ("su_parameters" in t and self.prof["su"]):
                    k.frame_reuse[(p.name, which)] = {"ref": f}
            joint = p.ids.get("joint")
            if joint not in recs:
                a = _args(recs[pid], "kinematic_pair") if "complex" in recs[pid] else recs[pid]["args"]
                joint = next((_ref_of(x) for x in a if "kinematic_joint" in self.types.get(_ref_of(x) or -1, ())),
                             None)
            if joint in recs:
                ids["joint"][p.name] = joint
                self.consumed.add(joint)
            for r in self.referrers.get(pid, ()):
                t = self.types[r]
                if any(x.endswith("_pair_range") for x in t):
                    ids["range"][p.name] = r
                    self.consumed.add(r)
                elif "pair_actuator" in t:
                    ids["actuator"][p.name] = r
                    self.consumed.add(r)
                elif "pair_representation_relationship" in t:
                    self.consumed.add(r)
        return frames

    def _higher_pairs(self) -> set:
        """A higher pair's curves/surfaces stay as they are where their coordinates do (same
        layout, or the pair frame is the link frame); the source's geometry of the pair, its
        range and the 1996 frame backgrounds go quietly (re-expressed). Returns the items the
        link representations must not carry over."""
        k, recs = self.k, self.records
        src_layout = PROFILES.get(self.mech.profile or "", {}).get("layout")
        items = set()
        higher = [p for p in self.mech.pairs if p.kind in _CURVE_PAIRS and p.name in self.ids["pair"]]
        for p in higher:
            pid = self.ids["pair"][p.name]
            for key, which in _GEOMETRY[p.kind][0]:
                g = p.ids.get(key)
                P = p.P1 if which == 1 else p.P2
                same = src_layout == self.prof["layout"] or np.allclose(P, np.eye(4), rtol=0.0, atol=1e-12)
                if g in recs and same:
                    k.curve_reuse[(p.name, key)] = {"ref": g}
            for r in [pid, *self.referrers.get(pid, ())]:
                for x in _rec_refs(recs[r]):
                    if x in recs and not self.types[x] & {"kinematic_joint", "axis2_placement_3d", "su_parameters"}:
                        items.add(x)
                        self.quiet.add(x)
        if higher:
            for i in self.of_type("kinematic_frame_background_representation"):
                self.quiet.update(_ref_of(x) for x in recs[i]["args"][1])
                self.quiet.add(_ref_of(recs[i]["args"][2]))
                self.consumed.add(i)
            self.consumed.update(self.of_type("kinematic_frame_based_transformation",
                                              "kinematic_frame_background_representation_association"))
            for i in self.of_type("representation"):  # the holders of the frame-based transformations
                held = [_ref_of(x) for x in recs[i]["args"][1]]
                if held and all("kinematic_frame_based_transformation" in self.types.get(x, ()) for x in held):
                    self.extra_drop.add(i)
        return items

    def _initial_state(self):
        recs = self.records
        ist = self.mech.ids.get("initial_state")
        if ist not in recs:
            return
        self.consumed.add(ist)
        t = self.types[ist]
        vals = recs[ist]["args"][1] if t & {"initial_state", "mechanism_state_representation"} else []
        by_pair = {}
        for v in vals:
            vid = _ref_of(v)
            if vid in recs:
                self.consumed.add(vid)
                pref = next((_ref_of(x) for x in recs[vid]["args"] if _ref_of(x) is not None), None)
                by_pair[pref] = vid
        for p in self.mech.pairs:
            pid = self.ids["pair"].get(p.name)
            if pid in by_pair:
                self.ids["value"][p.name] = by_pair[pid]

    def _mechanism(self) -> dict:
        """The mechanism, its structure, properties, ground and base (one mechanism per file:
        all of them are its); the mechanism-level ids the new instances take."""
        for i in self.kin:
            if self.types[i] & _MECHANISM_TYPES:
                self.consumed.add(i)
        mech_ids = dict(self.mech.ids)
        for role, types in (("structure", ("kinematic_structure", "kinematic_topology_structure")),
                            ("mechanism", ("mechanism", "mechanism_representation")),
                            ("base_placement", ("mechanism_base_placement",))):
            if mech_ids.get(role) not in self.records:
                found = self.of_type(*types)
                if found:
                    mech_ids[role] = found[0]
        self.k.mech = _with_ids(self.mech, mech_ids)
        return mech_ids

    def _supporting(self):
        """World context, world origin, the assembly's product definition."""
        k = self.k
        world_ctx = None
        for etype in ("kinematic_ground_representation", "mechanism_representation", "kinematic_topology_structure"):
            found = self.of_type(etype)
            if found:
                world_ctx = self.records[found[0]]["args"][2]
                break
        k.world_ctx = world_ctx if world_ctx is not None else k.link_ctx[self.mech.base]
        found = self.of_type("kinematic_property_definition", "product_definition_kinematics")
        if not found:
            raise _model_error("the source has no product definition for the mechanism "
                               "(kinematic_property_definition / product_definition_kinematics)", None)
        k.assembly_pd = self.records[found[0]]["args"][2]
        for i in self.of_type("kinematic_ground_representation")[:1]:
            items = [_ref_of(x) for x in self.records[i]["args"][1]]
            origin = next((x for x in items if "axis2_placement_3d" in self.types.get(x, ())), None)
            if origin is not None:
                k.world_origin = {"ref": origin}

    # -- the output
    def _assemble(self) -> list:
        """Kept source instances and the new kinematics, with a diagnostic for everything of
        the source that is left out and not re-expressed."""
        kin, b = self.kin, self.b
        new = {r["id"]: r for r in b.data}
        # what of the source's kinematics is not re-expressed: kept as it is when the target has
        # its entities and everything it refers to is still there, of the same type (a motion
        # program in a same-layout conversion); else reported
        target_entities = _target_entities(self.profile)
        carried = self._carried(kin - self.consumed, kin, new, target_entities)
        for i in sorted(kin - self.consumed - carried):
            t = self.types[i]
            label = "+".join(sorted(t))
            if target_entities is not None and not all(x in target_entities for x in t):
                why = f"{label} does not exist in {self.profile}"
            elif t & _LOOP_TYPES:
                why = f"{label} (loop structure) is not converted; `p105 graph` derives the loops"
            else:
                why = (f"{label} is not converted (p105 converts configuration sequences, not paths, other "
                       "programs or results)")
            self.diags.append(f"#{i}: {why}; left out")

        dropped = (kin - carried) | self.extra_drop
        # source records are shared, not copied: nothing here changes a record in place
        kept = {i: self.records[i] for i in self.order if i not in dropped}
        # a kept instance that still refers to a dropped one (whose id no new instance took)
        # goes too, with a diagnostic
        todo = sorted({r for d in dropped for r in self.referrers.get(d, ()) if r in kept})
        while todo:
            i = todo.pop(0)
            if i not in kept:
                continue
            bad = [t for t in self.refs[i] if t in dropped and t not in new]
            if bad:
                label = "+".join(sorted(self.types[i]))
                self.diags.append(f"#{i}: {label} refers to #{bad[0]}, which is not converted; left out")
                del kept[i]
                dropped.add(i)
                todo.extend(sorted(r for r in self.referrers.get(i, ()) if r in kept))
        self._fix_profile(kept, b, new)
        data = {**kept, **new}
        refs = {i: (self.refs[i] if rec is self.records.get(i) else _rec_refs(rec)) for i, rec in data.items()}
        for i in _collect_orphans(data, refs, self.referrers, set(new)):
            t = self.types[i]
            if not t & _QUIET_ORPHANS and i not in self.quiet:
                self.diags.append(f"#{i}: {'+'.join(sorted(t))} was used only by instances that are not "
                                  "converted; left out")
        if target_entities is not None:
            for i in sorted(kept):
                missing = [t for t in sorted(self.types[i]) if t not in target_entities]
                if i in data and missing:
                    self.diags.append(f"#{i}: {'+'.join(sorted(self.types[i]))}: {missing[0]} does not exist "
                                      f"in {self.profile} (kept as it is)")
        return [data[i] for i in sorted(data)]

    def _check_base(self, header, data, iid):
        """AP242 has no mechanism_base_placement: the base is placed in the world only by the
        assembly (the base link's product occurrence). Say whether the converted file still
        carries the source's base placement that way."""
        from p105cli.step import DataSection
        from p105cli.step.jsonmodel import JsonDocument

        from .reader import read_mechanisms

        T = np.asarray(self.mech.T_world_base)
        where = f"translation {_fmt(T[:3, 3] / self.mech.units.length)} in file units"
        try:
            back = read_mechanisms(JsonDocument(header, [DataSection(None, len(data))], data), self.profile)
            T_back = next(m for m in back if m.name == self.mech.name).T_world_base
        except Exception:
            T_back = None
        tol = 1e-9 * max(1.0, self.mech.size())
        if T_back is not None and np.allclose(T_back, T, rtol=0.0, atol=tol):
            self.diags.append(f"#{iid}: mechanism_base_placement does not exist in AP242; the base link's "
                              f"placement ({where}) is carried by the assembly that places the base link")
        elif not np.allclose(T, np.eye(4), rtol=0.0, atol=tol):
            self.diags.append(f"#{iid}: mechanism_base_placement does not exist in AP242 and the assembly does "
                              f"not place the base link there: the base placement ({where}) is lost")

    def _carried(self, candidates, kin, new, target_entities) -> set:
        if self.occt or target_entities is None:
            return set()  # Open CASCADE would not read what p105 does not write itself
        dropped = set(kin) | self.extra_drop
        ok = {i for i in candidates if i not in new and all(t in target_entities for t in self.types[i])}
        changed = True
        while changed:
            changed = False
            for i in sorted(ok):
                for r in _rec_refs(self.records[i]):
                    if r in ok:
                        continue
                    if r in new:
                        good = _types(new[r]) == self.types.get(r)
                    else:
                        good = r in self.records and r not in dropped
                    if not good:
                        ok.discard(i)
                        changed = True
                        break
        return ok

    # -- the motion program's configuration sequences
    def _value_of(self, vid, pair_names):
        """(pair name, entity, arguments after the pair) of a pair value of either layout."""
        rec = self.records.get(vid)
        if rec is None or "complex" in rec or not rec["type"].endswith("_pair_value"):
            return None
        a = rec["args"]
        at = 0 if _ref_of(a[0]) is not None else 1  # 1996: (pair, ...); AP242: (name, pair, ...)
        name = pair_names.get(_ref_of(a[at]))
        if name is None:
            return None
        rest = a[at + 1:]
        kind = self.mech.pair(name).kind
        if kind in _HIGHER_VALUES:
            rest = self._higher_value(kind, rest)
            if rest is None:
                return None
        return name, rec["type"], rest

    def _higher_value(self, kind, rest):
        """A higher pair value's arguments with each point as ``("point", key, entity,
        parameters)`` (file units) and each rotation_about_direction as a ypr_rotation; the
        source's point and rotation instances go."""
        from .placements import convert_spatial_to_ypr_rotation

        out = []
        for item, x in zip(_HIGHER_VALUES[kind], rest):
            r = self.records.get(_ref_of(x))
            if isinstance(item, tuple):
                if r is None or not _types(r) & {"point_on_curve", "point_on_surface"}:
                    return None
                self.extra_drop.add(r["id"])
                out.append(("point", item[1], r["type"], list(r["args"][2:])))
            elif item == "ypr" and r is not None:
                d = self.records.get(_ref_of(r["args"][1]))
                if d is None:
                    return None
                ypr = convert_spatial_to_ypr_rotation(d["args"][1], r["args"][2], self.mech.units.angle)
                out.append(typed("ypr_rotation", [float(v) for v in ypr]))
                self.extra_drop.update((r["id"], d["id"]))
            else:
                out.append(x)
        return out

    def _configs_1996(self, seq, initial_vals, pair_names):
        steps = [self.records.get(_ref_of(x)) for x in self.records[seq]["args"][0]]
        if not steps or any(s is None or "configuration_interpolation" not in _types(s) for s in steps):
            return None, []
        defs = [_ref_of(steps[0]["args"][0])] + [_ref_of(s["args"][1]) for s in steps]
        interps = [s["args"][2].get("enum", "UNDEFINED").lower() for s in steps] + ["discontinuous"]
        used = [seq, *(_ref_of(x) for x in self.records[seq]["args"][0])]
        out = []
        for d, interp in zip(defs, interps):
            rec = self.records.get(d)
            if rec is None or len(rec.get("args", ())) < 2:
                return None, []
            vids = [_ref_of(x) for x in rec["args"][0]]
            t = rec["args"][1]
            t = t.get("value") if isinstance(t, dict) else t
            used.append(d)
            out.append((vids, t, interp))
        return self._neutral(out, initial_vals, pair_names, used)

    def _configs_242(self, seq, initial_state, pair_names):
        segs = [self.records.get(_ref_of(x)) for x in self.records[seq]["args"][1]]
        if not segs or any(s is None or "interpolated_configuration_segment" not in _types(s) for s in segs):
            return None, []
        used = [seq, *(_ref_of(x) for x in self.records[seq]["args"][1])]
        out = []
        for s in segs:
            state = _ref_of(s["args"][0])
            rec = self.records.get(state)
            if rec is None or "mechanism_state_representation" not in _types(rec):
                return None, []
            interp = s["args"][2].get("enum", "UNDEFINED_INTERPOLATION_TYPE").lower().replace("_interpolation_type", "")
            if state != initial_state:
                used.append(state)
            out.append(([_ref_of(x) for x in rec["args"][1]] if state != initial_state else None, s["args"][1],
                        interp))
        return self._neutral(out, None, pair_names, used)

    def _neutral(self, configs, initial_vals, pair_names, used):
        out = []
        for vids, t, interp in configs:
            if not isinstance(t, (int, float)):
                return None, []
            if vids is None or (initial_vals is not None and sorted(vids) == sorted(initial_vals)):
                out.append((None, float(t), interp))
                continue
            values = [self._value_of(v, pair_names) for v in vids]
            if any(v is None for v in values):
                return None, []
            used.extend(vids)
            out.append((values, float(t), interp))
        return out, used

    def _sequences(self, k, ids, consumed):
        if self.occt:
            return  # Open CASCADE does not read them: reported with the rest
        pair_names = {pid: name for name, pid in ids["pair"].items()}
        initial = self.mech.ids.get("initial_state")
        initial_vals = None
        if initial in self.records and "initial_state" in self.types[initial]:
            initial_vals = [_ref_of(x) for x in self.records[initial]["args"][1]]
        found = []
        for seq in self.of_type("interpolated_configuration_sequence"):
            a = self.records[seq]["args"]
            if len(a) == 1:
                configs, used = self._configs_1996(seq, initial_vals, pair_names)
                name = f"{self.mech.name} configurations"
                holders = self.referrers.get(seq, [])
            else:
                configs, used = self._configs_242(seq, initial, pair_names)
                name = a[0]
                holders = [r for r in self.referrers.get(seq, [])
                           if "interpolated_configuration_representation" in self.types[r]]
                used.extend(holders)
            if configs:
                found.append((name, configs, used, holders))
        for name, configs, used, holders in found:
            ctx = None
            if k.layout == "ap242":
                ctx = self._motion_context(k, holders)
            k.configuration_sequence(name, configs, ctx)
            consumed.update(used)
            self.extra_drop.update(i for i in used if i in self.records)
            if k.layout == "1996":  # a kinematic_control is written anew; AP242's motion context goes
                consumed.update(h for h in holders if "kinematic_control" in self.types[h])
                self.quiet.update(_ref_of(self.records[h]["args"][2]) for h in holders
                                  if "interpolated_configuration_representation" in self.types[h])

    def _motion_context(self, k, holders):
        """The context of an interpolated_configuration_representation: the source's (AP242),
        else the world context with a (dimensionless) parameter."""
        for h in holders:
            if "interpolated_configuration_representation" in self.types[h]:
                return self.records[h]["args"][2]
        ctx = self.records.get(_ref_of(k.world_ctx))
        if ctx is None or "complex" not in ctx:
            return k.world_ctx
        parts = []
        for part in ctx["complex"]:
            args = part["args"]
            if part["type"] == "representation_context":
                args = [f"{self.mech.name} motion", *args[1:]]
            parts.append((part["type"], args))
        parts.append(("geometric_representation_context_with_parameter", [None]))
        return k.b.add_complex(parts)

    # -- what differs between the layouts outside the kinematics
    def _fix_profile(self, kept, b, new):
        layout = self.prof["layout"]
        app, schema_name, year = _APPLICATION[layout]
        for i, rec in kept.items():
            t = self.types[i]
            if "application_protocol_definition" in t and "complex" not in rec:
                a = list(rec["args"])
                if len(a) >= 3:
                    a[1], a[2] = schema_name, year
                    kept[i] = {**rec, "args": a}
            if "conversion_based_unit" in t and "named_unit" in t:
                parts = []
                for part in rec["complex"]:
                    if part["type"] == "named_unit":
                        if self.prof["cbu_dimensions_explicit"]:
                            if part["args"] and part["args"][0] == DERIVED:
                                kind = next((x for x in t if x in _DIMENSIONS), "ratio_unit")
                                dims = b.add("dimensional_exponents", *[float(x) for x in _DIMENSIONS[kind]])
                                new[dims["ref"]] = b.data[-1]
                                part = {"type": "named_unit", "args": [dims]}
                        else:
                            part = {"type": "named_unit", "args": [DERIVED]}
                    parts.append(part)
                kept[i] = {"id": i, "complex": parts}
        if layout == "1996":
            # AP214's product_requires_id_owner: every product has an 'id owner' organization
            owned = False
            for i, rec in kept.items():
                if "applied_organization_assignment" in self.types[i]:
                    role = _ref_of(rec["args"][1])
                    if role in kept and kept[role]["args"][0] == "id owner":
                        owned = True
            products = [{"ref": i} for i in kept if "product" in self.types[i]]
            if products and not owned:
                org = b.add("organization", "p105cli", "p105cli", None)
                role = b.add("organization_role", "id owner")
                b.add("applied_organization_assignment", org, role, products)
                for r in b.data[-3:]:
                    new[r["id"]] = r


def _with_ids(mech, ids):
    import dataclasses

    return dataclasses.replace(mech, ids=ids)


def _target_entities(profile):
    try:
        from p105cli.schema.profiles import get_profile

        return get_profile(profile).schema.entities
    except Exception:  # the schema data is missing: no per-entity check
        return None


def _target_header(header, prof) -> dict:
    out = {k: (dict(v) if isinstance(v, dict) else v) for k, v in (header or {}).items()}
    out["file_schema"] = [prof["schema"]]
    return out


#: Supporting geometry that goes with the kinematic instances it served, without a diagnostic
#: (the kinematics it belonged to is re-expressed or reported itself).
_QUIET_ORPHANS = frozenset((
    "cartesian_point", "direction", "vector", "axis2_placement_3d", "cartesian_transformation_operator_3d",
    "su_parameters", "dimensional_exponents", "rotation_about_direction",
))


def _collect_orphans(data: dict, refs: dict, src_referrers, new_ids: set) -> list:
    """Remove kept instances that something referred to in the source and nothing refers to now
    (items of the replaced kinematics), transitively; returns their ids. ``refs``: the
    references of each record of ``data``."""
    removed = []
    refcount = defaultdict(int)
    for i in data:
        for t in refs[i]:
            refcount[t] += 1
    todo = [i for i in data if i not in new_ids and refcount[i] == 0 and src_referrers.get(i)]
    while todo:
        i = todo.pop()
        if i not in data:
            continue
        data.pop(i)
        removed.append(i)
        for t in refs[i]:
            refcount[t] -= 1
            if refcount[t] == 0 and t in data and t not in new_ids and src_referrers.get(t):
                todo.append(t)
    return sorted(removed)


def _model_error(message, iid):
    from p105cli.step.errors import ModelError

    return ModelError(f"#{iid}: {message}" if isinstance(iid, int) else message)
