"""Writers: a mechanism as JSON-model records in one schema profile.

Profiles (see :data:`PROFILES`):

* ``ap214`` - AUTOMOTIVE_DESIGN (AP214 ed3), the 1996 Part 105 layout as
  the AP214 long form carries it: ``rigid_placement`` is axis2_placement_3d
  only;
* ``p105`` - the same 1996 layout with ``su_parameters`` allowed as a
  ``rigid_placement`` (ISO 10303-105:1996 5.3.1); FILE_SCHEMA is still
  AUTOMOTIVE_DESIGN, the profile is chosen with ``--schema p105``;
* ``ap242`` - AP242 (ISO 10303-442, MIM long form N10962), the Part 105 ed2
  layout that Open CASCADE reads.

Both layouts carry the same mechanism: units (mm, degree), one product per
link plus the mechanism assembly (links placed at their initial-state
poses), link representations that share their context with the link's
shape, pairs with ranges, the base placement, the actuated pairs, the
initial state and a motion program (three configurations; a prescribed
point-to-point path in AP242). What one layout cannot say is written the
way the other can, or left out with a comment here:

1996 / AP214
  - no Cartesian path geometry: AP214 carries ``kinematic_path`` as a bare
    named ``representation_item`` (the clause 6 path elements of Part
    105:1996 are not in the AP214 long form). The path is written as a
    ``founded_kinematic_path`` tied to the link frame by a
    ``motion_link_relationship``; the motion itself is the
    ``kinematic_control`` with an ``interpolated_configuration_sequence``
    of ``configuration_definition``s (full sets of pair values).
  - a link representation holds frames only (its WR1), so a cam profile
    lives in a ``kinematic_frame_background_representation`` associated to
    the cam's pair frame (``frame_associated_to_background``); the contact
    points and the range's trimmed curve go there too, and the
    ``kinematic_frame_based_transformation`` is the one item of a plain
    ``representation`` in the cam's context, because every
    representation_item must be used by a representation (WR1 of
    representation_item) and no kinematic representation may hold it.
  - the contact orientation is a typed ``YPR_ROTATION`` (a
    ``rotation_about_direction`` would need a DIRECTION, another item that
    no representation could hold).
  - actuation is per pair (``pair_actuator``), not per degree of freedom.
  - the degree's ``named_unit.dimensions`` is ``*``: the AP214 ed3 long
    form re-declares it as DERIVE in ``conversion_based_unit`` (CAD systems
    write a DIMENSIONAL_EXPONENTS there, as AP242 requires).
AP242
  - no ``mechanism_base_placement``: the base is
    ``kinematic_property_mechanism_representation.base``; the base link is
    placed in the world by the assembly (the base link's product
    occurrence), as every link is.
  - actuation is ``actuated_kinematic_pair``, a complex instance with the
    pair (``ANDOR`` in kinematic_pair's supertype expression).
  - ranges are the pairs' ``*_with_range`` subtypes; an unlimited range is
    the plain pair type (the 1996 layout writes ``.UNLIMITED.``).

Both: shapes are ``geometrically_bounded_wireframe_shape_representation``s
(AP242's global rule ap242_subtype_mandatory_shape_representation wants a
specific shape representation type for anything but bare placements); the
application protocol definitions name the schema the global rules ask for
('AUTOMOTIVE_DESIGN_LF', 'ap242_managed_model_based_3d_engineering_mim_lf');
AP214 products get the 'id owner' organization its product_requires_id_owner
rule requires.
"""

from __future__ import annotations

import math

import numpy as np

from p105cli.part105.catalogue import APPLICATION as _APPLICATION
from p105cli.part105.catalogue import PROFILES, SCHEMA_AP214, SCHEMA_AP242  # noqa: F401 (re-exported)

from p105cli.part105.builder import DERIVED, FALSE, TRUE, Builder, enum, real, typed
from .digits import round_records
from .geometry import compose, su_parameters, ypr_angles
from .mechanisms import Mechanism, configuration, pair_frames, resolved_limits, scalar_value

#: Fixed so that regenerating the corpus gives the same bytes.
TIME_STAMP = "2026-01-01T00:00:00"



def header(mech: Mechanism, profile: str, filename: str) -> dict:
    prof = PROFILES[profile]
    return {
        "file_description": {"description": [f"p105cli corpus: {mech.title}; {prof['label']}"],
                             "implementation_level": "2;1"},
        "file_name": {"name": filename, "time_stamp": TIME_STAMP, "author": ["p105cli"],
                      "organization": ["p105cli project"], "preprocessor_version": "p105cli.corpus",
                      "originating_system": "p105cli corpus generator", "authorization": ""},
        "file_schema": [prof["schema"]],
    }


def records(mech: Mechanism, profile: str, *, rounded: bool = True) -> list[dict]:
    """The JSON-model records of ``mech`` in ``profile``; with ``rounded`` (the corpus files)
    every computed real to :data:`~p105cli.corpus.digits.DIGITS` significant digits, so that
    the files are the same bytes on every machine (see :mod:`p105cli.corpus.digits`)."""
    prof = PROFILES[profile]
    w = _Common(mech, profile)
    if prof["layout"] == "1996":
        _write_1996(w)
    else:
        _write_ap242(w)
    return round_records(w.b.data) if rounded else w.b.data


# ------------------------------------------------------------------ shared part

class _Common:
    """State shared by both layouts: builder, contexts, products, poses, values."""

    def __init__(self, mech: Mechanism, profile: str):
        self.mech = mech
        self.prof = PROFILES[profile]
        self.b = b = Builder()
        self.su = self.prof["su"] and mech.use_su
        axis = self.prof["slide_axis"]
        self.frames = {p.name: pair_frames(p, axis) for p in mech.pairs}
        self.states = [configuration(mech, d, axis) for d in mech.drives]
        self.limits = resolved_limits(mech)
        check_ranges(mech, self.states, self.limits)
        self.poses = mech.solve(mech.drives[0])
        explicit = self.prof["cbu_dimensions_explicit"]
        b.units(cbu_dimensions_explicit=explicit)
        self.world = b.context(f"{mech.key} world")
        self.link_ctx = {ln.name: b.context(f"{mech.key} link {ln.name}") for ln in mech.links}
        self._products()

    # products: the mechanism assembly and one part per link, placed at the initial state
    def _products(self):
        b, mech = self.b, self.mech
        app, schema_name, year = _APPLICATION[self.prof["layout"]]
        pf = b.product_frame(app, schema_name, year)
        self.link_origin = {}
        self.parts = {}
        self.shape_circles = []
        for ln in mech.links:
            origin = b.axis2(np.eye(4), f"{ln.name} link frame")
            self.link_origin[ln.name] = origin
            curves = [b.polyline(ln.outline, f"{ln.name} outline")]
            for T, radius, cname in ln.circles:
                circle = b.circle(T, radius, f"{ln.name} {cname}")
                self.shape_circles.append((ln.name, np.asarray(T, float)[:3, 3], float(radius), circle))
                curves.append(circle)
            items = [origin, b.add("geometric_curve_set", f"{ln.name} wireframe", curves)]
            self.parts[ln.name] = b.part(pf, f"{mech.key}-{ln.name}", ln.name, ln.description, items,
                                         self.link_ctx[ln.name], shape_name=f"{ln.name} shape",
                                         shape_type="geometrically_bounded_wireframe_shape_representation")
        world_origin = b.axis2(np.eye(4), "world")
        placements = {ln.name: b.axis2(compose(mech.base_pose, self.poses[ln.name]), f"{ln.name} placement")
                      for ln in mech.links}
        self.world_origin = world_origin
        self.assembly = b.part(pf, mech.key, mech.title, mech.description,
                               [world_origin, *placements.values()], self.world, shape_name=f"{mech.key} assembly")
        self.usage = {}
        for k, ln in enumerate(mech.links, start=1):
            self.usage[ln.name] = b.assembly_usage(self.assembly, self.parts[ln.name], f"{mech.key}.{k}",
                                                   ln.name, self.link_origin[ln.name], placements[ln.name])
        products = [self.assembly["product"], *(self.parts[ln.name]["product"] for ln in mech.links)]
        b.add("product_related_product_category", "part", None, products)
        if self.prof["layout"] == "1996":
            # AP214's product_requires_id_owner: every 'part' has one 'id owner'
            org = b.add("organization", "p105cli", "p105cli project", None)
            b.add("applied_organization_assignment", org, b.add("organization_role", "id owner"), products)

    # pair frames: axis2_placement_3d, or su_parameters where the profile and mechanism allow
    def placement(self, pair, which: int, name: str):
        T = self.frames[pair.name][which]
        su = pair.su_first if which == 0 else pair.su_second
        if self.su and su is not None:
            if np.abs(su_parameters(*su) - T).max() > 1e-12:
                raise AssertionError(f"su_parameters of {pair.name} do not give its frame")
            a, alpha, bb, beta, c, gamma = su
            return self.b.add("su_parameters", name, real(a), self.b.angle(alpha), real(bb), self.b.angle(beta),
                              real(c), self.b.angle(gamma))
        return self.b.axis2(T, name)

    def link_placements(self) -> dict:
        """``{link: [placement items]}``: each link's pair frames (in pair order), then its
        named frames; also fills ``pair_items`` and ``named_frames``."""
        mech = self.mech
        self.pair_items = {}
        per_link = {ln.name: [] for ln in mech.links}
        for p in mech.pairs:
            f1 = self.placement(p, 0, f"{p.name} on {p.first}")
            f2 = self.placement(p, 1, f"{p.name} on {p.second}")
            self.pair_items[p.name] = (f1, f2)
            per_link[p.first].append(f1)
            per_link[p.second].append(f2)
        self.named_frames = {}
        for ln in mech.links:
            for fname, T in ln.frames.items():
                item = self.b.axis2(T, f"{ln.name} {fname}")
                self.named_frames[(ln.name, fname)] = item
                per_link[ln.name].append(item)
        return per_link

    def shape_circle(self, link: str, centre, radius: float):
        """The circle of ``link``'s shape with that centre and radius (link coordinates)."""
        for name, c, r, item in self.shape_circles:
            if name == link and np.allclose(c, centre, atol=1e-12) and abs(r - radius) < 1e-12:
                return item
        raise KeyError(f"{link} has no shape circle of radius {radius} at {centre}")

    def t_parameters(self):
        n = len(self.mech.drives)
        return [real(k / (n - 1)) for k in range(n)]

    def path_poses(self):
        """World poses of the path frame at the configurations of the motion program."""
        link, fname = self.mech.path
        T_frame = self.mech.link(link).frames[fname]
        return [compose(self.mech.base_pose, self.mech.solve(d)[link], T_frame) for d in self.mech.drives]

    def orientation_angle(self, value):
        """(axis, angle) of a point-on-curve orientation with the axis turned to +z where it can."""
        axis, angle = value["orientation"]
        if axis[2] < 0 or (axis[2] == 0 and (axis[1] < 0 or axis[1] == 0 and axis[0] < 0)):
            axis, angle = -axis, -angle
        return axis, angle


def check_ranges(mech: Mechanism, states: list, limits: dict) -> None:
    """Every written pair value lies inside its pair's range (ranges are closed intervals)."""
    for k, state in enumerate(states):
        for p in mech.pairs:
            lim = limits[p.name]
            if lim is None or p.kind == "point_on_planar_curve":
                continue
            v = scalar_value(p.kind, state[p.name])
            if not lim[0] <= v <= lim[1]:
                raise AssertionError(f"{mech.key}: {p.name} = {v} at state {k} is outside its range {lim}")


def _limit_args(b: Builder, kind: str, limits, *, layout: str):
    """(lower, upper) arguments of a range in the file's units."""
    if limits is None:
        if layout == "1996":
            u = typed("unlimited_range", enum("unlimited"))
            return [u, u]
        return [None, None]
    lo, hi = limits
    if kind in ("revolute", "gear"):
        lo, hi = b.angle(lo), b.angle(hi)
        tname = "plane_angle_measure"
    else:
        lo, hi = real(lo), real(hi)
        tname = "length_measure"
    if layout == "1996":
        return [typed(tname, lo), typed(tname, hi)]
    return [lo, hi]


# ------------------------------------------------------------------ 1996 layout (AP214, p105)

_PAIR_1996 = {"revolute": "revolute_pair", "prismatic": "prismatic_pair", "gear": "gear_pair",
              "rack_and_pinion": "rack_and_pinion_pair", "point_on_planar_curve": "point_on_planar_curve_pair"}


def _write_1996(w: _Common):
    b, mech = w.b, w.mech
    links = {ln.name: b.add("kinematic_link") for ln in mech.links}
    joints = {p.name: b.add("kinematic_joint", links[p.first], links[p.second]) for p in mech.pairs}
    structure = b.add("kinematic_structure", list(joints.values()))

    per_link = w.link_placements()
    link_rep = {}
    for ln in mech.links:
        rep = b.add("kinematic_link_representation", ln.name, per_link[ln.name], w.link_ctx[ln.name])
        link_rep[ln.name] = rep
        b.add("kinematic_link_representation_relation", links[ln.name], rep)
        b.add("kinematic_link_representation_association", f"{ln.name} shape", None, rep,
              w.parts[ln.name]["shape"])

    # pairs; a pair curve lives in a frame background representation of the first link
    pairs, curves, background = {}, {}, {}
    for p in mech.pairs:
        f1, f2 = w.pair_items[p.name]
        args = [p.name, p.description, f1, f2, joints[p.name]]
        if p.kind == "gear":
            args += [real(p.params["radius_first"]), real(p.params["radius_second"]), b.angle(0.0),
                     b.angle(0.0), real(p.params["gear_ratio"])]
        elif p.kind == "rack_and_pinion":
            args += [real(p.params["pinion_radius"])]
        elif p.kind == "point_on_planar_curve":
            curve = b.circle(_trans(p.params["circle_center"]), p.params["circle_radius"], f"{p.name} pair curve")
            curves[p.name] = curve
            background[p.name] = [curve]
            args += [curve, TRUE]
        pairs[p.name] = b.add(_PAIR_1996[p.kind], *args)

    # ground, property, mechanism, base placement
    cto = b.cartesian_transformation_operator_3d(mech.base_pose, f"base placement of {mech.links[0].name}")
    ground = b.add("kinematic_ground_representation", "ground", [w.world_origin, cto], w.world)
    kpd = b.add("kinematic_property_definition", "kinematics", mech.description, w.assembly["pd"],
                w.parts[mech.links[0].name]["pd"])
    b.add("kinematic_property_representation_relation", kpd, ground)
    mechanism = b.add("mechanism", structure, links[mech.links[0].name], kpd)
    b.add("mechanism_base_placement", "base placement", None, ground, DERIVED, cto, mechanism)

    # ranges and actuators
    for p in mech.pairs:
        limits = w.limits[p.name]
        if p.kind == "point_on_planar_curve":
            start, end = typed("parameter_value", 0.0), typed("parameter_value", b.angle(2 * math.pi))
            trimmed = b.add("trimmed_curve", f"{p.name} range", curves[p.name], [start], [end], TRUE,
                            enum("parameter"))
            background[p.name].append(trimmed)
            u = typed("unlimited_range", enum("unlimited"))
            b.add("point_on_planar_curve_pair_range", pairs[p.name], trimmed, u, u, u, u, u, u)
        else:
            b.add(_PAIR_1996[p.kind] + "_range", pairs[p.name], *_limit_args(b, p.kind, limits, layout="1996"))
    for p in mech.pairs:
        if p.actuated:
            b.add("pair_actuator", pairs[p.name], f"{p.name} drive")

    # initial state and the configurations of the motion program
    def values(state):
        out = []
        for p in mech.pairs:
            v = state[p.name]
            if p.kind == "revolute":
                out.append(b.add("revolute_pair_value", pairs[p.name], b.angle(v["rotation"])))
            elif p.kind == "prismatic":
                out.append(b.add("prismatic_pair_value", pairs[p.name], real(v["translation"])))
            elif p.kind == "gear":
                out.append(b.add("gear_pair_value", pairs[p.name], b.angle(v["rotation_1"])))
            elif p.kind == "rack_and_pinion":
                out.append(b.add("rack_and_pinion_pair_value", pairs[p.name], real(v["displacement"])))
            elif p.kind == "point_on_planar_curve":
                point = b.add("point_on_curve", f"{p.name} point", curves[p.name], b.angle(v["parameter"]))
                background[p.name].append(point)
                # a ypr_rotation (typed), not a rotation_about_direction: the latter's direction
                # would be a representation item in no representation
                ypr = typed("ypr_rotation", b.angle(ypr_angles(v["orientation"])))
                out.append(b.add("point_on_planar_curve_pair_value", pairs[p.name], point, ypr))
        return out

    initial = values(w.states[0])
    b.add("initial_state", mechanism, initial)

    configs = [b.add("configuration_definition", initial, typed("parameter_value", w.t_parameters()[0]))]
    for state, t in zip(w.states[1:], w.t_parameters()[1:]):
        configs.append(b.add("configuration_definition", values(state), typed("parameter_value", t)))
    steps = [b.add("configuration_interpolation", c0, c1, enum("linear")) for c0, c1 in zip(configs, configs[1:])]
    sequence = b.add("interpolated_configuration_sequence", steps)
    b.add("kinematic_control", mechanism, [sequence])

    # frame backgrounds: the pair curve with its range and contact points, in the frame of the
    # first pair placement (kinematic_frame_based_transformation, itself an item of a plain
    # representation in the link's context: a representation_item must be used by one)
    for p in mech.pairs:
        if p.kind != "point_on_planar_curve":
            continue
        f1 = w.pair_items[p.name][0]
        bg_ctx = b.context(f"{mech.key} {p.name} background")
        bg = b.add("kinematic_frame_background_representation", f"{p.name} background", background[p.name], bg_ctx)
        kfbt = b.add("kinematic_frame_based_transformation", f"{p.name} background placement",
                     f"{p.name} background placement", None, f1)
        b.add("representation", f"{p.name} background placement", [kfbt], w.link_ctx[p.first])
        b.add("kinematic_frame_background_representation_association", f"{p.name} background", None,
              link_rep[p.first], bg, kfbt)

    # the path: a named kinematic_path founded in the world, tied to the link frame whose
    # motion it describes (AP214 has no path geometry, see the module docstring)
    link, fname = mech.path
    kpath = b.add("kinematic_path", f"{link} {fname} path")
    founded = b.add("founded_kinematic_path", f"{link} {fname} path", [kpath], w.world)
    b.add("motion_link_relationship", f"{link} {fname} motion", None, founded, link_rep[link],
          w.named_frames[(link, fname)])


def _trans(p):
    T = np.eye(4)
    T[:3, 3] = np.asarray(p, float)
    return T


# ------------------------------------------------------------------ AP242 layout

_PAIR_242 = {"revolute": ("revolute_pair", "revolute_pair_with_range"),
             "prismatic": ("prismatic_pair", "prismatic_pair_with_range"),
             "gear": ("gear_pair", "gear_pair_with_range"),
             "rack_and_pinion": ("rack_and_pinion_pair", "rack_and_pinion_pair_with_range"),
             "point_on_planar_curve": ("point_on_planar_curve_pair", "point_on_planar_curve_pair_with_range")}

#: The actuated freedom (index into t_x, t_y, t_z, r_x, r_y, r_z) of each actuated pair kind.
_ACTUATED_DOF = {"revolute": 5, "prismatic": 0}


def _write_ap242(w: _Common):
    b, mech = w.b, w.mech
    links = {ln.name: b.add("kinematic_link", ln.name) for ln in mech.links}
    joints = {p.name: b.add("kinematic_joint", p.name, links[p.first], links[p.second]) for p in mech.pairs}
    topology = b.add("kinematic_topology_structure", f"{mech.key} topology", list(joints.values()), w.world)

    per_link = w.link_placements()
    curves, trimmed = {}, {}
    for p in mech.pairs:
        if p.kind == "point_on_planar_curve":
            # the pair curve is an item of the first link's representation, in the first pair
            # frame, which is the cam's link frame here (checked below)
            if np.abs(w.frames[p.name][0] - np.eye(4)).max() > 1e-12:
                raise AssertionError("the pair curve is written in the link frame: its pair frame must be it")
            curve = w.shape_circle(p.first, p.params["circle_center"], p.params["circle_radius"])
            start, end = typed("parameter_value", 0.0), typed("parameter_value", b.angle(2 * math.pi))
            trim = b.add("trimmed_curve", f"{p.name} range", curve, [start], [end], TRUE, enum("parameter"))
            curves[p.name], trimmed[p.name] = curve, trim
            per_link[p.first] += [curve, trim]
    link_rep, klra = {}, {}
    for ln in mech.links:
        rep = b.add("rigid_link_representation", ln.name, per_link[ln.name], w.link_ctx[ln.name], links[ln.name])
        link_rep[ln.name] = rep
        klra[ln.name] = b.add("kinematic_link_representation_association", f"{ln.name} shape", None, rep,
                              w.parts[ln.name]["shape"])

    pairs = {}
    for p in mech.pairs:
        pairs[p.name] = _pair_242(w, p, w.pair_items[p.name], joints[p.name], curves.get(p.name),
                                  trimmed.get(p.name))
    prr = [b.add("pair_representation_relationship", p.name, p.name, p.description, link_rep[p.first],
                 link_rep[p.second], pairs[p.name]) for p in mech.pairs]
    mech_rep = b.add("mechanism_representation", mech.key, prr, w.world, topology)

    pdk = b.add("product_definition_kinematics", "kinematics", mech.description, w.assembly["pd"])
    b.add("kinematic_property_mechanism_representation", pdk, mech_rep, link_rep[mech.links[0].name])
    for ln in mech.links:
        pdrk = b.add("product_definition_relationship_kinematics", ln.name, f"kinematic link {ln.name}",
                     w.usage[ln.name]["nauo"])
        b.add("context_dependent_kinematic_link_representation", klra[ln.name], pdrk)

    # loops (closed chains), as oriented joints
    if mech.loops:
        loops = []
        for k, loop in enumerate(mech.loops, start=1):
            edges = [b.add("oriented_joint", "", DERIVED, DERIVED, joints[name], TRUE if fwd else FALSE)
                     for name, fwd in loop]
            loops.append(b.add("kinematic_loop", f"loop {k}", edges))
        b.add("kinematic_topology_network_structure", f"{mech.key} loops", loops, w.world, topology)

    # states: the initial one and the other configurations of the motion program
    def state(conf, name):
        items = []
        for p in mech.pairs:
            v = conf[p.name]
            if p.kind == "revolute":
                items.append(b.add("revolute_pair_value", p.name, pairs[p.name], b.angle(v["rotation"])))
            elif p.kind == "prismatic":
                items.append(b.add("prismatic_pair_value", p.name, pairs[p.name], real(v["translation"])))
            elif p.kind == "gear":
                items.append(b.add("gear_pair_value", p.name, pairs[p.name], b.angle(v["rotation_1"])))
            elif p.kind == "rack_and_pinion":
                items.append(b.add("rack_and_pinion_pair_value", p.name, pairs[p.name], real(v["displacement"])))
            elif p.kind == "point_on_planar_curve":
                point = b.add("point_on_curve", f"{p.name} point", curves[p.name], b.angle(v["parameter"]))
                axis, angle = w.orientation_angle(v)
                rot = b.add("rotation_about_direction", "", b.direction(axis), b.angle(angle))
                items.append(b.add("point_on_planar_curve_pair_value", p.name, pairs[p.name], point, rot))
        return b.add("mechanism_state_representation", name, items, DERIVED, mech_rep)

    states = [state(w.states[0], "initial state")]
    for k, conf in enumerate(w.states[1:], start=1):
        states.append(state(conf, f"configuration {k}"))

    path_ctx = b.context(f"{mech.key} motion", with_parameter=True)
    ts = w.t_parameters()
    segments = [b.add("interpolated_configuration_segment", s, t,
                      enum("linear_interpolation_type" if k + 1 < len(states) else "discontinuous_interpolation_type"))
                for k, (s, t) in enumerate(zip(states, ts))]
    sequence = b.add("interpolated_configuration_sequence", f"{mech.key} configurations", segments)
    b.add("interpolated_configuration_representation", f"{mech.key} configurations", [sequence], path_ctx)

    # the prescribed path: the world placements of the path frame at those configurations,
    # joined point to point
    link, fname = mech.path
    poses = w.path_poses()
    start = b.axis2(poses[0], f"{fname} at t={ts[0]:g}")
    nodes = [b.add("point_to_point_path", t, DERIVED, b.axis2(T, f"{fname} at t={t:g}"))
             for T, t in zip(poses[1:], ts[1:])]
    kpath = b.add("kinematic_path_defined_by_nodes", f"{link} {fname} path", nodes, ts[0], start)
    driving = [joints[p.name] for p in mech.pairs if p.actuated]
    prescribed = b.add("prescribed_path", f"{link} {fname} path", [kpath], path_ctx, driving)
    lmt = b.add("link_motion_transformation", f"{link} {fname} motion", None, w.named_frames[(link, fname)], kpath)
    b.add("link_motion_relationship", f"{link} {fname} motion", None, link_rep[link], prescribed, lmt)
    b.add("kinematic_control", mech_rep, prescribed)


def _pair_242(w: _Common, p, items, joint, curve, trim):
    """A pair in the AP242 layout: a simple instance, or a complex one with
    ``actuated_kinematic_pair`` when the pair is driven."""
    b = w.b
    f1, f2 = items
    limits = w.limits[p.name]
    plain, ranged = _PAIR_242[p.kind]
    with_range = limits is not None or p.kind == "point_on_planar_curve"
    entity = ranged if with_range else plain
    own = []  # the pair type's own attributes (after kinematic_pair's)
    if p.kind in ("revolute", "prismatic"):
        flags = [DERIVED] * 6
    else:
        flags = []
    if p.kind == "gear":
        own = [real(p.params["radius_first"]), real(p.params["radius_second"]), b.angle(0.0), b.angle(0.0),
               real(p.params["gear_ratio"])]
    elif p.kind == "rack_and_pinion":
        own = [real(p.params["pinion_radius"])]
    elif p.kind == "point_on_planar_curve":
        own = [curve, TRUE]
    range_args = []
    if p.kind == "point_on_planar_curve":
        range_args = [trim, None, None, None, None, None, None]
    elif with_range:
        range_args = _limit_args(b, p.kind, limits, layout="ap242")
    if not p.actuated:
        return b.add(entity, p.name, DERIVED, p.description, f1, f2, joint, *flags, *own, *range_args)
    if p.kind not in _ACTUATED_DOF:
        raise NotImplementedError(f"actuated {p.kind} pairs")
    directions = [enum("not_actuated")] * 6
    directions[_ACTUATED_DOF[p.kind]] = enum("bidirectional")
    parts = [("actuated_kinematic_pair", directions), ("geometric_representation_item", []),
             ("item_defined_transformation", [DERIVED, p.description, f1, f2]), ("kinematic_pair", [joint]),
             ("low_order_kinematic_pair", flags), ("representation_item", [p.name]), (plain, [])]
    if with_range:
        parts.append((ranged, range_args))
    return b.add_complex(parts)
