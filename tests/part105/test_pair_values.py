"""part105/pair_values.py and PairValueReader: pair values in SI, keyed by THE pair names,
read without reading the mechanisms again."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from p105cli.part105 import read_mechanism as rm
from p105cli.part105.model_file import ModelFile
from p105cli.step import read_step
from p105cli.step.errors import ModelError

ROOT = Path(__file__).resolve().parents[2]
FOUR_BAR = ROOT / "examples" / "four_bar_ap242.stp"
DEG = math.pi / 180.0


def _mf():
    return ModelFile.of(read_step(FOUR_BAR.read_text(), str(FOUR_BAR)))


def test_values_in_si_by_pair_name():
    # '#212..#215': configuration 1, written in degrees (the link contexts' plane-angle unit)
    got = rm.PairValueReader(_mf()).values([212, 213, 214, 215])
    assert list(got) == ["A", "B", "C", "D"]
    for name, deg in zip("ABCD", (90.0, -23.61873693652273, 44.41530859719298, 110.79657166067024)):
        assert got[name] == pytest.approx((deg * 0.0174532925199433,), rel=1e-15)
    assert rm.PairValueReader(_mf()).kinds == {n: "revolute" for n in "ABCD"}


def test_values_do_not_read_the_mechanisms_again(monkeypatch):
    mf = _mf()

    def no(*_a, **_k):
        raise AssertionError("the mechanism reader ran")

    monkeypatch.setattr(rm._Reader, "mechanisms", no)
    values = rm.PairValueReader(mf)
    assert values.values([207])["A"] == pytest.approx((30.0 * 0.0174532925199433,))
    assert set(mf.cached("read_mechanism.pairs", dict)) == {182}  # only the pair asked about


def test_the_mechanism_reader_and_the_value_reader_agree():
    mf = _mf()
    (mech,) = rm.read_mechanisms(mf)
    got = rm.PairValueReader(mf).values([207, 208, 209, 210])
    assert got == {k: tuple(v) for k, v in mech.initial.items()}


def test_a_value_of_no_pair_of_a_mechanism_is_an_error():
    mf = _mf()
    with pytest.raises(ModelError) as e:
        rm.PairValueReader(mf).values([211])  # a state, not a pair value
    assert e.value.message.startswith("#211:")
