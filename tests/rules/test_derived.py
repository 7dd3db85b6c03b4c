"""Explicit values where the schema derives (p105cli.rules.derived), edition by edition,
and entity types unknown to the declared schema, through ``validate_document``."""

from __future__ import annotations

from pathlib import Path

import pytest

from conftest import EXAMPLES, SHARED
from p105cli.rules.validate import validate_document
from p105cli.schema.profiles import (
    UnknownSchemaError, profile_for_header, schema_edition, stand_in_for,
)
from p105cli.step import read_step

AP214_ED1 = "AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }"
AP214_ED3 = "AUTOMOTIVE_DESIGN { 1 0 10303 214 3 1 1 }"
AP242_ED1 = "AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF { 1 0 10303 442 1 1 4 }"
EXTERNAL = SHARED / "external"

# A degree: its conversion factor is in radians, so its dimensions are all zero.
DEGREE = """#1=(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.));
#2=PLANE_ANGLE_MEASURE_WITH_UNIT(PLANE_ANGLE_MEASURE(0.0174532925),#1);
#3=DIMENSIONAL_EXPONENTS({dims});
#4=(CONVERSION_BASED_UNIT('DEGREE',#2)NAMED_UNIT({written})PLANE_ANGLE_UNIT());"""
DIMENSIONLESS = "0.,0.,0.,0.,0.,0.,0."
LENGTH = "1.,0.,0.,0.,0.,0.,0."


def part21(file_schema: str, body: str) -> str:
    return ("ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n"
            "FILE_NAME('t.stp','',(''),(''),'','','');\n"
            f"FILE_SCHEMA(('{file_schema}'));\nENDSEC;\nDATA;\n{body}\nENDSEC;\nEND-ISO-10303-21;\n")


def diagnostics(text: str, rule_prefix: str = "SCH-DERIVED") -> list:
    result = validate_document(read_step(text, "t.stp"), "t.stp")
    return [d for d in result.diagnostics if d.rule.startswith(rule_prefix)]


def degree(file_schema: str, dims: str, written: str = "#3") -> str:
    return part21(file_schema, DEGREE.format(dims=dims, written=written))


# ------------------------------------------------------------------ editions

def test_the_edition_comes_from_the_object_identifier():
    assert schema_edition(AP214_ED1) == (214, 1)
    assert schema_edition(AP214_ED3) == (214, 3)
    assert schema_edition(AP242_ED1) == (442, 1)
    assert schema_edition("AUTOMOTIVE_DESIGN") is None
    assert schema_edition("AUTOMOTIVE_DESIGN_CC2 { 1 2 10303 214 -1 1 5 4 }") is None
    assert profile_for_header({"file_schema": [AP214_ED1]}).edition == 1
    assert profile_for_header({"file_schema": [AP214_ED3]}).edition == 3
    assert profile_for_header({"file_schema": ["AUTOMOTIVE_DESIGN"]}).edition == 3
    # an explicit profile keeps the edition the file declares
    assert profile_for_header({"file_schema": [AP214_ED1]}, "p105").edition == 1


def test_edition_1_keeps_the_dimensions_of_a_conversion_based_unit_explicit():
    ed1 = profile_for_header({"file_schema": [AP214_ED1]})
    ed3 = profile_for_header({"file_schema": [AP214_ED3]})
    assert ed1.name == ed3.name == "ap214"

    def dimensions_derived(profile):
        (slot,) = [a for a in profile.schema.p21_attributes("conversion_based_unit")
                   if a.name == "dimensions"]
        return slot.derived
    assert dimensions_derived(ed3) and not dimensions_derived(ed1)


def test_ap203_is_refused_by_name():
    with pytest.raises(UnknownSchemaError, match="AP203 edition 1"):
        profile_for_header({"file_schema": ["CONFIG_CONTROL_DESIGN"]})


# ------------------------------------------------------------------ calibration

def test_edition_1_explicit_dimensions_equal_to_the_derivation_are_no_finding():
    assert diagnostics(degree(AP214_ED1, DIMENSIONLESS)) == []


def test_edition_3_explicit_dimensions_equal_to_the_derivation_are_a_warning():
    (d,) = diagnostics(degree(AP214_ED3, DIMENSIONLESS))
    assert (d.rule, d.severity, d.entity, d.line) == ("SCH-DERIVED-EXPLICIT", "warning", 4, 11)
    assert "AP214 edition 3 derives it" in d.message and "dimensionless" in d.message


@pytest.mark.parametrize("file_schema", [AP214_ED1, AP214_ED3])
def test_contradicting_dimensions_are_an_error_naming_both_values(file_schema):
    (d,) = diagnostics(degree(file_schema, LENGTH))
    assert (d.rule, d.severity, d.entity) == ("SCH-DERIVED-CONFLICT", "error", 4)
    assert "file says dimensions = #3 (length)" in d.message
    assert "derives dimensions = dimensionless" in d.message


def test_star_is_still_right_in_edition_3_and_wrong_in_edition_1():
    assert diagnostics(degree(AP214_ED3, DIMENSIONLESS, written="*")) == []
    (d,) = diagnostics(degree(AP214_ED1, DIMENSIONLESS, written="*"))
    assert (d.rule, d.severity) == ("SCH-DERIVED", "error")
    assert "explicit attribute" in d.message


PRISMATIC = """#1=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));
#2=(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.));
#3=(NAMED_UNIT(*)SI_UNIT($,.STERADIAN.)SOLID_ANGLE_UNIT());
#4=(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNIT_ASSIGNED_CONTEXT((#1,#2,#3))REPRESENTATION_CONTEXT('c','3D'));
#5=CARTESIAN_POINT('',(0.,0.,0.));
#6=AXIS2_PLACEMENT_3D('',#5,$,$);
#7=KINEMATIC_LINK('l1');
#8=KINEMATIC_LINK('l2');
#9=KINEMATIC_JOINT('j',#7,#8);
#10=PRISMATIC_PAIR('slider',{name},$,#6,#6,#9,{flags});"""


def test_prismatic_flags_contradicting_ap242_are_an_error_in_the_domains_words():
    text = part21(AP242_ED1, PRISMATIC.format(name="*", flags=".F.,.F.,.T.,.F.,.F.,.F."))
    d, same = diagnostics(text)
    assert (same.rule, same.severity, same.entity) == ("SCH-DERIVED-EXPLICIT", "warning", 10)
    assert same.message.startswith("t_y, r_x, r_y, r_z: written where AP242 derives them")
    assert (d.rule, d.severity, d.entity) == ("SCH-DERIVED-CONFLICT", "error", 10)
    assert d.message.startswith("t_x, t_z: file says t_x = FALSE, t_z = TRUE; "
                                "AP242 derives t_x = TRUE, t_z = FALSE")
    assert "the file's pair allows translation along z; a prismatic_pair allows translation along x" in d.message


def test_prismatic_flags_copied_from_ap242_are_one_warning():
    text = part21(AP242_ED1, PRISMATIC.format(name="'slider'", flags=".T.,.F.,.F.,.F.,.F.,.F."))
    (d,) = diagnostics(text)
    assert (d.rule, d.severity, d.entity) == ("SCH-DERIVED-EXPLICIT", "warning", 10)
    assert d.message.startswith("name, t_x, t_y, t_z, r_x, r_y, r_z: written where AP242 derives")
    clean = part21(AP242_ED1, PRISMATIC.format(name="*", flags="*,*,*,*,*,*"))
    assert diagnostics(clean) == []


# ------------------------------------------------------------------ unknown entities

def test_an_ap214_kinematics_file_re_headered_as_ap242_fails_the_gate():
    text = (EXAMPLES / "slider_crank_p105_1996_ap214.stp").read_text()
    start = text.index("FILE_SCHEMA")
    end = text.index(";", start)
    text = text[:start] + f"FILE_SCHEMA(('{AP242_ED1}'))" + text[end:]
    unknown = diagnostics(text, "SCH-UNKNOWN-ENTITY")
    assert unknown and all(d.severity == "error" for d in unknown)


def test_unknown_entities_of_a_schema_p105_has_no_long_form_of_are_warnings():
    header = {"file_schema": ["AUTOMOTIVE_DESIGN_CC2 { 1 2 10303 214 -1 1 5 4 }"]}
    assert stand_in_for(header, profile_for_header(header)) == "AUTOMOTIVE_DESIGN_CC2"
    assert stand_in_for({"file_schema": [AP214_ED1]}, profile_for_header({"file_schema": [AP214_ED1]})) \
        is None
    text = part21(header["file_schema"][0], "#1=MECHANICAL_CONTEXT('',#2,'mechanical');\n"
                                            "#2=APPLICATION_CONTEXT('');")
    (d,) = diagnostics(text, "SCH-UNKNOWN-ENTITY")
    assert d.severity == "warning" and "AUTOMOTIVE_DESIGN_CC2" in d.message


# ------------------------------------------------------------------ real files

REAL_CAD = EXTERNAL / "real_cad"
needs_real_cad = pytest.mark.skipif(not REAL_CAD.is_dir(), reason=f"{REAL_CAD} not present")


@needs_real_cad
@pytest.mark.parametrize("name", ["cax-if__dm1-id-214.stp", "cax-if__s1_pe_214__foot_asm.stp",
                                  "cube-units__cube-in.step"])
def test_edition_1_cad_exports_give_no_derived_error(name):
    path: Path = REAL_CAD / name
    result = validate_document(read_step(path.read_text(encoding="latin-1"), str(path)), str(path))
    assert not [d for d in result.diagnostics if d.rule.startswith("SCH-DERIVED")]


def test_the_new_rule_ids_have_descriptions_for_sarif():
    from p105cli.rules.diagnostics import rule_description
    assert "equal to its derivation" in rule_description("SCH-DERIVED-EXPLICIT")
    assert "contradicts the derivation" in rule_description("SCH-DERIVED-CONFLICT")
    assert "not UTF-8" in rule_description("P21-ENCODING")


def test_only_instances_that_write_a_derived_slot_are_evaluated():
    from p105cli.rules.conformance import check_population
    from p105cli.rules.derived import check_derived
    from p105cli.schema.population import Population
    text = part21(AP242_ED1, PRISMATIC.format(name="*", flags=".T.,*,*,*,*,*"))
    sf = read_step(text, "t.stp")
    pop = Population(sf)
    writes: set = set()
    list(check_population(sf.records(), pop.schema, lambda i: pop.types_of(i) if i in pop else None,
                          writes))
    assert writes == {10}
    (f,) = check_derived(pop, writes)
    assert (f.rule, f.entity, f.attribute) == ("SCH-DERIVED-EXPLICIT", 10, "t_x")
    assert check_derived(pop, set()) == []
