"""Structure analysis (p105cli.kinematics.graph): loops, Gruebler and rank mobility,
redundant constraints, the loop-closure Jacobian, and `p105 graph`.

Truth: Gruebler-Kutzbach counts done by hand, mobilities from the literature
(planar and spherical four-bars 1 with 3 redundant constraints, Bennett
linkage 1, generic spatial 4R 0, Stewart platform 6), and two second methods
that use only the model's own pair transforms, never graph.py: the rank of a
finite-difference Jacobian of an independently written loop residual, and
re-closing a loop with scipy after perturbing its driving pair.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from p105cli.kinematics.graph import analyse, loop_closure
from p105cli.kinematics.model import Link, Mechanism, Pair
from p105cli.kinematics.placements import axis2_placement_3d, ypr_rotation
from p105cli.kinematics.spatial import compose, inverse, rot_x, rot_z, rotation_vector, trans_x, trans_z

# --------------------------------------------------------------------------- builders


def dh_loop(a, alpha, d, theta, name="4R"):
    """A closed chain of revolutes in standard DH form: ``prod Rz(th_i) Tz(d_i) Tx(a_i) Rx(al_i) = I``.
    Pair J(i+1) joins L(i) to L(i+1 mod n) with ``T = Rz(th) Tz(d) Tx(a) Rx(al)``."""
    n = len(a)
    links = [Link(f"L{i}") for i in range(n)]
    pairs = [Pair(f"J{i + 1}", "revolute", f"L{i}", f"L{(i + 1) % n}", np.eye(4),
                  inverse(compose(trans_z(d[i]), trans_x(a[i]), rot_x(alpha[i])))) for i in range(n)]
    return Mechanism(name, links, pairs, "L0", initial={f"J{i + 1}": (theta[i],) for i in range(n)})


def dh_product(a, alpha, d, theta):
    T = np.eye(4)
    for i in range(len(a)):
        T = T @ rot_z(theta[i]) @ trans_z(d[i]) @ trans_x(a[i]) @ rot_x(alpha[i])
    return T


def planar_four_bar():
    """Crank-rocker: frame 60, crank 20, coupler 70, rocker 90 (mm as metres); frame angle 2 rad."""
    a = [0.060, 0.020, 0.070, 0.090]
    # Exterior angle th1 at J1 fixed; the other three close the quadrilateral (solved numerically,
    # the closure checked to 1e-12).
    th1 = 2.0

    def res(x):
        T = dh_product(a, [0] * 4, [0] * 4, [th1, *x])
        return np.r_[T[:3, 3] / 0.06, (T[:3, :3] - np.eye(3)).ravel()]
    sol = least_squares(res, [1.0, 1.0, 1.5], xtol=1e-15, ftol=1e-15, gtol=1e-15)
    assert np.max(np.abs(res(sol.x))) < 1e-12
    return dh_loop(a, [0] * 4, [0] * 4, [th1, *sol.x], "planar four-bar")


def bennett(al=0.6, be=1.1, A=1.0, th1=0.7):
    """Bennett linkage: a1 = a3 = A, a2 = a4 = B, twists al, be, al, be, a/sin(alpha) equal, d = 0.
    The closing angles: th3 = -th1, th4 = -th2 and tan(th1/2) tan(th2/2) = sin((be+al)/2)/sin((be-al)/2)
    (Bennett 1903, with the DH sign conventions used here), checked by the chain product."""
    B = A * math.sin(be) / math.sin(al)
    a, alpha = [A, B, A, B], [al, be, al, be]
    k = math.sin((be + al) / 2) / math.sin((be - al) / 2)
    candidates = []
    for s in (1, -1):
        th2 = s * 2 * math.atan(k / math.tan(th1 / 2))
        for t2 in (th2, -th2, math.pi - th2, th2 - math.pi):
            th = [th1, t2, -th1, -t2]
            candidates.append((np.max(np.abs(dh_product(a, alpha, [0] * 4, th) - np.eye(4))), th))
    err, th = min(candidates, key=lambda c: c[0])
    assert err < 1e-12, "the Bennett closing angles do not close the chain"
    return dh_loop(a, alpha, [0] * 4, th, "Bennett")


def assembled(name, links, joints, base, initial=None):
    """All link frames at the world frame in the initial state; each joint's pair frames are its
    world placement ``W`` on both links, so ``q = 0`` closes every loop exactly."""
    pairs = []
    for jn, kind, l1, l2, W, *params in joints:
        pairs.append(Pair(jn, kind, l1, l2, W, W, params=params[0] if params else {}))
    return Mechanism(name, [Link(n) for n in links], pairs, base, initial=initial or {})


def frame(origin, z, x=None):
    return axis2_placement_3d(origin, z, x)


def generic_4r(seed=3):
    rng = np.random.default_rng(seed)
    joints = []
    for i in range(4):
        z = rng.normal(size=3)
        joints.append((f"J{i + 1}", "revolute", f"L{i}", f"L{(i + 1) % 4}",
                       frame(rng.normal(size=3), z / np.linalg.norm(z))))
    return assembled("generic 4R", [f"L{i}" for i in range(4)], joints, "L0")


def spherical_four_bar(seed=5):
    """Four revolute axes through one point (the origin), at generic directions."""
    rng = np.random.default_rng(seed)
    joints = []
    for i in range(4):
        z = rng.normal(size=3)
        joints.append((f"J{i + 1}", "revolute", f"L{i}", f"L{(i + 1) % 4}", frame([0, 0, 0], z / np.linalg.norm(z))))
    return assembled("spherical four-bar", [f"L{i}" for i in range(4)], joints, "L0")


def slider_crank():
    """Crank 0.03, rod 0.11, slide along world x at offset 0.015 (1996 prismatic: slides along z)."""
    A = np.zeros(3)
    th = 0.8
    B = np.array([0.03 * math.cos(th), 0.03 * math.sin(th), 0.0])
    cy = 0.015
    cx = B[0] + math.sqrt(0.11 ** 2 - (cy - B[1]) ** 2)
    C = np.array([cx, cy, 0.0])
    z = [0, 0, 1]
    joints = [("A", "revolute", "frame", "crank", frame(A, z)),
              ("B", "revolute", "crank", "rod", frame(B, z)),
              ("C", "revolute", "rod", "slider", frame(C, z)),
              ("D", "prismatic", "frame", "slider", frame(C, [1, 0, 0], [0, 1, 0]))]
    return assembled("slider-crank", ["frame", "crank", "rod", "slider"], joints, "frame")


def serial_arm():
    """UR5 standard DH (d1 .089159, a2 -.425, a3 -.39225, d4 .10915, d5 .09465, d6 .0823)."""
    d = [0.089159, 0, 0, 0.10915, 0.09465, 0.0823]
    a = [0, -0.425, -0.39225, 0, 0, 0]
    alpha = [math.pi / 2, 0, 0, math.pi / 2, -math.pi / 2, 0]
    links = [Link(f"L{i}") for i in range(7)]
    pairs = [Pair(f"J{i + 1}", "revolute", f"L{i}", f"L{i + 1}", np.eye(4),
                  inverse(compose(trans_z(d[i]), trans_x(a[i]), rot_x(alpha[i])))) for i in range(6)]
    return Mechanism("UR5", links, pairs, "L0", initial={f"J{i + 1}": (0.1 * i,) for i in range(6)})


def stewart(legs=7, seed=11):
    """A Stewart-like platform with ``legs`` UPS legs (universal at the base, prismatic along the
    leg, spherical at the platform): ``legs - 1`` loops, mobility 6."""
    rng = np.random.default_rng(seed)
    links, joints = ["base", "platform"], []
    for i in range(legs):
        t = 2 * math.pi * i / legs
        b = np.array([math.cos(t), math.sin(t), 0.0]) + 0.05 * rng.normal(size=3)
        p = np.array([0.5 * math.cos(t + 0.4), 0.5 * math.sin(t + 0.4), 1.0]) + 0.05 * rng.normal(size=3)
        u = (p - b) / np.linalg.norm(p - b)
        z1 = np.cross(u, rng.normal(size=3))
        lo, up = f"lower{i}", f"upper{i}"
        links += [lo, up]
        joints += [(f"U{i}", "universal", "base", lo, frame(b, z1, np.cross(z1, u))),
                   (f"P{i}", "prismatic", lo, up, frame(b, u)),
                   (f"S{i}", "spherical", up, "platform", frame(p, rng.normal(size=3)))]
    return assembled(f"stewart {legs}", links, joints, "base")


def two_components():
    fb = planar_four_bar()
    extra_links = [Link("X0"), Link("X1"), Link("X2")]
    extra = [Pair("K1", "revolute", "X0", "X1", np.eye(4), trans_x(-0.1)),
             Pair("K2", "revolute", "X1", "X2", np.eye(4), trans_x(-0.1))]
    return Mechanism("two", fb.links + tuple(extra_links), fb.pairs + tuple(extra), "L0",
                     initial=dict(fb.initial))


# --------------------------------------------------------------------------- independent truth

def cycle_residual(mech, cycle, q):
    """(T_cycle - I)[:3, :] flattened for a list of (pair name, forward), by Pair.transform only."""
    T = np.eye(4)
    sl = mech.value_slices
    for name, fwd in cycle:
        p = mech.pair(name)
        Tp = p.transform(q[sl[name]])
        T = T @ (Tp if fwd else np.linalg.inv(Tp))
    return (T - np.eye(4))[:3, :].ravel()


def fd_rank_mobility(mech, cycles, q=None, h=1e-6, rtol=1e-6):
    """n - rank of the finite-difference Jacobian of the cycle residuals."""
    q = mech.initial_vector() if q is None else q
    n = q.size

    def f(x):
        return np.concatenate([cycle_residual(mech, c, x) for c in cycles])
    J = np.stack([(f(q + h * e) - f(q - h * e)) / (2 * h) for e in np.eye(n)], axis=-1)
    s = np.linalg.svd(J, compute_uv=False)
    return n - int(np.sum(s > rtol * s[0]))


def reclose(mech, cycle, drive, delta):
    """Least residual after moving pair ``drive`` by ``delta`` and re-solving the others."""
    q0 = mech.initial_vector()
    k = mech.value_slices[drive].start
    free = [i for i in range(q0.size) if i != k]

    def f(x):
        q = q0.copy()
        q[k] += delta
        q[free] = x
        return cycle_residual(mech, cycle, q)
    sol = least_squares(f, q0[free], xtol=1e-15, ftol=1e-15, gtol=1e-15)
    return float(np.max(np.abs(f(sol.x))))


RING4 = [("J1", True), ("J2", True), ("J3", True), ("J4", True)]


# --------------------------------------------------------------------------- mobility

@pytest.mark.parametrize("build, gruebler, mobility, redundant", [
    (planar_four_bar, -2, 1, 3),
    (spherical_four_bar, -2, 1, 3),
    (bennett, -2, 1, 3),
    (generic_4r, -2, 0, 2),
])
def test_four_revolute_loops(build, gruebler, mobility, redundant):
    mech = build()
    s = analyse(mech)
    assert s.kind == "network" and len(s.loops) == 1
    assert s.mobility_gruebler == gruebler
    assert s.mobility == mobility
    assert s.redundant_constraints == redundant
    assert s.mobility == s.mobility_gruebler + s.redundant_constraints
    # second method: rank of a finite-difference Jacobian of an independent residual
    assert fd_rank_mobility(mech, [RING4]) == mobility
    # every joint of a single overconstrained loop carries its redundant constraints
    assert s.redundant_joints == ["J1", "J2", "J3", "J4"]


@pytest.mark.parametrize("build, movable", [
    (planar_four_bar, True), (bennett, True), (spherical_four_bar, True), (generic_4r, False)])
def test_finite_mobility_by_reclosing(build, movable):
    """Perturb the driving pair and re-close the loop: a mobile linkage follows, a rigid one cannot."""
    mech = build()
    err = reclose(mech, RING4, "J1", 0.05)
    if movable:
        assert err < 1e-9
    else:
        assert err > 1e-4


def test_bennett_conditions_matter():
    """The same four joint axes, built from the Bennett chain at its closing angles, move; with the
    second length 5 % off (the Bennett condition a/sin(alpha) broken) the 4R is rigid."""
    mech = bennett()
    th = [mech.initial[f"J{i + 1}"][0] for i in range(4)]
    al, be, A = 0.6, 1.1, 1.0

    def screws_model(stretch):
        B = A * math.sin(be) / math.sin(al) * stretch
        a, alpha = [A, B, A, B], [al, be, al, be]
        T, joints = np.eye(4), []
        for i in range(4):
            joints.append((f"J{i + 1}", "revolute", f"L{i}", f"L{(i + 1) % 4}", T.copy()))
            T = T @ rot_z(th[i]) @ trans_x(a[i]) @ rot_x(alpha[i])
        return assembled(f"Bennett x{stretch}", [f"L{i}" for i in range(4)], joints, "L0")

    good, broken = screws_model(1.0), screws_model(1.05)
    assert analyse(good).mobility == 1 and fd_rank_mobility(good, [RING4]) == 1
    assert analyse(broken).mobility == 0 and fd_rank_mobility(broken, [RING4]) == 0


def test_slider_crank():
    mech = slider_crank()
    s = analyse(mech)
    assert (s.mobility_gruebler, s.mobility, s.redundant_constraints) == (-2, 1, 3)
    cycle = s.loops[0]
    assert fd_rank_mobility(mech, [cycle]) == 1
    assert reclose(mech, cycle, "A", 0.1) < 1e-9


def test_serial_arm_is_a_tree():
    mech = serial_arm()
    s = analyse(mech)
    assert s.kind == "tree" and s.loops == [] and s.chords == []
    assert s.mobility == s.mobility_gruebler == 6
    assert s.redundant_constraints == 0 and s.redundant_joints == []
    assert s.order == [f"L{i}" for i in range(7)]
    assert s.tree == [(f"J{i + 1}", f"L{i}", f"L{i + 1}", True) for i in range(6)]
    r, J = loop_closure(mech, s, np.zeros((3, 6)))
    assert r.shape == (3, 0) and J.shape == (3, 0, 6)


def test_stewart_platform():
    mech = stewart(7)
    s = analyse(mech)
    assert len(s.loops) == 6
    # 16 links, 21 joints, 7 x (2 + 1 + 3) freedoms
    assert s.mobility_gruebler == 6 * (16 - 1 - 21) + 42 == 6
    assert s.mobility == 6 and s.redundant_constraints == 0
    # independent cycles: base -> leg i -> platform -> leg 0 back to base
    leg = lambda i: [(f"U{i}", True), (f"P{i}", True), (f"S{i}", True)]
    back = [(n, not f) for n, f in reversed(leg(0))]
    cycles = [leg(i) + back for i in range(1, 7)]
    assert fd_rank_mobility(mech, cycles) == 6


def test_two_components():
    mech = two_components()
    s = analyse(mech)
    assert len(s.components) == 2
    c0, c1 = s.components
    assert c0.root == "L0" and not c0.floating and c0.mobility == 1 and c0.mobility_gruebler == -2
    assert c1.root == "X0" and c1.floating and c1.loops == []
    assert c1.mobility_gruebler == c1.mobility == 6 + 2
    # whole mechanism: 7 links, 6 joints, 6 freedoms
    assert s.mobility_gruebler == 6 * (7 - 1 - 6) + 6
    assert s.mobility == 9 and s.redundant_constraints == 3
    assert s.mobility == s.mobility_gruebler + s.redundant_constraints
    assert s.order[:4] == ["L0", "L1", "L3", "L2"] and s.order[4:] == ["X0", "X1", "X2"]


def test_branch_joint_carries_no_redundant_constraint():
    fb = planar_four_bar()
    mech = Mechanism("four-bar with a branch", fb.links + (Link("arm"),),
                     fb.pairs + (Pair("K", "revolute", "L2", "arm", trans_z(0.01), np.eye(4)),),
                     "L0", initial=dict(fb.initial))
    s = analyse(mech)
    assert s.mobility == 2 and s.redundant_constraints == 3
    assert s.redundant_joints == ["J1", "J2", "J3", "J4"]


def test_self_stress_only_in_the_overconstrained_loop():
    """A planar four-bar sharing no joint with a spatial 4-loop of a Stewart leg pair: only the
    four-bar's joints carry redundant constraints."""
    fb = planar_four_bar()
    st = stewart(2, seed=4)    # 1 loop, generic, no redundancy
    links = fb.links + tuple(Link(n.name) for n in st.links if n.name != "base")
    ren = {"base": "L0"}
    pairs = list(fb.pairs) + [Pair(p.name, p.kind, ren.get(p.link1, p.link1), ren.get(p.link2, p.link2),
                                   p.P1, p.P2) for p in st.pairs]
    mech = Mechanism("mixed", links, pairs, "L0", initial=dict(fb.initial))
    s = analyse(mech)
    assert len(s.loops) == 2
    assert s.redundant_constraints == 3
    assert s.redundant_joints == ["J1", "J2", "J3", "J4"]


# --------------------------------------------------------------------------- loops

@pytest.mark.parametrize("build", [planar_four_bar, slider_crank, lambda: stewart(7), two_components])
def test_loops_are_closed_walks_and_independent(build):
    mech = build()
    s = analyse(mech)
    n_comp = len(s.components)
    assert len(s.loops) == len(mech.pairs) - len(mech.links) + n_comp
    assert sorted(s.order) == sorted(mech.link_names)
    assert len(s.tree) == len(mech.links) - n_comp
    names = list(mech.pair_names)
    inc = np.zeros((len(s.loops), len(names)))
    for li, lp in enumerate(s.loops):
        assert lp[0] == (s.chords[li], True)
        p0 = mech.pair(lp[0][0])
        at = p0.link1
        for name, fwd in lp:
            p = mech.pair(name)
            assert at == (p.link1 if fwd else p.link2)
            at = p.link2 if fwd else p.link1
            inc[li, names.index(name)] = 1 if fwd else -1
        assert at == p0.link1
    if len(s.loops):
        assert np.linalg.matrix_rank(inc) == len(s.loops)
    for name, parent, child, fwd in s.tree:
        p = mech.pair(name)
        assert (p.link1, p.link2) == ((parent, child) if fwd else (child, parent))


# --------------------------------------------------------------------------- loop closure

@pytest.mark.parametrize("build", [bennett, slider_crank, lambda: stewart(4), two_components])
def test_loop_closure_jacobian_matches_finite_differences(build):
    mech = build()
    s = analyse(mech)
    rng = np.random.default_rng(1)
    q = mech.initial_vector() + 0.3 * rng.normal(size=(2, 3, mech.value_count))
    r, J = loop_closure(mech, s, q)
    assert r.shape == (2, 3, 6 * len(s.loops)) and J.shape == (2, 3, 6 * len(s.loops), mech.value_count)
    h = 1e-6
    for idx in np.ndindex(2, 3):
        fd = np.stack([(loop_closure(mech, s, q[idx] + h * e)[0] - loop_closure(mech, s, q[idx] - h * e)[0])
                       / (2 * h) for e in np.eye(mech.value_count)], axis=-1)
        assert np.allclose(J[idx], fd, atol=1e-6, rtol=1e-6)
        r1, J1 = loop_closure(mech, s, q[idx])
        assert np.allclose(r1, r[idx], atol=1e-14) and np.allclose(J1, J[idx], atol=1e-14)


@pytest.mark.parametrize("build", [bennett, slider_crank, spherical_four_bar, lambda: stewart(4), two_components])
def test_root_loop_twists_are_the_loop_twists_in_the_root_frame(build):
    """The structure analysis's Jacobian (each pair evaluated once, in its root's frame) is the
    solver's loop twists turned by Ad(X_a) at an assembled state."""
    from p105cli.kinematics.solver import link_poses, loop_errors, loop_twists, plan, root_loop_twists
    from p105cli.kinematics.spatial import adjoint

    mech = build()
    pl = plan(mech)
    q = mech.initial_vector()
    pos, rot = loop_errors(pl, q)
    assert max(pos[0] / pl.size, rot[0]) < 1e-9          # the builders assemble their mechanisms
    X, _, _ = link_poses(pl, q)
    J = root_loop_twists(pl, q, X)
    _, Jl = loop_twists(pl, q[None])
    assert J.shape == (6 * len(pl.loops), mech.value_count) and np.abs(J).max() > 0.1
    for i, lp in enumerate(pl.loops):
        a = pl.link_index[mech.pairs[lp[0][0]].link1]
        assert np.allclose(J[6 * i:6 * i + 6], adjoint(X[a]) @ Jl[0, 6 * i:6 * i + 6], atol=1e-8)
    assert np.array_equal(root_loop_twists(pl, q, X, [len(pl.loops) - 1]), J[-6:])


def test_loop_residual_definition():
    """r = (translation, rotation vector) of the walk round the loop from the chord's first link."""
    mech = slider_crank()
    s = analyse(mech)
    q = mech.initial_vector() + np.array([0.1, -0.2, 0.05, 0.01])
    r, _ = loop_closure(mech, s, q)
    T = np.eye(4)
    for name, fwd in s.loops[0]:
        Tp = mech.pair(name).transform(q[mech.value_slices[name]])
        T = T @ (Tp if fwd else np.linalg.inv(Tp))
    assert np.allclose(r[:3], T[:3, 3], atol=1e-14)
    # rotation vector: exp(phi) == R (Rodrigues)
    phi = r[3:]
    th = np.linalg.norm(phi)
    k = phi / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    R = np.eye(3) + math.sin(th) * K + (1 - math.cos(th)) * K @ K
    assert np.allclose(R, T[:3, :3], atol=1e-12)
    # at the initial (assembled) state it vanishes
    r0, _ = loop_closure(mech, s, mech.initial_vector())
    assert np.max(np.abs(r0)) < 1e-14


def test_rotation_vector_against_scipy():
    from scipy.spatial.transform import Rotation
    rng = np.random.default_rng(7)
    v = rng.normal(size=(50, 3))
    v *= (rng.uniform(0, math.pi, 50) / np.linalg.norm(v, axis=1))[:, None]
    v[0] = 0.0
    v[1] = [1e-9, 0, 0]
    R = Rotation.from_rotvec(v).as_matrix()
    assert np.allclose(rotation_vector(R), v, atol=1e-12)
    assert np.allclose(rotation_vector(ypr_rotation(0.3, 0.2, 0.1)),
                       Rotation.from_matrix(ypr_rotation(0.3, 0.2, 0.1)).as_rotvec(), atol=1e-13)


def test_unclosed_initial_state_is_noted():
    mech = planar_four_bar()
    bad = Mechanism(mech.name, mech.links, mech.pairs, mech.base,
                    initial={k: (v[0] + 0.1,) for k, v in mech.initial.items()})
    s = analyse(bad)
    assert s.closure_residual > 1e-3
    assert any("does not close" in n for n in s.notes)


def test_tolerance_is_relative_and_validated():
    mech = bennett()
    assert analyse(mech, tol=1e-6).mobility == 1
    with pytest.raises(ValueError):
        analyse(mech, tol=0.0)
    # the rank does not depend on the unit of length: every length times 1000 (dh_loop keeps
    # its lengths in P2; P1 is the identity)
    def scaled(P):
        P = np.array(P)
        P[:3, 3] *= 1000.0
        return P
    big = Mechanism(mech.name, mech.links,
                    [Pair(p.name, p.kind, p.link1, p.link2, p.P1, scaled(p.P2)) for p in mech.pairs],
                    mech.base, initial=dict(mech.initial))
    sb = analyse(big)
    assert sb.mobility == 1 and sb.redundant_constraints == 3


# --------------------------------------------------------------------------- the corpus

CORPUS_DIR = __import__("pathlib").Path(__file__).resolve().parents[1] / "data" / "corpus"
# (Gruebler-Kutzbach by hand, known mobility).
CORPUS_TRUTH = {
    "cam_follower": (6 * (3 - 1 - 3) + (1 + 1 + 4), 1),     # point on planar curve: 4 freedoms
    "four_bar": (6 * (4 - 1 - 4) + 4, 1),
    "slider_crank": (6 * (4 - 1 - 4) + 4, 1),
    "ur5_arm": (6 * (7 - 1 - 6) + 6, 6),
    "gear_train": (6 * (4 - 1 - 5) + 5, 1),
    "rack_and_pinion": (6 * (3 - 1 - 3) + 3, 1),
    "spherical_linkage": (6 * (4 - 1 - 4) + 4, 1),
}
LAYOUTS = ("ap214", "p105", "ap242")


def _read(path):
    from p105cli.cli.inputs import load_document
    from p105cli.part105.read_mechanism import read_mechanism
    doc = load_document(str(path))
    return doc, read_mechanism(doc)


@pytest.mark.parametrize("name", sorted(CORPUS_TRUTH))
@pytest.mark.parametrize("layout", LAYOUTS)
def test_corpus_mobility(name, layout):
    _, mech = _read(CORPUS_DIR / f"{name}_{layout}.stp")
    s = analyse(mech)
    gruebler, mobility = CORPUS_TRUTH[name]
    assert s.mobility_gruebler == gruebler
    assert s.mobility == mobility
    assert s.redundant_constraints == mobility - gruebler
    assert s.kind == ("tree" if name == "ur5_arm" else "network")
    assert s.closure_residual < 1e-9
    if s.loops:
        # second method on the file's own pair transforms, loops walked independently
        assert fd_rank_mobility(mech, s.loops) == mobility


@pytest.mark.parametrize("name, drive", [("four_bar", "A"), ("cam_follower", "shaft"), ("rack_and_pinion", None)])
def test_corpus_moves_by_reclosing(name, drive):
    """Finite mobility: move the driven pair and re-close the loop with scipy."""
    _, mech = _read(CORPUS_DIR / f"{name}_ap242.stp")
    s = analyse(mech)
    drive = drive or next(p.name for p in mech.pairs if p.actuated)
    assert reclose(mech, s.loops[0], drive, 0.05) < 1e-9


# --------------------------------------------------------------------------- --enrich

def _validate(doc):
    from p105cli.rules.validate import validate_document
    res = validate_document(doc, "<enriched>")
    return [d for d in res.diagnostics if d.severity in ("error", "warning")]


def _enriched(doc, profile="ap242"):
    from p105cli.part105.topology import enrich
    from p105cli.part105.read_mechanism import read_mechanisms
    return enrich(doc, [(m, analyse(m)) for m in read_mechanisms(doc)], profile)


def _strip_graph_entities(path):
    """The corpus file without its network structure, loops and oriented joints."""
    from p105cli.step import read_any
    drop = ("ORIENTED_JOINT(", "KINEMATIC_LOOP(", "KINEMATIC_TOPOLOGY_NETWORK_STRUCTURE(")
    lines = [ln for ln in path.read_text().splitlines() if not any(d in ln for d in drop)]
    return read_any("\n".join(lines) + "\n", str(path))


@pytest.mark.parametrize("name", sorted(CORPUS_TRUTH))
def test_enrich_ap242_corpus_validates_clean(name):
    from p105cli.cli.inputs import load_document
    doc = load_document(str(CORPUS_DIR / f"{name}_ap242.stp"))
    out, _ = _enriched(doc)
    assert _validate(out) == []
    old_max = max(r["id"] for r in doc.records())
    added = out.data[len(list(doc.records())):]
    assert added and min(r["id"] for r in added) == old_max + 1
    types = {r["type"] for r in added}
    assert "kinematic_topology_tree_structure" in types


@pytest.mark.parametrize("name", ["four_bar", "gear_train", "slider_crank"])
def test_enrich_writes_loops_that_validate(name):
    doc = _strip_graph_entities(CORPUS_DIR / f"{name}_ap242.stp")
    out, _ = _enriched(doc)
    assert _validate(out) == []
    recs = {r["id"]: r for r in out.data}
    nets = [r for r in out.data if r.get("type") == "kinematic_topology_network_structure"]
    assert len(nets) == 1
    loops = [recs[x["ref"]] for x in nets[0]["args"][1]]
    _, mech = _read(CORPUS_DIR / f"{name}_ap242.stp")
    assert len(loops) == len(mech.pairs) - len(mech.links) + 1
    # Head to tail, read back from the written instances alone.
    for lp in loops:
        ends = []
        for ref in lp["args"][1]:
            oj = recs[ref["ref"]]
            joint = recs[oj["args"][3]["ref"]]
            start, end = joint["args"][1]["ref"], joint["args"][2]["ref"]
            ends.append((start, end) if oj["args"][4] == {"enum": "T"} else (end, start))
        assert all(ends[i][1] == ends[(i + 1) % len(ends)][0] for i in range(len(ends)))
    # A loop that does not close head to tail is caught by the validator (so the check above
    # is not the only guard): flip one orientation.
    first = recs[loops[0]["args"][1][0]["ref"]]
    first["args"][4] = {"enum": "F" if first["args"][4] == {"enum": "T"} else "T"}
    assert any(d.severity == "error" for d in _validate(out))


def test_enrich_is_idempotent():
    from p105cli.step import write_step
    import io
    doc = _strip_graph_entities(CORPUS_DIR / "gear_train_ap242.stp")
    once, _ = _enriched(doc)
    twice, notes = _enriched(once)
    a, b = io.StringIO(), io.StringIO()
    write_step(once, a)
    write_step(twice, b)
    assert a.getvalue() == b.getvalue()
    assert len(notes) == 2


def test_enrich_refuses_the_1996_layout():
    from p105cli.cli.inputs import load_document
    from p105cli.part105.topology import EnrichError
    doc = load_document(str(CORPUS_DIR / "four_bar_ap214.stp"))
    with pytest.raises(EnrichError, match="AP214"):
        _enriched(doc, "ap214")


# --------------------------------------------------------------------------- the command
# In-process through p105cli.cli.main (the contract tests run the real process for `graph` too).

def _cli(tmp_path, *args):
    """(exit code, output text) of ``p105 ARGS -o OUT``."""
    from p105cli.cli import main
    out = tmp_path / f"out{len(list(tmp_path.iterdir()))}"
    code = main([*map(str, args), "-o", str(out)])
    return code, (out.read_text() if out.exists() else None)


def test_cli_json_keys_and_values(tmp_path, capsys):
    code, text = _cli(tmp_path, "graph", CORPUS_DIR / "four_bar_ap214.stp")
    assert code == 0 and capsys.readouterr().err == ""
    doc = json.loads(text)
    for key in ("links", "joints", "loops", "mobility", "mobility_gruebler", "redundant_constraints"):
        assert key in doc
    assert (doc["mobility"], doc["mobility_gruebler"], doc["redundant_constraints"]) == (1, -2, 3)
    assert [ln["name"] for ln in doc["links"]][0] == "frame"
    assert len(doc["loops"]) == 1 and len(doc["loops"][0]["joints"]) == 4
    assert doc["kind"] == "network"


def test_cli_json_input_gives_the_same_analysis(tmp_path):
    path = CORPUS_DIR / "slider_crank_ap242.stp"
    _, model = _cli(tmp_path, "parse", path)
    (tmp_path / "model.json").write_text(model)
    assert _cli(tmp_path, "graph", tmp_path / "model.json")[1] == _cli(tmp_path, "graph", path)[1]


def test_cli_dot_graphml_mermaid(tmp_path):
    import xml.etree.ElementTree as ET
    path = CORPUS_DIR / "gear_train_ap242.stp"
    code, text = _cli(tmp_path, "graph", "--to", "dot", path)
    assert code == 0
    assert text.startswith('digraph "gear_train" {') and text.count(" -> ") == 5
    assert text.count("style=dashed") == 2            # two chords, two loops
    root = ET.fromstring(_cli(tmp_path, "graph", "--to", "graphml", path)[1])
    ns = {"g": "http://graphml.graphdrawing.org/xmlns"}
    assert len(root.findall(".//g:node", ns)) == 4 and len(root.findall(".//g:edge", ns)) == 5
    mm = _cli(tmp_path, "graph", "--to", "mermaid", path)[1].splitlines()
    assert mm[0] == "flowchart LR"
    assert sum("-->" in ln for ln in mm) == 3 and sum(".->" in ln for ln in mm) == 2


def test_cli_enrich_then_validate(tmp_path):
    from p105cli.cli.inputs import load_document
    code, text = _cli(tmp_path, "graph", "--enrich", CORPUS_DIR / "ur5_arm_ap242.stp")
    assert code == 0
    (tmp_path / "e.stp").write_text(text)
    assert _validate(load_document(str(tmp_path / "e.stp"))) == []
    code, text = _cli(tmp_path, "graph", "--enrich", "--to", "json", CORPUS_DIR / "ur5_arm_ap242.stp")
    assert code == 0 and json.loads(text)["format"] == "p105/1"
    (tmp_path / "e.json").write_text(text)
    assert _validate(load_document(str(tmp_path / "e.json"))) == []
    # JSON in, JSON out by default; the same instances as the Part 21 route
    code, again = _cli(tmp_path, "graph", "--enrich", tmp_path / "e.json")
    assert code == 0 and json.loads(again)["data"] == json.loads(text)["data"]


def test_cli_errors(tmp_path, capsys):
    path = CORPUS_DIR / "four_bar_ap242.stp"
    assert _cli(tmp_path, "graph", "--mechanism", "nope", path)[0] == 2
    assert _cli(tmp_path, "graph", "--to", "p21", path)[0] == 2
    assert _cli(tmp_path, "graph", "--enrich", "--to", "dot", path)[0] == 2
    assert _cli(tmp_path, "graph", "--tol", "-1", path)[0] == 2
    capsys.readouterr()
    code, text = _cli(tmp_path, "graph", "--enrich", CORPUS_DIR / "four_bar_ap214.stp")
    err = capsys.readouterr().err
    assert code == 2 and text is None and "AP242" in err and "Traceback" not in err


def test_pair_without_motion_leaves_mobility_unknown(tmp_path):
    """A bevel gear has no motion here (pairs.UnsupportedPairError): the rank mobility of its
    component is None with the reason in notes; Gruebler is still counted; loop_closure raises."""
    from p105cli.kinematics.pairs import UnsupportedPairError
    W1, W2 = frame([0, 0, 0], [0, 0, 1]), frame([0.05, 0, 0], [0, 0, 1])
    gear = {"radius_first_link": 0.02, "radius_second_link": 0.03, "gear_ratio": 2 / 3, "bevel": 0.3}
    mech = Mechanism("bevel", [Link("frame"), Link("g1"), Link("g2")],
                     [Pair("b1", "revolute", "frame", "g1", W1, np.eye(4)),
                      Pair("b2", "revolute", "frame", "g2", W2, np.eye(4)),
                      Pair("mesh", "gear", "g1", "g2", np.eye(4), np.eye(4), params=gear)], "frame")
    s = analyse(mech)
    assert s.mobility is None and s.redundant_constraints is None
    assert s.mobility_gruebler == 6 * (3 - 1 - 3) + 3
    assert any("mesh" in n for n in s.notes)
    with pytest.raises(UnsupportedPairError):
        loop_closure(mech, s, mech.initial_vector())


def test_single_link_mechanism():
    mech = Mechanism("lonely", [Link("ground")], [], "ground")
    s = analyse(mech)
    assert (s.order, s.tree, s.loops, s.kind) == (["ground"], [], [], "tree")
    assert s.mobility == s.mobility_gruebler == 0


def test_rank_tolerance_follows_the_closure_error():
    """A Bennett state closed only to ~1e-7: the singular value of the special direction is then
    ~1e-7, not 1e-16; the rank tolerance follows the closure error, so mobility stays 1."""
    mech = bennett()
    off = Mechanism(mech.name, mech.links, mech.pairs, mech.base,
                    initial={k: (v[0] + 1e-7,) for k, v in mech.initial.items()})
    s = analyse(off)
    assert 1e-8 < s.closure_residual < 1e-5
    assert min(s.components[0].singular_values) > 1e-12      # the state is really off
    assert s.mobility == 1 and s.redundant_constraints == 3
    assert s.tol == pytest.approx(100 * s.closure_residual)


def random_assembled(seed, n_links=9, n_loops=3):
    """A random assembled mechanism: random tree of mixed pairs plus chords (see bench_graph)."""
    rng = np.random.default_rng(seed)
    kinds = ("revolute", "prismatic", "cylindrical", "universal", "spherical", "planar", "screw")
    joints = []

    def W():
        z = rng.normal(size=3)
        return frame(rng.uniform(-1, 1, 3), z / np.linalg.norm(z))
    for i in range(1, n_links):
        kind = kinds[int(rng.integers(len(kinds)))]
        params = {"pitch": 0.01} if kind == "screw" else {}
        joints.append((f"j{i}", kind, f"l{int(rng.integers(i))}", f"l{i}", W(), params))
    for c in range(n_loops):
        a, b = rng.choice(n_links, 2, replace=False)
        joints.append((f"c{c}", ("revolute", "spherical", "universal")[c % 3], f"l{a}", f"l{b}", W()))
    return assembled(f"random {seed}", [f"l{i}" for i in range(n_links)], joints, "l0")


@pytest.mark.parametrize("seed", range(6))
def test_random_mechanisms_agree_with_finite_differences(seed):
    mech = random_assembled(seed)
    s = analyse(mech)
    assert len(s.loops) == 3
    assert s.mobility == s.mobility_gruebler + s.redundant_constraints
    assert s.mobility == fd_rank_mobility(mech, s.loops)
    # the analytic Jacobian's rank at the assembled state agrees with its finite differences too
    q = mech.initial_vector()
    r, J = loop_closure(mech, s, q)
    assert np.max(np.abs(r)) < 1e-12
    h = 1e-6
    fd = np.stack([(loop_closure(mech, s, q + h * e)[0] - loop_closure(mech, s, q - h * e)[0]) / (2 * h)
                   for e in np.eye(mech.value_count)], axis=-1)
    assert np.allclose(J, fd, atol=1e-6)


@pytest.mark.parametrize("seed", range(6))
def test_redundant_joints_by_relaxing_each_joint(seed):
    """Second method for the joints that carry redundant constraints: replace one joint by an
    unconstrained pair (same frames, still assembled at q = 0). The redundancy drops exactly when
    that joint carried a self-stress."""
    mech = random_assembled(seed)
    s = analyse(mech)
    for p in mech.pairs:
        relaxed = Mechanism(mech.name, mech.links,
                            [Pair(x.name, "unconstrained", x.link1, x.link2, x.P1, x.P2) if x.name == p.name
                             else x for x in mech.pairs], mech.base)
        r = analyse(relaxed)
        assert (r.redundant_constraints < s.redundant_constraints) == (p.name in s.redundant_joints), p.name


# --------------------------------------------------------------------------- generic low-order pairs

def _with_generic_j2(flags):
    """The planar four-bar with J2 as AP242's generic low-order pair with ``flags`` (t_x .. r_z),
    its rotation the revolute's."""
    mech = planar_four_bar()
    j2 = mech.pair("J2")
    params = dict(zip(("t_x", "t_y", "t_z", "r_x", "r_y", "r_z"), map(bool, flags)))
    pairs = [Pair(p.name, "low_order", p.link1, p.link2, p.P1, p.P2, params=params) if p is j2 else p
             for p in mech.pairs]
    initial = {**mech.initial, "J2": (0.0, 0.0, 0.0, 0.0, 0.0, mech.initial["J2"][0])}
    return Mechanism(mech.name, mech.links, pairs, mech.base, initial=initial)


@pytest.mark.parametrize("flags, freedoms, mobility", [
    # only r_z: the revolute pin it is; six values, one freedom
    ((0, 0, 0, 0, 0, 1), 4, 1),
    # t_x and r_z: a pin that also slides in the plane; planar Gruebler 3 (4 - 1) - 2 * 3 - 1 = 2
    ((1, 0, 0, 0, 0, 1), 5, 2),
])
def test_a_generic_pairs_freedoms_are_its_flags(flags, freedoms, mobility):
    """Locked values are no freedoms: Gruebler and the rank mobility count the flags, not the
    six values (before: 6 freedoms, mobility 6 for the pin)."""
    mech = _with_generic_j2(flags)
    assert mech.pair("J2").value_count == 6 and mech.pair("J2").freedoms == sum(flags)
    s = analyse(mech)
    assert s.dof == freedoms and s.mobility == mobility
    assert s.mobility_gruebler == 6 * (4 - 1 - 4) + freedoms
    assert s.mobility == s.mobility_gruebler + s.redundant_constraints
    if flags == (0, 0, 0, 0, 0, 1):  # exactly the revolute four-bar's structure
        ref = analyse(planar_four_bar())
        assert (s.rank, s.redundant_constraints, s.redundant_joints) == (ref.rank, ref.redundant_constraints,
                                                                          ref.redundant_joints)
