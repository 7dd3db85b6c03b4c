"""Part 42 instances <-> geometry objects (p105cli.part105.geometry).

Round trips object -> p105/1 records -> Population -> object for every supported type (compared by
evaluating both at sample parameters), the records against the Part 21 argument orders of the AP242
long form, unit conversion, Part 21 text written by hand, and the cam curve of the corpus file.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from p105cli.kinematics import geometry as G
from p105cli.part105.geometry import curve_from_instance, curve_records, surface_from_instance, \
    surface_records
from p105cli.schema.population import Population
from p105cli.step import read_step
from p105cli.step.errors import ModelError

RNG = np.random.default_rng(42)
DATA = Path(__file__).resolve().parents[1] / "data" / "corpus"


def _T():
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("zyx", [0.3, -0.7, 1.1]).as_matrix()
    T[:3, 3] = [10.0, -20.0, 5.0]
    return T


T0 = _T()

CURVES = {
    "line": (G.Line([1.0, 2.0, 3.0], [0.5, -1.0, 2.0]), (-2.0, 2.0)),
    "circle": (G.Circle(T0, 40.0), (-4.0, 4.0)),
    "ellipse": (G.Ellipse(T0, 25.0, 8.0), (-4.0, 4.0)),
    "polyline": (G.Polyline(RNG.normal(size=(5, 3)) * 10), (0.0, 4.0)),
    "bspline": (G.BSplineCurve(3, RNG.normal(size=(7, 3)), [4, 1, 2, 4], [0.0, 0.7, 1.5, 2.5]), (0.0, 2.5)),
    "rational_bspline": (G.BSplineCurve(2, RNG.normal(size=(5, 3)), [3, 1, 1, 3], [0.0, 1.0, 2.0, 3.0],
                                        RNG.uniform(0.5, 2.0, 5)), (0.0, 3.0)),
    "trimmed_circle": (G.TrimmedCurve(G.Circle(T0, 12.0), 5.5, 1.0, False), (0.0, 4.0)),
    "trimmed_bspline": (G.TrimmedCurve(G.BSplineCurve(3, RNG.normal(size=(7, 3)), [4, 1, 2, 4],
                                                      [0.0, 0.7, 1.5, 2.5]), 0.2, 2.0, True), (0.0, 1.8)),
}

SURFACES = {
    "plane": G.Plane(T0),
    "cylinder": G.CylindricalSurface(T0, 13.0),
    "cone": G.ConicalSurface(T0, 9.0, 0.4),
    "sphere": G.SphericalSurface(T0, 21.0),
    "torus": G.ToroidalSurface(T0, 30.0, 7.0),
    "bspline": G.BSplineSurface(3, 2, RNG.normal(size=(5, 4, 3)), [4, 1, 4], [3, 1, 3], [0.0, 0.4, 1.0],
                                [-1.0, 0.2, 2.0]),
    "rational_bspline": G.BSplineSurface(3, 2, RNG.normal(size=(5, 4, 3)), [4, 1, 4], [3, 1, 3],
                                         [0.0, 0.4, 1.0], [-1.0, 0.2, 2.0], RNG.uniform(0.5, 2.0, (5, 4))),
}


def _population(records):
    return Population(records, "ap242")


def _ids(start=100):
    c = itertools.count(start)
    return lambda: next(c)


def _argument_orders():
    """Explicit attribute names per entity of the AP242 long form (supertypes first)."""
    import re
    path = Path("/work/shared/schema/AP242_N10962_mim_lf.exp")
    if not path.is_file():
        return None
    text = path.read_text()
    ents = {}
    for m in re.finditer(r"^\s*ENTITY\s+(\w+)(.*?)END_ENTITY;", text, flags=re.S | re.M | re.I):
        body = m.group(2)
        sup = re.search(r"SUBTYPE OF \(([^)]*)\)", body)
        attrs_part = re.split(r"\n\s*(?:WHERE|DERIVE|INVERSE|UNIQUE)\b", body)[0]
        attrs = re.findall(r"^\s*(\w+)\s*:", attrs_part, flags=re.M)
        ents[m.group(1).lower()] = ([s.strip().lower() for s in sup.group(1).split(",")] if sup else [], attrs)
    return ents


@pytest.mark.parametrize("name", sorted(CURVES))
def test_curve_round_trip(name):
    crv, (a, b) = CURVES[name]
    for lf, af in ((1.0, 1.0), (1e-3, math.pi / 180)):
        ref, records = curve_records(crv, _ids(), lf, af)
        assert records[-1]["id"] == ref
        assert len({r["id"] for r in records}) == len(records)
        back = curve_from_instance(_population(records), _population(records).instance(ref), lf, af)
        assert type(back) is type(crv)
        t = np.linspace(a, b, 17)
        for x, y in zip(crv.evaluate(t), back.evaluate(t)):
            np.testing.assert_allclose(y, x, atol=1e-12 * (1 + np.abs(x).max()))


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_surface_round_trip(name):
    srf = SURFACES[name]
    for lf, af in ((1.0, 1.0), (1e-3, math.pi / 180)):
        ref, records = surface_records(srf, _ids(), lf, af)
        back = surface_from_instance(_population(records), _population(records).instance(ref), lf, af)
        assert type(back) is type(srf)
        u, v = np.meshgrid(np.linspace(0.05, 0.95, 5), np.linspace(-0.9, 1.2, 4))
        for x, y in zip(srf.evaluate2(u, v), back.evaluate2(u, v)):
            np.testing.assert_allclose(y, x, atol=1e-12 * (1 + np.abs(x).max()))


def test_records_follow_part21_argument_order():
    orders = _argument_orders()
    if orders is None:
        pytest.skip("AP242 long form not available")

    def flat(e):
        sups, attrs = orders[e]
        out = []
        for s in sups:
            out += [a for a in flat(s) if a not in out]
        return out + attrs

    records = []
    for crv, _ in CURVES.values():
        records += curve_records(crv, _ids())[1]
    for srf in SURFACES.values():
        records += surface_records(srf, _ids())[1]
    seen = set()
    for r in records:
        if "complex" in r:
            for part in r["complex"]:
                assert len(part["args"]) == len(orders[part["type"]][1]), part["type"]
                seen.add(part["type"])
        else:
            assert len(r["args"]) == len(flat(r["type"])), (r["type"], flat(r["type"]))
            seen.add(r["type"])
    assert {"line", "vector", "circle", "ellipse", "polyline", "trimmed_curve", "b_spline_curve_with_knots",
            "rational_b_spline_curve", "plane", "conical_surface", "toroidal_surface",
            "b_spline_surface_with_knots", "rational_b_spline_surface", "axis2_placement_3d"} <= seen


def test_units_are_converted():
    # a circle of radius 40 mm trimmed from 90 to 180 degrees: SI object, radians
    text = """ISO-10303-21;
HEADER;
FILE_DESCRIPTION((''),'2;1');
FILE_NAME('t.stp','2026-01-01T00:00:00',(''),(''),'','','');
FILE_SCHEMA(('AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF { 1 0 10303 442 1 1 4 }'));
ENDSEC;
DATA;
#1=CARTESIAN_POINT('',(15.,0.,0.));
#2=DIRECTION('',(0.,0.,1.));
#3=DIRECTION('',(1.,0.,0.));
#4=AXIS2_PLACEMENT_3D('',#1,#2,#3);
#5=CIRCLE('',#4,40.);
#6=TRIMMED_CURVE('',#5,(PARAMETER_VALUE(90.)),(PARAMETER_VALUE(180.)),.T.,.PARAMETER.);
#7=CARTESIAN_POINT('',(15.,40.,0.));
#8=CARTESIAN_POINT('',(-25.,0.,0.));
#9=TRIMMED_CURVE('',#5,(#7),(#8),.T.,.CARTESIAN.);
#10=CONICAL_SURFACE('',#4,10.,30.);
#11=VECTOR('',#3,2.);
#12=LINE('',#1,#11);
ENDSEC;
END-ISO-10303-21;
"""
    pop = Population(read_step(text, "t.stp"))
    deg = math.pi / 180
    for i in (6, 9):
        tc = curve_from_instance(pop, pop.instance(i), 1e-3, deg)
        np.testing.assert_allclose(tc.bounds, (0.0, math.pi / 2), atol=1e-14)
        np.testing.assert_allclose(tc.evaluate(0.0)[0], [0.015, 0.040, 0.0], atol=1e-15)
        np.testing.assert_allclose(tc.evaluate(math.pi / 2)[0], [-0.025, 0.0, 0.0], atol=1e-15)
    cone = surface_from_instance(pop, pop.instance(10), 1e-3, deg)
    np.testing.assert_allclose(cone.semi_angle, math.pi / 6, atol=1e-15)
    np.testing.assert_allclose(cone.radius, 0.01, atol=1e-15)
    line = curve_from_instance(pop, pop.instance(12), 1e-3)
    np.testing.assert_allclose(line.evaluate(1.0)[0], [0.017, 0.0, 0.0], atol=1e-15)
    with pytest.raises(ModelError, match="#4"):
        curve_from_instance(pop, pop.instance(4))           # not a curve
    with pytest.raises(ModelError, match="#5"):
        surface_from_instance(pop, pop.instance(5))


def test_corpus_cam_curve():
    """The cam of the corpus cam_follower: a radius 40 mm circle 15 mm off the shaft (its file
    description says so), the pair curve of the point_on_planar_curve pair."""
    path = DATA / "cam_follower_ap242.stp"
    pop = Population(read_step(path.read_text(), str(path)))
    pair = pop.instances_of("point_on_planar_curve_pair")
    assert len(pair) == 1
    curve_ref = pair[0].get("pair_curve")["ref"]
    cam = curve_from_instance(pop, pop.instance(curve_ref), 1e-3)
    assert isinstance(cam, G.Circle)
    np.testing.assert_allclose(cam.radius, 0.040, atol=1e-15)
    u = np.linspace(0, 2 * math.pi, 9)
    P = cam.evaluate(u)[0]
    np.testing.assert_allclose(np.linalg.norm(P - [0.015, 0.0, 0.0], axis=-1), 0.040, atol=1e-15)
    np.testing.assert_allclose(P[:, 2], 0.0, atol=1e-15)                  # planar: in the pair frame's xy
    # and it round-trips through records in millimetres
    ref, records = curve_records(cam, _ids(), 1e-3)
    p2 = _population(records)
    back = curve_from_instance(p2, p2.instance(ref), 1e-3)
    np.testing.assert_allclose(back.evaluate(u)[0], P, atol=1e-15)
    assert [r for r in records if r["type"] == "circle"][0]["args"][2] == pytest.approx(40.0)
