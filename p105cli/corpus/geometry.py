"""Rigid transforms and the pair motions the corpus generator relies on.

Conventions (the generator asserts them for every pair at every
configuration it writes; ``docs`` of :mod:`p105cli.corpus` lists them):

* ``T_a_b`` is the placement of frame b in frame a (columns: axes, origin),
  as in :mod:`p105cli.kinematics.placements`.
* A pair between links j (first) and k (second) with pair frames ``P_j``
  (in link j) and ``P_k`` (in link k) satisfies, for link poses ``T_j``,
  ``T_k`` in any common frame, ``M = P_j^-1 T_j^-1 T_k P_k`` where ``M`` is
  the pair's motion at its pair value (ISO 10303-105 5.4.18 note 2; for low
  pairs the contact frame is the second pair frame):

  - revolute: ``M = Rz(q)``;
  - prismatic: ``M = Tz(s)`` in the 1996 layout (Annex F: "a pure
    translation along the z axis"), ``M = Tx(s)`` in AP242 (its
    ``prismatic_pair`` derives ``t_x = TRUE``, all others FALSE);
  - gear (spur: bevel and helical angle 0): ``M = Rz(-q1) Tx(r1 + r2) Rz(q2)``
    with ``q2 = -gear_ratio * q1`` and ``gear_ratio = r1 / r2``: each gear's
    rotation measured from the line of centres, as ``gear_pair_value``'s
    derived ``actual_rotation_2`` says;
  - rack and pinion (rack = first link): ``M = Tx(d) Ty(r) Rz(-d / r)``,
    which is the derived ``actual_rotation`` of the 1996
    ``rack_and_pinion_pair_value``;
  - point on planar curve: ``M = Trans(C(u)) R``, ``C(u)`` the point of the
    pair curve (given in the first pair frame) at parameter u, ``R`` the
    orientation (``input_orientation``).
"""

from __future__ import annotations

import math

import numpy as np

from p105cli.kinematics.placements import su_parameters  # noqa: F401  (re-exported for the mechanism modules)
from p105cli.kinematics.spatial import (  # noqa: F401  (re-exported for the mechanism modules)
    compose, inverse, rot_x, rot_y, rot_z, trans_x, trans_y, trans_z, transform,
)

TOL = 1e-9


class GeometryError(AssertionError):
    """A written configuration does not satisfy a pair's motion (a generator bug)."""


def trans(x=0.0, y=0.0, z=0.0) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def frame(origin, z, x) -> np.ndarray:
    """The frame at ``origin`` with z axis ``z`` and x axis the part of ``x`` normal to it."""
    z = np.asarray(z, float)
    z = z / np.linalg.norm(z)
    x = np.asarray(x, float)
    x = x - np.dot(x, z) * z
    n = np.linalg.norm(x)
    if n < 1e-12:
        raise GeometryError("frame: x is parallel to z")
    x = x / n
    T = np.eye(4)
    T[:3, 0] = x
    T[:3, 1] = np.cross(z, x)
    T[:3, 2] = z
    T[:3, 3] = origin
    return T


def wrap(a: float) -> float:
    """An angle in (-pi, pi]."""
    a = math.remainder(float(a), 2.0 * math.pi)
    return math.pi if a == -math.pi else a


def _rot_angle_z(R) -> float:
    return math.atan2(R[1, 0], R[0, 0])


def _check(ok: bool, what: str):
    if not ok:
        raise GeometryError(what)


def axis_angle(R) -> tuple[np.ndarray, float]:
    """Unit axis and angle in [0, pi] of a rotation matrix (axis z for the identity)."""
    R = np.asarray(R, float)[:3, :3]
    c = max(-1.0, min(1.0, (np.trace(R) - 1.0) / 2.0))
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    s = np.linalg.norm(w) / 2.0
    angle = math.atan2(s, c)
    if angle < 1e-12:
        return np.array([0.0, 0.0, 1.0]), 0.0
    if s > 1e-6:
        return w / (2.0 * s), angle
    # near pi: from the symmetric part
    B = (R + np.eye(3)) / 2.0
    k = int(np.argmax(np.diag(B)))
    axis = B[:, k] / math.sqrt(B[k, k])
    return axis / np.linalg.norm(axis), angle


def pair_motion(kind: str, value: dict, params: dict, slide_axis: int = 2) -> np.ndarray:
    """The motion ``M`` of a pair at ``value`` (radians and millimetres).

    The low pairs' motions are :mod:`p105cli.kinematics.pairs`' (one rule in
    one place); ``slide_axis`` 2 is its "1996" layout, 0 its "ap242" layout.
    """
    from p105cli.kinematics import pairs

    if kind == "revolute":
        return pairs.REVOLUTE.motion([value["rotation"]])
    if kind == "prismatic":
        layout = {2: "1996", 0: "ap242"}.get(slide_axis)
        if layout is None:
            raise ValueError("prismatic pairs slide along z (1996) or x (AP242)")
        return pairs.PRISMATIC.motion([value["translation"]], layout=layout)
    if kind == "gear":
        return pairs.GEAR.motion([value["rotation_1"]], radius_first_link=params["radius_first"],
                                 radius_second_link=params["radius_second"], gear_ratio=params["gear_ratio"])
    if kind == "rack_and_pinion":
        return pairs.RACK_AND_PINION.motion([value["displacement"]], pinion_radius=params["pinion_radius"])
    if kind == "point_on_planar_curve":
        c, rad = params["circle_center"], params["circle_radius"]
        u = value["parameter"]
        p = np.asarray(c, float) + rad * np.array([math.cos(u), math.sin(u), 0.0])
        axis, angle = value["orientation"]
        return compose(trans(*p), _rodrigues(axis, angle))
    raise ValueError(f"unknown pair kind {kind!r}")


def _rodrigues(axis, angle) -> np.ndarray:
    k = np.asarray(axis, float)
    k = k / np.linalg.norm(k)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    R = np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)
    T = np.eye(4)
    T[:3, :3] = R
    return T


def pair_value(kind: str, rel: np.ndarray, params: dict, slide_axis: int = 2, hint: float | None = None) -> dict:
    """The pair value whose motion is ``rel`` (= ``P_j^-1 T_j^-1 T_k P_k``).

    Angles come out in (-pi, pi], except a gear's rotation_1, which is not
    periodic (it fixes rotation_2 = -ratio * rotation_1): it is the value
    nearest ``hint`` (default 0) whose rotation_2 matches.

    Raises :class:`GeometryError` unless ``rel`` is such a motion to ``TOL``
    (the pair placements would not be consistent with the geometry).
    """
    rel = np.asarray(rel, float)
    R, t = rel[:3, :3], rel[:3, 3]
    if kind == "revolute":
        q = _rot_angle_z(R)
        value = {"rotation": q}
    elif kind == "prismatic":
        value = {"translation": float(t[slide_axis])}
    elif kind == "gear":
        q1 = -math.atan2(t[1], t[0])
        q2 = _rot_angle_z(R) + q1  # modulo 2 pi
        ratio = params["gear_ratio"]
        h = 0.0 if hint is None else float(hint)
        k0 = round((h - q1) / (2 * math.pi))
        fits = [q1 + 2 * math.pi * k for k in range(k0 - 64, k0 + 65)
                if abs(wrap(q2 + ratio * (q1 + 2 * math.pi * k))) < TOL]
        _check(bool(fits), f"gear: rotation_2 {q2} is not -ratio * rotation_1 for any turn of rotation_1")
        value = {"rotation_1": min(fits, key=lambda q: abs(q - h))}
    elif kind == "rack_and_pinion":
        value = {"displacement": float(t[0])}
    elif kind == "point_on_planar_curve":
        c = np.asarray(params["circle_center"], float)
        d = t - c
        _check(abs(np.linalg.norm(d[:2]) - params["circle_radius"]) < TOL and abs(d[2]) < TOL,
               "point on planar curve: the second pair frame's origin is not on the curve")
        value = {"parameter": math.atan2(d[1], d[0]) % (2.0 * math.pi), "orientation": axis_angle(R)}
    else:
        raise ValueError(f"unknown pair kind {kind!r}")
    err = np.abs(pair_motion(kind, value, params, slide_axis) - rel).max()
    _check(err < TOL, f"{kind}: relative placement is not a {kind} motion (residual {err:.3g})")
    return value


def link_relative(T_first, P_first, T_second, P_second) -> np.ndarray:
    """``P_first^-1 T_first^-1 T_second P_second``."""
    return compose(inverse(P_first), inverse(T_first), T_second, P_second)


def ypr_angles(orientation) -> list:
    """(yaw, pitch, roll) with ``R = Rx(roll) Ry(pitch) Rz(yaw)`` (ISO 10303-105 Annex E, as
    :func:`p105cli.kinematics.placements.ypr_rotation`), from an (axis, angle) rotation."""
    from p105cli.kinematics.placements import ypr_from_matrix, ypr_rotation

    axis, angle = orientation
    R = _rodrigues(axis, angle)[:3, :3]
    ypr = [float(x) for x in ypr_from_matrix(R)]
    if np.abs(ypr_rotation(*ypr) - R).max() > 1e-12:
        raise GeometryError("ypr angles do not rebuild the rotation")
    return ypr
