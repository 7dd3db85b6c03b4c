"""Placements: independent truths for every convention of p105cli.kinematics.placements.

Sources of truth used here (none of them is the module under test):
closed forms typed in from ISO 10303-105 (note 5 of 5.4.17, the Annex E
matrix, the EXPRESS function of 5.5.9 transcribed statement by statement),
scipy.spatial.transform.Rotation, plain products of elementary matrices, and
the reference DH arms of /work/shared/reference (roboticstoolbox fkine).
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from hypothesis.extra import numpy as hnp
from scipy.spatial.transform import Rotation

from conftest import SHARED
from p105cli.kinematics import placements as P
from p105cli.kinematics import spatial as S

PI = math.pi
ATOL = 1e-12

angles = st.floats(-4 * PI, 4 * PI, allow_nan=False, allow_infinity=False)
lengths = st.floats(-10.0, 10.0, allow_nan=False, allow_infinity=False)
unit_vecs = hnp.arrays(np.float64, 3, elements=st.floats(-1.0, 1.0, allow_nan=False)).filter(
    lambda v: np.linalg.norm(v) > 1e-3)

FAST = settings(max_examples=150, deadline=None)


def Rz3(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def Ry3(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def Rx3(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def H(R=None, p=(0.0, 0.0, 0.0)):
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    T[:3, 3] = p
    return T


def rot_err(A, B):
    return float(np.max(np.abs(np.asarray(A) - np.asarray(B))))


def ang_diff(a, b):
    """Distance of angles modulo 2 pi."""
    return np.abs(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b)))))


# --------------------------------------------------------------------------- elementary transforms

def test_elementary_closed_forms_and_positive_sense():
    t = 0.7
    assert rot_err(S.rot_x(t), H(Rx3(t))) == 0.0
    assert rot_err(S.rot_y(t), H(Ry3(t))) == 0.0
    assert rot_err(S.rot_z(t), H(Rz3(t))) == 0.0
    assert rot_err(S.trans_x(2.0), H(p=(2, 0, 0))) == 0.0
    assert rot_err(S.trans_y(2.0), H(p=(0, 2, 0))) == 0.0
    assert rot_err(S.trans_z(2.0), H(p=(0, 0, 2))) == 0.0
    # 5.2.3: positive = counter-clockwise looking from the tip of the axis: x -> y about z
    assert np.allclose(S.rot_z(PI / 2)[:3, :3] @ [1, 0, 0], [0, 1, 0], atol=1e-15)
    assert np.allclose(S.rot_x(PI / 2)[:3, :3] @ [0, 1, 0], [0, 0, 1], atol=1e-15)
    assert np.allclose(S.rot_y(PI / 2)[:3, :3] @ [0, 0, 1], [1, 0, 0], atol=1e-15)
    # scipy as a second method
    for f, ax in ((S.rot_x, "x"), (S.rot_y, "y"), (S.rot_z, "z")):
        assert rot_err(f(t)[:3, :3], Rotation.from_euler(ax, t).as_matrix()) < 1e-15


def test_transform_inverse_compose():
    rng = np.random.default_rng(1)
    R = Rotation.random(50, random_state=2).as_matrix()
    p = rng.normal(size=(50, 3))
    T = S.transform(R, p)
    assert T.shape == (50, 4, 4)
    assert np.array_equal(T[:, :3, :3], R) and np.array_equal(T[:, :3, 3], p)
    assert np.array_equal(T[:, 3], np.tile([0, 0, 0, 1.0], (50, 1)))
    Ti = S.inverse(T)
    assert rot_err(Ti, np.linalg.inv(T)) < 1e-13
    assert rot_err(S.compose(T, Ti), np.broadcast_to(np.eye(4), T.shape)) < 1e-14
    assert rot_err(S.compose(T[0], T[1], T[2]), T[0] @ T[1] @ T[2]) == 0.0
    # broadcasting of leading axes
    assert S.compose(T[0], T).shape == (50, 4, 4)
    assert rot_err(S.transform(R[0]), H(R[0])) == 0.0
    with pytest.raises(ValueError):
        S.inverse(np.eye(3))
    with pytest.raises(ValueError):
        S.compose()


# --------------------------------------------------------------------------- axis2_placement_3d

def test_axis2_placement_defaults_and_part42_rules():
    assert rot_err(P.axis2_placement_3d([0, 0, 0]), np.eye(4)) == 0.0
    T = P.axis2_placement_3d([1, 2, 3], [0, 0, 5])
    assert rot_err(T, H(p=(1, 2, 3))) == 0.0
    # first_proj_axis: default ref (1,0,0) unless z is exactly +-(1,0,0), then (0,1,0)
    T = P.axis2_placement_3d([0, 0, 0], [2, 0, 0])
    assert rot_err(T[:3, :3], np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0.0]])) < 1e-15
    T = P.axis2_placement_3d([0, 0, 0], [-1, 0, 0])
    assert np.allclose(T[:3, 0], [0, 1, 0]) and np.allclose(T[:3, 2], [-1, 0, 0])
    # default ref with an axis off x: ref (1,0,0) projected onto the plane normal to axis
    T = P.axis2_placement_3d([0, 0, 0], [0, 1, 1])
    assert np.allclose(T[:3, 0], [1, 0, 0]) and np.allclose(T[:3, 2], np.array([0, 1, 1]) / math.sqrt(2))
    # explicit ref is projected, not required orthogonal
    T = P.axis2_placement_3d([0, 0, 0], [0, 0, 1], [1, 0, 7])
    assert rot_err(T, np.eye(4)) < 1e-15
    # right-handed orthonormal
    T = P.axis2_placement_3d([0, 0, 0], [1, 2, 3], [-1, 0.3, 2])
    R = T[:3, :3]
    assert rot_err(R.T @ R, np.eye(3)) < 1e-15 and abs(np.linalg.det(R) - 1) < 1e-15


def test_axis2_placement_errors():
    with pytest.raises(ValueError, match="parallel"):
        P.axis2_placement_3d([0, 0, 0], [0, 0, 1], [0, 0, -3])
    with pytest.raises(ValueError, match="parallel"):
        # relative tolerance: tiny off-axis component relative to magnitude
        P.axis2_placement_3d([0, 0, 0], [0, 0, 1e6], [1e-9, 0, 1e6])
    with pytest.raises(ValueError, match="zero"):
        P.axis2_placement_3d([0, 0, 0], [0, 0, 0])
    with pytest.raises(ValueError, match="zero"):
        P.axis2_placement_3d([0, 0, 0], None, [0, 0, 0])
    # relative tolerance: small vectors are fine if not parallel
    T = P.axis2_placement_3d([0, 0, 0], [0, 0, 1e-20], [1e-20, 0, 0])
    assert rot_err(T, np.eye(4)) < 1e-15
    # batched: the message names the offending element
    axis = np.tile([0, 0, 1.0], (3, 4, 1))
    ref = np.tile([1, 0, 0.0], (3, 4, 1))
    ref[2, 1] = [0, 0, 2]
    with pytest.raises(ValueError, match=r"index \(2, 1\)"):
        P.axis2_placement_3d(np.zeros(3), axis, ref)


@FAST
@given(unit_vecs, unit_vecs, hnp.arrays(np.float64, 3, elements=lengths))
def test_axis2_placement_gram_schmidt(axis, ref, loc):
    z = axis / np.linalg.norm(axis)
    v = ref / np.linalg.norm(ref)
    if np.linalg.norm(np.cross(z, v)) < 1e-6:
        return
    x = v - (v @ z) * z
    x /= np.linalg.norm(x)
    T = P.axis2_placement_3d(loc, axis * 3.0, ref * 0.5)
    assert rot_err(T[:3, 0], x) < 1e-9
    assert rot_err(T[:3, 2], z) < 1e-15
    assert rot_err(T[:3, 1], np.cross(z, x)) < 1e-9
    assert np.array_equal(T[:3, 3], loc)
    R = T[:3, :3]
    assert rot_err(R.T @ R, np.eye(3)) < 1e-14


# --------------------------------------------------------------------------- su_parameters (5.4.17)

def note5(a, alpha, b, beta, c, gamma):
    """Note 5 of ISO 10303-105 5.4.17, typed in from the standard."""
    sa, ca, sb, cb, sg, cg = (math.sin(alpha), math.cos(alpha), math.sin(beta), math.cos(beta),
                              math.sin(gamma), math.cos(gamma))
    location = [a * cg + b * sg * sa, a * sg - b * cg * sa, c + b * ca]
    axis = [sg * sa, -cg * sa, ca]
    ref_direction = [cg * cb - sg * ca * sb, sg * cb + cg * ca * sb, sa * sb]
    return np.array(location), np.array(axis), np.array(ref_direction)


@FAST
@given(lengths, angles, lengths, angles, lengths, angles)
def test_su_parameters_note5_and_product(a, alpha, b, beta, c, gamma):
    T = P.su_parameters(a, alpha, b, beta, c, gamma)
    loc, axis, ref = note5(a, alpha, b, beta, c, gamma)
    assert rot_err(T[:3, 3], loc) < 1e-12
    assert rot_err(T[:3, 2], axis) < 1e-14
    assert rot_err(T[:3, 0], ref) < 1e-14
    # the same placement written as an axis2_placement_3d
    assert rot_err(P.axis2_placement_3d(loc, axis, ref), T) < 1e-12
    # DESIGN.md: Tz(c) Rz(gamma) Tx(a) Rx(alpha) Tz(b) Rz(beta), with plain matrices
    prod = (H(p=(0, 0, c)) @ H(Rz3(gamma)) @ H(p=(a, 0, 0)) @ H(Rx3(alpha))
            @ H(p=(0, 0, b)) @ H(Rz3(beta)))
    assert rot_err(T, prod) < 1e-12
    assert rot_err(S.compose(S.trans_z(c), S.rot_z(gamma), S.trans_x(a), S.rot_x(alpha),
                             S.trans_z(b), S.rot_z(beta)), T) < 1e-12
    for got, want in zip(P.su_to_axis2_placement_3d(a, alpha, b, beta, c, gamma), (loc, axis, ref)):
        assert rot_err(got, want) < 1e-12


@FAST
@given(st.floats(0.0, 5.0), angles, lengths, angles, lengths, angles)
def test_su_parameters_match_the_geometric_definitions(a, alpha, b, beta, c, gamma):
    """The six definitions of 5.4.17 (figure 2), evaluated on the frames of the placement."""
    T = P.su_parameters(a, alpha, b, beta, c, gamma)
    xp, zp, op = np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), np.zeros(3)   # link frame
    xk, zk, ok = T[:3, 0], T[:3, 2], T[:3, 3]                                 # pair frame
    t = np.array([math.cos(gamma), math.sin(gamma), 0.0])   # common normal, from z' to z_k
    sp = op + c * zp                                         # s'_k: foot on z'
    sk = sp + a * t                                          # s_k: foot on z_k
    assert abs(np.linalg.norm(sk - sp) - a) < 1e-12                       # a_k = |s_k - s'_k|
    assert abs(t @ zk) < 1e-14 and abs(t @ zp) < 1e-15                    # t normal to both axes
    assert abs(np.linalg.norm(np.cross(ok - sk, zk))) < 1e-11             # s_k lies on z_k
    assert abs(np.cross(zp, zk) @ t - math.sin(alpha)) < 1e-14            # sin alpha
    assert abs(zp @ zk - math.cos(alpha)) < 1e-14                         # cos alpha
    assert abs((ok - sk) @ zk - b) < 1e-11                                # b_k
    assert abs(np.cross(t, xk) @ zk - math.sin(beta)) < 1e-14             # sin beta
    assert abs(t @ xk - math.cos(beta)) < 1e-14                           # cos beta
    assert abs((sp - op) @ zp - c) < 1e-12                                # c_k
    assert abs(np.cross(xp, t) @ zp - math.sin(gamma)) < 1e-15            # sin gamma
    assert abs(xp @ t - math.cos(gamma)) < 1e-15                          # cos gamma


def test_su_parameters_batched_equals_elementwise():
    rng = np.random.default_rng(5)
    args = [rng.normal(size=(5, 7)) for _ in range(6)]
    T = P.su_parameters(*args)
    assert T.shape == (5, 7, 4, 4)
    for i in range(5):
        for j in range(7):
            assert np.array_equal(T[i, j], P.su_parameters(*(x[i, j] for x in args)))
    # broadcasting scalars with arrays
    assert P.su_parameters(args[0], 0.1, 0.2, 0.3, 0.4, 0.5).shape == (5, 7, 4, 4)


def test_su_parameters_from_transform_round_trip():
    rng = np.random.default_rng(6)
    n = 2000
    R = Rotation.random(n, random_state=7).as_matrix()
    T = S.transform(R, rng.normal(size=(n, 3)))
    a, alpha, b, beta, c, gamma = P.su_parameters_from_transform(T)
    assert np.all(a >= 0.0)
    assert rot_err(P.su_parameters(a, alpha, b, beta, c, gamma), T) < 1e-10
    for ang in (alpha, beta, gamma):
        assert np.all((ang > -PI) & (ang <= PI))
    # canonical parameters come back unchanged
    a0 = rng.uniform(0.1, 2.0, n)
    al0 = rng.uniform(-3.0, 3.0, n)
    al0 = np.where(np.abs(np.sin(al0)) < 0.05, 1.0, al0)
    others = [rng.uniform(-3.0, 3.0, n) for _ in range(4)]
    got = P.su_parameters_from_transform(P.su_parameters(a0, al0, others[0], others[1], others[2], others[3]))
    for g, w in zip(got, (a0, al0, *others)):
        assert np.max(ang_diff(g, w) if w is not a0 else np.abs(g - w)) < 1e-10
    # parallel and coaxial axes
    for Tp in (P.su_parameters(0.5, 0.0, 0.0, 0.3, 0.2, 1.0), P.su_parameters(0.5, PI, 0.0, 0.3, 0.2, 1.0),
               S.trans_z(0.7) @ S.rot_z(0.4), S.rot_x(PI) @ S.trans_z(1.0)):
        s = P.su_parameters_from_transform(Tp)
        assert rot_err(P.su_parameters(*s), Tp) < 1e-14
        assert s[2] == 0.0 and s[1] in (0.0, PI)
    # intersecting axes: a = 0 and alpha in (0, pi)
    s = P.su_parameters_from_transform(P.su_parameters(0.0, -1.0, 0.4, 0.1, 0.2, 0.3))
    assert abs(s[0]) < 1e-15 and 0.0 < s[1] < PI


# --------------------------------------------------------------------------- DH -> SU (Annex F, DESIGN.md)

def _arms():
    data = json.loads((SHARED / "reference" / "dh_arms_and_loops.json").read_text())
    return data["arms"]


@pytest.mark.parametrize("name", ["Puma560", "UR5"])
def test_dh_standard_to_su_chain_reproduces_reference(name):
    """Annex F, revolute: link k's pair frame is su(a, alpha, -d, pi, 0, pi) =
    inverse(Tz(d) Tx(a) Rx(alpha)); link k-1's pair frame is its DH frame. The
    chain  T = base . prod_k [ I . Rz(theta_k) . inverse(su_k) ] . tool  is the
    plain DH product, checked against roboticstoolbox's fkine."""
    arm = _arms()[name]
    assert arm["convention"] == "standard"
    q = np.array([s["q"] for s in arm["samples"]])
    T_ref = np.array([s["T"] for s in arm["samples"]])
    T = np.broadcast_to(np.array(arm["base"]), T_ref.shape)
    T_naive = T
    for k, row in enumerate(arm["dh"]):
        assert row["joint"] == "revolute"
        su = P.su_parameters(row["a"], row["alpha"], -row["d"], PI, 0.0, PI)
        # su equals the inverse of the DH transform without the pair parameter
        assert rot_err(su, S.inverse(S.compose(S.trans_z(row["d"]), S.trans_x(row["a"]),
                                               S.rot_x(row["alpha"])))) < 1e-15
        pair = S.rot_z(q[:, k] + row["offset"])
        T = S.compose(T, np.eye(4), pair, S.inverse(su))
        T_naive = S.compose(T_naive, pair, su)
    T = S.compose(T, np.array(arm["tool"]))
    assert rot_err(T, T_ref) < 1e-12
    # the naive composition (SU frame multiplied after the pair rotation) must fail
    assert rot_err(S.compose(T_naive, np.array(arm["tool"])), T_ref) > 1e-2


def test_dh_modified_panda_chain():
    """Modified DH (Craig): A_j = Rx(alpha) Tx(a) Rz(theta) Tz(d): pair frame on link j-1 is
    su(a, alpha, 0, 0, 0, 0), on link j su(0, 0, -d, 0, 0, 0) (= inverse of Tz(d))."""
    arm = _arms()["Panda"]
    assert arm["convention"] == "modified"
    q = np.array([s["q"] for s in arm["samples"]])
    T_ref = np.array([s["T"] for s in arm["samples"]])
    T = np.broadcast_to(np.array(arm["base"]), T_ref.shape)
    for k, row in enumerate(arm["dh"]):
        first = P.su_parameters(row["a"], row["alpha"], 0.0, 0.0, 0.0, 0.0)
        second = P.su_parameters(0.0, 0.0, -row["d"], 0.0, 0.0, 0.0)
        T = S.compose(T, first, S.rot_z(q[:, k] + row["offset"]), S.inverse(second))
    T = S.compose(T, np.array(arm["tool"]))
    assert rot_err(T, T_ref) < 1e-12


def test_dh_prismatic_cylindrical_and_offsets_against_dh_product():
    """Annex F prismatic (b = 0, beta with Rz(pi + beta) = Rz(-theta), i.e. beta = pi - theta),
    cylindrical (b = 0, beta = pi) and a revolute offset folded into beta (pi - offset),
    each against the plain standard-DH product Rz(theta) Tz(d) Tx(a) Rx(alpha)."""
    rng = np.random.default_rng(11)
    n = 64
    rows = [("revolute", 0.3, 0.5, 0.2, 0.0, 0.4), ("prismatic", -0.2, -1.1, 0.7, 0.9, 0.0),
            ("cylindrical", 0.4, 2.0, 0.0, 0.0, 0.0), ("revolute", 0.0, -PI / 2, 0.1, 0.0, -0.8),
            ("prismatic", 0.25, 0.0, -0.3, -2.5, 0.0)]
    # joint variable per sample; DH parameters (a, alpha, d, theta, offset)
    T_dh = np.broadcast_to(np.eye(4), (n, 4, 4))
    T_su = T_dh
    for kind, a, alpha, d, theta, offset in rows:
        qv = rng.uniform(-2, 2, n)
        qd = rng.uniform(-2, 2, n)
        if kind == "revolute":
            A = S.compose(S.rot_z(qv + offset), S.trans_z(d), S.trans_x(a), S.rot_x(alpha))
            su = P.su_parameters(a, alpha, -d, PI - offset, 0.0, PI)
            pair = S.rot_z(qv)
        elif kind == "prismatic":
            A = S.compose(S.rot_z(theta), S.trans_z(qd), S.trans_x(a), S.rot_x(alpha))
            su = P.su_parameters(a, alpha, 0.0, PI - theta, 0.0, PI)
            assert rot_err(S.rot_z(PI + (PI - theta)), S.rot_z(-theta)) < 1e-15
            pair = S.trans_z(qd)
        else:
            A = S.compose(S.rot_z(qv), S.trans_z(qd), S.trans_x(a), S.rot_x(alpha))
            su = P.su_parameters(a, alpha, 0.0, PI, 0.0, PI)
            pair = S.compose(S.trans_z(qd), S.rot_z(qv))
        T_dh = S.compose(T_dh, A)
        T_su = S.compose(T_su, pair, S.inverse(su))
    assert rot_err(T_su, T_dh) < 1e-13


# --------------------------------------------------------------------------- ypr_rotation (5.3.7, Annex E)

def annex_e(y, p, r, factor=1.0):
    """compute_rotation_matrix_from_ypr_rotation of Annex E.2, typed in from the standard."""
    y, p, r = factor * y, factor * p, factor * r
    cos, sin = math.cos, math.sin
    return np.array([
        [cos(y) * cos(p), -sin(y) * cos(p), sin(p)],
        [sin(y) * cos(r) + cos(y) * sin(p) * sin(r), cos(y) * cos(r) - sin(y) * sin(p) * sin(r), -cos(p) * sin(r)],
        [sin(y) * sin(r) - cos(y) * sin(p) * cos(r), cos(y) * sin(r) + sin(y) * sin(p) * cos(r), cos(p) * cos(r)]])


@FAST
@given(angles, st.floats(-PI / 2, PI / 2), angles)
def test_ypr_rotation_is_annex_e_and_rx_ry_rz(y, p, r):
    R = P.ypr_rotation(y, p, r)
    assert rot_err(R, annex_e(y, p, r)) < 1e-15
    assert rot_err(R, Rx3(r) @ Ry3(p) @ Rz3(y)) < 1e-14
    assert rot_err(R, Rotation.from_euler("zyx", [y, p, r]).as_matrix()) < 1e-14   # extrinsic z, y, x
    assert rot_err(R, Rotation.from_euler("XYZ", [r, p, y]).as_matrix()) < 1e-14   # intrinsic Cardan
    assert rot_err(P.ypr_rotation(y / P.DEGREE, p / P.DEGREE, r / P.DEGREE, P.DEGREE), R) < 1e-13
    assert rot_err(annex_e(y / P.DEGREE, p / P.DEGREE, r / P.DEGREE, P.DEGREE), R) < 1e-13


@FAST
@given(st.floats(-PI, PI).filter(lambda v: v > -PI), st.floats(-PI / 2, PI / 2),
       st.floats(-PI, PI).filter(lambda v: v > -PI))
def test_ypr_from_matrix_round_trip(y, p, r):
    R = P.ypr_rotation(y, p, r)
    y2, p2, r2 = P.ypr_from_matrix(R)
    assert rot_err(P.ypr_rotation(y2, p2, r2), R) < 1e-14
    assert -PI / 2 <= p2 <= PI / 2 and -PI < y2 <= PI and -PI < r2 <= PI
    if math.cos(p) > 1e-6:
        assert abs(p2 - p) < 1e-12 and ang_diff(y2, y) < 1e-9 and ang_diff(r2, r) < 1e-9


HALF_PI = 0.5 * math.pi
YPR_REL_TOL = 1e-6   # the validator's band around +-pi/2 (part105.catalogue.YPR_REL_TOL)


@pytest.mark.parametrize("pitch", [HALF_PI, -HALF_PI, HALF_PI - 1e-9, HALF_PI + 1e-7, -HALF_PI + 1e-7],
                         ids=["+pi/2", "-pi/2", "pi/2-1e-9", "pi/2+1e-7", "-pi/2+1e-7"])
@pytest.mark.parametrize("yaw, roll", [(0.3, 0.2), (-2.9, 3.0), (3.1, -0.4)])
def test_canonical_ypr_at_the_gimbal_lock(pitch, yaw, roll):
    # D15: at a rectangular pitch 5.3.7 wants roll 0; the yaw carries the rotation about the locked axis
    y, p, r = P.canonical_ypr(yaw, pitch, roll, YPR_REL_TOL)
    assert r == 0.0 and abs(p) == HALF_PI and -math.pi < y <= math.pi
    want = Rotation.from_euler("zyx", [yaw, pitch, roll]).as_matrix()   # scipy: Rx(roll) Ry(pitch) Rz(yaw)
    got = Rotation.from_euler("zyx", [y, p, r]).as_matrix()
    assert np.allclose(P.ypr_rotation(y, p, r), got, atol=1e-15, rtol=0)
    # exactly at the lock the same rotation; near it (within the validator's band) the nearest
    # rotation with roll 0: moved by no more than the pitch's distance from +-pi/2 (times 2)
    moved = abs(abs(pitch) - HALF_PI)
    assert np.abs(got - want).max() <= (1e-12 if moved == 0.0 else 2.0 * moved + 1e-12)
    if moved == 0.0:
        sign = 1.0 if pitch > 0 else -1.0
        assert math.remainder(y - (yaw + sign * roll), 2 * math.pi) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("ypr", [(0.3, 0.5, 0.2), (math.pi, -1.2, -0.7), (0.1, HALF_PI - 1e-3, 2.0),
                                 (0.4, HALF_PI - 1e-9, 0.0)])
def test_canonical_ypr_leaves_a_canonical_triple_alone(ypr):
    assert P.canonical_ypr(*ypr, YPR_REL_TOL) == ypr


@pytest.mark.parametrize("ypr", [(4.0, 0.5, 0.2), (0.3, 2.0, -0.1), (-math.pi, 0.2, 7.0)])
def test_canonical_ypr_brings_angles_into_their_intervals(ypr):
    y, p, r = P.canonical_ypr(*ypr, YPR_REL_TOL)
    assert -math.pi < y <= math.pi and -HALF_PI <= p <= HALF_PI and -math.pi < r <= math.pi
    assert rot_err(P.ypr_rotation(y, p, r), P.ypr_rotation(*ypr)) < 1e-14


def test_ypr_rotation_in_frames_of_5_3_6():
    """5.3.6: yaw about z, then pitch and roll; check the intermediate axes the matrix uses."""
    y, p, r = 0.4, -0.3, 1.1
    R = P.ypr_rotation(y, p, r)
    # yaw alone turns about z, pitch alone about y, roll alone about x
    assert rot_err(P.ypr_rotation(y, 0, 0), Rz3(y)) < 1e-16
    assert rot_err(P.ypr_rotation(0, p, 0), Ry3(p)) < 1e-16
    assert rot_err(P.ypr_rotation(0, 0, r), Rx3(r)) < 1e-16
    # Annex E "rightmost first": applied to a vector, yaw acts first, then pitch, then roll,
    # all about the axes of the non-rotated frame
    v = np.array([0.3, -0.2, 0.9])
    assert rot_err(R @ v, Rx3(r) @ (Ry3(p) @ (Rz3(y) @ v))) < 1e-15


# --------------------------------------------------------------------------- 5.5.9

def _express_atan(v1, v2):
    """EXPRESS ATAN(V1, V2): angle whose tangent is V1/V2, in [-pi/2, pi/2]."""
    if v2 == 0.0:
        return math.copysign(PI / 2, v1) if v1 != 0.0 else 0.0
    return math.atan(v1 / v2)


def express_convert_spatial_to_ypr(direction, angle, factor=1.0):
    """convert_spatial_to_ypr_rotation of 5.5.9, transcribed statement by statement
    (conv_angle = plane_angle_for_pair_in_radian(pair, angle) = angle * factor)."""
    n = math.sqrt(sum(v * v for v in direction))
    dx, dy, dz = (v / n for v in direction)
    if angle == 0.0:
        return (0.0, 0.0, 0.0)
    conv_angle = angle * factor
    ucf = angle / conv_angle
    s_a, c_a = math.sin(conv_angle), math.cos(conv_angle)
    if dy == 0.0 and dx * dz == 0.0:
        while conv_angle <= -PI:
            conv_angle += 2.0 * PI
        while conv_angle > PI:
            conv_angle -= 2.0 * PI
        ya = ucf * conv_angle
        ra = -ya if conv_angle != PI else ya
        if dx != 0.0:
            return (0.0, 0.0, ya) if dx > 0.0 else (0.0, 0.0, ra)
        return (ya, 0.0, 0.0) if dz > 0.0 else (ra, 0.0, 0.0)
    if dy != 0.0 and dx == 0.0 and dz == 0.0:
        if c_a >= 0.0:
            ya = ra = 0.0
        else:
            ya = ra = ucf * PI
        pa = ucf * _express_atan(s_a, abs(c_a))
        if dy < 0.0:
            pa = -pa
        return (ya, pa, ra)
    cm1 = 1.0 - c_a
    rotmat = [[dx * dx * cm1 + c_a, dx * dy * cm1 - dz * s_a, dx * dz * cm1 + dy * s_a],
              [dx * dy * cm1 + dz * s_a, dy * dy * cm1 + c_a, dy * dz * cm1 - dx * s_a],
              [dx * dz * cm1 - dy * s_a, dy * dz * cm1 + dx * s_a, dz * dz * cm1 + c_a]]
    m = lambda i, j: rotmat[i - 1][j - 1]  # noqa: E731  (1-based as in EXPRESS)
    if abs(m(1, 3)) == 1.0:
        pa = 0.5 * PI if m(1, 3) == 1.0 else -0.5 * PI
        ra = 0.0
        ya = _express_atan(m(2, 1), m(2, 2))
        if m(2, 2) < 0.0:
            ya = ya + PI if ya <= 0.0 else ya - PI
    else:
        ya = _express_atan(-m(1, 2), m(1, 1))
        if m(1, 1) < 0.0:
            ya = ya + PI if ya <= 0.0 else ya - PI
        ra = _express_atan(-m(2, 3), m(3, 3))
        if m(3, 3) < 0.0:
            ra = ra + PI if ra <= 0.0 else ra - PI
        s_y, c_y, s_r, c_r = math.sin(ya), math.cos(ya), math.sin(ra), math.cos(ra)
        if abs(s_y) > abs(c_y) and abs(s_y) > abs(s_r) and abs(s_y) > abs(c_r):
            cm1 = -m(1, 2) / s_y
        elif abs(c_y) > abs(s_r) and abs(c_y) > abs(c_r):
            cm1 = m(1, 1) / c_y
        elif abs(s_r) > abs(c_r):
            cm1 = -m(2, 3) / s_r
        else:
            cm1 = m(3, 3) / c_r
        pa = _express_atan(m(1, 3), cm1)
    return (ya * ucf, pa * ucf, ra * ucf)


def test_convert_spatial_matches_the_express_function():
    rng = np.random.default_rng(3)
    n = 3000
    d = rng.normal(size=(n, 3))
    a = rng.uniform(-3 * PI, 3 * PI, n)
    got = np.stack(P.convert_spatial_to_ypr_rotation(d, a), axis=-1)
    want = np.array([express_convert_spatial_to_ypr(d[i], a[i]) for i in range(n)])
    # away from the lock the standard's extraction is well conditioned
    ok = np.cos(want[:, 1]) > 1e-6
    assert ok.sum() > n * 0.99
    assert np.max(np.abs(got[ok] - want[ok])) < 1e-9
    # special branches, including -x, -z, half turns, degrees
    cases = [([1, 0, 0], 0.3), ([-2, 0, 0], 0.3), ([0, 0, 1], -5.0), ([0, 0, -1], PI), ([-1, 0, 0], -PI),
             ([0, 0, 3], 7 * PI), ([0, 1, 0], 2.5), ([0, -1, 0], 2.5), ([0, -1, 0], 0.5), ([0, 1, 0], -2.0),
             ([1, 1, 1], 0.0), ([0, 0, -1], 90.0), ([0, 1, 0], 135.0), ([1, 2, 3], 200.0)]
    for direction, angle in cases:
        f = P.DEGREE if abs(angle) > 10 else 1.0
        got = P.convert_spatial_to_ypr_rotation(direction, angle, f)
        want = express_convert_spatial_to_ypr(direction, angle, f)
        assert np.allclose(got, want, atol=1e-12, rtol=1e-12), (direction, angle, got, want)
        assert rot_err(P.ypr_rotation(*got, f), P.rotation_about_direction(direction, angle, f)) < 1e-14


def test_near_lock_better_than_the_literal_express_function():
    """The literal 5.5.9 algorithm reads yaw and roll from entries of size cos(pitch) and loses
    accuracy near the lock; ours reads the roll after removing the yaw and stays exact."""
    rng = np.random.default_rng(21)
    y, r = rng.uniform(-3, 3, 300), rng.uniform(-3, 3, 300)
    R = P.ypr_rotation(y, PI / 2 - 1e-9, r)
    rv = Rotation.from_matrix(R).as_rotvec()
    nrm = np.linalg.norm(rv, axis=1)
    k = rv / nrm[:, None]
    Rd = P.rotation_about_direction(k, nrm)
    lit = np.array([annex_e(*express_convert_spatial_to_ypr(k[i], nrm[i])) for i in range(len(nrm))])
    ours = P.ypr_rotation(*P.convert_spatial_to_ypr_rotation(k, nrm))
    assert rot_err(lit, Rd) > 1e-9
    assert rot_err(ours, Rd) < 2e-15


@settings(max_examples=300, deadline=None)
@given(unit_vecs, st.floats(-20.0, 20.0, allow_nan=False))
def test_convert_spatial_reproduces_rotation_about_direction(direction, angle):
    y, p, r = P.convert_spatial_to_ypr_rotation(direction * 7.0, angle)
    assert rot_err(P.ypr_rotation(y, p, r), P.rotation_about_direction(direction, angle)) < 1e-14
    assert -PI / 2 <= p <= PI / 2 and -PI < y <= PI and -PI < r <= PI
    if abs(p) == PI / 2:
        assert r == 0.0


def test_rotation_about_direction_rodrigues():
    rng = np.random.default_rng(4)
    d = rng.normal(size=(500, 3))
    a = rng.uniform(-10, 10, 500)
    R = P.rotation_about_direction(d, a)
    k = d / np.linalg.norm(d, axis=1, keepdims=True)
    assert rot_err(R, Rotation.from_rotvec(k * a[:, None]).as_matrix()) < 1e-14
    # 5.4.1: positive angle counter-clockwise seen from the tip of the axis
    assert np.allclose(P.rotation_about_direction([0, 0, 2], PI / 2) @ [1, 0, 0], [0, 1, 0], atol=1e-16)
    # scaling the direction changes nothing; degrees through unit_factor
    assert rot_err(P.rotation_about_direction(d * 1e-30, a), R) < 1e-15
    assert rot_err(P.rotation_about_direction(d, a / P.DEGREE, P.DEGREE), R) < 1e-13
    with pytest.raises(ValueError, match="zero"):
        P.rotation_about_direction([0, 0, 0], 1.0)


def test_gimbal_lock_cases():
    """|pitch| = pi/2: roll = 0 (rectangular pitch angle, 5.3.7), yaw carries the rest."""
    # 120 degrees about (1,1,1): x -> y, y -> z, z -> x; R[0,2] = 1
    y, p, r = P.convert_spatial_to_ypr_rotation([1, 1, 1], 120.0, P.DEGREE)
    assert (p, r) == (90.0, 0.0) and abs(y - 90.0) < 1e-12
    # -120 degrees about (1,1,1)... and a pure pitch of +-90 about y
    for direction, angle in (([1, 1, 1], -2 * PI / 3), ([0, 1, 0], PI / 2), ([0, -1, 0], PI / 2),
                             ([-1, 1, 1], 2 * PI / 3), ([1, -1, 1], 4 * PI / 3)):
        R = P.rotation_about_direction(direction, angle)
        y, p, r = P.convert_spatial_to_ypr_rotation(direction, angle)
        assert rot_err(P.ypr_rotation(y, p, r), R) < 1e-15
        if abs(abs(R[0, 2]) - 1.0) < 1e-15:
            assert abs(p) == PI / 2 and r == 0.0
    # every rotation at the lock: Ry(+-pi/2) Rz(psi) -> (psi, +-pi/2, 0)
    psi = np.linspace(-PI, PI, 41)[1:]
    for s in (1.0, -1.0):
        R = P.ypr_rotation(psi, s * PI / 2, 0.0)
        rv = Rotation.from_matrix(R).as_rotvec()
        nrm = np.linalg.norm(rv, axis=1)
        y, p, r = P.convert_spatial_to_ypr_rotation(rv / nrm[:, None], nrm)
        # (psi = 0 is a pure turn about y: the y-axis branch of 5.5.9 returns the pitch of the
        # given angle, which may differ from pi/2 by rounding; roll is 0 there as well)
        assert np.max(np.abs(p - s * PI / 2)) < 1e-15 and np.all(r == 0.0)
        assert np.sum(p == s * PI / 2) >= len(psi) - 1
        assert np.max(ang_diff(y, psi)) < 1e-12
        assert rot_err(P.ypr_rotation(y, p, r), R) < 1e-14
        # a lock reached with roll != 0 folds the roll into the yaw
        R2 = P.ypr_rotation(psi, s * PI / 2, 0.3)
        y2, p2, r2 = P.ypr_from_matrix(R2)
        assert np.all(r2 == 0.0) and np.all(p2 == s * PI / 2)
        assert rot_err(P.ypr_rotation(y2, p2, r2), R2) < 1e-14


@pytest.mark.parametrize("delta", [1e-3, 1e-6, 1e-9, 1e-11, 1e-13, 1e-15, 1e-17, 0.0])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_near_lock_stability(delta, sign):
    rng = np.random.default_rng(int(1e6 * delta) + 7)
    y = rng.uniform(-PI, PI, 200)
    r = rng.uniform(-PI, PI, 200)
    p = sign * (PI / 2 - delta)
    R = P.ypr_rotation(y, p, r)
    y2, p2, r2 = P.ypr_from_matrix(R)
    err = rot_err(P.ypr_rotation(y2, p2, r2), R)
    # generic branch: exact to rounding; lock branch: within the snap tolerance
    assert err < (2e-15 if delta > 1e-12 else 2e-12 + 2e-15)
    assert np.all(np.abs(p2) <= PI / 2)
    assert np.max(np.abs(p2 - p)) < max(4 * delta, 1e-12) + 1e-15
    # the same through the axis-angle form of 5.5.9
    rv = Rotation.from_matrix(R).as_rotvec()
    nrm = np.linalg.norm(rv, axis=1)
    Rd = P.rotation_about_direction(rv / nrm[:, None], nrm)
    yc, pc, rc = P.convert_spatial_to_ypr_rotation(rv / nrm[:, None], nrm)
    assert rot_err(P.ypr_rotation(yc, pc, rc), Rd) < (1e-14 if delta > 1e-12 else 2e-12 + 1e-14)
    lock = np.abs(pc) == PI / 2
    assert np.all(rc[lock] == 0.0)


def test_convert_batched_equals_elementwise():
    rng = np.random.default_rng(8)
    d = rng.normal(size=(5, 7, 3))
    d[0, 0] = [0, 0, -1]
    d[1, 2] = [0, 2, 0]
    d[2, 3] = [1, 1, 1]
    a = rng.uniform(-4, 4, (5, 7))
    a[2, 3] = 2 * PI / 3
    a[4, 6] = 0.0
    out = P.convert_spatial_to_ypr_rotation(d, a)
    assert all(o.shape == (5, 7) for o in out)
    Rb = P.rotation_about_direction(d, a)
    for i in range(5):
        for j in range(7):
            single = P.convert_spatial_to_ypr_rotation(d[i, j], a[i, j])
            assert tuple(float(o[i, j]) for o in out) == tuple(float(s) for s in single)
            assert np.array_equal(Rb[i, j], P.rotation_about_direction(d[i, j], a[i, j]))
    # a direction shared by a batch of angles
    y, p, r = P.convert_spatial_to_ypr_rotation([0.2, 0.5, -1.0], a)
    assert y.shape == (5, 7)


def test_plane_angle_units():
    assert P.plane_angle_to_radian(180.0, P.DEGREE) == PI
    assert P.plane_angle_to_radian(2.0) == 2.0
    assert P.radian_to_plane_angle(PI, P.DEGREE) == 180.0
    v = np.array([[10.0, 20.0], [30.0, 40.0]])
    assert np.allclose(P.plane_angle_to_radian(v, 1e-3), v * 1e-3)   # milliradian
    with pytest.raises(ValueError):
        P.plane_angle_to_radian(1.0, 0.0)
    with pytest.raises(ValueError):
        P.radian_to_plane_angle(1.0, -1.0)


# --------------------------------------------------------------------------- quaternions

def test_quaternion_against_scipy_and_sign_convention():
    R = Rotation.random(3000, random_state=9)
    M = R.as_matrix()
    q = S.matrix_to_quaternion(M, order="xyzw")
    assert rot_err(q, R.as_quat(canonical=True)) < 1e-14
    q_wxyz = S.matrix_to_quaternion(M)
    assert np.array_equal(q_wxyz, q[:, [3, 0, 1, 2]])
    assert np.all(q_wxyz[:, 0] >= 0.0)
    assert np.max(np.abs(np.linalg.norm(q, axis=1) - 1)) < 1e-15
    assert rot_err(S.quaternion_to_matrix(q, order="xyzw"), M) < 1e-14
    assert rot_err(S.quaternion_to_matrix(-q_wxyz), M) < 1e-14
    assert rot_err(S.quaternion_to_matrix(q_wxyz * 3.0), M) < 1e-14
    # 4x4 input
    assert rot_err(S.matrix_to_quaternion(S.transform(M, np.ones(3))), q_wxyz) == 0.0


def test_quaternion_half_turns_and_pivots():
    # every Shepperd pivot and the w == 0 sign rule
    cases = {
        "identity": (np.eye(3), [1, 0, 0, 0]),
        "x half turn": (Rx3(PI), [0, 1, 0, 0]),
        "y half turn": (Ry3(PI), [0, 0, 1, 0]),
        "z half turn": (Rz3(PI), [0, 0, 0, 1]),
        "x half turn, exact": (np.diag([1.0, -1.0, -1.0]), [0, 1, 0, 0]),
        "y half turn, exact": (np.diag([-1.0, 1.0, -1.0]), [0, 0, 1, 0]),
        "z half turn, exact": (np.diag([-1.0, -1.0, 1.0]), [0, 0, 0, 1]),
        # sin(pi) = 1.2e-16 makes w a tiny positive number: the sign follows w, not x
        "-x half turn": (P.rotation_about_direction([-1, 0, 0], PI), [0, -1, 0, 0]),
        "(0,-1,1) half turn, exact": (np.array([[-1.0, 0, 0], [0, 0, -1], [0, -1, 0]]),
                                      [0, 0, 1 / math.sqrt(2), -1 / math.sqrt(2)]),
    }
    for name, (M, want) in cases.items():
        q = S.matrix_to_quaternion(M)
        assert rot_err(q, want) < 1e-15, name
        assert rot_err(S.quaternion_to_matrix(q), M) < 1e-15, name
    # exact zeros: the first non-zero component is made positive
    q = S.matrix_to_quaternion(np.diag([-1.0, 1.0, -1.0]))
    assert np.array_equal(q, [0.0, 0.0, 1.0, 0.0]) and not np.signbit(q).any()
    with pytest.raises(ValueError):
        S.quaternion_to_matrix([0, 0, 0, 0])
    with pytest.raises(ValueError):
        S.matrix_to_quaternion(np.eye(3), order="xyz")


@FAST
@given(unit_vecs, st.floats(-PI, PI))
def test_quaternion_closed_form(axis, angle):
    k = axis / np.linalg.norm(axis)
    want = np.r_[math.cos(angle / 2), math.sin(angle / 2) * k]
    want = want if want[0] >= 0 else -want
    got = S.matrix_to_quaternion(P.rotation_about_direction(k, angle))
    if abs(want[0]) > 1e-8:
        assert rot_err(got, want) < 1e-13


# --------------------------------------------------------------------------- Euler / Cardan

@pytest.mark.parametrize("seq", ["ZXZ", "ZYZ", "XYZ"])
def test_euler_against_scipy(seq):
    R = Rotation.random(3000, random_state=10)
    M = R.as_matrix()
    e = P.matrix_to_euler(M, seq)
    assert np.max(ang_diff(e, R.as_euler(seq))) < 1e-12
    assert rot_err(P.euler_to_matrix(e, seq), M) < 1e-14
    assert rot_err(P.euler_to_matrix(R.as_euler(seq), seq), M) < 1e-14
    # construction against scipy (intrinsic, body-fixed)
    ang = np.random.default_rng(12).uniform(-4, 4, (200, 3))
    assert rot_err(P.euler_to_matrix(ang, seq), Rotation.from_euler(seq, ang).as_matrix()) < 1e-14
    # and against the plain product
    f = {"X": Rx3, "Y": Ry3, "Z": Rz3}
    a0 = ang[0]
    assert rot_err(P.euler_to_matrix(a0, seq), f[seq[0]](a0[0]) @ f[seq[1]](a0[1]) @ f[seq[2]](a0[2])) < 1e-15
    # ranges
    assert np.all((e[:, 0] > -PI) & (e[:, 0] <= PI) & (e[:, 2] > -PI) & (e[:, 2] <= PI))
    if seq == "XYZ":
        assert np.all(np.abs(e[:, 1]) <= PI / 2)
    else:
        assert np.all((e[:, 1] >= 0) & (e[:, 1] <= PI))


@pytest.mark.parametrize("seq,mids", [("ZXZ", (0.0, PI)), ("ZYZ", (0.0, PI)), ("XYZ", (PI / 2, -PI / 2))])
def test_euler_singular_cases(seq, mids):
    """At the singularity the third angle is 0 and the first carries the rotation (as scipy)."""
    first = np.linspace(-3.0, 3.0, 13)
    third = np.linspace(2.5, -2.0, 13)
    for mid in mids:
        ang = np.stack([first, np.full(13, mid), third], axis=-1)
        M = P.euler_to_matrix(ang, seq)
        e = P.matrix_to_euler(M, seq)
        assert np.all(e[:, 2] == 0.0) and np.all(e[:, 1] == mid)
        assert rot_err(P.euler_to_matrix(e, seq), M) < 1e-14
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            sc = Rotation.from_matrix(M).as_euler(seq)
        assert rot_err(P.euler_to_matrix(sc, seq), M) < 1e-12
        assert np.max(ang_diff(e, sc)) < 1e-9


@pytest.mark.parametrize("seq", ["ZXZ", "ZYZ", "XYZ"])
@pytest.mark.parametrize("delta", [1e-4, 1e-8, 1e-10, 1e-13, 1e-16])
def test_euler_near_singularity_consistent(seq, delta):
    rng = np.random.default_rng(13)
    n = 100
    mids = {"ZXZ": (delta, PI - delta), "ZYZ": (delta, PI - delta), "XYZ": (PI / 2 - delta, -PI / 2 + delta)}[seq]
    for mid in mids:
        ang = np.stack([rng.uniform(-3, 3, n), np.full(n, mid), rng.uniform(-3, 3, n)], axis=-1)
        M = P.euler_to_matrix(ang, seq)
        e = P.matrix_to_euler(M, seq)
        assert rot_err(P.euler_to_matrix(e, seq), M) < (2e-15 if delta > 1e-12 else 2e-12)
        assert np.max(np.abs(e[:, 1] - mid)) < max(2 * delta, 1e-12)
    with pytest.raises(ValueError):
        P.matrix_to_euler(np.eye(3), "XZX")


@pytest.mark.parametrize("seq", ["ZXZ", "ZYZ", "XYZ"])
def test_euler_continuous_across_the_lock_tolerance(seq):
    """Just inside and just outside the snap tolerance the defined combination of the first and
    third angles (their sum, or difference) is the same, and the middle angle moves by <= tol."""
    tol = P.ANGLE_LOCK_TOL
    base = {"ZXZ": 0.0, "ZYZ": 0.0, "XYZ": PI / 2}[seq]
    combo = []
    for eps in (0.5 * tol, 2.0 * tol, 10.0 * tol):
        mid = base - eps if seq == "XYZ" else base + eps
        M = P.euler_to_matrix([0.9, mid, -0.4], seq)
        e = P.matrix_to_euler(M, seq)
        assert abs(e[1] - mid) <= 1.01 * eps
        # Rz(a) Rk(0) Rz(c) = Rz(a + c); Rx(a) Ry(pi/2) Rz(c) = Ry(pi/2) Rz(a + c)
        combo.append(e[0] + e[2])
    assert np.max(ang_diff(np.array(combo), combo[0])) < 1e-10
    assert ang_diff(combo[0], 0.5) < 1e-10


def test_conversions_batched_shapes():
    rng = np.random.default_rng(14)
    M = Rotation.random(35, random_state=15).as_matrix().reshape(5, 7, 3, 3)
    T = S.transform(M, rng.normal(size=(5, 7, 3)))
    assert T.shape == (5, 7, 4, 4)
    q = S.matrix_to_quaternion(T)
    e = P.matrix_to_euler(T, "ZYZ")
    ypr = P.ypr_from_matrix(T)
    Ti = S.inverse(T)
    s = P.su_parameters_from_transform(T)
    A = P.axis2_placement_3d(T[..., :3, 3], T[..., :3, 2], T[..., :3, 0])
    assert q.shape == (5, 7, 4) and e.shape == (5, 7, 3) and Ti.shape == (5, 7, 4, 4)
    assert all(v.shape == (5, 7) for v in ypr) and all(v.shape == (5, 7) for v in s)
    for i in range(5):
        for j in range(7):
            assert np.array_equal(q[i, j], S.matrix_to_quaternion(T[i, j]))
            assert np.array_equal(e[i, j], P.matrix_to_euler(T[i, j], "ZYZ"))
            assert np.array_equal(Ti[i, j], S.inverse(T[i, j]))
            assert np.array_equal(A[i, j], P.axis2_placement_3d(T[i, j, :3, 3], T[i, j, :3, 2], T[i, j, :3, 0]))
            assert tuple(float(v[i, j]) for v in ypr) == tuple(float(v) for v in P.ypr_from_matrix(T[i, j]))
            assert tuple(float(v[i, j]) for v in s) == tuple(float(v) for v in P.su_parameters_from_transform(T[i, j]))
    assert rot_err(A, T) < 1e-14
    assert rot_err(S.quaternion_to_matrix(q), M) < 1e-14
    assert rot_err(P.euler_to_matrix(e, "ZYZ"), M) < 1e-14
    assert rot_err(P.ypr_rotation(*ypr), M) < 1e-14


def test_science_module_has_no_cli_imports():
    import p105cli.kinematics.placements as mod
    src = open(mod.__file__, encoding="utf-8").read()
    assert "import click" not in src and "from click" not in src and "rich" not in src
