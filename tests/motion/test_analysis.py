"""motion/analysis.py: how solve runs an analysis (forward or inverse, and with how many iterations)."""

from __future__ import annotations

import numpy as np

from p105cli.kinematics import solver
from p105cli.kinematics.model import Link, Mechanism, Pair
from p105cli.motion import analysis
from p105cli.motion.analysis import INVERSE_ITERATIONS, Motion, analyse_motion

I4 = np.eye(4)


def _arm():
    return Mechanism("arm", (Link("l0"), Link("l1")), (Pair("A", "revolute", "l0", "l1", I4, I4, actuated=True),),
                     "l0")


def test_forward_runs_block_by_block():
    mech = _arm()
    motion = Motion(None, driven={"A": np.linspace(0.0, 1.0, 10)})
    assert not motion.inverse
    blocks = list(analyse_motion(mech, motion, tol=1e-10, max_iter=30, pl=solver.plan(mech), block=4))
    assert [b.Q.shape[0] for b in blocks] == [4, 4, 2]
    assert np.allclose(np.concatenate([b.Q[:, 0] for b in blocks]), np.linspace(0.0, 1.0, 10))


def test_inverse_gets_more_iterations(monkeypatch):
    mech = _arm()
    seen = {}
    real = solver.solve_path

    def spy(*args, **kw):
        seen.update(kw)
        return real(*args, **kw)
    monkeypatch.setattr(solver, "solve_path", spy)
    c, s = np.cos(0.3), np.sin(0.3)
    pose = np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    motion = Motion(None, poses=pose[None], link="l1")
    (result,) = analyse_motion(mech, motion, tol=1e-10, max_iter=7, pl=solver.plan(mech))
    assert motion.inverse and seen["max_iter"] == INVERSE_ITERATIONS * 7
    assert abs(result.Q[0, 0] - 0.3) < 1e-9
    assert analysis.INVERSE_ITERATIONS == 4   # the documented "inverse analysis: x4" of --max-iter
