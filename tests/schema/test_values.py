"""schema/values.py: the one lenient reading of typed attribute values."""

from __future__ import annotations

from p105cli.schema.values import enum, is_false, is_true, is_unlimited, number, numbers, ref, refs, untyped


def test_untyped_unwraps_every_level():
    v = {"type": "PARAMETER_VALUE", "value": {"type": "LENGTH_MEASURE", "value": 2.5}}
    assert untyped(v) == 2.5
    assert untyped({"ref": 3}) == {"ref": 3}


def test_number_accepts_reals_and_integers_only():
    assert number(3) == 3.0 and type(number(3)) is float
    assert number({"type": "LENGTH_MEASURE", "value": {"type": "POSITIVE_LENGTH_MEASURE", "value": 2}}) == 2.0
    for bad in (True, False, "1.0", None, {"ref": 1}, {"enum": "T"}, [1.0], {"derived": True}):
        assert number(bad) is None


def test_numbers():
    assert numbers([1, 2.5, {"type": "REAL", "value": 3}]) == [1.0, 2.5, 3.0]
    assert numbers([1, "x"]) is None and numbers(1.0) is None


def test_enums_and_logicals():
    assert enum({"enum": "unlimited"}) == "UNLIMITED"
    assert enum("T") is None
    assert is_true({"enum": "T"}) and is_true(True) and not is_true({"enum": "F"}) and not is_true(None)
    assert is_false({"enum": "f"}) and is_false(False) and not is_false({"enum": "U"}) and not is_false(None)


def test_unlimited_limits_of_both_layouts():
    assert is_unlimited(None)                                                      # AP242 $
    assert is_unlimited({"type": "UNLIMITED_RANGE", "value": {"enum": "UNLIMITED"}})  # 1996
    assert is_unlimited({"enum": "UNLIMITED"})
    assert not is_unlimited(0.0) and not is_unlimited({"type": "PLANE_ANGLE_MEASURE", "value": 1.0})


def test_references():
    assert ref({"ref": 7}) == 7 and ref({"ref": "7"}) is None and ref(7) is None
    assert refs([{"ref": 1}, 2, {"ref": 3}]) == [1, 3]
    assert refs({"type": "SET", "value": [{"ref": 4}]}) == [4]
    assert refs(None) == [] and refs({"ref": 1}) == []
