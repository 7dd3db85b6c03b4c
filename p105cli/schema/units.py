"""Units of a representation context: length and plane-angle units reduced to SI factors.

``context_units(pop, context_id) -> ContextUnits`` reads a ``global_unit_assigned_context``:
each of its length and plane-angle units is reduced to an SI factor (``si_unit`` with its
prefix; ``conversion_based_unit`` chains through ``conversion_factor.value_component`` x
``unit_component``, e.g. DEGREE = pi/180 rad, INCH = 25.4 x 1 mm; each step must be a unit of
the same kind and the chain must end in the metre or the radian). What cannot be reduced is
kept as a problem ``(severity, instance id, message)`` for the validator to report and for the
model readers to raise; ``UnitReader`` caches the contexts of one population.

ISO 10303-105 5.2.5 (units of a mechanism's representations) is checked by ``rules.kinematics``
on top of this; the mechanism reader converts every length and angle with it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

from ..step.values import refs_in
from .values import enum, number, ref, untyped

__all__ = ["LENGTH", "ANGLE", "SI_PREFIX", "KIND_SYMBOL", "ContextUnits", "UnitReader", "context_units"]

LENGTH, ANGLE = "length", "plane-angle"
#: the EXPRESS type a unit of each kind is an instance of
KIND_TYPE = {LENGTH: "length_unit", ANGLE: "plane_angle_unit"}
#: the SI unit (si_unit_name) each kind's conversion chain must end in
KIND_SI = {LENGTH: "METRE", ANGLE: "RADIAN"}
KIND_SYMBOL = {LENGTH: "m", ANGLE: "rad"}

SI_PREFIX = {
    "EXA": 1e18, "PETA": 1e15, "TERA": 1e12, "GIGA": 1e9, "MEGA": 1e6, "KILO": 1e3,
    "HECTO": 1e2, "DECA": 1e1, "DECI": 1e-1, "CENTI": 1e-2, "MILLI": 1e-3, "MICRO": 1e-6,
    "NANO": 1e-9, "PICO": 1e-12, "FEMTO": 1e-15, "ATTO": 1e-18,
}

# severities of unit problems, the validator's words
ERROR, WARNING = "error", "warning"


@dataclass
class ContextUnits:
    """Length and plane-angle units of one representation context.

    ``length``/``angle``: ``(si_factor, label, unit_id)`` or None (no such
    unit, or one that could not be reduced to an SI factor); ``count``: how
    many units of each kind the context assigns; ``assigned``: the context
    is a ``global_unit_assigned_context``; ``problems``: ``(severity,
    entity, message)`` for units that are ambiguous or wrong."""

    context: Optional[int]
    assigned: bool = False
    length: Optional[tuple] = None
    angle: Optional[tuple] = None
    count: dict = field(default_factory=lambda: {LENGTH: 0, ANGLE: 0})
    problems: list = field(default_factory=list)

    def unit(self, kind: str) -> Optional[tuple]:
        return self.length if kind == LENGTH else self.angle

    def factor(self, kind: str) -> Optional[float]:
        u = self.unit(kind)
        return None if u is None else u[0]


class UnitError(Exception):
    """A unit with no SI factor: ``severity``, the ``entity`` at fault and a message."""

    def __init__(self, severity, entity, message):
        super().__init__(message)
        self.severity = severity
        self.entity = entity
        self.message = message


class UnitReader:
    """The units of the contexts of one population, each context read once."""

    def __init__(self, pop):
        self.pop = pop
        self._units: dict = {}

    # lenient access: a unit chain that is broken is a problem to report, not an exception
    def _types(self, i) -> frozenset:
        try:
            return self.pop.types_of(i)
        except (KeyError, TypeError):
            return frozenset()

    def _get(self, i, attr):
        try:
            return self.pop.instance(i).get(attr)
        except Exception:  # noqa: BLE001 - no such attribute / instance: absent
            return None

    def context_units(self, ctx: Optional[int]) -> ContextUnits:
        cu = self._units.get(ctx)
        if cu is not None:
            return cu
        cu = self._units[ctx] = ContextUnits(ctx)
        if ctx is None or ctx not in self.pop:
            return cu
        if "global_unit_assigned_context" not in self._types(ctx):
            return cu
        cu.assigned = True
        units = refs_in(self._get(ctx, "units") or [], [])
        for kind in (LENGTH, ANGLE):
            found = [u for u in dict.fromkeys(units) if KIND_TYPE[kind] in self._types(u)]
            cu.count[kind] = len(found)
            if len(found) > 1:
                cu.problems.append((ERROR, ctx, f"context #{ctx} assigns {len(found)} {kind} "
                                    f"units ({', '.join(f'#{u}' for u in found)}); exactly one "
                                    "is needed to read the pair values (5.2.5, 5.5.7)"))
                continue
            if not found:
                continue
            try:
                factor, label = self.unit_factor(found[0], kind, ())
            except UnitError as e:
                cu.problems.append((e.severity, e.entity, e.message))
                continue
            if kind == LENGTH:
                cu.length = (factor, label, found[0])
            else:
                cu.angle = (factor, label, found[0])
        return cu

    def unit_factor(self, u: int, kind: str, chain: tuple = ()) -> tuple:
        """(SI factor, label) of unit ``#u`` of kind ``kind``; UnitError if it has none."""
        if u in chain:
            raise UnitError(ERROR, chain[0], f"conversion-based unit #{chain[0]} loops back to "
                            f"#{u}; its {kind} factor is undefined")
        t = self._types(u)
        if KIND_TYPE[kind] not in t:
            at = chain[-1] if chain else u
            raise UnitError(ERROR, at, f"#{at}'s conversion factor is given in #{u}, which is not "
                            f"a {kind} unit")
        if "si_unit" in t:
            name = enum(self._get(u, "si_unit.name"))
            prefix = enum(self._get(u, "si_unit.prefix"))
            if name != KIND_SI[kind]:
                raise UnitError(ERROR, u, f"{kind} unit #{u} is the SI unit .{name}., not "
                                f".{KIND_SI[kind]}.")
            f = SI_PREFIX.get(prefix, 1.0) if prefix else 1.0
            return f, f"{(prefix or '').lower()}{name.lower()}"
        if "conversion_based_unit" in t:
            cname = untyped(self._get(u, "conversion_based_unit.name"))
            shown = f"'{cname}'" if isinstance(cname, str) else f"#{u}"
            mwu = ref(self._get(u, "conversion_factor"))
            if mwu is None or mwu not in self.pop:
                raise UnitError(ERROR, u, f"conversion-based unit {shown} #{u} has no conversion "
                                "factor")
            value = number(self._get(mwu, "value_component"))
            base = ref(self._get(mwu, "unit_component"))
            if value is None or not math.isfinite(value) or value <= 0.0:
                raise UnitError(ERROR, u, f"conversion-based unit {shown} #{u}: conversion factor "
                                f"#{mwu} has value_component {value!r}, not a positive number")
            if base is None or base not in self.pop:
                raise UnitError(ERROR, u, f"conversion-based unit {shown} #{u}: conversion factor "
                                f"#{mwu} has no unit_component")
            f, _ = self.unit_factor(base, kind, chain + (u,))
            factor = value * f
            if not (math.isfinite(factor) and factor > 0.0 and math.isfinite(1.0 / factor)):
                # values are converted both ways: a factor or its inverse beyond the reals is unusable
                raise UnitError(ERROR, u, f"conversion-based unit {shown} #{u}: its SI factor "
                                f"{value!r} x {f!r} cannot convert {kind} values (it or its inverse is beyond "
                                "the range of reals)")
            return factor, (cname.lower() if isinstance(cname, str) else f"#{u}")
        what = ("context_dependent_unit" if "context_dependent_unit" in t else
                "+".join(sorted(self.pop.leaf_types_of(u))))
        raise UnitError(WARNING, u, f"{kind} unit #{u} ({what}) has no SI conversion; "
                        f"{kind} values in its context cannot be compared with others")


def context_units(pop, context_id: Optional[int]) -> ContextUnits:
    """The length and plane-angle units of representation context ``#context_id``."""
    return UnitReader(pop).context_units(context_id)
