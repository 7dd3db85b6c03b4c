"""Motion representation (ISO 10303-105 clauses 6 and 7): kinematic paths and
configuration interpolation, sampled at parameter values.

- :mod:`p105cli.motion.paths` -- schema-neutral paths of a link frame
  (point-to-point, linear, circular, curve-based segments; composite paths)
  and their vectorised sampling (translations as the segment type says,
  rotations by slerp, synchronised on one parameter).
- :mod:`p105cli.motion.configurations` -- configuration interpolation
  sequences (pair values over t) and their sampling.
- :mod:`p105cli.motion.sampling` -- the records of ``p105 interpolate``.

Both are read from a Part 21 / JSON model by :mod:`p105cli.part105.motion` (AP242 path
entities; both layouts' configuration sequences).

Plain numpy; nothing here imports click.
"""
