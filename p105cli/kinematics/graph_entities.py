"""Moved to :mod:`p105cli.part105.topology` (``graph --enrich`` entities). This re-export keeps
``cli/graph.py``'s import working until the integrator switches it; it goes then."""

from ..part105.topology import EnrichError, enrich  # noqa: F401

__all__ = ["EnrichError", "enrich"]
