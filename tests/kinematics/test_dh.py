"""DH tables <-> Part 105 mechanisms (Annex F): p105cli.kinematics.dh and `p105 convert-dh-su`.

Independent truth: the reference poses of roboticstoolbox-python's fkine for
Puma560, UR5 (standard DH) and Panda (modified DH, with a tool transform),
cross-checked with Pinocchio (/work/shared/reference/dh_arms_and_loops.json),
and the plain DH product written out here from elementary rotations and
translations.
"""

from __future__ import annotations

import dataclasses
import io
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from conftest import EXAMPLES, SHARED
from p105cli.formats import dh_table
from p105cli.kinematics import dh
from p105cli.kinematics.model import Mechanism, Pair
from p105cli.kinematics.placements import su_parameters
from p105cli.kinematics.spatial import compose, inverse, rot_x, rot_y, rot_z, trans_x, trans_z

REFERENCE = SHARED / "reference" / "dh_arms_and_loops.json"
ARMS = ("Puma560", "UR5", "Panda")


@pytest.fixture(scope="module")
def reference():
    if not REFERENCE.is_file():
        pytest.fail(f"reference data missing: {REFERENCE}")
    return json.loads(REFERENCE.read_text())["arms"]


def ref_table(arm: dict, name: str) -> dh.DHTable:
    joints = [dh.DHJoint(f"J{r['j']}", "R" if r["joint"] == "revolute" else "P", r["a"], r["alpha"],
                         r["d"] if r["joint"] == "revolute" else 0.0,
                         r["theta"] if r["joint"] != "revolute" else 0.0, r["offset"])
              for r in arm["dh"]]
    return dh.DHTable(arm["convention"], joints, np.array(arm["base"]), np.array(arm["tool"]), name=name)


def ref_samples(arm: dict):
    return (np.array([s["q"] for s in arm["samples"]]), np.array([s["T"] for s in arm["samples"]]))


def compose_chain(mech: Mechanism, Q: np.ndarray) -> np.ndarray:
    """base . T_link0_link1(q1) ... T_link(n-1)_linkn(qn) . tool with Pair.transform, batched."""
    T = np.broadcast_to(mech.T_world_base, Q.shape[:-1] + (4, 4))
    for k, p in enumerate(mech.pairs):
        assert (p.link1, p.link2) == (f"link{k}", f"link{k + 1}")
        T = T @ p.transform(Q[..., k:k + 1])
    return T @ mech.link(f"link{len(mech.pairs)}").frames["tool"]


def plain_dh(convention: str, a, alpha, d, theta) -> np.ndarray:
    """The DH matrix written out from its definition (independent of dh.dh_transform)."""
    a, alpha, d, theta = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (a, alpha, d, theta)))
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    z, o = np.zeros_like(ct), np.ones_like(ct)
    if convention == "standard":
        rows = [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st],
                [z, sa * o, ca * o, d], [z, z, z, o]]
    else:
        rows = [[ct, -st, z, a], [st * ca, ct * ca, -sa * o, -sa * d],
                [st * sa, ct * sa, ca * o, ca * d], [z, z, z, o]]
    return np.moveaxis(np.array(rows, dtype=float), (0, 1), (-2, -1))


def plain_forward(table: dh.DHTable, Q: np.ndarray) -> np.ndarray:
    T = np.broadcast_to(table.base, Q.shape[:-1] + (4, 4))
    for k, j in enumerate(table.joints):
        q = Q[..., k]
        if j.type == "R":
            A = plain_dh(table.convention, j.a, j.alpha, j.d, q + j.offset)
        else:
            A = plain_dh(table.convention, j.a, j.alpha, q + j.offset, j.theta)
        T = T @ A
    return T @ table.tool


def angle_diff(x, y):
    return abs(math.remainder(x - y, 2 * math.pi))


def same_rows(t1: dh.DHTable, t2: dh.DHTable, tol=1e-12):
    assert t1.convention == t2.convention and len(t1.joints) == len(t2.joints)
    for j1, j2 in zip(t1.joints, t2.joints):
        assert (j1.name, j1.type) == (j2.name, j2.type)
        for f in ("a", "d"):
            assert abs(getattr(j1, f) - getattr(j2, f)) <= tol, (j1, j2, f)
        for f in ("alpha", "theta"):
            assert angle_diff(getattr(j1, f), getattr(j2, f)) <= tol, (j1, j2, f)
        off = angle_diff(j1.offset, j2.offset) if j1.type == "R" else abs(j1.offset - j2.offset)
        assert off <= tol, (j1, j2)


# ------------------------------------------------------------------ Annex F mapping

def test_design_note_annex_f_revolute_tuple():
    """DESIGN.md: standard revolute, offset 0: a=a, alpha=alpha, b=-d, beta=pi, c=0, gamma=pi."""
    j = dh.DHJoint("J", "R", 0.4318, -math.pi / 2, d=0.15005)
    su1, su2 = dh.annex_f("standard", j)
    assert su1 == (0.0,) * 6
    assert su2 == (0.4318, -math.pi / 2, -0.15005, math.pi, 0.0, math.pi)
    # the pair frame on link k is the inverse of the DH transform without the pair parameter
    np.testing.assert_allclose(su_parameters(*su2), inverse(compose(trans_z(0.15005), trans_x(0.4318),
                                                                    rot_x(-math.pi / 2))), atol=1e-15)


@pytest.mark.parametrize("convention", dh.CONVENTIONS)
@pytest.mark.parametrize("jtype", ["R", "P"])
def test_annex_f_frames_give_the_dh_transform(convention, jtype):
    rng = np.random.default_rng(7)
    for _ in range(20):
        a, d, off = rng.uniform(-1, 1, 3)
        alpha, theta = rng.uniform(-math.pi, math.pi, 2)
        j = (dh.DHJoint("J", "R", a, alpha, d=d, offset=off) if jtype == "R"
             else dh.DHJoint("J", "P", a, alpha, theta=theta, offset=off))
        su1, su2 = dh.annex_f(convention, j)
        P1, P2 = su_parameters(*su1), su_parameters(*su2)
        q = rng.uniform(-3, 3, 8)
        M = rot_z(q) if jtype == "R" else trans_z(q)
        want = (plain_dh(convention, a, alpha, d, q + off) if jtype == "R"
                else plain_dh(convention, a, alpha, q + off, theta))
        np.testing.assert_allclose(P1 @ M @ inverse(P2), want, atol=1e-14)


# ------------------------------------------------------------------ reference arms

@pytest.mark.parametrize("layout", ["1996", "ap242"])
@pytest.mark.parametrize("name", ARMS)
def test_reference_arms_reproduce_reference_poses(reference, name, layout):
    arm = reference[name]
    table = ref_table(arm, name)
    mech = dh.to_mechanism(table, layout)
    Q, T_ref = ref_samples(arm)
    assert Q.shape[0] == 21
    T = compose_chain(mech, Q)
    assert np.abs(T - T_ref).max() <= 1e-12
    assert np.abs(dh.chain_pose(mech, Q) - T_ref).max() <= 1e-12
    assert np.abs(plain_forward(table, Q) - T_ref).max() <= 1e-12


def test_panda_tool_and_base_are_part_of_the_comparison(reference):
    arm = reference["Panda"]
    mech = dh.to_mechanism(ref_table(arm, "Panda"))
    Q, T_ref = ref_samples(arm)
    assert np.abs(np.array(arm["tool"]) - np.eye(4)).max() > 0.1
    without_tool = dh.chain_pose(mech, Q, tool=None)
    assert np.abs(without_tool - T_ref).max() > 0.05     # the tool matters ...
    moved = dataclasses.replace(mech, T_world_base=compose(trans_x(0.5), rot_z(0.3)))
    assert np.abs(dh.chain_pose(moved, Q) - T_ref).max() > 0.1  # ... and so does the base
    np.testing.assert_allclose(dh.chain_pose(moved, Q), compose(trans_x(0.5), rot_z(0.3)) @ T_ref,
                               atol=1e-12)


@pytest.mark.parametrize("name", ARMS)
def test_naive_composition_gives_wrong_poses(reference, name):
    """Multiplying the SU frame after the pair rotation (M(q) . P2, or P1 . M(q) . P2 without
    the inverse) is not the pair rule of 5.4.18; it must be visibly wrong."""
    arm = reference[name]
    mech = dh.to_mechanism(ref_table(arm, name))
    Q, T_ref = ref_samples(arm)
    tool = mech.link(f"link{len(mech.pairs)}").frames["tool"]
    naive_a = naive_b = mech.T_world_base
    for k, p in enumerate(mech.pairs):
        M = p.motion(Q[:, k:k + 1])
        naive_a = naive_a @ M @ p.P2
        naive_b = naive_b @ p.P1 @ M @ p.P2
    assert np.abs(naive_a @ tool - T_ref).max() > 0.1
    assert np.abs(naive_b @ tool - T_ref).max() > 0.1
    assert np.abs(compose_chain(mech, Q) - T_ref).max() <= 1e-12


@pytest.mark.parametrize("name", ARMS)
def test_link_frames_are_the_dh_frames_and_initial_state_is_zero(reference, name):
    arm = reference[name]
    table = ref_table(arm, name)
    mech = dh.to_mechanism(table)
    n = len(table.joints)
    assert mech.link_names == tuple(f"link{k}" for k in range(n + 1)) and mech.base == "link0"
    assert mech.pair_names == tuple(j.name for j in table.joints)
    assert dict(mech.initial) == {j.name: (0.0,) for j in table.joints}
    Q, _ = ref_samples(arm)
    T = np.broadcast_to(np.eye(4), (len(Q), 4, 4))
    for k, (p, j) in enumerate(zip(mech.pairs, table.joints)):
        T = T @ p.transform(Q[:, k:k + 1])
        A = plain_dh(table.convention, j.a, j.alpha, j.d, Q[:, k] + j.offset)
        if k == 0:
            want = A
        else:
            want = want @ A
        np.testing.assert_allclose(T, want, atol=1e-13)          # T_link0_linkk = A_1 ... A_k
    for p in mech.pairs:                                          # frames are their su_parameters
        assert np.abs(su_parameters(*p.params["su_1"]) - p.P1).max() == 0.0
        assert np.abs(su_parameters(*p.params["su_2"]) - p.P2).max() == 0.0


@pytest.mark.parametrize("layout", ["1996", "ap242"])
@pytest.mark.parametrize("name", ARMS)
def test_to_dh_round_trip_reproduces_the_table(reference, name, layout):
    table = ref_table(reference[name], name)
    back = dh.from_mechanism(dh.to_mechanism(table, layout), table.convention)
    same_rows(table, back)
    np.testing.assert_array_equal(back.base, table.base)
    np.testing.assert_array_equal(back.tool, table.tool)


# ------------------------------------------------------------------ prismatic joints and offsets

def small_arm(convention: str) -> dh.DHTable:
    joints = [dh.DHJoint("J1", "R", 0.1, 0.7, d=0.3, offset=0.4),
              dh.DHJoint("slide", "P", -0.2, -1.1, theta=2.5, offset=0.15, lower=-0.1, upper=0.4),
              dh.DHJoint("J3", "R", 0.05, 3.0, d=-0.1, offset=-2.9, lower=-1.0, upper=2.0),
              dh.DHJoint("lift", "P", 0.0, 0.0, theta=-0.3, offset=0.0)]
    base = compose(trans_x(0.3), trans_z(0.5), rot_z(1.0), rot_x(0.2))
    tool = compose(rot_y(0.3), trans_x(0.1), trans_z(0.2))
    return dh.DHTable(convention, joints, base, tool, name="rprp")


@pytest.mark.parametrize("layout", ["1996", "ap242"])
@pytest.mark.parametrize("convention", dh.CONVENTIONS)
def test_prismatic_joints_and_offsets_match_the_plain_dh_product(convention, layout):
    table = small_arm(convention)
    mech = dh.to_mechanism(table, layout)
    Q = np.random.default_rng(3).uniform(-2, 2, (50, 4))
    want = plain_forward(table, Q)
    np.testing.assert_allclose(compose_chain(mech, Q), want, atol=1e-13)
    np.testing.assert_allclose(dh.forward(table, Q), want, atol=1e-13)
    slide = mech.pair("slide")
    assert slide.kind == "prismatic" and slide.params["layout"] == layout
    # AP242's prismatic pair slides along x of its frames, the 1996 one along z
    axis = 0 if layout == "ap242" else 2
    np.testing.assert_allclose(slide.motion([0.25])[:3, 3], 0.25 * np.eye(3)[axis], atol=0)
    assert (slide.lower, slide.upper) == ((-0.1,), (0.4,))
    same_rows(table, dh.from_mechanism(mech, convention))
    back = dh.from_mechanism(mech, convention)
    assert [(j.lower, j.upper) for j in back.joints] == [(j.lower, j.upper) for j in table.joints]


def test_offsets_shift_the_zero_of_the_joint_variable():
    j0 = dh.DHJoint("J", "R", 0.2, 0.5, d=0.1, offset=0.0)
    j1 = dataclasses.replace(j0, offset=0.3)
    m0 = dh.to_mechanism(dh.DHTable("standard", [j0]))
    m1 = dh.to_mechanism(dh.DHTable("standard", [j1]))
    np.testing.assert_allclose(m1.pairs[0].transform([0.0]), m0.pairs[0].transform([0.3]), atol=1e-15)
    p0 = dh.DHJoint("S", "P", 0.2, 0.5, theta=0.1, offset=0.0)
    m0 = dh.to_mechanism(dh.DHTable("modified", [p0]))
    m1 = dh.to_mechanism(dh.DHTable("modified", [dataclasses.replace(p0, offset=0.05)]))
    np.testing.assert_allclose(m1.pairs[0].transform([0.0]), m0.pairs[0].transform([0.05]), atol=1e-15)


# ------------------------------------------------------------------ what is not a DH chain

def _replace_pair(mech, name, **changes):
    return dataclasses.replace(mech, pairs=tuple(dataclasses.replace(p, **changes) if p.name == name else p
                                                 for p in mech.pairs))


@pytest.mark.parametrize("convention", dh.CONVENTIONS)
def test_non_dh_placements_name_the_pair(convention):
    mech = dh.to_mechanism(small_arm(convention))
    # the pair axis tilted away from the DH axis
    p3 = mech.pair("J3")
    if convention == "standard":
        bad = _replace_pair(mech, "J3", P1=rot_x(0.2) @ p3.P1)
    else:
        bad = _replace_pair(mech, "J3", P2=rot_x(0.2) @ p3.P2)
    with pytest.raises(dh.DHConversionError) as e:
        dh.from_mechanism(bad, convention)
    assert e.value.pair == "J3" and "'J3'" in str(e.value) and "axis" in str(e.value)
    # link frames that are not DH frames: shift link 3's frame along its own y axis
    shift = compose(trans_x(0.0), np.array([[1, 0, 0, 0], [0, 1, 0, 0.05], [0, 0, 1, 0], [0, 0, 0, 1.0]]))
    bad = _replace_pair(mech, "J3", P2=shift @ p3.P2)
    with pytest.raises(dh.DHConversionError) as e:
        dh.from_mechanism(bad, convention)
    assert e.value.pair == "J3"
    # the other convention does not fit this arm
    other = "modified" if convention == "standard" else "standard"
    with pytest.raises(dh.DHConversionError) as e:
        dh.from_mechanism(mech, other)
    assert e.value.pair == "J1"


def test_chains_that_are_not_serial_or_not_r_p_are_refused():
    mech = dh.to_mechanism(small_arm("standard"))
    sph = _replace_pair(mech, "J3", kind="spherical", lower=(), upper=(), params={})
    with pytest.raises(dh.DHConversionError) as e:
        dh.from_mechanism(sph, "standard")
    assert e.value.pair == "J3" and "spherical" in str(e.value)
    I = np.eye(4)
    branch = dataclasses.replace(mech, pairs=mech.pairs + (Pair("extra", "revolute", "link1", "link4", I, I),))
    with pytest.raises(dh.DHConversionError) as e:
        dh.serial_chain(branch)
    assert e.value.pair == "extra"
    loop = dataclasses.replace(mech, pairs=mech.pairs + (Pair("close", "revolute", "link4", "link0", I, I),))
    with pytest.raises(dh.DHConversionError) as e:
        dh.from_mechanism(loop, "standard")
    assert "loop" in str(e.value)


def test_reversed_pair_is_walked_but_must_still_be_a_dh_row():
    table = small_arm("standard")
    mech = dh.to_mechanism(table)
    p = mech.pair("J3")
    rev = _replace_pair(mech, "J3", link1=p.link2, link2=p.link1, P1=p.P2, P2=p.P1, lower=(-2.0,), upper=(1.0,))
    Q = np.random.default_rng(5).uniform(-2, 2, (10, 4))
    Qr = Q * (1, 1, -1, 1)
    np.testing.assert_allclose(dh.chain_pose(rev, Qr), plain_forward(table, Q), atol=1e-13)
    with pytest.raises(dh.DHConversionError) as e:   # it turns the other way about z_(k-1)
        dh.from_mechanism(rev, "standard")
    assert e.value.pair == "J3"


# ------------------------------------------------------------------ reading and writing tables

PUMA_CSV = """name,type,a,alpha,d,theta,offset
J1,R,0,pi/2,0.67183,,0
J2,R,0.4318,0,0,0,0
J3,R,0.0203,-pi/2,0.15005,0,0
J4,R,0,pi/2,0.4318,0,0
J5,R,0,-pi/2,0,0,0
J6,R,0,0,0,0,0
"""


def test_csv_reads_pi_forms_and_matches_the_reference(reference):
    table = dh_table.read_csv(PUMA_CSV, "standard", source="puma.csv")
    Q, T_ref = ref_samples(reference["Puma560"])
    assert np.abs(dh.chain_pose(dh.to_mechanism(table), Q) - T_ref).max() <= 1e-12
    assert dh_table._number("-2*pi/3") == -2 * math.pi / 3 and dh_table._number(" 1e-3 ") == 1e-3


def test_csv_in_degrees_equals_radians():
    deg = PUMA_CSV.replace("pi/2", "90")
    t_deg = dh_table.read_csv(deg, "standard", deg=True)
    t_rad = dh_table.read_csv(PUMA_CSV, "standard")
    same_rows(t_rad, t_deg, tol=1e-15)
    # prismatic offsets are lengths: never scaled by --deg
    t = dh_table.read_csv("name,type,a,alpha,d,theta,offset,lower,upper\nS,P,0,90,,45,0.2,-0.1,0.3\n",
                    "standard", deg=True)
    j = t.joints[0]
    assert (j.theta, j.offset, j.lower, j.upper) == (math.pi / 4, 0.2, -0.1, 0.3)


@pytest.mark.parametrize("text, where, words", [
    ("name,type,a,alpha,d,theta,offset\nJ1,R,0,pi/2,zero,0,0\n", "t.csv:2:13:", "d: 'zero' is not a number"),
    ("name,type,a,alpha,d,theta,offset\nJ1,X,0,0,0,0,0\n", "t.csv:2:4:", "type must be R"),
    ("name,type,a,alpha,d,theta,offset\nJ1,R,0,0,0,0.3,0\n", "t.csv:2:12:", "theta must be empty or 0"),
    ("name,type,a,alpha,d,theta,offset\nS,P,0,0,0.5,0,0\n", "t.csv:2:9:", "d must be empty or 0"),
    ("name,type,a,alpha,d,theta,offset\nJ1,R,0,0,0,0,0\nJ1,R,0,0,0,0,0\n", "t.csv:3:1:", "used twice"),
    ("name,type,a,alpha,d,theta,offset\nJ1,R,0,0,0\n", "t.csv:2:", "5 fields, the header has 7"),
    ("# c\nname,type,a,alpha,d,theat,offset\n", "t.csv:2:21:", "unknown column 'theat'"),
    ("name,type,a,alpha,d,offset\nJ1,R,0,0,0,0\n", "t.csv:1:1:", "lacks column(s) theta"),
    ("name,type,a,alpha,d,theta,offset\n", "t.csv:1:1:", "no joints"),
    ("name,type,a,alpha,d,theta,offset\nJ1,R,,0,0,0,0\n", "t.csv:2:6:", "a is missing"),
    ("name,type,a,alpha,d,theta,offset,lower,upper\nJ1,R,0,0,0,0,0,1,-1\n", "t.csv:2:", "above the upper"),
    ('name,type,a,alpha,d,theta,offset\n"J1,R,0,0,0,0,0\n', "t.csv:2:1:", "unterminated"),
])
def test_bad_csv_names_file_line_and_column(text, where, words):
    with pytest.raises(dh_table.DHTableError) as e:
        dh_table.read_csv(text, "standard", source="t.csv")
    msg = str(e.value)
    assert msg.startswith(where) and words in msg, msg


def test_quoted_names_round_trip_through_csv():
    table = dh.DHTable("modified", [dh.DHJoint('wrist, "roll"', "R", 0.1, 0.2, d=0.3, offset=-0.4),
                                    dh.DHJoint("slide", "P", 0.0, -0.5, theta=1.0, offset=0.25, upper=1.0)])
    buf = io.StringIO()
    dh_table.write_csv(table, buf)
    back = dh_table.read_csv(buf.getvalue(), "modified")
    assert back.joints == table.joints


def test_json_table_round_trip_and_errors():
    table = small_arm("modified")
    for deg in (False, True):
        buf = io.StringIO()
        dh_table.write_json(table, buf, deg=deg)
        back = dh_table.read_json(buf.getvalue(), source="t.json")
        same_rows(table, back, tol=1e-14)
        np.testing.assert_array_equal(back.base, table.base)
        np.testing.assert_array_equal(back.tool, table.tool)
    text = buf.getvalue()
    with pytest.raises(dh_table.DHTableError, match=r"^t.json:/convention: the file says convention 'modified'"):
        dh_table.read_json(text, "standard", source="t.json")
    obj = json.loads(text)
    del obj["convention"]
    with pytest.raises(dh_table.DHTableError, match="no DH convention"):
        dh_table.read_json(json.dumps(obj), None, source="t.json")
    assert dh_table.read_json(json.dumps(obj), "modified").convention == "modified"
    obj["tool"][0][0] = 2.0
    with pytest.raises(dh_table.DHTableError, match=r"^t.json:/tool: not a rigid transform"):
        dh_table.read_json(json.dumps(obj), "modified", source="t.json")
    obj = json.loads(text)
    obj["joints"][2]["alpha"] = "abc"
    with pytest.raises(dh_table.DHTableError, match=r"^t.json:/joints/2/alpha: joint 'J3': alpha: 'abc'"):
        dh_table.read_json(json.dumps(obj), source="t.json")


def test_looks_like_dh():
    assert dh_table.looks_like_dh(PUMA_CSV) == "csv"
    assert dh_table.looks_like_dh("# comment\n\nName,Type,a\n") == "csv"
    assert dh_table.looks_like_dh('{"joints": []}') == "json"
    assert dh_table.looks_like_dh('{"format": "p105/1", "data": []}') is None
    assert dh_table.looks_like_dh("hello world") is None
    assert dh_table.looks_like_dh("ISO-10303-21;\nHEADER;") is None


def test_examples_are_the_reference_arms(reference):
    puma = dh_table.read_csv((EXAMPLES / "puma560_dh.csv").read_text(), "standard")
    Q, T_ref = ref_samples(reference["Puma560"])
    assert np.abs(dh.chain_pose(dh.to_mechanism(puma), Q) - T_ref).max() <= 1e-12
    assert all(j.lower is not None and j.lower <= 0.0 <= j.upper for j in puma.joints)
    panda = dh_table.read_json((EXAMPLES / "panda_dh.json").read_text())
    Q, T_ref = ref_samples(reference["Panda"])
    assert panda.convention == "modified"
    assert np.abs(dh.chain_pose(dh.to_mechanism(panda), Q) - T_ref).max() <= 1e-12


# ------------------------------------------------------------------ the command

def _cli(*args) -> int:
    from p105cli.cli import main
    return main([str(a) for a in args])


def _read_model(path):
    from p105cli.part105.read_mechanism import read_mechanism
    from p105cli.step import read_any
    return read_mechanism(read_any(path.read_text(), str(path)))


@pytest.mark.parametrize("name", ARMS)
def test_converted_files_validate_clean_and_reproduce_the_reference_poses(reference, name, tmp_path,
                                                                          capsys):
    """Through the file: table -> convert-dh-su -> Part 21 -> validate (exit 0) -> reader ->
    composed poses = the reference poses (base and tool included), for ap242, p105 and ap214."""
    arm = reference[name]
    table = ref_table(arm, name)
    src = tmp_path / f"{name}.json"
    with open(src, "w") as fh:
        dh_table.write_json(table, fh)
    Q, T_ref = ref_samples(arm)
    for schema in ("ap242", "p105", "ap214"):
        out = tmp_path / f"{name}_{schema}.stp"
        assert _cli("convert-dh-su", "--schema", schema, src, "-o", out) == 0
        assert _cli("validate", "--schema", schema, out, "-o", tmp_path / "report.txt") == 0, \
            (tmp_path / "report.txt").read_text()
        assert "0 errors, 0 warnings" in (tmp_path / "report.txt").read_text()
        text = out.read_text()
        assert ("SU_PARAMETERS(" in text) == (schema != "ap214")
        mech = _read_model(out)
        assert [p.name for p, _ in dh.serial_chain(mech)] == [j.name for j in table.joints]
        assert np.abs(dh.chain_pose(mech, Q) - T_ref).max() <= 1e-12, schema
        back = tmp_path / "back.json"
        assert _cli("convert-dh-su", "--convention", table.convention, "--to", "dh-json", out,
                    "-o", back) == 0
        again = dh_table.read_json(back.read_text())
        same_rows(table, again, tol=1e-12)
        np.testing.assert_allclose(again.tool, table.tool, atol=1e-15)
    assert capsys.readouterr().err == ""


def test_cli_json_output_is_the_same_model(tmp_path):
    csv = EXAMPLES / "puma560_dh.csv"
    assert _cli("convert-dh-su", "--convention", "standard", "--to", "json", csv, "-o", tmp_path / "m.json") == 0
    assert _cli("convert-dh-su", "--convention", "standard", csv, "-o", tmp_path / "m.stp") == 0
    assert _cli("export", "--to", "p21", tmp_path / "m.json", "-o", tmp_path / "m2.stp") == 0
    assert (tmp_path / "m2.stp").read_bytes() == (tmp_path / "m.stp").read_bytes()


@pytest.mark.parametrize("convention, schema", [("standard", "ap242"), ("modified", "p105"),
                                                ("modified", "ap242"), ("standard", "ap214")])
def test_cli_prismatic_arm_through_the_file_and_back_to_dh_csv(convention, schema, tmp_path, capsys):
    src = tmp_path / "rprp.json"
    table = small_arm(convention)
    with open(src, "w") as fh:
        dh_table.write_json(table, fh)
    out = tmp_path / "m.stp"
    assert _cli("convert-dh-su", "--schema", schema, src, "-o", out) == 0
    assert _cli("validate", "--schema", schema, out, "-o", tmp_path / "report.txt") == 0
    Q = np.random.default_rng(4).uniform(-1, 1, (20, 4))
    np.testing.assert_allclose(dh.chain_pose(_read_model(out), Q), plain_forward(table, Q), atol=1e-13)
    assert _cli("convert-dh-su", "--convention", convention, "--to", "dh", out, "-o", tmp_path / "t.csv") == 0
    err = capsys.readouterr().err
    assert "CSV cannot hold it" in err                # base and tool are not identities
    back = dh_table.read_csv((tmp_path / "t.csv").read_text(), convention)
    same_rows(table, back)
    for j, k in zip(back.joints, table.joints):
        for x, y in ((j.lower, k.lower), (j.upper, k.upper)):
            assert (x is None and y is None) or abs(x - y) <= 1e-15


def test_cli_deg_equals_radians(tmp_path):
    rad = EXAMPLES / "puma560_dh.csv"
    deg = tmp_path / "puma_deg.csv"
    lines = []
    for line in rad.read_text().splitlines():
        if line.startswith("J"):
            f = line.split(",")
            f[3] = repr(math.degrees(dh_table._number(f[3])))
            f[7], f[8] = (repr(math.degrees(float(x))) for x in f[7:9])
            line = ",".join(f)
        lines.append(line)
    deg.write_text("\n".join(lines) + "\n")
    assert _cli("convert-dh-su", "--convention", "standard", "--deg", deg, "-o", tmp_path / "d.stp") == 0
    assert _cli("convert-dh-su", "--convention", "standard", rad, "-o", tmp_path / "r.stp") == 0
    m_deg, m_rad = _read_model(tmp_path / "d.stp"), _read_model(tmp_path / "r.stp")
    Q = np.random.default_rng(2).uniform(-2, 2, (10, 6))
    np.testing.assert_allclose(dh.chain_pose(m_deg, Q), dh.chain_pose(m_rad, Q), atol=1e-14)
    assert m_deg.pair("J2").upper[0] == pytest.approx(3.9269908169872414, abs=1e-15)
    # --deg on the way out writes degrees
    assert _cli("convert-dh-su", "--convention", "standard", "--to", "dh", "--deg", tmp_path / "r.stp",
                "-o", tmp_path / "t.csv") == 0
    row = (tmp_path / "t.csv").read_text().splitlines()[1].split(",")
    assert float(row[3]) == pytest.approx(90.0, abs=1e-12)


def test_cli_usage_and_input_errors(tmp_path, capsys):
    csv = EXAMPLES / "puma560_dh.csv"
    assert _cli("convert-dh-su", csv) == 2                              # no silent default
    assert "--convention standard|modified is required" in capsys.readouterr().err
    bad = tmp_path / "bad.csv"
    bad.write_text("name,type,a,alpha,d,theta,offset\nJ1,R,0,pi/2,0.3,,0\nJ2,R,0.4,0,0,1.0,0\n")
    assert _cli("convert-dh-su", "--convention", "standard", bad) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"p105: error: {bad}:3:14: joint 'J2' is revolute") and "Traceback" not in err
    js = tmp_path / "panda.json"
    js.write_text((EXAMPLES / "panda_dh.json").read_text())
    assert _cli("convert-dh-su", "--convention", "standard", js) == 2   # the file says modified
    assert f"{js}:/convention:" in capsys.readouterr().err
    assert _cli("convert-dh-su", "--convention", "standard", EXAMPLES / "four_bar_ap242.stp") == 2
    assert "is a model" in capsys.readouterr().err
    assert _cli("convert-dh-su", "--convention", "standard", "--to", "dh", csv) == 2
    assert "is a DH table" in capsys.readouterr().err


def test_cli_names_the_pair_that_is_not_a_dh_row(tmp_path, capsys):
    assert _cli("convert-dh-su", "--convention", "standard", "--to", "dh",
                EXAMPLES / "four_bar_ap242.stp") == 1
    assert "closes a loop" in capsys.readouterr().err
    assert _cli("convert-dh-su", EXAMPLES / "panda_dh.json", "-o", tmp_path / "panda.stp") == 0
    assert _cli("convert-dh-su", "--convention", "standard", "--to", "dh", tmp_path / "panda.stp") == 1
    err = capsys.readouterr().err
    assert "pair 'J2' (link1 -> link2)" in err and "not a standard DH row" in err


# ------------------------------------------------------------------ property: any table round trips

_len = st.floats(-2.0, 2.0, allow_nan=False)
_ang = st.floats(-math.pi, math.pi, allow_nan=False)
_joint = st.tuples(st.sampled_from("RP"), _len, _ang, _len, _ang, st.floats(-1.0, 1.0, allow_nan=False))


@settings(max_examples=60, deadline=None)
@given(st.sampled_from(dh.CONVENTIONS), st.sampled_from(["1996", "ap242"]),
       st.lists(_joint, min_size=1, max_size=5))
def test_any_table_converts_and_round_trips(convention, layout, rows):
    joints = [dh.DHJoint(f"J{k}", t, a, alpha, d=d if t == "R" else 0.0, theta=th if t == "P" else 0.0,
                         offset=off)
              for k, (t, a, alpha, d, th, off) in enumerate(rows)]
    table = dh.DHTable(convention, joints, compose(trans_x(0.2), rot_y(0.4)), rot_x(-0.7))
    mech = dh.to_mechanism(table, layout)
    Q = np.random.default_rng(len(rows)).uniform(-2, 2, (6, len(rows)))
    np.testing.assert_allclose(dh.chain_pose(mech, Q), plain_forward(table, Q), atol=1e-12)
    same_rows(table, dh.from_mechanism(mech, convention), tol=1e-12)
