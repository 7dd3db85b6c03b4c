"""Quaternion (wxyz, body to world) and small 3-vector helpers of the rod solver.

To move to ``p105cli/kinematics/spatial.py`` (the one home of rotation
helpers) once that module exists; kept here, private, until then. At the
rod's sizes the cost is the number of numpy calls, so products go through
matmuls with constant 0/1 tensors rather than broadcasting.
"""

from __future__ import annotations

import numpy as np


_EYE3 = np.eye(3)


def _qmul_components(a, b):
    aw, ax, ay, az = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bw, bx, by, bz = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    out = np.empty(a.shape if a.shape == b.shape else np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = aw * bw - ax * bx - ay * by - az * bz
    out[..., 1] = aw * bx + ax * bw + ay * bz - az * by
    out[..., 2] = aw * by - ax * bz + ay * bw + az * bx
    out[..., 3] = aw * bz + ax * by - ay * bx + az * bw
    return out


def _qconj(q):
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def _qexp(theta):
    """exp(theta/2) as a unit quaternion, theta (..., 3) rotation vector."""
    ang = np.sqrt(np.einsum("...i,...i->...", theta, theta))
    half = 0.5 * ang
    # sin(half)/ang, series below 1e-4
    k = np.where(ang < 1e-4, 0.5 - ang * ang / 48.0, np.sin(half) / np.where(ang < 1e-4, 1.0, ang))
    return np.concatenate([np.cos(half)[..., None], k[..., None] * theta], axis=-1)


def _qlog(q):
    """Rotation vector of a unit quaternion (shortest: sign of w made >= 0)."""
    q = np.where(q[..., :1] < 0.0, -q, q)
    v = q[..., 1:]
    sv = np.linalg.norm(v, axis=-1)
    ang = 2.0 * np.arctan2(sv, q[..., 0])
    k = np.where(sv < 1e-12, 2.0, ang / np.where(sv < 1e-12, 1.0, sv))
    return k[..., None] * v


def _quadratic_form_of_rotation():
    """M (16, 9) with R(q).ravel() = (q q^T).ravel() @ M for a unit quaternion q (wxyz)."""
    M = np.zeros((4, 4, 3, 3))
    w, x, y, z = range(4)

    def put(i, j, terms):
        for c, a, b in terms:
            M[a, b, i, j] += c
    # R = (w^2 - |v|^2) I + 2 v v^T + 2 w [v]x, written with w^2 + |v|^2 = 1 kept homogeneous
    put(0, 0, [(1, w, w), (1, x, x), (-1, y, y), (-1, z, z)])
    put(1, 1, [(1, w, w), (-1, x, x), (1, y, y), (-1, z, z)])
    put(2, 2, [(1, w, w), (-1, x, x), (-1, y, y), (1, z, z)])
    put(0, 1, [(2, x, y), (-2, z, w)])
    put(0, 2, [(2, x, z), (2, y, w)])
    put(1, 0, [(2, x, y), (2, z, w)])
    put(1, 2, [(2, y, z), (-2, x, w)])
    put(2, 0, [(2, x, z), (-2, y, w)])
    put(2, 1, [(2, y, z), (2, x, w)])
    return M.reshape(16, 9)


# Products of quaternion components by matmuls with 0/1 matrices (numpy broadcasting over a
# trailing axis of 4 is several times slower): a_i b_j for all 16 pairs, a_i a_j for the 10 with i <= j
_I16 = np.repeat(np.eye(4), 4, axis=1)
_J16 = np.tile(np.eye(4), (1, 4))
_PAIRS = [(i, j) for i in range(4) for j in range(i, 4)]
_I10 = np.eye(4)[:, [i for i, _ in _PAIRS]]
_J10 = np.eye(4)[:, [j for _, j in _PAIRS]]


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


_QFORM = _quadratic_form_of_rotation()
_QFORM10 = _fold10(_QFORM)
_QM = np.stack([_qmul_components(np.eye(4)[i], np.eye(4)[j]) for i in range(4) for j in range(4)])


def _qmul(a, b):
    """Quaternion product (wxyz, broadcasting): bilinear, so the 16 component products and one matmul."""
    return _outer16(a, b) @ _QM


def _qmat(q):
    """Rotation matrices (..., 3, 3) of unit quaternions (..., 4): quadratic monomials, one matmul."""
    return (_square10(q) @ _QFORM10).reshape(q.shape[:-1] + (3, 3))


def _cross(a, b):
    out = np.empty(a.shape if a.shape == b.shape else np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


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


def _skew(v):
    S = np.zeros(v.shape[:-1] + (3, 3))
    S[..., 0, 1], S[..., 0, 2] = -v[..., 2], v[..., 1]
    S[..., 1, 0], S[..., 1, 2] = v[..., 2], -v[..., 0]
    S[..., 2, 0], S[..., 2, 1] = -v[..., 1], v[..., 0]
    return S


def _slerp_mid(qa, qb, t=0.5):
    """q_a exp(t log(conj(q_a) q_b)) (geodesic interpolation)."""
    return _qmul(qa, _qexp(t * _qlog(_qmul(_qconj(qa), qb))))


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
