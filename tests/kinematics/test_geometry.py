"""Part 42 curve and surface evaluation: p105cli.kinematics.geometry.

Independent truths: closed forms typed in from the Part 42 definitions,
central finite differences, scipy.interpolate.BSpline (a different B-spline
implementation), and a hand-made rational quarter/full circle.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.interpolate import BSpline
from scipy.spatial.transform import Rotation

from p105cli.kinematics import geometry as G

PI = math.pi
RNG = np.random.default_rng(105)


def _frame():
    """A generic 4x4 placement (random rotation, offset origin)."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("zyx", [0.3, -0.7, 1.1]).as_matrix()
    T[:3, 3] = [1.0, -2.0, 0.5]
    return T


T0 = _frame()
C, X, Y, Z = T0[:3, 3], T0[:3, 0], T0[:3, 1], T0[:3, 2]


# ---------------------------------------------------------------- fixtures of entities
def _bspline_curve(rational=False):
    P = RNG.normal(size=(7, 3))
    w = RNG.uniform(0.5, 2.0, 7) if rational else None
    # cubic, interior knot 1.5 doubled: 4+1+2+4 = 11 = 7 + 3 + 1
    return G.BSplineCurve(3, P, [4, 1, 2, 4], [0.0, 0.7, 1.5, 2.5], w)


def _bspline_surface(rational=False):
    P = RNG.normal(size=(5, 4, 3))
    w = RNG.uniform(0.5, 2.0, (5, 4)) if rational else None
    return G.BSplineSurface(3, 2, P, [4, 1, 4], [3, 1, 3], [0.0, 0.4, 1.0], [-1.0, 0.2, 2.0], w)


CURVES = {
    "line": (G.Line([1.0, 2.0, 3.0], [0.5, -1.0, 2.0]), (-2.0, 2.0)),
    "circle": (G.Circle(T0, 1.7), (-4.0, 4.0)),
    "ellipse": (G.Ellipse(T0, 2.5, 0.8), (-4.0, 4.0)),
    "bspline": (_bspline_curve(), (0.0, 2.5)),
    "rational_bspline": (_bspline_curve(True), (0.0, 2.5)),
}

SURFACES = {
    "plane": (G.Plane(T0), (-2, 2), (-2, 2)),
    "cylinder": (G.CylindricalSurface(T0, 1.3), (-4, 4), (-2, 2)),
    "cone": (G.ConicalSurface(T0, 0.9, 0.4), (-4, 4), (-1, 2)),
    "sphere": (G.SphericalSurface(T0, 2.1), (-4, 4), (-1.4, 1.4)),
    "torus": (G.ToroidalSurface(T0, 3.0, 0.7), (-4, 4), (-4, 4)),
    "bspline": (_bspline_surface(), (0.0, 1.0), (-1.0, 2.0)),
    "rational_bspline": (_bspline_surface(True), (0.0, 1.0), (-1.0, 2.0)),
}


def _avoid_knots(t, knots, eps=1e-3):
    """Move samples away from knots (FD across a C1/C2 break is meaningless)."""
    t = np.array(t)
    for k in knots:
        t = np.where(np.abs(t - k) < eps, k + 2 * eps, t)
    return t


# ---------------------------------------------------------------- closed forms
def test_line_closed_form():
    p, d, dd = G.Line([1, 2, 3], [0.5, -1, 2]).evaluate([0.0, 2.0])
    np.testing.assert_allclose(p, [[1, 2, 3], [2, 0, 7]], atol=1e-15)
    np.testing.assert_allclose(d, [[0.5, -1, 2]] * 2)
    assert np.all(dd == 0)


def test_circle_and_ellipse_closed_form():
    r = 1.7
    p, d, dd = G.Circle(T0, r).evaluate([0.0, PI / 2, PI])
    np.testing.assert_allclose(p, [C + r * X, C + r * Y, C - r * X], atol=1e-14)
    np.testing.assert_allclose(d, [r * Y, -r * X, -r * Y], atol=1e-14)
    np.testing.assert_allclose(dd, [-r * X, -r * Y, r * X], atol=1e-14)
    p, _, _ = G.Ellipse(T0, 2.5, 0.8).evaluate([0.0, PI / 2])
    np.testing.assert_allclose(p, [C + 2.5 * X, C + 0.8 * Y], atol=1e-14)


def test_polyline_part42_parameterisation():
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 2, 0], [1, 2, 3.0]])
    pl = G.Polyline(pts)
    # range 0 <= u <= n-1, vertices at integer parameters
    p, d, dd = pl.evaluate([0.0, 1.0, 2.0, 3.0, 0.5, 1.25, 2.5])
    np.testing.assert_allclose(p[:4], pts, atol=1e-15)
    np.testing.assert_allclose(p[4:], [[0.5, 0, 0], [1, 0.5, 0], [1, 2, 1.5]], atol=1e-15)
    np.testing.assert_allclose(d[4:], [[1, 0, 0], [0, 2, 0], [0, 0, 3]])
    np.testing.assert_allclose(d[3], [0, 0, 3])  # end point uses last segment
    assert np.all(dd == 0)


def test_surfaces_closed_form():
    u = np.array([0.0, PI / 2])
    s, _, _ = G.Plane(T0).evaluate(2.0, -1.0)
    np.testing.assert_allclose(s, C + 2 * X - Y, atol=1e-14)
    s, _, _ = G.CylindricalSurface(T0, 1.3).evaluate(u, 0.5)
    np.testing.assert_allclose(s, [C + 1.3 * X + 0.5 * Z, C + 1.3 * Y + 0.5 * Z], atol=1e-14)
    a = 0.4
    s, _, sv = G.ConicalSurface(T0, 0.9, a).evaluate(0.0, 2.0)
    np.testing.assert_allclose(s, C + (0.9 + 2 * math.tan(a)) * X + 2 * Z, atol=1e-14)
    np.testing.assert_allclose(sv, math.tan(a) * X + Z, atol=1e-14)
    s, _, _ = G.SphericalSurface(T0, 2.1).evaluate([0.0, 1.0], [0.0, PI / 2])
    np.testing.assert_allclose(s, [C + 2.1 * X, C + 2.1 * Z], atol=1e-14)
    s, _, _ = G.ToroidalSurface(T0, 3.0, 0.7).evaluate([PI / 2, 0.0, 0.0], [0.0, PI, PI / 2])
    np.testing.assert_allclose(s, [C + 3.7 * Y, C + 2.3 * X, C + 3.0 * X + 0.7 * Z], atol=1e-14)


def test_normals_part42_sense():
    n = G.Plane(T0).normal(0.3, 0.4)
    np.testing.assert_allclose(n, Z, atol=1e-15)
    u, v = np.meshgrid(np.linspace(-3, 3, 7), np.linspace(-1.2, 1.2, 5))
    for surf, centre_of in [
        (G.CylindricalSurface(T0, 1.3), lambda s, u, v: C + v[..., None] * Z),
        (G.SphericalSurface(T0, 2.1), lambda s, u, v: C),
        (G.ToroidalSurface(T0, 3.0, 0.7),
         lambda s, u, v: C + 3.0 * (np.cos(u)[..., None] * X + np.sin(u)[..., None] * Y)),
    ]:
        s, _, _ = surf.evaluate(u, v)
        radial = s - centre_of(s, u, v)
        radial /= np.linalg.norm(radial, axis=-1, keepdims=True)
        np.testing.assert_allclose(surf.normal(u, v), radial, atol=1e-13)  # outward
    # cone: outward normal (cos a e_r - sin a z)
    a = 0.4
    n = G.ConicalSurface(T0, 0.9, a).normal(0.0, 1.0)
    np.testing.assert_allclose(n, math.cos(a) * X - math.sin(a) * Z, atol=1e-14)
    # float pi/2 at the sphere pole: cos v ~ 6e-17, normal is the correct limit +z
    np.testing.assert_allclose(G.SphericalSurface(T0, 1.0).normal(0.3, PI / 2), Z, atol=1e-15)
    # exactly degenerate (cone apex, Su = 0) -> NaN, not a silent wrong vector
    assert np.all(np.isnan(G.ConicalSurface(T0, 0.0, 0.4).normal(0.3, 0.0)))


# ---------------------------------------------------------------- finite differences
@pytest.mark.parametrize("name", sorted(CURVES))
def test_curve_derivatives_vs_finite_differences(name):
    crv, (a, b) = CURVES[name]
    t = np.linspace(a + 0.05, b - 0.05, 41)
    if "bspline" in name:
        t = _avoid_knots(t, crv.U)
    h = 1e-5
    p, d, dd = crv.evaluate(t)
    pp, dp, _ = crv.evaluate(t + h)
    pm, dm, _ = crv.evaluate(t - h)
    scale = 1 + np.abs(p).max()
    np.testing.assert_allclose(d, (pp - pm) / (2 * h), atol=1e-7 * scale * 10)
    np.testing.assert_allclose(dd, (dp - dm) / (2 * h), atol=1e-6 * scale * 10)


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_surface_derivatives_vs_finite_differences(name):
    srf, (u0, u1), (v0, v1) = SURFACES[name]
    u, v = np.meshgrid(np.linspace(u0 + 0.05, u1 - 0.05, 9), np.linspace(v0 + 0.05, v1 - 0.05, 7))
    if "bspline" in name:
        u, v = _avoid_knots(u, srf.U), _avoid_knots(v, srf.V)
    h = 1e-6
    s, su, sv = srf.evaluate(u, v)
    fu = (srf.evaluate(u + h, v)[0] - srf.evaluate(u - h, v)[0]) / (2 * h)
    fv = (srf.evaluate(u, v + h)[0] - srf.evaluate(u, v - h)[0]) / (2 * h)
    np.testing.assert_allclose(su, fu, atol=1e-6 * (1 + np.abs(s).max()))
    np.testing.assert_allclose(sv, fv, atol=1e-6 * (1 + np.abs(s).max()))


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_normals_unit_and_orthogonal(name):
    srf, (u0, u1), (v0, v1) = SURFACES[name]
    u, v = np.meshgrid(np.linspace(u0, u1, 8), np.linspace(v0, v1, 6))
    _, su, sv = srf.evaluate(u, v)
    n = srf.normal(u, v)
    np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1.0, atol=1e-13)
    np.testing.assert_allclose(np.einsum("...k,...k", n, su), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.einsum("...k,...k", n, sv), 0.0, atol=1e-12)
    # same sense as Su x Sv
    assert np.all(np.einsum("...k,...k", n, np.cross(su, sv)) > 0)


# ---------------------------------------------------------------- B-splines vs scipy
def test_bspline_curve_vs_scipy():
    crv = CURVES["bspline"][0]
    ref = BSpline(crv.U, crv.P, 3)
    t = np.linspace(0.0, 2.5, 301)  # includes knots and both ends
    p, d, dd = crv.evaluate(t)
    np.testing.assert_allclose(p, ref(t), atol=1e-12)
    # derivatives only away from the double knot (C1 there: right/left limits differ)
    tt = _avoid_knots(t, crv.U, 1e-9)
    _, d, dd = crv.evaluate(tt)
    np.testing.assert_allclose(d, ref.derivative(1)(tt), atol=1e-10)
    np.testing.assert_allclose(dd, ref.derivative(2)(tt), atol=1e-8)


def test_rational_bspline_curve_vs_scipy_homogeneous():
    crv = CURVES["rational_bspline"][0]
    A = BSpline(crv.U, crv.P * crv.w[:, None], 3)
    W = BSpline(crv.U, crv.w, 3)
    t = np.linspace(0.0, 2.5, 201)
    p, _, _ = crv.evaluate(t)
    np.testing.assert_allclose(p, A(t) / W(t)[:, None], atol=1e-12)
    tt = _avoid_knots(t, crv.U, 1e-9)
    _, d, _ = crv.evaluate(tt)
    a, da, w, dw = A(tt), A.derivative()(tt), W(tt)[:, None], W.derivative()(tt)[:, None]
    np.testing.assert_allclose(d, (da * w - a * dw) / w**2, atol=1e-9)


def test_bspline_surface_vs_scipy():
    for rational in (False, True):
        srf = SURFACES["rational_bspline" if rational else "bspline"][0]
        w = srf.w if rational else np.ones(srf.P.shape[:2])
        u, v = np.meshgrid(np.linspace(0, 1, 11), np.linspace(-1, 2, 13))
        nu, nv = srf.P.shape[:2]
        Bu = BSpline(srf.U, np.eye(nu), 3)(u)          # (..., nu) basis values
        Bv = BSpline(srf.V, np.eye(nv), 2)(v)
        Pw = srf.P * w[..., None]
        A = np.einsum("...i,...j,ijk->...k", Bu, Bv, Pw)
        W = np.einsum("...i,...j,ij->...", Bu, Bv, w)[..., None]
        s, _, _ = srf.evaluate(u, v)
        np.testing.assert_allclose(s, A / W, atol=1e-12)


def test_basis_partition_of_unity_and_derivative_sums():
    U = G.expand_knots([3, 1, 1, 3], [0.0, 0.3, 0.8, 1.0])
    t = np.linspace(-0.2, 1.2, 57)  # includes extrapolation
    N, dN, ddN = G.basis_functions(U, 2, t)
    np.testing.assert_allclose(N.sum(-1), 1.0, atol=1e-13)
    np.testing.assert_allclose(dN.sum(-1), 0.0, atol=1e-12)
    np.testing.assert_allclose(ddN.sum(-1), 0.0, atol=1e-10)


def test_rational_quarter_circle_exact():
    s = math.sqrt(2) / 2
    q = G.BSplineCurve(2, [[1, 0, 0], [1, 1, 0], [0, 1, 0]], [3, 3], [0.0, 1.0], [1, s, 1])
    t = np.linspace(0, 1, 1001)
    p, d, dd = q.evaluate(t)
    np.testing.assert_allclose(np.linalg.norm(p, axis=-1), 1.0, atol=1e-12)
    assert np.all(p[:, 2] == 0)
    np.testing.assert_allclose(p[[0, -1]], [[1, 0, 0], [0, 1, 0]], atol=1e-15)
    np.testing.assert_allclose(p[500], [s, s, 0], atol=1e-12)  # symmetric midpoint
    # tangent perpendicular to radius; d/dt |P|^2 = 0 and its derivative too
    np.testing.assert_allclose(np.einsum("ik,ik->i", p, d), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.einsum("ik,ik->i", d, d) + np.einsum("ik,ik->i", p, dd),
                               0.0, atol=1e-11)


def test_rational_full_circle_exact():
    s = math.sqrt(2) / 2
    P = [[1, 0, 0], [1, 1, 0], [0, 1, 0], [-1, 1, 0], [-1, 0, 0],
         [-1, -1, 0], [0, -1, 0], [1, -1, 0], [1, 0, 0]]
    w = [1, s, 1, s, 1, s, 1, s, 1]
    c = G.BSplineCurve(2, P, [3, 2, 2, 2, 3], [0, 1, 2, 3, 4], w)
    p, _, _ = c.evaluate(np.linspace(0, 4, 2001))
    np.testing.assert_allclose(np.linalg.norm(p, axis=-1), 1.0, atol=1e-12)


# ---------------------------------------------------------------- batching
@pytest.mark.parametrize("name", sorted(CURVES))
def test_curve_batching_matches_elementwise(name):
    crv, (a, b) = CURVES[name]
    t = np.random.default_rng(1).uniform(a, b, (4, 5))
    out = crv.evaluate(t)
    for k in range(3):
        assert out[k].shape == (4, 5, 3)
    for i in range(4):
        for j in range(5):
            single = crv.evaluate(t[i, j])
            for k in range(3):
                assert single[k].shape == (3,)
                np.testing.assert_allclose(out[k][i, j], single[k], rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_surface_batching_matches_elementwise(name):
    srf, (u0, u1), (v0, v1) = SURFACES[name]
    g = np.random.default_rng(2)
    u, v = g.uniform(u0, u1, (4, 5)), g.uniform(v0, v1, (4, 5))
    out = srf.evaluate(u, v) + (srf.normal(u, v),)
    for o in out:
        assert o.shape == (4, 5, 3)
    for i in range(4):
        for j in range(5):
            single = srf.evaluate(u[i, j], v[i, j]) + (srf.normal(u[i, j], v[i, j]),)
            for k in range(4):
                np.testing.assert_allclose(out[k][i, j], single[k], rtol=1e-14, atol=1e-14)


def test_polyline_batching_and_broadcast_uv():
    pl = G.Polyline([[0, 0, 0], [1, 0, 0], [1, 2, 0]])
    t = np.linspace(0, 2, 20).reshape(4, 5)
    p, _, _ = pl.evaluate(t)
    assert p.shape == (4, 5, 3)
    np.testing.assert_allclose(p[2, 3], pl.evaluate(t[2, 3])[0])
    s, su, sv = G.SphericalSurface(T0, 1.0).evaluate(np.zeros((4, 1)), np.zeros(5))
    assert s.shape == su.shape == sv.shape == (4, 5, 3)


def test_batched_geometry_parameters():
    """Positions and radii with leading batch axes broadcast against t."""
    Ts = np.stack([T0, np.eye(4)])              # (2, 4, 4)
    radii = np.array([1.0, 2.0])
    circ = G.Circle(Ts, radii)
    t = np.array([0.3, 1.2])
    p, d, dd = circ.evaluate(t)
    for b in range(2):
        ref = G.Circle(Ts[b], radii[b]).evaluate(t[b])
        for k, arr in enumerate((p, d, dd)):
            np.testing.assert_allclose(arr[b], ref[k], atol=1e-15)
    tor = G.ToroidalSurface(Ts, np.array([3.0, 4.0]), 0.5)
    s, _, _ = tor.evaluate(t, t)
    np.testing.assert_allclose(s[1], G.ToroidalSurface(np.eye(4), 4.0, 0.5).evaluate(1.2, 1.2)[0])


# ---------------------------------------------------------------- input errors
def test_invalid_inputs_raise():
    with pytest.raises(ValueError, match="must equal"):
        G.BSplineCurve(3, np.zeros((5, 3)), [4, 4], [0.0, 1.0])
    with pytest.raises(ValueError):
        G.BSplineCurve(2, np.zeros((3, 3)), [3, 3], [0.0, 1.0], [1.0, -1.0, 1.0])
    with pytest.raises(ValueError):
        G.expand_knots([2, 2], [1.0, 1.0])
    with pytest.raises(ValueError):
        G.Circle(np.eye(3), 1.0)
    with pytest.raises(ValueError):
        G.ConicalSurface(T0, 1.0, PI / 2)
    with pytest.raises(ValueError):
        G.Polyline([[0, 0, 0]])


# ---------------------------------------------------------------- second derivatives of surfaces
@pytest.mark.parametrize("name", sorted(SURFACES))
def test_surface_second_derivatives_vs_finite_differences(name):
    srf, (u0, u1), (v0, v1) = SURFACES[name]
    u, v = np.meshgrid(np.linspace(u0 + 0.05, u1 - 0.05, 7), np.linspace(v0 + 0.05, v1 - 0.05, 5))
    if "bspline" in name:
        u, v = _avoid_knots(u, srf.U, 1e-2), _avoid_knots(v, srf.V, 1e-2)
    h = 1e-5
    s, su, sv, suu, suv, svv = srf.evaluate2(u, v)
    s1, su1, sv1 = srf.evaluate(u, v)
    np.testing.assert_allclose(s, s1, atol=1e-13)
    np.testing.assert_allclose(su, su1, atol=1e-12)
    np.testing.assert_allclose(sv, sv1, atol=1e-12)
    _, su_p, sv_p = srf.evaluate(u + h, v)
    _, su_m, sv_m = srf.evaluate(u - h, v)
    _, su_q, sv_q = srf.evaluate(u, v + h)
    _, su_n, sv_n = srf.evaluate(u, v - h)
    tol = 1e-6 * (1 + np.abs(s).max()) * 10
    np.testing.assert_allclose(suu, (su_p - su_m) / (2 * h), atol=tol)
    np.testing.assert_allclose(suv, (sv_p - sv_m) / (2 * h), atol=tol)
    np.testing.assert_allclose(suv, (su_q - su_n) / (2 * h), atol=tol)
    np.testing.assert_allclose(svv, (sv_q - sv_n) / (2 * h), atol=tol)


# ---------------------------------------------------------------- transformed
T1 = np.eye(4)
T1[:3, :3] = Rotation.from_rotvec([0.4, -1.2, 0.7]).as_matrix()
T1[:3, 3] = [3.0, -1.0, 2.5]


def _moved(T, p):
    return p @ T[:3, :3].T + T[:3, 3]


ALL_CURVES = dict(CURVES, polyline=(G.Polyline(RNG.normal(size=(4, 3))), (0.0, 3.0)),
                  trimmed=(G.TrimmedCurve(G.Circle(T0, 1.1), 0.5, 2.0, True), (0.0, 1.5)))


@pytest.mark.parametrize("name", sorted(ALL_CURVES))
def test_curve_transformed(name):
    crv, (a, b) = ALL_CURVES[name]
    moved = crv.transformed(T1)
    assert type(moved) is type(crv)
    t = np.linspace(a, b, 23)
    p, d, dd = crv.evaluate(t)
    q, e, ee = moved.evaluate(t)
    np.testing.assert_allclose(q, _moved(T1, p), atol=1e-12)
    np.testing.assert_allclose(e, d @ T1[:3, :3].T, atol=1e-12)
    np.testing.assert_allclose(ee, dd @ T1[:3, :3].T, atol=1e-11)
    # the original is unchanged
    np.testing.assert_array_equal(crv.evaluate(t)[0], p)


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_surface_transformed(name):
    srf, (u0, u1), (v0, v1) = SURFACES[name]
    moved = srf.transformed(T1)
    assert type(moved) is type(srf)
    u, v = np.meshgrid(np.linspace(u0, u1, 5), np.linspace(v0, v1, 4))
    a = srf.evaluate2(u, v)
    b = moved.evaluate2(u, v)
    np.testing.assert_allclose(b[0], _moved(T1, a[0]), atol=1e-12)
    for x, y in zip(a[1:], b[1:]):
        np.testing.assert_allclose(y, x @ T1[:3, :3].T, atol=1e-11)
    np.testing.assert_allclose(moved.normal(u, v), srf.normal(u, v) @ T1[:3, :3].T, atol=1e-12)


def test_transformed_rejects_non_rigid():
    with pytest.raises(ValueError, match="rigid"):
        G.Circle(T0, 1.0).transformed(np.diag([2.0, 1.0, 1.0, 1.0]))


# ---------------------------------------------------------------- trimmed curves
def test_trimmed_curve_parameterisation():
    circle = G.Circle(T0, 2.0)
    # sense TRUE: c(s) = B(t1 + s), s in [0, t2 - t1]
    tc = G.TrimmedCurve(circle, 0.5, 2.0, True)
    assert tc.bounds == (0.0, 1.5)
    np.testing.assert_allclose(tc.evaluate(0.3)[0], C + 2.0 * (math.cos(0.8) * X + math.sin(0.8) * Y), atol=1e-14)
    # sense FALSE: c(s) = B(t1 - s); the tangent is reversed
    tf = G.TrimmedCurve(circle, 2.0, 0.5, False)
    np.testing.assert_allclose(tf.evaluate(0.0)[0], circle.evaluate(2.0)[0], atol=1e-14)
    np.testing.assert_allclose(tf.evaluate(1.5)[0], circle.evaluate(0.5)[0], atol=1e-14)
    np.testing.assert_allclose(tf.evaluate(0.4)[1], -circle.evaluate(1.6)[1], atol=1e-14)
    # periodic basis: 350 deg -> 10 deg with sense TRUE is the short arc through 0
    tp = G.TrimmedCurve(circle, math.radians(350), math.radians(10), True)
    np.testing.assert_allclose(tp.bounds[1], math.radians(20), atol=1e-14)
    np.testing.assert_allclose(tp.evaluate(math.radians(10))[0], circle.evaluate(0.0)[0], atol=1e-14)
    # ... and with sense FALSE the long way round
    tq = G.TrimmedCurve(circle, math.radians(350), math.radians(10), False)
    np.testing.assert_allclose(tq.bounds[1], math.radians(340), atol=1e-13)
    # a line trimmed against its sense is an error (not periodic)
    with pytest.raises(ValueError, match="sense_agreement"):
        G.TrimmedCurve(G.Line([0, 0, 0], [1.0, 0, 0]), 0.0, 2.0, False)


# ---------------------------------------------------------------- arc length
def test_arc_length_closed_forms():
    circle = G.Circle(T0, 1.7)
    t0, t1 = np.array([0.0, -1.0, 2.0]), np.array([1.0, 3.0, -2.0])
    np.testing.assert_allclose(G.arc_length(circle, t0, t1), 1.7 * (t1 - t0), atol=1e-13)
    line = G.Line([1.0, 2.0, 3.0], [0.5, -1.0, 2.0])
    np.testing.assert_allclose(G.arc_length(line, 0.0, 2.0), 2.0 * math.sqrt(5.25), atol=1e-13)
    poly = G.Polyline([[0, 0, 0], [3, 4, 0], [3, 4, 2.0]])
    np.testing.assert_allclose(G.arc_length(poly, [0.0, 0.5, 0.0], [2.0, 1.5, 1.25]), [7.0, 2.5 + 1.0, 5.5],
                               atol=1e-13)


def test_arc_length_ellipse_and_bspline_vs_quad():
    from scipy.integrate import quad
    ell = G.Ellipse(T0, 2.5, 0.8)
    ref = quad(lambda t: math.hypot(2.5 * math.sin(t), 0.8 * math.cos(t)), 0.2, 2.9, epsabs=1e-13)[0]
    np.testing.assert_allclose(G.arc_length(ell, 0.2, 2.9), ref, rtol=1e-12)
    crv = CURVES["bspline"][0]
    pts = [0.0, 0.7, 1.5, 2.2]
    ref = quad(lambda t: np.linalg.norm(crv.evaluate(t)[1]), 0.1, 2.2, points=pts, epsabs=1e-12, limit=200)[0]
    np.testing.assert_allclose(G.arc_length(crv, 0.1, 2.2), ref, rtol=1e-11)
    np.testing.assert_allclose(G.arc_length(crv, 2.2, 0.1), -ref, rtol=1e-11)
    # a trimmed curve against its sense has the basis' length between the trims
    tc = G.TrimmedCurve(ell, 2.9, 0.2, False)
    np.testing.assert_allclose(G.arc_length(tc, 0.0, 2.7), G.arc_length(ell, 0.2, 2.9), rtol=1e-13)


def test_parameter_at_arc_length_inverts():
    for crv, t0, ts in ((G.Ellipse(T0, 2.5, 0.8), 0.3, np.array([-2.0, 0.1, 1.0, 4.0])),
                        (G.Circle(T0, 1.7), 0.0, np.array([-1.0, 2.0])),
                        (G.Polyline([[0, 0, 0], [3, 4, 0], [3, 4, 2.0]]), 0.2, np.array([0.5, 1.7])),
                        (CURVES["bspline"][0], 0.3, np.array([0.1, 1.4, 1.6, 2.45])),
                        (G.TrimmedCurve(G.Ellipse(T0, 2.5, 0.8), 2.0, 0.5, False), 0.1, np.array([0.0, 1.3]))):
        s = G.arc_length(crv, t0, ts)
        np.testing.assert_allclose(G.parameter_at_arc_length(crv, t0, s), ts, atol=1e-10)


def test_bspline_many_spans_vs_scipy():
    """The span-local recursion scattered into the dense basis: 30 spans, uneven knots, 2 derivatives."""
    knots = np.concatenate([[0.0], np.sort(RNG.uniform(0.0, 1.0, 29)), [1.0]])
    P = RNG.normal(size=(33, 3))
    crv = G.BSplineCurve(3, P, [4] + [1] * 29 + [4], knots)
    ref = BSpline(crv.U, P, 3)
    t = _avoid_knots(np.linspace(0.0, 1.0, 997), knots, 1e-7)
    p, d, dd = crv.evaluate(t)
    np.testing.assert_allclose(p, ref(t), atol=1e-12)
    np.testing.assert_allclose(d, ref.derivative(1)(t), atol=1e-8 * np.abs(ref.derivative(1)(t)).max())
    np.testing.assert_allclose(dd, ref.derivative(2)(t), atol=1e-8 * np.abs(ref.derivative(2)(t)).max())
