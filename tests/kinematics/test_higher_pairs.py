"""Higher pairs (point/sliding/rolling on surfaces and planar curves), the generic low order pair and
the spherical pair with pin (p105cli.kinematics.pairs).

Independent truths: matrices derived by hand at special values (typed in literally), scipy Rotation
for the ypr parts, central finite differences for every Jacobian, the contact conditions (the contact
point lies on both geometries, the normals are opposed/aligned as the orientation flag says), zero
slip at the contact of the rolling pairs, the epicycloid/hypocycloid angle of rolling circles and
the rolling ball's angular velocity.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from p105cli.kinematics import geometry as G
from p105cli.kinematics import pairs
from p105cli.kinematics.pairs import PAIR_KINDS, PAIRS, UnsupportedPairError, pair_type
from p105cli.kinematics.spatial import vee
from p105cli.kinematics.spatial import (
    compose, inverse, rot_x, rot_y, rot_z, trans_x, trans_y, trans_z, transform,
)

PI = math.pi
RNG = np.random.default_rng(4105)


def close(a, b, tol=1e-12):
    np.testing.assert_allclose(a, b, rtol=0, atol=tol)


def rigid(T):
    R = T[..., :3, :3]
    close(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape), 1e-12)
    close(np.linalg.det(R), 1.0, 1e-12)


# ---------------------------------------------------------------- geometry fixtures
T0 = compose(trans_x(0.4), trans_y(-1.0), trans_z(0.3), rot_x(0.5), rot_y(-0.3), rot_z(0.9))
T_PLANAR = compose(trans_x(0.7), trans_y(-0.2), rot_z(0.6))      # keeps curves in the xy plane


def _bs_surface(rational):
    P = RNG.normal(size=(5, 4, 3)) + np.array([0.0, 0.0, 0.0])
    u = np.linspace(0, 1, 5)[:, None]
    v = np.linspace(-1, 2, 4)[None, :]
    P[..., 0] += 3 * u
    P[..., 1] += 3 * v
    w = RNG.uniform(0.5, 2.0, (5, 4)) if rational else None
    return G.BSplineSurface(3, 2, P, [4, 1, 4], [3, 1, 3], [0.0, 0.4, 1.0], [-1.0, 0.2, 2.0], w)


#: surfaces with a parameter box away from degeneracies and knots
SURFACES = {
    "plane": (G.Plane(T0), (-2, 2), (-2, 2)),
    "cylinder": (G.CylindricalSurface(T0, 1.3), (-3, 3), (-2, 2)),
    "cone": (G.ConicalSurface(T0, 0.9, 0.4), (-3, 3), (-1, 2)),
    "sphere": (G.SphericalSurface(T0, 2.1), (-3, 3), (-1.2, 1.2)),
    "torus": (G.ToroidalSurface(T0, 3.0, 0.7), (-3, 3), (-3, 3)),
    "bspline": (_bs_surface(False), (0.45, 0.95), (0.25, 1.9)),
    "rational_bspline": (_bs_surface(True), (0.45, 0.95), (0.25, 1.9)),
}


def _bs_curve(rational):
    P = np.zeros((7, 3))
    P[:, 0] = np.linspace(0, 6, 7)
    P[:, 1] = RNG.normal(size=7)
    w = RNG.uniform(0.5, 2.0, 7) if rational else None
    return G.BSplineCurve(3, P, [4, 1, 2, 4], [0.0, 0.7, 1.5, 2.5], w)


#: planar curves (in the xy plane of their pair frame) with a parameter range away from knots
CURVES = {
    "line": (G.Line([1.0, 2.0, 0.0], [0.5, -1.0, 0.0]), (-2, 2)),
    "circle": (G.Circle(T_PLANAR, 1.7), (-4, 4)),
    "ellipse": (G.Ellipse(T_PLANAR, 2.5, 0.8), (-4, 4)),
    "bspline": (_bs_curve(False), (0.75, 1.45)),
    "rational_bspline": (_bs_curve(True), (1.55, 2.45)),
    "trimmed_circle": (G.TrimmedCurve(G.Circle(T_PLANAR, 1.2), 5.5, 1.0, False), (0.2, 3.0)),
}


def _u(box, size=None):
    return RNG.uniform(box[0], box[1], size)


# ---------------------------------------------------------------- finite differences

def _fd_body(t, q, params, h=1e-6):
    M0 = t.motion(q, **params)
    cols = []
    for i in range(t.value_count):
        e = np.zeros(t.value_count)
        e[i] = h
        dM = (t.motion(q + e, **params) - t.motion(q - e, **params)) / (2 * h)
        cols.append(vee(inverse(M0) @ dM))
    return np.stack(cols, axis=-1)


def _check_jacobian(t, q, params, tol=2e-7):
    M0 = t.motion(q, **params)
    rigid(M0)
    J = t.motion_jacobian(q, **params)
    assert J.shape == (6, t.value_count)
    scale = max(1.0, float(np.abs(M0[:3, 3]).max()), float(np.abs(J).max()))
    np.testing.assert_allclose(J, _fd_body(t, q, params), rtol=0, atol=tol * scale)


def _ypr():
    return list(RNG.uniform([-PI, -1.4, -PI], [PI, 1.4, PI]))


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_point_on_surface_jacobian(name):
    s, bu, bv = SURFACES[name]
    for _ in range(4):
        q = np.array([_u(bu), _u(bv)] + _ypr())
        _check_jacobian(PAIR_KINDS["point_on_surface"], q, {"surface": s})
        # the second pair frame's origin is on the surface
        close(PAIR_KINDS["point_on_surface"].motion(q, surface=s)[:3, 3], s.evaluate(q[0], q[1])[0], 1e-12)


@pytest.mark.parametrize("name", sorted(CURVES))
def test_point_on_planar_curve_jacobian(name):
    c, b = CURVES[name]
    for orientation in (True, False):
        q = np.array([_u(b)] + _ypr())
        _check_jacobian(PAIR_KINDS["point_on_planar_curve"], q, {"curve": c, "orientation": orientation})
        close(PAIR_KINDS["point_on_planar_curve"].motion(q, curve=c)[:3, 3], c.evaluate(q[0])[0], 1e-12)


@pytest.mark.parametrize("n1,n2", [("sphere", "plane"), ("torus", "bspline"), ("cone", "rational_bspline"),
                                   ("cylinder", "sphere"), ("rational_bspline", "torus")])
def test_sliding_surface_jacobian_and_contact(n1, n2):
    (s1, bu1, bv1), (s2, bu2, bv2) = SURFACES[n1], SURFACES[n2]
    t = PAIR_KINDS["sliding_surface"]
    for orientation in (True, False):
        q = np.array([_u(bu1), _u(bv1), _u(bu2), _u(bv2), _u((-PI, PI))])
        params = {"surface_1": s1, "surface_2": s2, "orientation": orientation}
        _check_jacobian(t, q, params)
        M = t.motion(q, **params)
        # the contact point lies on both surfaces: S2(u2, v2) (frame 2) maps to S1(u1, v1) (frame 1)
        p1, p2 = s1.evaluate(q[0], q[1])[0], s2.evaluate(q[2], q[3])[0]
        close(M[:3, :3] @ p2 + M[:3, 3], p1, 1e-10 * max(1.0, np.abs(p1).max()))
        # normals: same direction (orientation TRUE) or opposed (FALSE)
        n1v, n2v = s1.normal(q[0], q[1]), M[:3, :3] @ s2.normal(q[2], q[3])
        close(n2v, n1v if orientation else -n1v, 1e-10)
        # actual_rotation: angle about the common normal from the u tangent of surface 1 to that of 2
        x1 = s1.evaluate(q[0], q[1])[1]
        x2 = M[:3, :3] @ s2.evaluate(q[2], q[3])[1]
        x1, x2 = x1 / np.linalg.norm(x1), x2 / np.linalg.norm(x2)
        ang = math.atan2(np.dot(np.cross(x1, x2), n1v), np.dot(x1, x2))
        close((ang - q[4] + PI) % (2 * PI) - PI, 0.0, 1e-10)


@pytest.mark.parametrize("n1,n2", [("ellipse", "circle"), ("bspline", "line"), ("circle", "rational_bspline"),
                                   ("trimmed_circle", "ellipse")])
def test_sliding_curve_jacobian_and_contact(n1, n2):
    (c1, b1), (c2, b2) = CURVES[n1], CURVES[n2]
    t = PAIR_KINDS["sliding_curve"]
    for orientation in (True, False):
        q = np.array([_u(b1), _u(b2)])
        params = {"curve_1": c1, "curve_2": c2, "orientation": orientation}
        _check_jacobian(t, q, params)
        M = t.motion(q, **params)
        close(M[2, :3], [0, 0, 1], 1e-14)          # a planar motion
        P1, d1, _ = c1.evaluate(q[0])
        P2, d2, _ = c2.evaluate(q[1])
        close(M[:3, :3] @ P2 + M[:3, 3], P1, 1e-10 * max(1.0, np.abs(P1).max()))
        t1, t2 = d1 / np.linalg.norm(d1), M[:3, :3] @ d2 / np.linalg.norm(d2)
        close(t2, t1 if orientation else -t1, 1e-10)


def _slip(t, q, params, contact):
    """Velocity (frame 1) of the material point of link 2 at ``contact`` per unit rate of each value."""
    Js = t.motion_jacobian(q, frame="spatial", **params)
    return Js[:3] + np.cross(Js[3:].T, contact).T


@pytest.mark.parametrize("n1,n2", [("ellipse", "circle"), ("circle", "bspline"), ("bspline", "ellipse"),
                                   ("rational_bspline", "circle")])
def test_rolling_curve_zero_slip_and_jacobian(n1, n2):
    (c1, b1), (c2, b2) = CURVES[n1], CURVES[n2]
    t = PAIR_KINDS["rolling_curve"]
    for orientation in (True, False):
        u1 = _u(b1)
        ref1 = float(np.clip(u1 + 0.1, *b1))
        params = {"curve_1": c1, "curve_2": c2, "orientation": orientation,
                  "reference_parameter_1": ref1, "reference_parameter_2": float(np.mean(b2))}
        q = np.array([u1])
        _check_jacobian(t, q, params)
        P1 = c1.evaluate(u1)[0]
        close(_slip(t, q, params, P1), np.zeros((3, 1)), 1e-8 * max(1.0, np.abs(P1).max()))
        # at the reference parameters the reference points touch
        M = t.motion([ref1], **params)
        close(M[:3, :3] @ c2.evaluate(params["reference_parameter_2"])[0] + M[:3, 3],
              c1.evaluate(ref1)[0], 1e-9)


@pytest.mark.parametrize("inside", [False, True])
def test_rolling_circles_epicycloid_and_hypocycloid(inside):
    """Circle 2 (radius r2, centre at frame 2's origin) rolls on circle 1 (r1, centre at frame 1's
    origin): outside (tangents opposed, orientation FALSE) its centre is at (r1 + r2) e(u1) and it has
    turned by pi + (1 + r1/r2) u1; inside (tangents aligned, TRUE) at (r1 - r2) e(u1), turned by
    (1 - r1/r2) u1 (hand-derived rolling of circles, as in epicyclic gearing)."""
    r1, r2 = 3.0, 1.25
    t = PAIR_KINDS["rolling_curve"]
    params = {"curve_1": G.Circle(np.eye(4), r1), "curve_2": G.Circle(np.eye(4), r2),
              "orientation": inside}
    for u1 in (0.0, 0.7, PI, -2.2):
        M = t.motion([u1], **params)
        d = r1 - r2 if inside else r1 + r2
        close(M[:3, 3], [d * math.cos(u1), d * math.sin(u1), 0.0], 1e-9)
        turn = (1 - r1 / r2) * u1 if inside else PI + (1 + r1 / r2) * u1
        close(M[:3, :3], rot_z(turn)[:3, :3], 1e-9)


def test_rolling_circle_matches_gear_pair_kinematics():
    """A spur gear pair is two pitch circles rolling: the rolling curve pair's relative rotation rate
    equals the gear pair's (1 + gear_ratio) per unit rotation of the first link's contact."""
    r1, r2 = 2.0, 3.0
    J = PAIR_KINDS["rolling_curve"].motion_jacobian(
        [0.4], curve_1=G.Circle(np.eye(4), r1), curve_2=G.Circle(np.eye(4), r2), orientation=False)
    Jg = PAIR_KINDS["gear"].motion_jacobian([0.4], radius_first_link=r1, radius_second_link=r2,
                                            gear_ratio=r1 / r2)
    close(abs(J[5, 0]), abs(Jg[5, 0]), 1e-9)


@pytest.mark.parametrize("n1,n2", [("plane", "sphere"), ("sphere", "torus"), ("bspline", "sphere"),
                                   ("cylinder", "rational_bspline")])
def test_rolling_surface_zero_slip_and_sliding_part(n1, n2):
    (s1, bu1, bv1), (s2, bu2, bv2) = SURFACES[n1], SURFACES[n2]
    t = PAIR_KINDS["rolling_surface"]
    for orientation in (True, False):
        q = np.array([_u(bu1), _u(bv1), _u((-PI, PI))])
        w = np.array([_u(bu2), _u(bv2)])
        params = {"surface_1": s1, "surface_2": s2, "orientation": orientation, "point_on_surface_2": w}
        M = t.motion(q, **params)
        q5 = np.array([q[0], q[1], w[0], w[1], q[2]])
        sparams = {k: params[k] for k in ("surface_1", "surface_2", "orientation")}
        close(M, PAIR_KINDS["sliding_surface"].motion(q5, **sparams), 0)
        P1 = s1.evaluate(q[0], q[1])[0]
        close(_slip(t, q, params, P1), np.zeros((3, 3)), 1e-8 * max(1.0, np.abs(P1).max()))
        # the no-slip Jacobian = the sliding columns along the rates, checked by finite differences
        rates = pairs.rolling_surface_rates(q, **params)
        h = 1e-6
        for i in range(3):
            e5 = np.zeros(5)
            e5[[0, 1, 4][i]] = 1.0
            e5[2:4] = rates[:, i]
            dM = (PAIR_KINDS["sliding_surface"].motion(q5 + h * e5, **sparams)
                  - PAIR_KINDS["sliding_surface"].motion(q5 - h * e5, **sparams)) / (2 * h)
            close(t.motion_jacobian(q, **params)[:, i], vee(inverse(M) @ dM), 2e-7 * max(1, np.abs(M).max()))


def test_ball_rolling_on_plane():
    """A ball of radius r on the plane z = 0 (surface_1, normal +z; the ball's outward normal at the
    contact is -z: orientation FALSE). Moving the contact by du1 along x turns the ball about +y by
    du1 / r (and by dv1 along y about -x); its centre is r above the contact and moves with it; the
    rotation value spins it about the normal. (Holding the rotation value while the contact moves
    also spins the ball about the normal, at the rate the ball's (u, v) tangent frame turns: that
    part depends on the parameterisation, so only the tangential components are closed forms.)"""
    r = 0.8
    plane, ball = G.Plane(np.eye(4)), G.SphericalSurface(np.eye(4), r)
    t = PAIR_KINDS["rolling_surface"]
    params = {"surface_1": plane, "surface_2": ball, "orientation": False,
              "point_on_surface_2": np.array([0.3, -0.6])}
    q = np.array([1.5, -0.5, 0.4])
    M = t.motion(q, **params)
    close(M[:3, 3], [1.5, -0.5, r], 1e-12)
    Js = t.motion_jacobian(q, frame="spatial", **params)
    close(Js[3:5, 0], [0, 1 / r], 1e-12)            # d/du1: roll about +y
    close(Js[3:5, 1], [-1 / r, 0], 1e-12)           # d/dv1: roll about -x
    close(Js[3:, 2], [0, 0, 1], 1e-12)              # d/drotation: spin about the normal
    # centre velocity = contact point velocity on the plane
    centre = M[:3, 3]
    close(Js[:3, 0] + np.cross(Js[3:, 0], centre), [1, 0, 0], 1e-12)


# ---------------------------------------------------------------- closed forms at special values

def test_point_on_surface_closed_forms():
    """M = Trans(S(u, v)) Rx(roll) Ry(pitch) Rz(yaw): the point of link 2 is on the surface, its
    orientation is relative to the first pair frame's axes (the corpus convention)."""
    t = PAIR_KINDS["point_on_surface"]
    # plane: S(u, v) = C + u x + v y
    close(t.motion([1.5, -2.0, 0, 0, 0], surface=G.Plane(T0)),
          transform(np.eye(3), T0[:3, 3] + 1.5 * T0[:3, 0] - 2.0 * T0[:3, 1]), 1e-12)
    # sphere of radius R at (u, 0) and at the pole: a pure translation to the surface point
    R = 2.0
    for u in (0.0, PI / 2, PI, -0.7):
        literal = np.array([[1, 0, 0, R * math.cos(u)], [0, 1, 0, R * math.sin(u)], [0, 0, 1, 0], [0, 0, 0, 1.0]])
        close(t.motion([u, 0.0, 0, 0, 0], surface=G.SphericalSurface(np.eye(4), R)), literal, 1e-12)
    close(t.motion([0.3, PI / 2, 0, 0, 0], surface=G.SphericalSurface(np.eye(4), R))[:3, 3], [0, 0, R], 1e-12)
    # the orientation part is Annex E's ypr = scipy's extrinsic 'zyx' (yaw, pitch, roll), at any point
    for _ in range(5):
        y, p, r = _ypr()
        u, v = RNG.uniform(-2, 2, 2)
        Mq = t.motion([u, v, y, p, r], surface=G.Plane(T0))
        close(Mq[:3, :3], Rotation.from_euler("zyx", [y, p, r]).as_matrix(), 1e-12)
        close(Mq[:3, 3], G.Plane(T0).evaluate(u, v)[0], 1e-12)
    # limits: pitch = +-pi/2, yaw = pi
    Mq = t.motion([0.0, 0.0, PI, PI / 2, 0.0], surface=G.Plane(np.eye(4)))
    close(Mq[:3, :3], [[0, 0, 1], [0, -1, 0], [1, 0, 0]], 1e-12)


def test_point_on_planar_curve_closed_forms():
    """Circle of radius r about c: M = Trans(c + r e(u)) Rx(roll) Ry(pitch) Rz(yaw); the
    orientation flag does not change the motion."""
    r, cx, cy = 1.5, 2.0, -1.0
    circle = G.Circle(compose(trans_x(cx), trans_y(cy)), r)
    t = PAIR_KINDS["point_on_planar_curve"]
    for u in (0.0, PI / 2, PI, 2.5):
        for yaw in (0.0, PI / 2, -PI):
            literal = np.array([[math.cos(yaw), -math.sin(yaw), 0, cx + r * math.cos(u)],
                                [math.sin(yaw), math.cos(yaw), 0, cy + r * math.sin(u)],
                                [0, 0, 1, 0], [0, 0, 0, 1.0]])
            for orientation in (True, False):
                close(t.motion([u, yaw, 0, 0], curve=circle, orientation=orientation), literal, 1e-12)
    # the knife edge of the corpus cam: radius 40 mm circle 15 mm off the shaft; the top of the
    # profile (u = pi/2) is at (15, 40)
    cam = G.Circle(trans_x(15.0), 40.0)
    close(t.motion([PI / 2, 0, 0, 0], curve=cam)[:3, 3], [15.0, 40.0, 0.0], 1e-12)


def test_corpus_cam_follower_poses_are_reproduced():
    """The corpus cam-follower's solved link poses (the generator's own geometry) satisfy
    T_cam^-1 T_follower = P1 M(q) P2^-1 at the contact pair's values it writes."""
    from p105cli.corpus import geometry as cgeo
    from p105cli.corpus import mechanisms as cmech
    mech = cmech.cam_follower()
    contact = [p for p in mech.pairs if p.kind == "point_on_planar_curve"][0]
    circle = G.Circle(transform(np.eye(3), contact.params["circle_center"]), contact.params["circle_radius"])
    checked = 0
    for drive in list(mech.drives) + list(mech.sweep)[::5]:
        poses = mech.solve(drive)
        value = cmech.configuration(mech, drive, 2)[contact.name]
        q = np.array([value["parameter"]] + cgeo.ypr_angles(value["orientation"]))
        Mq = PAIR_KINDS["point_on_planar_curve"].motion(q, curve=circle, orientation=True)
        P1, P2 = cmech.pair_frames(contact, 2)
        T = compose(inverse(poses[contact.first]), poses[contact.second])
        close(pairs.link_transform(P1, Mq, P2), T, 1e-9 * max(1.0, float(np.abs(T[:3, 3]).max())))
        checked += 1
    assert checked > 3


def test_sliding_circles_closed_form():
    """Two circles touching from outside (tangents opposed): circle 2's centre is at (r1 + r2) e(u1)
    and frame 2 is turned by u1 - u2 + pi, whatever u2 (hand-derived)."""
    r1, r2 = 2.0, 0.5
    t = PAIR_KINDS["sliding_curve"]
    for u1, u2 in ((0.0, 0.0), (PI / 2, PI), (1.0, -2.0)):
        M = t.motion([u1, u2], curve_1=G.Circle(np.eye(4), r1), curve_2=G.Circle(np.eye(4), r2),
                     orientation=False)
        close(M[:3, 3], [(r1 + r2) * math.cos(u1), (r1 + r2) * math.sin(u1), 0], 1e-12)
        close(M[:3, :3], rot_z(u1 - u2 + PI)[:3, :3], 1e-12)


def test_sphere_on_plane_sliding_closed_form():
    r = 1.5
    t = PAIR_KINDS["sliding_surface"]
    plane, ball = G.Plane(np.eye(4)), G.SphericalSurface(np.eye(4), r)
    # any (u2, v2): the ball's centre is r above the contact point on the plane
    for q in ([0.0, 0.0, 0.3, -0.4, 0.0], [2.0, -1.0, 1.0, 0.7, PI]):
        M = t.motion(q, surface_1=plane, surface_2=ball, orientation=False)
        close(M[:3, 3], [q[0], q[1], r], 1e-12)
    # at (u2, v2) = (0, 0) the ball's contact frame is x = +y, y = +z, z = +x (outward); with the
    # normals opposed and rotation 0 it is the plane's frame turned by pi about x, so the ball's
    # +x point is down, its +y along +x and its +z along -y (hand-derived)
    M = t.motion([0.5, 0.25, 0.0, 0.0, 0.0], surface_1=plane, surface_2=ball, orientation=False)
    close(M, [[0, 1, 0, 0.5], [0, 0, -1, 0.25], [-1, 0, 0, r], [0, 0, 0, 1]], 1e-12)
    # rotation pi/2 about the plane normal: the ball's +y (its u tangent there) goes to +y
    M = t.motion([0.0, 0.0, 0.0, 0.0, PI / 2], surface_1=plane, surface_2=ball, orientation=False)
    close(M[:3, :3] @ [0, 1, 0], [0, 1, 0], 1e-12)


# ---------------------------------------------------------------- batching and errors

HIGHER_CASES = {
    "point_on_surface": ({"surface": SURFACES["torus"][0]}, [(-3, 3), (-3, 3), (-3, 3), (-1.4, 1.4), (-3, 3)]),
    "sliding_surface": ({"surface_1": SURFACES["sphere"][0], "surface_2": SURFACES["cylinder"][0],
                         "orientation": False}, [(-3, 3), (-1, 1), (-3, 3), (-2, 2), (-3, 3)]),
    "rolling_surface": ({"surface_1": SURFACES["sphere"][0], "surface_2": SURFACES["torus"][0],
                         "orientation": True, "point_on_surface_2": np.array([0.2, 0.3])},
                        [(-3, 3), (-1, 1), (-3, 3)]),
    "point_on_planar_curve": ({"curve": CURVES["ellipse"][0], "orientation": True},
                              [(-3, 3), (-3, 3), (-1.4, 1.4), (-3, 3)]),
    "sliding_curve": ({"curve_1": CURVES["ellipse"][0], "curve_2": CURVES["bspline"][0], "orientation": False},
                      [(-3, 3), (0.75, 1.45)]),
    "rolling_curve": ({"curve_1": CURVES["ellipse"][0], "curve_2": CURVES["circle"][0], "orientation": False},
                      [(-3, 3)]),
}


@pytest.mark.parametrize("kind", sorted(HIGHER_CASES))
def test_higher_batching_equals_per_element(kind):
    params, boxes = HIGHER_CASES[kind]
    t = PAIR_KINDS[kind]
    q = np.stack([RNG.uniform(lo, hi, (3, 4)) for lo, hi in boxes], axis=-1)
    Mb, Jb = t.motion(q, **params), t.motion_jacobian(q, **params)
    assert Mb.shape == (3, 4, 4, 4) and Jb.shape == (3, 4, 6, t.value_count)
    for i in range(3):
        for j in range(4):
            close(Mb[i, j], t.motion(q[i, j], **params), 1e-12)
            close(Jb[i, j], t.motion_jacobian(q[i, j], **params), 1e-9)


def test_rolling_surface_batched_state_and_flags():
    s1, s2 = SURFACES["sphere"][0], SURFACES["plane"][0]
    t = PAIR_KINDS["rolling_surface"]
    w = np.array([[0.1, 0.2], [0.3, -0.4]])
    flags = np.array([True, False])
    q = np.array([0.5, 0.2, 0.1])
    Mb = t.motion(q, surface_1=s1, surface_2=s2, orientation=flags, point_on_surface_2=w)
    assert Mb.shape == (2, 4, 4)
    for k in range(2):
        close(Mb[k], t.motion(q, surface_1=s1, surface_2=s2, orientation=bool(flags[k]),
                              point_on_surface_2=w[k]), 1e-12)


def test_degenerate_geometry_raises_not_nan():
    t = PAIR_KINDS["sliding_surface"]
    apex = G.ConicalSurface(np.eye(4), 0.0, 0.3)
    plane = G.Plane(np.eye(4))
    with pytest.raises(ValueError, match="degenerate"):       # the apex of a cone with radius 0 at v = 0
        t.motion([0.0, 0.0, 0, 0, 0], surface_1=apex, surface_2=plane, orientation=False)
    with pytest.raises(ValueError, match="degenerate"):       # batched: one bad sample is enough
        t.motion([[0.3, 1.0, 0, 0, 0], [0.0, 0.0, 0, 0, 0]], surface_1=apex, surface_2=plane, orientation=False)
    # the point pair needs no frame at the apex: the point is well defined
    close(PAIR_KINDS["point_on_surface"].motion([0.0, 0.0, 0, 0, 0], surface=apex), np.eye(4), 0)
    with pytest.raises(ValueError, match="xy plane"):
        PAIR_KINDS["sliding_curve"].motion([0.0, 0.0], curve_1=G.Line([0, 0, 0], [0, 0, 1.0]),
                                           curve_2=CURVES["circle"][0], orientation=True)
    with pytest.raises(TypeError, match="missing"):
        PAIR_KINDS["sliding_curve"].motion([0.0, 0.0], curve_1=CURVES["circle"][0])
    with pytest.raises(ValueError, match="non-holonomic"):
        PAIR_KINDS["rolling_surface"].motion([0.0, 0.0, 0.0], surface_1=plane, surface_2=plane, orientation=False)
    with pytest.raises(TypeError, match="geometry surface"):
        PAIR_KINDS["point_on_surface"].motion([0.0, 0.0, 0, 0, 0], surface="#12")


# ---------------------------------------------------------------- low order pair and spherical pair with pin

def test_low_order_closed_forms_and_flags():
    t = PAIR_KINDS["low_order"]
    q = [1.0, -2.0, 0.5, 0.3, -0.4, 1.2]
    # translation first, then Rx(rx) Ry(ry) Rz(rz) -- the ypr matrix with roll = rx, pitch = ry, yaw = rz
    close(t.motion(q), compose(trans_x(1.0), trans_y(-2.0), trans_z(0.5), rot_x(0.3), rot_y(-0.4), rot_z(1.2)))
    close(t.motion(q)[:3, :3], Rotation.from_euler("zyx", [1.2, -0.4, 0.3]).as_matrix())
    # the AP242 revolute pair is the low order pair with only r_z: same motion
    locked = dict(t_x=False, t_y=False, t_z=False, r_x=False, r_y=False, r_z=True)
    close(t.motion([0, 0, 0, 0, 0, 0.7], **locked), PAIR_KINDS["revolute"].motion([0.7]))
    # cylindrical: t_z, r_z
    close(t.motion([0, 0, 2.0, 0, 0, 0.7], **{**locked, "t_z": True}),
          PAIR_KINDS["cylindrical"].motion([2.0, 0.7]))
    J = t.motion_jacobian([0, 0, 0, 0, 0, 0.7], **locked)
    close(J[:, :5], np.zeros((6, 5)), 0)
    with pytest.raises(ValueError, match="r_x = FALSE"):
        t.motion([0, 0, 0, 0.1, 0, 0.7], **locked)
    for _ in range(5):
        _check_jacobian(t, RNG.uniform(-2, 2, 6), {})
    assert PAIRS["low_order_kinematic_pair"] is t and PAIRS["low_order_kinematic_pair_with_range"] is t


def test_spherical_pair_with_pin():
    t = PAIRS["spherical_pair_with_pin"]
    assert PAIRS["spherical_pair_with_pin_and_range"] is t
    for y, p in ((0.0, 0.0), (0.7, -0.3), (PI, PI / 2)):
        close(t.motion([y, p, 0.0]), compose(rot_y(p), rot_z(y)))
        close(t.motion([y, p, 0.0]), PAIR_KINDS["spherical"].motion([y, p, 0.0]))
    with pytest.raises(ValueError, match="roll"):
        t.motion([0.1, 0.2, 0.3])
    J = t.motion_jacobian([0.4, 0.2, 0.0])
    close(J[:, 2], np.zeros(6), 0)
    # yaw and pitch columns against finite differences (roll is locked, not perturbed)
    h = 1e-6
    M0 = t.motion([0.4, 0.2, 0.0])
    for i in range(2):
        e = np.zeros(3)
        e[i] = h
        dM = (t.motion(np.array([0.4, 0.2, 0.0]) + e) - t.motion(np.array([0.4, 0.2, 0.0]) - e)) / (2 * h)
        close(J[:, i], vee(inverse(M0) @ dM), 1e-8)


# ---------------------------------------------------------------- registry

def test_higher_pair_registry():
    for name, kind, n in (("point_on_surface_pair", "point_on_surface", 5),
                          ("point_on_surface_pair_with_range", "point_on_surface", 5),
                          ("sliding_surface_pair", "sliding_surface", 5),
                          ("rolling_surface_pair", "rolling_surface", 3),
                          ("point_on_planar_curve_pair", "point_on_planar_curve", 4),
                          ("point_on_planar_curve_pair_with_range", "point_on_planar_curve", 4),
                          ("sliding_curve_pair", "sliding_curve", 2),
                          ("rolling_curve_pair", "rolling_curve", 1)):
        assert pair_type(name.upper()) is PAIR_KINDS[kind]
        assert PAIRS[name].value_count == n
    for name in PAIRS:
        assert name not in pairs.NOT_IMPLEMENTED
    with pytest.raises(UnsupportedPairError):
        pair_type("linear_flexible_and_planar_curve_pair")
    # bevel and helical gears stay refused (their geometry is not defined in the available text)
    with pytest.raises(UnsupportedPairError, match="bevel"):
        PAIR_KINDS["gear"].motion([0.1], radius_first_link=1.0, radius_second_link=2.0, gear_ratio=0.5,
                                  bevel=0.3)
    with pytest.raises(UnsupportedPairError, match="helical_angle"):
        PAIR_KINDS["gear"].motion([0.1], radius_first_link=1.0, radius_second_link=2.0, gear_ratio=0.5,
                                  helical_angle=0.3)
