"""schema/units.py: a context's length and plane-angle units as SI factors."""

from __future__ import annotations

import math

from p105cli.schema.population import Population
from p105cli.schema.units import ANGLE, LENGTH, UnitReader, context_units
from p105cli.step import read_step

HEAD = "AUTOMOTIVE_DESIGN { 1 0 10303 214 3 1 1 }"

UNITS = {
    1: "(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.))",
    2: "(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.))",
    3: "PLANE_ANGLE_MEASURE_WITH_UNIT(PLANE_ANGLE_MEASURE(0.0174532925199433),#2)",
    4: "(CONVERSION_BASED_UNIT('DEGREE',#3)NAMED_UNIT(*)PLANE_ANGLE_UNIT())",
    5: "LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#1)",
    6: "(CONVERSION_BASED_UNIT('INCH',#5)LENGTH_UNIT()NAMED_UNIT(*))",
    7: "(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT($,.RADIAN.))",
    8: "(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT(.KILO.,.RADIAN.))",
    # a conversion-based unit converted through itself
    9: "PLANE_ANGLE_MEASURE_WITH_UNIT(PLANE_ANGLE_MEASURE(2.),#10)",
    10: "(CONVERSION_BASED_UNIT('LOOP',#9)NAMED_UNIT(*)PLANE_ANGLE_UNIT())",
}


def ctx(i, units):
    return (i, f"(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNIT_ASSIGNED_CONTEXT(({units}))"
               f"REPRESENTATION_CONTEXT('c{i}','3D'))")


def pop_of(table: dict) -> Population:
    body = "\n".join(f"#{i}={t};" for i, t in sorted(table.items()))
    text = ("ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n"
            "FILE_NAME('t.stp','2026-01-01T00:00:00',(''),(''),'','','');\n"
            f"FILE_SCHEMA(('{HEAD}'));\nENDSEC;\nDATA;\n{body}\nENDSEC;\nEND-ISO-10303-21;\n")
    return Population(read_step(text, "<test>"))


def test_si_prefix_and_conversion_chains():
    pop = pop_of({**UNITS, **dict([ctx(20, "#1,#2"), ctx(21, "#6,#4"), ctx(22, "#8")])})
    cu = context_units(pop, 20)
    assert cu.assigned and cu.length == (0.001, "millimetre", 1) and cu.angle == (1.0, "radian", 2)
    cu = context_units(pop, 21)
    assert math.isclose(cu.factor(LENGTH), 0.0254, rel_tol=1e-15) and cu.length[1] == "inch"
    assert math.isclose(cu.factor(ANGLE), math.pi / 180.0, rel_tol=1e-14) and cu.angle[1] == "degree"
    assert context_units(pop, 22).factor(ANGLE) == 1000.0 and context_units(pop, 22).factor(LENGTH) is None


def test_problems_are_kept_not_raised():
    pop = pop_of({**UNITS, **dict([ctx(20, "#1,#6"), ctx(21, "#7"), ctx(22, "#10")])})
    cu = context_units(pop, 20)
    assert cu.length is None and cu.count[LENGTH] == 2
    assert [(s, e) for s, e, _m in cu.problems] == [("error", 20)]
    cu = context_units(pop, 21)
    assert cu.length is None and "not .METRE." in cu.problems[0][2]
    cu = context_units(pop, 22)
    assert cu.angle is None and "loops back" in cu.problems[0][2]


def test_missing_context_and_cache():
    pop = pop_of({**UNITS, **dict([ctx(20, "#1,#2")])})
    r = UnitReader(pop)
    assert r.context_units(20) is r.context_units(20)
    none = r.context_units(None)
    assert not none.assigned and none.factor(LENGTH) is None
    assert not r.context_units(999).assigned
