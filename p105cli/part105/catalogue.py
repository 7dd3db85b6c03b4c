"""The standard's vocabulary as data: profiles and their layouts, application contexts.

One home for what every reader, writer and check of Part 105 files needs to agree on. No
numpy, no schema: plain tables.
"""

from __future__ import annotations

__all__ = ["SCHEMA_AP214", "SCHEMA_AP242", "PROFILES", "APPLICATION", "layout_of"]

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


# =========================================================================== writing tables
# What the writers (part105.write_mechanism, part105.emit, part105.convert) say in a file and
# how they recognise the source's instances. Moved here from kinematics/writer.py; the reading
# tables above may say the same in other words (the integrator merges the two).

#: Low pair kinds p105 writes, in the order of ``SUPPORTED_KINDS``; the unit of each of their
#: values comes from ``PairType.value_units`` (the one angle/length rule).
WRITTEN_LOW_KINDS = ("revolute", "prismatic", "screw", "cylindrical", "spherical", "universal", "homokinetic",
                     "planar", "unconstrained", "fully_constrained", "gear", "rack_and_pinion")

#: Higher pairs: their geometry (params key, which pair frame it is given in), in the order of
#: the pair's attributes; whether an ``orientation`` flag follows.
HIGHER_GEOMETRY = {
    "point_on_planar_curve": ((("curve", 1),), True),
    "point_on_surface": ((("surface", 1),), False),
    "sliding_curve": ((("curve_1", 1), ("curve_2", 2)), True),
    "rolling_curve": ((("curve_1", 1), ("curve_2", 2)), True),
    "sliding_surface": ((("surface_1", 1), ("surface_2", 2)), True),
    "rolling_surface": ((("surface_1", 1), ("surface_2", 2)), True),
}

#: Higher pair values: ("point", geometry key) for a point on that curve/surface (1 or 2
#: model values), "ypr" for an orientation (3 values), "A" for a plane angle.
HIGHER_VALUES = {
    "point_on_planar_curve": (("point", "curve"), "ypr"),
    "point_on_surface": (("point", "surface"), "ypr"),
    "sliding_curve": (("point", "curve_1"), ("point", "curve_2")),
    "rolling_curve": (("point", "curve_1"),),
    "sliding_surface": (("point", "surface_1"), ("point", "surface_2"), "A"),
    "rolling_surface": (("point", "surface_1"), "A"),
}

#: Higher pairs whose limits are written: a trimmed curve / rectangular trimmed surface of the
#: pair's geometry for the point parameter(s), and yaw, pitch, roll limits.
WRITTEN_HIGHER_RANGES = ("point_on_planar_curve", "point_on_surface")

#: Model-only parameters of higher pairs that the file cannot carry (with their defaults).
HIGHER_PARAMS_NOT_IN_FILE = {"reference_parameter_1": 0.0, "reference_parameter_2": 0.0,
                             "point_on_surface_2": None}

#: AP242: the derived freedom flags (t_x, t_y, t_z, r_x, r_y, r_z) of the low-order pairs,
#: which are also the freedoms an actuated pair drives. Screw, gear and rack-and-pinion
#: pairs are low_order_kinematic_pair_with_motion_coupling subtypes (no flags).
FREEDOM_FLAGS = {
    "revolute": (0, 0, 0, 0, 0, 1), "prismatic": (1, 0, 0, 0, 0, 0), "cylindrical": (0, 0, 1, 0, 0, 1),
    "spherical": (0, 0, 0, 1, 1, 1), "universal": (0, 0, 0, 1, 0, 1), "homokinetic": (0, 0, 0, 1, 0, 1),
    "planar": (1, 1, 0, 0, 0, 1), "unconstrained": (1, 1, 1, 1, 1, 1), "fully_constrained": (0,) * 6,
}
#: The freedom an actuated coupled pair drives (it has no flags of its own).
COUPLED_FREEDOMS = {"screw": (0, 0, 0, 0, 0, 1), "gear": (0, 0, 0, 0, 0, 1),
                    "rack_and_pinion": (1, 0, 0, 0, 0, 0)}

#: Pair kinds with a range entity in each layout (1996 ``*_pair_range``, AP242 ``*_with_range``).
RANGE_KINDS_1996 = frozenset({"revolute", "prismatic", "screw", "cylindrical", "spherical", "universal",
                              "homokinetic", "planar", "gear", "rack_and_pinion"})
RANGE_KINDS_AP242 = frozenset({"revolute", "prismatic", "screw", "cylindrical", "spherical", "universal",
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


def kinematic_entity_names() -> frozenset:
    """The entity names ``schema/data/kinematics_entities.txt`` lists (the converter's kinematic
    instances; the validator reads the same file)."""
    global _KINEMATIC_ENTITY_NAMES
    if _KINEMATIC_ENTITY_NAMES is None:
        from pathlib import Path

        text = (Path(__file__).resolve().parent.parent / "schema" / "data" / "kinematics_entities.txt").read_text()
        _KINEMATIC_ENTITY_NAMES = frozenset(line.strip().lower() for line in text.splitlines() if line.strip())
    return _KINEMATIC_ENTITY_NAMES


_KINEMATIC_ENTITY_NAMES = None
# =========================================================================== end of writing tables
