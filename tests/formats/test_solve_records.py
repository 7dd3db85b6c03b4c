"""formats/solve_records.py: solve's jsonl and csv tables say the same, in the user's units."""

from __future__ import annotations

import csv
import io
import json
import math

import numpy as np

from p105cli.formats.solve_records import Table, Tally, write_blocks
from p105cli.kinematics import solver
from p105cli.kinematics.model import Link, Mechanism, Pair
from p105cli.kinematics.spatial import trans_x

I4 = np.eye(4)


def _arm():
    links = (Link("l0"), Link("l1"), Link("l2"))
    pairs = (Pair("A", "revolute", "l0", "l1", I4, I4, actuated=True),
             Pair("S", "prismatic", "l1", "l2", trans_x(0.5), I4))
    return Mechanism("arm", links, pairs, "l0")


def _run(fmt, blocks_of=2):
    mech = _arm()
    pl = solver.plan(mech)
    driven = {"A": np.radians([0.0, 30.0, 60.0]), "S": np.array([0.001, 0.002, 0.003])}
    out, tally, placements = io.StringIO(), Tally(False), []
    table = Table(out, fmt, mech, pl, inverse=False, length=1e-3, angle=math.pi / 180)
    table.header()
    blocks = solver.iter_motion(mech, driven, pl=pl, block=blocks_of)
    write_blocks(blocks, np.array([0.0, 0.5, 1.0]), table.write, tally, mech.link_names, placements)
    return out.getvalue(), tally, placements


def test_jsonl_and_csv_carry_the_same_values_in_the_output_units():
    text, tally, placements = _run("jsonl")
    recs = [json.loads(line) for line in text.splitlines()]
    assert [r["index"] for r in recs] == [0, 1, 2] and [r["t"] for r in recs] == [0.0, 0.5, 1.0]
    assert np.allclose([r["pairs"]["A"] for r in recs], [0.0, 30.0, 60.0])      # degrees
    assert np.allclose([r["pairs"]["S"] for r in recs], [1.0, 2.0, 3.0])        # millimetres
    l2 = np.array(recs[1]["links"]["l2"])
    # the prismatic pair slides along its frame's z: 2 mm up, at 0.5 m along the turned x
    assert np.allclose(l2[:3, 3], [500 * math.cos(math.radians(30)), 500 * math.sin(math.radians(30)), 2.0])
    rows = list(csv.DictReader(io.StringIO(_run("csv")[0])))
    assert [float(r["A"]) for r in rows] == [r["pairs"]["A"] for r in recs]
    assert [float(r["l2.m03"]) for r in rows] == [r["links"]["l2"][0][3] for r in recs]
    assert tally.n == 3 and not tally.failed and len(placements) == 3 and placements[2][0] == 1.0


def test_summary_and_messages():
    _, tally, _ = _run("jsonl")
    s = tally.summary(_arm(), 1e-3, math.pi / 180, timings=False)
    assert s["configurations"] == 3 and s["status"] == {"ok": 3} and s["units"] == {"length": "mm", "angle": "deg"}
    assert "seconds" not in s and tally.messages(for_a_person=False) == []
    (level, text), = tally.messages(for_a_person=True)
    assert level == "note" and text.startswith("3 configurations, max residual ")
