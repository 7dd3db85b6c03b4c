"""The standard's vocabulary as data: profiles and their layouts, application contexts.

One home for what every reader, writer and check of Part 105 files needs to agree on: the
profiles, the kinematic entity list, pair entities and their kinds, higher-pair geometry
attributes, ranges and limits. No numpy, no schema: plain tables (the pair types of
``kinematics.pairs`` are imported only when a pair kind is asked for).
"""

from __future__ import annotations

from typing import NamedTuple, Optional

__all__ = ["SCHEMA_AP214", "SCHEMA_AP242", "PROFILES", "APPLICATION", "layout_of", "choose_profile",
           "KINEMATIC_ENTITIES", "HIGHER_PAIR_ENTITIES", "HIGHER_KINDS", "pair_kind_of_entity",
           "pair_entity", "range_entity", "GENERIC_LOW_ORDER", "HIGHER_PAIR_GEOMETRY", "HIGHER_PAIR_ORIENTATION",
           "GEOMETRY_ATTRIBUTES", "HIGHER_PAIR_VALUES", "RangeOn", "RANGE_ON", "range_on_values", "Limit", "LIMITS",
           "LIMIT_SUFFIX", "YPR_NAMES", "limit_attributes"]

#: FILE_SCHEMA names p105 writes for each long form.
SCHEMA_AP214 = "AUTOMOTIVE_DESIGN { 1 0 10303 214 3 1 1 }"
SCHEMA_AP242 = "AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF { 1 0 10303 442 1 1 4 }"

#: Profiles a file is written in: its layout ("1996" or "ap242"), whether su_parameters are
#: allowed, its FILE_SCHEMA, whether conversion_based_unit dimensions are written explicitly,
#: the axis of a prismatic pair's frame it slides along (1996: z; AP242: x), and a label.
PROFILES = {
    "ap214": {"layout": "1996", "su": False, "schema": SCHEMA_AP214, "cbu_dimensions_explicit": False,
              "slide_axis": 2, "label": "Part 105:1996 layout, AP214 (AUTOMOTIVE_DESIGN)"},
    "p105": {"layout": "1996", "su": True, "schema": SCHEMA_AP214, "cbu_dimensions_explicit": False,
             "slide_axis": 2, "label": "Part 105:1996 layout with su_parameters (p105 profile)"},
    "ap242": {"layout": "ap242", "su": True, "schema": SCHEMA_AP242, "cbu_dimensions_explicit": True,
              "slide_axis": 0, "label": "AP242 layout (ISO 10303-442)"},
}

#: Per layout: application context, application protocol definition schema name and year.
#: The schema names are the ones the long forms' global rules require (AP214:
#: application_protocol_definition_required; AP242:
#: ap242_application_protocol_definition_required).
APPLICATION = {
    "1996": ("automotive_design", "AUTOMOTIVE_DESIGN_LF", 2010),
    "ap242": ("managed model based 3d engineering", "ap242_managed_model_based_3d_engineering_mim_lf", 2014),
}


def layout_of(profile: str) -> str:
    """The layout ("1996" or "ap242") a profile name's files use."""
    return "ap242" if profile == "ap242" else "1996"


# --------------------------------------------------------------------------- profile selection

def choose_profile(header_profile: str, has_su_parameters: bool) -> str:
    """The profile a file is read with, from the profile its FILE_SCHEMA names: a 1996-layout
    AP214 file that holds su_parameters is read as ``p105`` (AP214's long form lacks the
    entity, ISO 10303-105:1996 has it). ``ModelFile`` applies this once per file."""
    if header_profile == "ap214" and has_su_parameters:
        return "p105"
    return header_profile


# --------------------------------------------------------------------------- the kinematic entities

#: Entity names of Part 105 in both layouts (1996 / AP214 and AP242): the instances the
#: validator's kinematic closure starts from and the KIN-* checks look at. 139 names: the
#: union of the two long forms' Part 105 entities, including the 1996 layout's
#: ``configuration_definition`` (AP214's long form tags it "10303-105:
#: kinematic_analysis_control_and_result_schema"; the earlier list derived from the subset
#: files had lost it).
KINEMATIC_ENTITIES = frozenset("""
actuated_kinematic_pair circular_path configuration_definition configuration_interpolation
constrained_kinematic_motion_representation context_dependent_kinematic_link_representation
curve_based_path curve_based_path_with_orientation curve_based_path_with_orientation_and_parameters
cylindrical_pair cylindrical_pair_range cylindrical_pair_value cylindrical_pair_with_range
founded_kinematic_path free_kinematic_motion_representation fully_constrained_pair gear_pair
gear_pair_range gear_pair_value gear_pair_with_range high_order_kinematic_pair homokinetic_pair
initial_state interpolated_configuration_representation interpolated_configuration_segment
interpolated_configuration_sequence item_link_motion_relationship kinematic_analysis_consistency
kinematic_analysis_result kinematic_control kinematic_frame_background_representation
kinematic_frame_background_representation_association kinematic_frame_based_transformation
kinematic_ground_representation kinematic_joint kinematic_link kinematic_link_representation
kinematic_link_representation_association kinematic_link_representation_relation kinematic_loop
kinematic_pair kinematic_path kinematic_path_defined_by_curves kinematic_path_defined_by_nodes
kinematic_path_segment kinematic_property_definition kinematic_property_definition_representation
kinematic_property_mechanism_representation kinematic_property_representation_relation
kinematic_property_topology_representation kinematic_structure kinematic_topology_directed_structure
kinematic_topology_network_structure kinematic_topology_structure kinematic_topology_substructure
kinematic_topology_tree_structure linear_flexible_and_pinion_pair
linear_flexible_and_planar_curve_pair linear_flexible_link_representation linear_path
link_motion_relationship link_motion_representation_along_path link_motion_transformation
low_order_kinematic_pair low_order_kinematic_pair_value
low_order_kinematic_pair_with_motion_coupling
low_order_kinematic_pair_with_range mechanism mechanism_base_placement mechanism_representation
mechanism_state_representation motion_link_relationship oriented_joint pair_actuator
pair_representation_relationship pair_value path_node planar_curve_pair planar_curve_pair_range
planar_pair planar_pair_range planar_pair_value planar_pair_with_range point_on_planar_curve_pair
point_on_planar_curve_pair_range point_on_planar_curve_pair_value
point_on_planar_curve_pair_with_range point_on_surface_pair point_on_surface_pair_range
point_on_surface_pair_value point_on_surface_pair_with_range point_to_point_path prescribed_path
prismatic_pair prismatic_pair_range prismatic_pair_value prismatic_pair_with_range
product_definition_kinematics product_definition_relationship_kinematics rack_and_pinion_pair
rack_and_pinion_pair_range rack_and_pinion_pair_value rack_and_pinion_pair_with_range
resulting_path revolute_pair revolute_pair_range revolute_pair_value revolute_pair_with_range
rigid_link_representation rolling_curve_pair rolling_curve_pair_value rolling_surface_pair
rolling_surface_pair_value rotation_about_direction screw_pair screw_pair_range screw_pair_value
screw_pair_with_range simple_pair_range sliding_curve_pair sliding_curve_pair_value
sliding_surface_pair sliding_surface_pair_value spherical_pair spherical_pair_range
spherical_pair_value spherical_pair_with_pin spherical_pair_with_pin_and_range
spherical_pair_with_range su_parameters surface_pair surface_pair_range surface_pair_with_range
unconstrained_pair unconstrained_pair_value universal_pair universal_pair_range
universal_pair_value universal_pair_with_range
""".split())


# --------------------------------------------------------------------------- pairs

#: Higher pair entity names (both layouts) -> pair kind. The low pairs' entity names are the
#: keys of :data:`p105cli.kinematics.pairs.PAIRS` (with their ``*_with_range`` variants).
HIGHER_PAIR_ENTITIES = {
    "point_on_surface_pair": "point_on_surface",
    "point_on_surface_pair_with_range": "point_on_surface",
    "sliding_surface_pair": "sliding_surface",
    "rolling_surface_pair": "rolling_surface",
    "point_on_planar_curve_pair": "point_on_planar_curve",
    "point_on_planar_curve_pair_with_range": "point_on_planar_curve",
    "sliding_curve_pair": "sliding_curve",
    "rolling_curve_pair": "rolling_curve",
}
HIGHER_KINDS = frozenset(HIGHER_PAIR_ENTITIES.values())


def pair_kind_of_entity(entity: str) -> Optional[str]:
    """The pair kind of a pair entity name (``revolute_pair_with_range`` -> ``revolute``), or None."""
    from ..kinematics.pairs import PAIRS  # numpy: only when a pair is read

    t = PAIRS.get(entity)
    if t is not None:
        return t.kind
    return HIGHER_PAIR_ENTITIES.get(entity)


#: AP242's generic low-order pair entities: their flags t_x..r_z say which freedoms are free
#: (:func:`p105cli.kinematics.pairs.named_low_order` names the pair a flag set is).
GENERIC_LOW_ORDER = frozenset({"low_order_kinematic_pair", "low_order_kinematic_pair_with_range"})


def pair_entity(kind: str, layout: str, with_range: bool = False) -> str:
    """The entity a pair of ``kind`` is written as: ``<kind>_pair`` (1996 and AP242 without a
    range), AP242's ``<kind>_pair_with_range`` subtype when it has one (``with_range``), the
    generic ``low_order_kinematic_pair`` of AP242."""
    base = {"low_order": "low_order_kinematic_pair"}.get(kind, f"{kind}_pair")
    if kind == "spherical_with_pin":
        base = "spherical_pair_with_pin"
        return base + ("_and_range" if layout == "ap242" and with_range else "")
    if layout == "ap242" and with_range:
        return base + "_with_range"
    return base


def range_entity(kind: str) -> str:
    """The 1996 layout's separate range entity of a pair kind (``revolute_pair_range``)."""
    return f"{kind}_pair_range"


#: Higher pairs' geometry attributes, in the order of the pair's attributes:
#: kind -> ((attribute, params key, which pair frame it is given in), ...).
HIGHER_PAIR_GEOMETRY = {
    "point_on_planar_curve": (("pair_curve", "curve", 1),),
    "point_on_surface": (("pair_surface", "surface", 1),),
    "sliding_curve": (("curve_1", "curve_1", 1), ("curve_2", "curve_2", 2)),
    "rolling_curve": (("curve_1", "curve_1", 1), ("curve_2", "curve_2", 2)),
    "sliding_surface": (("surface_1", "surface_1", 1), ("surface_2", "surface_2", 2)),
    "rolling_surface": (("surface_1", "surface_1", 1), ("surface_2", "surface_2", 2)),
}
#: Higher pairs with an ``orientation`` flag after their geometry.
HIGHER_PAIR_ORIENTATION = frozenset({"point_on_planar_curve", "sliding_curve", "rolling_curve",
                                     "sliding_surface", "rolling_surface"})
#: Higher pairs' ``*_pair_value`` attributes, in the order of the model's values: kind ->
#: ((attribute, family, geometry key), ...); family ``"point"``: a point_on_curve /
#: point_on_surface on the pair's curve/surface ``key`` (1 or 2 model values), ``"ypr"``: an
#: orientation (yaw, pitch, roll), ``"A"``: a plane angle.
HIGHER_PAIR_VALUES = {
    "point_on_planar_curve": (("actual_point_on_curve", "point", "curve"), ("input_orientation", "ypr", None)),
    "point_on_surface": (("actual_point_on_surface", "point", "surface"), ("input_orientation", "ypr", None)),
    "sliding_curve": (("actual_point_on_curve_1", "point", "curve_1"), ("actual_point_on_curve_2", "point", "curve_2")),
    "rolling_curve": (("actual_point_on_curve_1", "point", "curve_1"),),
    "sliding_surface": (("actual_point_on_surface_1", "point", "surface_1"),
                        ("actual_point_on_surface_2", "point", "surface_2"), ("actual_rotation", "A", None)),
    "rolling_surface": (("actual_point_on_surface", "point", "surface_1"), ("actual_rotation", "A", None)),
}
#: geometry attribute -> (params key, which pair frame), over every higher pair
GEOMETRY_ATTRIBUTES = {a: (key, which) for spec in HIGHER_PAIR_GEOMETRY.values() for a, key, which in spec}


class RangeOn(NamedTuple):
    """A ``range_on_*`` attribute (1996 ``*_pair_range``, AP242 ``*_with_range``): the geometry
    key of the curve/surface it trims, the model values it bounds, and the attributes of the
    ``*_pair_value`` entities that hold the point it bounds."""

    attribute: str
    geometry: str
    values: tuple
    value_attributes: tuple


RANGE_ON = {r.attribute: r for r in (
    RangeOn("range_on_pair_curve", "curve", ("point_parameter",), ("actual_point_on_curve",)),
    RangeOn("range_on_pair_surface", "surface", ("point_parameter_u", "point_parameter_v"),
            ("actual_point_on_surface",)),
    RangeOn("range_on_curve_1", "curve_1", ("point_parameter_1",), ("actual_point_on_curve_1",)),
    RangeOn("range_on_curve_2", "curve_2", ("point_parameter_2",), ("actual_point_on_curve_2",)),
    # a rolling surface pair's value holds its point as actual_point_on_surface
    RangeOn("range_on_surface_1", "surface_1", ("point_parameter_u_1", "point_parameter_v_1"),
            ("actual_point_on_surface_1", "actual_point_on_surface")),
    RangeOn("range_on_surface_2", "surface_2", ("point_parameter_u_2", "point_parameter_v_2"),
            ("actual_point_on_surface_2",)),
)}


def range_on_values(attribute: str, kind: str) -> tuple:
    """The model values a ``range_on_*`` attribute bounds for a pair of ``kind`` (a rolling
    surface pair has one point: its ``range_on_surface_1`` bounds point_parameter_u, _v)."""
    if kind == "rolling_surface" and attribute == "range_on_surface_1":
        return ("point_parameter_u", "point_parameter_v")
    return RANGE_ON[attribute].values


class Limit(NamedTuple):
    """``lower_limit_<suffix>`` / ``upper_limit_<suffix>``: the ``*_pair_value`` attribute they
    bound, its unit (``"A"`` plane angle, ``"L"`` length) and, for the yaw, pitch and roll of
    an ``input_orientation``, the index in it (else None)."""

    value_attribute: str
    unit: str
    ypr_index: Optional[int]


YPR_NAMES = ("yaw", "pitch", "roll")

#: How close (relative to pi/2) a ypr pitch is to +-pi/2 to be at the rectangular pitch angle
#: of 5.3.7, where the roll must be 0, and how far (relative to pi or pi/2) a ypr angle may lie
#: outside its interval: the one tolerance of the validator (KIN-YPR) and of the writer
#: (pair_values.ypr_values), so that every triple p105 writes is one it accepts.
YPR_REL_TOL = 1e-6

#: Every limit suffix of both layouts (the only ones the schemas have).
LIMITS = {
    "actual_rotation": Limit("actual_rotation", "A", None),
    "actual_translation": Limit("actual_translation", "L", None),
    "actual_rotation_1": Limit("actual_rotation_1", "A", None),
    "first_rotation": Limit("first_rotation_angle", "A", None),
    "second_rotation": Limit("second_rotation_angle", "A", None),
    "rack_displacement": Limit("actual_displacement", "L", None),
    "actual_translation_x": Limit("actual_translation_x", "L", None),
    "actual_translation_y": Limit("actual_translation_y", "L", None),
    "actual_translation_z": Limit("actual_translation_z", "L", None),
    "actual_rotation_x": Limit("actual_rotation_x", "A", None),
    "actual_rotation_y": Limit("actual_rotation_y", "A", None),
    "actual_rotation_z": Limit("actual_rotation_z", "A", None),
    "yaw": Limit("input_orientation", "A", 0),
    "pitch": Limit("input_orientation", "A", 1),
    "roll": Limit("input_orientation", "A", 2),
}


def _value_of_limit(suffix: str, lim: Limit) -> str:
    return YPR_NAMES[lim.ypr_index] if lim.ypr_index is not None else lim.value_attribute


#: model value name (a PairType's value_names) -> the suffix of the limits bounding it
LIMIT_SUFFIX = {_value_of_limit(s, lim): s for s, lim in LIMITS.items()}


def limit_attributes(value_name: str) -> Optional[tuple]:
    """``(lower_limit_..., upper_limit_...)`` bounding a model value, or None if none does."""
    s = LIMIT_SUFFIX.get(value_name)
    return None if s is None else (f"lower_limit_{s}", f"upper_limit_{s}")


# =========================================================================== writing tables
# What the writers (part105.write_mechanism, part105.emit, part105.convert) say in a file and
# how they recognise the source's instances. Where they say what a reading table says, they
# are derived from it (HIGHER_GEOMETRY, HIGHER_VALUES); the rest is what only a writer needs:
# which pair kinds are written, and with which range entity in each layout (pair_entity and
# range_entity above name those entities).

#: Low pair kinds p105 writes, in the order of ``SUPPORTED_KINDS``; the unit of each of their
#: values comes from ``PairType.value_units`` (the one angle/length rule).
WRITTEN_LOW_KINDS = ("revolute", "prismatic", "screw", "cylindrical", "spherical", "universal", "homokinetic",
                     "planar", "unconstrained", "fully_constrained", "gear", "rack_and_pinion", "low_order")

#: Higher pairs, as the writers use them: their geometry (params key, which pair frame it is
#: given in), in the order of the pair's attributes, and whether an ``orientation`` flag
#: follows (from HIGHER_PAIR_GEOMETRY and HIGHER_PAIR_ORIENTATION above).
HIGHER_GEOMETRY = {kind: (tuple((key, which) for _attr, key, which in spec), kind in HIGHER_PAIR_ORIENTATION)
                   for kind, spec in HIGHER_PAIR_GEOMETRY.items()}

#: Higher pair values, as the writers use them: ("point", geometry key) for a point on that
#: curve/surface (1 or 2 model values), "ypr" for an orientation (3 values), "A" for a plane
#: angle (from HIGHER_PAIR_VALUES above).
HIGHER_VALUES = {kind: tuple(("point", key) if family == "point" else family for _attr, family, key in spec)
                 for kind, spec in HIGHER_PAIR_VALUES.items()}

#: Higher pairs whose limits are written: a trimmed curve / rectangular trimmed surface of the
#: pair's geometry for the point parameter(s), and yaw, pitch, roll limits.
WRITTEN_HIGHER_RANGES = ("point_on_planar_curve", "point_on_surface")

#: Model-only parameters of higher pairs that the file cannot carry (with their defaults).
HIGHER_PARAMS_NOT_IN_FILE = {"reference_parameter_1": 0.0, "reference_parameter_2": 0.0,
                             "point_on_surface_2": None}

#: ``FREEDOM_FLAGS`` (read on first use, :func:`__getattr__`): AP242's derived freedom flags (t_x,
#: t_y, t_z, r_x, r_y, r_z) of the named low-order pairs p105 writes, which are also the freedoms
#: an actuated pair drives, from ``kinematics.pairs.LOW_ORDER_NAMED`` (the one table). Screw,
#: gear and rack-and-pinion pairs are low_order_kinematic_pair_with_motion_coupling subtypes
#: (no flags: COUPLED_FREEDOMS).


def __getattr__(name):
    # the one flags table lives with the pair motions (numpy): imported when first asked for
    if name == "FREEDOM_FLAGS":
        from ..kinematics.pairs import LOW_ORDER_NAMED

        value = {k: flags for k, (flags, _c) in LOW_ORDER_NAMED.items() if k in WRITTEN_LOW_KINDS}
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


#: The freedom an actuated coupled pair drives (it has no flags of its own).
COUPLED_FREEDOMS = {"screw": (0, 0, 0, 0, 0, 1), "gear": (0, 0, 0, 0, 0, 1),
                    "rack_and_pinion": (1, 0, 0, 0, 0, 0)}

#: Pair kinds with a range entity in each layout (1996 ``*_pair_range``, AP242 ``*_with_range``).
RANGE_KINDS_1996 = frozenset({"revolute", "prismatic", "screw", "cylindrical", "spherical", "universal",
                              "homokinetic", "planar", "gear", "rack_and_pinion"})
RANGE_KINDS_AP242 = frozenset({"low_order", "revolute", "prismatic", "screw", "cylindrical", "spherical", "universal",
                               "planar", "gear", "rack_and_pinion", "point_on_planar_curve", "point_on_surface"})

#: The mechanism's own instances, both layouts (a converted file holds one mechanism).
MECHANISM_ENTITIES = frozenset((
    "kinematic_structure", "kinematic_topology_structure", "kinematic_property_definition",
    "kinematic_property_representation_relation", "kinematic_ground_representation", "mechanism",
    "mechanism_base_placement", "mechanism_representation", "product_definition_kinematics",
    "kinematic_property_mechanism_representation", "product_definition_relationship_kinematics",
    "context_dependent_kinematic_link_representation",
))
#: AP242's loop structure (``p105 graph`` derives it).
LOOP_ENTITIES = frozenset((
    "kinematic_loop", "oriented_joint", "kinematic_topology_network_structure", "kinematic_topology_tree_structure",
    "kinematic_topology_directed_structure", "kinematic_topology_substructure",
))
#: Items of the kinematics list that are plain geometry to a converter: kept unless orphaned.
GEOMETRY_IN_KINEMATICS = frozenset(("su_parameters", "rotation_about_direction"))
#: The link representation entities (1996, AP242, flexible).
LINK_REPRESENTATION_ENTITIES = frozenset(("kinematic_link_representation", "rigid_link_representation",
                                          "linear_flexible_link_representation"))


# =========================================================================== end of writing tables
