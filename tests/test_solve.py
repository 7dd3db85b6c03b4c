"""p105 solve: forward analysis of trees and loops, inverse analysis, the CLI.

Independent truth: the shared reference file (DH arms from roboticstoolbox,
cross-checked with Pinocchio; the four-bar in closed form on both
branches), finite differences for the analytic Jacobians, and a plain DH
product written here for the inverse analysis.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from conftest import EXAMPLES, ROOT, SHARED
from p105cli.kinematics import solver
from p105cli.kinematics.model import Link, Mechanism, Pair
from p105cli.kinematics.placements import compose, inverse, rot_x, rot_z, su_parameters, trans_x, trans_z

REFERENCE = SHARED / "reference" / "dh_arms_and_loops.json"
I4 = np.eye(4)


@pytest.fixture(scope="module")
def ref():
    if not REFERENCE.exists():
        pytest.skip("shared reference data not available")
    return json.loads(REFERENCE.read_text())


# ---------------------------------------------------------------- builders (also used by test_solve_hard)

def four_bar(a, b, c, d, t2, t3, t4, *, driven="A", scale=1.0, name="four_bar"):
    """Planar four-bar: A (frame-crank) at the origin, D (frame-rocker) at (d, 0); link frames at
    A, B, D; link angles theta2 (crank), theta3 (coupler), theta4 (rocker) from +x.
    Values: A = theta2, B = theta3 - theta2, C = theta4 - theta3, D = theta4."""
    a, b, c, d = (scale * x for x in (a, b, c, d))
    links = [Link(n) for n in ("frame", "crank", "coupler", "rocker")]
    pairs = [Pair("A", "revolute", "frame", "crank", I4, I4, actuated=driven == "A"),
             Pair("B", "revolute", "crank", "coupler", trans_x(a), I4),
             Pair("C", "revolute", "coupler", "rocker", trans_x(b), trans_x(c)),
             Pair("D", "revolute", "frame", "rocker", trans_x(d), I4, actuated=driven == "D")]
    init = {"A": (t2,), "B": (t3 - t2,), "C": (t4 - t3,), "D": (t4,)}
    return Mechanism(name, links, pairs, "frame", initial=init)


def link_angles(result):
    """theta2, theta3, theta4 of the four-bar from the solved values."""
    Q = result.Q
    return Q[:, 0], Q[:, 0] + Q[:, 1], Q[:, 3]


def wrap(x):
    return np.remainder(np.asarray(x) + np.pi, 2 * np.pi) - np.pi


def dh_mechanism(arm, *, su=True):
    """A serial arm from its DH table: links L0..Ln, revolute pairs J1..Jn.

    Standard DH ``A = Rz(theta) Tz(d) Tx(a) Rx(alpha)``: the pair frame on link j-1
    is its link frame, the one on link j is the inverse of the DH transform without
    the pair value (Annex F; with ``su`` built from Sheth-Uicker parameters
    a=a, alpha=alpha, b=-d, beta=pi, c=0, gamma=pi). Modified DH
    ``A = Rx(alpha) Tx(a) Rz(theta) Tz(d)``: P1 = Rx(alpha) Tx(a), P2 = Tz(-d).
    ``naive`` builds the wrong composition (SU frame multiplied after the pair
    rotation) that the convention must not regress to."""
    n = arm["n_joints"]
    links = [Link(f"L{j}") for j in range(n + 1)]
    if arm.get("tool") is not None:
        links[-1] = Link(f"L{n}", frames={"tool": np.array(arm["tool"])})
    pairs = []
    for j, row in enumerate(arm["dh"], 1):
        a, alpha, d, off = row["a"], row["alpha"], row["d"], row["offset"]
        if arm["convention"] == "standard":
            if su:
                P2 = su_parameters(a, alpha, -d, math.pi, 0.0, math.pi)
            else:
                P2 = inverse(compose(trans_z(d), trans_x(a), rot_x(alpha)))
            P1 = rot_z(off)
        else:
            P1 = compose(rot_x(alpha), trans_x(a), rot_z(off))
            P2 = inverse(trans_z(d))
        pairs.append(Pair(f"J{j}", "revolute", f"L{j - 1}", f"L{j}", P1, P2, actuated=True))
    return Mechanism(arm["description"], links, pairs, "L0", T_world_base=np.array(arm["base"]))


def end_pose(mech, result, arm):
    pl = result.plan
    T = result.links()[:, pl.link_index[f"L{arm['n_joints']}"]]
    return T @ np.array(arm["tool"]) if arm.get("tool") is not None else T


# ---------------------------------------------------------------- forward analysis of trees

@pytest.mark.parametrize("name", ["Puma560", "UR5", "Panda"])
def test_dh_arms_reproduce_the_reference_poses(ref, name):
    arm = ref["arms"][name]
    mech = dh_mechanism(arm)
    q = np.array([s["q"] for s in arm["samples"]])
    driven = {f"J{j + 1}": q[:, j] for j in range(arm["n_joints"])}
    result = solver.solve_motion(mech, driven)
    T = end_pose(mech, result, arm)
    want = np.array([s["T"] for s in arm["samples"]])
    assert np.abs(T - want).max() < 1e-12
    assert result.status.count("ok") + result.status.count("out_of_range") == len(q)


def test_plain_pair_frames_and_su_frames_agree(ref):
    arm = ref["arms"]["Puma560"]
    q = np.array([s["q"] for s in arm["samples"]])
    driven = {f"J{j + 1}": q[:, j] for j in range(6)}
    a = solver.solve_motion(dh_mechanism(arm, su=True), driven).links()
    b = solver.solve_motion(dh_mechanism(arm, su=False), driven).links()
    assert np.abs(a - b).max() < 1e-14


def test_naive_composition_fails(ref):
    # T = Rz(q) @ SU (the SU frame multiplied after the pair rotation) is not the Part 105 rule.
    arm = ref["arms"]["Puma560"]
    q = np.array([s["q"] for s in arm["samples"]])
    T = np.broadcast_to(np.eye(4), (len(q), 4, 4)).copy()
    for j, row in enumerate(arm["dh"]):
        su = su_parameters(row["a"], row["alpha"], -row["d"], math.pi, 0.0, math.pi)
        T = T @ rot_z(q[:, j]) @ su
    want = np.array([s["T"] for s in arm["samples"]])
    assert np.abs(T - want).max() > 1e-2


def test_forward_is_batched_and_matches_single_calls(ref):
    arm = ref["arms"]["UR5"]
    mech = dh_mechanism(arm)
    pl = solver.plan(mech)
    rng = np.random.default_rng(1)
    Q = rng.uniform(-3, 3, (50, 6))
    batch = solver.forward(pl, Q)
    one = np.array([solver.forward(pl, Q[i:i + 1])[0] for i in range(50)])
    assert np.array_equal(batch, one)


def test_forward_mixed_tree_over_several_blocks_matches_a_plain_product():
    # Revolute pairs forward and crossed backwards, with pair frames that do and do not commute
    # with the joint rotation, a prismatic pair, and more configurations than one block of the
    # batched evaluation: against the Part 105 product P1 M(q) P2^-1 written out per configuration.
    from p105cli.kinematics.placements import transform, ypr_rotation

    rng = np.random.default_rng(11)

    def rnd():
        return transform(ypr_rotation(*rng.uniform(-2, 2, 3)), rng.uniform(-0.5, 0.5, 3))

    zc = compose(rot_z(0.3), trans_z(0.2))            # a rotation about z and a shift along z
    links = [Link(n) for n in "abcdef"]
    pairs = [Pair("p1", "revolute", "a", "b", rnd(), rnd()),
             Pair("p2", "revolute", "c", "b", rnd(), zc),      # crossed backwards (b -> c)
             Pair("p3", "revolute", "b", "d", zc, rnd()),
             Pair("p4", "prismatic", "d", "e", rnd(), rnd()),
             Pair("p5", "revolute", "f", "e", zc, rnd())]      # backwards, P2 generic
    mech = Mechanism("mixed", links, pairs, "a", T_world_base=rnd())
    pl = solver.plan(mech)
    n = 2 * 4096 + 37
    Q = rng.uniform(-3, 3, (n, mech.value_count))
    got = solver.forward(pl, Q)
    pick = np.r_[0:5, 4090:4100, n - 5:n]
    prism = pl.types[3]
    for b in pick:
        q = Q[b]
        M = [rot_z(q[0]), rot_z(q[1]), rot_z(q[2]), prism.motion(q[3:4][None], **pl.params[3])[0], rot_z(q[4])]
        A = [p.P1 @ m @ inverse(p.P2) for p, m in zip(pairs, M)]
        want = {"a": mech.T_world_base}
        want["b"] = want["a"] @ A[0]
        want["c"] = want["b"] @ inverse(A[1])
        want["d"] = want["b"] @ A[2]
        want["e"] = want["d"] @ A[3]
        want["f"] = want["e"] @ inverse(A[4])
        for name, T in want.items():
            assert np.abs(got[b, pl.link_index[name]] - T).max() < 1e-13, (b, name)
    assert np.isfinite(got).all()
    assert np.array_equal(got[pick], solver.forward(pl, Q[pick]))


# ---------------------------------------------------------------- closed loops: the reference four-bar

def _reference_four_bar(fb, branch, *, scale=1.0):
    s0 = fb["samples"][0]["branches"][branch]
    # The initial state only roughly on the branch (whole degrees): the solver assembles it.
    r = lambda x: round(math.degrees(x)) * math.pi / 180.0
    return four_bar(fb["a_crank"], fb["b_coupler"], fb["c_rocker"], fb["d_ground"],
                    0.0, r(s0["theta3_rad"]), r(s0["theta4_rad"]), scale=scale)


@pytest.mark.parametrize("branch", ["open", "crossed"])
def test_four_bar_matches_the_closed_form_on_the_initial_branch(ref, branch):
    fb = ref["closed_loop"]["fourbar"][0]
    mech = _reference_four_bar(fb, branch)
    th = np.array([s["theta2_rad"] for s in fb["samples"]])
    result = solver.solve_motion(mech, {"A": th}, tol=1e-13)
    assert result.status == ["ok"] * len(th)
    t2, t3, t4 = link_angles(result)
    want3 = np.array([s["branches"][branch]["theta3_rad"] for s in fb["samples"]])
    want4 = np.array([s["branches"][branch]["theta4_rad"] for s in fb["samples"]])
    assert np.abs(wrap(t3 - want3)).max() < 1e-12
    assert np.abs(wrap(t4 - want4)).max() < 1e-12
    # The branch tag of the reference (side of C relative to B->D) is the same at every sample.
    links = result.links()
    pl = result.plan
    Bw = links[:, pl.link_index["coupler"], :2, 3]
    Cw = Bw + fb["b_coupler"] * np.stack([np.cos(t3), np.sin(t3)], axis=1)
    Dw = np.array([fb["d_ground"], 0.0])
    u, v = Dw - Bw, Cw - Bw
    sigma = np.sign(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    assert set(sigma) == {fb["samples"][0]["branches"][branch]["sigma_side_of_BD"]}
    # and the solver's own branch invariant never changed sign
    assert len(set(result.branch)) == 1


def test_loop_jacobian_matches_finite_differences(ref):
    fb = ref["closed_loop"]["fourbar"][0]
    mech = _reference_four_bar(fb, "open")
    pl = solver.plan(mech)
    rng = np.random.default_rng(7)
    Q = rng.uniform(-2, 2, (3, 4))
    r, J = solver.closure(pl, Q)
    h = 1e-6
    for k in range(4):
        dq = np.zeros(4)
        dq[k] = h
        fd = (solver.closure(pl, Q + dq, jacobian=False)[0] - solver.closure(pl, Q - dq, jacobian=False)[0]) / (2 * h)
        assert np.abs(fd - J[:, :, k]).max() < 1e-8


def test_conditioning_and_tangent_agree_with_the_svd_near_and_far_from_singular(ref):
    # The continuation's conditioning and tangent skip the SVD where J_u is clearly regular;
    # against numpy's SVD and pseudo-inverse, with Jacobians from regular to rank-deficient.
    fb = ref["closed_loop"]["fourbar"][0]
    pl = solver.plan(_reference_four_bar(fb, "open"))
    u, d = np.array([1, 2, 3]), np.array([0])
    prob = solver._Loops(pl, u, d, np.ones(3), np.ones(1), 1e-12, 30, rank=3)
    rng = np.random.default_rng(5)
    conds = np.r_[1.0, 0.3, 1e-2, 1e-3, np.geomspace(1e-4, 1e-6, 24), 1e-9, 1e-13]
    U = np.linalg.qr(rng.normal(size=(len(conds), 6, 3)))[0]
    V = np.linalg.qr(rng.normal(size=(len(conds), 3, 3)))[0]
    S = np.stack([np.ones_like(conds), np.sqrt(conds), conds], axis=1) * rng.uniform(0.5, 2, (len(conds), 1))
    Ju = U @ (S[:, :, None] * np.swapaxes(V, 1, 2))
    Jd = rng.normal(size=(len(conds), 6, 1))
    cond, T = prob.conditioning_and_tangent(Ju, Jd)
    sv = np.linalg.svd(Ju, compute_uv=False)
    want = sv[:, 2] / sv[:, 0]
    assert np.allclose(want, conds, rtol=1e-6)
    assert list(cond > prob.singular_below) == list(want > prob.singular_below)
    assert np.allclose(cond, want, rtol=1e-4, atol=0)
    regular = want > 1e-8
    pinv = np.linalg.pinv(Ju[regular], rcond=1e-10)
    Tw = -(pinv @ Jd[regular])
    assert np.abs(T[regular] - Tw).max() <= 1e-6 * np.abs(Tw).max()
    assert np.isfinite(T).all()


def test_spatial_loop_jacobian_matches_finite_differences():
    # A loop with spherical, universal, cylindrical and prismatic pairs (not closed: only derivatives).
    rng = np.random.default_rng(3)

    def rnd():
        from p105cli.kinematics.placements import ypr_rotation, transform
        return transform(ypr_rotation(*rng.uniform(-1, 1, 3)), rng.uniform(-0.1, 0.1, 3))

    links = [Link(n) for n in "abcde"]
    pairs = [Pair("p1", "spherical", "a", "b", rnd(), rnd()),
             Pair("p2", "universal", "b", "c", rnd(), rnd()),
             Pair("p3", "cylindrical", "d", "c", rnd(), rnd()),
             Pair("p4", "prismatic", "d", "e", rnd(), rnd()),
             Pair("p5", "revolute", "a", "e", rnd(), rnd())]
    mech = Mechanism("spatial", links, pairs, "a")
    pl = solver.plan(mech)
    Q = rng.uniform(-1, 1, (2, mech.value_count))
    r, J = solver.closure(pl, Q)
    h = 1e-6
    for k in range(mech.value_count):
        dq = np.zeros(mech.value_count)
        dq[k] = h
        fd = (solver.closure(pl, Q + dq, jacobian=False)[0] - solver.closure(pl, Q - dq, jacobian=False)[0]) / (2 * h)
        assert np.abs(fd - J[:, :, k]).max() < 1e-7


def test_ranges_are_reported_per_configuration(ref):
    fb = ref["closed_loop"]["fourbar"][0]
    s0 = fb["samples"][0]["branches"]["open"]
    mech = _reference_four_bar(fb, "open")
    D = mech.pair("D")
    limited = Pair("D", "revolute", "frame", "rocker", D.P1, D.P2, lower=(2.0,), upper=(2.4,))
    mech = Mechanism("fb", mech.links, [*mech.pairs[:3], limited], "frame", initial=mech.initial)
    th = np.array([s["theta2_rad"] for s in fb["samples"]])
    result = solver.solve_motion(mech, {"A": th}, tol=1e-12)
    want4 = np.array([s["branches"]["open"]["theta4_rad"] for s in fb["samples"]])
    inside = (want4 >= 2.0) & (want4 <= 2.4)
    assert [s == "ok" for s in result.status] == list(inside)
    assert all(s in ("ok", "out_of_range") for s in result.status)
    assert s0["theta4_rad"] > 2.0


# ---------------------------------------------------------------- inverse analysis

def _dh_product(arm, q):
    T = np.broadcast_to(np.eye(4), q.shape[:-1] + (4, 4)).copy()
    for j, row in enumerate(arm["dh"]):
        T = T @ compose(rot_z(q[..., j] + row["offset"]), trans_z(row["d"]), trans_x(row["a"]), rot_x(row["alpha"]))
    return T


def test_inverse_analysis_follows_a_path(ref):
    arm = ref["arms"]["Puma560"]
    mech = dh_mechanism(arm)
    s = np.linspace(0.0, 1.0, 40)[:, None]
    q_path = np.array([0.1, 0.5, -0.4, 0.3, 0.8, -0.2]) + s * np.array([0.6, -0.3, 0.2, -0.5, 0.4, 0.9])
    poses = _dh_product(arm, q_path)
    init = {f"J{j + 1}": (q_path[0, j] + 0.05,) for j in range(6)}
    mech = Mechanism(mech.name, mech.links, mech.pairs, mech.base, T_world_base=mech.T_world_base, initial=init)
    result = solver.solve_path(mech, "L6", poses, tol=1e-12)
    assert set(result.status) <= {"ok", "out_of_range"}
    assert result.position_error.max() < 1e-11 and result.rotation_error.max() < 1e-11
    # Independent check: the plain DH product of the solved values gives the targets.
    q = result.Q
    assert np.abs(_dh_product(arm, q) - poses).max() < 1e-10
    # Warm start: the solution follows the path's own joint motion (no jump to another arm posture).
    assert np.abs(wrap(q - q_path)).max() < 1e-8


def test_inverse_analysis_reports_unreachable_poses(ref):
    arm = ref["arms"]["Puma560"]
    mech = dh_mechanism(arm)
    far = np.eye(4)
    far[:3, 3] = [3.0, 0.0, 0.0]  # beyond the arm's reach (under 1 m)
    result = solver.solve_path(mech, "L6", far[None], tol=1e-10)
    assert result.status == ["not_converged"]
    assert np.isfinite(result.Q).all()
    assert 1.5 < result.position_error[0] < 3.0


# ---------------------------------------------------------------- the CLI

FOUR_BAR_STP = EXAMPLES / "four_bar_ap242.stp"


@pytest.fixture
def cli(p105):
    """Run ``p105 ARGS`` in this process (conftest.p105)."""
    return p105


def _records(stdout: bytes):
    return [json.loads(line) for line in stdout.decode().splitlines()]


def test_cli_jsonl_four_bar_example_against_the_closed_form(ref, cli):
    fb = ref["closed_loop"]["fourbar"][0]
    csv = EXAMPLES / "four_bar_crank.csv"
    r = cli("solve", FOUR_BAR_STP, "--values", csv, "--angle-unit", "deg", "--to", "jsonl", "--tol", "1e-13")
    assert r.returncode == 0, r.stderr
    recs = _records(r.stdout)
    conf = [x for x in recs if x["type"] == "configuration"]
    assert recs[-1]["type"] == "summary" and recs[-1]["configurations"] == len(conf)
    rows = [line.split(",") for line in csv.read_text().splitlines()[1:]]
    # The example file is in millimetres with the open branch; the reference is the same linkage in metres.
    for rec, row in zip(conf, rows):
        t2 = math.radians(float(row[1]))
        B = np.array([fb["a_crank"] * math.cos(t2), fb["a_crank"] * math.sin(t2)])
        D = np.array([fb["d_ground"], 0.0])
        BD = D - B
        L = np.hypot(*BD)
        along = (fb["b_coupler"] ** 2 - fb["c_rocker"] ** 2 + L * L) / (2 * L)
        C = B + along * BD / L + math.sqrt(fb["b_coupler"] ** 2 - along ** 2) * np.array([-BD[1], BD[0]]) / L
        t4 = math.atan2(C[1], C[0] - fb["d_ground"])
        assert abs(wrap(math.radians(rec["pairs"]["D"]) - t4)) < 1e-11
        assert rec["status"] in ("ok", "out_of_range")
        assert rec["residual"] < 1e-12
        rocker = np.array(rec["links"]["rocker"])
        frame = np.array(rec["links"]["frame"])
        rel = inverse(frame) @ rocker  # rocker frame at D, in the ground link's frame (metres)
        assert np.allclose(rel[:2, 3], [fb["d_ground"], 0.0], atol=1e-12)
        assert abs(wrap(math.atan2(rel[1, 0], rel[0, 0]) - t4)) < 1e-11


def test_cli_csv_and_jsonl_agree_and_are_deterministic(cli):
    csv = EXAMPLES / "four_bar_crank.csv"
    a = cli("solve", FOUR_BAR_STP, "--values", csv, "--angle-unit", "deg", "--to", "csv")
    b = cli("solve", FOUR_BAR_STP, "--values", csv, "--angle-unit", "deg", "--to", "csv")
    j = cli("solve", FOUR_BAR_STP, "--values", csv, "--angle-unit", "deg", "--to", "jsonl")
    assert a.returncode == 0 and a.stdout == b.stdout
    lines = a.stdout.decode().splitlines()
    head = lines[0].split(",")
    conf = [x for x in _records(j.stdout) if x["type"] == "configuration"]
    assert len(lines) - 1 == len(conf)
    for line, rec in zip(lines[1:], conf):
        row = dict(zip(head, line.split(",")))
        assert float(row["C"]) == rec["pairs"]["C"]
        assert float(row["coupler.m03"]) == rec["links"]["coupler"][0][3]


def test_cli_values_from_stdin_with_model_from_file_and_set(p105):
    r = p105("solve", FOUR_BAR_STP, "--values", "-", "--to", "jsonl", input="t,A\n0,0.5\n1,0.6\n")
    assert r.returncode == 0, r.stderr
    conf = [x for x in _records(r.stdout) if x["type"] == "configuration"]
    assert [c["t"] for c in conf] == [0.0, 1.0] and conf[1]["pairs"]["A"] == pytest.approx(0.6, abs=1e-15)
    s = p105("solve", FOUR_BAR_STP, "--set", "A=0.6", "--to", "jsonl")
    assert s.returncode == 0, s.stderr
    one = [x for x in _records(s.stdout) if x["type"] == "configuration"]
    assert one[0]["pairs"] == conf[1]["pairs"]


def test_cli_exit_1_when_a_configuration_cannot_be_assembled(cli):
    # Driving the rocker D beyond its swing (the example's rocker swings 104..154 deg).
    r = cli("solve", FOUR_BAR_STP, "--values", "-", "--angle-unit", "deg", "--to", "jsonl",
                input="D\n130\n175\n130\n")
    assert r.returncode == 1
    conf = [x for x in _records(r.stdout) if x["type"] == "configuration"]
    assert [c["status"] for c in conf][1] == "not_assemblable"
    assert conf[1]["residual"] > 1e-3
    assert b"configuration 1: not_assemblable" in r.stderr


@pytest.mark.parametrize("text, where", [("A\n0\nx\n", "<stdin>:3:1"), ("A,B\n1\n", "<stdin>:2:1"),
                                         ("Q\n1\n", "'Q' is not a pair")])
def test_cli_bad_values_are_exit_2_with_the_place(text, where, cli):
    r = cli("solve", FOUR_BAR_STP, "--values", "-", "--to", "jsonl", input=text)
    assert r.returncode == 2
    assert where.encode() in r.stderr and b"Traceback" not in r.stderr


def test_cli_inverse_analysis_with_a_jsonl_path(ref, tmp_path, cli):
    arm = ref["arms"]["Puma560"]
    from p105cli.part105.write_mechanism import write_mechanism
    from p105cli.step import write_json
    mech = dh_mechanism(arm, su=False)
    q_path = np.array([0.1, 0.5, -0.4, 0.3, 0.8, -0.2]) + np.linspace(0, 1, 5)[:, None] * 0.2
    init = {f"J{j + 1}": (q_path[0, j],) for j in range(6)}
    mech = Mechanism(mech.name, mech.links, mech.pairs, mech.base, initial=init)
    doc, _ = write_mechanism(mech, "ap242")
    model = tmp_path / "puma.json"
    with open(model, "w") as fh:
        write_json(doc, fh)
    poses = _dh_product(arm, q_path)
    path = tmp_path / "path.jsonl"
    path.write_text("".join(json.dumps({"t": i * 0.1, "pose": poses[i].tolist()}) + "\n" for i in range(5)))
    r = cli("solve", model, "--path", path, "--target-link", "L6", "--to", "jsonl", "--tol", "1e-12")
    assert r.returncode == 0, r.stderr
    recs = _records(r.stdout)
    conf = [x for x in recs if x["type"] == "configuration"]
    for i, c in enumerate(conf):
        assert c["position_error"] < 1e-11 and c["rotation_error"] < 1e-11
        assert np.abs(np.array(c["links"]["L6"]) - poses[i]).max() < 1e-10
    assert recs[-1]["max_position_error"] < 1e-11


def _four_bar_cable_scene():
    """A cable from the ground link's origin (pivot A) to the coupler's origin (pin B): their
    distance is the crank length (20 mm) in every configuration, so the slack is 1 - 20/80."""
    pose = [[0, 0, 1, 0], [0, 1, 0, 0], [-1, 0, 0, 0], [0, 0, 0, 1]]
    return {"format": "p105-scene/1", "units": {"length": "mm", "force": "N", "mass": "kg", "pressure": "MPa"},
            "gravity": [0, -9810, 0],
            "cables": [{"name": "c1", "length": 80, "density": 1.5e-6,
                        "section": {"radius": 1, "youngs_modulus": 200, "poisson_ratio": 0.4},
                        "start": {"link": "frame", "condition": "clamped", "pose": pose},
                        "end": {"link": "coupler", "condition": "clamped", "pose": pose},
                        "numerics": {"model": "rod", "segments": 20, "tol": 1e-10},
                        "effects": ["shape", "overlength"]}]}


def test_cli_scene_cable_rides_on_the_solved_links(tmp_path, cli):
    scene = _four_bar_cable_scene()
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    r = cli("solve", FOUR_BAR_STP, "--sweep", "A=0:1.5:4", "--scene", path, "--to", "jsonl")
    assert r.returncode == 0, r.stderr
    recs = _records(r.stdout)
    types = [x["type"] for x in recs]
    assert types == ["configuration"] * 4 + ["summary"] + ["cable_state"] * 4 + ["summary"]
    states = [x for x in recs if x["type"] == "cable_state"]
    assert [s["t"] for s in states] == [0.0, 1.0, 2.0, 3.0]
    assert all(abs(s["slack"] - 0.75) < 1e-12 and s["status"] == "ok" for s in states)


@pytest.mark.parametrize("example, sweep", [("four_bar_ap242.stp", "A=0:1.2:4"),
                                            ("slider_crank_p105_1996_ap214.stp", "O=0:1.2:4")])
def test_cli_model_output_validates_and_reads_back(example, sweep, cli, tmp_path):
    src = EXAMPLES / example
    out = tmp_path / "solved.stp"
    r = cli("solve", src, "--sweep", sweep, "-o", out)
    assert r.returncode == 0, r.stderr
    v = cli("validate", out)
    assert v.returncode == 0, v.stdout.decode()
    # The configurations written into the model are the ones the table reports (file units).
    from p105cli.cli.inputs import load_document
    from p105cli.kinematics.reader import read_mechanism
    j = cli("solve", src, "--sweep", sweep, "--to", "jsonl")
    conf = [x for x in _records(j.stdout) if x["type"] == "configuration"]
    doc = load_document(str(out))
    mech = read_mechanism(doc)
    recs = {rec["id"]: rec for rec in doc.records()}
    first_new = max(rec["id"] for rec in load_document(str(src)).records()) + 1
    added = [rec for rid, rec in recs.items() if rid >= first_new and rec.get("type", "").endswith("_pair_value")]
    assert len(added) == 4 * len(conf)
    pair_of = {p.ids["pair"]: p.name for p in mech.pairs}
    got = {}
    for rec in added:
        args = rec["args"]
        ref, val = (args[0], args[1]) if mech.profile != "ap242" else (args[1], args[2])
        got.setdefault(pair_of[ref["ref"]], []).append(val)
    for name, vals in got.items():
        want = [c["pairs"][name] for c in conf]
        factor = mech.units.angle if mech.pair(name).kind == "revolute" else mech.units.length
        assert np.allclose(np.array(vals) * factor, want, atol=1e-12, rtol=0)
    text = out.read_text()
    assert "KINEMATIC_ANALYSIS_RESULT" in text and "INTERPOLATED_CONFIGURATION_SEQUENCE" in text


def test_cli_example_tool_path_on_the_converted_puma(ref, cli, tmp_path):
    # The shipped example: a Puma 560 tool path (poses from the DH product of a smooth joint path).
    model = tmp_path / "puma560.stp"
    r = cli("convert-dh-su", "--convention", "standard", EXAMPLES / "puma560_dh.csv", "-o", model)
    assert r.returncode == 0, r.stderr
    path = EXAMPLES / "puma560_tool_path.jsonl"
    r = cli("solve", model, "--path", path, "--target-link", "link6", "--to", "jsonl", "--tol", "1e-12")
    assert r.returncode == 0, r.stderr
    recs = _records(r.stdout)
    targets = [json.loads(line) for line in path.read_text().splitlines()]
    conf = [x for x in recs if x["type"] == "configuration"]
    assert [c["t"] for c in conf] == [x["t"] for x in targets]
    arm = ref["arms"]["Puma560"]
    q = np.array([[c["pairs"][f"J{j}"] for j in range(1, 7)] for c in conf])
    # Independent check: the plain DH product of the answers puts the tool on the targets.
    assert np.abs(_dh_product(arm, q) - np.array([x["pose"] for x in targets])).max() < 1e-11
    assert recs[-1]["max_position_error"] < 1e-11 and recs[-1]["max_rotation_error"] < 1e-11


@pytest.mark.parametrize("args, message", [
    (["--path", "x.jsonl"], "--path needs --target-link"),
    (["--values", "-", "--sweep", "A=0:1:2"], "--sweep and --values cannot be combined"),
    (["--sweep", "A=0:1"], "expected PAIR=START:STOP:COUNT"),
    (["--sweep", "Z=0:1:3"], "'Z' is not a pair of mechanism"),
    (["--set", "A=1", "--tol", "-1"], "--tol must be a positive number"),
    (["--scene", "s.json", "--to", "csv"], "--scene writes JSON Lines"),
])
def test_cli_usage_errors_are_exit_2(args, message, cli):
    r = cli("solve", FOUR_BAR_STP, *args)
    assert r.returncode == 2
    assert message.encode() in r.stderr and b"Traceback" not in r.stderr


def test_cli_stdin_can_serve_one_input_only(cli):
    r = cli("solve", "--values", "-", input="A\n1\n")
    assert r.returncode == 2 and b"only one of MODEL and --values can read standard input" in r.stderr


def test_cli_degrees_and_millimetres_in_and_out(cli):
    si = cli("solve", FOUR_BAR_STP, "--set", "A=0.5", "--to", "jsonl")
    deg = cli("solve", FOUR_BAR_STP, "--set", f"A={math.degrees(0.5)!r}", "--angle-unit", "deg",
              "--length-unit", "mm", "--to", "jsonl")
    a = _records(si.stdout)[0]
    b = _records(deg.stdout)[0]
    assert abs(math.radians(b["pairs"]["C"]) - a["pairs"]["C"]) < 1e-12
    assert abs(b["links"]["rocker"][0][3] - 1000.0 * a["links"]["rocker"][0][3]) < 1e-9
    assert _records(deg.stdout)[-1]["units"] == {"length": "mm", "angle": "deg"}


@pytest.mark.parametrize("key", ["four_bar", "slider_crank"])
@pytest.mark.parametrize("profile", ["ap214", "ap242"])
def test_program_runs_the_models_own_motion(p105, key, profile):
    """--program: the 1996 files' configuration sequence drives the actuated pair, the AP242
    files' prescribed path is followed by inverse analysis; either way every pair value
    at the program's nodes is the corpus generator's solved state (its own position solver)."""
    from p105cli.corpus import MECHANISMS, configuration

    mech = MECHANISMS[key]()
    axis = 0 if profile == "ap242" else 2
    truth = [configuration(mech, d, axis) for d in mech.drives]
    r = p105("solve", ROOT / "tests" / "data" / "corpus" / f"{key}_{profile}.stp", "--program",
                "--to", "jsonl", "--no-timings")
    assert r.returncode == 0, r.stderr
    recs = [json.loads(x) for x in r.stdout.decode().splitlines()]
    confs = [x for x in recs if x["type"] == "configuration"]
    assert [c["t"] for c in confs] == [0.0, 0.5, 1.0]
    for c, state in zip(confs, truth):
        assert c["status"] == "ok"
        for p in mech.pairs:
            (want,) = state[p.name].values()
            if p.kind in ("prismatic", "rack_and_pinion"):
                want *= 1e-3
            got = c["pairs"][p.name]
            d = got - want
            if p.kind == "revolute":
                d = (d + np.pi) % (2 * np.pi) - np.pi
            assert abs(d) < 1e-9, (p.name, got, want)


def test_program_sampled_and_refused_without_a_program(p105, tmp_path):
    f = ROOT / "tests" / "data" / "corpus" / "four_bar_ap214.stp"
    r = p105("solve", f, "--program", "--count", "5", "--to", "csv")
    assert r.returncode == 0, r.stderr
    assert len(r.stdout.decode().splitlines()) == 6
    r = p105("solve", f, "--count", "5")
    assert r.returncode == 2 and b"need --program" in r.stderr
    bare = tmp_path / "bare.stp"
    bare.write_text("\n".join(line for line in f.read_text().splitlines() if "KINEMATIC_CONTROL" not in line))
    r = p105("solve", bare, "--program")
    assert r.returncode == 2 and b"no kinematic_control" in r.stderr


def test_a_scene_block_in_the_json_model_runs_like_scene(tmp_path, cli):
    """The JSON model may carry its scene ("scene" block): solve runs it as --scene would,
    export to JSON keeps it, and Part 21 (which cannot hold it) says it is left out."""
    scene = _four_bar_cable_scene()
    model = json.loads(cli("parse", FOUR_BAR_STP).stdout)
    model["scene"] = scene
    mpath = tmp_path / "model.json"
    mpath.write_text(json.dumps(model))
    spath = tmp_path / "scene.json"
    spath.write_text(json.dumps(scene))
    embedded = cli("solve", mpath, "--sweep", "A=0:1.5:4", "--no-timings")
    separate = cli("solve", FOUR_BAR_STP, "--sweep", "A=0:1.5:4", "--scene", spath, "--no-timings")
    assert embedded.returncode == 0 and separate.returncode == 0, embedded.stderr + separate.stderr

    def steady(out):  # the cable records carry their run time; everything else must agree
        recs = _records(out)
        for r in recs:
            r.pop("time_s", None)
        return recs
    assert steady(embedded.stdout) == steady(separate.stdout)
    assert any(r["type"] == "cable_state" for r in _records(embedded.stdout))
    kept = cli("export", "--to", "json", mpath)
    assert json.loads(kept.stdout)["scene"] == scene
    import jsonschema
    schema_path = ROOT / "p105cli" / "schemas" / "p105-1.schema.json"
    jsonschema.validate(json.loads(kept.stdout), json.loads(schema_path.read_text()))
    p21 = cli("export", "--to", "p21", mpath)
    assert p21.returncode == 0 and b"scene block" in p21.stderr and b"left out" in p21.stderr


def test_scene_pictures_from_the_cli(tmp_path, cli):
    """--plot/--animate draw the cable states the run wrote (matplotlib: the plot extra)."""
    pytest.importorskip("matplotlib")
    svg, html = tmp_path / "shapes.svg", tmp_path / "path.html"
    r = cli("solve", "--scene", EXAMPLES / "cable_scene.json", "--keypoints", EXAMPLES / "cable_keypoints.jsonl",
            "--plot", svg, "--animate", html)
    assert r.returncode == 0, r.stderr
    assert svg.read_text().lstrip().startswith(("<?xml", "<svg")) and "</svg>" in svg.read_text()
    states = [x for x in _records(r.stdout) if x["type"] == "cable_state"]
    assert len(states) == 9
    assert html.read_text().count("<html") == 1 and html.stat().st_size > 10_000
    bad = cli("solve", "--scene", EXAMPLES / "cable_scene.json", "--keypoints", EXAMPLES / "cable_keypoints.jsonl",
              "--plot", tmp_path / "shapes.jpg")
    assert bad.returncode == 2 and b".png or .svg" in bad.stderr


def test_requests_beyond_double_precision_or_memory_are_usage_errors(cli):
    r = cli("solve", FOUR_BAR_STP, "--set", "A=1e20", "--to", "jsonl")
    assert r.returncode == 2 and b"more than 1e+06 turns" in r.stderr and r.stdout == b""
    r = cli("solve", FOUR_BAR_STP, "--program", "--step", "1e-12", "--to", "jsonl")
    assert r.returncode == 2 and b"more than 10 million samples" in r.stderr and b"Traceback" not in r.stderr
    r = cli("interpolate", "--what", "paths", "--step", "1e-12", FOUR_BAR_STP)
    assert r.returncode == 2 and b"more than 10 million samples" in r.stderr and b"Traceback" not in r.stderr
