"""part105/read_mechanism.py: Part 21 / JSON -> the schema-neutral Mechanism model.

Independent truth: the authored corpus (tests/data/corpus) describes seven
mechanisms in three layouts; ``p105cli.corpus.mechanisms`` holds their
geometry (mm, radians), pair frames, ranges and position solvers, from
which the written pair values were measured. The reader must give the same
model from every layout, agree with that ground truth in SI, close every
loop at the initial state, read the same model whatever the file's units,
and name the instance at fault when it cannot read one.
"""

from __future__ import annotations

import copy
import functools
import math
from pathlib import Path

import numpy as np
import pytest

from p105cli.corpus.mechanisms import (MECHANISMS, Z_TO_X, configuration, pair_frames, resolved_limits,
                                       scalar_value)
from p105cli.kinematics.model import Mechanism
from p105cli.kinematics.spatial import inverse
from p105cli.part105.read_mechanism import read_mechanism, read_mechanisms
from p105cli.step import DataSection, JsonDocument, ModelError, read_step

CORPUS_DIR = Path(__file__).resolve().parents[1] / "data" / "corpus"
PROFILES = ("ap214", "p105", "ap242")
MM = 1e-3
FRAME_TOL = 1e-12  # metres / matrix entries
REL = 1e-12

ALL = tuple(MECHANISMS)  # the seven corpus mechanisms


@functools.lru_cache(maxsize=None)
def _records(mech: str, profile: str):
    path = CORPUS_DIR / f"{mech}_{profile}.stp"
    sf = read_step(path.read_text(encoding="utf-8"), str(path))
    return sf.header, tuple(sf.records())


def _doc(mech: str, profile: str, edit=None) -> JsonDocument:
    """The corpus file as a JsonDocument (a deep copy, optionally edited)."""
    header, recs = _records(mech, profile)
    data = copy.deepcopy(list(recs))
    if edit is not None:
        edit(data)
    return JsonDocument(copy.deepcopy(header), [DataSection(None, len(data))], data, source=f"{mech}_{profile}")


@functools.lru_cache(maxsize=None)
def _model(mech: str, profile: str) -> Mechanism:
    # the p105 files carry AP214's FILE_SCHEMA: the profile is given, as `--schema p105` does
    return read_mechanism(_doc(mech, profile), "p105" if profile == "p105" else None)


@functools.lru_cache(maxsize=None)
def _truth(mech: str):
    m = MECHANISMS[mech]()
    return m, resolved_limits(m)


def _close(a, b, tol=FRAME_TOL) -> bool:
    return bool(np.abs(np.asarray(a, float) - np.asarray(b, float)).max() <= tol)


def _rel_close(a, b, rel=REL) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return abs(a - b) <= rel * max(abs(a), abs(b), 1e-300)


def _numeric_params(p) -> dict:
    """The pair's numeric motion parameters (not the layout, frames' su_parameters, geometry)."""
    return {k: v for k, v in p.params.items()
            if k not in ("layout", "su_1", "su_2", "orientation") and (v is None or isinstance(v, float))}


def _check_contact(m, p, tp, value, limits):
    """The cam contact: the pair curve (a circle in the cam's first pair frame), the initial
    point parameter and ypr orientation, against the corpus's circle and measured value."""
    from p105cli.corpus.geometry import ypr_angles
    centre, radius = np.asarray(tp.params["circle_center"], float) * MM, tp.params["circle_radius"] * MM
    u = np.linspace(-1.0, 7.0, 9)
    want = centre + radius * np.stack([np.cos(u), np.sin(u), 0 * u], axis=-1)
    assert _close(p.params["curve"].evaluate(u)[0], want)
    assert p.params["orientation"] is True
    got = m.initial[p.name]
    assert p.value_names == ("point_parameter", "yaw", "pitch", "roll")
    assert abs(got[0] - value["parameter"]) < 1e-12
    assert all(abs(a - b) < 1e-12 for a, b in zip(got[1:], ypr_angles(value["orientation"])))
    assert limits is None and all(x is None for x in p.lower + p.upper)


def _si_turn(kind: str, profile: str):
    """Post-multiplier that turns a pair frame of ``profile`` into the 1996 convention."""
    return inverse(Z_TO_X) if (kind == "prismatic" and profile == "ap242") else np.eye(4)


# --------------------------------------------------------------------------- (a) layouts agree

@pytest.mark.parametrize("mech", ALL)
def test_three_profiles_give_the_same_model(mech):
    models = {p: _model(mech, p) for p in PROFILES}
    ref = models["ap214"]
    for prof, m in models.items():
        assert m.profile == prof
        assert m.name == mech  # 1996: the kinematic property's product id; AP242: the representation's name
        assert m.description == ref.description != ""
        assert m.link_names == ref.link_names
        assert m.pair_names == ref.pair_names
        assert m.base == ref.base
        assert _close(m.T_world_base, ref.T_world_base)
        assert m.units == ref.units
        for la, lb in zip(m.links, ref.links):
            assert sorted(la.frames) == sorted(lb.frames)
            for k in la.frames:
                assert _close(la.frames[k], lb.frames[k]), (prof, la.name, k)
        for pa, pb in zip(m.pairs, ref.pairs):
            assert (pa.kind, pa.link1, pa.link2, pa.actuated) == (pb.kind, pb.link1, pb.link2, pb.actuated)
            turn = _si_turn(pa.kind, prof)
            assert _close(pa.P1 @ turn, pb.P1), (prof, pa.name)
            assert _close(pa.P2 @ turn, pb.P2), (prof, pa.name)
            pa_params, pb_params = _numeric_params(pa), _numeric_params(pb)
            assert pa_params.keys() == pb_params.keys()
            for k in pa_params:
                assert _rel_close(pa_params[k], pb_params[k]), (prof, pa.name, k)
            if "curve" in pb.params:  # higher pairs: the same curve in the first pair frame
                u = np.linspace(0.0, 2 * math.pi, 7)
                assert _close(pa.params["curve"].evaluate(u)[0], pb.params["curve"].evaluate(u)[0])
                assert pa.params["orientation"] is pb.params["orientation"]
            for x, y in zip(pa.lower + pa.upper, pb.lower + pb.upper):
                assert _rel_close(x, y), (prof, pa.name)
            assert pa.description == pb.description
        assert m.initial.keys() == ref.initial.keys() == set(ref.pair_names)
        for k, v in m.initial.items():
            assert all(_rel_close(x, y, 1e-11) for x, y in zip(v, ref.initial[k])), (prof, k)
    # prismatic pairs slide along z in the 1996 layout and along x in AP242: each reads its own
    for prof, m in models.items():
        for p in m.pairs:
            if p.kind == "prismatic":
                assert p.params["layout"] == ("ap242" if prof == "ap242" else "1996")


def test_p105_file_is_read_with_the_p105_profile_and_ap214_refuses_su_parameters():
    auto = read_mechanism(_doc("ur5_arm", "p105"))
    assert auto.profile == "p105"
    explicit = read_mechanism(_doc("ur5_arm", "p105"), "p105")
    for a, b in zip(auto.pairs, explicit.pairs):
        assert np.array_equal(a.P2, b.P2)
    with pytest.raises(ModelError) as err:
        read_mechanism(_doc("ur5_arm", "p105"), "ap214")
    su = next(r["id"] for r in _records("ur5_arm", "p105")[1] if r.get("type") == "su_parameters")
    assert f"#{su}" in str(err.value) and "su_parameters" in str(err.value)


# --------------------------------------------------------------------------- (b) ground truth

@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize("mech", ALL)
def test_model_matches_the_corpus_ground_truth(mech, profile):
    truth, limits = _truth(mech)
    m = _model(mech, profile)
    axis = 0 if profile == "ap242" else 2
    assert m.link_names == tuple(ln.name for ln in truth.links)
    assert [ln.description for ln in m.links] == [ln.description for ln in truth.links]  # from the products
    assert m.base == truth.links[0].name
    T = np.array(truth.base_pose, float)
    T[:3, 3] *= MM
    assert _close(m.T_world_base, T)
    assert m.units.length == MM and m.units.length_name == "millimetre"
    assert abs(m.units.angle - math.pi / 180) < 1e-16 and m.units.angle_name == "degree"
    state = configuration(truth, truth.drives[0], axis)
    for tp in truth.pairs:
        p = m.pair(tp.name)
        assert (p.kind, p.link1, p.link2, p.actuated) == (tp.kind, tp.first, tp.second, tp.actuated)
        for P, F in zip((p.P1, p.P2), pair_frames(tp, axis)):
            F = np.array(F, float)
            F[:3, 3] *= MM
            assert _close(P, F), (tp.name, P, F)
        if tp.kind == "point_on_planar_curve":
            _check_contact(m, p, tp, state[tp.name], limits[tp.name])
            continue
        lengthy = tp.kind in ("prismatic", "rack_and_pinion")
        unit = MM if lengthy else 1.0
        q = scalar_value(tp.kind, state[tp.name]) * unit
        assert _rel_close(m.initial[tp.name][0], q, 1e-11) or abs(m.initial[tp.name][0] - q) < 1e-14
        lim = limits[tp.name]
        if lim is None:
            assert p.lower == (None,) and p.upper == (None,)
        else:
            assert _rel_close(p.lower[0], lim[0] * unit) and _rel_close(p.upper[0], lim[1] * unit)
        if tp.kind == "gear":
            assert _rel_close(p.params["radius_first_link"], tp.params["radius_first"] * MM)
            assert _rel_close(p.params["radius_second_link"], tp.params["radius_second"] * MM)
            assert _rel_close(p.params["gear_ratio"], tp.params["gear_ratio"])
            assert p.params["bevel"] == 0.0 and p.params["helical_angle"] == 0.0
        if tp.kind == "rack_and_pinion":
            assert _rel_close(p.params["pinion_radius"], tp.params["pinion_radius"] * MM)
    # named frames beyond the pair frames (written as "<link> <frame>")
    for ln in truth.links:
        frames = m.link(ln.name).frames
        assert sorted(frames) == sorted(f"{ln.name} {k}" for k in ln.frames)
        for k, F in ln.frames.items():
            F = np.array(F, float)
            F[:3, 3] *= MM
            assert _close(frames[f"{ln.name} {k}"], F)


@pytest.mark.parametrize("profile", ("p105", "ap242"))
def test_su_parameters_frames_are_kept_in_si(profile):
    """The UR5's frames are su_parameters (Annex F) where the profile allows it: params su_1/su_2
    hold them in SI (for writers), they rebuild P1/P2 exactly, and match the DH-derived truth."""
    from p105cli.kinematics.placements import su_parameters
    truth, _ = _truth("ur5_arm")
    m = _model("ur5_arm", profile)
    for tp in truth.pairs:
        p = m.pair(tp.name)
        for key, P, su in (("su_1", p.P1, tp.su_first), ("su_2", p.P2, tp.su_second)):
            got = p.params[key]
            assert np.array_equal(su_parameters(*got), P)
            want = (su[0] * MM, su[1], su[2] * MM, su[3], su[4] * MM, su[5])
            assert all(abs(x - y) <= 1e-12 * max(1.0, abs(y)) for x, y in zip(got, want)), (tp.name, key)
        assert "su_1" not in p.motion_params()
    assert all("su_1" not in p.params for p in _model("ur5_arm", "ap214").pairs)


def test_source_ids_point_at_the_instances_of_each_role():
    from p105cli.schema.population import Population
    for prof in PROFILES:
        doc = _doc("slider_crank", prof)
        m = read_mechanism(doc)
        pop = Population(doc, prof)
        want = {"pair": "kinematic_pair", "joint": "kinematic_joint", "value": "pair_value",
                "frame_1": "axis2_placement_3d", "frame_2": "axis2_placement_3d",
                "range": "simple_pair_range", "actuator": "pair_actuator",
                "relationship": "pair_representation_relationship"}
        for p in m.pairs:
            for role, entity in want.items():
                if role in p.ids:
                    assert entity in pop.types_of(p.ids[role]), (prof, p.name, role)
            assert ("range" in p.ids) == (prof != "ap242")
            assert ("actuator" in p.ids) == (prof != "ap242" and p.actuated)
        mech_entity = "mechanism_representation" if prof == "ap242" else "mechanism"
        assert mech_entity in pop.types_of(m.ids["mechanism"])
        state = "mechanism_state_representation" if prof == "ap242" else "initial_state"
        assert state in pop.types_of(m.ids["initial_state"])
        base = "item_defined_transformation" if prof == "ap242" else "mechanism_base_placement"
        assert base in pop.types_of(m.ids["base_placement"])


# --------------------------------------------------------------------------- (c) loops close

def _corpus_contact_transform(p, q):
    """T_link1_link2 of the cam contact in the corpus generator's convention
    (p105cli.corpus.geometry: M = Trans(C(u)) ypr_rotation), built from what the reader
    gives (the curve in the first pair frame, the point parameter and ypr angles).
    kinematics.pairs defines the point-on-planar-curve motion with the ypr measured from the
    curve's tangent frame instead, so Pair.transform does not close the corpus cam (reported)."""
    from p105cli.kinematics.placements import ypr_rotation
    from p105cli.kinematics.spatial import transform
    C = p.params["curve"].evaluate(q[0])[0]
    return p.P1 @ transform(ypr_rotation(*q[1:]), C) @ inverse(p.P2)


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize("mech", [k for k in ALL if MECHANISMS[k]().loops])
def test_loops_close_at_the_initial_state(mech, profile):
    truth, _ = _truth(mech)
    m = _model(mech, profile)
    q = {p.name: np.asarray(m.initial[p.name]) for p in m.pairs}

    def walk(dq):
        T = np.eye(4)
        for name, forward in loop:
            p = m.pair(name)
            qq = q[name] + (dq if name == loop[0][0] else 0.0)
            Tp = _corpus_contact_transform(p, qq) if p.kind == "point_on_planar_curve" else p.transform(qq)
            T = T @ (Tp if forward else inverse(Tp))
        return T

    for loop in truth.loops:
        T = walk(0.0)
        assert np.abs(T[:3, :3] - np.eye(3)).max() < 1e-9
        assert np.abs(T[:3, 3]).max() < 1e-9 * m.size()
        # and the loop is not closed by accident: another value of its first pair opens it
        assert np.abs(walk(0.3) - np.eye(4)).max() > 1e-3


# --------------------------------------------------------------------------- (d) units

LENGTH_TYPES = ("length_measure", "positive_length_measure", "non_negative_length_measure")
ANGLE_TYPES = ("plane_angle_measure", "positive_plane_angle_measure")
DEGREE = 0.0174532925199433  # the corpus's conversion factor of the degree


def _measure(schema, name: str):
    """'length', 'angle' or None for a defined type name (following defined types)."""
    seen = set()
    while name not in seen:
        seen.add(name)
        if name in LENGTH_TYPES:
            return "length"
        if name in ANGLE_TYPES:
            return "angle"
        decl = schema.types.get(name)
        if decl is None or type(decl.underlying).__name__ != "NamedType":
            return None
        name = decl.underlying.name
    return None


def _convert(schema, value, spec, factors, angle_parameters: bool):
    """``value`` of type ``spec`` with every length/angle multiplied by its factor."""
    kind_name = type(spec).__name__ if spec is not None else None
    if type(value) is dict and "type" in value and "value" in value:  # typed parameter
        tname = value["type"].lower()
        decl = schema.types.get(tname)
        sub = decl.underlying if decl is not None else None
        kind = _measure(schema, tname)
        if tname == "parameter_value" and angle_parameters:
            kind = "angle"
        if kind is not None:
            inner = value["value"]
            if type(inner) is list:
                return {**value, "value": [x * factors[kind] for x in inner]}
            return {**value, "value": inner * factors[kind]}
        return {**value, "value": _convert(schema, value["value"], sub, factors, angle_parameters)}
    if type(value) is list:
        elem = spec.element if kind_name == "AggregateType" else None
        return [_convert(schema, x, elem, factors, angle_parameters) for x in value]
    if type(value) in (int, float) and kind_name == "NamedType":
        kind = _measure(schema, spec.name)
        if spec.name == "parameter_value" and angle_parameters:
            kind = "angle"
        if kind is not None:
            return value * factors[kind]
    if kind_name == "NamedType" and type(value) is list:
        decl = schema.types.get(spec.name)
        return _convert(schema, value, decl.underlying if decl else None, factors, angle_parameters)
    return value


def _to_metre_radian(data: list, profile: str) -> None:
    """Rewrite a corpus file from (mm, degree) to (m, radian): every length and plane angle
    the schema types as such is converted, then the units are changed."""
    from p105cli.schema.population import Population
    pop = Population(data, profile if profile != "p105" else "p105")
    schema = pop.schema
    factors = {"length": MM, "angle": DEGREE}
    circles = {r["id"] for r in data if r.get("type") in ("circle", "ellipse")}
    length_unit = next(r["id"] for r in data if "complex" in r
                       and any(p["type"] == "length_unit" for p in r["complex"]))
    for rec in data:
        if rec.get("type", "").endswith("measure_with_unit") and rec["args"][1]["ref"] != length_unit:
            continue  # a unit's own conversion factor (the degree in radians) stays as it is
        inst = pop.instance(rec["id"])
        angle_params = False
        if rec.get("type") in ("point_on_curve", "trimmed_curve"):
            angle_params = rec["args"][1]["ref"] in circles
        for s in inst.layout.slots:
            args = rec["complex"][s.part]["args"] if "complex" in rec else rec["args"]
            if s.pos < len(args):
                args[s.pos] = _convert(schema, args[s.pos], s.type, factors, angle_params)
    units = {}
    for rec in data:
        parts = {p["type"]: p for p in rec.get("complex", ())}
        if "si_unit" in parts and "length_unit" in parts:
            parts["si_unit"]["args"][0] = None  # .MILLI. -> no prefix: the metre
            units["length"] = rec["id"]
        if "si_unit" in parts and "plane_angle_unit" in parts:
            units["radian"] = rec["id"]
        if "conversion_based_unit" in parts and "plane_angle_unit" in parts:
            units["degree"] = rec["id"]
    for rec in data:
        for p in rec.get("complex", ()):
            if p["type"] == "global_unit_assigned_context":
                p["args"][0] = [{"ref": units["radian"]} if r["ref"] == units["degree"] else r
                                for r in p["args"][0]]


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize("mech", ("slider_crank", "ur5_arm", "gear_train", "rack_and_pinion", "cam_follower"))
def test_metre_radian_variant_reads_the_same_model(mech, profile):
    ref = _model(mech, profile)
    var = read_mechanism(_doc(mech, profile, lambda d: _to_metre_radian(d, profile)),
                         "p105" if profile == "p105" else None)
    assert (var.units.length, var.units.angle, var.units.length_name, var.units.angle_name) == (
        1.0, 1.0, "metre", "radian")
    assert var.link_names == ref.link_names and var.pair_names == ref.pair_names
    assert _close(var.T_world_base, ref.T_world_base, 1e-15)
    for a, b in zip(var.pairs, ref.pairs):
        assert _close(a.P1, b.P1, 1e-15) and _close(a.P2, b.P2, 1e-15)
        for k, v in _numeric_params(b).items():
            assert _rel_close(a.params[k], v, 1e-14)
        if "curve" in b.params:
            u = np.linspace(0.0, 6.0, 7)
            assert _close(a.params["curve"].evaluate(u)[0], b.params["curve"].evaluate(u)[0], 1e-15)
        for k in ("su_1", "su_2"):
            assert (k in a.params) == (k in b.params)
            if k in b.params:
                assert all(_rel_close(x, y, 1e-14) or abs(x - y) < 1e-15 for x, y in zip(a.params[k], b.params[k]))
        for x, y in zip(a.lower + a.upper, b.lower + b.upper):
            assert _rel_close(x, y, 1e-14)
        assert all(_rel_close(x, y, 1e-14) for x, y in zip(var.initial[a.name], ref.initial[b.name]))
    # the variant really is in metres and radians: the numbers in the file changed
    _, recs = _records(mech, profile)
    assert any(r.get("type") == "cartesian_point" and any(abs(c) > 1.0 for c in r["args"][1]) for r in recs)


def test_inch_length_unit_is_converted():
    """A conversion-based inch (25.4 mm) in the link contexts: the reader follows the chain."""
    ref = _model("four_bar", "ap242")

    def edit(data):
        top = max(r["id"] for r in data)
        mm = next(r["id"] for r in data if "complex" in r and any(p["type"] == "length_unit" for p in r["complex"]))
        inch_factor = {"id": top + 1, "type": "length_measure_with_unit",
                       "args": [{"type": "LENGTH_MEASURE", "value": 25.4}, {"ref": mm}]}
        inch = {"id": top + 2, "complex": [
            {"type": "conversion_based_unit", "args": ["INCH", {"ref": top + 1}]},
            {"type": "length_unit", "args": []}, {"type": "named_unit", "args": [{"derived": True}]}]}
        data.extend([inch_factor, inch])
        for r in data:
            for p in r.get("complex", ()):
                if p["type"] == "global_unit_assigned_context" and "link" in r["complex"][-1]["args"][0]:
                    p["args"][0] = [{"ref": top + 2} if x["ref"] == mm else x for x in p["args"][0]]

    m = read_mechanism(_doc("four_bar", "ap242", edit))
    assert m.units.length == pytest.approx(0.0254, rel=1e-15) and m.units.length_name == "inch"
    for a, b in zip(m.pairs, ref.pairs):  # link contexts now in inches: frames 25.4 times farther out
        assert _close(a.P1[:3, 3], b.P1[:3, 3] * 25.4, 1e-13)
        assert _close(a.P1[:3, :3], b.P1[:3, :3])
    assert _close(m.T_world_base, ref.T_world_base)  # the world context stayed in mm


# --------------------------------------------------------------------------- several mechanisms

def _merge(a: str, b: str, profile: str, offset: int = 100000) -> JsonDocument:
    def shift(v):
        if type(v) is dict:
            if "ref" in v:
                return {"ref": v["ref"] + offset}
            return {k: shift(x) for k, x in v.items()}
        if type(v) is list:
            return [shift(x) for x in v]
        return v

    header, ra = _records(a, profile)
    _, rb = _records(b, profile)
    data = copy.deepcopy(list(ra))
    for r in rb:
        r = shift(copy.deepcopy(r))
        r["id"] = r["id"] + offset if type(r["id"]) is int else r["id"]
        data.append(r)
    return JsonDocument(copy.deepcopy(header), [DataSection(None, len(data))], data)


@pytest.mark.parametrize("profile", ("ap214", "ap242"))
def test_several_mechanisms_in_one_file(profile):
    doc = _merge("four_bar", "rack_and_pinion", profile)
    ms = read_mechanisms(doc)
    assert [m.name for m in ms] == ["four_bar", "rack_and_pinion"]
    for m in ms:
        one = _model(m.name, profile)
        assert m.link_names == one.link_names and m.pair_names == one.pair_names
        for a, b in zip(m.pairs, one.pairs):
            assert np.array_equal(a.P1, b.P1) and np.array_equal(a.P2, b.P2)
            assert a.lower == b.lower and a.upper == b.upper
        assert dict(m.initial) == dict(one.initial)
    assert ms[1].ids["mechanism"] == _model("rack_and_pinion", profile).ids["mechanism"] + 100000
    assert read_mechanism(doc, name="rack_and_pinion").name == "rack_and_pinion"
    with pytest.raises(ModelError, match="2 mechanisms.*'four_bar', 'rack_and_pinion'"):
        read_mechanism(doc)
    with pytest.raises(ModelError, match="no mechanism named 'x'"):
        read_mechanism(doc, name="x")


# --------------------------------------------------------------------------- (e) errors

def _first(data, type_name):
    return next(r for r in data if r.get("type") == type_name)


def _error_of(mech, profile, edit) -> str:
    with pytest.raises(ModelError) as err:
        read_mechanisms(_doc(mech, profile, edit))
    return str(err.value)


def test_dangling_joint_reference_names_the_pair():
    _, recs = _records("four_bar", "ap214")
    pid = _first(recs, "revolute_pair")["id"]

    def edit(data):
        _first(data, "revolute_pair")["args"][4] = {"ref": 987654}

    msg = _error_of("four_bar", "ap214", edit)
    assert f"#{pid}:" in msg and "#987654" in msg and "not in the file" in msg


def test_pair_without_joint_names_the_pair():
    _, recs = _records("four_bar", "ap214")
    pid = _first(recs, "revolute_pair")["id"]
    joint = _first(recs, "revolute_pair")["args"][4]["ref"]

    def edit(data):
        _first(data, "revolute_pair")["args"][4] = None

    msg = _error_of("four_bar", "ap214", edit)
    # the structure's joint lost its pair; the pair without a joint is the one named
    assert f"#{pid}:" in msg and "no joint" in msg and f"#{joint}" not in msg
    # AP242: the pair is reached through its representation relationship; its joint is unset
    _, recs242 = _records("four_bar", "ap242")
    pair242 = next(r for r in recs242 if r.get("type") == "revolute_pair")

    def edit242(data):
        next(r for r in data if r["id"] == pair242["id"])["args"][5] = None

    msg = _error_of("four_bar", "ap242", edit242)
    assert f"#{pair242['id']}:" in msg and "joint" in msg


def test_dangling_reference_in_ap242_representation_names_the_relationship():
    _, recs = _records("gear_train", "ap242")
    prr = _first(recs, "pair_representation_relationship")["id"]

    def edit(data):
        next(r for r in data if r["id"] == prr)["args"][5] = {"ref": 424242}

    msg = _error_of("gear_train", "ap242", edit)
    assert f"#{prr}:" in msg and "#424242" in msg


@pytest.mark.parametrize("profile", ("ap214", "ap242"))
def test_unit_without_si_conversion_names_the_unit(profile):
    def edit(data):
        rec = next(r for r in data if "complex" in r and any(p["type"] == "length_unit" for p in r["complex"]))
        rec["complex"] = [{"type": "context_dependent_unit", "args": ["furlong"]},
                          {"type": "length_unit", "args": []},
                          {"type": "named_unit", "args": [{"derived": True}]}]

    _, recs = _records("four_bar", profile)
    unit = next(r["id"] for r in recs if "complex" in r and any(p["type"] == "length_unit" for p in r["complex"]))
    msg = _error_of("four_bar", profile, edit)
    assert f"#{unit}:" in msg and "no SI conversion" in msg


def test_context_without_plane_angle_unit_is_an_error_only_when_angles_are_read():
    def drop_angles(data):
        deg = next(r["id"] for r in data if "complex" in r
                   and any(p["type"] == "conversion_based_unit" for p in r["complex"]))
        for r in data:
            for p in r.get("complex", ()):
                if p["type"] == "global_unit_assigned_context":
                    p["args"][0] = [x for x in p["args"][0] if x["ref"] != deg]

    # the four-bar's values are rotations: its first links' contexts must give the angle unit
    msg = _error_of("four_bar", "ap214", drop_angles)
    assert "plane-angle unit" in msg and msg.split(":")[1].strip().startswith("#")


def test_degenerate_pair_frame_names_the_placement():
    _, recs = _records("four_bar", "ap242")
    pair = next(r for r in recs if r.get("type") == "revolute_pair")
    frame = pair["args"][3]["ref"]
    a2 = next(r for r in recs if r["id"] == frame)
    axis = a2["args"][2]["ref"]

    def edit(data):
        next(r for r in data if r["id"] == frame)["args"][3] = {"ref": axis}  # ref_direction := axis

    msg = _error_of("four_bar", "ap242", edit)
    assert f"#{frame}:" in msg and "parallel" in msg


def test_no_mechanism_is_an_error():
    def edit(data):
        data[:] = [r for r in data if r.get("type") not in ("mechanism", "mechanism_base_placement",
                                                            "initial_state", "kinematic_control")]

    assert read_mechanisms(_doc("four_bar", "ap214", edit)) == []
    with pytest.raises(ModelError, match="no mechanism"):
        read_mechanism(_doc("four_bar", "ap214", edit))


def test_pair_frame_in_the_other_links_representation_names_the_pair():
    _, recs = _records("four_bar", "ap214")
    pair = [r for r in recs if r.get("type") == "revolute_pair"][1]  # B: crank -> coupler

    def edit(data):
        args = next(r for r in data if r["id"] == pair["id"])["args"]
        args[2], args[3] = args[3], args[2]  # transform_item_1 now lies in the coupler's representation

    msg = _error_of("four_bar", "ap214", edit)
    assert msg.split(": ", 1)[1].startswith(f"#{pair['id']}:") and "transform_item_1" in msg


# --------------------------------------------------------------------------- higher-pair geometry

@pytest.mark.parametrize("profile", ("ap214", "ap242"))
def test_pair_curve_is_held_in_its_pair_frame(profile):
    """Move the cam's first contact frame 5 mm along x. AP242 keeps the cam profile in the link
    representation, so in the moved pair frame its centre is 5 mm nearer; the 1996 layout holds
    the profile in a frame background attached to that pair frame, so it moves with it."""
    _, recs = _records("cam_follower", profile)
    frame = next(r for r in recs if r.get("type") == "axis2_placement_3d" and r["args"][0] == "contact on cam")
    point = frame["args"][1]["ref"]

    def edit(data):
        next(r for r in data if r["id"] == point)["args"][1] = [5.0, 0.0, 0.0]

    ref = _model("cam_follower", profile).pair("contact")
    moved = read_mechanism(_doc("cam_follower", profile, edit)).pair("contact")
    assert _close(moved.P1[:3, 3], [0.005, 0.0, 0.0])
    u = np.linspace(0.0, 6.0, 7)
    shift = np.array([0.005, 0.0, 0.0]) if profile == "ap242" else np.zeros(3)
    assert _close(moved.params["curve"].evaluate(u)[0], ref.params["curve"].evaluate(u)[0] - shift)
    centre = 0.015 - shift[0]
    assert _close(moved.params["curve"].evaluate(0.0)[0], [centre + 0.04, 0.0, 0.0])


def test_point_on_a_foreign_curve_is_an_error():
    _, recs = _records("cam_follower", "ap214")
    value = next(r for r in recs if r.get("type") == "point_on_planar_curve_pair_value" and
                 any(r["id"] in (x["ref"] for x in s["args"][1]) for s in recs if s.get("type") == "initial_state"))
    point = value["args"][1]["ref"]
    other = next(r["id"] for r in recs if r.get("type") == "circle" and r["args"][0] == "cam cam profile")

    def edit(data):
        next(r for r in data if r["id"] == point)["args"][1] = {"ref": other}

    msg = _error_of("cam_follower", "ap214", edit)
    assert msg.split(": ", 1)[1].startswith(f"#{value['id']}:") and f"#{other}" in msg


def test_trimmed_curve_range_bounds_the_point_parameter():
    """A contact range trimmed from 30 to 120 degrees (sense TRUE), and from 120 back to 30
    (sense FALSE): both bound the point parameter to [30, 120] degrees in radians."""
    for sense, (t1, t2) in (("T", (30.0, 120.0)), ("F", (120.0, 30.0))):
        def edit(data):
            rec = next(r for r in data if r.get("type") == "trimmed_curve")
            rec["args"][2] = [{"type": "PARAMETER_VALUE", "value": t1}]
            rec["args"][3] = [{"type": "PARAMETER_VALUE", "value": t2}]
            rec["args"][4] = {"enum": sense}

        for profile in ("ap214", "ap242"):
            p = read_mechanism(_doc("cam_follower", profile, edit)).pair("contact")
            assert p.lower[0] == pytest.approx(math.radians(30.0), rel=1e-12), (sense, profile)
            assert p.upper[0] == pytest.approx(math.radians(120.0), rel=1e-12), (sense, profile)
            assert p.lower[1:] == (None, None, None) and p.upper[1:] == (None, None, None)


def test_bad_pair_curve_names_the_curve():
    _, recs = _records("cam_follower", "ap214")
    curve = next(r["id"] for r in recs if r.get("type") == "circle" and r["args"][0] == "contact pair curve")

    def edit(data):
        next(r for r in data if r["id"] == curve)["args"][2] = "forty"

    msg = _error_of("cam_follower", "ap214", edit)
    assert msg.split(": ", 1)[1].startswith(f"#{curve}: circle") and "radius" in msg


# --------------------------------------------------------------------------- pair kinds the corpus lacks

def _rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _t(x, y, z):
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def _hand_built_1996() -> tuple:
    """A 1996-layout chain base -spherical- l1 -screw- l2 -universal- l3 -cylindrical- l4, mm and
    degrees, with su_parameters frames on the spherical pair (p105 profile)."""
    from p105cli.part105.builder import Builder, enum, typed
    b = Builder()
    b.units(cbu_dimensions_explicit=False)
    ctx = b.context("links")
    links = [b.add("kinematic_link") for _ in range(5)]
    joints = [b.add("kinematic_joint", links[k], links[k + 1]) for k in range(4)]
    structure = b.add("kinematic_structure", joints)
    su = b.add("su_parameters", "sph on base", 10.0, 90.0, 0.0, 0.0, 5.0, 45.0)
    frames = [(su, b.axis2(np.eye(4), "sph on l1"))]
    for k in range(1, 4):
        frames.append((b.axis2(_t(0, 0, 20.0 * k), f"f{k} a"), b.axis2(np.eye(4), f"f{k} b")))
    items = [[] for _ in links]
    for k, (f1, f2) in enumerate(frames):
        items[k].append(f1)
        items[k + 1].append(f2)
    for k, ln in enumerate(links):
        rep = b.add("kinematic_link_representation", f"link {k}", items[k], ctx)
        b.add("kinematic_link_representation_relation", ln, rep)
    sph = b.add("spherical_pair", "ball", "", *frames[0], joints[0])
    screw = b.add("screw_pair", "screw", "", *frames[1], joints[1], 5.0)
    uni = b.add("universal_pair", "cardan", "", *frames[2], joints[2], 10.0)
    cyl = b.add("cylindrical_pair", "sleeve", "", *frames[3], joints[3])
    mech = b.add("mechanism", structure, links[0], None)
    deg = lambda x: typed("plane_angle_measure", x)  # noqa: E731
    unl = typed("unlimited_range", enum("unlimited"))
    b.add("spherical_pair_range", sph, deg(-90.0), deg(90.0), unl, unl, deg(-45.0), deg(45.0))
    b.add("cylindrical_pair_range", cyl, typed("length_measure", 0.0), typed("length_measure", 50.0), unl, unl)
    b.add("pair_actuator", screw, "motor")
    axis = b.direction([1.0, 2.0, 2.0])
    values = [b.add("spherical_pair_value", sph, b.add("rotation_about_direction", axis, 50.0)),
              b.add("screw_pair_value", screw, 90.0),
              b.add("universal_pair_value", uni, 10.0, -20.0),
              b.add("cylindrical_pair_value", cyl, 12.0, 45.0)]
    b.add("initial_state", mech, values)
    header = {"file_description": {"description": [""], "implementation_level": "2;1"},
              "file_name": {"name": "chain", "time_stamp": "", "author": [""], "organization": [""],
                            "preprocessor_version": "", "originating_system": "", "authorization": ""},
              "file_schema": ["AUTOMOTIVE_DESIGN"]}
    return JsonDocument(header, [DataSection(None, len(b.data))], b.data), mech["ref"]


def test_spherical_screw_universal_cylindrical_pairs_from_closed_forms():
    from scipy.spatial.transform import Rotation
    from p105cli.kinematics.placements import ypr_rotation
    doc, mech_id = _hand_built_1996()
    m = read_mechanism(doc)  # su_parameters in an AUTOMOTIVE_DESIGN file: the p105 profile
    assert m.profile == "p105" and m.name == f"#{mech_id}"
    assert m.link_names == ("link 0", "link 1", "link 2", "link 3", "link 4")
    assert m.pair_names == ("ball", "screw", "cardan", "sleeve")
    assert [p.kind for p in m.pairs] == ["spherical", "screw", "universal", "cylindrical"]
    assert np.array_equal(m.T_world_base, np.eye(4))  # no mechanism_base_placement
    d = math.pi / 180
    ball, screw, cardan, sleeve = m.pairs
    # su_parameters (a, alpha, b, beta, c, gamma) = (10 mm, 90 deg, 0, 0, 5 mm, 45 deg):
    # Tz(c) Rz(gamma) Tx(a) Rx(alpha) Tz(b) Rz(beta) (ISO 10303-105 5.4.17)
    want = _t(0, 0, 0.005) @ _rz(45 * d) @ _t(0.010, 0, 0) @ _rx(90 * d)
    assert _close(ball.P1, want)
    assert _close(screw.P1, _t(0, 0, 0.020)) and _close(sleeve.P1, _t(0, 0, 0.060))
    assert ball.params["su_1"] == pytest.approx((0.010, 90 * d, 0.0, 0.0, 0.005, 45 * d), rel=1e-15)
    assert screw.params["pitch"] == pytest.approx(0.005, rel=1e-15)
    assert cardan.params["input_skew_angle"] == pytest.approx(10 * d, rel=1e-12)
    assert screw.actuated and not ball.actuated
    # ranges: ypr limits in radians, unlimited pitch; cylindrical translation in metres
    assert ball.lower[1] is None and ball.upper[1] is None
    assert (ball.lower[0], ball.upper[0], ball.lower[2], ball.upper[2]) == pytest.approx(
        (-math.pi / 2, math.pi / 2, -math.pi / 4, math.pi / 4), rel=1e-12)
    assert sleeve.lower[0] == 0.0 and sleeve.upper[0] == pytest.approx(0.050, rel=1e-15)
    assert sleeve.lower[1] is None and sleeve.upper[1] is None
    assert screw.lower == (None,) and cardan.upper == (None, None)  # no range given
    # initial values: the rotation about (1, 2, 2) by 50 degrees as ypr angles (5.5.9)
    ypr = m.initial["ball"]
    R = Rotation.from_rotvec(np.array([1.0, 2.0, 2.0]) / 3.0 * 50 * d).as_matrix()
    assert np.abs(ypr_rotation(*ypr) - R).max() < 1e-12 and abs(ypr[1]) <= math.pi / 2
    assert m.initial["screw"] == pytest.approx((math.pi / 2,), rel=1e-12)
    assert m.initial["cardan"] == pytest.approx((10 * d, -20 * d), rel=1e-12)
    assert m.initial["sleeve"] == pytest.approx((0.012, math.pi / 4), rel=1e-12)
    # the screw advances pitch / turn: a quarter turn moves link 2 by 1.25 mm along the axis
    T = screw.transform(m.initial["screw"])
    assert _close(T[:3, 3], [0.0, 0.0, 0.020 + 0.00125])


def _generic_pin_b(flags, values, limits=None):
    """The AP242 four-bar with pin B rewritten as AP242's generic low_order_kinematic_pair with
    ``flags`` (t_x .. r_z) and its values as low_order_kinematic_pair_value ``values(angle)``;
    ``limits``: the twelve limits of low_order_kinematic_pair_with_range (file units)."""
    _, recs = _records("four_bar", "ap242")
    pid = next(r["id"] for r in recs if r.get("type") == "revolute_pair" and r["args"][0] == "B")

    def edit(data):
        for r in data:
            if r["id"] == pid:
                r["type"] = "low_order_kinematic_pair" + ("_with_range" if limits else "")
                r["args"] = r["args"][:6] + [{"enum": "T" if f else "F"} for f in flags] + list(limits or ())
            elif r.get("type") == "revolute_pair_value" and r["args"][1]["ref"] == pid:
                r["type"] = "low_order_kinematic_pair_value"
                r["args"] = r["args"][:2] + list(values(r["args"][2]))

    return _doc("four_bar", "ap242", edit), pid


def test_ap242_generic_low_order_pair_with_revolute_flags_is_the_revolute_pair():
    """Pin B as the generic pair with only r_z free: read as the revolute pair its flags name
    (one freedom, the rotation from actual_rotation_z), moving exactly as the revolute pin."""
    doc, _pid = _generic_pin_b((0, 0, 0, 0, 0, 1), lambda a: (0.0, 0.0, 0.0, 0.0, 0.0, a))
    m = read_mechanism(doc)
    ref = _model("four_bar", "ap242")
    b = m.pair("B")
    assert (b.kind, b.freedoms, dict(b.params)) == ("revolute", 1, {})
    assert m.initial["B"] == pytest.approx(ref.initial["B"], rel=1e-15)
    assert _close(b.transform(m.initial["B"]), ref.pair("B").transform(ref.initial["B"]), 1e-15)


def test_a_generic_revolute_pairs_limits_are_its_rotation_z_limits():
    """low_order_kinematic_pair_with_range lists rotation limits (x, y, z), then translation
    limits: read as a revolute pair, pin B is bounded by lower/upper_limit_actual_rotation_z
    (degrees in the four-bar's file); the other, locked, limits bound nothing."""
    limits = [-1.0, 1.0, None, None, -120.0, 150.0, -5.0, 5.0, None, None, None, None]
    doc, _pid = _generic_pin_b((0, 0, 0, 0, 0, 1), lambda a: (0.0, 0.0, 0.0, 0.0, 0.0, a), limits)
    b = read_mechanism(doc).pair("B")
    assert b.kind == "revolute"
    assert (b.lower, b.upper) == (pytest.approx((-120.0 * math.pi / 180,), rel=1e-12),
                                  pytest.approx((150.0 * math.pi / 180,), rel=1e-12))


def test_ap242_generic_low_order_pair_with_no_named_flags_keeps_its_six_values():
    """Flags no named pair has (t_x and r_z): the generic pair, six values, two freedoms; its
    motion is T(tx) Rz(rz) (scipy's rotation as the independent truth)."""
    from scipy.spatial.transform import Rotation

    doc, _pid = _generic_pin_b((1, 0, 0, 0, 0, 1), lambda a: (2.5, 0.0, 0.0, 0.0, 0.0, a))
    m = read_mechanism(doc)
    ref = _model("four_bar", "ap242")
    b = m.pair("B")
    assert (b.kind, b.freedoms) == ("low_order", 2)
    assert {f: b.params[f] for f in ("t_x", "t_y", "t_z", "r_x", "r_y", "r_z")} == {
        "t_x": True, "t_y": False, "t_z": False, "r_x": False, "r_y": False, "r_z": True}
    angle = ref.initial["B"][0]
    assert m.initial["B"] == pytest.approx((0.0025, 0.0, 0.0, 0.0, 0.0, angle), rel=1e-15)
    M = b.motion(m.initial["B"])
    assert _close(M[:3, :3], Rotation.from_euler("z", angle).as_matrix(), 1e-15)
    assert _close(M[:3, 3], [0.0025, 0.0, 0.0], 1e-15)


@pytest.mark.parametrize("profile", ("ap214", "ap242"))
def test_part21_file_and_json_model_read_the_same(profile):
    """load_document gives a lazily decoded StepFile for Part 21: the same model as the JSON model."""
    from p105cli.cli.inputs import load_document
    path = CORPUS_DIR / f"gear_train_{profile}.stp"
    m = read_mechanism(load_document(str(path)))
    ref = _model("gear_train", profile)
    assert m.link_names == ref.link_names and dict(m.ids) == dict(ref.ids)
    for a, b in zip(m.pairs, ref.pairs):
        assert np.array_equal(a.P1, b.P1) and np.array_equal(a.P2, b.P2) and dict(a.ids) == dict(b.ids)
        assert dict(a.params) == dict(b.params) and (a.lower, a.upper) == (b.lower, b.upper)
    assert dict(m.initial) == dict(ref.initial)
    with pytest.raises(ModelError) as err:  # errors name the file
        read_mechanism(_doc("gear_train", profile), name="nope")
    assert str(err.value).startswith(f"gear_train_{profile}: ") and "'nope'" in str(err.value)


def test_shared_probes_and_examples_read():
    """The hand-written probes of the shared corpus (AP242 with the standard '*' and with Open
    CASCADE's explicit values; a 1996 fragment without a mechanism) and the shipped examples."""
    from conftest import corpus_files
    from p105cli.cli.inputs import load_document
    files = {p.name: p for p in corpus_files() if p.stat().st_size < 1_000_000}
    assert "four_bar_ap242.stp" in files
    for name, path in files.items():
        mechs = read_mechanisms(load_document(str(path)))
        if name.startswith("probe_p105_1996"):
            assert mechs == []  # a fragment: links, a joint and a pair, but no mechanism
        elif name.startswith("probe_"):
            (m,) = mechs
            assert (m.name, m.link_names, m.pair_names, m.base) == ("mech", ("base", "arm"), ("j1",), "base")
            assert m.pairs[0].kind == "revolute" and m.initial["j1"] == (0.5,)  # radians in the file
            assert m.units.length == 1e-3 and m.units.angle == 1.0
        elif name == "four_bar_ap242.stp":
            assert [m.name for m in mechs] == ["four_bar"]
        elif name.startswith("slider_crank"):
            assert [m.name for m in mechs] == ["slider_crank"]
