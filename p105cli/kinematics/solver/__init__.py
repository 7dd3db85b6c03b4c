"""Position analysis of mechanisms: forward analysis of trees and closed loops, inverse analysis.

Everything here is SI (metres, radians) and batched over configurations
(leading axes). Nothing imports click.

Forward analysis (:func:`solve_motion`, :func:`iter_motion`)
-----------------------------------------------------------

The mechanism's links are placed by a spanning tree from the base link
(:func:`plan`, from :func:`p105cli.kinematics.graph.topology`). A tree is
evaluated for every configuration at once (:func:`forward`): one batched
4x4 product per pair, in tree order.

Each independent loop (a chord of the tree plus the tree path back) must
close: the product of the pair transforms around it,
``T_loop = A_1 ... A_n`` (``A_k = T_link1_link2`` traversed forward, its
inverse backwards), must be the identity. The residual of a loop is
``(p / size, 2 q_v)`` of ``T_loop = [R, p]``, ``(q_w >= 0, q_v)`` the
quaternion of ``R`` (zero only at the identity; lengths divided by the
model size, so the same mechanism in millimetres and in metres takes the
same steps). Its Jacobian is analytic: the spatial twist of factor k in
the loop's start frame is ``Ad(A_1 ... A_{k-1}) xi_k`` with
``xi_k = Ad(P1 M) J_body`` forward and ``-Ad(P2) J_body`` backwards
(``J_body`` from :mod:`p105cli.kinematics.pairs`), and a spatial twist
``(v, w)`` changes the residual by ``(v + w x p) / size`` and
``q_w w + w x q_v``.

The unknowns are the values of the pairs in loops that are not driven.
Newton steps are least-squares steps with a round-off-level
regularisation (minimum norm where the Jacobian has lost rank), so
redundant constraints (a planar loop in 3D: 6 equations, rank 3; a
Bennett linkage) and remaining mobility are handled alike. A closing
Newton step from the last evaluation takes the values from the tolerance
to round-off.

Continuation and branches. The initial state is assembled first (its
driven values held, the rest by Levenberg-Marquardt); its assembly branch
is tracked along the input sequence. The branch invariant is the sign of
``det(U0^T J_u V0)``: the passive Jacobian reduced onto rank-r bases of
its column and row spaces, re-anchored (Procrustes-aligned) at every
accepted configuration. It can only change sign where the passive
Jacobian loses rank (a dead centre or a bifurcation), so a sign change
between two accepted configurations is a branch change and never accepted
silently. Configurations are solved in chunks from a tangent predictor
(``dq_u = -J_u^+ J_d dd``); a solution is accepted only if Newton
converged, the configuration is regular, the sign is the tracked one and
it lies where the first-order step from its predecessor puts it (up to
that step's size: a jump to another branch at a bifurcation is as large);
otherwise the chunk shrinks, and a single step is halved (down to 1/4096)
before the configuration is diagnosed: ``singular`` (converged with the
passive Jacobian rank-deficient: a dead centre; or a bifurcation passed
between two samples), ``branch_change`` (only the other branch could be
reached: the new branch is tracked from then on), ``not_assemblable``
(the least-squares residual stalls above the tolerance: reported with
it), ``not_converged``. The invariant is +1 at the initial assembly (the
bases are its singular vectors); ``branch=-1`` starts instead from another
assembly at the same driven values with invariant -1 (in those bases),
found by a deterministic multi-start Levenberg-Marquardt
(:func:`_other_assembly`).

Inverse analysis (:func:`solve_path`)
-------------------------------------

A link frame follows prescribed poses: damped least squares on the pose
error (position of the frame's origin in metres, rotation vector in
radians, world axes), analytic geometric Jacobians, the damping raised
only near singular configurations (so the answer is the exact one away
from them and finite through them), warm started along the path.

Layout
------

``plan.py`` (:class:`Plan`, the compiled mechanism; value scales and ranges),
``forward.py`` (pair transforms and link placements: the only forward
kinematics), ``closure.py`` (the only loop residual and Jacobian, also read by
:mod:`p105cli.kinematics.graph` for mobility), ``assembly.py`` (Newton,
continuation, branches: :func:`solve_motion`, :func:`iter_motion`),
``inverse.py`` (:func:`solve_path`).
"""

from __future__ import annotations

from .assembly import MotionResult, _Loops, iter_motion, solve_motion  # noqa: F401
from .closure import closure, loop_errors, loop_twists, root_loop_twists
from .forward import forward, link_poses, pair_transform
from .inverse import PathResult, _chain, solve_path  # noqa: F401
from .plan import STATUSES, BranchUndefined, Plan, SolveError, angle_value_mask, plan

__all__ = ["Plan", "plan", "forward", "link_poses", "pair_transform", "closure", "loop_twists",
           "root_loop_twists", "loop_errors",
           "MotionResult", "solve_motion", "iter_motion", "PathResult", "solve_path",
           "angle_value_mask", "STATUSES", "SolveError", "BranchUndefined"]
