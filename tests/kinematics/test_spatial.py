"""The rotation algebra of p105cli.kinematics.spatial against scipy.spatial.transform.Rotation
(an independent implementation) and against closed forms, including the edge cases of every
rotation-vector and quaternion route: angles near 0 and near pi, exactly pi, the identity."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.spatial.transform import Rotation, Slerp

from p105cli.kinematics import spatial as S

RNG = np.random.default_rng(105)


def _axes(n):
    v = RNG.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1)[:, None]


def _edge_rotvecs():
    """Rotation vectors at the hard places: tiny angles, angles just below pi, exactly pi about
    coordinate and skew axes, and ordinary ones."""
    ax = _axes(12)
    angles = np.r_[0.0, 1e-17, 1e-12, 1e-8, 1e-5, 1e-4 * (1 + 1e-9), 0.3, 2.0, math.pi - 1e-3,
                   math.pi - 1e-7, math.pi - 1e-12, math.pi]
    vecs = ax * angles[:, None]
    half_turns = np.array([[math.pi, 0, 0], [0, math.pi, 0], [0, 0, math.pi],
                           np.array([1.0, 1.0, 0.0]) / math.sqrt(2) * math.pi])
    return np.vstack([vecs, half_turns, _axes(200) * RNG.uniform(0, math.pi, (200, 1))])


def _rot_err(R1, R2):
    return float(np.abs(np.asarray(R1) - np.asarray(R2)).max())


def _same_rotvec(a, b, tol):
    """Equal rotation vectors, except that at exactly pi +phi and -phi are the same rotation."""
    a, b = np.atleast_2d(a), np.atleast_2d(b)
    d = np.linalg.norm(a - b, axis=1)
    flipped = np.linalg.norm(a + b, axis=1)
    at_pi = np.abs(np.linalg.norm(b, axis=1) - math.pi) < 1e-9
    return np.all((d < tol) | (at_pi & (flipped < tol)))


def test_rotation_vector_against_scipy_at_the_edges():
    phi = _edge_rotvecs()
    R = Rotation.from_rotvec(phi).as_matrix()
    mine = S.rotation_vector(R)
    ref = Rotation.from_matrix(R).as_rotvec()
    assert _same_rotvec(mine, ref, 2e-15 * 8)
    # near 0 the relative error matters: 1e-12 rad must come back as 1e-12, not 0 or 1.1e-12
    tiny = S.rotation_vector(Rotation.from_rotvec([[1e-12, 0, 0], [0, 3e-9, 0]]).as_matrix())
    np.testing.assert_allclose(tiny, [[1e-12, 0, 0], [0, 3e-9, 0]], rtol=1e-6)
    assert np.all(np.linalg.norm(mine, axis=1) <= math.pi + 1e-15)
    # (..., 4, 4) transforms and leading axes
    T = np.tile(np.eye(4), (len(R), 1, 1))
    T[:, :3, :3] = R
    np.testing.assert_array_equal(S.rotation_vector(T.reshape(-1, 2, 4, 4)), mine.reshape(-1, 2, 3))


def test_rotation_matrix_is_the_exponential():
    phi = _edge_rotvecs()
    ref = Rotation.from_rotvec(phi).as_matrix()
    assert _rot_err(S.rotation_matrix(phi), ref) < 1e-15 * 4
    for p in phi[::17]:
        assert _rot_err(S.rotation_matrix(p), expm(S.hat3(p))) < 1e-14
    assert _same_rotvec(S.rotation_vector(S.rotation_matrix(phi)), phi, 1e-13)


def test_left_jacobian_and_its_inverse():
    """w = Jl(phi) dphi: the spatial angular velocity of exp(phi + t dphi), by central
    differences; Jl^-1 is its inverse (phi below pi, where Jl is regular)."""
    phi = np.vstack([_axes(20) * RNG.uniform(0, 3.0, (20, 1)), [[1e-9, 0, 0], [0, 2e-5, 1e-5]]])
    h = 1e-6
    for p in phi:
        for dphi in np.eye(3):
            Rp, Rm = S.rotation_matrix(p + h * dphi), S.rotation_matrix(p - h * dphi)
            w = S.vee3((Rp - Rm) / (2 * h) @ S.rotation_matrix(p).T)
            np.testing.assert_allclose(S.left_jacobian(p) @ dphi, w, atol=1e-8)
    Jl, Jli = S.left_jacobian(phi), S.left_jacobian_inverse(phi)
    np.testing.assert_allclose(Jl @ Jli, np.broadcast_to(np.eye(3), Jl.shape), atol=1e-12)


def test_quaternions_against_scipy():
    phi = _edge_rotvecs()
    R = Rotation.from_rotvec(phi)
    q = S.matrix_to_quaternion(R.as_matrix(), order="xyzw")
    ref = R.as_quat(canonical=True)
    np.testing.assert_allclose(q, ref, atol=2e-16 * 8)
    qw = S.matrix_to_quaternion(R.as_matrix())
    assert _rot_err(S.quaternion_to_matrix(qw), R.as_matrix()) < 1e-15 * 4
    assert _rot_err(S.unit_quaternion_to_matrix(qw), R.as_matrix()) < 1e-15 * 4
    # the solver's hot path: same rotation, w >= 0
    w, v = S.quaternion_parts(R.as_matrix())
    assert np.all(w >= 0.0)
    qq = np.c_[w, v]
    assert _rot_err(S.unit_quaternion_to_matrix(qq), R.as_matrix()) < 1e-15 * 8
    # exp / log of the half angle
    e = S.quaternion_from_rotation_vector(phi)
    np.testing.assert_allclose(np.abs(np.sum(e * qw, axis=1)), 1.0, atol=1e-15 * 4)
    assert _same_rotvec(S.rotation_vector_from_quaternion(e), phi, 1e-14)
    assert _same_rotvec(S.rotation_vector_from_quaternion(-e), phi, 1e-14)


def test_quaternion_product_is_composition():
    a, b = Rotation.random(50, random_state=1), Rotation.random(50, random_state=2)
    qa = np.roll(a.as_quat(), 1, axis=1)
    qb = np.roll(b.as_quat(), 1, axis=1)
    ab = S.quaternion_multiply(qa, qb)
    assert _rot_err(S.quaternion_to_matrix(ab), (a * b).as_matrix()) < 1e-15 * 8
    one = S.quaternion_multiply(qa, S.quaternion_conjugate(qa))
    np.testing.assert_allclose(one, np.tile([1.0, 0, 0, 0], (50, 1)), atol=1e-15 * 4)
    # broadcasting: one quaternion times many
    np.testing.assert_allclose(S.quaternion_multiply(qa[0], qb), S.quaternion_multiply(np.tile(qa[0], (50, 1)), qb))


def test_slerp_against_scipy():
    ends = Rotation.from_rotvec([[0, 0, 0], [0.1, -2.9, 0.2]])
    s = np.linspace(0.0, 1.0, 11)
    ref = Slerp([0.0, 1.0], ends)(s).as_matrix()
    mine = S.slerp(ends[0].as_matrix(), ends[1].as_matrix(), s)
    assert _rot_err(mine, ref) < 1e-14
    qa, qb = (np.roll(r.as_quat(), 1) for r in ends)
    for t in s:
        assert _rot_err(S.quaternion_to_matrix(S.quaternion_slerp(qa, qb, t)), Slerp([0.0, 1.0], ends)(t).as_matrix()) < 1e-14
    # ends exactly, and the shorter arc through pi
    np.testing.assert_array_equal(mine[0], ends[0].as_matrix())
    np.testing.assert_array_equal(mine[-1], ends[1].as_matrix())


def test_rigid_transforms_hat_and_adjoint():
    R = Rotation.random(30, random_state=3).as_matrix()
    p = RNG.normal(size=(30, 3))
    T = S.transform(R, p)
    np.testing.assert_allclose(S.compose(T, S.inverse(T)), np.broadcast_to(np.eye(4), T.shape), atol=1e-14)
    np.testing.assert_allclose(S.inverse(T), np.linalg.inv(T), atol=1e-13)
    xi = RNG.normal(size=(30, 6))
    np.testing.assert_allclose(S.vee(S.hat(xi)), xi)
    np.testing.assert_allclose(S.vee3(S.hat3(xi[:, 3:])), xi[:, 3:])
    np.testing.assert_allclose(S.hat3(xi[:, :3]) @ p[..., None], np.cross(xi[:, :3], p)[..., None], atol=1e-14)
    np.testing.assert_allclose(S.cross(xi[:, :3], p), np.cross(xi[:, :3], p), atol=1e-15)
    # the adjoint's defining identity, and the product form used on the solver's hot path
    lhs = S.hat(np.einsum("bij,bj->bi", S.adjoint(T), xi))
    np.testing.assert_allclose(lhs, T @ S.hat(xi) @ S.inverse(T), atol=1e-13)
    X = RNG.normal(size=(30, 6, 4))
    np.testing.assert_allclose(S.adjoint_apply(T, X), S.adjoint(T) @ X, atol=1e-14)
    np.testing.assert_allclose(S.adjoint_apply(T, X[0]), S.adjoint(T) @ X[0], atol=1e-14)
    # elementary rotations are scipy's active rotations
    for f, ax in ((S.rot_x, "x"), (S.rot_y, "y"), (S.rot_z, "z")):
        np.testing.assert_allclose(f(0.7)[:3, :3], Rotation.from_euler(ax, 0.7).as_matrix(), atol=1e-16)


def test_checked_entry_points_refuse_wrong_shapes():
    with pytest.raises(ValueError):
        S.inverse(np.eye(3))
    with pytest.raises(ValueError):
        S.quaternion_to_matrix(np.zeros(4))
    with pytest.raises(ValueError):
        S.rotation_matrix(np.zeros(4))
