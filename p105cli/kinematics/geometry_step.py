"""Moved to :mod:`p105cli.part105.geometry` (Part 42 instances <-> geometry objects). This
re-export keeps ``kinematics/writer.py`` and ``kinematics/motion_io.py`` working until the
integrator switches them; it goes then."""

from ..part105.geometry import *  # noqa: F401,F403
from ..part105.geometry import __all__  # noqa: F401
from ..part105.geometry import placement_from_instance, point_from_instance  # noqa: F401
