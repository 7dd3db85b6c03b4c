"""A position analysis along a motion, as ``p105 solve`` runs it: forward along driven
values, or inverse along target poses of a link frame.

The policy of a run lives here, not in the CLI: an inverse analysis solves one pose
from the previous one by damped Newton, which needs more iterations than closing a
loop, so it gets :data:`INVERSE_ITERATIONS` times the iterations per configuration.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

__all__ = ["INVERSE_ITERATIONS", "Motion", "analyse_motion"]

#: Newton iterations per configuration of an inverse analysis, per iteration of a forward one.
INVERSE_ITERATIONS = 4


@dataclass(frozen=True)
class Motion:
    """What to analyse: the times ``t`` (None: not given) and either ``driven`` pair values
    (forward; ``{pair or (pair, j): (N,) or (N, k) SI}``) or ``poses`` (N, 4, 4) of
    ``link``'s ``frame`` (4x4 in link coordinates, None: the link frame; ``frame_name``
    as the user named it)."""

    t: Optional[np.ndarray]
    driven: Optional[dict] = None
    poses: Optional[np.ndarray] = None
    link: Optional[str] = None
    frame: Optional[np.ndarray] = None
    frame_name: Optional[str] = None

    @property
    def inverse(self) -> bool:
        return self.poses is not None


def analyse_motion(mech, motion: Motion, *, tol: float, max_iter: int, pl, block=None, branch=None):
    """The analysis results block by block (an inverse analysis is one block): forward by
    :func:`~p105cli.kinematics.solver.iter_motion` (``block`` configurations at a time,
    None: all; ``branch`` the assembly to track), inverse by
    :func:`~p105cli.kinematics.solver.solve_path`. Errors of the request
    (:class:`~p105cli.kinematics.solver.SolveError`) come with the first block."""
    from p105cli.kinematics import solver

    if motion.inverse:
        yield solver.solve_path(mech, motion.link, motion.poses, frame=motion.frame, tol=tol,
                                max_iter=INVERSE_ITERATIONS * max_iter, pl=pl)
        return
    yield from solver.iter_motion(mech, motion.driven, tol=tol, max_iter=max_iter, pl=pl, block=block,
                                  branch=branch)
