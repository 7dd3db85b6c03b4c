"""Kinematic paths and configuration interpolation (p105cli.motion), against
closed forms and scipy's Rotation/Slerp."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

from p105cli.kinematics import geometry as g
from p105cli.kinematics.placements import ypr_from_matrix, ypr_rotation
from p105cli.kinematics.spatial import transform
from p105cli.motion.configurations import ConfigurationNode, ConfigurationSequence, sample_configurations
from p105cli.motion.paths import KinematicPath, PathError, PathSegment, parameter_grid, sample_path


def frame(R, p):
    return transform(np.asarray(R), np.asarray(p, dtype=float))


RA, RB = Rotation.from_euler("xyz", [10, -40, 75], degrees=True), Rotation.from_euler("zyx", [-120, 30, 5], degrees=True)


def test_linear_segment_translation_is_linear_and_rotation_is_scipy_slerp():
    T0, T1 = frame(RA.as_matrix(), [0.1, 0.2, 0.3]), frame(RB.as_matrix(), [1.1, -0.4, 0.9])
    path = KinematicPath("p", [PathSegment("linear", 2.0, 4.0, T0, T1)])
    t = np.linspace(2.0, 4.0, 11)
    out = sample_path(path, t)
    s = (t - 2.0) / 2.0
    assert np.allclose(out.T[:, :3, 3], T0[:3, 3] + s[:, None] * (T1[:3, 3] - T0[:3, 3]), atol=1e-15)
    ref = Slerp([0.0, 1.0], Rotation.concatenate([RA, RB]))(s).as_matrix()
    assert np.abs(out.T[:, :3, :3] - ref).max() < 1e-14
    assert np.allclose(out.T[:, 3], [0, 0, 0, 1])
    assert out.prescribed.all()
    # the ends are the nodes exactly
    assert np.abs(out.T[0] - T0).max() < 1e-15 and np.abs(out.T[-1] - T1).max() < 1e-15


def test_circular_segment_moves_on_the_circle_through_the_via_point_at_constant_speed():
    # circle of radius 2 about (1, 1, 0) in a tilted plane
    c = np.array([1.0, 1.0, 0.5])
    R = Rotation.from_euler("xy", [30, 20], degrees=True).as_matrix()
    u, w = R[:, 0], R[:, 1]
    pt = lambda a: c + 2.0 * (np.cos(a) * u + np.sin(a) * w)  # noqa: E731
    a0, av, a1 = 0.3, 1.4, 2.9
    seg = PathSegment("circular", 0.0, 1.0, frame(RA.as_matrix(), pt(a0)), frame(RB.as_matrix(), pt(a1)),
                      via_point=pt(av))
    out = sample_path(KinematicPath("c", [seg]), np.linspace(0, 1, 101))
    P = out.T[:, :3, 3]
    assert np.abs(np.linalg.norm(P - c, axis=1) - 2.0).max() < 1e-12
    assert np.abs((P - c) @ R[:, 2]).max() < 1e-12          # in the circle's plane
    chords = np.linalg.norm(np.diff(P, axis=0), axis=1)
    assert np.ptp(chords) < 1e-12                            # constant angular speed
    # the arc passes through the via point: at s = (av - a0) / (a1 - a0)
    s_via = (av - a0) / (a1 - a0)
    pv = sample_path(KinematicPath("c", [seg]), [s_via]).T[0, :3, 3]
    assert np.linalg.norm(pv - pt(av)) < 1e-12


def test_circular_path_takes_the_long_arc_when_the_via_point_says_so():
    c = np.zeros(3)
    pt = lambda a: np.array([np.cos(a), np.sin(a), 0.0])  # noqa: E731
    # start at 0, end at 90 deg, via 200 deg: the arc goes the long way round (clockwise)
    seg = PathSegment("circular", 0.0, 1.0, frame(np.eye(3), pt(0)), frame(np.eye(3), pt(np.pi / 2)),
                      via_point=pt(np.radians(200)))
    P = sample_path(KinematicPath("c", [seg]), np.linspace(0, 1, 7)).T[:, :3, 3]
    ang = np.degrees(np.unwrap(np.arctan2(P[:, 1], P[:, 0])))
    assert np.allclose(ang, np.linspace(0, -270, 7), atol=1e-9)
    assert np.abs(np.linalg.norm(P - c, axis=1) - 1).max() < 1e-14


def test_degenerate_circle_is_refused():
    with pytest.raises(PathError, match="collinear"):  # refused when read, before any sampling
        PathSegment("circular", 0.0, 1.0, frame(np.eye(3), [0, 0, 0]), frame(np.eye(3), [2, 0, 0]),
                    via_point=[1, 0, 0])


def test_curve_based_segment_follows_the_curve_between_the_end_points():
    circle = g.Circle(np.eye(4), 0.5)
    T0 = frame(np.eye(3), [0.5 * np.cos(0.2), 0.5 * np.sin(0.2), 0])
    T1 = frame(RB.as_matrix(), [0.5 * np.cos(2.0), 0.5 * np.sin(2.0), 0])
    seg = PathSegment("curve_based", 0.0, 3.0, T0, T1, curve=circle)
    t = np.linspace(0, 3, 31)
    P = sample_path(KinematicPath("k", [seg]), t).T[:, :3, 3]
    ang = np.arctan2(P[:, 1], P[:, 0])
    assert np.allclose(ang, 0.2 + (t / 3.0) * 1.8, atol=1e-12)
    # an end frame off the curve is an error
    with pytest.raises(PathError, match="off the path curve"):
        PathSegment("curve_based", 0.0, 1.0, frame(np.eye(3), [0.6, 0, 0]), T1, curve=circle)


def test_curve_based_on_a_bspline_matches_its_parameters():
    bs = g.BSplineCurve(3, [[0, 0, 0], [1, 2, 0], [3, 2, 1], [4, 0, 1]], [4, 4], [0.0, 1.0])
    P0 = bs.evaluate(np.array(0.1))[0]
    P1 = bs.evaluate(np.array(0.8))[0]
    seg = PathSegment("curve_based", 0.0, 1.0, frame(np.eye(3), P0), frame(np.eye(3), P1), curve=bs)
    s = np.linspace(0, 1, 9)
    P = sample_path(KinematicPath("b", [seg]), s).T[:, :3, 3]
    assert np.abs(P - bs.evaluate(0.1 + 0.7 * s)[0]).max() < 1e-10


def test_composite_path_is_continuous_and_labels_point_to_point_samples():
    Ts = [frame(Rotation.from_rotvec([0, 0, a]).as_matrix(), [a, 0, 0]) for a in (0.0, 1.0, 2.0)]
    path = KinematicPath("comp", [PathSegment("linear", 0.0, 1.0, Ts[0], Ts[1]),
                                  PathSegment("point_to_point", 1.0, 3.0, Ts[1], Ts[2])])
    out = sample_path(path, [0.0, 0.5, 1.0, 2.0, 3.0])
    assert list(out.segment) == [0, 0, 1, 1, 1]
    assert list(out.prescribed) == [True, True, False, False, False]
    assert np.abs(out.T[2] - Ts[1]).max() < 1e-15 and np.abs(out.T[4] - Ts[2]).max() < 1e-15
    with pytest.raises(PathError, match="outside its range"):
        sample_path(path, [3.5])
    with pytest.raises(PathError, match="not contiguous"):
        KinematicPath("gap", [PathSegment("linear", 0.0, 1.0, Ts[0], Ts[1]),
                              PathSegment("linear", 1.5, 2.0, Ts[1], Ts[2])])


def test_parameter_grid():
    assert np.allclose(parameter_grid(0.0, 1.0, count=5), [0, 0.25, 0.5, 0.75, 1])
    assert np.allclose(parameter_grid(0.0, 1.0, step=0.3), [0, 0.3, 0.6, 0.9, 1.0])
    assert np.allclose(parameter_grid(0.0, 1.0, step=0.25), [0, 0.25, 0.5, 0.75, 1.0])
    assert np.allclose(parameter_grid(0.0, 1.0, count=2, breakpoints=[0.4]), [0, 0.4, 1])
    with pytest.raises(ValueError):
        parameter_grid(0.0, 1.0, step=0.0)


def test_configuration_interpolation_linear_hold_and_spherical_slerp():
    ypr_a = (0.3, -0.2, 1.0)
    ypr_b = (-2.5, 1.1, -0.4)
    seq = ConfigurationSequence("s", [
        ConfigurationNode(0.0, {"J1": (0.0,), "S": ypr_a}, "linear"),
        ConfigurationNode(1.0, {"J1": (1.0,), "S": ypr_b}, "discontinuous"),
        ConfigurationNode(2.0, {"J1": (5.0,), "S": ypr_a}, "linear"),
    ])
    t = np.array([0.0, 0.25, 0.5, 1.0, 1.5, 1.999, 2.0])
    out = sample_configurations(seq, t, {"J1": "revolute", "S": "spherical"})
    assert np.allclose(out.values["J1"][:, 0], [0, 0.25, 0.5, 1.0, 1.0, 1.0, 5.0])
    assert out.interpolation[:3] == ("linear",) * 3 and out.interpolation[4] == "discontinuous"
    # spherical: slerp of the rotations, compared with scipy
    Ra, Rb = ypr_rotation(*ypr_a), ypr_rotation(*ypr_b)
    ref = Slerp([0, 1], Rotation.from_matrix(np.stack([Ra, Rb])))([0.25, 0.5]).as_matrix()
    got = ypr_rotation(*np.moveaxis(out.values["S"][1:3], -1, 0))
    assert np.abs(got - ref).max() < 1e-13
    # the angle-by-angle blend differs (the reason for slerp)
    naive = ypr_rotation(*(0.5 * (np.array(ypr_a) + np.array(ypr_b))))
    assert np.abs(naive - ref[1]).max() > 1e-2
    assert np.allclose(out.values["S"][0], ypr_a) and np.allclose(out.values["S"][3], ypr_b)


def test_ypr_round_trip_of_slerped_rotations_through_gimbal_lock():
    # pitch passes +pi/2 at s = 0.5: the sampled ypr still rebuilds the slerped rotation
    from p105cli.kinematics.spatial import rot_y
    ya = (0.0, 1.2, 0.0)
    yb = tuple(float(x) for x in ypr_from_matrix(rot_y(np.pi - 1.2)))  # pitch 1.2, yaw = roll = pi
    seq = ConfigurationSequence("g", [ConfigurationNode(0.0, {"S": ya}), ConfigurationNode(1.0, {"S": yb})])
    s = np.linspace(0, 1, 201)
    out = sample_configurations(seq, s, {"S": "spherical"})
    assert np.isfinite(out.values["S"]).all()
    got = ypr_rotation(*np.moveaxis(out.values["S"], -1, 0))
    ref = Slerp([0, 1], Rotation.from_matrix(np.stack([ypr_rotation(*ya), ypr_rotation(*yb)])))(s).as_matrix()
    assert np.abs(got - ref).max() < 1e-12
    assert (np.abs(out.values["S"][:, 1]) <= np.pi / 2 + 1e-15).all()
    y = np.stack(ypr_from_matrix(got), axis=-1)
    assert np.isfinite(y).all()
