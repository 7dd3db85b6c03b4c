"""Placements: homogeneous transforms and the placement methods of ISO 10303-105.

Conventions (read these before using any function)
---------------------------------------------------

* Every function is vectorised over leading axes: vectors are ``(..., 3)``,
  rotations ``(..., 3, 3)``, homogeneous transforms ``(..., 4, 4)``, scalars
  ``(...)``; arguments broadcast with numpy rules; results are float64. No
  function loops over samples in Python.
* Matrices are *active* rotations acting on column vectors: ``R @ v`` turns
  ``v``; the columns of ``R`` are the rotated frame's x, y, z axes expressed
  in the reference frame.
* ``T_a_b`` (4x4) is the placement of frame *b* in frame *a*: its columns are
  b's axes and origin in a's coordinates, so ``p_a = T_a_b @ p_b`` and
  ``T_a_c = T_a_b @ T_b_c`` (:func:`compose`). This is the matrix the
  standard writes ``aP_b`` (ISO 10303-105, 5.2.2, rigid homogeneous matrix).
* Positive angles turn counter-clockwise when looking from the tip of the
  rotation axis towards the origin (ISO 10303-105, 5.2.3: "looking along the
  axis in the direction opposite to it").
* Angles are radians unless a function takes ``unit_factor``: then the
  value in radians is ``value * unit_factor`` (``unit_factor = DEGREE`` for a
  file whose plane-angle unit is the degree), as in the standard's
  ``plane_angle_for_pair_in_radian`` (5.5.7).
* Angle outputs are canonical: periodic angles in ``(-pi, pi]`` (``-pi`` is
  returned as ``+pi``), never ``-0.0``.

Contents
--------

Elementary transforms (``rot_x`` ... ``compose``), quaternions and ``slerp`` are
:mod:`p105cli.kinematics.spatial`'s (import them from there).

Part 105 / Part 42 placements: :func:`build_axes`, :func:`axis2_placement_3d`,
:func:`su_parameters`, :func:`su_to_axis2_placement_3d`,
:func:`su_parameters_from_transform`, :func:`ypr_rotation`,
:func:`ypr_from_matrix`, :func:`rotation_about_direction`,
:func:`convert_spatial_to_ypr_rotation`, :func:`plane_angle_to_radian`,
:func:`radian_to_plane_angle`.

Output conversions (always labelled): :func:`matrix_to_euler`, :func:`euler_to_matrix`
(``"ZXZ"`` = Euler 3-1-3, ``"ZYZ"`` = Euler 3-2-3, ``"XYZ"`` = Cardan 1-2-3;
all intrinsic, i.e. about the body-fixed, moving axes).
"""

from __future__ import annotations

import numpy as np

# the argument checks are spatial's (one message format for both modules)
from .spatial import _f, _first_bad, _hom, _mat, _norm, _r3, _rot_part, _vec3, cross

__all__ = [
    "DEGREE",
    "ANGLE_LOCK_TOL",
    "build_axes", "axis2_placement_3d",
    "su_parameters", "su_to_axis2_placement_3d", "su_parameters_from_transform",
    "ypr_rotation", "ypr_from_matrix", "canonical_ypr", "rotation_about_direction",
    "convert_spatial_to_ypr_rotation",
    "plane_angle_to_radian", "radian_to_plane_angle",
    "EULER_SEQUENCES", "matrix_to_euler", "euler_to_matrix",
]

#: Conversion factor of the degree to the radian (``conversion_based_unit``
#: 'DEGREE' with ``value_component`` pi/180 of the radian).
DEGREE = np.pi / 180.0

#: Default tolerance on cos(middle angle) (ypr, Cardan) or sin(middle angle)
#: (Euler) below which an orientation is treated as exactly at the gimbal lock.
#: Snapping to the lock changes the matrix by at most this much.
ANGLE_LOCK_TOL = 1e-12

#: Supported angle sequences (intrinsic, body-fixed axes).
EULER_SEQUENCES = ("ZXZ", "ZYZ", "XYZ")

_TWO_PI = 2.0 * np.pi


# --------------------------------------------------------------------------- helpers

def _unit(v: np.ndarray, name: str, func: str) -> np.ndarray:
    n = _norm(v)
    bad = ~(np.isfinite(n) & (n > 0.0))
    if np.any(bad):
        raise ValueError(f"{func}: {name} is a zero or non-finite vector{_first_bad(bad)}; "
                         "a direction needs a non-zero magnitude")
    return v / n[..., None]


def _canon_angle(x: np.ndarray) -> np.ndarray:
    """Map an angle in [-pi, pi] (an atan2 result) to (-pi, pi]; drop -0.0."""
    x = np.where(x == -np.pi, np.pi, x)
    return x + 0.0


def _wrap_angle(x: np.ndarray) -> np.ndarray:
    """Reduce any angle to (-pi, pi]."""
    return _canon_angle(np.pi - np.mod(np.pi - x, _TWO_PI))


def _scalar(x: np.ndarray):
    """A numpy scalar for 0-d results, the array otherwise."""
    return x[()] if isinstance(x, np.ndarray) and x.ndim == 0 else x


# --------------------------------------------------------------------------- axis2_placement_3d

def build_axes(axis=None, ref_direction=None, *, tol: float = 1e-12) -> np.ndarray:
    """Part 42 ``build_axes``: (..., 3, 3) rotation whose columns are the placement's x, y, z.

    ISO 10303-42 ``build_axes`` / ``first_proj_axis`` semantics:

    * z = ``normalise(axis)``; ``axis=None`` means (0, 0, 1).
    * ``ref_direction=None`` means (1, 0, 0), except when z is exactly
      +-(1, 0, 0), where Part 42's ``first_proj_axis`` takes (0, 1, 0).
    * x is ``ref_direction`` projected onto the plane normal to z, normalised
      (computed as ``z x (ref x z)``, accurate even when ``ref`` is close to z).
    * y = z x x.

    Raises ``ValueError`` if ``axis`` or ``ref_direction`` is zero (or not
    finite), or if they are parallel: ``|axis x ref| <= tol * |axis| * |ref|``
    (Part 42 axis2_placement_3d WR4 asks for a non-zero cross product; ``tol``
    makes the test relative to the magnitudes).
    """
    func = "axis2_placement_3d"
    if axis is None:
        z = np.array([0.0, 0.0, 1.0])
    else:
        z = _unit(_vec3(axis, "axis"), "axis", func)
    if ref_direction is None:
        on_x = (z[..., 1] == 0.0) & (z[..., 2] == 0.0)
        v = np.where(on_x[..., None], np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0]))
    else:
        v = _unit(_vec3(ref_direction, "ref_direction"), "ref_direction", func)
        z, v = np.broadcast_arrays(z, v)
        sin_angle = _norm(cross(v, z))
        bad = ~(sin_angle > tol)
        if np.any(bad):
            raise ValueError(
                f"{func}: axis and ref_direction are parallel{_first_bad(bad)} "
                f"(|axis x ref_direction| / (|axis| |ref_direction|) = "
                f"{float(np.asarray(sin_angle)[bad].flat[0]):.3g} <= tol {tol:g}); "
                "ref_direction must have a component normal to axis (ISO 10303-42, "
                "axis2_placement_3d WR4)")
    z, v = np.broadcast_arrays(z, v)
    x = cross(z, cross(v, z))   # spatial's: a placement per pair frame, np.cross's overhead adds up
    x = x / _norm(x)[..., None]
    y = cross(z, x)
    y = y / _norm(y)[..., None]
    return np.stack([x, y, z], axis=-1)


def axis2_placement_3d(location, axis=None, ref_direction=None, *, tol: float = 1e-12) -> np.ndarray:
    """(..., 4, 4) transform ``T_context_placement`` of an ``axis2_placement_3d``.

    Columns: x = ``p[1]``, y = ``p[2]``, z = ``p[3]`` of Part 42's
    ``build_axes(axis, ref_direction)`` (see :func:`build_axes` for the
    defaults, the projection of ``ref_direction`` and the errors), origin =
    ``location``. Arguments broadcast over leading axes; ``None`` applies to
    the whole batch.
    """
    loc = _vec3(location, "location")
    return _hom(build_axes(axis, ref_direction, tol=tol), loc)


# --------------------------------------------------------------------------- su_parameters (5.4.17)

def su_parameters(a, alpha, b, beta, c, gamma) -> np.ndarray:
    """Sheth-Uicker parameters as a placement (ISO 10303-105, 5.4.17).

    Returns ``T_link_pair`` (..., 4, 4), the pair frame k in the link frame:

        T = Tz(c) Rz(gamma) Tx(a) Rx(alpha) Tz(b) Rz(beta)

    i.e. from the link frame (x', y', z'): move ``c`` along z', turn ``gamma``
    about z' so that x' lies along the common normal t_k, move ``a`` along t_k,
    turn ``alpha`` about t_k (z' onto z_k), move ``b`` along z_k, turn ``beta``
    about z_k (t_k onto x_k). Its origin, z axis and x axis are the
    ``location``, ``axis`` and ``ref_direction`` of note 5 of 5.4.17 (see
    :func:`su_to_axis2_placement_3d`). Angles in radians; all six arguments
    broadcast.
    """
    a, alpha, b, beta, c, gamma = np.broadcast_arrays(*(_f(v) for v in (a, alpha, b, beta, c, gamma)))
    ca, sa = np.cos(alpha), np.sin(alpha)
    cb, sb = np.cos(beta), np.sin(beta)
    cg, sg = np.cos(gamma), np.sin(gamma)
    T = np.zeros(a.shape + (4, 4))
    # rotation Rz(gamma) Rx(alpha) Rz(beta); column 0 = ref_direction, column 2 = axis (note 5)
    T[..., 0, 0] = cg * cb - sg * ca * sb
    T[..., 1, 0] = sg * cb + cg * ca * sb
    T[..., 2, 0] = sa * sb
    T[..., 0, 1] = -cg * sb - sg * ca * cb
    T[..., 1, 1] = -sg * sb + cg * ca * cb
    T[..., 2, 1] = sa * cb
    T[..., 0, 2] = sg * sa
    T[..., 1, 2] = -cg * sa
    T[..., 2, 2] = ca
    # origin = location of note 5
    T[..., 0, 3] = a * cg + b * sg * sa
    T[..., 1, 3] = a * sg - b * cg * sa
    T[..., 2, 3] = c + b * ca
    T[..., 3, 3] = 1.0
    return T


def su_to_axis2_placement_3d(a, alpha, b, beta, c, gamma):
    """``(location, axis, ref_direction)`` of the axis2_placement_3d equal to su_parameters.

    Note 5 of ISO 10303-105 5.4.17, verbatim (each (..., 3)):

        location      = (a cos(gamma) + b sin(gamma) sin(alpha),
                         a sin(gamma) - b cos(gamma) sin(alpha),
                         c + b cos(alpha))
        axis          = (sin(gamma) sin(alpha), -cos(gamma) sin(alpha), cos(alpha))
        ref_direction = (cos(gamma) cos(beta) - sin(gamma) cos(alpha) sin(beta),
                         sin(gamma) cos(beta) + cos(gamma) cos(alpha) sin(beta),
                         sin(alpha) sin(beta))

    ``axis`` and ``ref_direction`` are unit and orthogonal, so the
    placement's x axis is ``ref_direction`` itself.
    """
    a, alpha, b, beta, c, gamma = np.broadcast_arrays(*(_f(v) for v in (a, alpha, b, beta, c, gamma)))
    ca, sa = np.cos(alpha), np.sin(alpha)
    cb, sb = np.cos(beta), np.sin(beta)
    cg, sg = np.cos(gamma), np.sin(gamma)
    location = np.stack([a * cg + b * sg * sa, a * sg - b * cg * sa, c + b * ca], axis=-1)
    axis = np.stack([sg * sa, -cg * sa, ca], axis=-1)
    ref = np.stack([cg * cb - sg * ca * sb, sg * cb + cg * ca * sb, sa * sb], axis=-1)
    return location, axis, ref


def su_parameters_from_transform(T, *, tol: float = float(np.sqrt(np.finfo(float).eps))):
    """Sheth-Uicker parameters ``(a, alpha, b, beta, c, gamma)`` of a rigid transform.

    Inverse of :func:`su_parameters` with the geometric reading of 5.4.17:
    t_k is the common normal of z' (the link frame's z axis) and z_k (the
    pair frame's), pointing from z' to z_k, and ``a = |s_k - s'_k| >= 0``.

    * Non-parallel axes (sin(alpha) > ``tol``): the common normal is unique;
      when the axes intersect (a = 0, taken when the distance is below
      ``64 eps |location|``), t_k is ``z' x z_k`` normalised, so alpha is in
      (0, pi).
    * Parallel axes (sin(alpha) <= ``tol``): alpha is set to exactly 0 or pi
      and the common normal is taken through the pair frame's origin
      (``b = 0``); for coaxial frames ``gamma = 0``, ``a = 0``.

    Angles are in (-pi, pi]. Round trip: ``su_parameters(*su_parameters_from_transform(T))``
    reproduces ``T`` to rounding, except near parallel axes where the
    representation itself is ill-conditioned (b grows like 1/sin(alpha)); the
    default ``tol = sqrt(eps)`` bounds that error at about 1e-8 relative.
    """
    T = _mat(T, "T", 4)
    R = T[..., :3, :3]
    p = T[..., :3, 3]
    w = R[..., :, 2]
    n = np.stack([-w[..., 1], w[..., 0], np.zeros(w.shape[:-1])], axis=-1)  # e_z x w
    sn = np.hypot(w[..., 0], w[..., 1])
    parallel = ~(sn > tol)
    safe = np.where(parallel, 1.0, sn)
    nh = n / safe[..., None]
    d = np.einsum("...i,...i->...", p, nh)
    # intersecting axes (to rounding: |d| <= 64 eps |p|): a = 0, t = z' x z_k normalised
    meet = np.abs(d) <= 64.0 * np.finfo(float).eps * _norm(p)
    d = np.where(meet, 0.0, d)
    sgn = np.where(d < 0.0, -1.0, 1.0)
    # skew or intersecting axes
    t = sgn[..., None] * nh
    gamma_s = np.arctan2(t[..., 1], t[..., 0])
    alpha_s = np.arctan2(sgn * sn, w[..., 2])
    qy = -np.sin(gamma_s) * p[..., 0] + np.cos(gamma_s) * p[..., 1]
    b_s = -qy / np.where(parallel, 1.0, np.sin(alpha_s))
    c_s = p[..., 2] - b_s * np.cos(alpha_s)
    a_s = np.abs(d)
    # parallel axes
    a_p = np.hypot(p[..., 0], p[..., 1])
    gamma_p = np.where(a_p > 0.0, np.arctan2(p[..., 1], p[..., 0]), 0.0)
    alpha_p = np.where(w[..., 2] < 0.0, np.pi, 0.0)
    a = np.where(parallel, a_p, a_s)
    alpha = np.where(parallel, alpha_p, alpha_s)
    b = np.where(parallel, 0.0, b_s)
    c = np.where(parallel, p[..., 2], c_s)
    gamma = np.where(parallel, gamma_p, gamma_s)
    # beta: Rz(beta) = (Rz(gamma) Rx(alpha))^T R
    A = _r3(2, gamma) @ _r3(0, alpha)
    M = np.swapaxes(A, -1, -2) @ R
    beta = np.arctan2(M[..., 1, 0], M[..., 0, 0])
    out = (a + 0.0, _canon_angle(alpha), b + 0.0, _canon_angle(beta), c + 0.0, _canon_angle(gamma))
    return tuple(_scalar(v) for v in out)


# --------------------------------------------------------------------------- ypr_rotation (5.3.7, Annex E)

def ypr_rotation(yaw, pitch, roll, unit_factor=1.0) -> np.ndarray:
    """(..., 3, 3) rotation matrix of a ``ypr_rotation`` (ISO 10303-105 5.3.7, Annex E).

    The matrix of Annex E.1 / ``compute_rotation_matrix_from_ypr_rotation``
    (E.2), transcribed term by term::

        [[ cy cp,            -sy cp,             sp    ],
         [ sy cr + cy sp sr,  cy cr - sy sp sr, -cp sr ],
         [ sy sr - cy sp cr,  cy sr + sy sp cr,  cp cr ]]

    which is ``Rx(roll) Ry(pitch) Rz(yaw)``: the yaw is applied first
    (rightmost), about z, then the pitch about y, then the roll about x, all
    three about the axes of the *non-rotated* frame (equivalently: intrinsic
    Cardan X-Y'-Z'' with angles (roll, pitch, yaw); scipy
    ``Rotation.from_euler('zyx', [yaw, pitch, roll])``). Angles are
    ``value * unit_factor`` radians (the ``factor`` argument of E.2).
    """
    uf = _f(unit_factor)
    y, p, r = np.broadcast_arrays(_f(yaw) * uf, _f(pitch) * uf, _f(roll) * uf)
    cy, sy = np.cos(y), np.sin(y)
    cp, sp = np.cos(p), np.sin(p)
    cr, sr = np.cos(r), np.sin(r)
    R = np.empty(y.shape + (3, 3))
    R[..., 0, 0] = cy * cp
    R[..., 0, 1] = -sy * cp
    R[..., 0, 2] = sp
    R[..., 1, 0] = sy * cr + cy * sp * sr
    R[..., 1, 1] = cy * cr - sy * sp * sr
    R[..., 1, 2] = -cp * sr
    R[..., 2, 0] = sy * sr - cy * sp * cr
    R[..., 2, 1] = cy * sr + sy * sp * cr
    R[..., 2, 2] = cp * cr
    return R


def canonical_ypr(yaw: float, pitch: float, roll: float, lock_rel_tol: float) -> tuple:
    """The ``(yaw, pitch, roll)`` that 5.3.7 allows for ``ypr_rotation(yaw, pitch, roll)``: pitch
    in [-pi/2, pi/2], yaw and roll in (-pi, pi], and at a rectangular pitch angle roll 0, the
    yaw carrying the rotation about the locked axis (yaw + roll at +pi/2, yaw - roll at -pi/2).

    A triple that already is canonical is returned unchanged. A pitch within
    ``lock_rel_tol * pi/2`` of +-pi/2 is the lock (the validator's test): it becomes exactly
    +-pi/2 with roll 0, which moves the rotation by at most about that angle's distance from
    +-pi/2 (no triple with roll 0 is nearer); any other triple gives the same matrix to
    rounding (:func:`ypr_from_matrix`)."""
    half = 0.5 * np.pi
    y, p, r = (float(x) for x in (yaw, pitch, roll))
    near_lock = abs(abs(p) - half) <= lock_rel_tol * half
    if (-np.pi < y <= np.pi and -np.pi < r <= np.pi and abs(p) <= half
            and not (near_lock and r != 0.0)):
        return y, p, r
    # the lock test of ypr_from_matrix is on cos(pitch): the same band around +-pi/2
    y, p, r = ypr_from_matrix(ypr_rotation(y, p, r), lock_tol=float(np.sin(lock_rel_tol * half)))
    return float(y), float(p), float(r)


def ypr_from_matrix(R, *, lock_tol: float = ANGLE_LOCK_TOL):
    """``(yaw, pitch, roll)`` in radians with ``ypr_rotation(yaw, pitch, roll) == R``.

    The extraction of 5.5.9 (general branch), done so that it stays exact near
    the lock: pitch = atan2(R[0,2], hypot(R[0,0], R[0,1])) is in
    [-pi/2, pi/2]; yaw = atan2(-R[0,1], R[0,0]); the roll is then read from
    ``R Rz(-yaw) = Rx(roll) Ry(pitch)`` (entries of size 1, not cos(pitch)),
    so the three angles reproduce ``R`` to rounding however close the pitch
    is to +-pi/2 (yaw and roll individually become ill-defined there, only
    their combination matters).

    Lock (``cos(pitch) <= lock_tol``): pitch is exactly +-pi/2, roll = 0 (the
    "rectangular pitch angle" rule of 5.3.7) and yaw = atan2(R[1,0], R[1,1])
    carries the whole rotation about the locked axis, as in 5.5.9. The
    standard tests ``ABS(rotmat[1][3]) = 1.0`` exactly; ``lock_tol`` makes the
    test robust to rounding and moves the matrix by at most ``lock_tol``.

    yaw and roll are in (-pi, pi]. Accepts (..., 3, 3) or (..., 4, 4).
    """
    R = _rot_part(R, "R")
    cp = np.hypot(R[..., 0, 0], R[..., 0, 1])
    lock = cp <= lock_tol
    up = R[..., 0, 2] >= 0.0
    pitch = np.where(lock, np.where(up, 0.5 * np.pi, -0.5 * np.pi), np.arctan2(R[..., 0, 2], cp))
    yaw = np.where(lock, np.arctan2(R[..., 1, 0], R[..., 1, 1]), np.arctan2(-R[..., 0, 1], R[..., 0, 0]))
    sy, cy = np.sin(yaw), np.cos(yaw)
    # (R Rz(-yaw)) = Rx(roll) Ry(pitch): [2,1] = sin(roll), [1,1] = cos(roll)
    n21 = R[..., 2, 0] * sy + R[..., 2, 1] * cy
    n11 = R[..., 1, 0] * sy + R[..., 1, 1] * cy
    roll = np.where(lock, 0.0, np.arctan2(n21, n11))
    return _scalar(_canon_angle(yaw)), _scalar(pitch + 0.0), _scalar(_canon_angle(roll))


def rotation_about_direction(direction, angle, unit_factor=1.0) -> np.ndarray:
    """(..., 3, 3) matrix of a ``rotation_about_direction`` (ISO 10303-105 5.4.1).

    Rodrigues' formula with the unit axis ``k = direction / |direction|``:
    ``R = cos(t) I + sin(t) [k]x + (1 - cos(t)) k k^T``, ``t = angle * unit_factor``
    radians; the same matrix as ``rotmat`` in ``convert_spatial_to_ypr_rotation``
    (5.5.9). Positive angles turn counter-clockwise seen from the tip of
    ``direction`` (5.4.1); any finite angle is allowed. ``1 - cos(t)`` is
    computed as ``2 sin(t/2)^2`` (no cancellation for small angles).
    Raises ``ValueError`` for a zero direction.
    """
    k = _unit(_vec3(direction, "direction"), "direction_of_axis", "rotation_about_direction")
    t = _f(angle) * _f(unit_factor)
    k, t = np.broadcast_arrays(k, t[..., None])
    t = t[..., 0]
    c, s = np.cos(t), np.sin(t)
    cm1 = 2.0 * np.sin(0.5 * t) ** 2
    kx, ky, kz = k[..., 0], k[..., 1], k[..., 2]
    R = np.empty(t.shape + (3, 3))
    R[..., 0, 0] = kx * kx * cm1 + c
    R[..., 0, 1] = kx * ky * cm1 - kz * s
    R[..., 0, 2] = kx * kz * cm1 + ky * s
    R[..., 1, 0] = kx * ky * cm1 + kz * s
    R[..., 1, 1] = ky * ky * cm1 + c
    R[..., 1, 2] = ky * kz * cm1 - kx * s
    R[..., 2, 0] = kx * kz * cm1 - ky * s
    R[..., 2, 1] = ky * kz * cm1 + kx * s
    R[..., 2, 2] = kz * kz * cm1 + c
    return R


def convert_spatial_to_ypr_rotation(direction, angle, unit_factor=1.0, *,
                                    lock_tol: float = ANGLE_LOCK_TOL):
    """``(yaw, pitch, roll)`` equal to a ``rotation_about_direction`` (ISO 10303-105 5.5.9).

    ``angle`` is in the file's plane-angle unit (radians = ``angle * unit_factor``,
    the role of ``plane_angle_for_pair_in_radian`` in the standard); the three
    results are in the same unit. ``ypr_rotation(*result, unit_factor)`` equals
    ``rotation_about_direction(direction, angle, unit_factor)``.

    Follows the function of 5.5.9 branch by branch (vectorised):

    * ``angle == 0``: (0, 0, 0).
    * axis exactly along +-x or +-z (after normalisation): the angle is reduced
      to (-pi, pi] and becomes the roll (x) or the yaw (z), negated for the
      negative axis unless it is pi.
    * axis exactly along +-y: pitch = +-atan2(sin t, |cos t|); yaw = roll = 0
      if cos t >= 0, else yaw = roll = pi.
    * otherwise: the Rodrigues matrix and :func:`ypr_from_matrix` (pitch in
      [-pi/2, pi/2]; at the lock |pitch| = pi/2, roll = 0: the "rectangular
      pitch angle" rule of 5.3.7), using ``lock_tol`` where the standard
      tests ``ABS(rotmat[1][3]) = 1.0`` exactly.

    Yaw and roll are in (-pi, pi] (in radians before scaling back).
    """
    d = _unit(_vec3(direction, "direction"), "direction_of_axis", "convert_spatial_to_ypr_rotation")
    uf = _f(unit_factor)
    ang = _f(angle)
    t = ang * uf
    d, t = np.broadcast_arrays(d, t[..., None])
    t = t[..., 0]
    dx, dy, dz = d[..., 0], d[..., 1], d[..., 2]
    yaw, pitch, roll = (_f(v) for v in ypr_from_matrix(rotation_about_direction(d, t), lock_tol=lock_tol))
    zero = np.zeros(t.shape)
    # axis along x or z
    w = _wrap_angle(t)
    ra = np.where(w != np.pi, -w, w) + 0.0
    xz = (dy == 0.0) & (dx * dz == 0.0)
    on_x = xz & (dx != 0.0)
    on_z = xz & (dx == 0.0)
    r_x = np.where(dx > 0.0, w, ra)
    y_z = np.where(dz > 0.0, w, ra)
    yaw = np.where(on_x, 0.0, np.where(on_z, y_z, yaw))
    pitch = np.where(xz, 0.0, pitch)
    roll = np.where(on_x, r_x, np.where(on_z, 0.0, roll))
    # axis along y
    on_y = (dy != 0.0) & (dx == 0.0) & (dz == 0.0)
    s_a, c_a = np.sin(t), np.cos(t)
    yr = np.where(c_a >= 0.0, 0.0, np.pi)
    pa = np.arctan2(s_a, np.abs(c_a))
    pa = np.where(dy < 0.0, -pa, pa)
    yaw = np.where(on_y, yr, yaw)
    pitch = np.where(on_y, pa, pitch)
    roll = np.where(on_y, yr, roll)
    # zero rotation
    nil = t == 0.0
    yaw, pitch, roll = (np.where(nil, zero, v) for v in (yaw, pitch, roll))
    uf_b = np.broadcast_to(uf, t.shape)
    return tuple(_scalar(v / uf_b + 0.0) for v in (yaw, pitch, roll))


# --------------------------------------------------------------------------- units

def plane_angle_to_radian(value, unit_factor=1.0):
    """``value * unit_factor``: a plane angle in the file's unit converted to radians.

    ``unit_factor`` is the radians per unit of the plane-angle unit found in
    the link's ``global_unit_assigned_context`` (ISO 10303-105 5.2.5, 5.5.7
    ``plane_angle_for_pair_in_radian``): 1.0 for the radian, :data:`DEGREE`
    (pi/180) for a ``conversion_based_unit`` 'DEGREE'; for a chain of
    conversion_based_units it is the product of their
    ``conversion_factor.value_component``; an SI prefix on the radian
    multiplies it (milli: 1e-3, ...). Deriving the factor from the model is
    the job of the units layer; this helper only applies it.
    """
    uf = _f(unit_factor)
    if not np.all(np.isfinite(uf) & (uf > 0.0)):
        raise ValueError("plane_angle_to_radian: unit_factor must be finite and > 0")
    return _scalar(_f(value) * uf)


def radian_to_plane_angle(value, unit_factor=1.0):
    """``value / unit_factor``: radians back to the file's plane-angle unit (5.5.8,
    ``convert_plane_angle_for_pair_from_radian``); see :func:`plane_angle_to_radian`."""
    uf = _f(unit_factor)
    if not np.all(np.isfinite(uf) & (uf > 0.0)):
        raise ValueError("radian_to_plane_angle: unit_factor must be finite and > 0")
    return _scalar(_f(value) / uf)


# --------------------------------------------------------------------------- Euler / Cardan angles

def _check_seq(seq: str) -> str:
    if seq not in EULER_SEQUENCES:
        raise ValueError(f"angle sequence must be one of {EULER_SEQUENCES} (intrinsic, "
                         f"body-fixed axes), got {seq!r}")
    return seq


def euler_to_matrix(angles, seq: str) -> np.ndarray:
    """(..., 3, 3) rotation of three angles (..., 3) about body-fixed (intrinsic) axes.

    ``R = R_{seq[0]}(angles[..., 0]) @ R_{seq[1]}(angles[..., 1]) @ R_{seq[2]}(angles[..., 2])``:

    * ``"ZXZ"``: Euler 3-1-3 (precession about z, nutation about the new x,
      spin about the newest z): ``Rz Rx Rz``.
    * ``"ZYZ"``: Euler 3-2-3: ``Rz Ry Rz``.
    * ``"XYZ"``: Cardan (Bryant) 1-2-3: ``Rx Ry Rz``.

    Intrinsic: each rotation is about an axis of the frame produced by the
    previous ones (scipy ``Rotation.from_euler`` with upper-case ``seq``).
    Radians.
    """
    seq = _check_seq(seq)
    ang = _vec3(angles, "angles")
    ax = {"X": 0, "Y": 1, "Z": 2}
    return _r3(ax[seq[0]], ang[..., 0]) @ _r3(ax[seq[1]], ang[..., 1]) @ _r3(ax[seq[2]], ang[..., 2])


def matrix_to_euler(R, seq: str, *, tol: float = ANGLE_LOCK_TOL) -> np.ndarray:
    """Angles (..., 3) with ``euler_to_matrix(angles, seq) == R`` (see there for ``seq``).

    Ranges: ``"ZXZ"``, ``"ZYZ"``: first and third angle in (-pi, pi], middle
    angle in [0, pi]. ``"XYZ"``: first and third in (-pi, pi], middle in
    [-pi/2, pi/2].

    Singular case (the first and third axes line up: sin(middle) <= ``tol``
    for Euler, cos(middle) <= ``tol`` for Cardan): only the sum (or
    difference) of the first and third angles is defined. The *third* angle
    is returned as 0, the first carries the whole rotation, and the middle
    angle is exact (0 or pi; +-pi/2) -- the convention of scipy's
    ``as_euler``. Snapping moves the matrix by at most ``tol``.

    Near the singularity one outer angle is read from a matrix with the
    other one removed (ZXZ, ZYZ: the third from ``Rz(-first) @ R``; XYZ: the
    first from ``R @ Rz(-third)``), i.e. from entries of size 1, so the
    angles reproduce ``R`` to rounding all the way to the singular set.

    Accepts (..., 3, 3) or (..., 4, 4).
    """
    seq = _check_seq(seq)
    R = _rot_part(R, "R")
    if seq == "XYZ":
        cb = np.hypot(R[..., 0, 0], R[..., 0, 1])
        sing = cb <= tol
        up = R[..., 0, 2] >= 0.0
        mid = np.where(sing, np.where(up, 0.5 * np.pi, -0.5 * np.pi), np.arctan2(R[..., 0, 2], cb))
        third = np.where(sing, 0.0, np.arctan2(-R[..., 0, 1], R[..., 0, 0]))
        s3, c3 = np.sin(third), np.cos(third)
        # R Rz(-third) = Rx(first) Ry(mid): [2,1] = sin(first), [1,1] = cos(first)
        first = np.arctan2(R[..., 2, 0] * s3 + R[..., 2, 1] * c3, R[..., 1, 0] * s3 + R[..., 1, 1] * c3)
        return np.stack([_canon_angle(first), mid + 0.0, _canon_angle(third)], axis=-1)
    # proper Euler angles: third column of R is R_z(first) R_k(mid) e_z
    sb = np.hypot(R[..., 0, 2], R[..., 1, 2])
    sing = sb <= tol
    mid = np.arctan2(sb, R[..., 2, 2])
    mid = np.where(sing, np.where(R[..., 2, 2] >= 0.0, 0.0, np.pi), mid)
    if seq == "ZXZ":
        # column 2 = (s1 sm, -c1 sm, cm); singular: column 0 = (c1, s1, 0)
        first = np.where(sing, np.arctan2(R[..., 1, 0], R[..., 0, 0]), np.arctan2(R[..., 0, 2], -R[..., 1, 2]))
        s1, c1 = np.sin(first), np.cos(first)
        # N = Rz(-first) R = Rx(mid) Rz(third): row 0 = (c3, -s3, 0)
        n00 = c1 * R[..., 0, 0] + s1 * R[..., 1, 0]
        n01 = c1 * R[..., 0, 1] + s1 * R[..., 1, 1]
        third = np.arctan2(-n01, n00)
    else:  # ZYZ
        # column 2 = (c1 sm, s1 sm, cm); singular: column 1 = (-s1, c1, 0)
        first = np.where(sing, np.arctan2(-R[..., 0, 1], R[..., 1, 1]), np.arctan2(R[..., 1, 2], R[..., 0, 2]))
        s1, c1 = np.sin(first), np.cos(first)
        # N = Rz(-first) R = Ry(mid) Rz(third): row 1 = (s3, c3, 0)
        n10 = -s1 * R[..., 0, 0] + c1 * R[..., 1, 0]
        n11 = -s1 * R[..., 0, 1] + c1 * R[..., 1, 1]
        third = np.arctan2(n10, n11)
    third = np.where(sing, 0.0, third)
    return np.stack([_canon_angle(first), mid + 0.0, _canon_angle(third)], axis=-1)
