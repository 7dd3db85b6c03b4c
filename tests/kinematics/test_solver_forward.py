"""Forward kinematics, once (solver/forward.py): the batched ``forward`` and the plain-product
``link_poses`` against independent truth (the DH product of an arm, pair transforms composed
by hand along a hand-written walk, backwards-crossed pairs inverted by hand), against each
other on every corpus mechanism, and as the model writer and dh.chain_pose use them."""

from __future__ import annotations

import glob
import math
from pathlib import Path

import numpy as np
import pytest

from p105cli.kinematics import dh, geometry as G, solver
from p105cli.kinematics.model import Link, Mechanism, Pair
from p105cli.kinematics.pairs import UnsupportedPairError
from p105cli.kinematics.reader import read_mechanisms
from p105cli.kinematics.spatial import compose, inverse, rot_x, rot_y, rot_z, trans_x, trans_z
from p105cli.part105.write_mechanism import _forward_poses
from p105cli.step import read_any

ROOT = Path(__file__).resolve().parents[2]
FILES = sorted(glob.glob(str(ROOT / "tests/data/corpus/*.stp")) + glob.glob(str(ROOT / "examples/*.stp")))
RNG = np.random.default_rng(105)

# Puma 560, standard DH (a, alpha, d) in metres and radians
PUMA = [(0.0, math.pi / 2, 0.6718), (0.4318, 0.0, 0.0), (0.0203, -math.pi / 2, 0.15005),
        (0.0, math.pi / 2, 0.4318), (0.0, -math.pi / 2, 0.0), (0.0, 0.0, 0.0)]


def _corpus():
    out = []
    for fn in FILES:
        for m in read_mechanisms(read_any(Path(fn).read_text(), fn)):
            out.append(pytest.param(m, id=f"{Path(fn).stem}:{m.name}"))
    return out


def test_forward_is_the_dh_product():
    table = dh.DHTable("standard", [dh.DHJoint(f"J{i + 1}", "R", a, al, d=d) for i, (a, al, d) in enumerate(PUMA)],
                       compose(trans_x(0.3), rot_z(0.4)), np.eye(4))
    mech = dh.to_mechanism(table)
    pl = solver.plan(mech)
    Q = RNG.uniform(-3, 3, (50, 6))
    want = np.empty((50, 4, 4))
    for b in range(50):
        T = table.base.copy()
        for (a, al, d), q in zip(PUMA, Q[b]):
            T = T @ rot_z(q) @ trans_z(d) @ trans_x(a) @ rot_x(al)
        want[b] = T
    cols = [mech.value_slices[f"J{i + 1}"].start for i in range(6)]
    Qf = np.zeros((50, pl.nv))
    Qf[:, cols] = Q
    tip = pl.link_index["link6"]
    np.testing.assert_allclose(solver.forward(pl, Qf)[:, tip], want, atol=1e-13)
    X, _, _ = solver.link_poses(pl, Qf, world=True)
    np.testing.assert_allclose(X[tip], want, atol=1e-13)
    np.testing.assert_allclose(dh.chain_pose(mech, Q, tool=None), want, atol=1e-13)


def _backwards():
    """A tree whose pairs are crossed backwards (the parent is the pair's second link): a
    revolute, a prismatic and a cylindrical pair, with general pair frames."""
    P = [compose(trans_x(0.1 * k), rot_x(0.3 * k), trans_z(0.05), rot_y(0.2 * k)) for k in range(1, 7)]
    links = [Link(n) for n in ("base", "a", "b", "c")]
    pairs = [Pair("R", "revolute", "a", "base", P[0], P[1]),
             Pair("S", "prismatic", "b", "a", P[2], P[3]),
             Pair("C", "cylindrical", "b", "c", P[4], P[5])]
    return Mechanism("backwards", links, pairs, "base", initial={"R": (0.4,), "S": (0.02,), "C": (0.1, -0.7)})


def test_backwards_crossed_pairs_are_inverted():
    mech = _backwards()
    pl = solver.plan(mech)
    q = RNG.uniform(-1, 1, (7, pl.nv))
    T = {p.name: p.transform(q[:, mech.value_slices[p.name]]) for p in mech.pairs}
    want = {"base": np.broadcast_to(np.eye(4), (7, 4, 4))}
    want["a"] = inverse(T["R"])
    want["b"] = want["a"] @ inverse(T["S"])
    want["c"] = want["b"] @ T["C"]
    F = solver.forward(pl, q, world=False)
    X, _, _ = solver.link_poses(pl, q)
    for name, i in pl.link_index.items():
        np.testing.assert_allclose(F[:, i], want[name], atol=1e-14)
        np.testing.assert_allclose(X[i], want[name], atol=1e-14)


def test_a_part_not_connected_to_the_base_is_placed_from_its_first_link():
    links = [Link(n) for n in ("base", "a", "x", "y")]
    pairs = [Pair("R", "revolute", "base", "a", trans_x(0.1), np.eye(4)),
             Pair("Q", "revolute", "x", "y", trans_x(0.2), rot_x(0.5))]
    mech = Mechanism("two parts", links, pairs, "base", initial={"R": (0.3,), "Q": (0.7,)},
                     T_world_base=trans_z(1.0))
    pl = solver.plan(mech)
    q = mech.initial_vector()
    F = solver.forward(pl, q)[0]
    X, _, _ = solver.link_poses(pl, q, world=True)
    want_y = pairs[1].transform(np.array([0.7]))
    np.testing.assert_allclose(F[pl.link_index["x"]], np.eye(4))
    np.testing.assert_allclose(F[pl.link_index["y"]], want_y, atol=1e-15)
    np.testing.assert_allclose(X[pl.link_index["y"]], want_y, atol=1e-15)
    np.testing.assert_allclose(F[pl.link_index["a"]], trans_z(1.0) @ pairs[0].transform(np.array([0.3])), atol=1e-15)


@pytest.mark.parametrize("mech", _corpus())
def test_batched_and_plain_products_agree(mech):
    pl = solver.plan(mech)
    scale = np.where(pl.angle_mask, 1.0, pl.size)
    Q = mech.initial_vector() + RNG.uniform(-0.5, 0.5, (9, pl.nv)) * scale
    try:
        X, _, _ = solver.link_poses(pl, Q, world=True)
    except UnsupportedPairError:
        pytest.skip("a pair without a motion")
    F = solver.forward(pl, Q)
    for i in range(len(pl.link_names)):
        np.testing.assert_allclose(F[:, i], X[i], atol=1e-13 * max(1.0, pl.size))
    # the writer places the links of the initial state this way
    W = _forward_poses(mech)
    X0, _, _ = solver.link_poses(pl, mech.initial_vector())
    for name, i in pl.link_index.items():
        np.testing.assert_array_equal(W[name], X0[i])


def test_pairs_without_a_motion():
    """A rolling surface pair is not a function of its values: raise by default, or skip
    the links beyond it, or place them at the identity (the model writer)."""
    plane, sphere = G.Plane(np.eye(4)), G.SphericalSurface(np.eye(4), 0.05)
    links = [Link(n) for n in ("base", "a", "b")]
    pairs = [Pair("R", "revolute", "base", "a", trans_x(0.1), np.eye(4)),
             Pair("H", "rolling_surface", "a", "b", np.eye(4), np.eye(4),
                  params={"surface_1": plane, "surface_2": sphere, "orientation": True})]
    mech = Mechanism("rolling", links, pairs, "base", initial={"R": (0.3,), "H": (0.0, 0.0, 0.1)})
    pl = solver.plan(mech)
    q = mech.initial_vector()
    with pytest.raises(UnsupportedPairError, match="'H'"):
        solver.link_poses(pl, q)
    X, T, skipped = solver.link_poses(pl, q, unsupported="skip")
    assert list(skipped) == [1] and T[1] is None and X[pl.link_index["b"]] is None
    X, T, _ = solver.link_poses(pl, q, unsupported="identity")
    np.testing.assert_array_equal(X[pl.link_index["b"]], X[pl.link_index["a"]])
    assert _forward_poses(mech)["b"].tolist() == X[pl.link_index["a"]].tolist()
