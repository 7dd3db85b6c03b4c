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
