"""The inextensible catenary: closed form, used as the start of hanging-cable solves.

A perfectly flexible, inextensible cable of length ``L`` and weight ``w`` per
unit length hangs between two points ``A`` and ``B``. In the vertical plane
through ``A`` and ``B`` (horizontal span ``h`` >= 0 along the chord's
horizontal projection, rise ``v`` of ``B`` above ``A`` against gravity):

    sqrt(L^2 - v^2) = 2 a sinh(h / 2a)           (a = H / w, the catenary parameter)
    x_m = h/2 - a artanh(v / L)                   (abscissa of the vertex)
    sigma = s - a sinh(x_m / a)                   (arc length measured from the vertex)
    x(s) = x_m + a asinh(sigma / a)
    y(s) = sqrt(a^2 + sigma^2) - a cosh(x_m / a)
    tension T(s) = w sqrt(a^2 + sigma^2), along the tangent

The equation for ``a`` is solved in the variable ``xi = h / 2a`` as
``log(sinh(xi) / xi) = log(r)`` with ``r = sqrt(L^2 - v^2) / h >= 1``: the
left side is increasing and convex, so safeguarded Newton from below converges
for every ``r`` from ``1 + 1e-15`` to ``1e12``.

Degenerate cases (``h`` ~ 0: vertical chord; ``r <= 1``: taut or over-length)
have no catenary; :func:`catenary` raises ``ValueError`` for them and the rod
solver picks another start.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Catenary", "catenary", "catenary_parameter"]


def _log_sinhc(xi):
    """log(sinh(xi)/xi) without overflow or cancellation (xi >= 0)."""
    xi = np.asarray(xi, dtype=float)
    small = xi < 1e-3
    xs = np.where(small, xi, 1.0)
    xl = np.where(small, 1.0, xi)
    # series: sinh(x)/x = 1 + x^2/6 + x^4/120 ...; log of it = x^2/6 - x^4/180 + ...
    ser = xs * xs / 6.0 - xs ** 4 / 180.0
    big = xl + np.log1p(-np.exp(-2.0 * xl)) - np.log(2.0 * xl)
    return np.where(small, ser, big)


def _dlog_sinhc(xi):
    """d/dxi log(sinh(xi)/xi) = coth(xi) - 1/xi."""
    xi = np.asarray(xi, dtype=float)
    small = xi < 1e-3
    xs = np.where(small, xi, 1.0)
    xl = np.where(small, 1.0, xi)
    return np.where(small, xs / 3.0 - xs ** 3 / 45.0, 1.0 / np.tanh(xl) - 1.0 / xl)


def catenary_parameter(length: float, span: float, rise: float) -> float:
    """Catenary parameter ``a = H / w`` for a cable of ``length`` over ``span`` (h) and ``rise`` (v).

    Raises ``ValueError`` when no catenary exists (span <= 0 or the cable is
    taut/over-length: ``sqrt(L^2 - v^2) <= h``).
    """
    L, h, v = float(length), float(span), float(rise)
    if not (np.isfinite(L) and np.isfinite(h) and np.isfinite(v)) or L <= 0.0:
        raise ValueError("catenary: length, span and rise must be finite, length > 0")
    if h <= 1e-14 * L:
        raise ValueError("catenary: vertical chord (no horizontal span)")
    chord2 = L * L - v * v
    if chord2 <= h * h:
        raise ValueError("catenary: cable is taut or over-length")
    logr = 0.5 * np.log(chord2) - np.log(h)
    # start below the root (the function is convex increasing): xi0 from the
    # small-xi expansion log r ~ xi^2/6, capped by the large-xi form xi - log(2 xi) ~ log r.
    xi = min(np.sqrt(6.0 * logr), logr + np.log(2.0 * max(logr, 1.0)) + 1.0)
    for _ in range(100):
        f = float(_log_sinhc(xi)) - logr
        d = float(_dlog_sinhc(xi))
        step = f / d
        xi_new = xi - step
        if xi_new <= 0.0:
            xi_new = 0.5 * xi
        if abs(xi_new - xi) <= 1e-15 * xi:
            xi = xi_new
            break
        xi = xi_new
    return h / (2.0 * xi)


@dataclass(frozen=True)
class Catenary:
    """A solved catenary in the plane of its end points (see module docstring)."""

    length: float
    weight: float          # w, N/m (> 0)
    a: float               # H / w, m
    x_m: float             # abscissa of the vertex, m
    origin: np.ndarray     # (3,) end A, world
    e_h: np.ndarray        # (3,) horizontal unit vector from A towards B
    e_v: np.ndarray        # (3,) unit vector against gravity

    @property
    def horizontal_tension(self) -> float:
        return self.weight * self.a

    def _sigma(self, s):
        return np.asarray(s, dtype=float) - self.a * np.sinh(self.x_m / self.a)

    def points(self, s) -> np.ndarray:
        """(..., 3) world positions at arc lengths ``s`` from A."""
        sig = self._sigma(s)
        a = self.a
        x = self.x_m + a * np.arcsinh(sig / a)
        y = np.hypot(a, sig) - a * np.cosh(self.x_m / a)
        return self.origin + x[..., None] * self.e_h + y[..., None] * self.e_v

    def tangents(self, s) -> np.ndarray:
        """(..., 3) unit tangents (direction of increasing arc length)."""
        sig = self._sigma(s)
        r = np.hypot(self.a, sig)
        return (self.a / r)[..., None] * self.e_h + (sig / r)[..., None] * self.e_v

    def tension(self, s) -> np.ndarray:
        """(...) tension T(s) = w sqrt(a^2 + sigma^2), N."""
        return self.weight * np.hypot(self.a, self._sigma(s))

    def internal_force(self, s) -> np.ndarray:
        """(..., 3) force that the part (s, L] exerts on the part [0, s]: T t."""
        return self.tension(s)[..., None] * self.tangents(s)


def catenary(p_a, p_b, length: float, weight) -> Catenary:
    """The catenary of ``length`` hanging from ``p_a`` to ``p_b`` under ``weight`` (3,) N/m, world.

    Raises ``ValueError`` when there is none (no weight, vertical chord, taut
    or over-length cable).
    """
    p_a = np.asarray(p_a, dtype=float).reshape(3)
    p_b = np.asarray(p_b, dtype=float).reshape(3)
    f = np.asarray(weight, dtype=float).reshape(3)
    w = float(np.linalg.norm(f))
    if not w > 0.0:
        raise ValueError("catenary: zero weight")
    e_v = -f / w
    d = p_b - p_a
    v = float(d @ e_v)
    dh = d - v * e_v
    h = float(np.linalg.norm(dh))
    a = catenary_parameter(length, h, v)
    e_h = dh / h
    x_m = 0.5 * h - a * np.arctanh(v / length)
    return Catenary(float(length), w, a, float(x_m), p_a, e_h, e_v)
