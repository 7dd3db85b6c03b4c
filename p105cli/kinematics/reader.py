"""Moved to :mod:`p105cli.part105.read_mechanism` (the mechanism reader, on
:class:`~p105cli.part105.model_file.ModelFile` and :mod:`p105cli.part105.layout`). This
re-export keeps ``kinematics/writer.py``, ``kinematics/motion_io.py``, ``cli/`` and
``motion/sampling.py`` working until the integrator switches their imports; it goes then."""

from ..part105.catalogue import HIGHER_PAIR_ENTITIES, pair_kind_of_entity  # noqa: F401
from ..part105.read_mechanism import PairValueReader, population, read_mechanism, read_mechanisms  # noqa: F401
# the units the old reader exposed (motion_io reads a context's length unit through here)
from ..schema.units import ANGLE, LENGTH, ContextUnits, context_units  # noqa: F401

__all__ = ["read_mechanisms", "read_mechanism", "PairValueReader", "population", "HIGHER_PAIR_ENTITIES",
           "pair_kind_of_entity"]
