"""The model writer (p105cli.part105.write_mechanism) and `p105 export --schema`.

Truth is independent of the writer: the corpus's own files of each layout,
written by p105cli.corpus from its mechanism descriptions, read by the
reader; the validator (EXPRESS rules of the target long form); and closed
forms for the hand-built mechanisms (pair motions of p105cli.kinematics.pairs).
"""

from __future__ import annotations

import io
import math
import re
from functools import lru_cache

import numpy as np
import pytest

from conftest import ROOT
from p105cli.cli import main
from p105cli.kinematics.model import FRAME_PARAMS, Link, Mechanism, Pair, Units
from p105cli.kinematics.placements import compose, rot_x, rot_y, rot_z, transform
from p105cli.kinematics.reader import read_mechanisms
from p105cli.part105.write_mechanism import write_mechanism
from p105cli.rules.validate import validate_document
from p105cli.step import read_step, write_step

def trans(x, y, z):
    return transform(np.eye(3), [x, y, z])


CORPUS = ROOT / "tests" / "data" / "corpus"
MECHS = ["four_bar", "slider_crank", "ur5_arm", "gear_train", "rack_and_pinion", "cam_follower",
         "spherical_linkage"]


@lru_cache(maxsize=None)
def source(name: str, profile: str):
    path = CORPUS / f"{name}_{profile}.stp"
    return read_step(path.read_text(), str(path))


@lru_cache(maxsize=None)
def model(name: str, profile: str):
    (m,) = read_mechanisms(source(name, profile))
    return m


def text_of(doc) -> str:
    buf = io.StringIO()
    write_step(doc, buf)
    return buf.getvalue()


@lru_cache(maxsize=None)
def converted(name: str, src: str, target: str, occt: bool = False):
    doc, diags = write_mechanism(model(name, src), target, source=source(name, src), occt_compat=occt)
    text = text_of(doc)
    return read_step(text, f"{name}_{src}_to_{target}.stp"), text, tuple(diags)


def problems(doc, profile):
    result = validate_document(doc, doc.source, "p105" if profile == "p105" else None)
    return [f"{d.rule} #{d.entity}: {d.message[:160]}" for d in result.diagnostics
            if d.severity in ("error", "warning")]


def assert_same_model(a: Mechanism, b: Mechanism, *, base: bool = True, tol: float = 1e-12):
    assert a.name == b.name
    assert a.base == b.base
    assert a.link_names == b.link_names
    for la, lb in zip(a.links, b.links):
        assert sorted(la.frames) == sorted(lb.frames)
        for k in la.frames:
            np.testing.assert_allclose(la.frames[k], lb.frames[k], atol=tol, rtol=0)
    assert a.pair_names == b.pair_names
    for pa, pb in zip(a.pairs, b.pairs):
        assert (pa.kind, pa.link1, pa.link2, pa.actuated) == (pb.kind, pb.link1, pb.link2, pb.actuated), pa.name
        np.testing.assert_allclose(pa.P1, pb.P1, atol=tol, rtol=0, err_msg=pa.name)
        np.testing.assert_allclose(pa.P2, pb.P2, atol=tol, rtol=0, err_msg=pa.name)
        ka = {k: v for k, v in pa.params.items() if k not in FRAME_PARAMS}
        kb = {k: v for k, v in pb.params.items() if k not in FRAME_PARAMS}
        assert sorted(ka) == sorted(kb), pa.name
        for k in ka:
            if hasattr(ka[k], "evaluate"):  # a curve: the same points at the same parameters
                t = np.linspace(-1.0, 7.0, 9)
                np.testing.assert_allclose(ka[k].evaluate(t)[0], kb[k].evaluate(t)[0], atol=tol, rtol=0)
            elif isinstance(ka[k], (str, bool)) or ka[k] is None:
                assert ka[k] == kb[k]
            else:
                assert math.isclose(ka[k], kb[k], rel_tol=1e-12, abs_tol=tol), (pa.name, k)
        for la_, lb_ in ((pa.lower, pb.lower), (pa.upper, pb.upper)):
            assert [x is None for x in la_] == [x is None for x in lb_], pa.name
            for x, y in zip(la_, lb_):
                if x is not None:
                    assert math.isclose(x, y, rel_tol=1e-12, abs_tol=tol), pa.name
    assert sorted(a.initial) == sorted(b.initial)
    for k in a.initial:
        np.testing.assert_allclose(a.initial[k], b.initial[k], atol=tol, rtol=1e-12, err_msg=k)
    if base:
        np.testing.assert_allclose(a.T_world_base, b.T_world_base, atol=tol, rtol=0)
    assert a.units == b.units


def check_conversion(name, src, target):
    doc, text, diags = converted(name, src, target)
    assert problems(doc, target) == []
    (back,) = read_mechanisms(doc)
    assert_same_model(back, model(name, target))
    return doc, text, diags


# ---------------------------------------------------------------- conversions against the corpus

FAST = [("slider_crank", "ap214", "ap242"), ("ur5_arm", "p105", "ap214"), ("gear_train", "ap242", "ap214"),
        ("cam_follower", "ap242", "p105")]
SWEEP = [(m, s, t) for m in MECHS for s, t in (("ap214", "ap242"), ("ap242", "ap214"), ("ap242", "p105"))
         if (m, s, t) not in FAST]


@pytest.mark.parametrize("name,src,target", FAST, ids=[f"{m}-{s}-{t}" for m, s, t in FAST])
def test_conversion_validates_and_matches_the_corpus(name, src, target):
    check_conversion(name, src, target)


@pytest.mark.slow
@pytest.mark.parametrize("name,src,target", SWEEP, ids=[f"{m}-{s}-{t}" for m, s, t in SWEEP])
def test_conversion_sweep(name, src, target):
    check_conversion(name, src, target)


def test_round_trip_p105_ap242_p105_keeps_the_model():
    there, _, _ = converted("ur5_arm", "p105", "ap242")
    (m242,) = read_mechanisms(there)
    back, diags = write_mechanism(m242, "p105", source=there)
    back = read_step(text_of(back), "back.stp")
    assert problems(back, "p105") == []
    (m,) = read_mechanisms(back, "p105")
    assert_same_model(m, model("ur5_arm", "p105"))


def test_prismatic_frames_are_turned_between_layouts():
    # 1996 slides along z, AP242 along x: the frames differ by Z_TO_X, the link motion does not
    _, _, _ = converted("slider_crank", "ap214", "ap242")
    (m,) = read_mechanisms(converted("slider_crank", "ap214", "ap242")[0])
    a, b = m.pair("S"), model("slider_crank", "ap214").pair("S")
    assert a.params["layout"] == "ap242" and b.params["layout"] == "1996"
    np.testing.assert_allclose(a.P1[:3, 0], b.P1[:3, 2], atol=1e-15)
    for q in (0.05, 0.1, 0.13):
        np.testing.assert_allclose(a.transform([q]), b.transform([q]), atol=1e-15)


def test_ids_outside_the_kinematics_are_kept_and_kinematic_ids_reused():
    src = {r["id"]: r for r in source("slider_crank", "ap214").records()}
    out = {r["id"]: r for r in converted("slider_crank", "ap214", "ap242")[0].records()}
    # products, shapes and units keep their ids and contents
    for i, r in src.items():
        if r.get("type") in ("product", "product_definition", "geometric_curve_set", "polyline"):
            assert out[i] == r
    m = model("slider_crank", "ap214")
    for p in m.pairs:  # a pair keeps its instance name across layouts
        t = out[p.ids["pair"]]
        assert "complex" in t or t["type"].startswith(p.kind)
    assert max(out) > max(src)  # new instances above the source's ids


def test_nothing_is_dropped_silently():
    """Every source instance missing from the output is named by a diagnostic, or is one of
    the 1996 entities the AP242 layout says with another one, as many times."""
    src_doc = source("four_bar", "ap214")
    doc, _, diags = converted("four_bar", "ap214", "ap242")
    src = {r["id"]: r for r in src_doc.records()}
    out = {r["id"]: r for r in doc.records()}
    named = {int(x) for d in diags for x in re.findall(r"#(\d+)", d)}
    geometry = {"cartesian_point", "direction", "axis2_placement_3d", "cartesian_transformation_operator_3d"}
    missing = {}
    for i, r in src.items():
        if i not in out and i not in named and r.get("type") not in geometry:
            missing.setdefault(r.get("type"), []).append(i)

    def count(t):
        return sum(1 for r in out.values()
                   if r.get("type") == t or any(p["type"] == t for p in r.get("complex", ())))

    counterpart = {  # 1996 entity -> the AP242 entity that says the same, one for one
        "kinematic_link_representation_relation": "rigid_link_representation",
        "kinematic_property_definition": "product_definition_kinematics",
        "kinematic_property_representation_relation": "kinematic_property_mechanism_representation",
        "kinematic_ground_representation": "kinematic_property_mechanism_representation",
        "mechanism": "mechanism_representation", "kinematic_structure": "kinematic_topology_structure",
        "revolute_pair_range": "revolute_pair_with_range", "pair_actuator": "actuated_kinematic_pair",
        "configuration_definition": "mechanism_state_representation",
        "configuration_interpolation": "interpolated_configuration_segment",
        "interpolated_configuration_sequence": "interpolated_configuration_sequence",
        "revolute_pair_value": "revolute_pair_value",
    }
    for t, ids in missing.items():
        assert t in counterpart, f"{t} {ids} left out without a diagnostic"
        if t != "revolute_pair_range":
            assert count(counterpart[t]) >= len(ids), t
    # ranges: a limited one is a *_with_range pair; an unlimited one is the plain pair
    assert count("revolute_pair_with_range") == sum(
        1 for r in src.values() if r.get("type") == "revolute_pair_range"
        and r["args"][1]["type"] != "UNLIMITED_RANGE")
    # the base placement is named, with what carries it
    base = model("four_bar", "ap214").ids["base_placement"]
    assert any(d.startswith(f"#{base}: mechanism_base_placement") for d in diags)


def configurations(doc):
    """The configurations of a file's motion program, in file units: [(t, {pair: values})]."""
    recs = {r["id"]: r for r in doc.records()}
    pair_name = {}
    for i, r in recs.items():
        if "complex" in r:
            for p in r["complex"]:
                if p["type"] == "representation_item":
                    pair_name[i] = p["args"][0]
        elif r["type"].endswith("_pair") or r["type"].endswith("_pair_with_range"):
            pair_name[i] = r["args"][0]

    def values(refs):
        out = {}
        for v in refs:
            a = recs[v["ref"]]["args"]
            at = 0 if isinstance(a[0], dict) else 1
            out[pair_name[a[at]["ref"]]] = a[at + 1:]
        return out

    configs = []
    for r in recs.values():
        if r.get("type") == "configuration_definition":
            configs.append((r["args"][1]["value"], values(r["args"][0])))
        elif r.get("type") == "interpolated_configuration_segment":
            configs.append((r["args"][1], values(recs[r["args"][0]["ref"]]["args"][1])))
    return sorted(configs, key=lambda c: c[0])


@pytest.mark.parametrize("name,src,target", [("slider_crank", "ap214", "ap242"), ("gear_train", "ap242", "ap214")])
def test_configuration_sequences_are_those_of_the_corpus(name, src, target):
    got = configurations(converted(name, src, target)[0])
    want = configurations(source(name, target))
    assert len(got) == len(want) == 3
    assert got == want


def test_units_are_preserved():
    _, text, _ = converted("slider_crank", "ap214", "ap242")
    assert "SI_UNIT(.MILLI.,.METRE.)" in text and "CONVERSION_BASED_UNIT('DEGREE'" in text
    assert "PRISMATIC_PAIR_WITH_RANGE('S',*,'slide guide',#234,#238,#139,*,*,*,*,*,*,76.,142.)" in text
    assert re.search(r"REVOLUTE_PAIR_WITH_RANGE\('B',.*,-30\.,13\.\);", text)


# ---------------------------------------------------------------- self-contained files

@pytest.mark.parametrize("name", ["slider_crank", "cam_follower"])
@pytest.mark.parametrize("profile", ["ap214", "p105", "ap242"])
def test_self_contained_file_from_a_read_model(profile, name):
    m = model(name, "ap214" if profile != "ap242" else "ap242")
    doc, diags = write_mechanism(m, profile)
    doc = read_step(text_of(doc), "standalone.stp")
    assert problems(doc, profile) == []
    (back,) = read_mechanisms(doc, profile)
    assert_same_model(back, m, tol=1e-12)


def _hand_built(units: Units) -> Mechanism:
    """A chain with one pair of every low kind the writer knows, built in code (SI)."""
    I = np.eye(4)
    off = trans(0.1, 0.02, 0.0)
    kinds = [
        ("revolute", {}, (0.3,), (-1.0,), (1.0,)),
        ("prismatic", {"layout": "1996"}, (0.05,), (0.0,), (0.2,)),
        ("screw", {"pitch": 0.004}, (1.2,), (None,), (None,)),
        ("cylindrical", {}, (0.01, 0.4), (-0.1, None), (0.1, None)),
        ("spherical", {}, (0.1, -0.2, 0.3), (-1.0, -0.5, -1.0), (1.0, 0.5, 1.0)),
        ("universal", {"input_skew_angle": 0.1}, (0.2, -0.1), (None, None), (None, None)),
        ("planar", {}, (0.5, 0.02, -0.03), (None, -0.1, -0.1), (None, 0.1, 0.1)),
        ("gear", {"radius_first_link": 0.02, "radius_second_link": 0.03, "gear_ratio": 2 / 3}, (0.7,),
         (-7.0,), (7.0,)),
        ("rack_and_pinion", {"pinion_radius": 0.025}, (0.04,), (-0.1,), (0.1,)),
        ("homokinetic", {}, (0.2, 0.1), (None, None), (None, None)),
        ("unconstrained", {}, (0.01, 0.02, -0.03, 0.1, 0.2, 0.3), (), ()),
    ]
    links = [Link("L0", description="base")]
    pairs = []
    initial = {}
    for n, (kind, params, q, lo, hi) in enumerate(kinds, start=1):
        links.append(Link(f"L{n}", frames={"marker": trans(0.01 * n, 0, 0)} if n == 3 else {}))
        P1 = compose(off, rot_x(0.1 * n), rot_z(0.2))
        P2 = compose(trans(0, 0.01 * n, 0.0), rot_y(-0.05 * n))
        pairs.append(Pair(f"J{n}", kind, f"L{n - 1}", f"L{n}", P1, P2 if kind != "gear" else I, params=params,
                          lower=lo, upper=hi, actuated=kind in ("revolute", "prismatic", "screw", "gear"),
                          description=f"{kind} joint"))
        initial[f"J{n}"] = q
    return Mechanism("chain", links, pairs, "L0", T_world_base=compose(trans(0.5, -0.2, 0.1), rot_z(0.3)),
                     initial=initial, units=units, description="every low pair kind")


@pytest.mark.parametrize("profile", ["ap214", "ap242"])
@pytest.mark.parametrize("units", [Units(), Units(1e-3, math.pi / 180, "millimetre", "degree")],
                         ids=["SI", "mm-degree"])
def test_hand_built_mechanism_every_low_pair(profile, units):
    m = _hand_built(units)
    doc, diags = write_mechanism(m, profile)
    doc = read_step(text_of(doc), "chain.stp")
    assert problems(doc, profile) == []
    (back,) = read_mechanisms(doc)
    assert back.units == units
    # the link motions are the truth: the same in both layouts (prismatic frames turn in AP242)
    for pa in m.pairs:
        pb = back.pair(pa.name)
        q = np.asarray(m.initial[pa.name])
        np.testing.assert_allclose(pb.transform(q), pa.transform(q), atol=1e-12, err_msg=pa.name)
        assert pb.actuated == pa.actuated
        for x, y in zip((*pa.lower, *pa.upper), (*pb.lower, *pb.upper)):
            assert (x is None) == (y is None) and (x is None or math.isclose(x, y, rel_tol=1e-12)), pa.name
    np.testing.assert_allclose(back.T_world_base, m.T_world_base, atol=1e-12)
    np.testing.assert_allclose(back.link("L3").frames["marker"], m.link("L3").frames["marker"], atol=1e-12)


# ---------------------------------------------------------------- Open CASCADE compatibility (text form)

def test_occt_compat_writes_the_derived_values_explicitly():
    _, text, diags = converted("slider_crank", "ap214", "ap242", True)
    assert "REVOLUTE_PAIR('A','A','crank pin',#152,#156,#137,.F.,.F.,.F.,.F.,.F.,.T.)" in text
    assert re.search(r"PRISMATIC_PAIR_WITH_RANGE\('S','S',.*,\.T\.,\.F\.,\.F\.,\.F\.,\.F\.,\.F\.,76\.,142\.\)", text)
    assert "ACTUATED_KINEMATIC_PAIR" not in text
    assert any("actuation not written" in d for d in diags)
    assert not re.search(r"MECHANISM_STATE_REPRESENTATION\('initial state',\([^)]*\),\*", text)
    # the standard form keeps '*', and validates clean (checked above); the explicit flags do not
    doc = read_step(text, "occt.stp")
    assert any(p.startswith("SCH-") for p in problems(doc, "ap242"))


# ---------------------------------------------------------------- the CLI

def test_cli_export_schema(tmp_path, capsys):
    out = tmp_path / "four_bar.stp"
    rc = main(["export", "--schema", "ap242", str(CORPUS / "four_bar_ap214.stp"), "-o", str(out)])
    err = capsys.readouterr().err
    assert rc == 0
    text = out.read_text()
    assert "FILE_SCHEMA(('AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF" in text
    assert "p105: warning:" in err and "#201: mechanism_base_placement" in err
    rc = main(["validate", str(out)])
    assert rc == 0
    capsys.readouterr()
    rc = main(["export", "--schema", "ap214", "--to", "json", str(out)])
    captured = capsys.readouterr()
    assert rc == 0 and captured.out.startswith('{"format":"p105/1"')
    assert "AUTOMOTIVE_DESIGN" in captured.out


def test_cli_export_occt_compat_needs_ap242(capsys):
    rc = main(["export", "--occt-compat", str(CORPUS / "four_bar_ap214.stp")])
    assert rc == 2
    assert "--occt-compat" in capsys.readouterr().err


def test_cli_export_schema_without_mechanism_is_bad_input(tmp_path, capsys):
    text = (CORPUS / "four_bar_ap214.stp").read_text()
    data = text[:text.index("DATA;") + 5] + "\n#1=CARTESIAN_POINT('',(0.,0.,0.));\nENDSEC;\nEND-ISO-10303-21;\n"
    path = tmp_path / "empty.stp"
    path.write_text(data)
    rc = main(["export", "--schema", "ap242", str(path)])
    assert rc == 2
    assert "no mechanism" in capsys.readouterr().err


def test_ap242_loops_are_those_of_the_corpus():
    """The AP242 output carries the independent loops (from p105cli.kinematics.graph); the
    corpus's own AP242 file, written from the mechanism description, has the same joints in
    its loop."""
    def loops(doc):
        recs = {r["id"]: r for r in doc.records()}
        joint_name = {i: r["args"][0] for i, r in recs.items() if r.get("type") == "kinematic_joint"}
        out = []
        for r in recs.values():
            if r.get("type") == "kinematic_loop":
                out.append(sorted(joint_name[recs[e["ref"]]["args"][3]["ref"]] for e in r["args"][1]))
        return sorted(out)

    doc, text, diags = converted("four_bar", "ap214", "ap242")
    assert loops(doc) == loops(source("four_bar", "ap242")) == [["A", "B", "C", "D"]]
    assert loops(converted("gear_train", "ap242", "ap214")[0]) == []  # 1996 has no loops ...
    assert any("kinematic_loop" in d for d in converted("gear_train", "ap242", "ap214")[2])  # ... said so


def test_conversion_is_deterministic_and_reads_json_too(tmp_path, capsys):
    path = CORPUS / "rack_and_pinion_ap242.stp"
    assert main(["export", "--schema", "p105", str(path)]) == 0
    first = capsys.readouterr().out
    assert main(["parse", str(path), "-o", str(tmp_path / "m.json")]) == 0
    capsys.readouterr()
    assert main(["export", "--schema", "p105", str(tmp_path / "m.json")]) == 0
    second = capsys.readouterr().out
    assert first == second and "FILE_SCHEMA(('AUTOMOTIVE_DESIGN" in first


def _higher(units: Units) -> Mechanism:
    """One pair of every higher kind, built in code: curves and surfaces in their pair frames."""
    from p105cli.kinematics import geometry as G

    def at(x, y, z):
        return trans(x, y, z)

    circle = G.Circle(at(0.01, 0.0, 0.0), 0.04)
    line = G.Line([0.0, -0.02, 0.0], [0.5, 0.0, 0.0])
    plane = G.Plane(compose(at(0.0, 0.0, 0.01), rot_x(0.2)))
    sphere = G.SphericalSurface(at(0.0, 0.0, 0.0), 0.05)
    cylinder = G.CylindricalSurface(at(0.0, 0.01, 0.0), 0.03)
    kinds = [
        ("point_on_planar_curve", {"curve": circle, "orientation": True}, (0.7, 0.1, 0.0, 0.0),
         (0.2, -0.5, None, None), (2.0, 0.5, None, None)),
        ("point_on_surface", {"surface": plane}, (0.01, -0.02, 0.3, 0.0, 0.1),
         (-0.05, -0.04, None, -0.2, None), (0.05, 0.04, None, 0.2, None)),
        ("sliding_curve", {"curve_1": circle, "curve_2": line, "orientation": True}, (0.4, 0.05)),
        ("rolling_curve", {"curve_1": circle, "curve_2": G.Circle(np.eye(4), 0.02), "orientation": False}, (0.3,)),
        ("sliding_surface", {"surface_1": sphere, "surface_2": cylinder, "orientation": True},
         (0.2, 0.1, 0.5, 0.01, 0.3)),
        ("rolling_surface", {"surface_1": plane, "surface_2": sphere, "orientation": True}, (0.01, 0.02, 0.4)),
    ]
    links = [Link("L0")]
    pairs, initial = [], {}
    for n, (kind, params, q, *limits) in enumerate(kinds, start=1):
        links.append(Link(f"L{n}"))
        P1 = compose(at(0.1, 0.0, 0.0), rot_z(0.3 * n))  # not the link frame: geometry moves with it
        P2 = compose(at(0.0, 0.02, 0.0), rot_x(0.1 * n))
        lower, upper = limits or ((), ())
        pairs.append(Pair(f"H{n}", kind, f"L{n - 1}", f"L{n}", P1, P2, params=params, description=kind,
                          lower=lower, upper=upper))
        initial[f"H{n}"] = q
    return Mechanism("higher", links, pairs, "L0", initial=initial, units=units)


@pytest.mark.parametrize("profile", ["ap214", "ap242"])
def test_hand_built_higher_pairs(profile):
    units = Units(1e-3, 0.0174532925199433, "millimetre", "degree")
    m = _higher(units)
    doc, diags = write_mechanism(m, profile)
    doc = read_step(text_of(doc), "higher.stp")
    assert problems(doc, profile) == []
    (back,) = read_mechanisms(doc)
    for pa in m.pairs:
        pb = back.pair(pa.name)
        assert pb.kind == pa.kind
        np.testing.assert_allclose(back.initial[pa.name], m.initial[pa.name], atol=1e-12, rtol=1e-12)
        for x, y in zip((*pa.lower, *pa.upper), (*pb.lower, *pb.upper)):  # limits, with trimmed geometry
            assert (x is None) == (y is None) and (x is None or math.isclose(x, y, rel_tol=1e-12)), pa.name
        for key, g in pa.params.items():
            if hasattr(g, "evaluate"):  # the same geometry, in the same pair frame
                uv = (np.linspace(0.0, 1.0, 5),) if not hasattr(g, "normal") else (np.linspace(0, 1, 5),) * 2
                np.testing.assert_allclose(pb.params[key].evaluate(*uv)[0], g.evaluate(*uv)[0], atol=1e-12)
            else:
                assert pb.params[key] == g, (pa.name, key)


def test_fully_constrained_pair_and_the_1996_initial_state():
    """A fully constrained pair has no value entity, yet the 1996 initial_state's WR1 wants a
    value for every joint: the writer says so, and the validator finds it; AP242 has no such
    rule."""
    I = np.eye(4)
    m = Mechanism("fixed", [Link("a"), Link("b"), Link("c")],
                  [Pair("F", "fully_constrained", "a", "b", I, trans(0.0, 0.1, 0.0)),
                   Pair("R", "revolute", "b", "c", I, I)], "a", initial={"R": (0.5,)})
    doc, diags = write_mechanism(m, "ap214")
    assert any("'F'" in d and "WR1" in d for d in diags)
    assert [p.split()[0] for p in problems(read_step(text_of(doc), "f.stp"), "ap214")] == ["SCH-initial_state.wr1"]
    doc, diags = write_mechanism(m, "ap242")
    doc = read_step(text_of(doc), "f.stp")
    assert diags == [] and problems(doc, "ap242") == []
    (back,) = read_mechanisms(doc)
    np.testing.assert_allclose(back.pair("F").transform(np.zeros((0,))), m.pair("F").transform(np.zeros((0,))))


def test_an_open_point_parameter_range_is_reported():
    from p105cli.kinematics import geometry as G

    line = G.Line([0.0, 0.0, 0.0], [1.0, 0.0, 0.0])
    I = np.eye(4)
    m = Mechanism("open", [Link("a"), Link("b")],
                  [Pair("P", "point_on_planar_curve", "a", "b", I, I, params={"curve": line},
                        lower=(None, -0.1, None, None), upper=(None, 0.1, None, None))],
                  "a", initial={"P": (0.2, 0.0, 0.0, 0.0)})
    for profile in ("ap214", "ap242"):
        doc, diags = write_mechanism(m, profile)
        assert any("open point parameter range" in d for d in diags)
        doc = read_step(text_of(doc), "open.stp")
        assert problems(doc, profile) == []
        assert read_mechanisms(doc)[0].pair("P").lower == (None,) * 4


def test_sections_of_the_source():
    """Edition 3 frames: several DATA sections become one, ANCHOR/REFERENCE sections stay, a
    SIGNATURE (of the source's bytes) goes; each said."""
    from p105cli.step import DataSection
    from p105cli.step.jsonmodel import JsonDocument

    src = source("rack_and_pinion", "ap242")
    data = list(src.records())
    doc = JsonDocument(src.header, [DataSection(["a", []], 100), DataSection(["b", []], len(data) - 100)], data,
                       [{"keyword": "ANCHOR", "after_data": 0, "text": "<a> = #1;"},
                        {"keyword": "SIGNATURE", "after_data": 2, "text": "abc"}], "ed3.json")
    out, diags = write_mechanism(model("rack_and_pinion", "ap242"), "ap214", source=doc)
    assert [s["keyword"] for s in out.other_sections] == ["ANCHOR"]
    assert len(out.sections) == 1 and out.sections[0].count == len(out.data)
    assert any("SIGNATURE" in d for d in diags) and any("DATA section" in d for d in diags)
