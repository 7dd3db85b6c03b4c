"""p105 solve, the hard cases: dead centres, non-assemblable ranges, branches, spatial loops,
redundant constraints, many loops, singular inverse analysis, units.

Each answer is checked against a closed form or an independent construction
written here (circle intersections, the Bennett relation, leg lengths of a
Stewart platform, the corpus' own geometric construction of the spherical
four-bar), never against the solver itself.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from p105cli.kinematics import solver
from p105cli.kinematics.model import Link, Mechanism, Pair
from p105cli.kinematics.placements import ypr_from_matrix, ypr_rotation
from p105cli.kinematics.spatial import compose, rot_x, rot_y, rot_z, trans_x, trans_y, transform
from kinematics.test_solver import _dh_product, dh_mechanism, four_bar, link_angles, ref, wrap  # noqa: F401 - ref is a fixture

I4 = np.eye(4)


def circles(P, rp, Q, rq, side):
    """The intersection of circle (P, rp) and circle (Q, rq) on ``side`` (+1: left of P->Q);
    None when they do not meet."""
    PQ = Q - P
    L = math.hypot(*PQ)
    along = (rp * rp - rq * rq + L * L) / (2 * L)
    h2 = rp * rp - along * along
    if h2 < 0:
        return None
    return P + along * PQ / L + side * math.sqrt(h2) * np.array([-PQ[1], PQ[0]]) / L


def four_bar_closed_form(a, b, c, d, t2, sigma):
    """(theta3, theta4) from the crank angle; sigma = side of C relative to B->D."""
    B = np.array([a * math.cos(t2), a * math.sin(t2)])
    C = circles(B, b, np.array([d, 0.0]), c, sigma)
    if C is None:
        return None
    return math.atan2(C[1] - B[1], C[0] - B[0]), math.atan2(C[1], C[0] - d)


def sigma_of(a, b, c, d, t2, t3):
    B = np.array([a * math.cos(t2), a * math.sin(t2)])
    C = B + b * np.array([math.cos(t3), math.sin(t3)])
    u, v = np.array([d, 0.0]) - B, C - B
    return int(np.sign(u[0] * v[1] - u[1] * v[0]))


# ---------------------------------------------------------------- four-bars

def test_four_bar_driven_through_a_dead_centre():
    # A crank-rocker driven by its rocker: at the rocker's extreme the crank and the coupler are
    # in line (a dead centre). The sequence goes to the extreme and back.
    a, b, c, d = 0.02, 0.07, 0.09, 0.06
    t4max = math.acos(((b - a) ** 2 - d * d - c * c) / (2 * d * c))     # |AC| = b - a
    t4min = math.acos(((b + a) ** 2 - d * d - c * c) / (2 * d * c))     # |AC| = b + a
    t40 = 0.5 * (t4min + t4max)
    C0 = np.array([d + c * math.cos(t40), c * math.sin(t40)])
    B0 = circles(np.zeros(2), a, C0, b, +1)                                 # the initial assembly
    mech = four_bar(a, b, c, d, math.atan2(B0[1], B0[0]), math.atan2(*(C0 - B0)[::-1]), t40, driven="D")
    seq = np.concatenate([np.linspace(t40, t4max, 20), np.linspace(t4max, t40, 20)[1:]])
    result = solver.solve_motion(mech, {"D": seq}, tol=1e-12)
    assert result.status[19] == "singular" and "dead centre" in result.messages[19]
    assert [s for i, s in enumerate(result.status) if i != 19] == ["ok"] * 38
    t2, _, _ = link_angles(result)
    for i, t4 in enumerate(seq):
        C = np.array([d + c * math.cos(t4), c * math.sin(t4)])
        if i == 19:
            # At the dead centre B lies on C->A extended beyond A: the crank points away from C.
            assert abs(wrap(t2[i] - math.atan2(C[1], C[0]) - math.pi)) < 1e-4
            continue
        B = circles(np.zeros(2), a, C, b, +1)                               # the same side as the start
        assert abs(wrap(t2[i] - math.atan2(B[1], B[0]))) < 1e-10
    assert np.isfinite(result.Q).all()


def test_non_grashof_four_bar_into_and_out_of_its_non_assemblable_range():
    # s + l > p + q: a triple rocker. The input can only swing where |BD| >= c - b.
    a, b, c, d = 0.06, 0.045, 0.07, 0.05
    limit = math.acos((a * a + d * d - (c - b) ** 2) / (2 * a * d))       # about 24.1 deg
    seq = np.radians(np.concatenate([np.linspace(90, 10, 17), np.linspace(10, 90, 17)[1:]]))
    t30, t40 = four_bar_closed_form(a, b, c, d, seq[0], +1)
    mech = four_bar(a, b, c, d, seq[0], t30 + 0.01, t40 - 0.01)
    result = solver.solve_motion(mech, {"A": seq}, tol=1e-12)
    _, t3, t4 = link_angles(result)
    for i, t2 in enumerate(seq):
        if t2 < limit:
            assert result.status[i] == "not_assemblable", (i, math.degrees(t2))
            assert result.residual[i] > 1e-4 and "cannot be assembled" in result.messages[i]
        else:
            assert result.status[i] == "ok", (i, math.degrees(t2), result.messages[i])
            want3, want4 = four_bar_closed_form(a, b, c, d, t2, +1)
            assert abs(wrap(t3[i] - want3)) < 1e-10 and abs(wrap(t4[i] - want4)) < 1e-10
    assert result.status[-1] == "ok"                                       # recovered after the range
    assert np.isfinite(result.Q).all()


@pytest.mark.parametrize("sigma", [+1, -1])
def test_drag_link_full_turns_on_both_branches(sigma):
    # Grashof with the ground link shortest: crank and rocker both turn fully.
    a, b, c, d = 0.06, 0.07, 0.065, 0.02
    seq = np.linspace(0.0, 4 * math.pi, 97)                                 # two full turns
    t3, t4 = four_bar_closed_form(a, b, c, d, 0.0, sigma)
    mech = four_bar(a, b, c, d, 0.0, t3 + 0.02, t4 + 0.02)
    result = solver.solve_motion(mech, {"A": seq}, tol=1e-13)
    assert result.status == ["ok"] * len(seq)
    _, s3, s4 = link_angles(result)
    for i, t2 in enumerate(seq):
        w3, w4 = four_bar_closed_form(a, b, c, d, t2, sigma)
        assert abs(wrap(s3[i] - w3)) < 1e-11 and abs(wrap(s4[i] - w4)) < 1e-11
    assert len(set(result.branch)) == 1


def test_same_model_in_millimetres_and_metres_gives_the_same_answers_scaled():
    a, b, c, d = 0.02, 0.07, 0.09, 0.06
    seq = np.linspace(0.0, 2 * math.pi, 25)
    t3, t4 = four_bar_closed_form(a, b, c, d, 0.0, -1)
    m = four_bar(a, b, c, d, 0.0, t3 + 0.05, t4 - 0.05)
    mm = four_bar(a, b, c, d, 0.0, t3 + 0.05, t4 - 0.05, scale=1000.0)
    rm = solver.solve_motion(m, {"A": seq}, tol=1e-12)
    rmm = solver.solve_motion(mm, {"A": seq}, tol=1e-12)
    assert rm.status == rmm.status == ["ok"] * len(seq)
    assert np.abs(wrap(rm.Q - rmm.Q)).max() < 1e-12
    assert list(rm.iterations) == list(rmm.iterations)
    Lm, Lmm = rm.links(), rmm.links()
    assert np.abs(Lm[..., :3, :3] - Lmm[..., :3, :3]).max() < 1e-12
    assert np.abs(1000.0 * Lm[..., :3, 3] - Lmm[..., :3, 3]).max() < 1e-9
    assert np.abs(rm.residual - rmm.residual).max() < 1e-13


# ---------------------------------------------------------------- slider-crank

SLIDER_OFFSET = 0.015


def offset_slider_crank(sigma):
    """An offset slider-crank (crank 30 mm, rod 110 mm, offset 15 mm) assembled on branch
    ``sigma`` (the slider ahead of the crank pin: +1, behind: -1), the initial state a little
    off so it must be closed; with ``x_of(theta, sigma)``, the closed-form slider position,
    and the initial crank angle."""
    r, l, e = 0.03, 0.11, SLIDER_OFFSET
    slide = rot_y(math.pi / 2)                                              # pair z axis along world x
    links = [Link(n) for n in ("frame", "crank", "rod", "slider")]
    pairs = [Pair("O", "revolute", "frame", "crank", I4, I4, actuated=True),
             Pair("A", "revolute", "crank", "rod", trans_x(r), I4),
             Pair("B", "revolute", "rod", "slider", trans_x(l), I4),
             Pair("S", "prismatic", "frame", "slider", compose(trans_y(e), slide), slide)]

    def x_of(th, s):
        return r * math.cos(th) + s * math.sqrt(l * l - (e - r * math.sin(th)) ** 2)

    th0 = 0.3
    x0 = x_of(th0, sigma)
    phi = math.atan2(e - r * math.sin(th0), x0 - r * math.cos(th0))
    init = {"O": (th0,), "A": (phi - th0 + 0.03,), "B": (-phi,), "S": (x0 + 0.002,)}
    return Mechanism("slider_crank", links, pairs, "frame", initial=init), x_of, th0


@pytest.mark.parametrize("sigma", [+1, -1])
def test_offset_slider_crank_both_branches(sigma):
    mech, x_of, th0 = offset_slider_crank(sigma)
    e = SLIDER_OFFSET
    seq = th0 + np.linspace(0.0, 2 * math.pi, 61)
    result = solver.solve_motion(mech, {"O": seq}, tol=1e-13)
    assert result.status == ["ok"] * len(seq)
    s = result.Q[:, 3]
    want = np.array([x_of(t, sigma) for t in seq])
    assert np.abs(s - want).max() < 1e-13 * 10
    slider = result.links()[:, result.plan.link_index["slider"]]
    assert np.abs(slider[:, 0, 3] - want).max() < 1e-12 and np.abs(slider[:, 1, 3] - e).max() < 1e-12


# ---------------------------------------------------------------- spatial loops

def test_spherical_four_bar_against_the_geometric_construction():
    from p105cli.corpus import mechanisms as corpus

    cm = corpus.spherical_linkage()
    values = corpus.configuration(cm, cm.drives[0])
    links = [Link(ln.name) for ln in cm.links]
    pairs = [Pair(p.name, "revolute", p.first, p.second, p.frame_first, p.frame_second, actuated=p.actuated)
             for p in cm.pairs]
    # Start from a rough initial state (1 degree off): the solver assembles it.
    init = {name: (v["rotation"] + math.radians(1.0),) for name, v in values.items()}
    init["input"] = (values["input"]["rotation"],)
    mech = Mechanism("spherical", links, pairs, cm.links[0].name, initial=init)
    seq = cm.drives[0] + np.linspace(0.0, 2 * math.pi, 37)
    result = solver.solve_motion(mech, {"input": seq}, tol=1e-13)
    assert result.status == ["ok"] * len(seq)
    L = solver.forward(result.plan, result.Q, world=False)
    for i, th in enumerate(seq):
        want = cm.solve(th)                                                 # axes by spherical trigonometry
        for name, T in want.items():
            got = L[i, result.plan.link_index[name]]
            assert np.abs(got[:3, :3] - T[:3, :3]).max() < 1e-11
            assert np.abs(got[:3, 3] - T[:3, 3]).max() < 1e-9               # millimetres


def _bennett(a, b, alpha, beta, t1, t2):
    """Bennett linkage: four revolutes, link k from axis k to axis k+1 is Tx(a_k) Rx(alpha_k)
    with (a, alpha), (b, beta), (a, alpha), (b, beta); a / sin(alpha) = b / sin(beta)."""
    geo = [(a, alpha), (b, beta), (a, alpha), (b, beta)]
    links = [Link(f"L{k}") for k in range(4)]
    pairs = []
    for k in range(4):
        prev = geo[(k - 1) % 4]
        pairs.append(Pair(f"R{k + 1}", "revolute", f"L{(k - 1) % 4}", f"L{k}",
                          compose(trans_x(prev[0]), rot_x(prev[1])), I4, actuated=k == 0))
    # Closed form (Bennett): theta3 = -theta1, theta4 = -theta2 (mod 2 pi).
    init = {"R1": (t1,), "R2": (t2 + 0.02,), "R3": (-t1 - 0.01,), "R4": (-t2 + 0.01,)}
    return Mechanism("bennett", links, pairs, "L3", initial=init)


def test_bennett_linkage_with_its_redundant_constraints():
    a, alpha, beta = 0.1, math.radians(40.0), math.radians(70.0)
    b = a * math.sin(beta) / math.sin(alpha)
    K = math.sin((beta + alpha) / 2) / math.sin((beta - alpha) / 2)

    def theta2(t1):  # tan(t1/2) tan(t2/2) = K  (the branch through the initial state)
        return 2 * math.atan(K / math.tan(t1 / 2))

    t1 = 1.0
    mech = _bennett(a, b, alpha, beta, t1, theta2(t1))
    seq = np.linspace(0.4, 2.6, 23)
    result = solver.solve_motion(mech, {"R1": seq}, tol=1e-13)
    assert result.status == ["ok"] * len(seq)
    q = result.Q
    for i, t in enumerate(seq):
        assert abs(wrap(q[i, 1] - theta2(t))) < 1e-11
        assert abs(wrap(q[i, 2] + t)) < 1e-11
        assert abs(wrap(q[i, 3] + theta2(t))) < 1e-11
    # 3 loop unknowns, 6 equations of rank 3: a mobile linkage that Gruebler calls a structure.
    assert result.residual.max() < 1e-13


def _stewart(pose0):
    """6-UPS platform with an unconstrained pair ground -> platform (so its pose is read as values):
    14 links, 19 pairs, 6 independent loops."""
    ang_b = np.radians([-15, 15, 105, 135, 225, 255])
    ang_p = np.radians([-45, 45, 75, 165, 195, 285])
    base_pts = np.stack([np.cos(ang_b), np.sin(ang_b), np.zeros(6)], axis=1)
    plat_pts = 0.5 * np.stack([np.cos(ang_p), np.sin(ang_p), np.zeros(6)], axis=1)
    links = [Link("base"), Link("platform")]
    pairs = []
    for i in range(6):
        links += [Link(f"cyl{i}"), Link(f"rod{i}")]
        pairs += [Pair(f"U{i}", "universal", "base", f"cyl{i}", transform(np.eye(3), base_pts[i]), I4),
                  Pair(f"P{i}", "prismatic", f"cyl{i}", f"rod{i}", I4, I4, actuated=True),
                  Pair(f"S{i}", "spherical", f"rod{i}", "platform", I4, transform(np.eye(3), plat_pts[i]))]
    pairs.append(Pair("F", "unconstrained", "base", "platform", I4, I4))
    return links, pairs, base_pts, plat_pts


def _stewart_values(pose, base_pts, plat_pts):
    """Leg values of the platform pose (the inverse kinematics of a Stewart platform)."""
    vals = {}
    R, t = pose[:3, :3], pose[:3, 3]
    for i in range(6):
        leg = R @ plat_pts[i] + t - base_pts[i]
        s = float(np.linalg.norm(leg))
        u = leg / s
        q2 = math.acos(u[2])
        q1 = math.atan2(u[0], -u[1])
        Rc = (rot_z(q1) @ rot_x(q2))[:3, :3]
        vals[f"U{i}"] = (q1, q2)
        vals[f"P{i}"] = (s,)
        vals[f"S{i}"] = tuple(float(x) for x in ypr_from_matrix(Rc.T @ R))
    vals["F"] = (*t, *(float(x) for x in ypr_from_matrix(R)))
    return vals


def test_stewart_platform_with_six_loops():
    def pose(k):
        return transform(ypr_rotation(0.1 * math.sin(k), 0.05 * k, -0.08 * k), [0.05 * k, -0.03 * k, 1.0 + 0.1 * k])

    links, pairs, bp, pp = _stewart(pose(0.0))
    init = _stewart_values(pose(0.0), bp, pp)
    init = {k: tuple(x + 0.01 for x in v) if k.startswith(("U", "S")) else v for k, v in init.items()}
    mech = Mechanism("stewart", links, pairs, "base", initial=init)
    assert len(solver.plan(mech).loops) == 6
    ks = np.linspace(0.0, 1.0, 11)
    legs = np.array([[_stewart_values(pose(k), bp, pp)[f"P{i}"][0] for i in range(6)] for k in ks])
    result = solver.solve_motion(mech, {f"P{i}": legs[:, i] for i in range(6)}, tol=1e-13)
    assert result.status == ["ok"] * len(ks)
    plat = result.links()[:, result.plan.link_index["platform"]]
    for j, k in enumerate(ks):
        assert np.abs(plat[j] - pose(k)).max() < 1e-10


# ---------------------------------------------------------------- inverse analysis at a singularity

def test_inverse_analysis_through_a_wrist_singularity(ref):
    arm = ref["arms"]["Puma560"]
    s = np.linspace(-1.0, 1.0, 21)[:, None]
    q_path = np.array([0.2, 0.6, -0.5, 0.4, 0.0, -0.3]) + s * np.array([0.3, -0.2, 0.1, 0.5, 0.3, 0.4])
    assert q_path[10, 4] == 0.0                        # q5 = 0: axes 4 and 6 in line, the wrist is singular
    poses = _dh_product(arm, q_path)
    mech = dh_mechanism(arm)
    init = {f"J{j + 1}": (q_path[0, j],) for j in range(6)}
    mech = Mechanism(mech.name, mech.links, mech.pairs, mech.base, initial=init)
    result = solver.solve_path(mech, "L6", poses, tol=1e-10)
    assert np.isfinite(result.Q).all()
    assert np.isfinite(result.position_error).all() and np.isfinite(result.rotation_error).all()
    # The poses are reachable: the damped steps still get there, also at the singular sample.
    assert result.position_error.max() < 1e-9 and result.rotation_error.max() < 1e-9
    assert np.abs(_dh_product(arm, result.Q) - poses).max() < 1e-8
    # Away from the singularity the arm keeps its posture (joints 1-3 follow the path).
    assert np.abs(wrap(result.Q[:, :3] - q_path[:, :3])).max() < 1e-6


def test_parallelogram_through_its_change_point_is_not_a_silent_flip():
    # a = c, b = d: at theta2 = 0 all links are in line and the parallelogram branch crosses the
    # anti-parallelogram one (a bifurcation). The invariant of the initial branch (the sign of the
    # reduced passive Jacobian) is carried by the anti-parallelogram past the crossing: reported.
    a, b, c, d = 0.03, 0.08, 0.03, 0.08
    seq = np.linspace(0.5, -0.5, 20)                          # no sample exactly at 0
    t3, t4 = four_bar_closed_form(a, b, c, d, seq[0], +1)
    mech = four_bar(a, b, c, d, seq[0], t3 + 0.01, t4 - 0.01)
    result = solver.solve_motion(mech, {"A": seq}, tol=1e-12)
    _, s3, s4 = link_angles(result)
    crossing = int(np.argmax(seq < 0))
    assert result.status[:crossing] == ["ok"] * crossing
    assert result.status[crossing] == "singular" and "bifurcation" in result.messages[crossing]
    assert result.status[crossing + 1:] == ["ok"] * (len(seq) - crossing - 1)
    for i, t2 in enumerate(seq):
        if i < crossing:                                      # the parallelogram: coupler parallel to ground
            assert abs(wrap(s3[i])) < 1e-10 and abs(wrap(s4[i] - t2)) < 1e-10
        else:                                                 # a closed-form assembly, not the parallelogram
            sigma = sigma_of(a, b, c, d, t2, s3[i])
            w3, w4 = four_bar_closed_form(a, b, c, d, t2, sigma)
            assert abs(wrap(s3[i] - w3)) < 1e-10 and abs(wrap(s4[i] - w4)) < 1e-10
            assert abs(wrap(s4[i] - t2)) > 1e-2
    assert set(result.branch) == {1.0}


def test_gear_train_over_twenty_turns_with_redundant_planar_loops():
    # Two gear meshes on three bearings: planar loops modelled in 3D whose start frames turn with
    # the gears (the column space of the passive Jacobian turns too), one redundant constraint,
    # steps of 4.3 rad. Truth: the pitch circles roll, so each gear turns by -r_in/r_out of its driver.
    from conftest import ROOT
    from p105cli.cli.inputs import load_document
    from p105cli.part105.read_mechanism import read_mechanism

    mech = read_mechanism(load_document(str(ROOT / "tests" / "data" / "corpus" / "gear_train_ap242.stp")))
    mesh12, mesh23 = mech.pair("mesh 1-2").params, mech.pair("mesh 2-3").params
    seq = np.linspace(-20 * math.pi, 20 * math.pi, 30)
    result = solver.solve_motion(mech, {"bearing 1": seq}, tol=1e-12)
    assert result.status == ["ok"] * len(seq)
    L = result.links()

    def turn(name):  # world angle of a gear (mod 2 pi: the steps are too large to unwrap)
        R = L[:, result.plan.link_index[name]]
        return np.arctan2(R[:, 1, 0], R[:, 0, 0])

    g1, g2, g3 = turn("gear_1"), turn("gear_2"), turn("gear_3")
    k12 = mesh12["radius_first_link"] / mesh12["radius_second_link"]
    k23 = mesh23["radius_first_link"] / mesh23["radius_second_link"]
    d1 = seq - seq[0]                                       # gear 1 turns with its bearing
    assert np.abs(wrap(g1 - g1[0] - d1)).max() < 1e-10
    assert np.abs(wrap(g2 - g2[0] + k12 * d1)).max() < 1e-10
    assert np.abs(wrap(g3 - g3[0] - k23 * k12 * d1)).max() < 1e-10
    # bearing 1 has a 20-turn range: its values are reported as driven, not folded into one turn
    assert np.array_equal(result.Q[:, mech.value_slices["bearing 1"].start], seq)


def test_inverse_analysis_of_a_closed_loop_follows_the_coupler():
    # The coupler's poses from a forward analysis (closed form checked elsewhere) given back as a
    # path: the loop residuals join the pose error, and every pair value comes back, on the branch.
    a, b, c, d = 0.02, 0.07, 0.09, 0.06
    t3, t4 = four_bar_closed_form(a, b, c, d, 0.3, -1)
    mech = four_bar(a, b, c, d, 0.3, t3, t4)
    seq = np.linspace(0.3, 0.3 + 2 * math.pi, 37)
    poses = []
    for t2 in seq:                                   # the coupler frame sits at B, along B->C
        w3, _ = four_bar_closed_form(a, b, c, d, t2, -1)
        poses.append(transform(rot_z(w3)[:3, :3], [a * math.cos(t2), a * math.sin(t2), 0.0]))
    result = solver.solve_path(mech, "coupler", np.array(poses), tol=1e-12)
    assert result.status == ["ok"] * len(seq)
    assert result.position_error.max() < 1e-12 * 0.09 and result.rotation_error.max() < 1e-11
    _, s3, s4 = link_angles(result)
    for i, t2 in enumerate(seq):
        w3, w4 = four_bar_closed_form(a, b, c, d, t2, -1)
        assert abs(wrap(result.Q[i, 0] - t2)) < 1e-11
        assert abs(wrap(s4[i] - w4)) < 1e-11
