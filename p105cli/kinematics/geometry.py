"""Vectorised evaluation of ISO 10303-42 curves and surfaces.

Used by the higher kinematic pairs (curve and surface contact pairs) of
ISO 10303-105. Only numpy is used.

Conventions
-----------

* Parameters ``t`` (curves) and ``u, v`` (surfaces) are arrays of any shape;
  ``u`` and ``v`` broadcast with numpy rules. Results have shape
  ``param_shape + (3,)``. No function loops over samples in Python.
* For the elementary curves and surfaces the geometric data (``position``
  4x4 transform, radii, angles) may also carry leading batch axes; they
  broadcast against the parameter shape. B-spline control data are single
  (unbatched) nets.
* ``position`` is an ``axis2_placement_3d`` as a homogeneous 4x4 transform
  (see :mod:`p105cli.kinematics.placements`): columns 0, 1, 2 are the
  placement's x, y, z axes (Part 42 ``p[1]``, ``p[2]``, ``p[3]``) and column
  3 is its location ``C``.
* All angles (curve parameters of conics, surface parameters ``u`` and the
  ``v`` of sphere and torus, ``semi_angle``) are **radians**. Part 42
  parameterises these entities by angle in the file's plane-angle unit;
  convert first (``placements.plane_angle_to_radian``).
* Curves: ``evaluate(t) -> (P, dP, ddP)`` (point, first and second
  derivative with respect to the parameter), ``bounds`` (the parametric
  range; infinite for a line) and ``period`` (``2 pi`` for conics, else
  None). Surfaces: ``evaluate(u, v) -> (S, Su, Sv)``, ``evaluate2(u, v) ->
  (S, Su, Sv, Suu, Suv, Svv)`` (with the second derivatives the surface
  pairs' Jacobians need) and ``normal(u, v)`` = unit
  ``Su x Sv``, which is the Part 42 sense of the surface normal (outward for
  the cylinder, cone, sphere and torus; ``+z`` for the plane). Where
  ``Su x Sv`` is exactly zero (cone apex with ``radius = 0``, a collapsed
  B-spline edge) the normal is NaN; at ``v = pi/2`` in floating point the
  sphere's tiny but nonzero ``Su`` still yields the correct limit ``+z``.
* Every curve and surface has ``transformed(T)``: the same kind of entity
  in new coordinates, ``T`` a rigid 4x4 transform (new <- old). Rigid only:
  a conic stays a conic only under a similarity, and the pairs need no more.
* :func:`arc_length` (composite Gauss-Legendre, vectorised) and
  :func:`parameter_at_arc_length` (Newton on it) serve the rolling pairs.

Definitions (ISO 10303-42, geometry_schema; the repository's seed texts do
not quote Part 42, so these are the Part 42 formulas as published):

* line:      ``C(u) = P + u V`` (``V`` a vector *with* magnitude).
* circle:    ``C(u) = C + R (cos u x + sin u y)``.
* ellipse:   ``C(u) = C + R1 cos u x + R2 sin u y``.
* polyline:  ``c(u) = P_i (i - u) + P_{i+1} (u + 1 - i)`` for
  ``i - 1 <= u <= i`` (points numbered from 1), parametric range
  ``0 <= u <= n - 1``. Outside the range the end segments are extended.
* trimmed_curve (trimmed by parameter values ``t1 = trim_1``, ``t2 = trim_2``):
  the parameterisation of Part 42 as restated by IFC4 ``IfcTrimmedCurve``
  (adapted from ISO 10303-42): ``c(s) = B(t1 + s)`` when ``sense_agreement``
  and ``c(s) = B(t1 - s)`` otherwise, ``0 <= s <= |t2 - t1|``. On a periodic
  basis (circle, ellipse) ``t2`` is first moved by whole turns so that it
  lies after ``t1`` in the sense of the trimmed curve.
* b_spline_curve_with_knots: ``C(u) = sum_i N_i^d(u) P_i`` with the knot
  vector obtained by repeating each ``knots[k]`` ``knot_multiplicities[k]``
  times; range ``[U_d, U_{m-d}]``. rational_b_spline_curve:
  ``C(u) = sum N_i w_i P_i / sum N_i w_i`` (homogeneous coordinates).
* plane:                 ``S(u,v) = C + u x + v y``.
* cylindrical_surface:   ``S = C + R (cos u x + sin u y) + v z``.
* conical_surface:       ``S = C + (R + v tan a)(cos u x + sin u y) + v z``.
* spherical_surface:     ``S = C + R cos v (cos u x + sin u y) + R sin v z``.
* toroidal_surface:      ``S = C + (R + r cos v)(cos u x + sin u y) + r sin v z``.
* b_spline_surface_with_knots: ``S = sum_ij N_i(u) M_j(v) P_ij`` (and the
  rational variant with weights ``w_ij``), control net indexed ``[i, j]`` with
  ``i`` along ``u``.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "Line", "Circle", "Ellipse", "Polyline", "BSplineCurve", "TrimmedCurve",
    "Plane", "CylindricalSurface", "ConicalSurface", "SphericalSurface",
    "ToroidalSurface", "BSplineSurface",
    "expand_knots", "basis_functions", "arc_length", "parameter_at_arc_length",
]


# ---------------------------------------------------------------- helpers
def _f(x) -> np.ndarray:
    return np.asarray(x, dtype=float)


def _frame(T):
    T = _f(T)
    if T.shape[-2:] != (4, 4):
        raise ValueError(f"position must have shape (..., 4, 4), got {T.shape}")
    return T[..., :3, 3], T[..., :3, 0], T[..., :3, 1], T[..., :3, 2]


def _s(a) -> np.ndarray:
    """Scalar array -> broadcastable against (..., 3)."""
    return _f(a)[..., None]


def _unit_rows(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = v / n
    return np.where(n > 1e-300, out, np.nan)


def _rigid(T) -> np.ndarray:
    T = _f(T)
    if T.shape != (4, 4):
        raise ValueError(f"transformed: T must be one 4x4 transform, got shape {T.shape}")
    R = T[:3, :3]
    if not (np.allclose(R.T @ R, np.eye(3), atol=1e-9) and np.linalg.det(R) > 0
            and np.allclose(T[3], [0, 0, 0, 1])):
        raise ValueError("transformed: T must be a rigid transform (rotation and translation)")
    return T


def _move_points(T, P) -> np.ndarray:
    return P @ T[:3, :3].T + T[:3, 3]


class _Surface:
    def normal(self, u, v) -> np.ndarray:
        """Unit normal ``Su x Sv / |Su x Sv|`` (NaN where degenerate)."""
        _, su, sv = self.evaluate(u, v)
        return _unit_rows(np.cross(su, sv))


class _Placed:
    """Entities defined by a ``position`` (4x4) and shape numbers: move the position."""

    def transformed(self, T):
        T = _rigid(T)
        out = object.__new__(type(self))
        out.__dict__.update(self.__dict__)
        pos = T @ self.position
        out.position = pos
        out.c, out.x, out.y, out.z = _frame(pos)
        return out


# ---------------------------------------------------------------- conics etc.
class Line:
    """Part 42 ``line``: ``C(t) = pnt + t dir`` (``dir`` has magnitude)."""

    period = None
    bounds = (-np.inf, np.inf)

    def __init__(self, pnt, dir):
        self.pnt, self.dir = _f(pnt), _f(dir)

    def transformed(self, T):
        T = _rigid(T)
        return Line(_move_points(T, self.pnt), self.dir @ T[:3, :3].T)

    def evaluate(self, t):
        t = _s(t)
        p = self.pnt + t * self.dir
        d = np.broadcast_to(self.dir, p.shape).copy()
        return p, d, np.zeros_like(p)


class Ellipse(_Placed):
    """Part 42 ``ellipse``: ``C + a cos t x + b sin t y`` (t in radians)."""

    period = 2.0 * np.pi
    bounds = (0.0, 2.0 * np.pi)

    def __init__(self, position, semi_axis_1, semi_axis_2):
        self.position = _f(position)
        self.c, self.x, self.y, self.z = _frame(position)
        self.a, self.b = _f(semi_axis_1), _f(semi_axis_2)
        if np.any(self.a <= 0) or np.any(self.b <= 0):
            raise ValueError("semi axes must be positive")

    def evaluate(self, t):
        t = _f(t)
        ca, sa = _s(self.a * np.cos(t)), _s(self.a * np.sin(t))
        cb, sb = _s(self.b * np.cos(t)), _s(self.b * np.sin(t))
        p = self.c + ca * self.x + sb * self.y
        d = -sa * self.x + cb * self.y
        dd = -ca * self.x - sb * self.y
        return p, d, dd


class Circle(Ellipse):
    """Part 42 ``circle``: ``C + r (cos t x + sin t y)`` (t in radians)."""

    def __init__(self, position, radius):
        super().__init__(position, radius, radius)
        self.radius = self.a


class Polyline:
    """Part 42 ``polyline``: piecewise linear, parameter range ``[0, n-1]``.

    Segment ``i`` (1-based, between points ``i`` and ``i+1``) covers
    ``i - 1 <= t <= i``; at an interior vertex the derivative of the
    following segment is returned. ``ddP`` is zero.
    """

    period = None

    def __init__(self, points):
        self.points = _f(points)
        if self.points.ndim != 2 or self.points.shape[0] < 2 or self.points.shape[1] != 3:
            raise ValueError("points must have shape (n >= 2, 3)")
        self.bounds = (0.0, float(self.points.shape[0] - 1))

    def transformed(self, T):
        return Polyline(_move_points(_rigid(T), self.points))

    def evaluate(self, t):
        t = _f(t)
        n = self.points.shape[0]
        seg = np.clip(np.floor(t).astype(np.intp), 0, n - 2)
        p0, p1 = self.points[seg], self.points[seg + 1]
        d = p1 - p0
        p = p0 + _s(t - seg) * d
        return p, d, np.zeros_like(p)


# ---------------------------------------------------------------- B-splines
def expand_knots(knot_multiplicities, knots) -> np.ndarray:
    """Part 42 knot vector: each ``knots[k]`` repeated ``knot_multiplicities[k]`` times."""
    m = np.asarray(knot_multiplicities, dtype=np.intp)
    k = _f(knots)
    if m.shape != k.shape or m.ndim != 1:
        raise ValueError("knot_multiplicities and knots must be 1-D of equal length")
    if np.any(m < 1) or np.any(np.diff(k) <= 0):
        raise ValueError("multiplicities must be >= 1 and knots strictly increasing")
    return np.repeat(k, m)


def basis_functions(U, degree: int, t, nder: int = 2):
    """All B-spline basis functions and their derivatives at ``t``.

    ``U`` is the full knot vector (length ``m + 1``); returns a list of
    ``nder + 1`` arrays of shape ``t.shape + (m - degree,)``: the ``k``-th
    derivatives of ``N_i^degree``. Cox-de Boor recursion, vectorised over
    ``t`` (the Python loop runs over the degree only). The knot span is
    clamped to ``[U_d, U_{m-d}]`` so the curve end point is included and
    parameters outside the range evaluate the polynomial extension of the
    end spans.
    """
    U = _f(U)
    t = _f(t)
    p = int(degree)
    ncoef = U.size - p - 1
    if p < 0 or ncoef < 1:
        raise ValueError("knot vector too short for degree")
    tf = t.reshape(-1, 1)
    span = np.searchsorted(U, tf[:, 0], side="right") - 1
    span = np.clip(span, p, ncoef - 1)
    # Only the d + 1 functions N_{span-d .. span, d} are nonzero on the span: run the recursion on
    # those (local arrays (M, d + 1)) and scatter the result into the dense (M, ncoef) output.
    # D[k] = k-th derivative of the current degree's local basis.
    M = tf.shape[0]
    D = [np.ones((M, 1))] + [np.zeros((M, 1)) for _ in range(nder)]

    def inv(den):
        with np.errstate(divide="ignore"):
            return np.where(den != 0, 1.0 / np.where(den != 0, den, 1.0), 0.0)

    for d in range(1, p + 1):
        i = span[:, None] - d + np.arange(d + 1)     # global index of each local function
        ia = inv(U[i + d] - U[i])                    # 1 / (U_{i+d} - U_i)
        ib = inv(U[i + d + 1] - U[i + 1])            # 1 / (U_{i+d+1} - U_{i+1})
        prev = [np.pad(A, ((0, 0), (1, 1))) for A in D]   # N_{i, d-1} = prev[:, :-1], N_{i+1, d-1} = prev[:, 1:]
        new = [(tf - U[i]) * ia * prev[0][:, :-1] + (U[i + d + 1] - tf) * ib * prev[0][:, 1:]]
        for k in range(1, nder + 1):
            new.append(d * (ia * prev[k - 1][:, :-1] - ib * prev[k - 1][:, 1:]))
        D = new
    rows = np.arange(M)[:, None]
    cols = span[:, None] - p + np.arange(p + 1)
    dense = []
    for Dk in D:
        out = np.zeros((M, ncoef))
        out[rows, cols] = Dk
        dense.append(out)
    D = dense
    return [Dk.reshape(t.shape + (ncoef,)) for Dk in D]


def _check_bspline(degree, n, mults, knots):
    U = expand_knots(mults, knots)
    if degree < 1:
        raise ValueError("degree must be >= 1")
    if U.size != n + degree + 1:
        raise ValueError(
            f"sum(knot_multiplicities) = {U.size} must equal "
            f"number of control points + degree + 1 = {n + degree + 1}")
    return U


class BSplineCurve:
    """Part 42 ``b_spline_curve_with_knots`` (``weights`` -> ``rational_b_spline_curve``).

    ``control_points`` shape ``(n, 3)``; ``weights`` shape ``(n,)`` positive.
    Parameter range :attr:`bounds` = ``(U_d, U_n)``.
    """

    def __init__(self, degree, control_points, knot_multiplicities, knots, weights=None):
        self.degree = int(degree)
        self.P = _f(control_points)
        if self.P.ndim != 2 or self.P.shape[1] != 3:
            raise ValueError("control_points must have shape (n, 3)")
        self.U = _check_bspline(self.degree, self.P.shape[0], knot_multiplicities, knots)
        self.w = None if weights is None else _f(weights)
        if self.w is not None and (self.w.shape != self.P.shape[:1] or np.any(self.w <= 0)):
            raise ValueError("weights must have shape (n,) and be positive")
        self.bounds = (self.U[self.degree], self.U[-self.degree - 1])
        self.knot_multiplicities = np.asarray(knot_multiplicities, dtype=np.intp)
        self.knots = _f(knots)

    period = None

    def transformed(self, T):
        # affine invariance (also of the rational form: weights are unchanged)
        return BSplineCurve(self.degree, _move_points(_rigid(T), self.P), self.knot_multiplicities,
                            self.knots, self.w)

    def evaluate(self, t):
        N, dN, ddN = basis_functions(self.U, self.degree, t, 2)
        if self.w is None:
            return N @ self.P, dN @ self.P, ddN @ self.P
        Pw = self.P * self.w[:, None]
        A, dA, ddA = N @ Pw, dN @ Pw, ddN @ Pw
        W, dW, ddW = (_s(B @ self.w) for B in (N, dN, ddN))
        C = A / W
        dC = (dA - dW * C) / W
        ddC = (ddA - 2 * dW * dC - ddW * C) / W
        return C, dC, ddC


class TrimmedCurve:
    """Part 42 ``trimmed_curve`` trimmed by parameter values.

    ``c(s) = B(t1 + s)`` (``sense_agreement``) or ``B(t1 - s)``, ``0 <= s <=
    |t2 - t1|`` (IFC4 IfcTrimmedCurve's restatement of Part 42). On a
    periodic basis ``t2`` is shifted by whole periods to lie after ``t1`` in
    the trimmed curve's sense (so a circle trimmed from 350 to 10 degrees
    with sense TRUE is the 20 degree arc through 0).
    """

    period = None

    def __init__(self, basis_curve, trim_1, trim_2, sense_agreement=True):
        self.basis = basis_curve
        self.trim_1, self.trim_2 = float(trim_1), float(trim_2)
        self.sense = bool(sense_agreement)
        t1, t2 = self.trim_1, self.trim_2
        per = getattr(basis_curve, "period", None)
        if per:
            if self.sense:
                while t2 <= t1:
                    t2 += per
            else:
                while t2 >= t1:
                    t2 -= per
        elif (t2 > t1) != self.sense and t2 != t1:
            raise ValueError("trimmed_curve: on a non-periodic basis curve sense_agreement must equal "
                             f"(trim_1 < trim_2); got trim_1 = {t1:g}, trim_2 = {t2:g}, "
                             f"sense_agreement = {self.sense}")
        self._t2 = t2
        self.bounds = (0.0, abs(t2 - t1))

    def transformed(self, T):
        return TrimmedCurve(self.basis.transformed(T), self.trim_1, self.trim_2, self.sense)

    def evaluate(self, t):
        t = _f(t)
        sgn = 1.0 if self.sense else -1.0
        p, d, dd = self.basis.evaluate(self.trim_1 + sgn * t)
        return p, sgn * d, dd


# ---------------------------------------------------------------- arc length
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)


def _gauss_legendre(curve, t0, t1, panels):
    h = (t1 - t0) / panels
    k = np.arange(panels)
    nodes = t0[..., None, None] + h[..., None, None] * (k[:, None] + 0.5 + 0.5 * _GL_X)   # (..., panels, 8)
    _, d, _ = curve.evaluate(nodes)
    return 0.5 * h * np.einsum("...pk,k->...", np.linalg.norm(d, axis=-1), _GL_W)


def _bspline_s(curve, t, panels):
    """Arc length from the curve start: a table at the knots plus Gauss-Legendre inside one span
    (the speed is smooth inside a knot span, so the quadrature never straddles a knot)."""
    lo, hi = curve.bounds
    br = np.unique(curve.U[(curve.U >= lo) & (curve.U <= hi)])
    key = ("_cum_len", panels)
    cum = curve.__dict__.get(key)
    if cum is None:
        cum = np.concatenate([[0.0], np.cumsum(_gauss_legendre(curve, br[:-1], br[1:], panels))])
        curve.__dict__[key] = cum
    span = np.clip(np.searchsorted(br, t, side="right") - 1, 0, br.size - 2)
    return cum[span] + _gauss_legendre(curve, br[span], t, panels)


def arc_length(curve, t0, t1, panels: int = 16) -> np.ndarray:
    """Signed arc length ``int_t0^t1 |C'(t)| dt`` (negative when ``t1 < t0``).

    Composite 8-point Gauss-Legendre on ``panels`` equal panels, vectorised
    over the broadcast shape of ``t0`` and ``t1``; for a B-spline the
    quadrature runs knot span by knot span (a table of span lengths plus the
    partial span), for a polyline the segment lengths are summed exactly, for
    a trimmed curve its basis curve is integrated. Exact to rounding for
    lines, circles and polylines.
    """
    t0, t1 = np.broadcast_arrays(_f(t0), _f(t1))
    if isinstance(curve, TrimmedCurve):
        sg = 1.0 if curve.sense else -1.0
        return sg * arc_length(curve.basis, curve.trim_1 + sg * t0, curve.trim_1 + sg * t1, panels)
    if isinstance(curve, Polyline):
        seg_len = np.linalg.norm(np.diff(curve.points, axis=0), axis=-1)
        cum = np.concatenate([[0.0], np.cumsum(seg_len)])

        def s_at(t):
            seg = np.clip(np.floor(t).astype(np.intp), 0, seg_len.size - 1)
            return cum[seg] + (t - seg) * seg_len[seg]

        return s_at(t1) - s_at(t0)
    if isinstance(curve, BSplineCurve):
        return _bspline_s(curve, t1, panels) - _bspline_s(curve, t0, panels)
    return _gauss_legendre(curve, t0, t1, panels)


def parameter_at_arc_length(curve, t0, s, guess=None, panels: int = 16, iterations: int = 40,
                            tol: float = 1e-13):
    """Parameter ``t`` with ``arc_length(curve, t0, t) = s`` (vectorised Newton).

    ``guess`` defaults to ``t0 + s / |C'(t0)|``. Newton steps first update the
    arc length by one 8-point Gauss-Legendre panel over the step (cheap, and
    accurate once the steps are small), then finish with full
    :func:`arc_length` evaluations until ``|s(t) - s| <= tol * max(|s|, 1)``.
    Raises ValueError where the curve's speed vanishes or Newton does not
    converge.
    """
    t0, s = np.broadcast_arrays(_f(t0), _f(s))

    def speed(t):
        sp = np.linalg.norm(curve.evaluate(t)[1], axis=-1)
        if np.any(~(sp > 0)):
            raise ValueError("parameter_at_arc_length: the curve has zero speed")
        return sp

    t = t0 + s / speed(t0) if guess is None else np.broadcast_to(_f(guess), t0.shape).astype(float)
    scale = np.maximum(np.abs(s), 1.0)
    sk = arc_length(curve, t0, t, panels)
    for _ in range(iterations):                      # cheap phase: incremental arc length
        step = (sk - s) / speed(t)
        t_new = t - step
        sk = sk + _gauss_legendre(curve, t, t_new, 1)
        t = t_new
        if np.all(np.abs(step) <= 1e-7 * np.maximum(np.abs(t), 1.0)):
            break
    for _ in range(iterations):                      # exact phase
        f = arc_length(curve, t0, t, panels) - s
        if np.all(np.abs(f) <= tol * scale):
            return t
        t = t - f / speed(t)
    if np.all(np.abs(arc_length(curve, t0, t, panels) - s) <= 1e-9 * scale):
        return t
    raise ValueError("parameter_at_arc_length: Newton iteration did not converge")


# ---------------------------------------------------------------- surfaces
class Plane(_Placed, _Surface):
    """Part 42 ``plane``: ``S = C + u x + v y``."""

    def __init__(self, position):
        self.position = _f(position)
        self.c, self.x, self.y, self.z = _frame(position)

    def evaluate(self, u, v):
        u, v = np.broadcast_arrays(_f(u), _f(v))
        s = self.c + _s(u) * self.x + _s(v) * self.y
        return s, np.broadcast_to(self.x, s.shape).copy(), np.broadcast_to(self.y, s.shape).copy()

    def evaluate2(self, u, v):
        s, su, sv = self.evaluate(u, v)
        z = np.zeros_like(s)
        return s, su, sv, z, z.copy(), z.copy()


class _Revolved(_Placed, _Surface):
    """Surfaces ``S = C + rho(v)(cos u x + sin u y) + h(v) z``."""

    def __init__(self, position):
        self.position = _f(position)
        self.c, self.x, self.y, self.z = _frame(position)

    def _profile(self, v):  # -> rho, drho, h, dh (arrays)
        raise NotImplementedError

    def _profile2(self, v):  # -> ddrho, ddh
        raise NotImplementedError

    def evaluate2(self, u, v):
        """``S, Su, Sv, Suu, Suv, Svv``: ``Suu = -rho e_r``, ``Suv = rho' e_t``,
        ``Svv = rho'' e_r + h'' z``."""
        u, v = np.broadcast_arrays(_f(u), _f(v))
        rho, drho, h, dh = self._profile(v)
        ddrho, ddh = self._profile2(v)
        er = _s(np.cos(u)) * self.x + _s(np.sin(u)) * self.y
        et = -_s(np.sin(u)) * self.x + _s(np.cos(u)) * self.y
        s = self.c + _s(rho) * er + _s(h) * self.z
        return (s, _s(rho) * et, _s(drho) * er + _s(dh) * self.z, -_s(rho) * er, _s(drho) * et,
                _s(ddrho) * er + _s(ddh) * self.z)

    def evaluate(self, u, v):
        u, v = np.broadcast_arrays(_f(u), _f(v))
        rho, drho, h, dh = self._profile(v)
        er = _s(np.cos(u)) * self.x + _s(np.sin(u)) * self.y
        et = -_s(np.sin(u)) * self.x + _s(np.cos(u)) * self.y
        s = self.c + _s(rho) * er + _s(h) * self.z
        su = _s(rho) * et
        sv = _s(drho) * er + _s(dh) * self.z
        return s, su, sv


class CylindricalSurface(_Revolved):
    """Part 42 ``cylindrical_surface``: ``C + r(cos u x + sin u y) + v z``."""

    def __init__(self, position, radius):
        super().__init__(position)
        self.radius = _f(radius)
        if np.any(self.radius <= 0):
            raise ValueError("radius must be positive")

    def _profile(self, v):
        r = self.radius + 0 * v
        return r, 0 * r, v + 0 * r, 1 + 0 * r

    def _profile2(self, v):
        z = 0 * (self.radius + 0 * v)
        return z, z


class ConicalSurface(_Revolved):
    """Part 42 ``conical_surface``: ``C + (r + v tan a)(cos u x + sin u y) + v z``.

    ``radius`` is the radius at ``v = 0`` (Part 42: >= 0), ``semi_angle`` in
    radians, ``0 < a < pi/2``. The apex (``r + v tan a = 0``) is degenerate.
    """

    def __init__(self, position, radius, semi_angle):
        super().__init__(position)
        self.radius, self.semi_angle = _f(radius), _f(semi_angle)
        if np.any(self.radius < 0):
            raise ValueError("radius must be >= 0")
        if np.any(self.semi_angle <= 0) or np.any(self.semi_angle >= np.pi / 2):
            raise ValueError("semi_angle must be in (0, pi/2) radians")

    def _profile(self, v):
        ta = np.tan(self.semi_angle)
        rho = self.radius + v * ta
        return rho, ta + 0 * rho, v + 0 * rho, 1 + 0 * rho

    def _profile2(self, v):
        z = 0 * (self.radius + v * np.tan(self.semi_angle))
        return z, z


class SphericalSurface(_Revolved):
    """Part 42 ``spherical_surface``: ``C + r cos v (cos u x + sin u y) + r sin v z``."""

    def __init__(self, position, radius):
        super().__init__(position)
        self.radius = _f(radius)
        if np.any(self.radius <= 0):
            raise ValueError("radius must be positive")

    def _profile(self, v):
        r = self.radius
        return r * np.cos(v), -r * np.sin(v), r * np.sin(v), r * np.cos(v)

    def _profile2(self, v):
        r = self.radius
        return -r * np.cos(v), -r * np.sin(v)


class ToroidalSurface(_Revolved):
    """Part 42 ``toroidal_surface``: ``C + (R + r cos v)(cos u x + sin u y) + r sin v z``."""

    def __init__(self, position, major_radius, minor_radius):
        super().__init__(position)
        self.major_radius, self.minor_radius = _f(major_radius), _f(minor_radius)
        if np.any(self.major_radius <= 0) or np.any(self.minor_radius <= 0):
            raise ValueError("radii must be positive")

    def _profile(self, v):
        R, r = self.major_radius, self.minor_radius
        return R + r * np.cos(v), -r * np.sin(v), r * np.sin(v), r * np.cos(v)

    def _profile2(self, v):
        r = self.minor_radius
        return -r * np.cos(v), -r * np.sin(v)


class BSplineSurface(_Surface):
    """Part 42 ``b_spline_surface_with_knots`` (+ ``rational_b_spline_surface``).

    ``control_points`` shape ``(nu, nv, 3)`` (first index along ``u``),
    ``weights`` shape ``(nu, nv)``.
    """

    def __init__(self, u_degree, v_degree, control_points,
                 u_multiplicities, v_multiplicities, u_knots, v_knots, weights=None):
        self.pu, self.pv = int(u_degree), int(v_degree)
        self.P = _f(control_points)
        if self.P.ndim != 3 or self.P.shape[2] != 3:
            raise ValueError("control_points must have shape (nu, nv, 3)")
        self.U = _check_bspline(self.pu, self.P.shape[0], u_multiplicities, u_knots)
        self.V = _check_bspline(self.pv, self.P.shape[1], v_multiplicities, v_knots)
        self.w = None if weights is None else _f(weights)
        if self.w is not None and (self.w.shape != self.P.shape[:2] or np.any(self.w <= 0)):
            raise ValueError("weights must have shape (nu, nv) and be positive")
        self.u_multiplicities = np.asarray(u_multiplicities, dtype=np.intp)
        self.v_multiplicities = np.asarray(v_multiplicities, dtype=np.intp)
        self.u_knots, self.v_knots = _f(u_knots), _f(v_knots)
        self.u_bounds = (self.U[self.pu], self.U[-self.pu - 1])
        self.v_bounds = (self.V[self.pv], self.V[-self.pv - 1])

    def transformed(self, T):
        return BSplineSurface(self.pu, self.pv, _move_points(_rigid(T), self.P), self.u_multiplicities,
                              self.v_multiplicities, self.u_knots, self.v_knots, self.w)

    def evaluate2(self, u, v):
        """``S, Su, Sv, Suu, Suv, Svv`` (quotient rule on the homogeneous form)."""
        u, v = np.broadcast_arrays(_f(u), _f(v))
        Nu = basis_functions(self.U, self.pu, u, 2)
        Nv = basis_functions(self.V, self.pv, v, 2)
        w = np.ones(self.P.shape[:2]) if self.w is None else self.w
        Pw = np.concatenate([self.P * w[..., None], w[..., None]], axis=-1)

        def tp(a, b):
            return np.einsum("...i,...j,ijk->...k", a, b, Pw)

        H = tp(Nu[0], Nv[0])
        Hu, Hv = tp(Nu[1], Nv[0]), tp(Nu[0], Nv[1])
        Huu, Huv, Hvv = tp(Nu[2], Nv[0]), tp(Nu[1], Nv[1]), tp(Nu[0], Nv[2])
        A, W = H[..., :3], H[..., 3:]
        S = A / W
        Su = (Hu[..., :3] - Hu[..., 3:] * S) / W
        Sv = (Hv[..., :3] - Hv[..., 3:] * S) / W
        Suu = (Huu[..., :3] - 2 * Hu[..., 3:] * Su - Huu[..., 3:] * S) / W
        Svv = (Hvv[..., :3] - 2 * Hv[..., 3:] * Sv - Hvv[..., 3:] * S) / W
        Suv = (Huv[..., :3] - Hu[..., 3:] * Sv - Hv[..., 3:] * Su - Huv[..., 3:] * S) / W
        return S, Su, Sv, Suu, Suv, Svv

    def evaluate(self, u, v):
        u, v = np.broadcast_arrays(_f(u), _f(v))
        Nu, dNu = basis_functions(self.U, self.pu, u, 1)
        Nv, dNv = basis_functions(self.V, self.pv, v, 1)
        w = np.ones(self.P.shape[:2]) if self.w is None else self.w
        Pw = np.concatenate([self.P * w[..., None], w[..., None]], axis=-1)

        def tp(a, b):
            return np.einsum("...i,...j,ijk->...k", a, b, Pw)

        H, Hu, Hv = tp(Nu, Nv), tp(dNu, Nv), tp(Nu, dNv)
        W, Wu, Wv = H[..., 3:], Hu[..., 3:], Hv[..., 3:]
        S = H[..., :3] / W
        return S, (Hu[..., :3] - Wu * S) / W, (Hv[..., :3] - Wv * S) / W
