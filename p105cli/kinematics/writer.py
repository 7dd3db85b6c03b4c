"""Moved: :mod:`p105cli.part105.write_mechanism` (and ``part105.emit``, ``part105.convert``).

Kept for importers outside p105cli while they move; p105cli itself imports the new home.
"""

from p105cli.part105.write_mechanism import PROFILES, SUPPORTED_KINDS, write_mechanism  # noqa: F401

__all__ = ["PROFILES", "write_mechanism", "SUPPORTED_KINDS"]
