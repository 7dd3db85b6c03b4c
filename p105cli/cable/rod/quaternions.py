"""The rod solver's names for the rotation algebra of :mod:`p105cli.kinematics.spatial`
(quaternions wxyz, body to world), and the few helpers only the rod needs (products of
quaternion components for its Hessians, a 3x3 solve, one pose's quaternion on floats).

At the rod's sizes the cost is the number of numpy calls, so products go through matmuls
with constant 0/1 tensors rather than broadcasting (spatial's own tensors).
"""

from __future__ import annotations

import numpy as np

from p105cli.kinematics.spatial import _I10, _I16, _J10, _J16, _PAIRS  # the 0/1 product tensors
from p105cli.kinematics.spatial import cross as _cross  # noqa: F401 (the rod's names)
from p105cli.kinematics.spatial import hat3 as _skew  # noqa: F401
from p105cli.kinematics.spatial import quaternion_conjugate as _qconj  # noqa: F401
from p105cli.kinematics.spatial import quaternion_from_rotation_vector as _qexp  # noqa: F401
from p105cli.kinematics.spatial import quaternion_multiply as _qmul  # noqa: F401
from p105cli.kinematics.spatial import quaternion_slerp as _slerp_mid  # noqa: F401
from p105cli.kinematics.spatial import rotation_vector_from_quaternion as _qlog  # noqa: F401
from p105cli.kinematics.spatial import unit_quaternion_to_matrix as _qmat  # noqa: F401

_EYE3 = np.eye(3)


def _outer16(a, b):
    """(..., 16) products a_i b_j (i major) of two (..., 4) arrays."""
    return (a @ _I16) * (b @ _J16)


def _square10(a):
    """(..., 10) products a_i a_j, i <= j, of a (..., 4) array (pairs as in _PAIRS)."""
    return (a @ _I10) * (a @ _J10)


def _fold10(T):
    """A quadratic-form tensor (16, k) on a_i a_j rewritten for _square10 (10, k)."""
    T = np.asarray(T).reshape(4, 4, -1)
    return np.stack([T[i, j] + T[j, i] if i != j else T[i, i] for i, j in _PAIRS])


def _solve3(S, r):
    """Solve a 3x3 system by the adjugate; None when nearly singular (|det| < 1e-13 ||S||^3)."""
    (a, b, c), (d, e, f), (g, h, i) = S.tolist()
    A, B, C = e * i - f * h, f * g - d * i, d * h - e * g
    det = a * A + b * B + c * C
    nrm = max(abs(a), abs(b), abs(c), abs(d), abs(e), abs(f), abs(g), abs(h), abs(i))
    if not abs(det) > 1e-13 * nrm ** 3:
        return None
    inv = np.array([[A, c * h - b * i, b * f - c * e],
                    [B, a * i - c * g, c * d - a * f],
                    [C, b * g - a * h, a * e - b * d]]) / det
    return inv @ r




def _pose_quat(T):
    """Quaternion (wxyz) of one pose's rotation: Shepperd's method on Python floats (hot path;
    same result as placements.matrix_to_quaternion up to sign)."""
    R = np.asarray(T, dtype=float)[:3, :3].tolist()
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R
    tr = r00 + r11 + r22
    k = max(range(4), key=lambda i: (tr, r00, r11, r22)[i])
    if k == 0:
        q = [1.0 + tr, r21 - r12, r02 - r20, r10 - r01]
    elif k == 1:
        q = [r21 - r12, 1.0 + 2.0 * r00 - tr, r01 + r10, r02 + r20]
    elif k == 2:
        q = [r02 - r20, r01 + r10, 1.0 + 2.0 * r11 - tr, r12 + r21]
    else:
        q = [r10 - r01, r02 + r20, r12 + r21, 1.0 + 2.0 * r22 - tr]
    q = np.array(q)
    return q / np.sqrt(q @ q)
