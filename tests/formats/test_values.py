"""formats/values.py: --values files, --set, --sweep, and the rules of driving a mechanism."""

from __future__ import annotations

import math

import numpy as np
import pytest

from p105cli.formats.values import FormatError, MAX_TURNS, driven_columns, read_values
from p105cli.kinematics.model import Link, Mechanism, Pair

I4 = np.eye(4)


def test_values_reader_units_columns_and_jsonl():
    is_angle = lambda key: (key if isinstance(key, str) else key[0]) != "S"  # noqa: E731
    t, cols = read_values("t,A,S,U[1]\n0,90,10,45\n1,180,20,-45\n", "x.csv", length=1e-3,
                          angle=math.pi / 180, is_angle=is_angle)
    assert list(t) == [0.0, 1.0]
    assert np.allclose(cols["A"], [math.pi / 2, math.pi]) and np.allclose(cols["S"], [0.01, 0.02])
    assert np.allclose(cols[("U", 1)], [math.pi / 4, -math.pi / 4])
    t2, cols2 = read_values('{"t": 0, "pairs": {"A": 90, "U": [1, 2]}}\n{"t": 1, "pairs": {"A": 180, "U": [3, 4]}}\n',
                            "x.jsonl", angle=math.pi / 180, is_angle=lambda k: True)
    assert list(t2) == [0.0, 1.0] and np.allclose(cols2["A"], cols["A"])
    assert np.allclose(cols2[("U", 0)], np.radians([1, 3])) and np.allclose(cols2[("U", 1)], np.radians([2, 4]))


@pytest.mark.parametrize("text, where", [("A,A\n1,2\n", "x.csv:1:3: column 'A' given twice"),
                                         ("t\n1\n", "x.csv:1:1: no pair column"),
                                         ("A\n", "x.csv:2:1: no configuration"),
                                         ("A\nnan\n", "x.csv:2:1: 'nan' is not a finite number"),
                                         ('{"t": 0, "pairs": {"A": 1}}\n{"t": 1}\n', "x.csv:2:1:"),
                                         ('{"t": 0, "pairs": ' + "[" * 5000 + "]" * 5000 + "}\n",
                                          "x.csv:1:1: JSON nested too deeply")])
def test_values_reader_errors_name_the_place(text, where):
    with pytest.raises(FormatError) as err:
        read_values(text, "x.csv")
    assert where in str(err.value)


def test_value_tables_parse_the_same_fast_and_careful():
    """Plain numeric tables go through numpy's C parser; anything unusual through the careful
    one. Both must give the same bits, and errors still name LINE:COL."""
    rng = np.random.default_rng(7)
    q = rng.normal(size=(200, 3)) * np.array([1e-300, 1.0, 1e200])
    body = "".join(f"{i},{a!r},{b:.17g},{c!r}\n" for i, (a, b, c) in enumerate(q.tolist()))
    text = "# a comment\nt,A,B[0],B[1]\n" + body
    fast_t, fast = read_values(text, "x.csv")
    careful_t, careful = read_values(text.replace("\n0,", '\n"0",', 1), "x.csv")  # quotes: careful
    assert np.array_equal(fast_t, careful_t)
    for k in fast:
        assert np.array_equal(fast[k], careful[k])
    bad = text.split("\n")
    bad[4] = "2,nan?," + bad[4].split(",", 2)[2]
    with pytest.raises(FormatError, match=r"x\.csv:5:3: 'nan\?' is not a number"):
        read_values("\n".join(bad), "x.csv")


def _arm():
    """A revolute A (actuated), a prismatic S, and a cylindrical C (angle, then length)."""
    links = tuple(Link(n) for n in ("l0", "l1", "l2", "l3"))
    pairs = (Pair("A", "revolute", "l0", "l1", I4, I4, actuated=True), Pair("S", "prismatic", "l1", "l2", I4, I4),
             Pair("C", "cylindrical", "l2", "l3", I4, I4))
    return Mechanism("arm", links, pairs, "l0")


def test_driving_rules():
    mech = _arm()
    t, driven, notes = driven_columns(mech, ("t,A,S\n0,90,10\n1,180,20\n", "v.csv"), ["C[0]=5"],
                                      length=1e-3, angle=math.pi / 180)
    assert list(t) == [0.0, 1.0] and set(driven) == {"A", "S", ("C", 0)}
    assert np.allclose(driven["A"], [math.pi / 2, math.pi]) and np.allclose(driven[("C", 0)], [5e-3, 5e-3])
    assert notes == ["pair 'S' is driven but has no actuator in the model",
                     "pair 'C' is driven but has no actuator in the model"]
    t, driven, notes = driven_columns(mech)   # nothing given: the actuated pairs at their initial values
    assert t is None and list(driven) == ["A"] and driven["A"].shape == (1, 1) and notes == []
    t, driven, _ = driven_columns(mech, sweeps=["A=0:1:3", "S[0]=1:2:3"])
    assert set(driven) == {"A", "S"} and np.allclose(driven["S"], [1, 1.5, 2])
    for kw, message in [({"sets": ["X=1"]}, "'X' is not a pair of mechanism 'arm'"),
                        ({"sets": ["C=1"]}, "pair 'C' has 2 values: name them C[0], C[1], ..."),
                        ({"sets": ["A[1]=1"]}, "pair 'A' has 1 value(s); A[1] does not exist"),
                        ({"values": ("A\n1\n", "v.csv"), "sets": ["A=1"]}, "--set A: the pair is in --values too"),
                        ({"sets": [f"A={MAX_TURNS * 7}"]}, "more than 1e+06 turns")]:
        with pytest.raises(FormatError) as err:
            driven_columns(mech, **kw)
        assert message in str(err.value)
