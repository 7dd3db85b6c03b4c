"""part105.results: analysis results and resulting paths added to a model.

Independent truth: the records the input file holds (each is decoded once, by the one bulk
read the output needs), the solver's forward kinematics for the path's nodes, and the
mechanism's own link names for the request errors.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import EXAMPLES, ROOT
from p105cli.kinematics.reader import read_mechanism
from p105cli.kinematics.solver import forward, plan
from p105cli.part105.results import ResultingPathError, add_results, resulting_path_request
from p105cli.step import read_step

FOUR_BAR_242 = EXAMPLES / "four_bar_ap242.stp"
FOUR_BAR_214 = ROOT / "tests" / "data" / "corpus" / "four_bar_ap214.stp"


def _counted(path):
    """The file read, its mechanism, and counters of how often its records get decoded."""
    doc = read_step(path.read_text(), str(path))
    mech = read_mechanism(doc)
    calls = {"records": 0, "slot": 0}
    records, slot = doc.records, doc._decode_slot
    bulk = []  # set while the bulk read runs (it decodes some records one by one itself)

    def count_records():
        calls["records"] += 1
        bulk.append(True)
        try:
            return list(records())
        finally:
            bulk.pop()

    def count_slot(k):
        if not bulk:
            calls["slot"] += 1
        return slot(k)

    doc.records, doc._decode_slot = count_records, count_slot
    return doc, mech, calls


@pytest.mark.parametrize("path", [FOUR_BAR_242, FOUR_BAR_214], ids=["ap242", "ap214"])
def test_results_with_a_resulting_path_decode_the_model_once(path):
    doc, mech, calls = _counted(path)
    pl = plan(mech)
    Q = np.tile(mech.initial_vector(), (3, 1))
    rp = resulting_path_request(mech, pl, "coupler")
    out, notes = add_results(doc, mech, Q, [0.0, 1.0, 2.0], ["ok"] * 3, paths=[rp], pl=pl)
    assert calls == {"records": 1, "slot": 0}
    assert notes == []
    assert len(out.data) > len(doc.index)
    kinds = [r.get("type") for r in out.data[len(doc.index):]]
    assert kinds.count("resulting_path") == 1
    assert kinds.count("kinematic_analysis_result") >= 1


def test_ap242_path_nodes_are_the_forward_kinematics_of_the_link():
    doc = read_step(FOUR_BAR_242.read_text(), str(FOUR_BAR_242))
    mech = read_mechanism(doc)
    pl = plan(mech)
    sl = mech.value_slices["A"] if "A" in mech.value_slices else next(iter(mech.value_slices.values()))
    Q = np.tile(mech.initial_vector(), (2, 1))
    Q[1, sl] += 0.25  # any values: the nodes are the tree's forward kinematics, closed or not
    rp = resulting_path_request(mech, pl, "coupler")
    out, _ = add_results(doc, mech, Q, [0.0, 1.0], ["ok"] * 2, paths=[rp], pl=pl)
    by_id = {r["id"]: r for r in out.data}
    (node,) = [r for r in out.data[len(doc.index):] if r.get("type") == "point_to_point_path"]
    placement = by_id[node["args"][2]["ref"]]
    origin = by_id[placement["args"][1]["ref"]]["args"][1]
    want = forward(pl, Q[1:])[0, pl.link_index["coupler"]][:3, 3] / mech.units.length
    assert np.allclose(origin, want, rtol=0.0, atol=1e-9)


def test_a_request_naming_no_link_or_frame_is_a_resulting_path_error():
    doc = read_step(FOUR_BAR_214.read_text(), str(FOUR_BAR_214))
    mech = read_mechanism(doc)
    pl = plan(mech)
    with pytest.raises(ResultingPathError, match="'nolink' is not a link of mechanism 'four_bar'"):
        resulting_path_request(mech, pl, "nolink")
    with pytest.raises(ResultingPathError, match="link 'coupler' has no frame 'nope'"):
        resulting_path_request(mech, pl, "coupler:nope")
    with pytest.raises(ResultingPathError, match="does not move"):
        resulting_path_request(mech, pl, mech.base)
