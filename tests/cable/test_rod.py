"""Discrete Kirchhoff rod (p105cli.cable.rod) and the catenary, against independent truth.

Truth: /work/shared/reference/rod_cases.json (closed forms, mpmath; converted
to L = 1, EI = 1), finite differences of the discrete energy, scipy's
``solve_bvp`` on the continuous Kirchhoff equations (second method), and
exact balance laws. Units of the reference: lengths / L, forces in EI/L^2
(w L for the catenary), moments in EI/L.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import SHARED
from p105cli.cable.catenary import catenary, catenary_parameter
from p105cli.cable.helix import helix_frames as kirchhoff_helix
from p105cli.cable.rod import RodProblem, solve_rod, state_from_frames
from p105cli.cable.rod.model import _Model
from p105cli.cable.rod.quaternions import _pose_quat, _qconj, _qexp, _qmat, _qmul
from p105cli.kinematics.spatial import matrix_to_quaternion, quaternion_to_matrix, rot_x, rot_y, rot_z

CASES = {c["id"]: c for c in json.loads((SHARED / "reference" / "rod_cases.json").read_text())["cases"]}
NOLOAD = np.zeros(3)


def planar_pose(p, angle=0.0):
    """Pose in the x-y plane: tangent at ``angle`` from +x, section x axis = world z (stiffness A)."""
    z = np.array([np.cos(angle), np.sin(angle), 0.0])
    x = np.array([0.0, 0.0, 1.0])
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2] = x, np.cross(z, x), z
    T[:3, 3] = p
    return T


def pose(p, R=np.eye(4)):
    T = np.eye(4)
    T[:3, :3] = np.asarray(R)[:3, :3]
    T[:3, 3] = p
    return T


def heavy_3d(t=0.0):
    """3D heavy cable, anisotropic, both ends clamped, end frame twisted (the benchmark case)."""
    Ts = pose([0, 0, 0], rot_y(np.pi / 2))
    Te = pose([0.55 + 0.05 * np.sin(t), 0.3 * np.cos(t), -0.25 + 0.1 * t],
              rot_z(0.6 + 0.3 * t) @ rot_y(np.pi / 2 + 0.4) @ rot_z(1.2 + t))
    return RodProblem(1.0, (0.02, 0.035, 0.015), np.array([0.0, 0.0, -1.0]), Ts, Te)


def cantilever(alpha):
    return RodProblem(1.0, (1.0, 1.0, 1.0), NOLOAD, planar_pose([0, 0, 0]), np.eye(4),
                      "clamped", "free", None, np.array([0.0, -alpha, 0.0]))


# --------------------------------------------------------------------------- catenary

@pytest.mark.parametrize("cid", ["c_catenary_h0.8_v0", "c_catenary_h0.95_v0"])
def test_catenary_closed_form(cid):
    c = CASES[cid]
    h, out = c["inputs"]["span_h_over_L"], c["outputs"]
    cat = catenary([0, 0, 0], [h, 0, 0], 1.0, [0, -1.0, 0])
    assert cat.a == pytest.approx(out["a_over_L"], abs=1e-13)
    mid = cat.points(0.5)
    assert mid[1] == pytest.approx(out["y_lowest"], abs=1e-13)
    assert mid[0] == pytest.approx(out["x_lowest"], abs=1e-13)
    assert cat.tension(0.0) == pytest.approx(out["T_A"], abs=1e-13)
    assert cat.internal_force(0.0)[1] == pytest.approx(-out["V_A"], abs=1e-13)
    t0 = cat.tangents(0.0)
    assert np.arctan2(t0[1], t0[0]) == pytest.approx(out["angle_A_rad"], abs=1e-13)
    assert np.abs(cat.points(1.0) - [h, 0, 0]).max() < 1e-13


def test_catenary_parameter_extremes_and_errors():
    # nearly taut and very slack spans still solve sqrt(L^2 - v^2) = 2 a sinh(h / 2a)
    for L, h, v in ((1.0, 1 - 1e-12, 0.0), (1.0, 1e-6, 0.3), (2.0, 0.5, -1.2)):
        a = catenary_parameter(L, h, v)
        assert 2 * a * np.sinh(h / (2 * a)) == pytest.approx(np.sqrt(L * L - v * v), rel=1e-12)
    for L, h, v in ((1.0, 1.0, 0.0), (1.0, 0.0, 0.5), (1.0, 0.9, 0.5)):
        with pytest.raises(ValueError):
            catenary_parameter(L, h, v)


# --------------------------------------------------------------------------- discrete energy derivatives

def test_energy_gradient_and_hessian_match_finite_differences():
    rng = np.random.default_rng(7)
    p = RodProblem(1.0, (0.7, 1.3, 0.5), NOLOAD, pose([0, 0, 0]), pose([0.5, 0.2, 0.6]))
    m = _Model(p, 6)
    q = m.align(_qexp(0.4 * rng.standard_normal((7, 3))))
    e0, ga, gb, *whg = m.bend(q)
    G = m.grad_nodes(ga, gb)
    Haa, Hbb, Hab = m.hess(*whg)
    eps = 1e-6

    def energy(dth):
        return m.bend(_qmul(q, _qexp(dth)))[0]

    for node in (0, 3, 6):
        for k in range(3):
            d = np.zeros((7, 3))
            d[node, k] = eps
            fd = (energy(d) - energy(-d)) / (2 * eps)
            assert fd == pytest.approx(G[node, k], abs=1e-7 * max(1.0, abs(G[node, k])))
    # Hessian blocks of cell 2 (nodes 2, 3): second differences of the energy
    i = 2
    H = np.block([[Haa[i], Hab[i]], [Hab[i].T, Hbb[i]]])
    h2 = 1e-4
    for a in range(6):
        for b in range(6):
            da = np.zeros((7, 3))
            db = np.zeros((7, 3))
            da[i + a // 3, a % 3] = h2
            db[i + b // 3, b % 3] = h2
            fd = (energy(da + db) - energy(da - db) - energy(-da + db) + energy(-da - db)) / (4 * h2 * h2)
            # only cell i couples these nodes off-diagonally; on the diagonal blocks subtract neighbours
            if a // 3 == b // 3:
                continue
            assert fd == pytest.approx(H[a, b], abs=1e-5 * max(1.0, abs(H[a, b])))
    # full diagonal block of node 3 = Hbb of cell 2 + Haa of cell 3
    D3 = Hbb[2] + Haa[3]
    for a in range(3):
        for b in range(3):
            da = np.zeros((7, 3))
            db = np.zeros((7, 3))
            da[3, a] = h2
            db[3, b] = h2
            fd = (energy(da + db) - energy(da - db) - energy(-da + db) + energy(-da - db)) / (4 * h2 * h2)
            assert fd == pytest.approx(D3[a, b], abs=1e-5 * max(1.0, abs(D3[a, b])))


# --------------------------------------------------------------------------- planar reference cases

def tip_values(sol):
    t = sol.frames[-1, :3, 2]
    return (-sol.nodes[-1, 1], 1.0 - sol.nodes[-1, 0], np.arctan2(-t[1], t[0]),
            np.linalg.norm(sol.moment_start))


@pytest.mark.parametrize("alpha", [1.0, 5.0])
def test_cantilever_tip_load(alpha):
    out = CASES[f"a_cantilever_tipload_alpha{int(alpha)}"]["outputs"]
    truth = (out["tip_vertical_deflection_over_L"], out["tip_horizontal_displacement_over_L"],
             out["tip_angle_rad"], out["root_moment_ML_over_EI"])
    plain = solve_rod(cantilever(alpha), segments=64)
    rich = solve_rod(cantilever(alpha), segments=64, richardson=True)
    assert plain.status == rich.status == "ok"
    for got_p, got_r, want in zip(tip_values(plain), tip_values(rich), truth):
        assert abs(got_p - want) < 2e-4 * max(1.0, want)      # second order at n = 64
        assert abs(got_r - want) < 2e-7 * max(1.0, want)      # n = 64 and 128 extrapolated
    # the clamp carries the tip load: force on the wall = -P (down), no weight
    assert np.abs(rich.force_start - [0, -alpha, 0]).max() < 1e-10
    assert rich.error_estimate >= abs(tip_values(rich)[0] - truth[0])


def test_heavy_cantilever():
    out = CASES["b_cantilever_selfweight_beta5"]["outputs"]
    p = RodProblem(1.0, (1.0, 1.0, 1.0), np.array([0, -5.0, 0]), planar_pose([0, 0, 0]), np.eye(4),
                   "clamped", "free")
    sol = solve_rod(p, segments=64, richardson=True)
    dv, dh, ang, m0 = tip_values(sol)
    assert abs(dv - out["tip_vertical_deflection_over_L"]) < 1e-7
    assert abs(dh - out["tip_horizontal_displacement_over_L"]) < 1e-7
    assert abs(ang - out["tip_angle_rad"]) < 1e-7
    assert abs(m0 - out["root_moment_ML_over_EI"]) < 1e-6
    assert np.abs(sol.force_start - [0, -5.0, 0]).max() < 1e-9      # the wall carries the weight


@pytest.mark.parametrize("cid", ["c_catenary_h0.8_v0", "c_catenary_h0.95_v0"])
def test_inextensible_catenary_pinned(cid):
    c = CASES[cid]
    h, out = c["inputs"]["span_h_over_L"], c["outputs"]
    EI = 1e-7                                   # EI / (w L^3) <= 1e-5, hinged ends
    p = RodProblem(1.0, (EI, EI, EI), np.array([0, -1.0, 0]), planar_pose([0, 0, 0]),
                   planar_pose([h, 0, 0]), "pinned", "pinned")
    sol = solve_rod(p, segments=64, richardson=True)
    assert sol.status == "ok"
    assert abs(sol.nodes[32, 1] - out["y_lowest"]) < 1e-5
    assert abs(np.linalg.norm(sol.force_start) - out["T_A"]) < 1e-5
    assert abs(-sol.force_start[1] - out["V_A"]) < 1e-5        # each support carries half the weight
    assert abs(sol.force_start[0] - out["H_over_wL"]) < 1e-5    # the cable pulls the support inwards
    cat = catenary([0, 0, 0], [h, 0, 0], 1.0, [0, -1.0, 0])
    assert np.abs(sol.nodes - cat.points(sol.s)).max() < 2e-5


def test_clamped_flexible_cable_graded_mesh_reaches_catenary():
    # clamped ends, EI = 1e-7 w L^3: boundary layers sqrt(EI/T) ~ 4e-4 L, far thinner than a cell.
    # The continuum answer differs from the catenary by O(sqrt(EI/T)); the graded mesh gets there,
    # the uniform one is still off by the clamp cell's O(h x angle) error.
    out = CASES["c_catenary_h0.8_v0"]["outputs"]
    p = RodProblem(1.0, (1e-7, 1e-7, 1e-7), np.array([0, -1.0, 0]), planar_pose([0, 0, 0]),
                   planar_pose([0.8, 0, 0]))
    graded = solve_rod(p, segments=200)
    uniform = solve_rod(p, segments=200, grading=0.0)
    assert graded.status == uniform.status == "ok"
    assert graded.s[1] < 0.2 * (1.0 / 200)                     # end cells refined
    assert abs(graded.nodes[100, 1] - out["y_lowest"]) < 1e-4
    assert abs(uniform.nodes[100, 1] - out["y_lowest"]) > 5e-4
    # tension: the clamps carry part of the shape, O(sqrt(EI/T)) ~ 4e-4 relative
    assert abs(np.linalg.norm(graded.force_start) - out["T_A"]) < 1e-3


def test_graded_mesh_keeps_fourth_order_with_richardson():
    ref = CASES["a_cantilever_tipload_alpha5"]["outputs"]["tip_vertical_deflection_over_L"]
    e = [abs(-solve_rod(cantilever(5.0), segments=n, richardson=True, grading=0.6).nodes[-1, 1] - ref)
         for n in (8, 16, 32)]
    assert np.polyfit(np.log([8, 16, 32]), np.log(e), 1)[0] < -3.6


def test_clamped_clamped_elastica():
    out = CASES["d_clamped_clamped_dL0.7"]["outputs"]
    # stiff out of plane (B = 10): the planar mode is the minimum
    p = RodProblem(1.0, (1.0, 10.0, 1.0), NOLOAD, planar_pose([0, 0, 0]), planar_pose([0.7, 0, 0]))
    sol = solve_rod(p, segments=64, richardson=True)
    assert sol.status == "ok" and sol.stable
    assert abs(np.abs(sol.nodes[32, 1]) - out["max_height_over_L"]) < 1e-6
    assert np.abs(sol.nodes[:, 2]).max() < 1e-12
    assert abs(-sol.force_start[0] - out["compressive_force_PL2_over_EI"]) < 1e-4
    assert abs(np.linalg.norm(sol.moment_start) - out["end_moment_ML_over_EI"]) < 1e-5
    t = sol.frames[:, :3, 2]
    assert abs(np.abs(np.arctan2(t[:, 1], t[:, 0])).max() - out["max_tangent_angle_rad"]) < 1e-3
    # isotropic section: the same shape, but it may turn about the clamp axis -> reported
    iso = solve_rod(RodProblem(1.0, (1.0, 1.0, 1.0), NOLOAD, p.T_start, p.T_end), segments=64,
                    richardson=True)
    assert iso.status == "non_unique" and "family" in iso.message
    assert abs(np.hypot(iso.nodes[32, 1], iso.nodes[32, 2]) - out["max_height_over_L"]) < 1e-6
    assert abs(-iso.force_start[0] - out["compressive_force_PL2_over_EI"]) < 1e-4


# --------------------------------------------------------------------------- 3D helix

def helix_frames(s):
    """The case's frames (p105cli.cable.helix) and binormals t x N (N: towards the axis)."""
    c = CASES["e1_helix_clamped"]["inputs"]
    F = kirchhoff_helix(s, c["R"], c["alpha_rad"], c["omega"])
    N = -F[:, :3, 3] * [1.0, 1.0, 0.0] / c["R"]
    return F, np.cross(F[:, :3, 2], N)


def test_helix_end_reactions():
    c = CASES["e1_helix_clamped"]
    I, bc, out = c["inputs"], c["boundary_conditions"], c["outputs"]
    F, B = helix_frames(np.array([0.0, 1.0]))
    # our closed-form poses are the case's (quaternions wxyz)
    assert np.abs(F[0, :3, :3] - quaternion_to_matrix(bc["q0"])).max() < 1e-12
    assert np.abs(F[1, :3, :3] - quaternion_to_matrix(bc["qL"])).max() < 1e-12
    assert np.abs(F[1, :3, 3] - bc["rL"]).max() < 1e-12
    p = RodProblem(1.0, (I["A"], I["B"], I["C"]), NOLOAD, F[0], F[1])
    kap, om, C = out["curvature_kappa"], I["omega"], I["C"]
    n0 = np.array([0, 0, out["axial_force_F"]])
    m0 = I["A"] * kap * B[0] + C * om * F[0, :3, 2]
    mL = I["A"] * kap * B[1] + C * om * F[1, :3, 2]
    rng = np.random.default_rng(3)
    errs = []
    for n in (32, 64):
        G, _ = helix_frames(np.linspace(0, 1, n + 1))
        G[1:-1, :3, 3] += 0.002 * rng.standard_normal((n - 1, 3))     # 2 % of the radius
        # the helix is an unstable equilibrium: follow it with plain Newton from a nearby start
        sol = solve_rod(p, segments=n, warm=state_from_frames(p, G), inertia=False, richardson=True)
        assert sol.status == "ok" and sol.stable is False
        ex, _ = helix_frames(sol.s)
        errs.append(np.abs(sol.nodes - ex[:, :3, 3]).max())
        assert np.abs(sol.force_start - n0).max() < 5e-4 * 32 ** 4 / n ** 4
        assert np.abs(sol.force_end + n0).max() < 5e-4 * 32 ** 4 / n ** 4
        assert np.abs(sol.moment_start - m0).max() < 2e-4 * 32 ** 4 / n ** 4
        assert np.abs(sol.moment_end + mL).max() < 2e-4 * 32 ** 4 / n ** 4
    assert errs[1] < 2e-6 and errs[0] / errs[1] > 12       # fourth order after extrapolation
    # the default (minimum-seeking) solver says the helix is not a minimum
    cold = solve_rod(p, segments=32)
    assert cold.status == "ok" and cold.stable


# --------------------------------------------------------------------------- order of accuracy

def test_convergence_order():
    out = CASES["a_cantilever_tipload_alpha5"]["outputs"]
    want = out["tip_vertical_deflection_over_L"]
    ns = (8, 16, 32)
    e2 = [abs(-solve_rod(cantilever(5.0), segments=n, grading=0.0).nodes[-1, 1] - want) for n in ns]
    e4 = [abs(-solve_rod(cantilever(5.0), segments=n, richardson=True, grading=0.0).nodes[-1, 1] - want)
          for n in ns]
    slope2 = np.polyfit(np.log(ns), np.log(e2), 1)[0]
    slope4 = np.polyfit(np.log(ns), np.log(e4), 1)[0]
    assert -2.2 < slope2 < -1.8
    assert slope4 < -3.6


# --------------------------------------------------------------------------- second method: solve_bvp

def kirchhoff_bvp(p: RodProblem, guess):
    """Continuous Kirchhoff rod by scipy collocation: y = (r, q, n, m), 13 equations."""
    from scipy.integrate import solve_bvp

    K = np.asarray(p.stiffness, float)
    f = np.asarray(p.weight, float)
    qs = _pose_quat(p.T_start)
    qe = _pose_quat(p.T_end)
    if guess.quaternions[0] @ qs < 0:
        qs = -qs

    def rhs(s, y):
        q = y[3:7].T
        n, m = y[7:10].T, y[10:13].T
        R = _qmat(q / np.linalg.norm(q, axis=1)[:, None])
        u = np.einsum("pji,pj->pi", R, m) / K
        d3 = R[:, :, 2]
        uq = np.concatenate([np.zeros((len(s), 1)), u], axis=1)
        dq = 0.5 * _qmul(q, uq)
        dm = -np.cross(d3, n)
        dn = np.tile(-f, (len(s), 1))
        return np.concatenate([d3, dq, dn, dm], axis=1).T

    def bc(ya, yb):
        qb = yb[3:7]
        rel = _qmul(_qconj(qe), qb)
        if rel[0] < 0:
            rel = -rel
        return np.concatenate([ya[0:3] - p.T_start[:3, 3], ya[3:7] - qs,
                               yb[0:3] - p.T_end[:3, 3], rel[1:]])

    s = guess.s
    qn = matrix_to_quaternion(guess.frames[:, :3, :3])
    qn = qn * np.sign(np.einsum("ij,j->i", qn, qs))[:, None]
    nn = guess.force_start - s[:, None] * f                   # n(s) = n(0) - f s
    mm = np.zeros((len(s), 3))                                # m' = -r' x n, from m(0)
    mm[0] = guess.moment_start
    for k in range(1, len(s)):
        mm[k] = mm[k - 1] - np.cross(guess.nodes[k] - guess.nodes[k - 1], 0.5 * (nn[k] + nn[k - 1]))
    y0 = np.concatenate([guess.nodes, qn, nn, mm], axis=1).T
    return solve_bvp(rhs, bc, s, y0, tol=1e-9, max_nodes=100000)


def test_cross_check_3d_heavy_cable_with_solve_bvp():
    p = heavy_3d()
    sol = solve_rod(p, segments=64, richardson=True)
    assert sol.status == "ok" and sol.stable
    bvp = kirchhoff_bvp(p, sol)
    assert bvp.status == 0
    y0, yL = bvp.sol(0.0), bvp.sol(1.0)
    assert np.abs(bvp.sol(sol.s)[0:3].T - sol.nodes).max() < 1e-7
    assert np.abs(y0[7:10] - sol.force_start).max() < 1e-6
    assert np.abs(y0[10:13] - sol.moment_start).max() < 1e-6
    assert np.abs(-yL[7:10] - sol.force_end).max() < 1e-6
    assert np.abs(-yL[10:13] - sol.moment_end).max() < 1e-6


# --------------------------------------------------------------------------- robustness

@pytest.mark.parametrize("ratio", [0.99, 0.999])
@pytest.mark.parametrize("kind,EI", [("pinned", 1e-5), ("clamped", 1e-5), ("clamped", 1e-2)])
def test_near_taut_converges(ratio, kind, EI):
    p = RodProblem(1.0, (EI, EI, EI), np.array([0, -1.0, 0]), planar_pose([0, 0, 0]),
                   planar_pose([ratio, 0, 0]), kind, kind)
    sol = solve_rod(p, segments=50)
    assert sol.status == "ok" and sol.iterations <= 8
    if EI <= 1e-5:
        # a flexible cable: the tension is the catenary's (which grows like slack^-1/2)
        T_cat = catenary([0, 0, 0], [ratio, 0, 0], 1.0, [0, -1.0, 0]).tension(0.0)
        assert abs(np.linalg.norm(sol.force_start) - T_cat) < 0.05 * T_cat


@pytest.mark.parametrize("e", range(-5, 6))
def test_stiffness_range_converges(e):
    EI = 10.0 ** e            # EI / (w L^3) from 1e-5 to 1e5
    Ts = pose([0, 0, 0], rot_y(np.pi / 2))
    Te = pose([0.6, 0.2, -0.1], rot_z(0.5) @ rot_y(np.pi / 2))
    sol = solve_rod(RodProblem(1.0, (EI, 1.3 * EI, 0.8 * EI), np.array([0, 0, -1.0]), Ts, Te), segments=40)
    assert sol.status == "ok" and sol.stable
    for a in (sol.nodes, sol.frames, sol.force_start, sol.moment_start, sol.curvature):
        assert np.all(np.isfinite(a))
    assert np.abs(sol.force_start + sol.force_end - [0, 0, -1.0]).max() < 1e-9 * max(1.0, EI)


def test_end_load_balance_3d():
    p = heavy_3d()
    sol = solve_rod(p, segments=40)
    W = np.asarray(p.weight) * p.length
    assert np.abs(sol.force_start + sol.force_end - W).max() < 1e-12
    # moments about the origin: the bodies carry the moment of the weight (trapezoid = exact
    # for straight segments between the nodes)
    h = p.length / 40
    wk = np.full(41, h)
    wk[0] = wk[-1] = h / 2
    Mw = np.cross(sol.nodes, wk[:, None] * np.asarray(p.weight)).sum(axis=0)
    Mb = (sol.moment_start + sol.moment_end + np.cross(sol.nodes[0], sol.force_start)
          + np.cross(sol.nodes[-1], sol.force_end))
    assert np.abs(Mb - Mw).max() < 1e-10


def test_large_end_twist_by_key_points():
    # isotropic rod, non-coaxial clamps; the end turns 4 pi about its tangent in 32 key points
    sol = None
    Ts = pose([0, 0, 0], rot_y(np.pi / 2))
    for roll in np.linspace(0.0, 4 * np.pi, 33):
        Te = pose([0.8, 0.1, 0.0], rot_z(0.3) @ rot_y(np.pi / 2) @ rot_z(roll))
        p = RodProblem(1.0, (1.0, 1.0, 0.7), NOLOAD, Ts, Te)
        sol = solve_rod(p, segments=40, warm=None if sol is None else sol.state())
        assert sol.converged
        # isotropic rod, no distributed moment: twisting moment m . d3 is the same at both ends
        tw0 = sol.moment_start @ sol.frames[0, :3, 2]
        twL = -sol.moment_end @ sol.frames[-1, :3, 2]
        assert abs(tw0 - twL) < 1e-8 * max(1.0, abs(tw0))
    # the key points kept the two full turns (twisting moment of the order C * 4 pi / L) ...
    assert tw0 > 0.5 * 0.7 * 4 * np.pi
    # ... which a cold solve of the same end poses cannot know (it takes the roll modulo 2 pi)
    cold = solve_rod(p, segments=40)
    assert abs(cold.moment_start @ cold.frames[0, :3, 2]) < 1e-6


def test_overlength_reported_without_nan():
    for d in (1.0, 1.3):
        p = RodProblem(1.0, (1, 1, 1), np.array([0, 0, -1.0]), pose([0, 0, 0], rot_y(np.pi / 2)),
                       pose([d, 0, 0], rot_y(np.pi / 2)))
        sol = solve_rod(p, segments=10)
        assert sol.status == "overlength" and not sol.converged
        assert np.abs(sol.nodes[:, 1:]).max() == 0 and sol.nodes[-1, 0] == pytest.approx(1.0)
        for a in (sol.nodes, sol.frames, sol.quaternions, sol.force_start, sol.curvature):
            assert np.all(np.isfinite(a))
        assert np.isfinite(sol.residual)


@pytest.mark.parametrize("slack", [1e-6, 1e-9])
def test_any_slack_is_not_overlength(slack):
    # D16: over-length is |R| >= L; the rod reported it from |R| >= L (1 - 1e-9) on, as a solver failure
    Ts = pose([0, 0, 0], rot_y(np.pi / 2))
    p = RodProblem(1.0, (1, 1, 1), np.array([0, 0, -1.0]), Ts, pose([1.0 - slack, 0, 0], rot_y(np.pi / 2)))
    sol = solve_rod(p, segments=10)
    assert sol.status != "overlength"
    if not sol.converged:   # then it says why
        assert sol.status == "not_converged" and "nearly taut" in sol.message
    else:
        assert sol.status == "ok" and sol.residual < 1e-8
        assert np.linalg.norm(sol.nodes[-1] - [1.0 - slack, 0, 0]) < 1e-9


def test_coaxial_isotropic_family_reported():
    Ts = pose([0, 0, 0], rot_y(np.pi / 2))
    Te = pose([0.8, 0, 0], rot_x(2.0) @ rot_y(np.pi / 2))
    iso = solve_rod(RodProblem(1.0, (1.0, 1.0, 0.7), NOLOAD, Ts, Te), segments=40)
    assert iso.status == "non_unique"
    aniso = solve_rod(RodProblem(1.0, (1.0, 1.5, 0.7), NOLOAD, Ts, Te), segments=40)
    assert aniso.status == "ok"
    # gravity across the axis breaks the symmetry
    heavy = solve_rod(RodProblem(1.0, (1.0, 1.0, 0.7), np.array([0, 0, -1.0]), Ts, Te), segments=40)
    assert heavy.status == "ok"


def test_pinned_weightless_family_reported():
    # pinned ends, no weight: the buckled cable can turn about the chord
    p = RodProblem(1.0, (1.0, 1.5, 0.7), NOLOAD, pose([0, 0, 0]), pose([0.3, 0.2, -0.1]), "pinned", "pinned")
    sol = solve_rod(p, segments=40)
    assert sol.status == "non_unique" and "chord" in sol.message
    heavy = solve_rod(RodProblem(1.0, (1.0, 1.5, 0.7), np.array([0, 0, -1.0]), p.T_start, p.T_end,
                                 "pinned", "pinned"), segments=40)
    assert heavy.status == "ok" and heavy.stable


@pytest.mark.parametrize("weight", [0.0, 1.0])
def test_random_cold_problems_converge(weight):
    # random end poses (0.1 L .. 0.97 L apart), stiffness 1e-4 .. 1 w L^3, all end kinds
    rng = np.random.default_rng(11)
    kinds = [("clamped", "clamped"), ("clamped", "pinned"), ("pinned", "pinned"), ("clamped", "free")]
    for k in range(40):
        d = rng.standard_normal(3)
        d *= rng.uniform(0.1, 0.97) / np.linalg.norm(d)
        Te = pose(d, quaternion_to_matrix(rng.standard_normal(4)))
        Ts = pose([0, 0, 0], quaternion_to_matrix(rng.standard_normal(4)))
        EI = 10 ** rng.uniform(-4, 0)
        K = (EI, EI * rng.uniform(1, 2), EI * rng.uniform(0.5, 1))
        s, e = kinds[k % 4]
        sol = solve_rod(RodProblem(1.0, K, np.array([0, 0, -weight]), Ts, Te, s, e), segments=30)
        assert sol.converged and sol.status in ("ok", "non_unique"), (k, sol.status, sol.residual)
        assert sol.stable or sol.status == "non_unique"
        for a in (sol.nodes, sol.frames, sol.force_start, sol.moment_start, sol.force_end):
            assert np.all(np.isfinite(a))


# --------------------------------------------------------------------------- warm start and ends

def test_warm_start_matches_cold_and_is_cheaper():
    sol = solve_rod(heavy_3d(0.0), segments=40)
    warm_its = []
    for t in np.linspace(0.05, 0.5, 10):
        sol = solve_rod(heavy_3d(t), segments=40, warm=sol.state())
        warm_its.append(sol.iterations)
    cold = solve_rod(heavy_3d(0.5), segments=40)
    assert np.abs(cold.nodes - sol.nodes).max() < 1e-10
    assert max(warm_its) < cold.iterations
    # a large jump of the end pose: continuation with step halving from the warm state
    far = solve_rod(heavy_3d(1.5), segments=40, warm=sol.state())
    assert far.status == "ok"
    assert np.abs(far.nodes - solve_rod(heavy_3d(1.5), segments=40).nodes).max() < 1e-9


def test_key_point_path_one_newton_step_per_mesh():
    # once three key points are known the start is extrapolated quadratically along the path:
    # one Newton step reaches tol 1e-10, and the answer is the cold solve's
    sol = solve_rod(heavy_3d(0.0), segments=40)
    its = []
    for t in np.linspace(0.01, 0.2, 20):
        sol = solve_rod(heavy_3d(t), segments=40, warm=sol.state())
        its.append(sol.iterations)
    assert its[3:] == [1] * 17
    cold = solve_rod(heavy_3d(0.2), segments=40)
    assert np.abs(cold.nodes - sol.nodes).max() < 1e-10
    assert np.abs(cold.force_end - sol.force_end).max() < 1e-8
    assert sol.stable and cold.stable


def test_richardson_key_point_path_matches_cold():
    # both meshes follow their own histories (one step each), checked to stay on one branch; the
    # extrapolated answer, its loads, error estimate and stability equal the cold solve's
    sol = solve_rod(heavy_3d(0.0), segments=24, richardson=True)
    its = []
    for t in np.linspace(0.01, 0.15, 15):
        sol = solve_rod(heavy_3d(t), segments=24, richardson=True, warm=sol.state())
        its.append(sol.iterations)
    assert its[4:] == [2] * 11
    cold = solve_rod(heavy_3d(0.15), segments=24, richardson=True)
    assert np.abs(cold.nodes - sol.nodes).max() < 1e-10
    assert np.abs(cold.frames - sol.frames).max() < 1e-9
    for a, b in ((cold.force_start, sol.force_start), (cold.moment_end, sol.moment_end)):
        assert np.abs(a - b).max() < 1e-7 * np.abs(a).max()
    assert sol.error_estimate == pytest.approx(cold.error_estimate, rel=1e-6)
    assert sol.stable is True and cold.stable is True
    assert sol.quaternions.shape == (24, 4)
    assert np.allclose(quaternion_to_matrix(sol.quaternions[5]), quaternion_to_matrix(cold.quaternions[5]),
                       atol=1e-9)
    # a jump off the path: continuation on both meshes, still the cold answer
    far = solve_rod(heavy_3d(1.2), segments=24, richardson=True, warm=sol.state())
    cold_far = solve_rod(heavy_3d(1.2), segments=24, richardson=True)
    assert far.status == "ok" and far.stable is True
    assert np.abs(far.nodes - cold_far.nodes).max() < 1e-9


def test_free_start_is_the_reversed_cantilever():
    a = solve_rod(cantilever(1.0), segments=40)
    # the same cable held at its far end: start free (with the load), end clamped at the origin
    Te = planar_pose([0, 0, 0], np.pi)            # tangent into the end = -x
    b = solve_rod(RodProblem(1.0, (1, 1, 1), NOLOAD, np.eye(4), Te, "free", "clamped",
                             np.array([0, -1.0, 0]), None), segments=40)
    assert b.status == "ok"
    assert np.abs(b.nodes - a.nodes[::-1]).max() < 1e-10
    assert np.abs(b.force_end - [0, -1.0, 0]).max() < 1e-10
    assert np.linalg.norm(b.moment_end) == pytest.approx(np.linalg.norm(a.moment_start), abs=1e-10)
    assert np.allclose(b.frames[:, :3, 2], -a.frames[::-1, :3, 2], atol=1e-10)


def test_pinned_free_cable_hangs_plumb():
    p = RodProblem(2.0, (1e-3, 1e-3, 1e-3), np.array([0, 0, -3.0]), pose([0, 0, 1.0], rot_y(0.7)),
                   np.eye(4), "pinned", "free")
    sol = solve_rod(p, segments=20)
    assert sol.status == "ok" and sol.stable
    assert np.abs(sol.nodes - [[0, 0, 1.0 - s] for s in sol.s]).max() < 1e-9
    assert np.abs(sol.force_start - [0, 0, -6.0]).max() < 1e-9
    assert np.abs(sol.moment_start).max() == 0.0


def test_bad_input_raises():
    ok = dict(length=1.0, stiffness=(1, 1, 1), weight=NOLOAD, T_start=np.eye(4),
              T_end=pose([0.5, 0, 0]))
    with pytest.raises(ValueError):
        solve_rod(RodProblem(**ok, start="free", end="free"))
    with pytest.raises(ValueError):
        solve_rod(RodProblem(**{**ok, "stiffness": (1, 0, 1)}))
    with pytest.raises(ValueError):
        solve_rod(RodProblem(**{**ok, "T_end": np.diag([1.0, 1.0, -1.0, 1.0])}))
    with pytest.raises(ValueError):
        solve_rod(RodProblem(**ok, start="welded"))
