"""The solver's loop residual (solver/closure.py, ``(p / size, 2 q_v)``) and the structure
analysis's ``(p, phi)`` (graph.loop_closure) describe one loop closure.

Held equal where they must agree, on every mechanism of the corpus and the examples that
has loops, and on a Bennett linkage and a Stewart platform (overconstrained, many loops):

* the same loop placement ``T_loop`` at any values, so the same zero set: the translations
  differ by the model size exactly, the rotation parts are ``2 sin(|phi|/2) phi/|phi|`` and
  ``phi`` of one rotation;
* at assembled configurations (the initial state, and configurations solved by the
  continuation), Jacobians with the same rank and the same right null space (the finite
  motions), and the rank mobility that ``p105 graph`` reports;
* the Jacobian of each against central differences of its own residual.
"""

from __future__ import annotations

import glob
from pathlib import Path

import numpy as np
import pytest

from kinematics.test_graph import bennett  # the Bennett linkage of the graph tests
from p105cli.kinematics import solver
from p105cli.kinematics.graph import analyse, loop_closure
from p105cli.kinematics.pairs import UnsupportedPairError
from p105cli.part105.read_mechanism import read_mechanisms
from p105cli.step import read_any

ROOT = Path(__file__).resolve().parents[2]
FILES = sorted(glob.glob(str(ROOT / "tests/data/corpus/*.stp")) + glob.glob(str(ROOT / "examples/*.stp")))


def _corpus():
    out = []
    for fn in FILES:
        doc = read_any(Path(fn).read_text(), fn)
        for m in read_mechanisms(doc):
            out.append(pytest.param(m, id=f"{Path(fn).stem}:{m.name}"))
    out.append(pytest.param(bennett(), id="bennett"))
    return out


def _both(mech, Q):
    st = analyse(mech)
    pl = solver.plan(mech)
    assert [[(pl.pair_names[k], f) for k, f in lp] for lp in pl.loops] == st.loops
    rg, Jg = loop_closure(mech, st, Q)
    rs, Js = solver.closure(pl, Q)
    return st, pl, rg, Jg, rs, Js


def _loop_pair_columns(pl):
    return pl.loop_values()


def _null_projector(J, rank):
    _, s, Vt = np.linalg.svd(J)
    N = Vt[rank:].T
    return N @ N.T


@pytest.mark.parametrize("mech", _corpus())
def test_one_loop_placement_one_zero_set(mech):
    """At random values (far from assembled), both residuals come from the same T_loop."""
    if not analyse(mech).loops:
        pytest.skip("a tree: no loop")
    rng = np.random.default_rng(7)
    q0 = mech.initial_vector()
    Q = q0 + rng.uniform(-0.4, 0.4, size=(16, q0.size)) * np.where(solver.plan(mech).angle_mask, 1.0, mech.size())
    Q = np.vstack([q0, Q])
    try:
        st, pl, rg, Jg, rs, Js = _both(mech, Q)
    except UnsupportedPairError:
        pytest.skip("a pair of a loop has no motion")
    L = len(pl.loops)
    rg, rs = rg.reshape(-1, L, 6), rs.reshape(-1, L, 6)
    np.testing.assert_allclose(rs[..., :3] * pl.size, rg[..., :3], rtol=1e-12, atol=1e-13 * pl.size)
    phi = rg[..., 3:]
    ang = np.linalg.norm(phi, axis=-1, keepdims=True)
    expect = 2.0 * np.sin(ang / 2.0) * np.divide(phi, ang, out=np.zeros_like(phi), where=ang > 0)
    np.testing.assert_allclose(rs[..., 3:], expect, atol=1e-12)
    # the same zero set: the initial (assembled) state closes both, a displaced state neither
    tol = 1e-9
    closed_g = np.abs(rg[..., :3]).max(axis=(1, 2)) / pl.size <= tol
    closed_g &= np.abs(rg[..., 3:]).max(axis=(1, 2)) <= tol
    closed_s = np.abs(rs).max(axis=(1, 2)) <= tol
    assert closed_g[0] and closed_s[0]
    np.testing.assert_array_equal(closed_g, closed_s)


def _solved(mech, pl):
    """The initial state, and configurations the continuation solved (the first loop pair
    with one value driven by up to 0.3 rad or 0.05 model sizes)."""
    q0 = mech.initial_vector()
    out = [q0]
    for lp in pl.loops:
        for k, _ in lp:
            if pl.types[k].value_count == 1:
                d = 0.3 if pl.angle_mask[pl.slices[k].start] else 0.05 * pl.size
                res = solver.solve_motion(mech, {pl.pair_names[k]: q0[pl.slices[k].start] + np.linspace(0, d, 4)})
                out += [res.Q[i] for i in range(1, 4) if res.status[i] == "ok"]
                return np.array(out)
    return np.array(out)


@pytest.mark.parametrize("mech", _corpus())
def test_same_rank_and_motions_at_assembled_configurations(mech):
    st = analyse(mech)
    if not st.loops:
        pytest.skip("a tree: no loop")
    if st.mobility is None:
        pytest.skip("a pair of a loop has no motion")
    pl = solver.plan(mech)
    Q = _solved(mech, pl)
    st, pl, rg, Jg, rs, Js = _both(mech, Q)
    cols = _loop_pair_columns(pl)
    scale = np.where(pl.angle_mask, 1.0, pl.size)[cols]
    for b in range(Q.shape[0]):
        assert np.abs(rs[b]).max() < 1e-8
        G = Jg[b][:, cols] * scale
        G[np.arange(G.shape[0]) % 6 < 3] /= pl.size
        S = Js[b][:, cols] * scale
        sg, ss = np.linalg.svd(G, compute_uv=False), np.linalg.svd(S, compute_uv=False)
        rank_g = int(np.sum(sg > 1e-8 * sg[0]))
        rank_s = int(np.sum(ss > 1e-8 * ss[0]))
        assert rank_g == rank_s
        # no singular value near the threshold: the rank is not a matter of round-off
        assert np.all((sg > 1e-6 * sg[0]) | (sg < 1e-11 * sg[0]))
        np.testing.assert_allclose(_null_projector(G, rank_g), _null_projector(S, rank_s), atol=1e-8)
        if b == 0:
            # graph's mobility: freedoms minus this rank (all loops lie in one component here,
            # plus the freedoms of pairs on no loop, which add to both alike)
            assert st.rank == rank_s
            assert st.mobility == mech.value_count - rank_s + 6 * sum(c.floating for c in st.components)
            assert st.redundant_constraints == 6 * len(pl.loops) - rank_s


@pytest.mark.parametrize("mech", _corpus())
def test_each_jacobian_is_its_residuals_derivative(mech):
    st = analyse(mech)
    if not st.loops or st.mobility is None:
        pytest.skip("no loop, or a loop pair without motion")
    pl = solver.plan(mech)
    rng = np.random.default_rng(3)
    q = mech.initial_vector() + rng.uniform(-0.2, 0.2, mech.value_count) * np.where(pl.angle_mask, 1.0, pl.size)
    h = 1e-6
    st, pl, rg, Jg, rs, Js = _both(mech, q[None])
    for i in pl.loop_values():
        e = np.zeros_like(q)
        e[i] = h * (1.0 if pl.angle_mask[i] else pl.size)
        fg = (loop_closure(mech, st, q + e)[0] - loop_closure(mech, st, q - e)[0]) / (2 * e[i])
        fs = (solver.closure(pl, q + e)[0][0] - solver.closure(pl, q - e)[0][0]) / (2 * e[i])
        np.testing.assert_allclose(Jg[0][:, i], fg, atol=1e-6 * max(1.0, pl.size))
        np.testing.assert_allclose(Js[0][:, i], fs, atol=1e-6)
