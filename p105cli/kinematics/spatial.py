"""Spatial algebra: rigid transforms, rotations, twists and quaternions, one of each.

The one home of the rotation algebra of the package (compare
``scipy.spatial.transform``: one rotation vector, one inverse, batched on
leading axes). :mod:`placements` keeps what is specific to Part 42 and Part
105 (``axis2_placement_3d``, ``su_parameters``, ypr, Euler and Cardan angles)
and builds on this module.

Conventions
-----------

* Every function is vectorised over leading axes: vectors ``(..., 3)``,
  rotations ``(..., 3, 3)``, rigid transforms ``(..., 4, 4)``, twists
  ``(..., 6)`` ordered ``(v, w)``, quaternions ``(..., 4)`` scalar first
  (``wxyz``, Hamilton product) unless ``order="xyzw"``; results are float64.
* Rotations are active and act on column vectors. ``T_a_b`` is the placement
  of frame *b* in frame *a*: ``p_a = T_a_b @ p_b``, ``T_a_c = T_a_b @ T_b_c``.
* A twist ``xi = (v, w)`` and its matrix ``hat(xi) = [[hat3(w), v], [0, 0]]``;
  ``adjoint(T) @ xi`` is ``vee(T hat(xi) T^-1)``: a body twist of ``T`` made
  spatial.
* The rotation vector ``phi`` (axis times angle, ``|phi| <= pi``) and the
  exponential ``rotation_matrix(phi)``; ``left_jacobian(phi)`` maps
  ``d phi`` to the spatial angular velocity: ``w = Jl(phi) d phi``.

Contents
--------

Rigid transforms: :func:`rot_x`, :func:`rot_y`, :func:`rot_z`, :func:`trans_x`,
:func:`trans_y`, :func:`trans_z`, :func:`transform`, :func:`inverse`,
:func:`compose`.

Lie algebra: :func:`hat3`, :func:`vee3`, :func:`hat`, :func:`vee`,
:func:`adjoint`, :func:`adjoint_apply`, :func:`cross`.

Rotation vector: :func:`rotation_vector`, :func:`rotation_matrix`,
:func:`left_jacobian`, :func:`left_jacobian_inverse`.

Quaternions: :func:`matrix_to_quaternion`, :func:`quaternion_to_matrix`,
:func:`unit_quaternion_to_matrix`, :func:`quaternion_parts`,
:func:`quaternion_multiply`, :func:`quaternion_conjugate`,
:func:`quaternion_from_rotation_vector`, :func:`rotation_vector_from_quaternion`,
:func:`quaternion_slerp`, :func:`slerp`.

A science module: numpy only.
"""

from __future__ import annotations

from functools import reduce

import numpy as np

__all__ = [
    "rot_x", "rot_y", "rot_z", "trans_x", "trans_y", "trans_z", "transform", "inverse", "compose",
    "hat3", "vee3", "hat", "vee", "adjoint", "adjoint_apply", "cross",
    "rotation_vector", "rotation_matrix", "left_jacobian", "left_jacobian_inverse",
    "matrix_to_quaternion", "quaternion_to_matrix", "unit_quaternion_to_matrix", "quaternion_parts",
    "quaternion_multiply", "quaternion_conjugate", "quaternion_from_rotation_vector",
    "rotation_vector_from_quaternion", "quaternion_slerp", "slerp",
]


# --------------------------------------------------------------------------- argument helpers

def _f(x) -> np.ndarray:
    return np.asarray(x, dtype=np.float64)


def _vec3(x, name: str) -> np.ndarray:
    a = _f(x)
    if a.ndim < 1 or a.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3), got {a.shape}")
    return a


def _mat(x, name: str, n: int) -> np.ndarray:
    a = _f(x)
    if a.ndim < 2 or a.shape[-2:] != (n, n):
        raise ValueError(f"{name} must have shape (..., {n}, {n}), got {a.shape}")
    return a


def _rot_part(x, name: str) -> np.ndarray:
    """The rotation block of a (..., 3, 3) rotation or a (..., 4, 4) transform."""
    a = _f(x)
    if a.ndim >= 2 and a.shape[-2:] == (4, 4):
        return a[..., :3, :3]
    if a.ndim >= 2 and a.shape[-2:] == (3, 3):
        return a
    raise ValueError(f"{name} must have shape (..., 3, 3) or (..., 4, 4), got {a.shape}")


def _norm(v: np.ndarray) -> np.ndarray:
    """Euclidean norm of (..., 3) vectors without overflow or underflow."""
    return np.hypot(np.hypot(v[..., 0], v[..., 1]), v[..., 2])


def _first_bad(bad: np.ndarray) -> str:
    """'at index (i, j)' for the first True of ``bad`` (and how many there are)."""
    bad = np.asarray(bad)
    if bad.ndim == 0:
        return ""
    idx = tuple(int(i) for i in np.argwhere(bad)[0])
    n = int(np.count_nonzero(bad))
    more = f" (and {n - 1} more)" if n > 1 else ""
    return f" at index {idx}{more}"


def _r3(axis: int, angle) -> np.ndarray:
    """(..., 3, 3) rotation by ``angle`` about coordinate axis 0 (x), 1 (y) or 2 (z)."""
    a = _f(angle)
    c, s = np.cos(a), np.sin(a)
    R = np.zeros(a.shape + (3, 3))
    i, j = ((1, 2), (2, 0), (0, 1))[axis]
    R[..., axis, axis] = 1.0
    R[..., i, i] = c
    R[..., j, j] = c
    R[..., i, j] = -s
    R[..., j, i] = s
    return R


def _hom(R: np.ndarray, p: np.ndarray | None = None) -> np.ndarray:
    """(..., 4, 4) from a (..., 3, 3) rotation and an optional (..., 3) translation."""
    shape = R.shape[:-2] if p is None else np.broadcast_shapes(R.shape[:-2], p.shape[:-1])
    T = np.zeros(shape + (4, 4))
    T[..., :3, :3] = R
    if p is not None:
        T[..., :3, 3] = p
    T[..., 3, 3] = 1.0
    return T


def _trans(axis: int, d) -> np.ndarray:
    d = _f(d)
    T = np.zeros(d.shape + (4, 4))
    T[..., [0, 1, 2, 3], [0, 1, 2, 3]] = 1.0
    T[..., axis, 3] = d
    return T


# --------------------------------------------------------------------------- rigid transforms

def rot_x(angle) -> np.ndarray:
    """``Rx(angle)``: (..., 4, 4) rotation about the x axis, angle in radians.

    ``[[1, 0, 0], [0, c, -s], [0, s, c]]`` (active, counter-clockwise seen from +x;
    ISO 10303-105 5.2.3).
    """
    return _hom(_r3(0, angle))


def rot_y(angle) -> np.ndarray:
    """``Ry(angle)``: (..., 4, 4) rotation about the y axis: ``[[c, 0, s], [0, 1, 0], [-s, 0, c]]``."""
    return _hom(_r3(1, angle))


def rot_z(angle) -> np.ndarray:
    """``Rz(angle)``: (..., 4, 4) rotation about the z axis: ``[[c, -s, 0], [s, c, 0], [0, 0, 1]]``."""
    return _hom(_r3(2, angle))


def trans_x(d) -> np.ndarray:
    """``Tx(d)``: (..., 4, 4) translation by ``d`` along x."""
    return _trans(0, d)


def trans_y(d) -> np.ndarray:
    """``Ty(d)``: (..., 4, 4) translation by ``d`` along y."""
    return _trans(1, d)


def trans_z(d) -> np.ndarray:
    """``Tz(d)``: (..., 4, 4) translation by ``d`` along z."""
    return _trans(2, d)


def transform(R, p=None) -> np.ndarray:
    """``T = [[R, p], [0, 1]]``: (..., 4, 4) from a (..., 3, 3) rotation and a (..., 3) translation.

    ``R`` and ``p`` broadcast; ``p=None`` means no translation. The rotation is
    applied first, then the translation (as Part 105's ``transform``, 6.4.2).
    """
    R = _mat(R, "R", 3)
    if p is None:
        return _hom(R)
    return _hom(R, _vec3(p, "p"))


def inverse(T) -> np.ndarray:
    """Rigid inverse ``T_b_a`` of ``T_a_b``: ``[[R^T, -R^T p], [0, 1]]``.

    Exact for rigid transforms (uses the transpose, not ``np.linalg.inv``);
    (..., 4, 4) in and out.
    """
    T = _mat(T, "T", 4)
    Rt = np.swapaxes(T[..., :3, :3], -1, -2)
    out = np.zeros(T.shape)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", Rt, T[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def compose(*transforms) -> np.ndarray:
    """Product left to right: ``compose(T_a_b, T_b_c, T_c_d) = T_a_d``.

    Leading axes broadcast (a (4, 4) with a (5, 4, 4) gives (5, 4, 4)). Works
    for (..., 3, 3) rotations as well.
    """
    if not transforms:
        raise ValueError("compose: needs at least one transform")
    return reduce(np.matmul, (_f(t) for t in transforms))


# --------------------------------------------------------------------------- Lie algebra

def hat3(w) -> np.ndarray:
    """(..., 3, 3) cross-product matrix of (..., 3) vectors: ``hat3(w) @ x = w x x``."""
    w = _f(w)
    out = np.zeros(w.shape + (3,))
    out[..., 0, 1], out[..., 0, 2] = -w[..., 2], w[..., 1]
    out[..., 1, 0], out[..., 1, 2] = w[..., 2], -w[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -w[..., 1], w[..., 0]
    return out


def vee3(W) -> np.ndarray:
    """Inverse of :func:`hat3`, from the antisymmetric part: (..., 3) of (..., 3, 3)."""
    W = _f(W)
    return 0.5 * np.stack([W[..., 2, 1] - W[..., 1, 2], W[..., 0, 2] - W[..., 2, 0],
                           W[..., 1, 0] - W[..., 0, 1]], axis=-1)


def cross(a, b) -> np.ndarray:
    """``a x b`` of (..., 3) vectors, broadcasting (componentwise: faster than ``np.cross``)."""
    a, b = _f(a), _f(b)
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def hat(twist) -> np.ndarray:
    """(..., 4, 4) matrix ``[[w^, v], [0, 0]]`` of twists (..., 6) ordered (v, w)."""
    t = np.asarray(twist, dtype=np.float64)
    out = np.zeros(t.shape[:-1] + (4, 4))
    vx, vy, vz, wx, wy, wz = np.moveaxis(t, -1, 0)
    out[..., 0, 1], out[..., 0, 2] = -wz, wy
    out[..., 1, 0], out[..., 1, 2] = wz, -wx
    out[..., 2, 0], out[..., 2, 1] = -wy, wx
    out[..., 0, 3], out[..., 1, 3], out[..., 2, 3] = vx, vy, vz
    return out


def vee(X) -> np.ndarray:
    """Inverse of :func:`hat`: (..., 6) twist (v, w) of (..., 4, 4) se(3) matrices.

    The angular part is read from the antisymmetric part, so a matrix that
    is only approximately in se(3) (a finite difference) gives its nearest twist.
    """
    X = np.asarray(X, dtype=np.float64)
    w = 0.5 * np.stack([X[..., 2, 1] - X[..., 1, 2], X[..., 0, 2] - X[..., 2, 0],
                        X[..., 1, 0] - X[..., 0, 1]], axis=-1)
    return np.concatenate([X[..., :3, 3], w], axis=-1)


def adjoint(T) -> np.ndarray:
    """(..., 6, 6) adjoint of rigid transforms for twists ordered (v, w).

    ``hat(adjoint(T) @ xi) = T @ hat(xi) @ inverse(T)``: it maps a body
    twist of ``T`` to the spatial one.
    """
    T = np.asarray(T, dtype=np.float64)
    R, p = T[..., :3, :3], T[..., :3, 3]
    P = hat(np.concatenate([np.zeros(p.shape), p], axis=-1))[..., :3, :3]
    out = np.zeros(T.shape[:-2] + (6, 6))
    out[..., :3, :3] = R
    out[..., 3:, 3:] = R
    out[..., :3, 3:] = P @ R
    return out


def adjoint_apply(T, X) -> np.ndarray:
    """``adjoint(T) @ X`` for T (B, 4, 4) and twists as columns X (B, 6, n) or (6, n),
    without forming the adjoint (a hot path of the solvers: no argument checks)."""
    B, n = T.shape[0], X.shape[-1]
    R, p = T[:, :3, :3], T[:, :3, 3:]
    out = np.empty((B, 6, n))
    w = np.matmul(R, X[..., 3:, :], out=out[:, 3:])
    v = np.matmul(R, X[..., :3, :], out=out[:, :3])
    v[:, 0] += p[:, 1] * w[:, 2] - p[:, 2] * w[:, 1]
    v[:, 1] += p[:, 2] * w[:, 0] - p[:, 0] * w[:, 2]
    v[:, 2] += p[:, 0] * w[:, 1] - p[:, 1] * w[:, 0]
    return out


# --------------------------------------------------------------------------- rotation vector

def rotation_vector(R) -> np.ndarray:
    """Rotation vector (..., 3) of rotations (..., 3, 3) or (..., 4, 4): axis times angle,
    angle in [0, pi] (scipy's ``as_rotvec``). The angle is ``atan2(sin, cos)`` of the trace
    and the antisymmetric part, accurate near 0; near pi (cos < -0.99), where the
    antisymmetric part vanishes, the axis comes from the symmetric part and its sign from
    the antisymmetric part."""
    R = _rot_part(R, "R")
    c = np.clip(0.5 * (np.trace(R, axis1=-2, axis2=-1) - 1.0), -1.0, 1.0)
    w = 0.5 * np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]],
                       axis=-1)
    s = np.linalg.norm(w, axis=-1)
    th = np.arctan2(s, c)
    f = np.where(s > 1e-12, th / np.where(s > 1e-12, s, 1.0), 1.0 + th * th / 6.0)
    out = w * f[..., None]
    near_pi = c < -0.99
    if near_pi.any():
        # sin(th) ~ 0: R + R^T - 2 c I = 2 (1 - c) u u^T; its largest diagonal entry's row is
        # the best-conditioned multiple of the axis u.
        Rn, cn, wn = R[near_pi], c[near_pi], w[near_pi]
        Rs = 0.5 * (Rn + np.swapaxes(Rn, -1, -2)) - cn[:, None, None] * np.eye(3)
        j = np.argmax(np.diagonal(Rs, axis1=-2, axis2=-1), axis=-1)
        axis = np.take_along_axis(Rs, j[:, None, None], axis=-2)[:, 0]
        axis = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
        axis = np.where((np.sum(axis * wn, axis=-1) < 0.0)[:, None], -axis, axis)
        out[near_pi] = th[near_pi][:, None] * axis
    return out


def rotation_matrix(phi) -> np.ndarray:
    """The exponential: (..., 3, 3) rotation of rotation vectors (..., 3) (Rodrigues;
    series below 1e-4 rad)."""
    phi = _vec3(phi, "phi")
    th = _norm(phi)
    small = th < 1e-4
    ths = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th ** 2 / 6.0, np.sin(ths) / ths)
    b = np.where(small, 0.5 - th ** 2 / 24.0, (1.0 - np.cos(ths)) / ths ** 2)
    A = hat3(phi)
    return np.eye(3) + a[..., None, None] * A + b[..., None, None] * (A @ A)


def left_jacobian(phi) -> np.ndarray:
    """``Jl(phi)`` of SO(3): ``I + b A + c A^2``, ``A = hat3(phi)``; the spatial angular
    velocity of ``rotation_matrix(phi)`` is ``Jl(phi) d phi``."""
    phi = _vec3(phi, "phi")
    th = _norm(phi)
    small = th < 1e-4
    ths = np.where(small, 1.0, th)
    b = np.where(small, 0.5 - th ** 2 / 24.0, (1.0 - np.cos(ths)) / ths ** 2)
    c = np.where(small, 1.0 / 6.0 - th ** 2 / 120.0, (ths - np.sin(ths)) / ths ** 3)
    A = hat3(phi)
    return np.eye(3) + b[..., None, None] * A + c[..., None, None] * (A @ A)


def left_jacobian_inverse(phi) -> np.ndarray:
    """``Jl(phi)^-1`` of SO(3): ``I - A/2 + c A^2``, ``A = hat3(phi)`` (singular at 2 pi)."""
    th = np.linalg.norm(phi, axis=-1)
    A = hat3(phi)
    small = th < 1e-4
    ths = np.where(small, 1.0, th)
    c_big = 1.0 / ths ** 2 - (1.0 + np.cos(ths)) / (2.0 * ths * np.sin(ths))
    c = np.where(small, 1.0 / 12.0 + th ** 2 / 720.0, c_big)
    return np.eye(3) - 0.5 * A + c[..., None, None] * (A @ A)


# --------------------------------------------------------------------------- quaternions

def _check_order(order: str) -> str:
    if order not in ("wxyz", "xyzw"):
        raise ValueError(f"quaternion order must be 'wxyz' or 'xyzw', got {order!r}")
    return order


def matrix_to_quaternion(R, order: str = "wxyz") -> np.ndarray:
    """Unit quaternion (..., 4) of a rotation matrix, Shepperd's method.

    ``order="wxyz"`` (scalar first, the default) or ``"xyzw"`` (scalar last,
    scipy's ``as_quat`` layout). The quaternion rotates vectors as ``R`` does
    (Hamilton convention, ``R = quaternion_to_matrix(q)``).

    Shepperd: of the four expressions 4w^2 = 1 + tr, 4x^2 = 1 + 2 R00 - tr,
    ... the largest is used as the pivot, so no division by a small number
    occurs; the result is normalised. Sign convention: ``w >= 0``; when
    ``w == 0`` (half-turns) the first non-zero of x, y, z is positive (as
    scipy's ``as_quat(canonical=True)``). Accepts (..., 3, 3) or (..., 4, 4).
    """
    order = _check_order(order)
    R = _rot_part(R, "R")
    r00, r01, r02 = R[..., 0, 0], R[..., 0, 1], R[..., 0, 2]
    r10, r11, r12 = R[..., 1, 0], R[..., 1, 1], R[..., 1, 2]
    r20, r21, r22 = R[..., 2, 0], R[..., 2, 1], R[..., 2, 2]
    tr = r00 + r11 + r22
    # rows: 4*q_pivot*(w, x, y, z) for pivot w, x, y, z
    cand = np.stack([
        np.stack([1.0 + tr, r21 - r12, r02 - r20, r10 - r01], axis=-1),
        np.stack([r21 - r12, 1.0 + 2.0 * r00 - tr, r01 + r10, r02 + r20], axis=-1),
        np.stack([r02 - r20, r01 + r10, 1.0 + 2.0 * r11 - tr, r12 + r21], axis=-1),
        np.stack([r10 - r01, r02 + r20, r12 + r21, 1.0 + 2.0 * r22 - tr], axis=-1),
    ], axis=-2)
    pivot = np.argmax(np.stack([tr, r00, r11, r22], axis=-1), axis=-1)
    q = np.take_along_axis(cand, pivot[..., None, None], axis=-2)[..., 0, :]
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    nz = q != 0.0
    first = np.take_along_axis(q, np.argmax(nz, axis=-1)[..., None], axis=-1)
    q = np.where(first < 0.0, -q, q) + 0.0
    if order == "xyzw":
        q = q[..., [1, 2, 3, 0]]
    return q


def quaternion_to_matrix(q, order: str = "wxyz") -> np.ndarray:
    """(..., 3, 3) rotation matrix of a quaternion (normalised first; Hamilton convention).

    ``order`` as in :func:`matrix_to_quaternion`. ``q`` and ``-q`` give the
    same matrix. Raises ``ValueError`` for a zero quaternion.
    """
    order = _check_order(order)
    q = _f(q)
    if q.ndim < 1 or q.shape[-1] != 4:
        raise ValueError(f"q must have shape (..., 4), got {q.shape}")
    if order == "xyzw":
        q = q[..., [3, 0, 1, 2]]
    n = np.linalg.norm(q, axis=-1)
    bad = ~(np.isfinite(n) & (n > 0.0))
    if np.any(bad):
        raise ValueError(f"quaternion_to_matrix: zero or non-finite quaternion{_first_bad(bad)}")
    w, x, y, z = np.moveaxis(q / n[..., None], -1, 0)
    R = np.empty(w.shape + (3, 3))
    R[..., 0, 0] = 1.0 - 2.0 * (y * y + z * z)
    R[..., 0, 1] = 2.0 * (x * y - z * w)
    R[..., 0, 2] = 2.0 * (x * z + y * w)
    R[..., 1, 0] = 2.0 * (x * y + z * w)
    R[..., 1, 1] = 1.0 - 2.0 * (x * x + z * z)
    R[..., 1, 2] = 2.0 * (y * z - x * w)
    R[..., 2, 0] = 2.0 * (x * z - y * w)
    R[..., 2, 1] = 2.0 * (y * z + x * w)
    R[..., 2, 2] = 1.0 - 2.0 * (x * x + y * y)
    return R


def quaternion_parts(R):
    """``(w, v)`` of the unit quaternion (w >= 0) of rotations R (B, 3, 3): a hot path of the
    loop residual (no checks, no sign canonicalisation at w = 0, not re-normalised away from
    the half-turn), Shepperd's pivoting only beyond about 145 degrees."""
    tr = R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2]
    d = np.empty(R.shape[:1] + (3,))
    np.subtract(R[:, 2, 1], R[:, 1, 2], out=d[:, 0])
    np.subtract(R[:, 0, 2], R[:, 2, 0], out=d[:, 1])
    np.subtract(R[:, 1, 0], R[:, 0, 1], out=d[:, 2])
    w = 0.5 * np.sqrt(np.maximum(1.0 + tr, 0.0))
    far = w < 0.3  # no division by a small w
    if not far.any():
        return w, d / (4.0 * w)[:, None]
    v = d / (4.0 * np.where(far, 1.0, w))[:, None]
    qf = matrix_to_quaternion(R[far])
    w = w.copy()
    w[far], v[far] = qf[:, 0], qf[:, 1:]
    return w, v


def _qmul_components(a, b):
    aw, ax, ay, az = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bw, bx, by, bz = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = aw * bw - ax * bx - ay * by - az * bz
    out[..., 1] = aw * bx + ax * bw + ay * bz - az * by
    out[..., 2] = aw * by - ax * bz + ay * bw + az * bx
    out[..., 3] = aw * bz + ax * by - ay * bx + az * bw
    return out


# Products of quaternion components by matmuls with 0/1 matrices (numpy broadcasting over a
# trailing axis of 4 is several times slower): a_i b_j for all 16 pairs, a_i a_j for the 10
# with i <= j.
_I16 = np.repeat(np.eye(4), 4, axis=1)
_J16 = np.tile(np.eye(4), (1, 4))
_PAIRS = [(i, j) for i in range(4) for j in range(i, 4)]
_I10 = np.eye(4)[:, [i for i, _ in _PAIRS]]
_J10 = np.eye(4)[:, [j for _, j in _PAIRS]]
_QM = np.stack([_qmul_components(np.eye(4)[i], np.eye(4)[j]) for i in range(4) for j in range(4)])


def _quadratic_form_of_rotation():
    """(10, 9) F with R(q).ravel() = (q_i q_j, i <= j) @ F for a unit quaternion q (wxyz)."""
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
    M = M.reshape(4, 4, 9)
    return np.stack([M[i, j] + M[j, i] if i != j else M[i, i] for i, j in _PAIRS])


_QFORM10 = _quadratic_form_of_rotation()


def quaternion_multiply(a, b) -> np.ndarray:
    """Hamilton product ``a b`` of (..., 4) quaternions (wxyz, broadcasting): the rotation
    ``b`` first, then ``a``. Bilinear: the 16 component products and one matmul."""
    a, b = _f(a), _f(b)
    return ((a @ _I16) * (b @ _J16)) @ _QM


def quaternion_conjugate(q) -> np.ndarray:
    """``(w, -v)``: the inverse of a unit quaternion."""
    return _f(q) * np.array([1.0, -1.0, -1.0, -1.0])


def unit_quaternion_to_matrix(q) -> np.ndarray:
    """(..., 3, 3) rotations of *unit* quaternions (..., 4) (wxyz): the quadratic monomials
    and one matmul, no normalisation and no checks (a hot path; see
    :func:`quaternion_to_matrix` for the checked one)."""
    q = _f(q)
    return (((q @ _I10) * (q @ _J10)) @ _QFORM10).reshape(q.shape[:-1] + (3, 3))


def quaternion_from_rotation_vector(phi) -> np.ndarray:
    """``exp(phi / 2)``: the unit quaternion (..., 4) (wxyz) of rotation vectors (..., 3)
    (series below 1e-4 rad)."""
    phi = _f(phi)
    ang = np.sqrt(np.einsum("...i,...i->...", phi, phi))
    half = 0.5 * ang
    k = np.where(ang < 1e-4, 0.5 - ang * ang / 48.0, np.sin(half) / np.where(ang < 1e-4, 1.0, ang))
    return np.concatenate([np.cos(half)[..., None], k[..., None] * phi], axis=-1)


def rotation_vector_from_quaternion(q) -> np.ndarray:
    """The shortest rotation vector (..., 3) of unit quaternions (..., 4) (``q`` and ``-q``
    alike: the sign of w is made >= 0)."""
    q = _f(q)
    q = np.where(q[..., :1] < 0.0, -q, q)
    v = q[..., 1:]
    sv = np.linalg.norm(v, axis=-1)
    ang = 2.0 * np.arctan2(sv, q[..., 0])
    k = np.where(sv < 1e-12, 2.0, ang / np.where(sv < 1e-12, 1.0, sv))
    return k[..., None] * v


def quaternion_slerp(qa, qb, t=0.5) -> np.ndarray:
    """``qa exp(t log(conj(qa) qb))``: geodesic interpolation of unit quaternions (wxyz)
    along the shorter arc; ``t`` broadcasts as (...)."""
    t = _f(t)
    rel = rotation_vector_from_quaternion(quaternion_multiply(quaternion_conjugate(qa), qb))
    return quaternion_multiply(qa, quaternion_from_rotation_vector(t[..., None] * rel if t.ndim else t * rel))


def slerp(R0, R1, s) -> np.ndarray:
    """Spherical linear interpolation between rotations: (..., 3, 3), exact at s = 0 and 1.

    ``R0``, ``R1``: (..., 3, 3) or (..., 4, 4) (rotation part used); ``s``:
    fractions in [0, 1] broadcasting with their leading axes. Interpolates
    the unit quaternions along the shorter great arc (constant angular
    velocity about a fixed axis), so ``slerp(R0, R1, 0) = R0`` and
    ``slerp(R0, R1, 1) = R1``; never interpolates angles. For nearly equal
    rotations (angle below 1e-8 rad) the normalised linear blend of the
    quaternions is used, which agrees with slerp to rounding there.
    """
    q0 = matrix_to_quaternion(R0)
    q1 = matrix_to_quaternion(R1)
    s = _f(s)
    dot = np.sum(q0 * q1, axis=-1)
    q1 = np.where((dot < 0.0)[..., None], -q1, q1)  # the shorter arc
    dot = np.abs(dot)
    omega = np.arccos(np.clip(dot, -1.0, 1.0))
    small = omega < 1e-8
    sin_omega = np.where(small, 1.0, np.sin(omega))
    w0 = np.where(small, 1.0 - s, np.sin((1.0 - s) * omega) / sin_omega)
    w1 = np.where(small, s, np.sin(s * omega) / sin_omega)
    q = w0[..., None] * q0 + w1[..., None] * q1
    R = quaternion_to_matrix(q)
    # the end rotations exactly, not through a quaternion round trip
    R = np.where((s == 0.0)[..., None, None], _rot_part(R0, "R0"), R)
    return np.where((s == 1.0)[..., None, None], _rot_part(R1, "R1"), R)
