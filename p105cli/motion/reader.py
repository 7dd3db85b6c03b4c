"""Moved to :mod:`p105cli.part105.motion` (paths and configuration sequences read from a model
file; :mod:`p105cli.motion` keeps the sampling maths). This re-export keeps ``cli/solve.py`` and
``motion/sampling.py`` working until the integrator switches their imports; it goes then."""

from ..part105.motion import MotionReadResult, read_configuration_sequences, read_paths  # noqa: F401

__all__ = ["read_paths", "read_configuration_sequences", "MotionReadResult"]
