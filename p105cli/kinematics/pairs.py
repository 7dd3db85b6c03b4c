"""Pair motions of ISO 10303-105: ``M(q)``, its derivatives and twist Jacobians.

Conventions (read these before using any function)
---------------------------------------------------

* ``M(q)`` is the placement of the second pair frame in the first pair frame
  (``T_Pj_Pk``, the matrix the standard writes ``pPF_q`` between the pair
  frames, 5.4.18 note 2; for low pairs the contact frame is the second pair
  frame). For a pair whose frames are ``P1`` on link 1 (the first link) and
  ``P2`` on link 2::

      T_link1_link2(q) = P1 @ M(q) @ inverse(P2)

  (:func:`link_transform`). This is the convention the corpus generator
  asserts for every configuration it writes (:mod:`p105cli.corpus.geometry`).
* Every function is vectorised: ``q`` has shape ``(..., n_values)`` (the pair's
  values in the order of the attributes of its ``*_pair_value`` entity, see
  :attr:`PairType.value_names`); parameters are scalars or arrays that
  broadcast with ``q.shape[:-1]``; results are float64 with leading axes
  ``q.shape[:-1]`` (broadcast with the parameters). Nothing loops in Python.
* Angles (values and parameters) are radians, lengths in the file's length
  unit. Converting a file's plane-angle unit is the caller's job
  (:func:`p105cli.kinematics.placements.plane_angle_to_radian`).
* Twists are 6-vectors ordered ``(v_x, v_y, v_z, w_x, w_y, w_z)``: linear
  part first, then angular part.
* :meth:`PairType.motion_jacobian` returns the **body** Jacobian by default:
  column i is the twist ``vee(M^-1 dM/dq_i)``, i.e. the velocity of the
  second pair frame relative to the first, expressed in the *second* pair
  frame (origin velocity and angular velocity). ``frame="spatial"`` gives
  ``vee(dM/dq_i M^-1)`` (expressed in the first pair frame, linear part the
  velocity of the point of frame 2 passing through frame 1's origin). The
  two are related by the adjoint of ``M`` (:func:`p105cli.kinematics.spatial.adjoint`;
  ``hat``, ``vee`` and ``adjoint`` live there).
* :meth:`PairType.motion_derivative` gives ``dM/dq`` as ``(..., n, 4, 4)``
  (``dM/dq_i = M @ hat(J_body[..., :, i])``).

Pair motions (``q`` in the order given; [clause of ISO 10303-105:1996])
----------------------------------------------------------------------

=====================  =========================================  ==============================
pair                   values ``q``                               ``M(q)``
=====================  =========================================  ==============================
revolute               (rotation,)                                ``Rz(rotation)``  [5.4.22]
prismatic              (translation,)                             ``Tz(s)`` layout "1996" [Annex
                                                                  F: "pure translation along z"];
                                                                  ``Tx(s)`` layout "ap242" (its
                                                                  prismatic_pair derives t_x =
                                                                  TRUE, all other flags FALSE)
screw                  (rotation,); param ``pitch``               ``Rz(th) Tz(pitch th / (2 pi))``
                                                                  [Annex F; 5.4.29]
cylindrical            (translation, rotation)                    ``Tz(s) Rz(th)`` [Annex F; AP242
                                                                  flags t_z, r_z]
spherical              (yaw, pitch, roll)                         ``ypr_rotation`` = ``Rx(roll)
                                                                  Ry(pitch) Rz(yaw)`` [5.3.7,
                                                                  Annex E; 5.4.35 derives the
                                                                  ypr actual_orientation]
universal              (first_rotation_angle,                     ``Rz(q1) Ry(-s) Rx(q2) Ry(s)``,
                       second_rotation_angle); param              ``s`` = skew_angle [5.4.37]
                       ``input_skew_angle`` (None -> 0)
homokinetic            as universal (skew must be absent)         ``Rz(q1) Rx(q2) Rz(-q1)``
planar                 (rotation, translation_x, translation_y)   ``Tx(x) Ty(y) Rz(th)``
unconstrained          (tx, ty, tz, yaw, pitch, roll)             ``[ypr_rotation, (tx,ty,tz)]``
fully_constrained      ()                                         identity
gear                   (rotation_1,); params radius_first_link,   ``Rz(-q1) Tx(r1 + r2)
                       radius_second_link, gear_ratio, bevel=0,   Rz(-gear_ratio q1)``
                       helical_angle=0
rack_and_pinion        (displacement,); param pinion_radius       ``Tx(d) Ty(r) Rz(-d / r)``
point_on_surface       (u, v, yaw, pitch, roll); param surface    ``Trans(S(u,v)) ypr``
point_on_planar_curve  (u, yaw, pitch, roll); param curve         ``Trans(C(u)) ypr``
sliding_surface        (u1, v1, u2, v2, rotation); params         ``F1(u1,v1) Rz(rot) Rx(pi)^[not
                       surface_1, surface_2, orientation          o] F2(u2,v2)^-1``
rolling_surface        (u1, v1, rotation); + state (u2, v2)       as sliding_surface, no slip
sliding_curve          (u1, u2); curve_1, curve_2, orientation    ``G1(u1) Rz(pi)^[not o] G2(u2)^-1``
rolling_curve          (u1,); u2 from equal arc lengths           as sliding_curve
low_order (AP242)      (tx, ty, tz, rx, ry, rz); flags t_x..r_z   a named pair's flags: its M;
                                                                  else ``T(t) Rx(rx) Ry(ry) Rz(rz)``
spherical_with_pin     (yaw, pitch, roll = 0)                     ``Ry(pitch) Rz(yaw)``
=====================  =========================================  ==============================

``F(u, v)`` is a surface's contact frame (origin ``S``, x along ``Su``, z along
``Su x Sv``), ``G(u)`` a planar curve's (origin ``C``, x along the tangent's xy
part, z = +z); ``o`` the pair's ``orientation``. The full definitions, the
choices made and their reasons are in docs/pairs.md.

Where these come from, and what had to be chosen:

* revolute (5.4.22): the rotation that turns the first pair frame about the
  common z axis until its x axis coincides with the second frame's x axis;
  positive counter-clockwise seen from +z (5.2.3).
* prismatic: the 1996 text's Annex F (DH -> SU) calls the prismatic pair's
  transform "a pure translation along the z axis"; AP242 (ISO 10303-105 ed. 2
  as used by AP242) derives ``t_x = TRUE`` and every other flag FALSE, so it
  slides along x. The layout is the ``layout`` parameter: ``"1996"`` (the
  default for ``prismatic_pair``, which both layouts spell the same way) or
  ``"ap242"`` (the default for ``prismatic_pair_with_range``, an AP242-only
  name).
* screw: Annex F: "translation along z (s) and a yaw rotation (theta) ...
  in a screw pair one depends on the other (see 5.4.29)". The derived
  ``actual_translation`` of ``screw_pair_value`` is ``pitch * angle / (2 PI)``
  in AP242; the 1996 EXPRESS writes ``pitch * angle / 2 * PI`` which, by
  EXPRESS operator precedence, would be ``pitch * angle * PI / 2`` -- a
  transcription slip (it would not make ``pitch`` the advance per turn). We
  follow AP242: ``pitch`` is the translation per full turn, positive pitch =
  right-handed advance along +z for positive rotation.
* cylindrical: Annex F as for the screw pair, with independent values; AP242
  flags t_z and r_z. The two motions commute.
* spherical: ``spherical_pair_value`` derives a ``ypr_rotation`` (5.4.35),
  whose matrix is Annex E's ``Rx(roll) Ry(pitch) Rz(yaw)``
  (:func:`p105cli.kinematics.placements.ypr_rotation`).
* universal (5.4.37, 5.4.38): two rotations, "the first about the first axis,
  the second about the second axis"; ``skew_angle`` (= ``NVL(input_skew_angle,
  0)``) is "the offset of the angle between the two rotation axes from a right
  angle", and WR1 requires ``cos(skew_angle) > 0``. AP242 flags r_x and r_z.
  The body of 5.4.37 is not legible in the copy of the standard we have, so
  the frame assignment is ours: the first axis is the first pair frame's z
  axis; the second axis is fixed in the cross and in link 2 and is, at
  ``q1 = 0``, ``a = (cos s, 0, sin s)`` in the first pair frame (the x axis
  tilted by the skew towards +z, so the angle between the axes is
  ``pi/2 - s``); ``M = Rz(q1) Rot(a, q2)`` with ``Rot(a, q2) = Ry(-s) Rx(q2)
  Ry(s)``. With no skew, ``M = Rz(q1) Rx(q2)``; at ``q = 0`` the two pair
  frames coincide.
* homokinetic (a universal_pair subtype whose WR1 forbids a skew angle): the
  constant-velocity joint. Ours: ``M = Rz(q1) Rx(q2) Rz(-q1)``, a pure swing of
  the second frame's z axis by ``q2`` about the axis ``(cos q1, sin q1, 0)``
  with no twist about z: the relative pose of a symmetric double Cardan joint
  (two universal joints ``Rz(q1) Rx(q2/2)`` and its mirror image), which turns
  the output shaft at the speed of the input shaft. ``q1`` is undefined at
  ``q2 = 0`` (the Jacobian loses rank there).
* planar: AP242 flags t_x, t_y, r_z; values in the order of
  ``planar_pair_value`` (rotation, translation_x, translation_y). The
  translation is the second frame's origin in the first frame.
* unconstrained: the value is an ``axis2_placement_3d`` (the second pair frame
  in the first); we parameterise it by its location and its ypr angles.
* gear (spur): the corpus convention, each gear's rotation measured from the
  line of centres (the first pair frame's x axis) as ``gear_pair_value``'s
  derived ``actual_rotation_2 = -actual_rotation_1 * gear_ratio`` says:
  ``M = Rz(-q1) Tx(r1 + r2) Rz(q2)``, ``q2 = -gear_ratio * q1``. The pair frames
  sit on the gear axes; at ``q1 = 0`` they differ by the centre distance along
  x. ``gear_ratio`` is the file's attribute (``r1 / r2`` for a spur mesh; it is
  not checked against the radii). A non-zero ``bevel`` or ``helical_angle``
  raises :class:`UnsupportedPairError`: neither EXPRESS (both layouts
  declare the two angles with no rule or derived attribute using them) nor
  the available text (5.4.64-5.4.66 are missing from the capture) defines
  where a bevel's or helical gear's axes lie, so the motion would be a guess.
* rack and pinion (rack = first link): ``M = Tx(d) Ty(r) Rz(-d / r)`` -- the
  pinion's centre rides at height ``r`` above the rack's pitch line (x axis)
  and it turns by the 1996 ``rack_and_pinion_pair_value``'s derived
  ``actual_rotation = -actual_displacement / pinion_radius``. (AP242's
  ``rack_and_pinion_pair_value`` derives ``actual_rotation := 0.0``, which
  cannot be a rolling motion; we follow the 1996 derivation.)

* higher pairs (5.1: pairs 12-17) take their curves and surfaces as
  :mod:`p105cli.kinematics.geometry` objects in the coordinates of their pair
  frame (``surface``, ``curve``, ``surface_1``/``surface_2`` in the first/second
  pair frame, ``curve_1``/``curve_2``). The point pairs' orientation is
  relative to the first pair frame's axes (the corpus convention); sliding
  pairs make the two contact frames coincide (normals and tangents as the
  ``orientation`` flag says); rolling curves add equal arc lengths from the
  ``reference_parameter_1``/``_2`` points (holonomic); rolling surfaces are
  non-holonomic: ``point_on_surface_2`` is state and their Jacobian is the
  no-slip velocity map (:func:`rolling_surface_rates`). Degenerate contact
  frames raise ValueError (never NaN).
* low_order (AP242 ``low_order_kinematic_pair``): a named pair's flags move
  as that pair (:data:`LOW_ORDER_NAMED`); others translation first, then
  ``Rx(rx) Ry(ry) Rz(rz)`` (the ypr matrix, roll, pitch, yaw = rx, ry, rz).
  A locked value must be 0 (zero Jacobian column); docs/pairs.md.
* spherical_pair_with_pin: its ``spherical_pair_value`` ypr with the roll
  (about x) locked, as AP242's DERIVE (r_x FALSE, r_y and r_z TRUE) says.
  (``spherical_pair_with_pin_and_range`` bounds yaw and roll, not pitch; we
  follow the DERIVE, which is normative, and document the clash.)

Not implemented: the flexible pairs (``linear_flexible_and_pinion_pair``,
``linear_flexible_and_planar_curve_pair``); :func:`pair_type` raises
:class:`UnsupportedPairError` for those names.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .freedoms import FREEDOM_NAMES
from .placements import ypr_rotation
from .spatial import adjoint, compose, hat, inverse, rot_x, rot_y, rot_z, trans_x, trans_y, trans_z, transform

__all__ = [
    "UnsupportedPairError", "PairType", "PAIRS", "PAIR_KINDS", "NOT_IMPLEMENTED", "pair_type",
    "link_transform", "LAYOUTS", "HIGHER_KINDS", "rolling_surface_rates",
    "VALUE_UNITS", "LOW_ORDER_NAMED", "FREEDOM_NAMES", "named_low_order", "low_order_components",
]

#: Layouts of the pair frames: where a prismatic pair slides.
LAYOUTS = ("1996", "ap242")

_TWO_PI = 2.0 * np.pi


class UnsupportedPairError(NotImplementedError):
    """A pair type, or a parameter value, whose motion this module does not define."""


# --------------------------------------------------------------------------- link transform

def link_transform(P1, M, P2=None, *, P2inv=None) -> np.ndarray:
    """``T_link1_link2 = P1 @ M @ inverse(P2)`` (leading axes broadcast): THE pair transform
    (``Pair.transform`` and the solver's forward kinematics compute it here). ``P2inv``:
    ``inverse(P2)`` when the caller has it (the solver's plan keeps it per pair)."""
    return compose(P1, M, inverse(P2) if P2inv is None else P2inv)


# --------------------------------------------------------------------------- small builders

def _f(x) -> np.ndarray:
    return np.asarray(x, dtype=np.float64)


def _col(vectors, shape) -> np.ndarray:
    """Stack a list of (..., 6) twists into a (..., 6, n) Jacobian of batch ``shape``."""
    if not vectors:
        return np.zeros(shape + (6, 0))
    vs = [np.broadcast_to(v, shape + (6,)) for v in vectors]
    return np.stack(vs, axis=-1)


def _twist(v=None, w=None, shape=()) -> np.ndarray:
    out = np.zeros(shape + (6,))
    if v is not None:
        out[..., :3] = v
    if w is not None:
        out[..., 3:] = w
    return out


_EX = np.array([1.0, 0.0, 0.0])
_EY = np.array([0.0, 1.0, 0.0])
_EZ = np.array([0.0, 0.0, 1.0])


def _rt(R, v) -> np.ndarray:
    """R^T v for (..., 3, 3) R and (..., 3) v."""
    return np.einsum("...ji,...j->...i", R, v)


# --------------------------------------------------------------------------- the pairs
# Each pair: motion(q_list, params) -> (..., 4, 4); body_jacobian(q_list, params, shape) -> (..., 6, n).
# q_list is the list of (...) arrays q[..., i]; shape the broadcast batch shape.

def _revolute_m(q, p):
    return rot_z(q[0])


def _revolute_j(q, p, shape):
    return _col([_twist(w=_EZ, shape=shape)], shape)


def _slide_axis(layout) -> int:
    if layout == "1996":
        return 2
    if layout == "ap242":
        return 0
    raise ValueError(f"prismatic pair: layout must be one of {LAYOUTS} (1996: slide along z, "
                     f"Annex F; ap242: slide along x, t_x = TRUE), got {layout!r}")


def _prismatic_m(q, p):
    return (trans_x, trans_y, trans_z)[_slide_axis(p["layout"])](q[0])


def _prismatic_j(q, p, shape):
    axis = np.eye(3)[_slide_axis(p["layout"])]
    return _col([_twist(v=axis, shape=shape)], shape)


def _lead(p):
    return _f(p["pitch"]) / _TWO_PI


def _screw_m(q, p):
    return compose(rot_z(q[0]), trans_z(_lead(p) * q[0]))


def _screw_j(q, p, shape):
    h = _f(_lead(p))[..., None]
    return _col([_twist(v=h * _EZ, w=_EZ, shape=shape)], shape)


def _cylindrical_m(q, p):
    return compose(trans_z(q[0]), rot_z(q[1]))


def _cylindrical_j(q, p, shape):
    return _col([_twist(v=_EZ, shape=shape), _twist(w=_EZ, shape=shape)], shape)


def _ypr_body_axes(yaw, pitch):
    """Body angular velocities of ``Rx(roll) Ry(pitch) Rz(yaw)`` per unit yaw, pitch, roll rate."""
    cy, sy = np.cos(yaw), np.sin(yaw)
    cp, sp = np.cos(pitch), np.sin(pitch)
    zero, one = np.zeros_like(cy), np.ones_like(cy)
    w_yaw = np.stack([zero, zero, one], axis=-1)
    w_pitch = np.stack([sy, cy, zero], axis=-1)                 # Rz(-yaw) e_y
    w_roll = np.stack([cy * cp, -sy * cp, sp], axis=-1)         # Rz(-yaw) Ry(-pitch) e_x
    return w_yaw, w_pitch, w_roll


def _spherical_m(q, p):
    return transform(ypr_rotation(q[0], q[1], q[2]))


def _spherical_j(q, p, shape):
    wy, wp, wr = _ypr_body_axes(*np.broadcast_arrays(q[0], q[1]))
    return _col([_twist(w=wy, shape=shape), _twist(w=wp, shape=shape), _twist(w=wr, shape=shape)], shape)


def _skew(p):
    s = p.get("input_skew_angle")
    s = _f(0.0 if s is None else s)
    if np.any(~(np.cos(s) > 0.0)):
        raise ValueError("universal pair: WR1 requires cos(skew_angle) > 0 (the axes' offset from a "
                         "right angle must be acute)")
    return s


def _universal_m(q, p):
    s = _skew(p)
    return compose(rot_z(q[0]), rot_y(-s), rot_x(q[1]), rot_y(s))


def _universal_j(q, p, shape):
    s = _skew(p)
    a = np.stack(np.broadcast_arrays(np.cos(s), np.zeros_like(s), np.sin(s)), axis=-1)
    Ra = compose(rot_y(-s), rot_x(q[1]), rot_y(s))[..., :3, :3]
    w1 = _rt(Ra, np.broadcast_to(_EZ, Ra.shape[:-1]))
    return _col([_twist(w=w1, shape=shape), _twist(w=a, shape=shape)], shape)


def _homokinetic_check(p):
    s = p.get("input_skew_angle")
    if s is not None:
        raise ValueError("homokinetic pair: WR1 forbids input_skew_angle")


def _homokinetic_m(q, p):
    _homokinetic_check(p)
    return compose(rot_z(q[0]), rot_x(q[1]), rot_z(-q[0]))


def _homokinetic_j(q, p, shape):
    _homokinetic_check(p)
    R = _homokinetic_m(q, p)[..., :3, :3]
    ez = np.broadcast_to(_EZ, R.shape[:-1])
    w1 = _rt(R, ez) - ez                                         # M^T z - z
    c, s = np.cos(q[0]), np.sin(q[0])
    w2 = np.stack(np.broadcast_arrays(c, s, np.zeros_like(c)), axis=-1)   # Rz(q1) e_x
    return _col([_twist(w=w1, shape=shape), _twist(w=w2, shape=shape)], shape)


def _planar_m(q, p):
    return compose(trans_x(q[1]), trans_y(q[2]), rot_z(q[0]))


def _planar_j(q, p, shape):
    R = rot_z(q[0])[..., :3, :3]
    ex = np.broadcast_to(_EX, R.shape[:-1])
    ey = np.broadcast_to(_EY, R.shape[:-1])
    return _col([_twist(w=_EZ, shape=shape), _twist(v=_rt(R, ex), shape=shape),
                 _twist(v=_rt(R, ey), shape=shape)], shape)


def _unconstrained_m(q, p):
    R = ypr_rotation(q[3], q[4], q[5])
    t = np.stack(np.broadcast_arrays(q[0], q[1], q[2]), axis=-1)
    return transform(R, t)


def _unconstrained_j(q, p, shape):
    R = ypr_rotation(q[3], q[4], q[5])
    cols = [_twist(v=_rt(R, np.broadcast_to(e, R.shape[:-1])), shape=shape) for e in (_EX, _EY, _EZ)]
    wy, wp, wr = _ypr_body_axes(*np.broadcast_arrays(q[3], q[4]))
    cols += [_twist(w=wy, shape=shape), _twist(w=wp, shape=shape), _twist(w=wr, shape=shape)]
    return _col(cols, shape)


def _fixed_m(q, p):
    shape = p["_shape"]
    return np.broadcast_to(np.eye(4), shape + (4, 4)).copy()


def _fixed_j(q, p, shape):
    return np.zeros(shape + (6, 0))


def _gear_check(p):
    for name in ("bevel", "helical_angle"):
        v = _f(p.get(name, 0.0))
        if np.any(v != 0.0):
            raise UnsupportedPairError(
                f"gear pair: {name} = {float(np.asarray(v).flat[np.flatnonzero(v)[0]]):g} is not "
                "supported; only spur gears (bevel = 0, helical_angle = 0) have a defined motion here: "
                "neither layout's EXPRESS places a bevel or helical gear's axes (docs/pairs.md)")


def _gear_m(q, p):
    _gear_check(p)
    q1 = q[0]
    q2 = -_f(p["gear_ratio"]) * q1
    return compose(rot_z(-q1), trans_x(_f(p["radius_first_link"]) + _f(p["radius_second_link"])), rot_z(q2))


def _gear_j(q, p, shape):
    _gear_check(p)
    k = _f(p["gear_ratio"])
    c = _f(p["radius_first_link"]) + _f(p["radius_second_link"])
    q1 = q[0]
    R = rot_z(-q1 - k * q1)[..., :3, :3]
    zxp = np.stack(np.broadcast_arrays(c * np.sin(q1), c * np.cos(q1), 0.0 * q1), axis=-1)  # z x p
    v = -_rt(R, zxp)
    w = -_f(1.0 + k)[..., None] * _EZ
    return _col([_twist(v=v, w=w, shape=shape)], shape)


def _rack_m(q, p):
    d, r = q[0], _f(p["pinion_radius"])
    return compose(trans_x(d), trans_y(r), rot_z(-d / r))


def _rack_j(q, p, shape):
    d, r = q[0], _f(p["pinion_radius"])
    R = rot_z(-d / r)[..., :3, :3]
    v = _rt(R, np.broadcast_to(_EX, R.shape[:-1]))
    w = _f(-1.0 / r)[..., None] * _EZ
    return _col([_twist(v=v, w=w, shape=shape)], shape)


# --------------------------------------------------------------------------- higher pairs
# Contact frames on the pair geometry (see docs/pairs.md). Each helper returns the frame F
# (..., 4, 4) and the body twists vee(F^-1 dF/dparam) (..., 6) of its parameters.

def _unit(v, what):
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(~(n > 0.0)):
        raise ValueError(f"{what} is degenerate (zero or non-finite) at the given parameter values")
    return v / n, n


def _dot(a, b):
    return np.einsum("...i,...i->...", a, b)


def _surface_frame(surface, u, v):
    """Contact frame of a surface: origin S(u, v), x = unit Su, z = unit (Su x Sv), y = z x x."""
    S, Su, Sv, Suu, Suv, Svv = _check_surface(surface).evaluate2(u, v)
    x, a = _unit(Su, "surface: the u tangent")
    z, nb = _unit(np.cross(Su, Sv), "surface: the normal (Su x Sv)")
    y = np.cross(z, x)
    R = np.stack([x, y, z], axis=-1)
    F = transform(R, S)
    twists = []
    for dS, dSu, db in ((Su, Suu, np.cross(Suu, Sv) + np.cross(Su, Suv)),
                        (Sv, Suv, np.cross(Suv, Sv) + np.cross(Su, Svv))):
        dx = (dSu - x * _dot(x, dSu)[..., None]) / a
        dz = (db - z * _dot(z, db)[..., None]) / nb
        # body angular velocity of [x y z]: (z.dy, x.dz, y.dx), z.dy = -y.dz
        w = np.stack([-_dot(y, dz), _dot(x, dz), _dot(y, dx)], axis=-1)
        twists.append(np.concatenate([_rt(R, dS), w], axis=-1))
    return F, twists


def _curve_frame(curve, u):
    """Contact frame of a planar curve: origin C(u), x = unit tangent in the xy plane, z = +z."""
    C, d, dd = _check_curve(curve).evaluate(u)
    sp2 = d[..., 0] ** 2 + d[..., 1] ** 2
    if np.any(~(sp2 > 0.0)):
        raise ValueError("curve: the tangent has no component in the pair frame's xy plane "
                         "(planar curve pairs need curves in planes parallel to it)")
    F = compose(transform(np.eye(3), C), rot_z(np.arctan2(d[..., 1], d[..., 0])))
    dalpha = (d[..., 0] * dd[..., 1] - d[..., 1] * dd[..., 0]) / sp2
    R = F[..., :3, :3]
    w = np.zeros(d.shape)
    w[..., 2] = dalpha
    return F, np.concatenate([_rt(R, d), w], axis=-1)


def _rot_body(R, twist):
    """Ad(Rot^-1) of a pure rotation ``R`` (..., 3, 3) applied to body twists: (R^T v, R^T w)."""
    return np.concatenate([_rt(R, twist[..., :3]), _rt(R, twist[..., 3:])], axis=-1)


def _flip(flag, shape):
    """Rx(pi) where ``flag`` is False (surface normals opposed), identity where True."""
    f = np.broadcast_to(np.asarray(flag, dtype=bool), shape)
    return np.where(f[..., None, None], np.eye(4), np.diag([1.0, -1.0, -1.0, 1.0]))


def _turn(flag, shape):
    """Rz(pi) where ``flag`` is False (curve tangents opposed), identity where True."""
    f = np.broadcast_to(np.asarray(flag, dtype=bool), shape)
    return np.where(f[..., None, None], np.eye(4), np.diag([-1.0, -1.0, 1.0, 1.0]))


def _contact_chain(F1, tw1, B, twB, F2, tw2):
    """Body twists of ``M = F1 B F2^-1``: ``Ad(F2) [Ad(B^-1) xi_F1 + xi_B - xi_F2]``.

    ``tw1``, ``twB``, ``tw2``: lists of body twists of F1, B and F2 (one per
    value they depend on), returned in that order. ``B`` is a pure rotation."""
    A2 = adjoint(F2)
    RB = B[..., :3, :3]
    out = [np.einsum("...ij,...j->...i", A2, _rot_body(RB, t)) for t in tw1]
    out += [np.einsum("...ij,...j->...i", A2, t) for t in twB]
    out += [-np.einsum("...ij,...j->...i", A2, t) for t in tw2]
    return out


# point_on_surface: q = (u, v, yaw, pitch, roll); M = Trans(S(u, v)) Rx(roll) Ry(pitch) Rz(yaw)
# point_on_planar_curve: q = (u, yaw, pitch, roll); M = Trans(C(u)) Rx(roll) Ry(pitch) Rz(yaw)
# The orientation is the second pair frame's relative to the first pair frame's axes (as for the
# spherical and unconstrained pairs), not to a tangent frame: the corpus convention.

def _check_surface(surface):
    if not hasattr(surface, "evaluate2"):
        raise TypeError(f"surface parameter must be a p105cli.kinematics.geometry surface, got {surface!r}")
    return surface


def _check_curve(curve):
    if not hasattr(curve, "evaluate"):
        raise TypeError(f"curve parameter must be a p105cli.kinematics.geometry curve, got {curve!r}")
    return curve


def _point_m(P, ypr):
    return transform(ypr_rotation(*ypr), P)


def _point_j(dPs, ypr, shape):
    Y = ypr_rotation(*ypr)
    wy, wp, wr = _ypr_body_axes(*np.broadcast_arrays(ypr[0], ypr[1]))
    return _col([_twist(v=_rt(Y, d), shape=shape) for d in dPs]
                + [_twist(w=wy, shape=shape), _twist(w=wp, shape=shape), _twist(w=wr, shape=shape)], shape)


def _finite(x, what):
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{what} is not finite at the given parameter values")
    return x


def _pos_m(q, p):
    S, _, _ = _check_surface(p["surface"]).evaluate(q[0], q[1])
    return _point_m(_finite(S, "surface point"), q[2:5])


def _pos_j(q, p, shape):
    _, Su, Sv = _check_surface(p["surface"]).evaluate(q[0], q[1])
    return _point_j([Su, Sv], q[2:5], shape)


def _popc_m(q, p):
    C, _, _ = _check_curve(p["curve"]).evaluate(q[0])
    return _point_m(_finite(C, "curve point"), q[1:4])


def _popc_j(q, p, shape):
    _, d, _ = _check_curve(p["curve"]).evaluate(q[0])
    return _point_j([d], q[1:4], shape)


# sliding_surface: q = (u1, v1, u2, v2, rotation);
# M = F1(u1, v1) Rz(rotation) Rx(pi)^[not orientation] F2(u2, v2)^-1

def _surface_contact(q5, p, shape):
    F1, tw1 = _surface_frame(p["surface_1"], q5[0], q5[1])
    F2, tw2 = _surface_frame(p["surface_2"], q5[2], q5[3])
    fl = _flip(p["orientation"], shape)
    B = compose(rot_z(q5[4]), fl)
    return F1, tw1, B, fl, F2, tw2


def _ss_m(q, p):
    F1, _, B, _, F2, _ = _surface_contact(q, p, p["_shape"])
    return compose(F1, B, inverse(F2))


def _ss_cols(q5, p, shape):
    F1, tw1, B, fl, F2, tw2 = _surface_contact(q5, p, shape)
    twB = _rot_body(fl[..., :3, :3], _twist(w=_EZ, shape=shape))    # B^-1 dB/drotation = Fl^T z^ Fl
    c = _contact_chain(F1, tw1, B, [twB], F2, tw2)
    return [c[0], c[1], c[3], c[4], c[2]]                             # u1, v1, u2, v2, rotation


def _ss_j(q, p, shape):
    return _col(_ss_cols(q, p, shape), shape)


# rolling_surface: q = (u1, v1, rotation); (u2, v2) = param point_on_surface_2 (non-holonomic state)

def _rs_q5(q, p, shape):
    if p["point_on_surface_2"] is None:
        raise ValueError("rolling surface pair: pass point_on_surface_2 = (u2, v2), the contact point on "
                         "surface_2: rolling surfaces is non-holonomic, so it is state to carry along "
                         "(integrate it with rolling_surface_rates), not a function of the pair values")
    w = np.asarray(p["point_on_surface_2"], dtype=np.float64)
    if w.shape[-1:] != (2,):
        raise ValueError("rolling surface pair: point_on_surface_2 must have shape (..., 2) (u2, v2)")
    u2 = np.broadcast_to(w[..., 0], shape)
    v2 = np.broadcast_to(w[..., 1], shape)
    return [q[0], q[1], u2, v2, q[2]]


def _rs_m(q, p):
    return _ss_m(_rs_q5(q, p, p["_shape"]), p)


def _rolling_rates(q5, p, shape):
    """d(u2, v2)/d(u1, v1, rotation) (..., 2, 3) for no slip, and the five sliding columns."""
    cols = _ss_cols(q5, p, shape)
    S2, S2u, S2v = p["surface_2"].evaluate(q5[2], q5[3])
    ta, _ = _unit(S2u, "surface_2: the u tangent")
    n, _ = _unit(np.cross(S2u, S2v), "surface_2: the normal")
    tb = np.cross(n, ta)

    def slip(t):        # tangential velocity of the material point of link 2 at the contact, frame-2 axes
        c = t[..., :3] + np.cross(t[..., 3:], S2)
        return np.stack([_dot(ta, c), _dot(tb, c)], axis=-1)

    G = np.stack([slip(cols[2]), slip(cols[3])], axis=-1)                 # (..., 2, 2)
    Q = np.stack([slip(cols[0]), slip(cols[1]), slip(cols[4])], axis=-1)  # (..., 2, 3)
    if np.any(~(np.abs(np.linalg.det(G)) > 0.0)):
        raise ValueError("rolling surface pair: the contact is degenerate (no-slip rates undefined)")
    return -np.linalg.solve(G, Q), cols


def rolling_surface_rates(q, *, surface_1, surface_2, orientation, point_on_surface_2) -> np.ndarray:
    """``d(u2, v2) / d(u1, v1, rotation)`` of a rolling surface pair: (..., 2, 3).

    Rolling of surfaces is non-holonomic: the contact point on ``surface_2``
    is state to integrate with these rates, not a function of the values."""
    t = PAIR_KINDS["rolling_surface"]
    qs, p, shape = t._args(q, dict(surface_1=surface_1, surface_2=surface_2, orientation=orientation,
                                   point_on_surface_2=point_on_surface_2))
    return _rolling_rates(_rs_q5(qs, p, shape), p, shape)[0]


def _rs_j(q, p, shape):
    rates, cols = _rolling_rates(_rs_q5(q, p, shape), p, shape)
    out = []
    for i, k in enumerate((0, 1, 4)):
        out.append(cols[k] + cols[2] * rates[..., 0, i, None] + cols[3] * rates[..., 1, i, None])
    return _col(out, shape)


# sliding_curve: q = (u1, u2); M = F1(u1) Rz(pi)^[not orientation] F2(u2)^-1

def _sc_m(q, p):
    F1, _ = _curve_frame(p["curve_1"], q[0])
    F2, _ = _curve_frame(p["curve_2"], q[1])
    return compose(F1, _turn(p["orientation"], p["_shape"]), inverse(F2))


def _sc_cols(u1, u2, p, shape):
    F1, t1 = _curve_frame(p["curve_1"], u1)
    F2, t2 = _curve_frame(p["curve_2"], u2)
    return _contact_chain(F1, [t1], _turn(p["orientation"], shape), [], F2, [t2])


def _sc_j(q, p, shape):
    return _col(_sc_cols(q[0], q[1], p, shape), shape)


# rolling_curve: q = (u1,); u2 from s2(ref2 -> u2) = sigma s1(ref1 -> u1), sigma = +1 (orientation) / -1

def _rc_u2(u1, p, shape):
    from .geometry import arc_length, parameter_at_arc_length
    sigma = np.where(np.broadcast_to(np.asarray(p["orientation"], dtype=bool), shape), 1.0, -1.0)
    r1 = np.broadcast_to(_f(p["reference_parameter_1"]), shape)
    r2 = np.broadcast_to(_f(p["reference_parameter_2"]), shape)
    s1 = arc_length(p["curve_1"], r1, u1)
    return parameter_at_arc_length(p["curve_2"], r2, sigma * s1), sigma


def _rc_m(q, p):
    u2, _ = _rc_u2(q[0], p, p["_shape"])
    return _sc_m([q[0], u2], p)


def _rc_j(q, p, shape):
    u2, sigma = _rc_u2(q[0], p, shape)
    c1, c2 = _sc_cols(q[0], u2, p, shape)
    sp1 = np.linalg.norm(p["curve_1"].evaluate(q[0])[1], axis=-1)
    sp2 = np.linalg.norm(p["curve_2"].evaluate(u2)[1], axis=-1)
    du2 = sigma * sp1 / sp2
    return _col([c1 + c2 * du2[..., None]], shape)


# low_order_kinematic_pair: q = (tx, ty, tz, rx, ry, rz), its flags say which are free

#: The one table of what a flag set and a low-order value mean: kind -> (the flags t_x..r_z
#: AP242 derives for it, the component (0..5 = tx, ty, tz, rx, ry, rz) of a
#: low_order_kinematic_pair_value giving each of its values). Spherical (yaw, pitch, roll) =
#: (rz, ry, rx); universal: rz then rx; prismatic: AP242's t_x. Where two kinds share flags,
#: the first is the one a generic pair is (universal, not homokinetic). docs/pairs.md.
LOW_ORDER_NAMED = {
    "revolute": ((0, 0, 0, 0, 0, 1), (5,)),
    "prismatic": ((1, 0, 0, 0, 0, 0), (0,)),
    "cylindrical": ((0, 0, 1, 0, 0, 1), (2, 5)),
    "spherical": ((0, 0, 0, 1, 1, 1), (5, 4, 3)),
    "spherical_with_pin": ((0, 0, 0, 0, 1, 1), (5, 4, 3)),
    "universal": ((0, 0, 0, 1, 0, 1), (5, 3)),
    "homokinetic": ((0, 0, 0, 1, 0, 1), (5, 3)),
    "planar": ((1, 1, 0, 0, 0, 1), (5, 0, 1)),
    "unconstrained": ((1, 1, 1, 1, 1, 1), (0, 1, 2, 5, 4, 3)),
    "fully_constrained": ((0, 0, 0, 0, 0, 0), ()),
}


def named_low_order(flags) -> "str | None":
    """The named pair kind whose freedoms are the flags ``(t_x, ..., r_z)``, or None."""
    key = tuple(int(bool(f)) for f in flags)
    for kind, (named, _components) in LOW_ORDER_NAMED.items():
        if named == key:
            return kind
    return None


def low_order_components(kind: str, layout: str = "ap242") -> tuple:
    """The component (0..5 = tx, ty, tz, rx, ry, rz of a low-order value) giving each value
    of a ``kind`` pair; a prismatic pair's slide axis is its layout's (1996: z)."""
    if kind == "prismatic":
        return (_slide_axis(layout),)
    return LOW_ORDER_NAMED[kind][1]


#: A locked value of a low order pair within this of 0 is 0: the solver's steps leave roundoff
#: (1e-19) on it through the pseudo-inverse, though its Jacobian column is zero.
_LOCKED_ROUNDOFF = 1e-12


def _low_check(q, p):
    for i, f in enumerate(FREEDOM_NAMES):
        if not p[f] and np.any(np.abs(q[i]) > _LOCKED_ROUNDOFF):
            raise ValueError(f"low order kinematic pair: {f} = FALSE locks value {i + 1} "
                             f"({LOW_ORDER.value_names[i]}), which must be 0")


def _low_named(p):
    """(the named PairType, its components) when the flags are a named pair's, else None."""
    kind = named_low_order([p[f] for f in FREEDOM_NAMES])
    if kind is None:
        return None
    t = PAIR_KINDS[kind]
    return (t.with_defaults(layout="ap242") if kind == "prismatic" else t), low_order_components(kind)


def _named_q(q, comps, shape):
    return np.stack([q[c] for c in comps], axis=-1) if comps else np.zeros(shape + (0,))


def _low_m(q, p):
    _low_check(q, p)
    named = _low_named(p)
    if named is not None:
        return named[0].motion(_named_q(q, named[1], p["_shape"]))
    t = np.stack(np.broadcast_arrays(q[0], q[1], q[2]), axis=-1)
    return transform(ypr_rotation(q[5], q[4], q[3]), t)


def _low_j(q, p, shape):
    _low_check(q, p)
    named = _low_named(p)
    if named is not None:  # the named pair's columns at its components, zero elsewhere
        J = np.zeros(shape + (6, 6))
        J[..., list(named[1])] = named[0].motion_jacobian(_named_q(q, named[1], shape))
        return J
    R = ypr_rotation(q[5], q[4], q[3])
    cols = [_twist(v=_rt(R, np.broadcast_to(e, R.shape[:-1])), shape=shape) for e in (_EX, _EY, _EZ)]
    wz, wy, wx = _ypr_body_axes(*np.broadcast_arrays(q[5], q[4]))
    cols += [_twist(w=wx, shape=shape), _twist(w=wy, shape=shape), _twist(w=wz, shape=shape)]
    return _col([c if p[f] else np.zeros(shape + (6,)) for c, f in zip(cols, FREEDOM_NAMES)], shape)


# spherical_pair_with_pin: q = (yaw, pitch, roll) of its spherical_pair_value; AP242 derives r_y, r_z
# free and r_x locked, so roll (about x) must be 0: M = Ry(pitch) Rz(yaw)

def _pin_check(q):
    if np.any(q[2] != 0.0):
        raise ValueError("spherical pair with pin: r_x = FALSE (AP242 DERIVE) locks the roll, which must be 0")


def _pin_m(q, p):
    _pin_check(q)
    return _spherical_m(q, p)


def _pin_j(q, p, shape):
    _pin_check(q)
    J = _spherical_j(q, p, shape).copy()
    J[..., 2] = 0.0
    return J


# --------------------------------------------------------------------------- the type

#: Every pair value attribute (both layouts) -> its unit kind: "A" plane angle, "L" length,
#: "P" a point parameter on a pair curve or surface. The only table that says which pair
#: values are angles; ``PairType.value_units`` reads it.
VALUE_UNITS = {
    "actual_rotation": "A", "actual_rotation_1": "A", "first_rotation_angle": "A",
    "second_rotation_angle": "A", "yaw": "A", "pitch": "A", "roll": "A",
    "actual_rotation_x": "A", "actual_rotation_y": "A", "actual_rotation_z": "A",
    "actual_translation": "L", "actual_translation_x": "L", "actual_translation_y": "L",
    "actual_translation_z": "L", "translation_x": "L", "translation_y": "L", "translation_z": "L",
    "actual_displacement": "L",
    "point_parameter": "P", "point_parameter_1": "P", "point_parameter_2": "P",
    "point_parameter_u": "P", "point_parameter_v": "P", "point_parameter_u_1": "P",
    "point_parameter_v_1": "P", "point_parameter_u_2": "P", "point_parameter_v_2": "P",
}


@dataclass(frozen=True)
class PairType:
    """One pair type: its values, parameters and motion.

    ``kind`` is the pair's short name (``"revolute"``, ...); ``value_names``
    the attributes of its ``*_pair_value`` entity in order (the columns of
    ``q``); ``param_names`` the pair attributes the motion needs;
    ``defaults`` the defaults of optional parameters.
    """

    kind: str
    value_names: tuple
    param_names: tuple
    _motion: Callable = field(repr=False)
    _jacobian: Callable = field(repr=False)
    defaults: dict = field(default_factory=dict)

    @property
    def value_count(self) -> int:
        return len(self.value_names)

    @property
    def value_units(self) -> tuple:
        """The kind of each value, in value order: ``"A"`` a plane angle, ``"L"`` a length,
        ``"P"`` a curve or surface parameter (converted like a length at I/O). The one rule
        for which pair values are angles."""
        return tuple(VALUE_UNITS[n] for n in self.value_names)

    @property
    def angle_mask(self) -> tuple:
        """Which values are plane angles (``value_units == "A"``)."""
        return tuple(u == "A" for u in self.value_units)

    def locked(self, params=None) -> tuple:
        """Which values are held at 0 (a zero Jacobian column, never moved by the solver): a
        generic low-order pair's whose flag is FALSE, a spherical pair with pin's roll."""
        if self.kind == "low_order":
            p = {**self.defaults, **dict(params or {})}
            return tuple(not p[f] for f in FREEDOM_NAMES)
        if self.kind == "spherical_with_pin":
            return (False, False, True)
        return (False,) * self.value_count

    def freedoms(self, params=None) -> int:
        """The pair's freedoms: its values less the locked ones (the graph's count)."""
        return self.value_count - sum(self.locked(params))

    def with_defaults(self, **defaults) -> "PairType":
        """The same pair type with other parameter defaults (e.g. ``layout="ap242"``)."""
        return PairType(self.kind, self.value_names, self.param_names, self._motion, self._jacobian,
                        {**self.defaults, **defaults})

    # -- argument handling
    def _args(self, q, params):
        q = _f(q)
        n = self.value_count
        if q.ndim < 1 or q.shape[-1] != n:
            raise ValueError(f"{self.kind} pair: q must have shape (..., {n}) "
                             f"({', '.join(self.value_names) or 'no values'}), got {q.shape}")
        unknown = set(params) - set(self.param_names) - set(self.defaults)
        if unknown:
            raise TypeError(f"{self.kind} pair: unknown parameter(s) {sorted(unknown)}; "
                            f"expected {list(self.param_names)}")
        p = {**self.defaults, **params}
        missing = [k for k in self.param_names if k not in p]
        if missing:
            raise TypeError(f"{self.kind} pair: missing parameter(s) {missing}")
        shape = q.shape[:-1]
        for k, v in p.items():
            if k in _NOT_BATCHED or v is None:
                continue
            vs = np.shape(v)[:-1] if k in _POINT_PARAMS else np.shape(v)
            shape = np.broadcast_shapes(shape, vs)
        qs = [np.broadcast_to(q[..., i], shape) for i in range(n)]
        p["_shape"] = shape
        return qs, p, shape

    # -- public API
    def motion(self, q, **params) -> np.ndarray:
        """``M(q)``: (..., 4, 4) placement of the second pair frame in the first."""
        qs, p, shape = self._args(q, params)
        M = self._motion(qs, p)
        return np.broadcast_to(M, shape + (4, 4)).copy() if M.shape[:-2] != shape else M

    def motion_jacobian(self, q, *, frame: str = "body", **params) -> np.ndarray:
        """(..., 6, n) twist Jacobian; column i is ``vee(M^-1 dM/dq_i)`` (body, default) or
        ``vee(dM/dq_i M^-1)`` (``frame="spatial"``). Twists ordered (v, w)."""
        qs, p, shape = self._args(q, params)
        J = self._jacobian(qs, p, shape)
        if frame == "body":
            return J
        if frame == "spatial":
            return adjoint(self.motion(q, **params)) @ J
        raise ValueError(f"frame must be 'body' or 'spatial', got {frame!r}")

    def motion_derivative(self, q, **params) -> np.ndarray:
        """``dM/dq``: (..., n, 4, 4), ``dM/dq_i = M @ hat(J_body[..., :, i])``."""
        M = self.motion(q, **params)
        J = self.motion_jacobian(q, **params)
        return M[..., None, :, :] @ hat(np.swapaxes(J, -1, -2))

    def __call__(self, q, **params) -> np.ndarray:
        return self.motion(q, **params)


#: Parameters that are not numbers to broadcast (geometry objects, the layout name).
_NOT_BATCHED = frozenset({"layout", "surface", "curve", "surface_1", "surface_2", "curve_1", "curve_2"})
#: Parameters whose last axis is a point's coordinates, not a batch axis.
_POINT_PARAMS = frozenset({"point_on_surface_2"})

REVOLUTE = PairType("revolute", ("actual_rotation",), (), _revolute_m, _revolute_j)
PRISMATIC = PairType("prismatic", ("actual_translation",), (), _prismatic_m, _prismatic_j,
                     {"layout": "1996"})
SCREW = PairType("screw", ("actual_rotation",), ("pitch",), _screw_m, _screw_j)
CYLINDRICAL = PairType("cylindrical", ("actual_translation", "actual_rotation"), (),
                       _cylindrical_m, _cylindrical_j)
SPHERICAL = PairType("spherical", ("yaw", "pitch", "roll"), (), _spherical_m, _spherical_j)
UNIVERSAL = PairType("universal", ("first_rotation_angle", "second_rotation_angle"), (),
                     _universal_m, _universal_j, {"input_skew_angle": None})
HOMOKINETIC = PairType("homokinetic", ("first_rotation_angle", "second_rotation_angle"), (),
                       _homokinetic_m, _homokinetic_j, {"input_skew_angle": None})
PLANAR = PairType("planar", ("actual_rotation", "actual_translation_x", "actual_translation_y"), (),
                  _planar_m, _planar_j)
UNCONSTRAINED = PairType("unconstrained", ("translation_x", "translation_y", "translation_z",
                                           "yaw", "pitch", "roll"), (), _unconstrained_m, _unconstrained_j)
FULLY_CONSTRAINED = PairType("fully_constrained", (), (), _fixed_m, _fixed_j)
GEAR = PairType("gear", ("actual_rotation_1",), ("radius_first_link", "radius_second_link", "gear_ratio"),
                _gear_m, _gear_j, {"bevel": 0.0, "helical_angle": 0.0})
RACK_AND_PINION = PairType("rack_and_pinion", ("actual_displacement",), ("pinion_radius",),
                           _rack_m, _rack_j)

POINT_ON_SURFACE = PairType("point_on_surface", ("point_parameter_u", "point_parameter_v", "yaw", "pitch",
                                                  "roll"), ("surface",), _pos_m, _pos_j)
SLIDING_SURFACE = PairType("sliding_surface", ("point_parameter_u_1", "point_parameter_v_1", "point_parameter_u_2",
                                                "point_parameter_v_2", "actual_rotation"),
                           ("surface_1", "surface_2", "orientation"), _ss_m, _ss_j)
ROLLING_SURFACE = PairType("rolling_surface", ("point_parameter_u", "point_parameter_v", "actual_rotation"),
                           ("surface_1", "surface_2", "orientation"), _rs_m, _rs_j, {"point_on_surface_2": None})
POINT_ON_PLANAR_CURVE = PairType("point_on_planar_curve", ("point_parameter", "yaw", "pitch", "roll"),
                                 ("curve",), _popc_m, _popc_j, {"orientation": True})
SLIDING_CURVE = PairType("sliding_curve", ("point_parameter_1", "point_parameter_2"),
                         ("curve_1", "curve_2", "orientation"), _sc_m, _sc_j)
ROLLING_CURVE = PairType("rolling_curve", ("point_parameter_1",), ("curve_1", "curve_2", "orientation"),
                         _rc_m, _rc_j, {"reference_parameter_1": 0.0, "reference_parameter_2": 0.0})
LOW_ORDER = PairType("low_order", ("actual_translation_x", "actual_translation_y", "actual_translation_z",
                                   "actual_rotation_x", "actual_rotation_y", "actual_rotation_z"), (),
                     _low_m, _low_j, {f: True for f in FREEDOM_NAMES})
SPHERICAL_WITH_PIN = PairType("spherical_with_pin", ("yaw", "pitch", "roll"), (), _pin_m, _pin_j)

#: The higher pairs (ISO 10303-105 5.1: pairs 12-17), which need curve/surface geometry.
HIGHER_KINDS = ("point_on_surface", "sliding_surface", "rolling_surface", "point_on_planar_curve",
                "sliding_curve", "rolling_curve")

#: Pair types by short name.
PAIR_KINDS = {t.kind: t for t in (REVOLUTE, PRISMATIC, SCREW, CYLINDRICAL, SPHERICAL, UNIVERSAL,
                                  HOMOKINETIC, PLANAR, UNCONSTRAINED, FULLY_CONSTRAINED, GEAR,
                                  RACK_AND_PINION, POINT_ON_SURFACE, SLIDING_SURFACE, ROLLING_SURFACE,
                                  POINT_ON_PLANAR_CURVE, SLIDING_CURVE, ROLLING_CURVE, LOW_ORDER,
                                  SPHERICAL_WITH_PIN)}

#: Pair types by Part 105 entity name, for both layouts: the 1996 text / AP214 names
#: (``*_pair``; its ranges are separate ``*_pair_range`` entities, not pairs) and
#: AP242's ``*_pair_with_range`` subtypes. ``prismatic_pair`` defaults to the 1996
#: layout (slide along z); ``prismatic_pair_with_range`` exists only in AP242 and
#: defaults to the AP242 layout (slide along x). Pass ``layout=`` to override.
PAIRS = {}
for _t in PAIR_KINDS.values():
    if _t.kind in ("low_order", "spherical_with_pin"):
        continue
    PAIRS[f"{_t.kind}_pair"] = _t
    if _t.kind not in ("homokinetic", "unconstrained", "fully_constrained", "sliding_surface",
                       "rolling_surface", "sliding_curve", "rolling_curve"):
        PAIRS[f"{_t.kind}_pair_with_range"] = _t
PAIRS["prismatic_pair_with_range"] = PRISMATIC.with_defaults(layout="ap242")
PAIRS["low_order_kinematic_pair"] = LOW_ORDER
PAIRS["low_order_kinematic_pair_with_range"] = LOW_ORDER
PAIRS["spherical_pair_with_pin"] = SPHERICAL_WITH_PIN
PAIRS["spherical_pair_with_pin_and_range"] = SPHERICAL_WITH_PIN
del _t

#: Entity names of pairs whose motion is not defined here (see the module docstring).
NOT_IMPLEMENTED = (
    "linear_flexible_and_pinion_pair", "linear_flexible_and_planar_curve_pair",
)


def pair_type(entity_name: str) -> PairType:
    """The :class:`PairType` of a Part 105 pair entity name (case-insensitive).

    Raises :class:`UnsupportedPairError` for a known pair whose motion is not
    implemented, ``KeyError`` for a name that is not a pair.
    """
    name = entity_name.lower()
    if name in PAIRS:
        return PAIRS[name]
    if name in NOT_IMPLEMENTED:
        raise UnsupportedPairError(f"{name}: the motion of this pair type is not implemented "
                                   "(flexible pairs: their flexible element's geometry is not rigid)")
    raise KeyError(f"{entity_name!r} is not a Part 105 pair entity name known to p105cli")
