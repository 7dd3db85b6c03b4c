"""Initial guesses for a cold solve: Hermite curve between the end poses with
parallel-transported frames, or a catenary when that fits the loads.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from p105cli.cable.catenary import catenary

from .model import _Model
from .quaternions import _cross, _qconj, _qexp, _qmat, _qmul


_E3 = np.array([0.0, 0.0, 1.0])


def _transport_frames(t, q0):
    """Quaternions of frames with z = t (n,3), carried from q0 by parallel transport.

    Discrete parallel transport composes the minimal rotations between
    consecutive tangents; for a start guess the direct minimal rotation from
    q0's z axis to each tangent is used instead when no tangent turns by more
    than ~150 degrees from it (same frames up to a small, smooth roll).
    """
    q0 = np.asarray(q0, dtype=float)
    z0 = _qmat(q0)[:, 2]
    c = t @ z0
    if np.all(c > -0.85):
        ax = _cross(z0, t)
        # quaternion of the minimal rotation z0 -> t: (1 + c, z0 x t) normalised
        rot = np.concatenate([(1.0 + c)[:, None], ax], axis=1)
        rot /= np.linalg.norm(rot, axis=1, keepdims=True)
        return _qmul(rot, q0[None, :])
    n = t.shape[0]
    out = np.empty((n, 4))
    q = q0
    prev = z0
    for i in range(n):
        ti = t[i]
        ax = _cross(prev, ti)
        cth = float(np.clip(prev @ ti, -1.0, 1.0))
        sn = float(np.linalg.norm(ax))
        if sn > 1e-15:
            q = _qmul(_qexp(ax / sn * np.arctan2(sn, cth)), q)
        elif cth < 0.0:     # exact reversal: turn about the frame's x axis
            q = _qmul(q, np.array([0.0, 1.0, 0.0, 0.0]))
        out[i] = q / np.linalg.norm(q)
        q = out[i]
        prev = ti
    return out


def _resample(curve_pts, frac):
    """Nodes at the arc-length fractions ``frac`` along a densely sampled curve."""
    seg = np.linalg.norm(np.diff(curve_pts, axis=0), axis=1)
    sc = np.concatenate([[0.0], np.cumsum(seg)])
    target = frac * sc[-1]
    return np.stack([np.interp(target, sc, curve_pts[:, k]) for k in range(3)], axis=1)


def _hermite_guess(m: _Model):
    """Cubic Hermite curve between the end points with the end tangents, length L."""
    d = m.pe - m.ps
    dist = float(np.linalg.norm(d))
    t0 = _qmat(m.qs)[:, 2]
    t1 = _qmat(m.qe)[:, 2] if m.clamp_e else (d / dist if dist > 0 else t0)
    if m.start != "clamped":
        t0 = d / dist if dist > 0 else t0
    # if both tangents are along the chord the cubic is straight: then a bow is
    # added in the plane of the start section's x axis (deterministic)
    side = _qmat(m.qs)[:, 1 if m.K[0] <= m.K[1] else 0]   # bow = bending about the weaker axis
    if dist > 0:
        side = side - (side @ d) / dist**2 * d
    if np.linalg.norm(side) < 1e-9:
        ref = np.array([0.0, 0.0, 1.0]) if abs(d[2]) < 0.9 * dist else np.array([1.0, 0.0, 0.0])
        side = _cross(d, ref)
    side = side / np.linalg.norm(side)
    gu, gw = np.polynomial.legendre.leggauss(6)
    ug = ((np.arange(24)[:, None] + 0.5 * (gu[None, :] + 1.0)) / 24.0).reshape(-1, 1)
    wg = np.tile(gw, 24) / 48.0

    def length(k, b):
        u = ug
        dc = ((3 * u**2 - 4 * u + 1) * (k * t0) + (-6 * u**2 + 6 * u) * d
              + (3 * u**2 - 2 * u) * (k * t1) + b * (4.0 - 8.0 * u) * side)
        return float(wg @ np.sqrt(np.einsum("ij,ij->i", dc, dc)))

    kmax = 3.0 * m.L
    dh = d / dist if dist > 0 else t0
    collinear = max(np.linalg.norm(_cross(t0, dh)), np.linalg.norm(_cross(t1, dh))) < 1e-6
    if not collinear and length(kmax, 0.0) >= m.L:
        k, b = brentq(lambda k: length(k, 0.0) - m.L, 0.0, kmax, xtol=1e-12 * m.L), 0.0
    else:
        k = dist
        b = brentq(lambda b: length(k, b) - m.L, 0.0, 2.0 * m.L, xtol=1e-12 * m.L)
    u = np.linspace(0.0, 1.0, 20 * m.n + 1)[:, None]
    return (m.ps + (u**3 - 2 * u**2 + u) * (k * t0) + (-2 * u**3 + 3 * u**2) * d
            + (u**3 - u**2) * (k * t1) + b * 4.0 * u * (1.0 - u) * side)


def _initial_guess(m: _Model):
    """Start: catenary for cables with weight (fixed ends), straight line for free ends, else Hermite."""
    n, L = m.n, m.L
    s_mid = 0.5 * (m.s[:-1] + m.s[1:])
    mu = None
    wnorm = float(np.linalg.norm(m.f))
    if not m.fixed_e:
        t0 = _qmat(m.qs)[:, 2]
        x = m.ps + m.s[:, None] * t0
        mu = m.Fe + (L - s_mid)[:, None] * m.f      # statically determinate
    else:
        x = None
        if wnorm > 0.0 and m.K.max() < 2.0 * wnorm * L ** 3:
            try:
                cat = catenary(m.ps, m.pe, L, m.f)
                x = cat.points(m.s)
                mu = cat.internal_force(s_mid)
            except ValueError:
                x = None
        if x is None:
            x = _resample(_hermite_guess(m), m.s / L)
    # node tangents: central differences, one-sided second order at the ends
    t = np.empty_like(x)
    t[1:-1] = x[2:] - x[:-2]
    t[0] = -3.0 * x[0] + 4.0 * x[1] - x[2]
    t[-1] = 3.0 * x[-1] - 4.0 * x[-2] + x[-3]
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    if m.clamp_s:
        t[0] = _qmat(m.qs)[:, 2]
    if m.clamp_e:
        t[-1] = _qmat(m.qe)[:, 2]
    q = _transport_frames(t, m.qs)
    if m.clamp_e:
        # distribute the roll mismatch at the end clamp linearly along the rod
        rel = _qmul(_qconj(q[-1]), m.qe)
        rel = np.where(rel[0] < 0, -rel, rel)
        roll = 2.0 * np.arctan2(rel[3], rel[0])
        q = _qmul(q, _qexp(np.outer(m.s / L * roll, _E3)))
        q[-1] = m.qe
    if m.clamp_s:
        q[0] = m.qs
    if mu is None:
        mu = np.zeros((n, 3)) + (L - s_mid)[:, None] * m.f * 0.5
    x = x.copy()
    x[0] = m.ps
    if m.fixed_e:
        x[-1] = m.pe
    return q, mu, x
