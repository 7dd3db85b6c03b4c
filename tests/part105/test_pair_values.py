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
    for name, deg in zip("ABCD", (90.0, -23.6187369365, 44.4153085972, 110.796571661)):  # as written
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


# ------------------------------------------------------------------ low_order_kinematic_pair_value on any low-order pair

#: A serial AP242 chain, one pair of each kind whose value a low_order_kinematic_pair_value can
#: give, and a screw pair (a motion-coupled pair: it has no low-order freedoms).
CHAIN_VALUES = {"revolute": (0.3,), "prismatic": (0.012,), "cylindrical": (0.02, -0.4),
                "spherical": (0.3, -0.2, 0.5), "universal": (0.25, -0.35), "planar": (0.7, 0.01, -0.02),
                "screw": (0.6,)}


def _to_components(kind, args):
    """A named pair value's own arguments (file units) as the six components (tx, ty, tz, rx,
    ry, rz) a low_order_kinematic_pair_value gives: written out per kind from the pair
    definitions (AP242: the prismatic pair slides along x; spherical yaw, pitch, roll are the
    rotations about z, y, x; the universal pair turns about z, then about x; planar_pair_value
    lists the rotation first)."""
    if kind == "revolute":
        return (0.0, 0.0, 0.0, 0.0, 0.0, args[0])
    if kind == "prismatic":
        return (args[0], 0.0, 0.0, 0.0, 0.0, 0.0)
    if kind == "cylindrical":
        return (0.0, 0.0, args[0], 0.0, 0.0, args[1])
    if kind == "spherical":
        yaw, pitch, roll = args[0]["value"]
        return (0.0, 0.0, 0.0, roll, pitch, yaw)
    if kind == "universal":
        return (0.0, 0.0, 0.0, args[1], 0.0, args[0])
    if kind == "planar":
        return (args[1], args[2], 0.0, 0.0, 0.0, args[0])
    return (0.0, 0.0, 0.0, 0.0, 0.0, args[0])  # screw: refused by the reader


def _chain_doc(edit_kinds=(), locked=None):
    """The chain written by p105 in AP242; the values of ``edit_kinds`` rewritten as
    low_order_kinematic_pair_value (``locked``: {kind: (component, value)} added)."""
    import numpy as np

    from p105cli.kinematics.model import Link, Mechanism, Pair
    from p105cli.kinematics.spatial import trans_z
    from p105cli.part105.write_mechanism import write_mechanism

    params = {"prismatic": {"layout": "ap242"}, "screw": {"pitch": 0.004}, "universal": {"input_skew_angle": None}}
    links = [Link(f"L{i}") for i in range(len(CHAIN_VALUES) + 1)]
    pairs = [Pair(k, k, f"L{i}", f"L{i + 1}", trans_z(0.05 * (i + 1)), np.eye(4), params=params.get(k, {}))
             for i, k in enumerate(CHAIN_VALUES)]
    doc, _ = write_mechanism(Mechanism("chain", links, pairs, "L0", initial=CHAIN_VALUES), "ap242")
    ids = {}
    for r in doc.records():
        kind = r.get("type", "").removesuffix("_pair_value")
        if kind in edit_kinds:
            comps = list(_to_components(kind, r["args"][2:]))
            for c, x in (locked or {}).get(kind, ()):
                comps[c] = x
            r["type"] = "low_order_kinematic_pair_value"
            r["args"] = r["args"][:2] + comps
            ids[kind] = r["id"]
    return doc, ids


def test_a_low_order_value_on_any_low_order_pair_is_read_by_its_own_type():
    """Each named pair's value rewritten as the conforming low_order_kinematic_pair_value reads
    as the same values (truth: the chain as p105 wrote it with the named value entities)."""
    kinds = [k for k in CHAIN_VALUES if k != "screw"]
    (ref,) = rm.read_mechanisms(_chain_doc()[0])
    mf = ModelFile.of(_chain_doc(kinds)[0])
    (got,) = rm.read_mechanisms(mf)
    for k in kinds:
        assert got.initial[k] == pytest.approx(ref.initial[k], rel=1e-15, abs=1e-15), k
        assert got.initial[k] == pytest.approx(CHAIN_VALUES[k], rel=1e-12), k
    assert mf.deviations() == []


def test_a_locked_component_is_projected_away_with_a_warning_naming_the_value():
    """A revolute pair's value with actual_translation_z = 5 (metres here) and a spherical one
    with a translation: read as the pair's free values, one warning each, naming the #id."""
    doc, ids = _chain_doc(("revolute", "spherical"), {"revolute": [(2, 5.0)], "spherical": [(0, 0.25)]})
    mf = ModelFile.of(doc)
    (m,) = rm.read_mechanisms(mf)
    assert m.initial["revolute"] == pytest.approx(CHAIN_VALUES["revolute"], rel=1e-15)
    assert m.initial["spherical"] == pytest.approx(CHAIN_VALUES["spherical"], rel=1e-15)
    warnings = mf.deviations()
    assert len(warnings) == 2
    assert warnings[0].startswith(f"#{ids['revolute']}: ") and "actual_translation_z = 5" in warnings[0]
    assert "revolute pair" in warnings[0] and "projected" in warnings[0]
    assert warnings[1].startswith(f"#{ids['spherical']}: ") and "actual_translation_x = 0.25" in warnings[1]
    rm.read_mechanisms(mf)  # read again: each warning once
    assert mf.deviations() == warnings


def test_a_low_order_value_on_a_motion_coupled_pair_is_an_error():
    """A screw pair is no low_order_kinematic_pair (AP242: low_order_kinematic_pair_with_motion_
    coupling): its value has no freedoms to be read by; the error names the value."""
    doc, ids = _chain_doc(("screw",))
    with pytest.raises(ModelError) as e:
        rm.read_mechanisms(doc)
    assert e.value.message.startswith(f"#{ids['screw']}: ") and "screw pair" in e.value.message
