"""The written digits of the corpus's computed reals: the same on every machine.

The corpus computes its geometry (solved link poses, pair values measured
from them, unit directions); on another CPU or libm a computed real can
differ in its last bit, and the shortest round-trip text of a float would
show it. So every real of a corpus record is written to :data:`DIGITS`
significant digits (correctly rounded, half to even), and
:func:`significant` refuses a value whose unrounded form lies within
:data:`MARGIN` units of the last kept digit of a rounding boundary: for
every value it accepts, a last-bit change cannot change the digits written
(an ulp is at most about 2.2e-4 of such a unit at 12 digits, so the margin
is at least 4.5 ulps).

Written constants are not computed and keep their digits: the degree's
conversion factor (``plane_angle_measure_with_unit``, 15 digits as CAD
systems write it) is left as it is.
"""

from __future__ import annotations

from decimal import Decimal
from fractions import Fraction
import math

#: Significant digits of every computed real in a corpus file.
DIGITS = 12

#: Least distance of an unrounded value from a rounding boundary, in units of the last kept digit.
MARGIN = 1e-3

#: Records whose reals are written constants, not computed values.
CONSTANT_RECORDS = frozenset({"plane_angle_measure_with_unit"})


class NearTieError(ValueError):
    """A computed real lies so close to a rounding boundary that its written digits could
    depend on the machine (change the mechanism's data, not the rounding)."""


def boundary_distance(x: float, digits: int = DIGITS) -> Fraction:
    """Exact distance of ``x`` from the nearest rounding boundary at ``digits``
    significant digits, in units of the last kept digit (0 at a tie, 1/2 at most)."""
    if x == 0.0:
        return Fraction(1, 2)
    shift = digits - 1 - Decimal(x).adjusted()  # exact: Decimal(float) does not round
    scaled = abs(Fraction(x)) * Fraction(10) ** shift
    return abs(scaled - math.floor(scaled) - Fraction(1, 2))


def significant(x: float, digits: int = DIGITS, margin: float = MARGIN) -> float:
    """``x`` rounded to ``digits`` significant digits; :class:`NearTieError` when it is
    within ``margin`` units of the last kept digit of a rounding boundary."""
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"{x!r} cannot be written to Part 21")
    if boundary_distance(x, digits) < margin:
        raise NearTieError(f"{x!r} is within {margin} units of the {digits}th significant digit "
                           "of a rounding boundary")
    return float(f"{x:.{digits - 1}e}")


def round_value(value):
    """A JSON-model value with every real rounded by :func:`significant` (ints, strings,
    enumerations, references and ``*`` unchanged)."""
    if isinstance(value, float):
        return significant(value)
    if isinstance(value, list):
        return [round_value(v) for v in value]
    if isinstance(value, dict) and "type" in value and "value" in value:
        return {**value, "value": round_value(value["value"])}
    return value


def round_records(data: list[dict]) -> list[dict]:
    """The records with their computed reals rounded (see the module docstring)."""
    out = []
    for rec in data:
        if "complex" in rec:
            out.append({**rec, "complex": [{**part, "args": round_value(part["args"])} for part in rec["complex"]]})
        elif rec["type"] in CONSTANT_RECORDS:
            out.append(rec)
        else:
            out.append({**rec, "args": round_value(rec["args"])})
    return out
