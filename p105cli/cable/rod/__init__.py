"""Discrete Kirchhoff rod for cable statics (the default cable model).

Model (docs/cable-rod.md has the derivation, the measured order and the limits)
------------------------------------------------------------------------------

An inextensible, unshearable rod of length ``L`` with bending stiffnesses
``A`` (about the section's x axis), ``B`` (about y) and torsional stiffness
``C`` (about the tangent z), loaded by a constant distributed weight ``f``
(N/m, world) and optional dead point forces at free ends. Nodes
``s_0 = 0 < ... < s_n = L`` (uniform, or graded towards the ends) carry
orientations ``q_k`` (unit quaternions wxyz, body to world, z axis = tangent
``d3``) and positions ``x_k``. The potential

    E = sum_i (2/h_i) V_i^T K V_i  -  sum_k w_k f . x_k  -  F_end . x_n

(``V_i`` = vector part of ``conj(q_i) q_{i+1}``, so ``2 V_i / h_i`` is the
cell's Darboux vector; ``w_k`` trapezoid weights) is made stationary subject
to ``c_i = x_{i+1} - x_i - (h_i/2)(d3_i + d3_{i+1}) = 0`` with multipliers
``mu_i`` = the internal force at the cell midpoints. Midpoint energy and
trapezoid centreline on full cells: a symmetric scheme, error ~ h^2 with an
even expansion, so Richardson extrapolation (n, 2n) gives h^4.

Solver: Newton on the KKT system with body-frame rotation increments
(``q <- q exp(theta/2)``) and exact second derivatives. Forces and positions
are eliminated, leaving a block-tridiagonal rotation system bordered by three
end-position rows: LAPACK ``dgbsv``, O(n) (the full interleaved KKT matrix,
band 11, is the fallback). The constrained Hessian's inertia is checked by a
banded Cholesky of ``H + rho C^T C`` (Finsler's lemma); when it fails the
rotation block is shifted (Levenberg-Marquardt, the trust-region dual), near
non-minimal stationary points the step follows the negative curvature
direction. Steps are capped at ``MAX_TURN`` rad per node and accepted on
residual decrease or by backtracking on an exact-penalty merit. Warm starts on
a key-point path extrapolate the previous solutions (quadratically from three),
so one Newton step per key point and mesh suffices. At these sizes the cost is
the number of numpy calls, so the per-step work is written as few, large array
operations (quadratic-form tensors, cached mesh data).

Conventions: see :class:`RodProblem` and :class:`RodSolution`. SI units.

The package follows the solver's seams: ``problem`` (types, validation,
reversal, symmetric families), ``quaternions`` (rotation helpers, to move to
``kinematics/spatial``), ``banded`` (LAPACK band storage), ``model`` (the
discrete model), ``guess`` (initial guesses), ``newton``, ``continuation``
(one mesh size, warm and cold) and ``solve`` (``solve_rod``: mesh pairs and
Richardson extrapolation).
"""

from .model import auto_grading
from .newton import MAX_TURN
from .problem import END_KINDS, RodProblem, RodSolution
from .solve import solve_rod, state_from_frames

__all__ = ["RodProblem", "RodSolution", "solve_rod", "state_from_frames", "auto_grading", "END_KINDS",
           "MAX_TURN"]
