"""Part 105 records of a :class:`~p105cli.kinematics.model.Mechanism` in one layout.

:class:`Emitter` writes the kinematic instances (links, joints, pairs with their frames, ranges,
actuation and higher-pair geometry, the mechanism, its base and initial state, AP242's loops,
configuration sequences) given the supporting instances (contexts, shapes, product definitions)
as references; :class:`IdBuilder` allocates the ids, and can give a new instance the id of the
source instance it replaces (a conversion). Used by :mod:`.write_mechanism` (a self-contained
file) and :mod:`.convert` (a layout conversion of a source).

SI inside the model; the emitter converts to the file's units.
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from p105cli.kinematics.dh import Z_TO_X
from p105cli.kinematics.pairs import FREEDOM_NAMES, PAIR_KINDS
from p105cli.kinematics.spatial import compose, inverse

from .builder import DERIVED, FALSE, TRUE, Builder, enum, real, typed
from .catalogue import (COUPLED_FREEDOMS, FREEDOM_FLAGS, HIGHER_GEOMETRY, HIGHER_PARAMS_NOT_IN_FILE, HIGHER_VALUES,
                        PROFILES, RANGE_KINDS_1996, RANGE_KINDS_AP242, WRITTEN_HIGHER_RANGES, WRITTEN_LOW_KINDS,
                        pair_entity)
from .pair_values import scalar_values, value_arguments, value_entity, ypr_values

__all__ = ["Emitter", "IdBuilder", "NotWritableError", "write_kinematics", "SUPPORTED_KINDS", "VALUE_UNITS", "HIGHER_KINDS_WRITTEN"]

#: Per written low pair kind: the unit of each value ("A" plane angle, "L" length), in value order.
VALUE_UNITS = {k: "".join(PAIR_KINDS[k].value_units) for k in WRITTEN_LOW_KINDS}
#: A generic low-order pair's limits in the order of AP242's low_order_kinematic_pair_with_range
#: (rotations, then translations), as indices into its values (translations, then rotations).
_LOW_ORDER_RANGE_ORDER = (3, 4, 5, 0, 1, 2)


class NotWritableError(ValueError):
    """The target layout cannot express a pair of the mechanism (the message names it): the
    file is not written (exit 1), rather than written without the pair."""

#: The higher pair kinds written (their geometry with them).
HIGHER_KINDS_WRITTEN = tuple(HIGHER_GEOMETRY)
#: Every pair kind p105 writes.
SUPPORTED_KINDS = (*VALUE_UNITS, *HIGHER_KINDS_WRITTEN)


# ------------------------------------------------------------------ id allocation

class IdBuilder(Builder):
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



class Emitter:
    """Writes the kinematic instances of ``mech`` in one layout, given the supporting
    instances (contexts, shapes, product definitions) as references."""

    def __init__(self, mech, profile, b: IdBuilder, length_factor: float, occt_compat: bool, diags: list):
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
        if p.kind in HIGHER_KINDS_WRITTEN:
            keys, oriented = HIGHER_GEOMETRY[p.kind]
            own = [self.curves[(p.name, key)] for key, _ in keys]
            return own + ([TRUE if prm.get("orientation", True) else FALSE] if oriented else [])
        return []

    # -- higher pairs: the pair curve and points on it
    def write_geometry(self, obj):
        """Records of a curve or surface object (metres, radians) in file units; its reference."""
        from p105cli.kinematics import geometry as G
        from .geometry import curve_records, surface_records

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
        for key, which in HIGHER_GEOMETRY[p.kind][0]:
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
        from p105cli.kinematics import geometry as G

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
        for item in HIGHER_VALUES[p.kind]:
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
                    which = dict(HIGHER_GEOMETRY[p.kind][0])[key]
                    self.background_items[(p.name, which)].append(point)
                out.append(point)
        return out

    def higher_range(self, p):
        """``(trimmed geometry, [yaw, pitch, roll limits as arguments])`` of a point-on-curve or
        point-on-surface pair with limits, or None (with a diagnostic when they cannot be
        written). The trimmed geometry still has to be put in a representation."""
        from p105cli.kinematics import geometry as G

        if p.kind not in WRITTEN_HIGHER_RANGES or not self.has_range(p):
            return None
        where = p.ids.get("range") or p.ids.get("pair")
        n = 1 if p.kind == "point_on_planar_curve" else 2
        key = HIGHER_GEOMETRY[p.kind][0][0][0]
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
        CASCADE (which reads that select as a real) the equal rotation_about_direction. The
        triple written is the canonical one of 5.3.7 (roll 0 at a rectangular pitch: what
        validate accepts), whatever triple the analysis produced or the user drove."""
        if not self.occt:
            return typed("ypr_rotation", ypr_values(ypr, self.A))
        from p105cli.kinematics.spatial import rotation_vector
        from p105cli.kinematics.placements import ypr_rotation

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
        units, lower, upper = VALUE_UNITS[p.kind], p.lower, p.upper
        if p.kind == "low_order":  # AP242 lists the rotation limits first
            units, lower, upper = ([seq[i] for i in _LOW_ORDER_RANGE_ORDER] for seq in (units, lower, upper))
        for unit, lo, hi in zip(units, lower, upper):
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
        if kind not in FREEDOM_FLAGS:
            return []
        if self.occt:
            return [TRUE if f else FALSE for f in FREEDOM_FLAGS[kind]]
        return [DERIVED] * 6

    def pair_value(self, p, pair_ref, q):
        """The ``*_pair_value`` of ``p`` at ``q`` (SI), or None for a pair without values."""
        b = self.b
        kind = p.kind
        if kind == "fully_constrained":
            return None
        entity = value_entity(kind)
        if kind in HIGHER_KINDS_WRITTEN:
            vals = self.higher_values(p, q)
        elif kind == "spherical":
            vals = [self.orientation(q)]
        elif kind == "unconstrained":
            M = p.motion(np.asarray(q, float))
            vals = [self.axis2(M, f"{p.name} value")]
            if self.layout == "1996":  # a representation item must be in a representation (WR1)
                self.b.add("representation", f"{p.name} value", vals, self.link_ctx[p.link1])
        else:
            vals = scalar_values(VALUE_UNITS[kind], q, self.A, self.L)
        self._reuse("value", p.name)
        return b.add(entity, *value_arguments(self.layout, p.name, pair_ref, vals))

    def check_kinds(self):
        ok = []
        for p in self.mech.pairs:
            if p.kind in HIGHER_KINDS_WRITTEN:
                if self.has_range(p) and p.kind not in WRITTEN_HIGHER_RANGES:
                    self.diags.append(_at(p.ids.get("range") or p.ids.get("pair"),
                                          f"pair {p.name!r}: the limits of {p.kind} pairs are not written yet"))
                for key, default in HIGHER_PARAMS_NOT_IN_FILE.items():
                    if key in p.params and p.params[key] is not None and p.params[key] != default:
                        self.diags.append(_at(p.ids.get("pair"), f"pair {p.name!r}: {key} has no attribute in "
                                                                 "the file; not written"))
                ok.append(p)
                continue
            if p.kind == "low_order" and self.layout == "1996":
                flags = ", ".join(f"{f} = {'TRUE' if p.params.get(f, True) else 'FALSE'}" for f in FREEDOM_NAMES)
                raise NotWritableError(_at(p.ids.get("pair"), f"pair {p.name!r}: a low_order_kinematic_pair with "
                                           f"{flags} is no named pair (revolute, prismatic, ...), and the 1996 "
                                           "layout has no generic pair to write it as; not converted"))
            if p.kind not in VALUE_UNITS:
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
            if p.kind in HIGHER_KINDS_WRITTEN:
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
            if self.has_range(p) and p.kind not in RANGE_KINDS_1996 and p.kind not in HIGHER_KINDS_WRITTEN:
                self.diags.append(_at(p.ids.get("range") or p.ids.get("pair"),
                                      f"pair {p.name!r}: the 1996 layout has no range for a {p.kind} pair; its "
                                      "limits are not written"))
            elif self.has_range(p) and p.kind in RANGE_KINDS_1996:
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
            if p.kind in HIGHER_KINDS_WRITTEN:
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
                                which = dict(HIGHER_GEOMETRY[self.mech.pair(pname).kind][0])[key]
                                self.background_items[(pname, which)].append(rest[j])
                    refs.append(b.add(entity, *value_arguments(self.layout, pname, pair, rest)))
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
            from p105cli.kinematics.graph import analyse

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
        with_range = (p.name in self.higher_ranges if p.kind in HIGHER_KINDS_WRITTEN  # (else reported already)
                      else self.has_range(p))
        if with_range and p.kind not in RANGE_KINDS_AP242:
            self.diags.append(_at(p.ids.get("range"), f"pair {p.name!r}: AP242 has no range for a {p.kind} pair; "
                                                      "its limits are not written"))
            with_range = False
        plain = pair_entity(p.kind, "ap242")
        ranged = pair_entity(p.kind, "ap242", with_range=True)
        entity = ranged if with_range else plain
        if p.kind == "low_order":  # the generic pair's flags are its own, written as they are
            flags = [TRUE if p.params.get(f, True) else FALSE for f in FREEDOM_NAMES]
        else:
            flags = self.flags(p.kind)
        own = self.own_params(p)
        if p.kind in HIGHER_KINDS_WRITTEN:
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
        if actuated and p.kind not in FREEDOM_FLAGS and p.kind not in COUPLED_FREEDOMS and p.kind != "low_order":
            self.diags.append(_at(p.ids.get("pair"), f"pair {p.name!r}: actuation not written (which freedoms an "
                                                     f"actuated {p.kind} pair drives is not defined)"))
            actuated = False
        self._reuse("pair", p.name)
        if not actuated:
            return b.add(entity, p.name, name2, p.description, f1, f2, joint, *flags, *own, *range_args)
        if p.kind == "low_order":
            dofs = tuple(not x for x in p.type.locked(p.params))
        else:
            dofs = FREEDOM_FLAGS.get(p.kind) or COUPLED_FREEDOMS[p.kind]
        directions = [enum("bidirectional") if f else enum("not_actuated") for f in dofs]
        parts = [("actuated_kinematic_pair", directions), ("geometric_representation_item", []),
                 ("item_defined_transformation", [DERIVED, p.description, f1, f2]), ("kinematic_pair", [joint]),
                 ("representation_item", [p.name])]
        if p.kind in FREEDOM_FLAGS or p.kind == "low_order":
            parts.append(("low_order_kinematic_pair", flags))
        else:
            parts.append(("low_order_kinematic_pair_with_motion_coupling", []))
        if p.kind == "homokinetic":
            parts += [("universal_pair", own), ("homokinetic_pair", [])]
        elif p.kind != "low_order":  # the generic pair is the low_order_kinematic_pair part itself
            parts.append((plain, own))
        if with_range:
            parts.append((ranged, range_args))
        return b.add_complex(parts)


def _at(iid, message: str) -> str:
    return f"#{iid}: {message}" if isinstance(iid, int) else message



def write_kinematics(k: Emitter, diags):
    mech = k.mech
    if k.layout == "1996":
        k.write_1996()
    else:
        k.write_ap242()
    if mech.paths:
        diags.append(f"mechanism {mech.name!r}: {len(mech.paths)} path(s) of the motion program are not written")

