"""The corpus is the same bytes on every machine (p105cli.corpus.digits).

The committed files are checked byte for byte against regeneration in
``test_corpus.py``; here the proof that a last-bit difference of the
computed geometry (another CPU, BLAS or libm) cannot change them: every
computed real is written to 12 significant digits, and its unrounded value
is far from every boundary where the written digits change (the rounding's
and the builder's snapping of round-off noise to 0 or an integer).
"""

from __future__ import annotations

import math
from fractions import Fraction
from functools import lru_cache

import pytest

from conftest import ROOT
import p105cli.part105.builder as builder
from p105cli.corpus import MECHANISMS, PROFILES, file_name, records
from p105cli.corpus.digits import CONSTANT_RECORDS, DIGITS, MARGIN, NearTieError, boundary_distance, significant
from p105cli.step import read_step

CORPUS_DIR = ROOT / "tests" / "data" / "corpus"
CASES = [(m, p) for m in MECHANISMS for p in PROFILES]
IDS = [file_name(m, p) for m, p in CASES]


def _reals(value, out):
    if isinstance(value, float):
        out.append(value)
    elif isinstance(value, list):
        for v in value:
            _reals(v, out)
    elif isinstance(value, dict) and "value" in value:
        _reals(value["value"], out)
    return out


def _computed_reals(data) -> list[float]:
    out = []
    for rec in data:
        if "complex" in rec:
            for part in rec["complex"]:
                _reals(part["args"], out)
        elif rec["type"] not in CONSTANT_RECORDS:
            _reals(rec["args"], out)
    return out


@lru_cache(maxsize=None)
def _unrounded_reals() -> tuple[float, ...]:
    """Every computed real of the corpus as the builder writes it before the rounding."""
    out = []
    for m, p in CASES:
        out += _computed_reals(records(MECHANISMS[m](), p, rounded=False))
    return tuple(sorted(set(out)))


@lru_cache(maxsize=None)
def _raw_reals() -> tuple[float, ...]:
    """Every real the corpus hands the builder, before its tidying (snapping round-off noise
    to 0 or an integer): the values a machine's arithmetic decides."""
    raw = []
    tidy = builder._tidy_real

    def recording(x):
        raw.append(float(x))
        return tidy(x)

    builder._tidy_real = recording
    try:
        for m, p in CASES:
            records(MECHANISMS[m](), p)
    finally:
        builder._tidy_real = tidy
    return tuple(sorted(set(raw)))


def test_significant_rounds_to_twelve_digits():
    assert DIGITS == 12
    assert significant(53.572625767849736) == 53.5726257678
    assert significant(-201.35435557450313) == -201.354355575
    assert significant(0.0) == 0.0 and significant(30.0) == 30.0 and significant(1e-7) == 1e-7
    assert significant(9.99999999999987) == 10.0
    with pytest.raises(ValueError):
        significant(math.inf)


def test_a_near_tie_is_refused():
    tie = 1.000000000005  # the float nearest a tie at the 12th digit
    assert boundary_distance(tie) < Fraction(1, 10**4)
    with pytest.raises(NearTieError):
        significant(tie)
    assert boundary_distance(1.0000000000049) > MARGIN
    assert significant(1.0000000000049) == 1.0


def test_boundary_distance_is_exact():
    assert boundary_distance(0.5) == Fraction(1, 2)
    assert boundary_distance(1.25, digits=2) == 0  # 1.25 is a float: exactly on the tie
    # the float -1.2 is -1.1999999999999999555...: 11.99999... tenths, just under 12
    assert boundary_distance(-1.2, digits=2) == Fraction(1.2) * 10 - 11 - Fraction(1, 2)


def test_every_computed_real_is_far_from_a_rounding_boundary():
    values = _unrounded_reals()
    assert len(values) > 300  # the whole corpus, not a sample
    near = [(x, float(boundary_distance(x))) for x in values if boundary_distance(x) < MARGIN]
    assert not near, f"within {MARGIN} units of the last digit of a rounding boundary: {near}"


def test_a_few_ulps_do_not_change_the_written_digits():
    """What the margins buy, shown directly: +-8 ulps of every raw value give the same digits."""
    def written(x):
        return significant(builder.real(x))

    values = _raw_reals()
    assert len(values) > 400  # the whole corpus, not a sample
    for x in values:
        up = down = x
        for _ in range(8):
            up, down = math.nextafter(up, math.inf), math.nextafter(down, -math.inf)
        assert written(up) == written(down) == written(x), x


def test_no_computed_real_is_near_the_builders_snapping():
    """The builder writes values within 1e-12 of 0 as 0 and within 1e-11 of an integer as it:
    every raw value is at least 10x inside or outside those thresholds."""
    for x in _raw_reals():
        assert not 1e-13 < abs(x) < 1e-11, x
        assert not 1e-12 < abs(x - round(x)) < 1e-10, x


@pytest.mark.parametrize("mechanism,profile", CASES, ids=IDS)
def test_committed_file_holds_the_unrounded_values_to_twelve_digits(mechanism, profile):
    """Every value of the committed file is its unrounded computation to half a unit of the
    12th significant digit (<= 5e-12 relative), everything else is identical."""
    text = (CORPUS_DIR / file_name(mechanism, profile)).read_text(encoding="ascii")
    written = list(read_step(text, file_name(mechanism, profile)).records())
    exact = records(MECHANISMS[mechanism](), profile, rounded=False)
    assert len(written) == len(exact)

    def same(a, b, where):
        if isinstance(b, float):
            assert isinstance(a, float), where
            assert abs(a - b) <= 5e-12 * abs(b), (where, a, b)
        elif isinstance(b, list):
            assert isinstance(a, list) and len(a) == len(b), where
            for x, y in zip(a, b):
                same(x, y, where)
        elif isinstance(b, dict):
            assert isinstance(a, dict) and a.keys() == b.keys(), where
            for k in b:
                same(a[k], b[k], where)
        else:
            assert a == b, where

    for w, e in zip(written, exact):
        same(w, e, f"#{e['id']}")
