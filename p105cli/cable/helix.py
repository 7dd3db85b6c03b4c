"""The exact Kirchhoff helix: a closed-form 3D equilibrium of an isotropic rod.

A rod with equal bending stiffnesses lies on a circular helix of radius
``R`` about the z axis, its tangent at the angle ``alpha`` from that axis,
and turns about its tangent at the twist rate ``omega``; held by end forces
and moments alone, it is in equilibrium (the reference case
``e1_helix_clamped`` of the shared rod cases). With ``phi = s sin(alpha) / R``:

    r(s)  = (R cos phi, R sin phi, s cos alpha)
    d3    = t = (-sin alpha sin phi, sin alpha cos phi, cos alpha)
    N     = (-cos phi, -sin phi, 0)  (the principal normal),  B = t x N
    d1    = cos psi N + sin psi B,   d2 = -sin psi N + cos psi B,
    psi   = (omega - tau) s,  tau = sin(alpha) cos(alpha) / R (the geometric torsion)

It serves the tests and the cable benchmark as exact truth for the rod and
patent models.
"""

from __future__ import annotations

import numpy as np

__all__ = ["helix_frames"]


def helix_frames(s, R: float, alpha: float, omega: float) -> np.ndarray:
    """(N, 4, 4) material frames of the helix at arc lengths ``s`` (N,): columns d1, d2, d3
    (the tangent) and the position (the rod's conventions, docs/cable-rod.md)."""
    s = np.asarray(s, dtype=np.float64)
    sa, ca = np.sin(alpha), np.cos(alpha)
    phi = s * sa / R
    t = np.stack([-sa * np.sin(phi), sa * np.cos(phi), ca + 0 * phi], 1)
    N = np.stack([-np.cos(phi), -np.sin(phi), 0 * phi], 1)
    B = np.cross(t, N)
    psi = ((omega - sa * ca / R) * s)[:, None]
    F = np.tile(np.eye(4), (len(s), 1, 1))
    F[:, :3, 0] = np.cos(psi) * N + np.sin(psi) * B
    F[:, :3, 1] = -np.sin(psi) * N + np.cos(psi) * B
    F[:, :3, 2] = t
    F[:, :3, 3] = np.stack([R * np.cos(phi), R * np.sin(phi), ca * s], 1)
    return F
