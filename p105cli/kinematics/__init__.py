"""Kinematics science modules: plain numpy code, no CLI.

- :mod:`p105cli.kinematics.placements` -- homogeneous transforms and the
  placement methods of ISO 10303-105 (axis2_placement_3d, su_parameters,
  ypr_rotation, rotation_about_direction) plus labelled conversions
  (quaternions, Euler and Cardan angles).

Modules are imported explicitly (``from p105cli.kinematics import placements``)
so that importing the package costs nothing.
"""
