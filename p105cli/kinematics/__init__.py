"""Kinematics science modules: plain numpy code, no CLI.

- :mod:`p105cli.kinematics.spatial` -- the one rotation algebra: homogeneous
  transforms, inverse, hat/vee/adjoint, rotation vector, quaternions, slerp.
- :mod:`p105cli.kinematics.placements` -- the placement methods of ISO 10303-105
  on it (axis2_placement_3d, su_parameters, ypr_rotation,
  rotation_about_direction) plus labelled Euler and Cardan conversions.
- :mod:`p105cli.kinematics.model`, :mod:`~p105cli.kinematics.pairs`,
  :mod:`~p105cli.kinematics.solver`, :mod:`~p105cli.kinematics.graph`,
  :mod:`~p105cli.kinematics.geometry`, :mod:`~p105cli.kinematics.dh`.

Nothing here imports the package outside ``kinematics`` (no file, schema or rule
knowledge: that is ``part105``'s).

Modules are imported explicitly (``from p105cli.kinematics import placements``)
so that importing the package costs nothing.
"""
